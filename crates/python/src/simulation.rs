//! `simulate`: measurements of a model with planted errors and effects, as
//! `urdf-dh simulate` makes them (the library's `dh_workflows::simulation`), returned as text: the
//! measurement CSV and the truth sheet (JSON for Python, YAML as the command line writes it).
//!
//! Also `write_outputs`, the command line's way of writing files (never over an input, all or
//! none), for the Python package's writers.
//!
//! Units: metres and radians throughout.

use std::path::Path;

use dh_workflows::geometry::Convention;
use dh_workflows::output::{check_destinations, write_all};
use dh_workflows::ranges as guard;
use dh_workflows::simulation::{simulate as run, SimulationRequest};
use pyo3::prelude::*;

use crate::to_py;

/// A number option checked by the command line's own guard of it, the error naming the
/// Python argument `name`.
fn checked<T>(name: &str, value: &str, guard: fn(&str) -> Result<T, String>) -> anyhow::Result<T> {
    guard(value).map_err(|e| anyhow::anyhow!("{name}: {e}"))
}

/// Simulates measurements of `model`; `effects` and `errors` as the command line's `--effect`
/// and `--error` values (`LABEL=V[,V...]`, `NAME=V`), `random_errors` as `LENGTH,ANGLE`,
/// `gravity` as `--gravity`'s values (m/s² in the base link frame, each checked by its guard,
/// their count by the library's `dh_workflows::calibration::gravity_given`); the numbers arrive
/// as text, checked by the command line's guards. `data_name` and `truth_name`
/// name the files in the truth and the CSV's comment. Returns the CSV, the truth as JSON and
/// as YAML, and the warnings (`urdf-dh: warning:` lines).
#[pyfunction]
#[pyo3(signature = (model, base, tip, poses, noise, orientation_noise, cpa, arc, effects, errors, random_errors, targets, repeats, validation, sessions, seed, data_name, truth_name, gravity=None))]
#[allow(clippy::too_many_arguments)]
fn simulate(
    py: Python<'_>,
    model: String,
    base: Option<String>,
    tip: Option<String>,
    poses: String,
    noise: String,
    orientation_noise: Option<String>,
    cpa: bool,
    arc: Option<String>,
    effects: Vec<String>,
    errors: Vec<String>,
    random_errors: Option<String>,
    targets: String,
    repeats: String,
    validation: String,
    sessions: String,
    seed: u64,
    data_name: String,
    truth_name: String,
    gravity: Option<Vec<String>>,
) -> PyResult<(String, String, String, String)> {
    let go = || -> anyhow::Result<(String, String, String, String)> {
        let request = SimulationRequest {
            model,
            base,
            tip,
            convention: Convention::Standard,
            poses: checked("poses", &poses, guard::poses)?,
            noise: checked("noise", &noise, guard::noise)?,
            orientation_noise: orientation_noise
                .map(|v| checked("orientation_noise", &v, guard::orientation_noise))
                .transpose()?,
            cpa,
            arc: arc.map(|v| checked("arc", &v, guard::arc)).transpose()?,
            effects,
            inertials: None,
            gravity: gravity
                .map(|g| {
                    g.iter()
                        .map(|v| checked("gravity", v, guard::gravity))
                        .collect::<anyhow::Result<Vec<f64>>>()
                })
                .transpose()?,
            errors,
            random_errors: random_errors
                .map(|v| checked("random_errors", &v, guard::random_errors))
                .transpose()?,
            targets: checked("targets", &targets, guard::small_count)?,
            repeats: checked("repeats", &repeats, guard::small_count)?,
            validation: checked("validation", &validation, guard::fraction)?,
            sessions: checked("sessions", &sessions, guard::small_count)?,
            seed,
        };
        let mut warnings = Vec::new();
        let sim = run(&request, &data_name, &truth_name, &mut warnings)?;
        let (json, yaml) = (serde_json::to_string(&sim.truth)?, sim.truth_yaml()?);
        Ok((
            sim.csv,
            json,
            yaml,
            String::from_utf8_lossy(&warnings).into_owned(),
        ))
    };
    py.detach(go).map_err(|e| to_py(py, e))
}

/// Writes `outputs` (argument name, path, text) as the command line writes its outputs: none
/// may be one of `inputs` (argument name, path) however spelled, each folder must exist, and
/// all are written or none (`dh_workflows::output`).
#[pyfunction]
fn write_outputs(
    py: Python<'_>,
    inputs: Vec<(String, String)>,
    outputs: Vec<(String, String, String)>,
) -> PyResult<()> {
    let go = || -> anyhow::Result<()> {
        let ins: Vec<(&str, &str)> = inputs
            .iter()
            .map(|(o, p)| (o.as_str(), p.as_str()))
            .collect();
        let outs: Vec<(&str, &str)> = outputs
            .iter()
            .map(|(o, p, _)| (o.as_str(), p.as_str()))
            .collect();
        check_destinations(&ins, &outs)?;
        let files: Vec<(&Path, &[u8])> = outputs
            .iter()
            .map(|(_, p, t)| (Path::new(p), t.as_bytes()))
            .collect();
        write_all(&files)
    };
    py.detach(go).map_err(|e| to_py(py, e))
}

/// Adds this module's functions to the native module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(write_outputs, m)?)?;
    Ok(())
}
