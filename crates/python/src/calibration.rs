//! Calibration from measured points and using its result: `calibrate` (the library's
//! `dh_workflows::calibration`, which the command line runs too), `predict` and `compensate` (the
//! library's `dh_workflows::predict` and `dh_workflows::compensate`, returning numbers), in process and without
//! files: measurements and joint values cross as arrays ([`ArraysIn`], read by `dh_workflows::measured::SampleArrays` with the
//! CSV reader's checks), or as a file path. Also `measured_joints` and the generic `run`.
//!
//! Units: the arrays are in the caller's `length_unit` and `angle_unit`; reports are in metres
//! and radians, predicted and compensated values in the caller's units.

use std::collections::HashMap;

use dh_workflows::calibrated::{load_calibrated, CalibratedModel};
use dh_workflows::calibration::{
    self as calibration, CalibrationRequest, GivenData, DEFAULT_FOLDS, DEFAULT_MAX_EFFECTS,
};
use dh_workflows::compensate::{
    failed_poses, same_joints, CompensateOptions, NominalModel, DEFAULT_MAX_CHANGE,
};
use dh_workflows::fit::{EffectsChoice, DEFAULT_ALPHA};
use dh_workflows::geometry::Convention;
use dh_workflows::input::display_name;
use dh_workflows::measured::{DataUnits, SampleArrays, RESERVED_COLUMNS};
use dh_workflows::output::{write_all, STDIO};
use dh_workflows::predict::{frame_of, read_joints, Frame};
use dh_workflows::ranges;
use dh_workflows::units::{AngleUnit, LengthUnit};
use pyo3::prelude::*;
use urdf_dh_cli::error::Outcome;

use crate::to_py;

/// Measurements or joint values from Python: the joint column names, the joint values
/// (`rows × names`, flattened row-major), the points (`rows × 3` flattened; empty for joint
/// values), the `sigma` column or None, the text columns (`target`, `config`, `session`,
/// `set`) by name, and a 6-DoF device's orientation: `qw, qx, qy, qz` (`rows × 4` flattened,
/// NaN rows for points) and `sigma_rot`, or None; the per-axis sigmas `sx, sy, sz` (`rows × 3`
/// flattened) or None; the `time` column (seconds, NaN for a row without one) or None.
pub(crate) type ArraysIn = (
    Vec<String>,
    Vec<f64>,
    Vec<f64>,
    Option<Vec<f64>>,
    HashMap<String, Vec<String>>,
    Option<Vec<f64>>,
    Option<Vec<f64>>,
    Option<Vec<f64>>,
    Option<Vec<f64>>,
);

/// The [`SampleArrays`] of `a`.
///
/// # Errors
/// A text column that is not one of `target`, `config`, `session`, `set`.
pub(crate) fn arrays(a: ArraysIn) -> anyhow::Result<SampleArrays> {
    let (joint_names, q, points, sigma, mut labels, quaternion, sigma_rot, sigma_axes, time) = a;
    let mut take = |k: &str| labels.remove(k);
    let out = SampleArrays {
        joint_names,
        q,
        points,
        sigma,
        target: take("target"),
        config: take("config"),
        session: take("session"),
        set: take("set"),
        quaternion,
        sigma_rot,
        sigma_axes,
        // Checked by the library as a file's `time` cells: one per row, finite or NaN (none).
        time,
    };
    if let Some(k) = labels.keys().next() {
        anyhow::bail!("expected text columns target, config, session or set, found '{k}'");
    }
    Ok(out)
}

/// The units of `length` (`m`, `mm`) and `angle` (`rad`, `deg`).
pub(crate) fn units(length: &str, angle: &str) -> anyhow::Result<DataUnits> {
    Ok(DataUnits {
        length: match length {
            "m" => LengthUnit::M,
            "mm" => LengthUnit::Mm,
            other => anyhow::bail!("length_unit: expected 'm' or 'mm', found '{other}'"),
        },
        angle: match angle {
            "rad" => AngleUnit::Rad,
            "deg" => AngleUnit::Deg,
            other => anyhow::bail!("angle_unit: expected 'rad' or 'deg', found '{other}'"),
        },
    })
}

/// A number option checked by the command line's own guard of it (`guard`), the error naming
/// the Python argument `name`.
fn guarded<T>(
    name: &str,
    value: Option<String>,
    guard: fn(&str) -> Result<T, String>,
) -> anyhow::Result<Option<T>> {
    value
        .map(|v| guard(&v).map_err(|e| anyhow::anyhow!("{name}: {e}")))
        .transpose()
}

