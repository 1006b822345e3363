//! What a calibration reports: error statistics per step ([`Stats`], [`StepReport`]), how
//! it was validated ([`Validation`]), the noise floor ([`NoiseFloor`]), the parameter
//! estimates with standard errors ([`ParameterEstimate`]), the parameters fixed at nominal
//! ([`FixedParameter`]), and the whole [`Report`]. Lengths in metres, angles in radians.

use super::*;

/// Distances between modelled and measured points (metres).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stats {
    /// Root mean square of the 3-D distances.
    pub rms: f64,
    /// Mean distance.
    pub mean: f64,
    /// Largest distance.
    pub max: f64,
    /// Number of points.
    pub count: usize,
}

impl Stats {
    /// Statistics of `distances`; `None` when empty.
    pub fn of(distances: &[f64]) -> Option<Stats> {
        if distances.is_empty() {
            return None;
        }
        let n = distances.len() as f64;
        Some(Stats {
            rms: (distances.iter().map(|d| d * d).sum::<f64>() / n).sqrt(),
            mean: distances.iter().sum::<f64>() / n,
            max: distances.iter().copied().fold(0.0, f64::max),
            count: distances.len(),
        })
    }
}

/// One step of the pipeline.
#[derive(Clone, Debug, PartialEq)]
pub struct StepReport {
    /// `nominal`, `geometric` or `effects`; the effect steps of [`crate::diagnose`] are
    /// `+<label>`.
    pub label: String,
    /// Calibration RMS before the step (the previous step's), metres; `None` for the first.
    pub rms_before: Option<f64>,
    /// Validation RMS before the step (the previous step's), metres.
    pub val_rms_before: Option<f64>,
    /// RMS distance on the calibration samples (metres).
    pub rms: f64,
    /// Mean distance on the calibration samples (metres).
    pub mean: f64,
    /// Largest distance on the calibration samples (metres).
    pub max: f64,
    /// RMS distance on validation (metres); `None` when there is nothing to validate on.
    pub val_rms: Option<f64>,
    /// Mean distance on validation (metres).
    pub val_mean: Option<f64>,
    /// Largest distance on validation (metres).
    pub val_max: Option<f64>,
    /// Number of free parameters.
    pub free: usize,
    /// RMS per axis of the orientation residuals `log(R_model R_measuredᵀ)` of the
    /// calibration samples that measure a 6-DoF pose (radians); `None` without such samples.
    pub angle_rms: Option<f64>,
    /// The same of the held-out samples (validation or cross-validation, as
    /// [`StepReport::val_rms`]); `None` without them or without validation.
    pub val_angle_rms: Option<f64>,
    /// Solver iterations.
    pub iterations: usize,
    /// Why the solver stopped.
    pub termination: Termination,
    /// Parameters this step would estimate but held at their start because the data cannot
    /// identify them, with the free parameters that absorb them: in `nominal`, device or target
    /// coordinates (targets seen at one tool orientation only alias with the device frame); in
    /// later steps the same list as [`Report::fixed`].
    pub fixed: Vec<FixedParameter>,
}

/// How validation figures were obtained.
#[derive(Clone, Debug, PartialEq)]
pub enum Validation {
    /// On the samples marked [`crate::data::Split::Validation`].
    Split {
        /// Their number.
        samples: usize,
    },
    /// k-fold cross-validation over pose groups of the calibration samples.
    CrossValidation {
        /// Number of folds.
        folds: usize,
        /// Number of pose groups.
        groups: usize,
        /// Beyond [`CV_TRAINING_MAX`] calibration samples, each fold is fitted on about this
        /// many of its training samples, its share of one evenly spaced pool (see
        /// [`CV_TRAINING_MAX`]; every held-out sample is still predicted): the held-out figure
        /// is then that of a model fitted on fewer samples, so it errs on the high side.
        /// `None`: every training sample.
        training_subsample: Option<usize>,
        /// Each fold's held-out figures from one Gauss-Newton step from the fit of all
        /// samples (the automatic diagnosis: its trials, and the steps it lists, see
        /// `docs/results.md`), instead of a Levenberg-Marquardt refit of the fold (`false`).
        /// On the real sets of `docs/results.md` the two differ by at most 0.11 µm in a
        /// step's held-out RMS and 2.5 µm in its maximum.
        one_step: bool,
    },
    /// Too few pose groups for either.
    None,
}

/// Where the noise floor comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum NoiseSource {
    /// The `sigma` option.
    Given,
    /// Every sample's own `sigma`.
    Samples,
    /// Pure error of repeated measurements (samples sharing `config` and target).
    Repeats {
        /// Groups with at least two samples.
        groups: usize,
        /// Degrees of freedom of the pooled estimate.
        dof: usize,
    },
}

