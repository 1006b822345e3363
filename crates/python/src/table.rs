//! Extraction (`extract`, with the proof of the YAML it writes) and `check`'s comparison of a
//! URDF chain with a sheet; [`NativeTable`] is the extracted table.

use anyhow::Context;
use dh_workflows::check::{compare, CHECK_ANGULAR, CHECK_LINEAR};
use dh_workflows::extract::{extract_bytes_in, prove_extracted, ExtractOptions};
use dh_workflows::geometry::{Convention, DhTable, Extraction, JointKind, Tolerance};
use dh_workflows::input::{display_name, folder_of, load_chain_in, read_robot_with, read_text};
use dh_workflows::poe::PoeDoc;
use dh_workflows::xacro::XacroOptions;
use dh_workflows::{AngleUnit, Format, LengthUnit, Sheet};
use pyo3::prelude::*;

use crate::{ranged, ranged_f64, to_py};

/// A 4x4 homogeneous matrix, row-major.
type Matrix = [[f64; 4]; 4];

/// Name of URDF text passed as a string, in error messages.
const XML_NAME: &str = "<string>";

/// The robot bytes, their display name and the folder of the file they came from: XML text as
/// given, or the file at `path` (a `.xacro` file expanded natively with `xacro`'s arguments and
/// package folders).
fn robot_bytes(
    source: &str,
    is_xml: bool,
    xacro: &XacroOptions,
) -> anyhow::Result<(Vec<u8>, String, Option<std::path::PathBuf>)> {
    if is_xml {
        Ok((source.as_bytes().to_vec(), XML_NAME.to_string(), None))
    } else {
        Ok((
            read_robot_with(source, xacro)?,
            display_name(source),
            folder_of(source),
        ))
    }
}

/// The xacro options of the keyword arguments `xacro_args` and `packages`.
fn xacro_options(
    args: Option<Vec<(String, String)>>,
    packages: Option<Vec<(String, String)>>,
) -> XacroOptions {
    XacroOptions {
        args: args.unwrap_or_default(),
        packages: packages
            .unwrap_or_default()
            .into_iter()
            .map(|(n, d)| (n, d.into()))
            .collect(),
        max_bytes: None,
        files: None,
    }
}

fn convention(name: &str) -> anyhow::Result<Convention> {
    match name {
        "standard" => Ok(Convention::Standard),
        "modified" => Ok(Convention::Modified),
        other => anyhow::bail!("convention: expected 'standard' or 'modified', found '{other}'"),
    }
}

fn homogeneous(iso: &nalgebra::Isometry3<f64>) -> Matrix {
    let m = iso.to_homogeneous();
    std::array::from_fn(|i| std::array::from_fn(|j| m[(i, j)]))
}

/// One row as a tuple: name, type, a, alpha, d, theta, lower, upper, mimic (joint, multiplier,
/// offset) or None. Metres and radians.
type RowTuple = (
    String,
    &'static str,
    f64,
    f64,
    f64,
    f64,
    Option<f64>,
    Option<f64>,
    Option<(String, f64, f64)>,
);

/// An extracted DH table with its verification and the YAML sheet the CLI writes.
#[pyclass(frozen, module = "urdf_dh._native")]
struct NativeTable {
    table: DhTable,
    yaml: String,
    sheet_json: String,
    verification_json: String,
    warnings: Vec<String>,
    /// Base and tip link of the chain.
    links: (String, String),
    /// The CLI's error line when the proof failed (without `urdf-dh: error: `), else `None`.
    failure: Option<String>,
}

#[pymethods]
impl NativeTable {
    /// Rows as tuples (see `RowTuple`).
    fn rows(&self) -> Vec<RowTuple> {
        self.table
            .rows
            .iter()
            .map(|r| {
                (
                    r.name.clone(),
                    match r.kind {
                        JointKind::Revolute => "revolute",
                        JointKind::Prismatic => "prismatic",
                    },
                    r.a,
                    r.alpha,
                    r.d,
                    r.theta,
                    r.limits.map(|l| l.lower),
                    r.limits.map(|l| l.upper),
                    r.mimic
                        .as_ref()
                        .map(|m| (m.joint.clone(), m.multiplier, m.offset)),
                )
            })
            .collect()
    }