/// Runs `go` with in-memory standard output and error; returns both as text and the outcome.
fn captured(
    go: impl FnOnce(&mut Vec<u8>, &mut Vec<u8>) -> anyhow::Result<Outcome>,
) -> anyhow::Result<(String, String, bool)> {
    let (mut out, mut err) = (Vec::new(), Vec::new());
    let outcome = go(&mut out, &mut err)?;
    Ok((
        String::from_utf8_lossy(&out).into_owned(),
        String::from_utf8_lossy(&err).into_owned(),
        outcome == Outcome::Differs,
    ))
}

/// Fits `model` (None: circle-point analysis of the data) to measurements as
/// `urdf-dh calibrate --format json --quiet` does; `data` (`validate`) are arrays, or None to
/// read the file `data_name` (`validate_name`), which otherwise only names them in messages.
/// Returns the JSON report, the warnings (`urdf-dh: warning:` lines) and whether the model
/// written to `out` failed its proof (then nothing was written).
#[pyfunction]
#[pyo3(signature = (model, data_name, data, validate_name, validate, base, tip, effects, max_effects, alpha, targets, sigma, folds, keep_outliers, inertials, length_unit, angle_unit, out))]
#[allow(clippy::too_many_arguments)]
fn calibrate(
    py: Python<'_>,
    model: Option<String>,
    data_name: String,
    data: Option<ArraysIn>,
    validate_name: Option<String>,
    validate: Option<ArraysIn>,
    base: Option<String>,
    tip: Option<String>,
    effects: Option<String>,
    max_effects: Option<String>,
    alpha: Option<String>,
    targets: Vec<String>,
    sigma: Option<String>,
    folds: Option<String>,
    keep_outliers: bool,
    inertials: Option<String>,
    length_unit: &str,
    angle_unit: &str,
    out: Option<String>,
) -> PyResult<(String, String, bool)> {
    let go = || -> anyhow::Result<(String, String, bool)> {
        use dh_workflows::ranges as guard;
        let given = match data {
            Some(d) => Some(GivenData {
                data: arrays(d)?,
                validate: validate.map(arrays).transpose()?,
            }),
            None => None,
        };
        let request = CalibrationRequest {
            model,
            base,
            tip,
            convention: Convention::Standard,
            data: data_name,
            validate: validate_name,
            units: units(length_unit, angle_unit)?,
            effects: effects
                .as_deref()
                .map_or(Ok(EffectsChoice::None), str::parse)
                .map_err(|e: String| anyhow::anyhow!("effects: {e}"))?,
            targets,
            sigma: guarded("sigma", sigma, guard::sigma)?,
            folds: guarded("folds", folds, guard::folds)?.unwrap_or(DEFAULT_FOLDS),
            out,
            inertials,
            gravity: None,
            payload: None,
            max_effects: guarded("max_effects", max_effects, guard::max_effects)?
                .unwrap_or(DEFAULT_MAX_EFFECTS),
            alpha: guarded("alpha", alpha, guard::alpha)?.unwrap_or(DEFAULT_ALPHA),
            keep_outliers,
            given,
        };
        if request.out.as_deref() == Some(STDIO) {
            anyhow::bail!("out: expected a file path, found '-' (the report is returned)");
        }
        request.check_destinations(&[])?;
        let mut warnings = Vec::new();
        let mut calibrated = calibration::run(&request, &mut warnings)?;
        let mut files = Vec::new();
        if let Some(path) = &request.out {
            if let Some(text) =
                calibrated.model_file(path, request.model.as_deref(), &mut warnings)?
            {
                files.push((std::path::Path::new(path), text));
            }
        }
        let proved = calibrated.proved();
        if proved {
            let files: Vec<_> = files.iter().map(|(p, t)| (*p, t.as_bytes())).collect();
            write_all(&files)?;
        }
        Ok((
            calibrated.json()?,
            String::from_utf8_lossy(&warnings).into_owned(),
            !proved,
        ))
    };
    py.detach(go).map_err(|e| to_py(py, e))
}

/// The frame of `name` (`device`, `base`).
fn frame(name: Option<&str>) -> anyhow::Result<Option<Frame>> {
    match name {
        None => Ok(None),
        Some("device") => Ok(Some(Frame::Device)),
        Some("base") => Ok(Some(Frame::Base)),
        Some(other) => anyhow::bail!("frame: expected 'device' or 'base', found '{other}'"),
    }
}

/// A calibrated model loaded for `predict` and `compensate`, with its warnings (those of its
/// effects aside: they are the calibration's own).
fn calibrated(
    path: &str,
    base: Option<&str>,
    tip: Option<&str>,
) -> anyhow::Result<(CalibratedModel, Vec<String>)> {
    let model = load_calibrated(path, base, tip)?;
    let warnings = model
        .loaded
        .warnings
        .iter()
        .filter(|w| !w.contains(": effects: "))
        .cloned()
        .collect();
    Ok((model, warnings))
}

