//! What circle-point analysis finds, per sweep ([`Sweep`], [`Coupled`]), per target
//! ([`TargetFit`], [`PoseResidual`], the trends of the residual against the joint value) and per
//! joint ([`JointCpa`], [`MotionCheck`]), and the whole [`CpaResult`]. Device frame, metres,
//! radians.

use super::*;

/// A joint that moved with the lead joint of a sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct Coupled {
    /// Index into `Measurements::joint_names`.
    pub joint: usize,
    /// Its name.
    pub name: String,
    /// `Δq_joint / Δq_lead` over the sweep (the Boby J2 block: −1). When the sweep is used, the
    /// joint's serial (DH) variable is `q_joint − ratio · q_lead`.
    pub ratio: f64,
}

/// A run of poses in which one joint (or one proportional group) moves.
#[derive(Clone, Debug, PartialEq)]
pub struct Sweep {
    /// The moving joint (the one nearest the base for a coupled sweep): index into
    /// `Measurements::joint_names`.
    pub joint: usize,
    /// Its name.
    pub name: String,
    /// Joints that moved with it in fixed proportion; empty for a one-joint sweep.
    pub coupled: Vec<Coupled>,
    /// Indices into `Measurements::samples`, in file order.
    pub samples: Vec<usize>,
    /// Number of distinct poses.
    pub poses: usize,
    /// Joint values at the first pose.
    pub start: Vec<f64>,
    /// Largest minus smallest commanded value of the joint (radians or metres).
    pub span: f64,
    /// 1-based lines of the first and last sample.
    pub lines: (usize, usize),
    /// Whether this sweep defines the joint's axis.
    pub used: bool,
}

/// One target's own fit in a sweep, before the targets are combined.
#[derive(Clone, Debug, PartialEq)]
pub struct TargetFit {
    /// Index into `Measurements::targets`.
    pub target: usize,
    /// Its name.
    pub name: String,
    /// Points fitted.
    pub points: usize,
    /// Circle centre (revolute) or centroid (prismatic), device frame at the sweep's
    /// configuration (metres).
    pub centre: Vector3<f64>,
    /// Plane normal (revolute) or line direction (prismatic), sensed like the joint axis.
    pub direction: Vector3<f64>,
    /// Radius of the circle (metres); `None` for a prismatic joint.
    pub radius: Option<f64>,
    /// RMS in-plane distance of the points from the target's own circle (revolute) or RMS
    /// distance from its own line (prismatic), metres.
    pub path_rms: f64,
    /// RMS distance of the points from the target's own plane (metres); `None` for prismatic.
    pub plane_rms: Option<f64>,
    /// Distance from `centre` to the joint axis (metres): 0 for concentric circles.
    pub axis_offset: f64,
    /// Angle between `direction` and the joint axis (radians).
    pub axis_tilt: f64,
}

/// The commanded joint value against the motion measured on a pose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseResidual {
    /// Commanded joint value (radians or metres).
    pub commanded: f64,
    /// Measured minus commanded change, mean removed (radians or metres).
    pub residual: f64,
}

/// A straight-line trend of the residuals: `residual ≈ offset + slope · commanded`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearTrend {
    /// Dimensionless: the measured motion is `(1 + slope)` times the commanded one (a gear-ratio
    /// or, for prismatic joints, scale error).
    pub slope: f64,
    /// RMS of the residuals after removing the line (radians or metres).
    pub rms: f64,
}

/// A once-per-turn trend: `residual ≈ c + amplitude · sin(commanded + phase)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SinusoidTrend {
    /// Amplitude (radians): for a transmission with an eccentric output, eccentricity over radius.
    pub amplitude: f64,
    /// Phase (radians).
    pub phase: f64,
    /// RMS after removing the sinusoid (radians).
    pub rms: f64,
}

/// Line and sinusoid fitted together: `c + slope · q + amplitude · sin(q + phase)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CombinedTrend {
    /// As [`LinearTrend::slope`].
    pub slope: f64,
    /// As [`SinusoidTrend::amplitude`] (radians).
    pub amplitude: f64,
    /// As [`SinusoidTrend::phase`] (radians).
    pub phase: f64,
    /// RMS after removing both (radians).
    pub rms: f64,
}

/// Commanded against measured joint motion over a sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct MotionCheck {
    /// One entry per pose, in sweep order.
    pub poses: Vec<PoseResidual>,
    /// RMS of the residuals (radians, metres for prismatic joints).
    pub rms: f64,
    /// Linear trend; `None` with fewer than three poses.
    pub linear: Option<LinearTrend>,
    /// Once-per-turn sinusoid; revolute joints with at least four poses.
    pub sinusoid: Option<SinusoidTrend>,
    /// Both; revolute joints with at least five poses spanning at least half a turn.
    pub combined: Option<CombinedTrend>,
}

/// What the analysis found about one joint.
#[derive(Clone, Debug, PartialEq)]
pub struct JointCpa {
    /// Index into `Measurements::joint_names`.
    pub joint: usize,
    /// Joint name.
    pub name: String,
    /// Revolute or prismatic.
    pub kind: JointKind,
    /// Index into [`CpaResult::sweeps`] of the sweep used.
    pub sweep: usize,
    /// The fitted axis at the sweep's configuration, device frame, sensed by the right-hand
    /// rule (for a prismatic joint: the direction of motion through the sweep's mean point).
    pub axis: Line,
    /// The targets' own fits.
    pub targets: Vec<TargetFit>,
    /// Points fitted (all targets).
    pub points: usize,
    /// Distinct poses.
    pub poses: usize,
    /// Largest target radius (metres); `None` for prismatic joints.
    pub radius: Option<f64>,
    /// RMS radial distance of all points from their circles about the common axis (metres);
    /// for prismatic joints the RMS distance from the fitted lines.
    pub circle_rms: f64,
    /// RMS distance of all points from their circles' planes, perpendicular to the common axis
    /// (metres); `None` for prismatic joints.
    pub plane_rms: Option<f64>,
    /// Commanded span (radians or metres).
    pub span: f64,
    /// Commanded against measured motion.
    pub motion: MotionCheck,
    /// The outlier screen of the sweep: the points left out of every figure above, named
    /// (see the `screen` step of the module docs).
    pub screen: SweepScreen,
}

/// The result of [`analyse`].
#[derive(Clone, Debug, PartialEq)]
pub struct CpaResult {
    /// Every sweep found, in file order.
    pub sweeps: Vec<Sweep>,
    /// One entry per joint, in `Measurements::joint_names` order.
    pub joints: Vec<JointCpa>,
    /// The joint axes at `q = 0` in the device frame (serial joint variables: see the module
    /// docs on coupled sweeps).
    pub axes: Vec<JointAxis>,
    /// The tip pose defined from the last joint's sweep, at `q = 0`, device frame.
    pub tip: Isometry3<f64>,
    /// The DH table from the axes and the tip; its `base` is DH frame 0 in the device frame.
    pub extraction: Extraction,
}
