//! The options of a calibration ([`CalibrationOptions`]): noise, validation split or
//! k-fold cross-validation, outlier screen, effect models and their defaults.

use super::*;

/// Options of [`calibrate`].
#[derive(Clone, Debug)]
pub struct CalibrationOptions {
    /// Parametrisation (Hayati threshold, scales).
    pub model: ModelOptions,
    /// Solver options; `fit.rank_tolerance` also decides identifiability.
    pub fit: FitOptions,
    /// Folds of cross-validation when there is no validation split (at least 2). Default 5.
    pub folds: usize,
    /// A start for `T_device_base` instead of the closed-form registration.
    pub device_guess: Option<Isometry3<f64>>,
    /// Starts for the target positions in the tip frame (one per target).
    pub target_guesses: Option<Vec<Vector3<f64>>>,
    /// Known per-axis measurement noise (metres); overrides the samples' own `sigma`.
    pub sigma: Option<f64>,
    /// Non-geometric effects to estimate in a last step.
    pub effects: Vec<Arc<dyn Effect>>,
    /// For a tree ([`calibrate_tree`]): `(target, branch)` pairs saying which branch a target
    /// rides on. A target without an entry rides on the branch of its own name, or on the only
    /// chain of a serial robot.
    pub target_branches: Vec<(String, String)>,
    /// Outlier screening before the fit ([`crate::outliers`]): on by default, flagged points
    /// left out unless `keep`.
    pub outliers: crate::outliers::OutlierOptions,
    /// The gravity of the verdict's gravity structure tests (`structure`): its direction for
    /// the lever arms and, when it has link masses, the torques about each joint. `None`:
    /// gravity along `-z` of the base link, no torque test. [`crate::diagnose`] sets it from
    /// its inertials and gravity.
    pub gravity: Option<Arc<crate::gravity::GravityModel>>,
}

impl Default for CalibrationOptions {
    fn default() -> Self {
        Self {
            model: ModelOptions::default(),
            fit: FitOptions::default(),
            folds: 5,
            device_guess: None,
            target_guesses: None,
            sigma: None,
            effects: Vec::new(),
            target_branches: Vec::new(),
            outliers: crate::outliers::OutlierOptions::default(),
            gravity: None,
        }
    }
}