    /// DH frame 0 in the base link frame.
    fn base(&self) -> Matrix {
        homogeneous(&self.table.base)
    }

    /// The tip link frame in the last DH frame.
    fn tool(&self) -> Matrix {
        homogeneous(&self.table.tool)
    }

    /// `standard` or `modified`.
    fn convention(&self) -> &'static str {
        match self.table.convention {
            Convention::Standard => "standard",
            Convention::Modified => "modified",
        }
    }

    /// The YAML text `urdf-dh extract --format yaml` writes, verification included.
    fn yaml(&self) -> &str {
        &self.yaml
    }

    /// The same sheet as JSON (the keys of `--format json`).
    fn sheet_json(&self) -> &str {
        &self.sheet_json
    }

    /// The verification of the YAML as written, as JSON.
    fn verification_json(&self) -> &str {
        &self.verification_json
    }

    /// The table's product-of-exponentials form as JSON (`dh_workflows::poe::PoeDoc`: screws in
    /// the base frame at zero and the tip's home pose), at full precision.
    fn poe_json(&self, py: Python<'_>) -> PyResult<String> {
        let run = || -> anyhow::Result<String> {
            let doc = PoeDoc::of_table(&self.table, &self.links.0, &self.links.1)?;
            Ok(serde_json::to_string(&doc)?)
        };
        run().map_err(|e| to_py(py, e))
    }

    /// Extraction warnings (near-degenerate pairs and the like).
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }

    /// The message `urdf-dh extract` prints when the proof failed (it then exits 1), or None.
    fn failure(&self) -> Option<String> {
        self.failure.clone()
    }

    /// Forward kinematics: the tip link in the base link frame at joint values `q` (one per
    /// row, radians or metres), each a finite number within the range of `--q`
    /// ([`dh_workflows::ranges::joint_value`]).
    fn fk(&self, py: Python<'_>, q: Vec<f64>) -> PyResult<Matrix> {
        let run = || -> anyhow::Result<Matrix> {
            for (row, v) in self.table.rows.iter().zip(&q) {
                ranged_f64(
                    &format!("fk: joint '{}'", row.name),
                    *v,
                    dh_workflows::ranges::joint_value,
                )?;
            }
            Ok(homogeneous(&self.table.fk(&q).context("fk")?))
        };
        run().map_err(|e| to_py(py, e))
    }
}

