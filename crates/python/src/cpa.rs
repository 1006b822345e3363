//! `cpa`: circle-point analysis of measurements in which one joint moves at a time, as
//! `urdf-dh cpa` runs it (the library's `dh_workflows::cpa_report`), the measurements as a file or
//! as arrays. Returns the extracted table as a sheet with the report as its `cpa` section, as
//! JSON (for Python) and YAML (what `cpa --format yaml` prints), in metres and radians.

use dh_workflows::cpa_report::{cpa as run, CpaRequest, CPA_ANGULAR, CPA_LINEAR};
use dh_workflows::geometry::{Convention, Tolerance};
use dh_workflows::render::{render_sheet, Format};
use pyo3::prelude::*;

use crate::calibration::{arrays, units, ArraysIn};
use crate::{ranged_f64, to_py};

/// Runs the circle-point analysis of `data` (arrays, or None to read the file `data_name`,
/// which otherwise only names them in messages) with `model` (None: the data's joint columns,
/// revolute, in `convention`). Returns the sheet with its `cpa` section as JSON and as YAML,
/// and the warnings (`urdf-dh: warning:` lines).
#[pyfunction]
#[pyo3(signature = (data_name, data, model, base, tip, convention, linear_tol, angular_tol, length_unit, angle_unit))]
#[allow(clippy::too_many_arguments)]
fn cpa(
    py: Python<'_>,
    data_name: String,
    data: Option<ArraysIn>,
    model: Option<String>,
    base: Option<String>,
    tip: Option<String>,
    convention: &str,
    linear_tol: f64,
    angular_tol: f64,
    length_unit: &str,
    angle_unit: &str,
) -> PyResult<(String, String, String)> {
    let go = || -> anyhow::Result<(String, String, String)> {
        let request = CpaRequest {
            data: data_name,
            model,
            base,
            tip,
            convention: match convention {
                "standard" => Convention::Standard,
                "modified" => Convention::Modified,
                other => {
                    anyhow::bail!("convention: expected 'standard' or 'modified', found '{other}'")
                }
            },
            tolerance: Tolerance::new(
                ranged_f64("linear_tol", linear_tol, dh_workflows::ranges::linear_tol)?,
                ranged_f64(
                    "angular_tol",
                    angular_tol,
                    dh_workflows::ranges::angular_tol,
                )?,
            )
            .map_err(|e| anyhow::anyhow!("{e}"))?,
            units: units(length_unit, angle_unit)?,
            given: data.map(arrays).transpose()?,
        };
        let mut warnings = Vec::new();
        let report = run(&request, &mut warnings)?;
        let sheet = report.sheet_with_report()?;
        Ok((
            serde_json::to_string(&sheet)?,
            render_sheet(&sheet, Format::Yaml)?,
            String::from_utf8_lossy(&warnings).into_owned(),
        ))
    };
    py.detach(go).map_err(|e| to_py(py, e))
}

/// Adds this module's functions and constants to the native module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(cpa, m)?)?;
    m.add("CPA_LINEAR", CPA_LINEAR)?;
    m.add("CPA_ANGULAR", CPA_ANGULAR)?;
    Ok(())
}
