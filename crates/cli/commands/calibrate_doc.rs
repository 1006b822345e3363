//! The documents `urdf-dh calibrate` writes: the JSON report's types ([`CalibrationDoc`] and its
//! parts; lengths in metres, angles in radians, units named per parameter by [`unit_of`]) and
//! the calibrated model (a URDF or a DH sheet with its `calibration` section).
//!
//! Shared by `calibrate`, its contact path and its tree path.

use anyhow::Result;
use dh_core::pose::to_xyz_rpy;
use dh_core::DhTable;
use nalgebra::Isometry3;
use serde::Serialize;

use crate::commands::calibrate_inputs::Inputs;
use crate::commands::to_urdf::{check_urdf, urdf_of};
use crate::commands::written::WrittenDoc;
use crate::sheet::{ConventionDoc, EffectDoc, SheetDoc};

/// One row of the candidate table (JSON `candidates`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CandidateDoc {
    /// The effect's label.
    pub label: String,
    /// First-order reduction of the calibration sum of squares beyond the geometric fit (m²).
    pub score: f64,
    /// Held-out RMS with it added, linearised (metres).
    pub val_rms: Option<f64>,
    /// Sine between its columns and the geometric ones (below 1e-3: aliased).
    pub independence: f64,
    /// selected, aliased, rejected, not selected, inert, rival.
    pub status: &'static str,
    /// Why a refitted candidate was not added (a rival's names the effect that did better).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
}

impl From<&dh_calib::diagnose::CandidateReport> for CandidateDoc {
    fn from(c: &dh_calib::diagnose::CandidateReport) -> Self {
        CandidateDoc {
            label: c.label.clone(),
            score: c.score,
            val_rms: c.val_rms,
            independence: c.independence,
            status: c.status.name(),
            reason: c.reason.clone(),
        }
    }
}

/// A step as reported (metres).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StepDoc {
    /// `nominal`, `geometric`, `effects`.
    pub label: String,
    /// Free parameters.
    pub free: usize,
    /// Solver iterations.
    pub iterations: usize,
    /// Calibration RMS before the step (the previous step's), `None` for the first.
    pub rms_before: Option<f64>,
    /// Validation RMS before the step.
    pub val_rms_before: Option<f64>,
    /// Calibration RMS.
    pub rms: f64,
    /// Calibration mean.
    pub mean: f64,
    /// Calibration max.
    pub max: f64,
    /// Validation RMS.
    pub val_rms: Option<f64>,
    /// Validation mean.
    pub val_mean: Option<f64>,
    /// Validation max.
    pub val_max: Option<f64>,
    /// RMS per axis of the orientation residuals of 6-DoF pose samples (radians); absent
    /// without such samples.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub angle_rms: Option<f64>,
    /// Parameters the step would estimate but held at their start, not identifiable from the
    /// data (in `nominal`: device or target coordinates), with what absorbs them.
    pub fixed: Vec<FixedDoc>,
}

/// One parameter as reported.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ParameterDoc {
    /// Name (`<joint>.a`, `base.x`, `device.rz`, `target.<name>.x`, effect names).
    pub name: String,
    /// `m`, `rad` or `1`.
    pub unit: &'static str,
    /// Nominal value (for device and targets: the `nominal` step's estimate).
    pub nominal: f64,
    /// Estimate.
    pub estimate: f64,
    /// Standard error; `None` when held fixed.
    pub std_error: Option<f64>,
    /// Estimated (`false`: held at nominal).
    pub free: bool,
}

/// A parameter held at nominal.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FixedDoc {
    /// Its name.
    pub name: String,
    /// The free parameters that absorb it.
    pub aliases: Vec<String>,
}

impl From<&dh_calib::calibrate::FixedParameter> for FixedDoc {
    fn from(f: &dh_calib::calibrate::FixedParameter) -> Self {
        FixedDoc {
            name: f.name.clone(),
            aliases: f.aliases.clone(),
        }
    }
}

/// How validation was done.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ValidationDoc {
    /// `split`, `k-fold` or `none`.
    pub method: &'static str,
    /// Validation samples (split).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub samples: Option<usize>,
    /// Folds (k-fold).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub folds: Option<usize>,
    /// Pose groups (k-fold).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub groups: Option<usize>,
    /// Training samples each fold is fitted on, when the data are too many to fit every
    /// fold on all of its training samples (k-fold beyond `dh_calib::calibrate::CV_TRAINING_MAX`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub training_subsample: Option<usize>,
}

/// Where the noise level comes from.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct NoiseDoc {
    /// Per-axis standard deviation (metres).
    pub sigma: f64,
    /// `given`, `samples` or `repeats`.
    pub source: &'static str,
}

/// A position with a name.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TargetDoc {
    /// Target name.
    pub name: String,
    /// Position in the tip frame (metres).
    pub xyz: [f64; 3],
}

/// A pose, metres and radians (URDF roll-pitch-yaw).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PoseSi {
    /// Translation (metres).
    pub xyz: [f64; 3],
    /// Roll, pitch, yaw (radians).
    pub rpy: [f64; 3],
}

impl PoseSi {
    /// The pose of `p`.
    pub fn of(p: &Isometry3<f64>) -> Self {
        let (xyz, rpy) = to_xyz_rpy(p);
        Self { xyz, rpy }
    }
}

