//! The report of a calibration as a plain document ([`CalibrationDoc`] and its parts): what
//! `urdf-dh calibrate --format json` prints, serialisable both ways with serde. Every length is
//! in metres, every angle in radians; [`unit_of`] names each parameter's unit. Poses are the
//! robot's base link frame in the device frame (`T_device_base`), as translation and URDF
//! roll-pitch-yaw.

use dh_core::pose::to_xyz_rpy;
use dh_core::Convention;
use nalgebra::Isometry3;
use serde::{Deserialize, Serialize};

use super::findings_doc::{DiagnosisDoc, OutliersDoc, VerdictDoc};

/// One row of the candidate table (JSON `candidates`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
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
    pub status: String,
    /// Why a refitted candidate was not added (a rival's names the effect that did better).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
}

impl From<&crate::findings::CandidateReport> for CandidateDoc {
    fn from(c: &crate::findings::CandidateReport) -> Self {
        CandidateDoc {
            label: c.label.clone(),
            score: c.score,
            val_rms: c.val_rms,
            independence: c.independence,
            status: c.status.name().to_string(),
            reason: c.reason.clone(),
        }
    }
}

/// A step as reported (metres).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
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
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angle_rms: Option<f64>,
    /// The same of the held-out samples (validation or cross-validation, as `val_rms`);
    /// absent without 6-DoF samples or without validation.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub val_angle_rms: Option<f64>,
    /// Parameters the step would estimate but held at their start, not identifiable from the
    /// data (in `nominal`: device or target coordinates), with what absorbs them.
    pub fixed: Vec<FixedDoc>,
}

/// One parameter as reported.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ParameterDoc {
    /// Name (`<joint>.a`, `base.x`, `device.rz`, `target.<name>.x`, effect names).
    pub name: String,
    /// `m`, `rad` or `1`.
    pub unit: String,
    /// Nominal value (for device and targets: the `nominal` step's estimate).
    pub nominal: f64,
    /// Estimate.
    pub estimate: f64,
    /// Standard error; `None` when held fixed.
    pub std_error: Option<f64>,
    /// Estimated (`false`: held at nominal).
    pub free: bool,
    /// Identified by this data: free, and for an effect's parameter an estimate at least
    /// [`IDENTIFIED_SIGMAS`] standard errors from zero; for a geometric parameter of the robot
    /// (a length or an angle; the setup's device, session and target frames are not judged) a
    /// standard error, as a length at the measured points, within [`super::GEOMETRIC_FLOOR_RATIO`] times the set's noise floor
    /// ([`ParameterDoc::identifies`], [`super::Identification`]). A parameter that is not is estimated
    /// and kept (the fit and its covariance are unchanged), but the data cannot tell it from
    /// no effect at all (an effect) or barely move it (a geometric parameter). Reports before
    /// this key read as `true`.
    #[serde(default = "identified_by_default")]
    pub identified: bool,
    /// A quantity derived from this parameter for reading, beside it ([`DerivedDoc::of`]: the
    /// time constant of `thermal_growth.ln_tau`); absent for other parameters. The parameter
    /// and the fit are unchanged.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub derived: Option<DerivedDoc>,
}

/// A quantity derived from a parameter for reading (JSON `parameters[].derived`), with its
/// standard error to first order (the delta method: `se_f = |f'(x)| se_x`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DerivedDoc {
    /// Name (`thermal_growth.tau`).
    pub name: String,
    /// Unit: `s`, or `session` (a fraction of the set's pose order, when the samples had no
    /// times).
    pub unit: String,
    /// Value at the parameter's estimate.
    pub estimate: f64,
    /// Standard error by the delta method; `None` without the parameter's.
    pub std_error: Option<f64>,
}

impl DerivedDoc {
    /// The quantity derived from parameter `name` estimated as `estimate` with `std_error`:
    /// for `thermal_growth.ln_tau`, the time constant `tau = exp(ln_tau)` (see
    /// `crate::effects_thermal`) with `se_tau = tau * se_ln_tau`, in seconds when the
    /// samples had times (`timed`), else in fractions of the session (the pose order from 0
    /// to 1). `None` for any other parameter, and when `tau` overflows a double.
    pub fn of(name: &str, estimate: f64, std_error: Option<f64>, timed: bool) -> Option<Self> {
        let ln_tau = crate::model::Effect::parameter_names(&crate::effects_thermal::ThermalGrowth)
            .into_iter()
            .nth(1)?;
        if name != ln_tau {
            return None;
        }
        let tau = estimate.exp();
        tau.is_finite().then(|| DerivedDoc {
            name: format!("{}.tau", crate::effects_thermal::LABEL),
            unit: if timed { "s" } else { "session" }.into(),
            estimate: tau,
            std_error: std_error.map(|se| tau * se).filter(|se| se.is_finite()),
        })
    }
}