/// The RMS 3-D residual that noise alone would leave after the fit.
#[derive(Clone, Debug, PartialEq)]
pub struct NoiseFloor {
    /// `sqrt(E‖e‖² · (1 − p / m))` with `E‖e‖²` the expected squared 3-D noise of one point
    /// (`3σ²` for isotropic σ), `p` free parameters and `m` calibration residuals (3 per
    /// point, 6 per 6-DoF pose: `3N` for points only) (metres).
    pub rms: f64,
    /// Per-axis noise standard deviation it corresponds to, `sqrt(E‖e‖² / 3)` (metres).
    pub sigma: f64,
    /// For 6-DoF poses, the floor of [`StepReport::angle_rms`]: the RMS of the samples'
    /// `sigma_rot` times `sqrt(1 − p / m)` (radians); `None` without poses.
    pub angle_rms: Option<f64>,
    /// Where it comes from.
    pub source: NoiseSource,
}

/// One parameter's estimate.
#[derive(Clone, Debug, PartialEq)]
pub struct ParameterEstimate {
    /// Name (see [`crate::model`]).
    pub name: String,
    /// Nominal value: the table's value for DH parameters (0 for `beta`), the table's base and
    /// tool as `x y z` metres and roll-pitch-yaw radians (`R = Rz(rz) Ry(ry) Rx(rx)`, URDF
    /// convention), and for the device frame (`T_device_base`, same layout) and targets the
    /// `nominal` step's estimate.
    pub nominal: f64,
    /// Estimated value, same layout.
    pub estimate: f64,
    /// Standard error (same unit), `None` when held fixed. For pose blocks it is propagated from
    /// the fit's small motions to `x y z` / roll-pitch-yaw to first order.
    pub std_error: Option<f64>,
    /// `true` when estimated, `false` when held at nominal.
    pub free: bool,
}

/// A parameter held at nominal because the data cannot identify it.
#[derive(Clone, Debug, PartialEq)]
pub struct FixedParameter {
    /// Its name.
    pub name: String,
    /// Names of the free parameters that absorb its error (its null-space partners), empty
    /// when it has no effect on the data at all.
    pub aliases: Vec<String>,
}

/// The calibration's result. Lengths in metres, angles in radians.
#[derive(Clone, Debug, PartialEq)]
pub struct Report {
    /// One entry per step, in order.
    pub steps: Vec<StepReport>,
    /// Calibration RMS of the `nominal` step.
    pub rms_before: f64,
    /// Calibration RMS of the last step.
    pub rms_after: f64,
    /// Validation RMS of the `nominal` step.
    pub val_rms_before: Option<f64>,
    /// Validation RMS of the last step.
    pub val_rms_after: Option<f64>,
    /// How validation was done.
    pub validation: Validation,
    /// Noise floor, when the noise is known or can be estimated from repeats.
    pub noise_floor: Option<NoiseFloor>,
    /// Condition number of the scaled Jacobian of the free parameters at the estimate.
    pub condition_number: f64,
    /// Number of free parameters in the last step.
    pub rank: usize,
    /// Residual standard deviation per coordinate, `sqrt(ssr / (3N − p))` (metres).
    pub sigma_hat: Option<f64>,
    /// Characteristic length that scaled the angle columns (metres).
    pub length_scale: f64,
    /// The relative singular value threshold used for identifiability.
    pub rank_tolerance: f64,
    /// Every parameter of the model.
    pub parameters: Vec<ParameterEstimate>,
    /// The parameters held at nominal, with their aliases.
    pub fixed: Vec<FixedParameter>,
    /// Classic DH or Hayati-Mirmirani for each consecutive pair of joints.
    pub parametrisation: Vec<PairParametrisation>,
    /// The calibrated table, Hayati tilts in their rows' `beta` (see [`Model::table_at`]).
    pub calibrated: DhTable,
    /// Estimated `T_device_base` (of the first calibration session when there are several).
    pub device: Isometry3<f64>,
    /// Every session's device frame and RMS (one entry for a set without sessions); the first
    /// is the session of `device`.
    pub sessions: Vec<crate::sessions::SessionReport>,
    /// Estimated target positions in the tip frame.
    pub targets: Vec<(String, Vector3<f64>)>,
    /// Estimated rotation of each target's frame in the tip frame, for targets measured as
    /// 6-DoF poses (`None` for a point target), in the order of `targets`.
    pub target_rotations: Vec<Option<nalgebra::UnitQuaternion<f64>>>,
    /// Remarks for the user (unused targets, approximations).
    pub notes: Vec<String>,
    /// For a tree: the calibrated tree (its trunk is `calibrated`); `None` for a serial robot.
    pub tree: Option<crate::tree::DhTree>,
    /// The effects' candidate table of the automatic diagnosis ([`crate::diagnose`]), in the
    /// order scored in its first round; empty otherwise.
    pub candidates: Vec<crate::findings::CandidateReport>,
    /// Labels of the effects estimated in the last step, in the order added.
    pub selected_effects: Vec<String>,
    /// What the automatic diagnosis found; `None` when it did not run.
    pub diagnosis: Option<crate::findings::Diagnosis>,
    /// What the outlier screen found; `None` when it did not run.
    pub outliers: Option<crate::outliers::OutlierReport>,
    /// The test of the final model against the noise, and what it means.
    pub verdict: crate::findings::Verdict,
    /// Covariance of the last step's free parameters (see [`crate::covariance`]); `None` when
    /// the residual's sigma is unknown (no more coordinates than parameters).
    pub covariance: Option<crate::covariance::Covariance>,
}