/// The JSON report; every length in metres, every angle in radians.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CalibrationDoc {
    /// Model file, or `cpa of <data>`.
    pub model: String,
    /// Data file.
    pub data: String,
    /// Validation file.
    pub validate: Option<String>,
    /// Convention of the model.
    pub convention: ConventionDoc,
    /// Always `{length: m, angle: rad}`.
    pub units: UnitsDoc,
    /// Calibration samples.
    pub samples: usize,
    /// Validation samples (split).
    pub validation_samples: usize,
    /// How validation was done.
    pub validation: ValidationDoc,
    /// The steps, in order.
    pub steps: Vec<StepDoc>,
    /// Calibration RMS of `nominal`.
    pub rms_before: f64,
    /// Calibration RMS of the last step.
    pub rms_after: f64,
    /// Validation RMS of `nominal`.
    pub val_rms_before: Option<f64>,
    /// Validation RMS of the last step.
    pub val_rms_after: Option<f64>,
    /// RMS 3-D residual noise alone would leave (metres), when the noise is known.
    pub noise_floor: Option<f64>,
    /// RMS per axis of the orientation residuals noise alone would leave (radians), with
    /// 6-DoF pose samples; absent without them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub angle_noise_floor: Option<f64>,
    /// The noise level behind it.
    pub noise: Option<NoiseDoc>,
    /// Condition number of the scaled Jacobian of the free parameters.
    pub condition_number: f64,
    /// Free parameters of the last step.
    pub rank: usize,
    /// Residual standard deviation per coordinate (metres).
    pub sigma_hat: Option<f64>,
    /// Every parameter.
    pub parameters: Vec<ParameterDoc>,
    /// The parameters held at nominal.
    pub fixed: Vec<FixedDoc>,
    /// Labels of the effects estimated in the last step.
    pub selected_effects: Vec<String>,
    /// The candidate table of `--effects auto` (empty otherwise).
    pub candidates: Vec<CandidateDoc>,
    /// Estimated robot base in the device frame (of the first session with several).
    pub device: PoseSi,
    /// With several measurement sessions: each one's device frame and RMS; absent otherwise.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub sessions: Vec<super::calibrate_sessions::SessionDoc>,
    /// Estimated targets in the tip frame.
    pub targets: Vec<TargetDoc>,
    /// Remarks.
    pub notes: Vec<String>,
    /// The proof on the written model (`--out`), see [`crate::commands::written`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub written: Option<WrittenDoc>,
    /// The outlier screen; `null` when it did not run.
    pub outliers: Option<super::calibrate_findings::OutliersDoc>,
    /// The test of the final model and what it means.
    pub verdict: super::calibrate_findings::VerdictDoc,
    /// The rounds of `--effects` (every candidate's scores, every refit and why it was taken
    /// or not, the final structure); `null` without a diagnosis.
    pub diagnosis: Option<super::calibrate_findings::DiagnosisDoc>,
}

/// Units of the JSON report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct UnitsDoc {
    /// `m`.
    pub length: &'static str,
    /// `rad`.
    pub angle: &'static str,
}

/// The unit of a parameter, from its name (see `dh_calib::model`).
pub fn unit_of(name: &str) -> &'static str {
    if name.contains(':') || name == "scale" || name == "drift" {
        // Effect parameters (see `dh_calib::effects`).
        return match name.split(':').next() {
            Some("compliance" | "lateral_compliance") => "rad/(N m)",
            Some("gear_harmonic" | "gear_harmonic2" | "parallel_tilt" | "backlash") => "rad",
            // Radians, metres for a prismatic joint (the report's effect table says which).
            Some("backlash_direction") => "rad",
            Some("gear_ratio" | "coupling") => "rad/rad",
            _ => "1",
        };
    }
    match name.rsplit('.').next() {
        Some("a" | "d" | "x" | "y" | "z") => "m",
        Some("alpha" | "theta" | "beta" | "rx" | "ry" | "rz") => "rad",
        _ => "1",
    }
}

/// `table` as the calibrated model of `inputs` without effects (see [`calibrated_text`]), for
/// the contact and tree paths.
///
/// # Errors
/// Serialisation failures, and names or values a URDF cannot hold.
pub(crate) fn calibrated_bytes(
    path: &str,
    inputs: &Inputs,
    table: &DhTable,
    source: String,
    calibration: serde_yaml::Value,
) -> Result<String> {
    calibrated_text(path, inputs, table, source, calibration, Vec::new())
}

/// `table` as the calibrated model of `inputs` (its robot name, links, units and coupled
/// joints): a URDF for `.urdf`, else a sheet (JSON for `.json`, else YAML) with `source`, the
/// `calibration` section and the estimated `effects`.
///
/// # Errors
/// Serialisation failures, and names or values a URDF cannot hold.
pub(crate) fn calibrated_text(
    path: &str,
    inputs: &Inputs,
    table: &DhTable,
    source: String,
    calibration: serde_yaml::Value,
    effects: Vec<EffectDoc>,
) -> Result<String> {
    let lower = path.to_ascii_lowercase();
    let robot = inputs.robot.clone().unwrap_or_else(|| "robot".into());
    let bytes = if lower.ends_with(".urdf") {
        check_urdf(table, &robot, &inputs.links.0, &inputs.links.1)?;
        urdf_of(table, &robot, &inputs.links.0, &inputs.links.1)
    } else {
        let (lu, au) = inputs.units;
        let mut sheet = SheetDoc::from_table(table, lu, au);
        sheet.robot = inputs.robot.clone();
        if !inputs.coupled.is_empty() {
            sheet.coupled = Some(
                inputs
                    .coupled
                    .iter()
                    .map(|(j, t)| (j.clone(), t.iter().cloned().collect()))
                    .collect(),
            );
        }
        sheet.source = Some(source);
        sheet.calibration = Some(calibration);
        sheet.effects = (!effects.is_empty()).then_some(effects);
        if lower.ends_with(".json") {
            serde_json::to_string_pretty(&sheet)? + "\n"
        } else {
            serde_yaml::to_string(&sheet)?
        }
    };
    Ok(bytes)
}