/// What `predict` returns to Python: per prediction its target, its row's config and session
/// (None without a session column), the position (in the length unit), the roll, pitch, yaw of
/// the tool or a 6-DoF target (angle unit; NaN for point targets; None when no row has one),
/// the uncertainty (3 lengths, then 3 angles with attitudes; None without covariance); then the frame (`device`, `base`) and the warnings.
type PredictOut = (
    Vec<String>,
    Vec<String>,
    Option<Vec<String>>,
    Vec<[f64; 3]>,
    Option<Vec<[f64; 3]>>,
    Option<Vec<Vec<f64>>>,
    &'static str,
    Vec<String>,
);

/// A calibrated model's target positions or tool poses at joint values
/// ([`dh_workflows::predict::predict`], as `urdf-dh predict` computes them); `joints` are arrays,
/// or None to read the file `joints_name`.
#[pyfunction]
#[pyo3(signature = (model, joints_name, joints, base, tip, targets, frame_name, session, length_unit, angle_unit, sequence, branch=None))]
#[allow(clippy::too_many_arguments)]
fn predict(
    py: Python<'_>,
    model: String,
    joints_name: String,
    joints: Option<ArraysIn>,
    base: Option<String>,
    tip: Option<String>,
    targets: Vec<String>,
    frame_name: Option<String>,
    session: Option<String>,
    length_unit: &str,
    angle_unit: &str,
    sequence: bool,
    branch: Option<String>,
) -> PyResult<PredictOut> {
    let go = || -> anyhow::Result<PredictOut> {
        let units = units(length_unit, angle_unit)?;
        let asked = frame(frame_name.as_deref())?;
        let (mut calibrated, mut warnings) = calibrated(&model, base.as_deref(), tip.as_deref())?;
        let origin = display_name(&model);
        if let Some(b) = &branch {
            calibrated.choose_branch(b, &origin)?;
        }
        let (frame, first) = frame_of(&mut calibrated, asked, session.as_deref(), &origin)?;
        warnings.splice(0..0, first);
        let given = joints.map(arrays).transpose()?;
        let mut input = read_joints(&joints_name, given.as_ref(), &calibrated, units)?;
        if sequence {
            dh_workflows::predict::in_sequence(&calibrated, &mut input);
        }
        let p = dh_workflows::predict::predict(
            &calibrated,
            frame,
            &input,
            &targets,
            session.as_deref(),
            &joints_name,
            &origin,
        )?;
        warnings.extend(p.warnings.iter().cloned());
        let (l, a) = (units.length.metres(), units.angle.radians());
        let row = |i: usize| input.rows.get(i);
        let sessions = input.rows.iter().any(|r| r.session.is_some()).then(|| {
            p.predicted
                .iter()
                .map(|x| {
                    row(x.row)
                        .and_then(|r| r.session.clone())
                        .unwrap_or_default()
                })
                .collect()
        });
        // Attitudes for the tool and 6-DoF targets; NaN in the rows of point targets.
        let rpy = p.has_attitude.then(|| {
            p.predicted
                .iter()
                .map(|x| x.rpy.map_or([f64::NAN; 3], |r| r.map(|v| v / a)))
                .collect()
        });
        let width = if p.has_attitude { 6 } else { 3 };
        let uncertainty = p.has_uncertainty.then(|| {
            p.predicted
                .iter()
                .map(|x| {
                    let u = x.uncertainty.as_deref().unwrap_or_default();
                    (0..width)
                        .map(|k| match u.get(k) {
                            Some(v) if k < 3 => v / l,
                            Some(v) => v / a,
                            None => f64::NAN,
                        })
                        .collect()
                })
                .collect()
        });
        Ok((
            p.predicted.iter().map(|x| x.target.clone()).collect(),
            p.predicted
                .iter()
                .map(|x| {
                    row(x.row).map_or_else(String::new, |r| {
                        r.config
                            .clone()
                            .unwrap_or_else(|| format!("line{}", r.line))
                    })
                })
                .collect(),
            sessions,
            p.predicted
                .iter()
                .map(|x| [x.position.x / l, x.position.y / l, x.position.z / l])
                .collect(),
            rpy,
            uncertainty,
            match p.frame {
                Frame::Device => "device",
                Frame::Base => "base",
            },
            warnings,
        ))
    };
    py.detach(go).map_err(|e| to_py(py, e))
}

/// What `compensate` returns to Python: the corrected joint values (poses x measured columns,
/// in the units), per pose the tool's position and orientation errors before and after
/// (position_before, orientation_before, position_error, orientation_error; in the units), the
/// poses not compensated (`config (line N): why`), and the warnings.
type CompensateOut = (Vec<Vec<f64>>, Vec<[f64; 4]>, Vec<String>, Vec<String>);