fn identified_by_default() -> bool {
    true
}

/// How many standard errors from zero an effect parameter's estimate must be to count as
/// identified by the data ([`ParameterDoc::identified`]): below it, the two-sided 95 %
/// interval of the estimate (±1.96 SE, rounded up) holds zero, i.e. the data are as consistent
/// with no effect as with the estimate. Geometric parameters are not judged this way: their
/// nominal value is a design value and their correction can legitimately be about zero (the
/// data then confirm the nominal to that precision); they are judged by
/// [`super::GEOMETRIC_FLOOR_RATIO`].
pub const IDENTIFIED_SIGMAS: f64 = 2.0;

impl ParameterDoc {
    /// Whether a free parameter `name` estimated as `estimate` with standard error `std_error`
    /// (`None`: no covariance, nothing to judge by) is identified by the data (see
    /// [`ParameterDoc::identified`]): an effect's by [`IDENTIFIED_SIGMAS`], a geometric one's
    /// by [`super::GEOMETRIC_FLOOR_RATIO`] with `judge`.
    pub fn identifies(
        name: &str,
        estimate: f64,
        std_error: Option<f64>,
        judge: &super::Identification,
    ) -> bool {
        match std_error {
            None => true,
            Some(se) if super::is_effect(name) => estimate.abs() >= IDENTIFIED_SIGMAS * se,
            Some(_) => judge.identifies(name),
        }
    }

    /// Whether this is an effect's parameter (see [`super::is_effect`]), whatever its unit,
    /// free or held at the value the fit used (a time constant the data cannot tell is held at
    /// its start): the report lists only the fitted model's effects, so these are what a
    /// calibrated sheet's `effects` and `calibration.effects` list, and the model rebuilt from
    /// the sheet is the one fitted.
    pub fn is_effect(&self) -> bool {
        super::is_effect(&self.name)
    }
}

impl CalibrationDoc {
    /// The fitted effects' parameter values by name (SI units, see [`ParameterDoc::is_effect`]):
    /// what a calibrated model's `calibration.effects` lists.
    pub fn estimated_effects(&self) -> Vec<(String, f64)> {
        self.parameters
            .iter()
            .filter(|p| p.is_effect())
            .map(|p| (p.name.clone(), p.estimate))
            .collect()
    }

    /// What the `t` of its effects of time was, for the calibrated sheet
    /// (`calibration.time_unit`): [`crate::effects_thermal::TimeUnit::of_calibration`] of its
    /// estimated effect parameters and the `data` it was fitted to; `None` without an effect of
    /// time.
    pub fn time_unit(
        &self,
        data: &crate::data::Measurements,
    ) -> Option<crate::effects_thermal::TimeUnit> {
        crate::effects_thermal::TimeUnit::of_calibration(
            self.parameters
                .iter()
                .filter(|p| p.is_effect())
                .map(|p| p.name.as_str()),
            data,
        )
    }

    /// How the held-out figures were made, in words (the text report's `data:` line and the
    /// report page): the held-out samples of a split, or the folds, poses and fit of a k-fold
    /// cross-validation.
    pub fn validation_words(&self) -> String {
        match self.validation.method.as_str() {
            "split" => format!(
                "validation on {} held-out samples{}",
                self.validation_samples,
                self.validate
                    .as_deref()
                    .map(|v| format!(" ({v})"))
                    .unwrap_or_default()
            ),
            "k-fold" => format!(
                "{}-fold cross-validation over {} poses{}{}",
                self.validation.folds.unwrap_or(0),
                self.validation.groups.unwrap_or(0),
                self.validation
                    .training_subsample
                    .map(|n| {
                        format!(" (each fold fitted on about {n} evenly spaced training samples)")
                    })
                    .unwrap_or_default(),
                if self.validation.fold_fits.as_deref() == Some("one-step") {
                    " (each fold one Gauss-Newton step from the fit of all samples)"
                } else {
                    ""
                }
            ),
            _ => "no validation (fewer than 2 poses)".into(),
        }
    }
}

/// A parameter held at nominal.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FixedDoc {
    /// Its name.
    pub name: String,
    /// The free parameters that absorb it.
    pub aliases: Vec<String>,
}

impl From<&crate::calibrate::FixedParameter> for FixedDoc {
    fn from(f: &crate::calibrate::FixedParameter) -> Self {
        FixedDoc {
            name: f.name.clone(),
            aliases: f.aliases.clone(),
        }
    }
}

