//! The JSON document of `cpa` ([`CpaDoc`] and its parts: sweeps, target circles, motion
//! checks, axes, pair comparisons). Device frame, metres, radians.

use super::*;

/// A joint that moved with the sweep's lead joint.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CoupledDoc {
    /// Joint name.
    pub joint: String,
    /// Its change per unit change of the lead joint.
    pub ratio: f64,
}

/// One sweep.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SweepDoc {
    /// The moving joint.
    pub joint: String,
    /// Joints moving with it in fixed proportion.
    pub coupled: Vec<CoupledDoc>,
    /// Distinct poses.
    pub poses: usize,
    /// Samples.
    pub samples: usize,
    /// Commanded span (radians or metres).
    pub span: f64,
    /// First and last line in the file.
    pub lines: [usize; 2],
    /// Whether this sweep defines the joint's axis.
    pub used: bool,
}

/// One target's own circle in a joint's sweep.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TargetCircleDoc {
    /// Target name.
    pub name: String,
    /// Points.
    pub points: usize,
    /// Radius (metres); absent for a prismatic joint.
    pub radius: Option<f64>,
    /// RMS distance from its own circle (or line), metres.
    pub path_rms: f64,
    /// RMS distance from its own plane (metres).
    pub plane_rms: Option<f64>,
    /// Distance of its centre from the common axis (metres).
    pub axis_offset: f64,
    /// Angle of its plane normal from the common axis (radians).
    pub axis_tilt: f64,
}

/// Commanded against measured motion.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MotionDoc {
    /// RMS of measured minus commanded (radians or metres), mean removed.
    pub rms: f64,
    /// Linear trend: measured = (1 + slope) commanded.
    pub slope: Option<f64>,
    /// RMS left after the linear trend.
    pub linear_rms: Option<f64>,
    /// Once-per-turn amplitude (radians).
    pub sinusoid_amplitude: Option<f64>,
    /// RMS left after the sinusoid.
    pub sinusoid_rms: Option<f64>,
    /// Per pose: commanded value and residual.
    pub poses: Vec<[f64; 2]>,
}

/// The axis line at the sweep's configuration (device frame).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AxisDoc {
    /// The point of the line nearest the device origin (metres).
    pub point: [f64; 3],
    /// Unit direction, the joint's positive sense.
    pub direction: [f64; 3],
}

/// What the analysis found about one joint.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct JointCpaDoc {
    /// Joint name.
    pub name: String,
    /// `revolute` or `prismatic`.
    pub kind: &'static str,
    /// Poses of the sweep used.
    pub poses: usize,
    /// Points fitted.
    pub points: usize,
    /// Largest target radius (metres).
    pub radius: Option<f64>,
    /// RMS radial distance from the circles about the common axis (metres).
    pub circle_rms: f64,
    /// RMS distance from the circles' planes (metres).
    pub plane_rms: Option<f64>,
    /// Commanded span (radians or metres).
    pub span: f64,
    /// The fitted axis.
    pub axis: AxisDoc,
    /// Commanded against measured motion.
    pub motion: MotionDoc,
    /// The targets' own circles.
    pub targets: Vec<TargetCircleDoc>,
    /// The outlier screen of the sweep ([`dh_calib::cpa::SweepScreen`]).
    pub screen: ScreenDoc,
}

/// The outlier screen of one sweep: the points left out of its fits, and whether the result
/// can be trusted.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ScreenDoc {
    /// Scale of the distances (metres): the known noise or the robust estimate, the larger.
    pub scale: f64,
    /// Threshold on distance / scale.
    pub threshold: f64,
    /// The points left out, in file order.
    pub left_out: Vec<LeftOutDoc>,
    /// The screen settled and left out at most a quarter of the sweep's points.
    pub sound: bool,
}

/// One point left out of a sweep's fits.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LeftOutDoc {
    /// 1-based line of the sample in the data file.
    pub line: usize,
    /// Target name.
    pub target: String,
    /// Distance from its target's fitted circle (metres; line for a prismatic joint).
    pub distance: f64,
    /// The same in units of the scale.
    pub sigmas: f64,
}

/// A consecutive pair of axes, nominal against measured.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PairComparisonDoc {
    /// The two joints.
    pub joints: [String; 2],
    /// Angle between the nominal axes (radians).
    pub nominal_angle: f64,
    /// Angle between the measured axes (radians).
    pub measured_angle: f64,
    /// Common-normal length of the nominal axes (metres); for a pair within 5 degrees of
    /// parallel the offset between the axes instead.
    pub nominal_distance: f64,
    /// The same for the measured axes (metres).
    pub measured_distance: f64,
}

/// The `cpa` section (metres and radians whatever the sheet's units).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CpaDoc {
    /// The data file.
    pub data: String,
    /// Always metres and radians.
    pub units: [&'static str; 2],
    /// Samples analysed.
    pub samples: usize,
    /// Target names.
    pub targets: Vec<String>,
    /// Every sweep found.
    pub sweeps: Vec<SweepDoc>,
    /// Per joint.
    pub joints: Vec<JointCpaDoc>,
    /// Nominal against measured axis pairs (with `--model`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub pairs: Vec<PairComparisonDoc>,
    /// The written table proved against the measured axes (see [`AxesProofDoc`]).
    pub proof: AxesProofDoc,
}

/// Forward kinematics of a table against the measured axes' own (the product of exponentials
/// of the zero-pose axis lines and the measured tip), at every measured joint vector: the
/// largest tip position and orientation differences (metres, radians), for the written table
/// and for the table that snaps every pair within the angular tolerance to parallel.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AxesProofDoc {
    /// Joint vectors compared.
    pub poses: usize,
    /// The written table: `[position, orientation]`.
    pub written: [f64; 2],
    /// The snapped table: `[position, orientation]`.
    pub snapped: [f64; 2],
}
