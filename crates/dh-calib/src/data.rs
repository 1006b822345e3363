//! Measurement sets: joint values and measured target positions.
//!
//! Frames and units: joint values in radians (metres for prismatic joints); measured points in
//! the measuring device's own frame, metres.

use nalgebra::Vector3;

/// Which part of the data a sample belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Split {
    /// Used to fit parameters.
    Calibration,
    /// Held out to judge the fit.
    Validation,
}

/// One measured point.
#[derive(Clone, Debug, PartialEq)]
pub struct Sample {
    /// One value per entry of [`Measurements::joint_names`] (radians or metres).
    pub q: Vec<f64>,
    /// Index into [`Measurements::targets`]: which reflector or marker was measured.
    pub target: usize,
    /// Measured position in the device frame (metres).
    pub point: Vector3<f64>,
    /// Per-axis standard deviation of `point` (metres), when known.
    pub sigma: Option<Vector3<f64>>,
    /// Pose identifier: samples with the same id repeat one pose (pure error).
    pub config: Option<String>,
    /// Calibration or validation.
    pub split: Split,
    /// 1-based line in the source file (0 when generated).
    pub line: usize,
}

/// A measurement set.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Measurements {
    /// Joint names, in the order of every sample's `q`.
    pub joint_names: Vec<String>,
    /// Target (reflector, marker) names; a set with one target has one entry.
    pub targets: Vec<String>,
    /// The samples, in file order.
    pub samples: Vec<Sample>,
}
