//! The settings of [`analyse`] ([`CpaOptions`], [`RIGID_RATIO`]) and its errors ([`CpaError`]).

use super::*;

/// A coupled sweep is a rotation about its lead axis when the targets' radial RMS about a
/// common axis is within this many times their RMS about their own circles (plus the linear
/// tolerance). Real arms make the common fit a few times worse than the targets' own through
/// elasticity and transmission errors (the Boby J2 sweep: 27 µm against 6 µm), while a
/// translating forearm puts the circles' centres a forearm's length apart (millimetres to metres
/// about a common axis against micrometres).
pub const RIGID_RATIO: f64 = 10.0;

/// Default linear tolerance of the extraction from measured axes (what `urdf-dh cpa` and a
/// calibration without a model use): 0.1 mm. Measured axes never intersect exactly; a laser
/// tracker's axis lines scatter by tens of micrometres.
pub const CPA_LINEAR: f64 = 1e-4;
/// Default angular tolerance of the extraction from measured axes: 1 mrad (0.057 degrees).
/// Measured axes are never exactly parallel; without snapping, a pair a fraction of a milliradian
/// from parallel gives a common normal kilometres away. The snap's cost is in the warnings, and
/// a calibration estimates the remaining tilt (Hayati-Mirmirani).
pub const CPA_ANGULAR: f64 = 1e-3;

/// Settings of [`analyse`].
#[derive(Clone, Debug, PartialEq)]
pub struct CpaOptions {
    /// Largest change of a joint value between two poses still counted as unchanged (radians,
    /// metres for prismatic joints). Default [`CpaOptions::DEFAULT_UNCHANGED`].
    pub unchanged: f64,
    /// Fewest poses that make a sweep (at least 3). Default [`CpaOptions::DEFAULT_MIN_POSES`].
    pub min_poses: usize,
    /// Names of the prismatic joints; every other joint is revolute.
    pub prismatic: Vec<String>,
    /// Tolerance of the DH extraction, and the linear allowance of the coaxiality check of
    /// coupled sweeps.
    pub tolerance: Tolerance,
    /// Convention of the extracted DH table.
    pub convention: Convention,
}

impl CpaOptions {
    /// Default [`CpaOptions::unchanged`]: 1e-5 rad (2 arc-seconds; 10 µm for prismatic joints).
    /// Controllers report commanded values to far better than this, and read-back encoder values
    /// jitter by a few encoder counts (1e-6 to 1e-5 rad), while a sweep step is degrees.
    pub const DEFAULT_UNCHANGED: f64 = 1e-5;
    /// Default [`CpaOptions::min_poses`]: 4. Three points always fit a circle exactly; a fourth
    /// gives a residual, and runs of two or three poses are usually transitions between sweeps.
    pub const DEFAULT_MIN_POSES: usize = 4;
}

impl Default for CpaOptions {
    fn default() -> Self {
        Self {
            unchanged: Self::DEFAULT_UNCHANGED,
            min_poses: Self::DEFAULT_MIN_POSES,
            prismatic: Vec::new(),
            tolerance: Tolerance::default(),
            convention: Convention::Standard,
        }
    }
}

/// Everything that stops a circle-point analysis.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum CpaError {
    /// The measurement set has no samples.
    #[error("expected measurements, found no samples")]
    NoSamples,
    /// A sample's joint values do not match the set's joint names.
    #[error("line {line}: expected {expected} joint values, found {found}")]
    JointCount {
        /// The sample's line.
        line: usize,
        /// Joint names in the set.
        expected: usize,
        /// Values in the sample.
        found: usize,
    },
    /// A joint value or coordinate that is NaN or infinite.
    #[error("line {line}: expected finite joint values and coordinates, found {value}")]
    NonFinite {
        /// The sample's line.
        line: usize,
        /// The offending value.
        value: f64,
    },
    /// An option out of range.
    #[error("option {option}: expected {expected}, found {found}")]
    InvalidOption {
        /// The option's name.
        option: &'static str,
        /// What it must be.
        expected: &'static str,
        /// Its value.
        found: String,
    },
    /// Some joints have no sweep.
    #[error("no sweep of {} found; sweeps found: {found}", quoted(.missing))]
    NotSwept {
        /// Joints without a usable sweep.
        missing: Vec<String>,
        /// The sweeps found, described (`joint_1: 6 poses, 60.0 deg`), or `none`.
        found: String,
    },
    /// Points that define no circle (or line).
    #[error("{joint}, target '{target}': {what}")]
    Degenerate {
        /// The swept joint.
        joint: String,
        /// The target.
        target: String,
        /// What is wrong.
        what: String,
    },
    /// A coupled sweep whose targets do not turn about one axis.
    #[error(
        "{joint} swept together with {followers}: the targets' circles are not concentric \
         ({common:.3e} m RMS about a common axis, {own:.3e} m about their own), so the motion is \
         not a rotation about {joint}'s axis"
    )]
    NotRigid {
        /// The lead joint.
        joint: String,
        /// The joints that moved with it.
        followers: String,
        /// Radial RMS about the common axis (metres).
        common: f64,
        /// Radial RMS of the targets' own circles (metres).
        own: f64,
    },
    /// The commanded steps do not tell the sense of rotation.
    #[error(
        "{joint}: every commanded step is a multiple of half a turn, so the sense of rotation \
         is unknown"
    )]
    Sense {
        /// The swept joint.
        joint: String,
    },
    /// The DH extraction failed.
    #[error(transparent)]
    Core(#[from] CoreError),
}

pub(super) fn quoted(items: &[String]) -> String {
    items
        .iter()
        .map(|s| format!("'{s}'"))
        .collect::<Vec<_>>()
        .join(", ")
}