/// Corrected joint values ([`dh_workflows::compensate::compensate`], as `urdf-dh compensate`
/// computes them); `joints` are arrays, or None to read the file `joints_name`.
#[pyfunction]
#[pyo3(signature = (nominal, model, joints_name, joints, base, tip, position_only, max_change, length_unit, angle_unit, sequence, branch=None))]
#[allow(clippy::too_many_arguments)]
fn compensate(
    py: Python<'_>,
    nominal: String,
    model: String,
    joints_name: String,
    joints: Option<ArraysIn>,
    base: Option<String>,
    tip: Option<String>,
    position_only: bool,
    max_change: Option<String>,
    length_unit: &str,
    angle_unit: &str,
    sequence: bool,
    branch: Option<String>,
) -> PyResult<CompensateOut> {
    let go = || -> anyhow::Result<CompensateOut> {
        let units = units(length_unit, angle_unit)?;
        let max_change =
            guarded("max_change", max_change, ranges::max_change)?.unwrap_or(DEFAULT_MAX_CHANGE);
        let (mut calibrated, mut warnings) = calibrated(&model, None, None)?;
        if let Some(b) = &branch {
            calibrated.choose_branch(b, &display_name(&model))?;
        }
        let chain = calibrated.tool_chain("compensate", &display_name(&model))?;
        let nominal_model =
            NominalModel::load(&nominal, base.as_deref(), tip.as_deref(), &calibrated)?;
        same_joints(
            &nominal_model.rows(),
            &calibrated,
            (&display_name(&nominal), &display_name(&model)),
        )?;
        let given = joints.map(arrays).transpose()?;
        let mut input = read_joints(&joints_name, given.as_ref(), &calibrated, units)?;
        if sequence {
            dh_workflows::predict::in_sequence(&calibrated, &mut input);
        }
        warnings.extend(dh_workflows::predict::backlash_warnings(
            &calibrated,
            &input,
        ));
        let options = CompensateOptions {
            orientation: !position_only,
            max_change,
            chain,
            ..CompensateOptions::default()
        };
        let rows = nominal_model.compensate(&calibrated, &input, &options)?;
        let (l, a) = (units.length.metres(), units.angle.radians());
        let q = rows
            .iter()
            .map(|r| {
                r.result
                    .q
                    .iter()
                    .zip(&input.prismatic)
                    .map(|(v, p)| if *p { v / l } else { v / a })
                    .collect()
            })
            .collect();
        let errors = rows
            .iter()
            .map(|r| {
                let c = &r.result;
                [
                    c.error_before.0 / l,
                    c.error_before.1 / a,
                    c.position_error / l,
                    c.orientation_error / a,
                ]
            })
            .collect();
        let failed = failed_poses(&rows, max_change, units.length, units.angle)
            .iter()
            .map(ToString::to_string)
            .collect();
        Ok((q, errors, failed, warnings))
    };
    py.detach(go).map_err(|e| to_py(py, e))
}

/// Runs one `urdf-dh` command in process (its arguments after the program name) and returns
/// its standard output, standard error and whether it exited 1 (a difference found, a pose not
/// compensated); an error is raised with the command's message and hint.
#[pyfunction]
fn run(py: Python<'_>, argv: Vec<String>) -> PyResult<(String, String, bool)> {
    let go = || {
        let args = std::iter::once("urdf-dh".to_string()).chain(argv);
        captured(|o, e| urdf_dh_cli::cli::run_command(args, o, e))
    };
    py.detach(go).map_err(|e| to_py(py, e))
}

/// The joint columns a measurement or joint-value file needs for `model`, in row order (mimic
/// and coupled rows follow theirs).
#[pyfunction]
#[pyo3(signature = (model, base=None, tip=None))]
fn measured_joints(
    py: Python<'_>,
    model: &str,
    base: Option<String>,
    tip: Option<String>,
) -> PyResult<Vec<String>> {
    let go = || -> anyhow::Result<Vec<String>> {
        match dh_workflows::model::load_model(
            model,
            base.as_deref(),
            tip.as_deref(),
            Convention::Standard,
        ) {
            Ok(m) => Ok(m.measured_joints()),
            // A tree sheet (a calibrated tree's): every joint of the tree.
            Err(e) => match load_calibrated(model, base.as_deref(), tip.as_deref()) {
                Ok(c) if c.is_tree() => Ok(c.loaded.measured_joints()),
                _ => Err(e),
            },
        }
    };
    py.detach(go).map_err(|e| to_py(py, e))
}

/// Adds this module's functions and constants to the native module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(calibrate, m)?)?;
    m.add_function(wrap_pyfunction!(predict, m)?)?;
    m.add_function(wrap_pyfunction!(compensate, m)?)?;
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(measured_joints, m)?)?;
    m.add("RESERVED_COLUMNS", RESERVED_COLUMNS.to_vec())?;
    Ok(())
}