/// How validation was done.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ValidationDoc {
    /// `split`, `k-fold` or `none`.
    pub method: String,
    /// Validation samples (split).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub samples: Option<usize>,
    /// Folds (k-fold).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub folds: Option<usize>,
    /// Pose groups (k-fold).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub groups: Option<usize>,
    /// About how many training samples each fold is fitted on (its share of one evenly spaced
    /// pool), when the data are too many to fit every fold on all of its training samples
    /// (k-fold beyond [`crate::calibrate::CV_TRAINING_MAX`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub training_subsample: Option<usize>,
    /// `one-step` when each fold's figures come from one Gauss-Newton step from the fit of
    /// all samples (the automatic diagnosis); absent when each fold is refitted.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fold_fits: Option<String>,
}

/// Where the noise level comes from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NoiseDoc {
    /// Per-axis standard deviation (metres).
    pub sigma: f64,
    /// `given`, `samples` or `repeats`.
    pub source: String,
}

/// A position with a name.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TargetDoc {
    /// Target name.
    pub name: String,
    /// Position in the tip frame (metres).
    pub xyz: [f64; 3],
    /// For a target measured as a 6-DoF pose: its frame's rotation in the tip frame as URDF
    /// roll, pitch, yaw (radians); absent for a point target.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rpy: Option<[f64; 3]>,
}

impl TargetDoc {
    /// The documents of named target positions (tip frame, metres), in order.
    pub fn list(targets: &[(String, nalgebra::Vector3<f64>)]) -> Vec<TargetDoc> {
        targets
            .iter()
            .map(|(n, p)| TargetDoc {
                name: n.clone(),
                xyz: [p.x, p.y, p.z],
                rpy: None,
            })
            .collect()
    }

    /// [`TargetDoc::list`] with each target's rotation in the tip frame where it has one
    /// (`rotations` in the same order; missing entries are point targets).
    pub fn list_with(
        targets: &[(String, nalgebra::Vector3<f64>)],
        rotations: &[Option<nalgebra::UnitQuaternion<f64>>],
    ) -> Vec<TargetDoc> {
        let mut docs = Self::list(targets);
        for (d, r) in docs.iter_mut().zip(rotations) {
            d.rpy = r.map(|q| {
                let (roll, pitch, yaw) = q.euler_angles();
                [roll, pitch, yaw]
            });
        }
        docs
    }
}

/// A pose, metres and radians (URDF roll-pitch-yaw).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
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
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
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
    #[serde(default, skip_serializing_if = "Option::is_none")]
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
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub sessions: Vec<SessionDoc>,
    /// Estimated targets in the tip frame.
    pub targets: Vec<TargetDoc>,
    /// Remarks.
    pub notes: Vec<String>,
    /// The proof on the written model (`urdf-dh calibrate --out`): filled in by the writer, `None`
    /// from [`CalibrationDoc::new`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub written: Option<WrittenDoc>,
    /// The outlier screen; `null` when it did not run.
    pub outliers: Option<OutliersDoc>,
    /// The test of the final model and what it means.
    pub verdict: VerdictDoc,
    /// The rounds of `--effects` (every candidate's scores, every refit and why it was taken
    /// or not, the final structure); `null` without a diagnosis.
    pub diagnosis: Option<DiagnosisDoc>,
}

/// Units of the JSON report.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct UnitsDoc {
    /// `m`.
    pub length: String,
    /// `rad`.
    pub angle: String,
}

/// The unit of a parameter, from its name (see [`crate::model`]).
pub fn unit_of(name: &str) -> &'static str {
    if super::is_effect(name) {
        // Effect parameters (see `crate::effects`).
        return match name.split(':').next() {
            Some("compliance" | "lateral_compliance") => "rad/(N m)",
            Some("gear_harmonic" | "gear_harmonic2" | "parallel_tilt" | "backlash") => "rad",
            // Radians, metres for a prismatic joint (the report's effect table says which).
            Some("backlash_direction") => "rad",
            Some("gear_ratio" | "coupling") => "rad/rad",
            // `thermal_growth.ln_tau`: the natural log of tau in seconds.
            Some("thermal_growth.ln_tau") => "ln s",
            // Metres of sag at a lever arm of 1 m (see `crate::effects::GravitySag`).
            Some("gravity_sag") => "1/m^2",
            _ => "1",
        };
    }
    match name.rsplit('.').next() {
        Some("a" | "d" | "x" | "y" | "z") => "m",
        Some("alpha" | "theta" | "beta" | "rx" | "ry" | "rz") => "rad",
        _ => "1",
    }
}

/// The unit of parameter `name` in a calibration whose samples had times (`timed`) or not:
/// [`unit_of`], except `thermal_growth.ln_tau`, the natural log of tau in fractions of the
/// session (`ln session`: the pose order from 0 to 1, see `crate::effects_thermal`) when the
/// samples had no times.
pub fn unit_in(name: &str, timed: bool) -> &'static str {
    match unit_of(name) {
        "ln s" if !timed => "ln session",
        unit => unit,
    }
}