/// Extracts the DH table of a URDF chain and proves the YAML sheet it writes, as
/// `urdf-dh extract --format yaml` does.
#[pyfunction]
#[pyo3(signature = (source, is_xml, base, tip, convention_name, samples, seed, linear, angular, xacro_args=None, packages=None))]
#[allow(clippy::too_many_arguments)]
fn extract(
    py: Python<'_>,
    source: &str,
    is_xml: bool,
    base: Option<String>,
    tip: Option<String>,
    convention_name: &str,
    samples: &str,
    seed: &str,
    linear: &str,
    angular: &str,
    xacro_args: Option<Vec<(String, String)>>,
    packages: Option<Vec<(String, String)>>,
) -> PyResult<NativeTable> {
    let xacro = xacro_options(xacro_args, packages);
    let run = || -> anyhow::Result<NativeTable> {
        // The command line's ranges, before any file is read (as clap checks them first).
        let samples = ranged("samples", samples, dh_workflows::ranges::samples)?;
        let seed = ranged("seed", seed, dh_workflows::ranges::seed)?;
        let tolerance = Tolerance::new(
            ranged("linear_tolerance", linear, dh_workflows::ranges::linear_tol)?,
            ranged(
                "angular_tolerance",
                angular,
                dh_workflows::ranges::angular_tol,
            )?,
        )?;
        let (bytes, name, dir) = robot_bytes(source, is_xml, &xacro)?;
        let expansion_warnings = dh_workflows::xacro::take_warnings();
        let options = ExtractOptions {
            convention: convention(convention_name)?,
            length_unit: LengthUnit::M,
            angle_unit: AngleUnit::Rad,
            tolerance,
        };
        let mut ex = extract_bytes_in(
            &bytes,
            &name,
            dir.as_deref(),
            base.as_deref(),
            tip.as_deref(),
            &options,
        )?;
        let (yaml, passed) = prove_extracted(&mut ex, Format::Yaml, samples, seed)?;
        let verification = ex
            .sheet
            .verification
            .as_ref()
            .context("the proof attached no verification")?;
        // The table Python sees is the proved artefact: the YAML read back (1e-12 m / rad), not
        // the numbers in memory.
        let table = Sheet::parse(&yaml, "written output")?.table;
        let Extraction { warnings, .. } = ex.extraction;
        Ok(NativeTable {
            yaml,
            sheet_json: serde_json::to_string(&ex.sheet)?,
            verification_json: serde_json::to_string(verification)?,
            warnings: expansion_warnings
                .into_iter()
                .chain(warnings.iter().map(|w| w.to_string()))
                .collect(),
            links: (ex.chain.base().to_owned(), ex.chain.tip().to_owned()),
            table,
            failure: (!passed).then(|| {
                let line =
                    dh_workflows::prove::failure_line("the table", "the URDF", Some(verification));
                line.strip_prefix("urdf-dh: error: ")
                    .unwrap_or(&line)
                    .to_string()
            }),
        })
    };
    py.detach(run).map_err(|e| to_py(py, e))
}

/// Compares a URDF chain with a DH sheet file as `urdf-dh check --format json` does; returns
/// the report as JSON text.
#[pyfunction]
#[pyo3(signature = (source, is_xml, sheet, base, tip, linear, angular, xacro_args=None, packages=None))]
#[allow(clippy::too_many_arguments)]
fn check(
    py: Python<'_>,
    source: &str,
    is_xml: bool,
    sheet: &str,
    base: Option<String>,
    tip: Option<String>,
    linear: &str,
    angular: &str,
    xacro_args: Option<Vec<(String, String)>>,
    packages: Option<Vec<(String, String)>>,
) -> PyResult<String> {
    let xacro = xacro_options(xacro_args, packages);
    let run = || -> anyhow::Result<String> {
        let (linear, angular) = (
            ranged("linear_tolerance", linear, dh_workflows::ranges::linear_tol)?,
            ranged(
                "angular_tolerance",
                angular,
                dh_workflows::ranges::angular_tol,
            )?,
        );
        let (bytes, name, dir) = robot_bytes(source, is_xml, &xacro)?;
        dh_workflows::xacro::take_warnings();
        let (_, chain) = load_chain_in(
            &bytes,
            &name,
            dir.as_deref(),
            base.as_deref(),
            tip.as_deref(),
        )?;
        let sheet_name = display_name(sheet);
        let sheet = Sheet::parse(&read_text(sheet)?, &sheet_name)?;
        let report = compare(&chain, &sheet, Tolerance::new(linear, angular)?)?;
        Ok(serde_json::to_string(&report)?)
    };
    py.detach(run).map_err(|e| to_py(py, e))
}

/// Adds this module's class, functions and constants to the native module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<NativeTable>()?;
    m.add_function(wrap_pyfunction!(extract, m)?)?;
    m.add_function(wrap_pyfunction!(check, m)?)?;
    m.add("CHECK_LINEAR", CHECK_LINEAR)?;
    m.add("CHECK_ANGULAR", CHECK_ANGULAR)?;
    m.add("DEFAULT_LINEAR", Tolerance::DEFAULT_LINEAR)?;
    m.add("DEFAULT_ANGULAR", Tolerance::DEFAULT_ANGULAR)?;
    Ok(())
}
