//! What one sample measures ([`Observation`]: a target's position or the tip frame's pose in
//! the device frame, metres and radians) and where it sits in the measurement sequence.

use std::sync::Arc;

use nalgebra::{Isometry3, Vector3};

/// What is measured in one sample.
///
/// The poses are boxed: most samples of a large set are points, and the enum's size (40
/// bytes) is paid by every prepared sample.
#[derive(Clone, Debug, PartialEq)]
pub enum Observation {
    /// A target's position in the device frame (3 residuals: model minus measured, metres).
    Point {
        /// Target index.
        target: usize,
        /// Measured position (metres).
        point: Vector3<f64>,
    },
    /// The tip frame's pose in the device frame (6 residuals: position difference in metres,
    /// then `orientation_scale · log(R_model R_measuredᵀ)` as a rotation vector).
    Pose(Box<Isometry3<f64>>),
    /// A target's frame in the device frame, measured by a 6-DoF device (a tracker's 6-DoF
    /// probe, an optical marker body): 6 residuals, the position difference (metres) as for
    /// [`Observation::Point`], then `weight · log(R_model R_measuredᵀ)` (a rotation vector in
    /// the device frame, radians, times `weight`). With `weight = σ_position / σ_rotation`
    /// (metres per radian) all six are in metres of equal variance: dividing them by
    /// `σ_position` whitens them. The target needs an orientation
    /// ([`crate::model::Model::add_target_orientation`]), else its frame is the tip frame's
    /// orientation.
    TargetPose {
        /// Target index.
        target: usize,
        /// Measured pose of the target frame in the device frame (metres, rotation).
        pose: Box<Isometry3<f64>>,
        /// Metres per radian of orientation residual (`σ_position / σ_rotation`), positive.
        weight: f64,
    },
}

impl Observation {
    /// Number of residuals: 3 for a point, 6 for a pose.
    pub fn residual_count(&self) -> usize {
        match self {
            Observation::Point { .. } => 3,
            Observation::Pose(_) | Observation::TargetPose { .. } => 6,
        }
    }

    /// The measured position in the device frame (metres).
    pub fn position(&self) -> Vector3<f64> {
        match self {
            Observation::Point { point, .. } => *point,
            Observation::Pose(p) | Observation::TargetPose { pose: p, .. } => p.translation.vector,
        }
    }
}

/// Where a sample sits in the measurement sequence (the file's sample order): what effects
/// of the motion history and of time see besides the joint values
/// ([`Effect::delta_in`](super::Effect::delta_in)). Built by [`crate::effects_order::sequence_contexts`]; the default
/// (no direction, order 0) is the neutral context of a pose outside any sequence (a
/// prediction, a synthetic sample).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct SampleContext {
    /// Per row (tree joint order): the sign of the joint's last motion before this pose,
    /// `-1`, `0` (not moved yet) or `+1`; empty means 0 for every row.
    pub direction: Vec<f64>,
    /// The pose's place in the sequence, normalised to `[0, 1]` (0 the first pose, 1 the
    /// last; repeats of one pose share it). Dimensionless.
    pub order: f64,
    /// The sample's time since the set's first timed sample (seconds), when the samples carry
    /// a time ([`crate::data::Sample::time`]); `None` otherwise.
    pub time: Option<f64>,
}

impl SampleContext {
    /// The direction of row `row` (0 when not given).
    pub fn direction_of(&self, row: usize) -> f64 {
        self.direction.get(row).copied().unwrap_or(0.0)
    }
}

/// One sample: joint values in row order, its place in the sequence and what was measured
/// there.
#[derive(Clone, Debug, PartialEq)]
pub struct Observed {
    /// One value per table row (radians or metres); shared with the measured sample's own
    /// ([`crate::data::Sample::q`]) when they are the same values.
    pub q: Arc<[f64]>,
    /// The measurement.
    pub observation: Observation,
    /// Measurement session (index into [`crate::data::Measurements::sessions`]): which device
    /// frame measured it. Sessions without their own block ([`Model::add_session`](super::Model::add_session)) use the
    /// `device` block.
    pub session: usize,
    /// Its place in the measurement sequence (neutral by default).
    pub context: SampleContext,
}

impl Observed {
    /// A sample in the neutral context.
    pub fn new(q: impl Into<Arc<[f64]>>, observation: Observation) -> Self {
        Self {
            q: q.into(),
            observation,
            session: 0,
            context: SampleContext::default(),
        }
    }
}