/// The DH convention of a report's model: `standard` or `modified`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ConventionDoc {
    /// Standard (distal) DH.
    Standard,
    /// Modified (Craig) DH.
    Modified,
}

impl From<Convention> for ConventionDoc {
    fn from(c: Convention) -> Self {
        match c {
            Convention::Standard => ConventionDoc::Standard,
            Convention::Modified => ConventionDoc::Modified,
        }
    }
}

impl From<ConventionDoc> for Convention {
    fn from(c: ConventionDoc) -> Self {
        match c {
            ConventionDoc::Standard => Convention::Standard,
            ConventionDoc::Modified => Convention::Modified,
        }
    }
}

/// The proof on a written calibrated model: what reading it back found (metres).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WrittenDoc {
    /// The file written (or, when the proof failed, not written).
    pub path: String,
    /// Predicted points compared.
    pub points: usize,
    /// Largest distance between the artefact's prediction and the fitted model's (metres).
    pub max_deviation: f64,
    /// The bound it must stay within.
    pub bound: f64,
    /// Largest written length (metres): `|a|`, `|d|`, base and tool offsets.
    pub max_length: f64,
    /// The bound on lengths: the nominal model's size plus a margin.
    pub length_bound: f64,
    /// Both within their bounds; the file is written only then.
    pub passed: bool,
}

/// One measurement session in the report (see [`crate::sessions`]; metres, radians).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SessionDoc {
    /// The session's name (the `session` column).
    pub name: String,
    /// Its device frame: the robot base in the device frame.
    pub device: PoseSi,
    /// Its calibration samples.
    pub samples: usize,
    /// RMS distance of its calibration samples at the final fit (metres).
    pub rms: Option<f64>,
    /// Its validation samples.
    pub validation_samples: usize,
    /// RMS distance of its validation samples at the final fit (metres).
    pub val_rms: Option<f64>,
    /// `true`: no calibration sample, the frame was fitted on its validation samples with the
    /// robot fixed (6 parameters).
    pub fitted_on_validation: bool,
}

/// A session's device frame as a calibrated sheet's `calibration.sessions` list holds it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SessionFrameDoc {
    /// The session's name.
    pub name: String,
    /// Translation (metres).
    pub xyz: [f64; 3],
    /// Roll, pitch, yaw (radians).
    pub rpy: [f64; 3],
}

impl SessionDoc {
    /// The frames of every session of `docs` but the first (whose frame the report's and the
    /// sheet's `device` holds).
    pub fn frames(docs: &[SessionDoc]) -> Vec<SessionFrameDoc> {
        docs.iter()
            .skip(1)
            .map(|s| SessionFrameDoc {
                name: s.name.clone(),
                xyz: s.device.xyz,
                rpy: s.device.rpy,
            })
            .collect()
    }
}

#[cfg(test)]
mod derived_tests {
    use super::{unit_in, DerivedDoc};

    /// `ln_tau` is in `ln s` with times, in `ln session` without; the other parameters'
    /// units do not depend on it.
    #[test]
    fn ln_tau_is_in_ln_seconds_or_ln_sessions() {
        assert_eq!(unit_in("thermal_growth.ln_tau", true), "ln s");
        assert_eq!(unit_in("thermal_growth.ln_tau", false), "ln session");
        assert_eq!(unit_in("thermal_growth.k", false), "1");
        assert_eq!(unit_in("gravity_sag:j2", false), "1/m^2");
        assert_eq!(unit_in("j2.a", false), "m");
    }

    /// tau = exp(ln_tau) with se_tau = tau se_ln_tau: ln 1200 +- 0.25 is 1200 +- 300 s.
    #[test]
    fn thermal_growth_tau_is_exp_ln_tau_with_its_delta_method_error() {
        let d = DerivedDoc::of("thermal_growth.ln_tau", 1200f64.ln(), Some(0.25), true)
            .expect("ln_tau derives tau");
        assert_eq!(
            (d.name.as_str(), d.unit.as_str()),
            ("thermal_growth.tau", "s")
        );
        assert!((d.estimate - 1200.0).abs() < 1e-9, "{}", d.estimate);
        assert!((d.std_error.unwrap_or(f64::NAN) - 300.0).abs() < 1e-9);
        let untimed = DerivedDoc::of("thermal_growth.ln_tau", -1.0, None, false);
        assert_eq!(
            untimed.map(|d| (d.unit, d.std_error)),
            Some(("session".into(), None))
        );
        assert_eq!(
            DerivedDoc::of("thermal_growth.k", 6e-5, Some(1e-6), true),
            None
        );
        assert_eq!(
            DerivedDoc::of("thermal_growth.ln_tau", 1e3, Some(1.0), true),
            None
        );
    }
}
