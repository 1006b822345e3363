//! Circle-point analysis (CPA): joint axes from points measured while one joint moves at a time
//! (H. W. Stone, A. C. Sanderson, "A prototype arm signature identification system", IEEE ICRA
//! 1987; H. W. Stone, *Kinematic Modeling, Identification, and Control of Robotic Manipulators*,
//! Kluwer 1987; B. W. Mooring, Z. S. Roth, M. R. Driels, *Fundamentals of Manipulator
//! Calibration*, Wiley 1991).
//!
//! # Frames and units
//! Every point, line and pose is in the measuring device's frame (laser tracker, camera system),
//! metres; angles are radians; prismatic joint values metres. The result's [`CpaResult::axes`]
//! are the joint axes at `q = 0`, still in the device frame, so the DH table of
//! [`CpaResult::extraction`] has `base` = DH frame 0 in the device frame.
//!
//! # Method
//! 1. **Poses**: consecutive samples with the same joint values (each within
//!    [`CpaOptions::unchanged`]) are one pose; all their samples (targets, repeats) are kept.
//! 2. **Sweeps**: maximal runs of consecutive poses in which the same joints change, in the same
//!    proportion: one joint alone, or a *coupled* sweep (below). Runs shorter than
//!    [`CpaOptions::min_poses`] are transitions between sweeps and are ignored. Consecutive runs
//!    may share their end pose.
//! 3. **Per target** of a sweep: a plane fitted through its points by SVD (orthogonal
//!    regression; C. M. Shakarji, "Least-squares fitting algorithms of the NIST algorithm testing
//!    system", J. Res. NIST 103(6), 1998), then a circle in that plane fitted *geometrically*,
//!    minimising the orthogonal distances to the circle by Levenberg-Marquardt started from the
//!    algebraic fit of I. Kåsa ("A circle fitting procedure and its error analysis", IEEE Trans.
//!    Instrum. Meas. 25, 1976). The algebraic fit alone shrinks circles fitted to short noisy
//!    arcs; the geometric fit does not (W. Gander, G. H. Golub, R. Strebel, "Least-squares
//!    fitting of circles and ellipses", BIT 34, 1994; N. Chernov, *Circular and Linear
//!    Regression*, CRC 2010, ch. 4-5).
//! 4. **Per joint**: the targets of a sweep ride on one rigid body, so their circles share one
//!    axis. All targets are fitted together as concentric circles about a common axis (each with
//!    its own radius and its own plane along the axis), minimising every point's orthogonal
//!    distance to its circle; the per-target fits start it. A target near the axis (small radius)
//!    pins the axis position and barely its direction, and this fit weighs it accordingly.
//! 5. **Sense**: the axis direction is chosen so that the measured rotation has the sign of the
//!    commanded change, i.e. the joint's positive sense is a right-hand rotation about it.
//! 6. **Commanded against measured motion**: each point's angle about the fitted axis, relative
//!    to the target's mean offset, minus the commanded joint value: its RMS, a linear trend
//!    (slope = gear-ratio or scale error: measured = (1 + slope) · commanded), a once-per-turn
//!    sinusoid (eccentricity of the transmission), and both together when the sweep spans at least
//!    half a turn (on shorter arcs a sinusoid and a line cannot be told apart). Angles of several
//!    targets are combined with weights r² (a point's angle noise goes as 1/r).
//! 7. **Axes at `q = 0`**: an axis measured with earlier joints away from zero is moved back by
//!    undoing those joints' motions about their own (already moved-back) axes, in the
//!    product-of-exponentials sense: `axis_i(0) = (M_1(q_1) ⋯ M_{i-1}(q_{i-1}))⁻¹ axis_i(q)`.
//! 8. **DH table**: [`dh_core::extract()`] on the axes at `q = 0` and a tip pose (below).
//!
//! Prismatic joints ([`CpaOptions::prismatic`]) trace lines: the direction comes from an SVD line
//! fit of all targets together (each about its own centroid), sensed by the commanded motion; the
//! measured displacement is checked against the commanded one as angles are. A prismatic axis
//! has no position; the line through the sweep's mean point is used.
//!
//! # Coupled sweeps (the Boby J2 block)
//! When several joints change together in fixed proportion (Δq_f = k · Δq_lead), the sweep is
//! attributed to the joint nearest the base, the *lead*. Whether its points turn about the lead's
//! axis depends on the mechanism:
//! - On a Fanuc-style arm the controller's J3 is the forearm's angle to the horizontal (the "J2/J3
//!   interaction"): the serial joint angle between upper arm and forearm is `J3 + J2`. Commanding
//!   `J3 = −J2` keeps it constant, so everything beyond J2 turns rigidly about J2's axis, and every
//!   target traces a circle about that one axis, the circles concentric.
//! - On a plain serial arm the same command keeps the forearm's orientation: the forearm
//!   translates along a circle. Every target then traces a circle of the same radius (the upper
//!   arm's length) about a *different* axis parallel to J2, offset by the forearm vector, and
//!   none of them is J2's axis.
//!
//! With two or more targets the data tells the two apart: the concentric fit of step 4 matches
//! the targets' own circles only in the first case. A coupled sweep is used as the lead's axis
//! when it does (radial RMS about the common axis within [`RIGID_RATIO`] times the targets' own
//! RMS plus the linear tolerance), and rejected with [`CpaError::NotRigid`] otherwise; with a
//! single target the rigid case is assumed. The follower's serial (DH) variable is then
//! `q_f − k · q_lead` (for the Fanuc case `J3 + J2`), which step 7 uses to move later axes back
//! to `q = 0`; [`Sweep::coupled`] reports `k` so that a model can use the same variable. The Boby
//! data is of the first kind: its three SMRs' J2 circles share one axis to within 0.16 mm while
//! their radii differ by 200 mm.
//!
//! # Tip pose
//! [`dh_core::extract()`] needs the tip link's pose at `q = 0`. CPA measures points, not a tool
//! frame, so one is defined from the last joint's sweep: origin at the centre of the circle of the
//! target farthest from the last axis, z along the last axis, x towards that target at
//! `q_n = 0`. The DH tool transform therefore ends at that circle centre, and a fitted model
//! expresses its targets relative to it. (For a prismatic last joint: origin at the sweep's mean
//! point, x perpendicular to the axis, chosen as `extract` does.)
//!
//! # What is not done
//! One sweep per joint is used (the one with most poses; ties go to the larger span); other
//! sweeps of the same joint are listed with `used = false`. Samples of both splits are used.
//! Joint values are taken as commanded: a controller's own joint coupling other than the
//! detected proportional one is not modelled.

use std::f64::consts::{FRAC_1_SQRT_2, PI, TAU};
use std::fmt::Write as _;

use nalgebra::{
    DMatrix, DVector, Isometry3, Matrix3, Rotation3, Translation3, Unit, UnitQuaternion, Vector2,
    Vector3,
};
use thiserror::Error;

use dh_core::{
    extract, Convention, CoreError, Extraction, JointAxis, JointKind, Line, Tolerance, Warning,
};

use crate::data::Measurements;

/// A coupled sweep is a rotation about its lead axis when the targets' radial RMS about a
/// common axis is within this many times their RMS about their own circles (plus the linear
/// tolerance). Real arms make the common fit a few times worse than the targets' own through
/// elasticity and transmission errors (the Boby J2 sweep: 27 µm against 6 µm), while a
/// translating forearm puts the circles' centres a forearm's length apart (millimetres to metres
/// about a common axis against micrometres).
pub const RIGID_RATIO: f64 = 10.0;

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

fn quoted(items: &[String]) -> String {
    items
        .iter()
        .map(|s| format!("'{s}'"))
        .collect::<Vec<_>>()
        .join(", ")
}

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

/// Runs circle-point analysis on a measurement set (see the [module docs](self)).
///
/// Frames: points, axes and the DH base are in the measuring device's frame; metres and
/// radians.
///
/// # Errors
/// [`CpaError::NoSamples`], [`CpaError::JointCount`], [`CpaError::NonFinite`] and
/// [`CpaError::InvalidOption`] for bad input; [`CpaError::NotSwept`] when some joint has no sweep of at least
/// [`CpaOptions::min_poses`] poses; [`CpaError::Degenerate`] when a sweep's points fit no circle
/// or line; [`CpaError::NotRigid`] for a coupled sweep that is not a rotation about the lead
/// axis; [`CpaError::Sense`] when the sense of rotation cannot be told; [`CpaError::Core`] from
/// the DH extraction.
pub fn analyse(m: &Measurements, opts: &CpaOptions) -> Result<CpaResult, CpaError> {
    check_input(m, opts)?;
    if m.session_count() > 1 {
        // Circles fitted across sessions would mix device frames.
        return Err(CpaError::InvalidOption {
            option: "session",
            expected: "one measurement session (circles are fitted in one device frame); give a nominal model to calibrate several sessions",
            found: format!("{} sessions ({})", m.session_count(), m.sessions.join(", ")),
        });
    }
    let kinds: Vec<JointKind> = m
        .joint_names
        .iter()
        .map(|n| {
            if opts.prismatic.contains(n) {
                JointKind::Prismatic
            } else {
                JointKind::Revolute
            }
        })
        .collect();
    let poses = group_poses(m, opts.unchanged);
    let mut sweeps = find_sweeps(m, &poses, opts);

    // One sweep per joint: most poses, then largest span.
    let n = m.joint_names.len();
    let mut chosen: Vec<Option<usize>> = vec![None; n];
    for (i, s) in sweeps.iter().enumerate() {
        let better = match chosen[s.joint] {
            None => true,
            Some(c) => (s.poses, s.span) > (sweeps[c].poses, sweeps[c].span),
        };
        if better {
            chosen[s.joint] = Some(i);
        }
    }
    let missing: Vec<String> = (0..n)
        .filter(|&j| chosen[j].is_none())
        .map(|j| m.joint_names[j].clone())
        .collect();
    if !missing.is_empty() {
        return Err(CpaError::NotSwept {
            missing,
            found: describe(&sweeps, &kinds),
        });
    }
    let chosen: Vec<usize> = chosen.into_iter().flatten().collect();
    for &c in &chosen {
        sweeps[c].used = true;
    }

    let mut joints = Vec::with_capacity(n);
    for (j, &c) in chosen.iter().enumerate() {
        joints.push(fit_sweep(m, &poses, &sweeps[c], c, kinds[j], opts)?);
    }

    // Serial joint variables: a follower of a used coupled sweep is q_f − k q_lead.
    let mut coupling: Vec<Option<(usize, f64)>> = vec![None; n];
    for &c in &chosen {
        for f in &sweeps[c].coupled {
            coupling[f.joint] = Some((sweeps[c].joint, f.ratio));
        }
    }
    let serial = |q: &[f64]| -> Vec<f64> {
        q.iter()
            .enumerate()
            .map(|(j, &v)| match coupling[j] {
                Some((lead, k)) => v - k * q[lead],
                None => v,
            })
            .collect()
    };

    // Axes at q = 0, base to tip.
    let mut zero: Vec<(JointKind, Line)> = Vec::with_capacity(n);
    for (j, joint) in joints.iter().enumerate() {
        let theta = serial(&sweeps[chosen[j]].start);
        let back = chain_motion(&zero, &theta).inverse();
        zero.push((joint.kind, joint.axis.transformed(&back)));
    }
    let last = n - 1;
    let tip_at_sweep = tip_pose(m, &poses, &sweeps[chosen[last]], &joints[last])?;
    let theta = serial(&sweeps[chosen[last]].start);
    let tip = chain_motion(&zero[..last], &theta).inverse() * tip_at_sweep;

    let axes: Vec<JointAxis> = zero
        .iter()
        .zip(&m.joint_names)
        .map(|((kind, line), name)| JointAxis {
            name: name.clone(),
            kind: *kind,
            line: *line,
            limits: None,
            mimic: None,
        })
        .collect();
    let snapped = extract(&axes, &tip, opts.tolerance, opts.convention)?;
    let extraction = measured_parallels(snapped, &axes, &tip, opts)?;
    Ok(CpaResult {
        sweeps,
        joints,
        axes,
        tip,
        extraction,
    })
}

/// Nearly parallel measured axes are the measurement, not noise to snap away: when the
/// extraction snapped a pair that is not exactly parallel, the table is extracted again without
/// angular snapping (only the linear tolerance decides) and every pair within
/// [`ModelOptions::DEFAULT_HAYATI_THRESHOLD`](crate::model::ModelOptions) of parallel is
/// written in the Hayati-Mirmirani form ([`dh_core::DhTable::hayati_form`]): a small `beta`
/// and bounded lengths, the placement `calibrate` estimates. The ill-conditioned warnings of
/// the pairs so written are dropped: their rows are no longer ill conditioned.
fn measured_parallels(
    snapped: Extraction,
    axes: &[JointAxis],
    tip: &Isometry3<f64>,
    opts: &CpaOptions,
) -> Result<Extraction, CpaError> {
    let tilted_snap = snapped.warnings.iter().any(
        |w| matches!(w, Warning::SnappedParallel { angle_deviation, .. } if *angle_deviation > 0.0),
    );
    if !tilted_snap {
        return Ok(snapped);
    }
    let threshold = crate::model::ModelOptions::DEFAULT_HAYATI_THRESHOLD;
    let exact_tol = Tolerance::new(opts.tolerance.linear, EXACT_ANGLE)?;
    let mut exact = extract(axes, tip, exact_tol, opts.convention)?;
    exact.table = exact.table.hayati_form(threshold);
    exact.warnings.retain(
        |w| !matches!(w, Warning::IllConditioned { angle_from_parallel, .. } if *angle_from_parallel <= threshold),
    );
    Ok(exact)
}

/// Angular tolerance (radians) of the extraction that keeps measured near-parallel pairs as
/// they are: far below any measurement, so only exactly parallel axes snap.
const EXACT_ANGLE: f64 = 1e-12;

fn check_input(m: &Measurements, opts: &CpaOptions) -> Result<(), CpaError> {
    if m.samples.is_empty() || m.joint_names.is_empty() {
        return Err(CpaError::NoSamples);
    }
    for s in &m.samples {
        if s.q.len() != m.joint_names.len() {
            return Err(CpaError::JointCount {
                line: s.line,
                expected: m.joint_names.len(),
                found: s.q.len(),
            });
        }
        if let Some(&value) = s.q.iter().chain(s.point.iter()).find(|v| !v.is_finite()) {
            return Err(CpaError::NonFinite {
                line: s.line,
                value,
            });
        }
    }
    if !opts.unchanged.is_finite() || opts.unchanged < 0.0 {
        return Err(CpaError::InvalidOption {
            option: "unchanged",
            expected: "a finite value >= 0",
            found: opts.unchanged.to_string(),
        });
    }
    if opts.min_poses < 3 {
        return Err(CpaError::InvalidOption {
            option: "min_poses",
            expected: "at least 3",
            found: opts.min_poses.to_string(),
        });
    }
    Ok(())
}

/// A set of consecutive samples at one joint configuration.
struct Pose {
    q: Vec<f64>,
    samples: Vec<usize>,
}

fn group_poses(m: &Measurements, unchanged: f64) -> Vec<Pose> {
    let mut poses: Vec<Pose> = Vec::new();
    for (i, s) in m.samples.iter().enumerate() {
        match poses.last_mut() {
            Some(p)
                if p.q
                    .iter()
                    .zip(&s.q)
                    .all(|(a, b)| (a - b).abs() <= unchanged) =>
            {
                p.samples.push(i);
            }
            _ => poses.push(Pose {
                q: s.q.clone(),
                samples: vec![i],
            }),
        }
    }
    poses
}

/// The joints that change from pose `a` to pose `b`.
fn changed(a: &Pose, b: &Pose, unchanged: f64) -> Vec<usize> {
    (0..a.q.len())
        .filter(|&j| (b.q[j] - a.q[j]).abs() > unchanged)
        .collect()
}

fn find_sweeps(m: &Measurements, poses: &[Pose], opts: &CpaOptions) -> Vec<Sweep> {
    let tol = opts.unchanged;
    let mut sweeps = Vec::new();
    let mut start = 0;
    while start + 1 < poses.len() {
        let set = changed(&poses[start], &poses[start + 1], tol);
        let Some(&lead) = set.first() else {
            start += 1;
            continue;
        };
        let step = |i: usize, j: usize| poses[i + 1].q[j] - poses[i].q[j];
        let ratios: Vec<(usize, f64)> = set[1..]
            .iter()
            .map(|&f| (f, step(start, f) / step(start, lead)))
            .collect();
        let mut end = start + 1;
        while end + 1 < poses.len() {
            let same_set = changed(&poses[end], &poses[end + 1], tol) == set;
            // Each value may be off by `tol`, so a difference by twice that.
            let proportional = ratios
                .iter()
                .all(|&(f, k)| (step(end, f) - k * step(end, lead)).abs() <= 2.0 * tol);
            if !(same_set && proportional) {
                break;
            }
            end += 1;
        }
        let count = end - start + 1;
        if count >= opts.min_poses {
            let run = &poses[start..=end];
            let samples: Vec<usize> = run.iter().flat_map(|p| p.samples.clone()).collect();
            let values = run.iter().map(|p| p.q[lead]);
            let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            });
            // Fit the ratio over the whole run rather than the first step alone.
            let coupled = ratios
                .iter()
                .map(|&(f, _)| {
                    let (mut num, mut den) = (0.0, 0.0);
                    for i in start..end {
                        num += step(i, f) * step(i, lead);
                        den += step(i, lead) * step(i, lead);
                    }
                    Coupled {
                        joint: f,
                        name: m.joint_names[f].clone(),
                        ratio: num / den,
                    }
                })
                .collect();
            let first = samples.first().map_or(0, |&i| m.samples[i].line);
            let last = samples.last().map_or(0, |&i| m.samples[i].line);
            sweeps.push(Sweep {
                joint: lead,
                name: m.joint_names[lead].clone(),
                coupled,
                samples,
                poses: count,
                start: run[0].q.clone(),
                span: hi - lo,
                lines: (first, last),
                used: false,
            });
        }
        start = end;
    }
    sweeps
}

fn describe(sweeps: &[Sweep], kinds: &[JointKind]) -> String {
    if sweeps.is_empty() {
        return "none".into();
    }
    let mut out = String::new();
    for (i, s) in sweeps.iter().enumerate() {
        if i > 0 {
            out.push_str("; ");
        }
        let _ = write!(out, "{}", s.name);
        for c in &s.coupled {
            let _ = write!(out, " with {} (x{})", c.name, c.ratio);
        }
        let _ = match kinds[s.joint] {
            JointKind::Revolute => {
                write!(out, ": {} poses, {:.1} deg", s.poses, s.span.to_degrees())
            }
            JointKind::Prismatic => write!(out, ": {} poses, {:.4} m", s.poses, s.span),
        };
    }
    out
}

/// Groups of one sweep: per target, (target index, per pose: (commanded lead value, points)).
type Groups = Vec<(usize, Vec<(f64, Vec<Vector3<f64>>)>)>;

fn groups(m: &Measurements, poses: &[Pose], sweep: &Sweep) -> Groups {
    let mut out: Groups = Vec::new();
    let in_sweep = |i: &usize| sweep.samples.binary_search(i).is_ok();
    for pose in poses {
        let members: Vec<usize> = pose.samples.iter().copied().filter(in_sweep).collect();
        if members.is_empty() {
            continue;
        }
        let q = pose.q[sweep.joint];
        for i in members {
            let s = &m.samples[i];
            let slot = match out.iter().position(|(t, _)| *t == s.target) {
                Some(k) => k,
                None => {
                    out.push((s.target, Vec::new()));
                    out.len() - 1
                }
            };
            let per_pose = &mut out[slot].1;
            match per_pose.last_mut() {
                Some((last_q, pts)) if *last_q == q => pts.push(s.point),
                _ => per_pose.push((q, vec![s.point])),
            }
        }
    }
    // A target seen at fewer than three poses fits no circle: leave it out.
    out.retain(|(_, per_pose)| per_pose.len() >= 3);
    out
}

fn target_name(m: &Measurements, t: usize) -> String {
    m.targets.get(t).cloned().unwrap_or_else(|| t.to_string())
}

fn fit_sweep(
    m: &Measurements,
    poses: &[Pose],
    sweep: &Sweep,
    index: usize,
    kind: JointKind,
    opts: &CpaOptions,
) -> Result<JointCpa, CpaError> {
    let groups = groups(m, poses, sweep);
    if groups.is_empty() {
        return Err(CpaError::Degenerate {
            joint: sweep.name.clone(),
            target: m.targets.join(", "),
            what: "no target was measured at three or more poses of the sweep".into(),
        });
    }
    match kind {
        JointKind::Revolute => fit_revolute(m, sweep, index, &groups, opts),
        JointKind::Prismatic => fit_prismatic(m, sweep, index, &groups),
    }
}

fn fit_revolute(
    m: &Measurements,
    sweep: &Sweep,
    index: usize,
    groups: &Groups,
    opts: &CpaOptions,
) -> Result<JointCpa, CpaError> {
    let degenerate = |t: usize, e: CpaError| CpaError::Degenerate {
        joint: sweep.name.clone(),
        target: target_name(m, t),
        what: match e {
            CpaError::Degenerate { what, .. } => what,
            other => other.to_string(),
        },
    };
    // Per target: plane + geometric circle.
    let mut own = Vec::with_capacity(groups.len());
    for (t, per_pose) in groups {
        let pts: Vec<Vector3<f64>> = per_pose.iter().flat_map(|(_, p)| p.clone()).collect();
        let circle = fit_circle(&pts, CircleMethod::Geometric).map_err(|e| degenerate(*t, e))?;
        own.push(circle);
    }
    // Common axis: start from the targets' circles, weighting directions by r² · points.
    let reference = own
        .iter()
        .max_by(|a, b| {
            (a.radius * a.radius * a.points as f64)
                .total_cmp(&(b.radius * b.radius * b.points as f64))
        })
        .map_or(Vector3::z(), |c| c.normal);
    let mut normal = Vector3::zeros();
    let mut centre = Vector3::zeros();
    let mut count = 0.0;
    for c in &own {
        let sign = c.normal.dot(&reference).signum();
        normal += c.normal * sign * c.radius * c.radius * c.points as f64;
        centre += c.centre * c.points as f64;
        count += c.points as f64;
    }
    let normal = if normal.norm() > 0.0 {
        normal.normalize()
    } else {
        reference
    };
    let point_sets: Vec<Vec<Vector3<f64>>> = groups
        .iter()
        .map(|(_, pp)| pp.iter().flat_map(|(_, p)| p.clone()).collect())
        .collect();
    let mut fit = fit_coaxial(&point_sets, centre / count, normal, &own);

    // Sense: rotation about the axis must follow the commanded change.
    let k_big = own
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.radius.total_cmp(&b.1.radius))
        .map_or(0, |(k, _)| k);
    let angles = pose_angles(&groups[k_big].1, &fit);
    let mut score = 0.0;
    let mut commanded_turn = 0.0f64;
    for w in angles.windows(2) {
        let (dq, dphi) = (w[1].0 - w[0].0, w[1].1 - w[0].1);
        score += dphi.sin() * dq.sin();
        commanded_turn = commanded_turn.max(dq.sin().abs());
    }
    if commanded_turn <= opts.tolerance.angular {
        return Err(CpaError::Sense {
            joint: sweep.name.clone(),
        });
    }
    if score < 0.0 {
        fit.normal = -fit.normal;
        for h in &mut fit.heights {
            *h = -*h;
        }
    }
    let axis = Line::through(fit.point, fit.normal)?;

    // Coupled sweeps must be concentric (module docs).
    let own_rms = rms(own.iter().flat_map(|c| c.radial.iter().copied()));
    let (radial, axial) = fit.residuals(&point_sets);
    let common_rms = rms(radial.iter().copied());
    if !sweep.coupled.is_empty()
        && own.len() >= 2
        && common_rms > RIGID_RATIO * own_rms + opts.tolerance.linear
    {
        return Err(CpaError::NotRigid {
            joint: sweep.name.clone(),
            followers: sweep
                .coupled
                .iter()
                .map(|c| c.name.clone())
                .collect::<Vec<_>>()
                .join(", "),
            common: common_rms,
            own: own_rms,
        });
    }

    let targets: Vec<TargetFit> = groups
        .iter()
        .zip(&own)
        .map(|((t, _), c)| {
            let direction = c.normal * c.normal.dot(&fit.normal).signum();
            TargetFit {
                target: *t,
                name: target_name(m, *t),
                points: c.points,
                centre: c.centre,
                direction,
                radius: Some(c.radius),
                path_rms: c.circle_rms,
                plane_rms: Some(c.plane_rms),
                axis_offset: axis.distance_to_point(&c.centre),
                axis_tilt: direction
                    .cross(&fit.normal)
                    .norm()
                    .atan2(direction.dot(&fit.normal)),
            }
        })
        .collect();

    // Commanded against measured angle, per pose, targets weighted by r².
    let per_target: Vec<(f64, Vec<(f64, f64)>)> = groups
        .iter()
        .zip(&fit.radii)
        .map(|((_, pp), &r)| (r * r, pose_angles(pp, &fit)))
        .collect();
    let motion = motion_check(&per_target, JointKind::Revolute, sweep.span);

    Ok(JointCpa {
        joint: sweep.joint,
        name: sweep.name.clone(),
        kind: JointKind::Revolute,
        sweep: index,
        axis,
        points: targets.iter().map(|t| t.points).sum(),
        poses: sweep.poses,
        radius: fit.radii.iter().copied().reduce(f64::max),
        targets,
        circle_rms: common_rms,
        plane_rms: Some(rms(axial.iter().copied())),
        span: sweep.span,
        motion,
    })
}

/// Per pose: (commanded value, mean angle of the pose's points about the fitted axis).
fn pose_angles(per_pose: &[(f64, Vec<Vector3<f64>>)], fit: &Coaxial) -> Vec<(f64, f64)> {
    let (b1, b2) = basis(&fit.normal);
    per_pose
        .iter()
        .map(|(q, pts)| {
            // Average the points' angles relative to the first one, so that no wrap splits them.
            let angle = |p: &Vector3<f64>| {
                let d = p - fit.point;
                d.dot(&b2).atan2(d.dot(&b1))
            };
            let first = angle(&pts[0]);
            let mean = pts.iter().map(|p| wrap(angle(p) - first)).sum::<f64>() / pts.len() as f64;
            (*q, first + mean)
        })
        .collect()
}

fn fit_prismatic(
    m: &Measurements,
    sweep: &Sweep,
    index: usize,
    groups: &Groups,
) -> Result<JointCpa, CpaError> {
    // All targets translate alike: one direction from every target's centred points.
    let mut centred = Vec::new();
    let mut centroids = Vec::new();
    for (_, pp) in groups {
        let pts: Vec<Vector3<f64>> = pp.iter().flat_map(|(_, p)| p.clone()).collect();
        let c = mean(&pts);
        centred.extend(pts.iter().map(|p| p - c));
        centroids.push(c);
    }
    let (_, vectors) = principal_axes(&centred);
    let mut dir = vectors[0];
    // Sense: displacement along the direction must follow the commanded change.
    let score: f64 = groups
        .iter()
        .zip(&centroids)
        .flat_map(|((_, pp), c)| pp.iter().map(move |(q, pts)| (q, (pts[0] - c).dot(&dir))))
        .map(|(q, s)| q * s)
        .sum();
    let spread: f64 = centred.iter().map(|d| d.norm()).fold(0.0, f64::max);
    if spread == 0.0 {
        return Err(CpaError::Degenerate {
            joint: sweep.name.clone(),
            target: target_name(m, groups[0].0),
            what: "the points do not move".into(),
        });
    }
    if score < 0.0 {
        dir = -dir;
    }
    let all: Vec<Vector3<f64>> = groups
        .iter()
        .flat_map(|(_, pp)| pp.iter().flat_map(|(_, p)| p.clone()))
        .collect();
    let axis = Line::through(mean(&all), dir)?;
    let mut line_sq = Vec::new();
    let mut targets = Vec::new();
    let mut per_target = Vec::new();
    for ((t, pp), c) in groups.iter().zip(&centroids) {
        let pts: Vec<Vector3<f64>> = pp.iter().flat_map(|(_, p)| p.clone()).collect();
        let own: Vec<f64> = pts
            .iter()
            .map(|p| {
                let d = p - c;
                (d - dir * d.dot(&dir)).norm()
            })
            .collect();
        line_sq.extend(own.iter().copied());
        let (_, own_dir) = principal_axes(&pts.iter().map(|p| p - c).collect::<Vec<_>>());
        let own_dir = own_dir[0] * own_dir[0].dot(&dir).signum();
        let own_rms = rms(pts.iter().map(|p| {
            let d = p - c;
            (d - own_dir * d.dot(&own_dir)).norm()
        }));
        targets.push(TargetFit {
            target: *t,
            name: target_name(m, *t),
            points: pts.len(),
            centre: *c,
            direction: own_dir,
            radius: None,
            path_rms: own_rms,
            plane_rms: None,
            axis_offset: 0.0,
            axis_tilt: own_dir.cross(&dir).norm().atan2(own_dir.dot(&dir)),
        });
        let along: Vec<(f64, f64)> = pp
            .iter()
            .map(|(q, p)| {
                (
                    *q,
                    p.iter().map(|x| (x - c).dot(&dir)).sum::<f64>() / p.len() as f64,
                )
            })
            .collect();
        per_target.push((1.0, along));
    }
    let motion = motion_check(&per_target, JointKind::Prismatic, sweep.span);
    Ok(JointCpa {
        joint: sweep.joint,
        name: sweep.name.clone(),
        kind: JointKind::Prismatic,
        sweep: index,
        axis,
        points: all.len(),
        poses: sweep.poses,
        radius: None,
        targets,
        circle_rms: rms(line_sq.into_iter()),
        plane_rms: None,
        span: sweep.span,
        motion,
    })
}

/// Residuals per pose from per-target (weight, [(commanded, measured)]) series. Revolute values
/// are angles (compared modulo a turn); prismatic ones lengths.
fn motion_check(per_target: &[(f64, Vec<(f64, f64)>)], kind: JointKind, span: f64) -> MotionCheck {
    let diff = |a: f64| match kind {
        JointKind::Revolute => wrap(a),
        JointKind::Prismatic => a,
    };
    // Per target: measured − commanded, about its first pose, then mean removed.
    let mut by_pose: Vec<(f64, f64, f64)> = Vec::new(); // (commanded, Σ w·residual, Σ w)
    for (w, series) in per_target {
        let Some(&(q0, m0)) = series.first() else {
            continue;
        };
        let rel: Vec<(f64, f64)> = series
            .iter()
            .map(|&(q, mv)| (q, diff(mv - m0 - (q - q0))))
            .collect();
        let mean = rel.iter().map(|r| r.1).sum::<f64>() / rel.len() as f64;
        for (q, r) in rel {
            match by_pose.iter_mut().find(|p| p.0 == q) {
                Some(p) => {
                    p.1 += w * (r - mean);
                    p.2 += w;
                }
                None => by_pose.push((q, w * (r - mean), *w)),
            }
        }
    }
    let mut poses: Vec<PoseResidual> = by_pose
        .iter()
        .filter(|p| p.2 > 0.0)
        .map(|p| PoseResidual {
            commanded: p.0,
            residual: p.1 / p.2,
        })
        .collect();
    let mean = poses.iter().map(|p| p.residual).sum::<f64>() / poses.len().max(1) as f64;
    for p in &mut poses {
        p.residual -= mean;
    }
    let q: Vec<f64> = poses.iter().map(|p| p.commanded).collect();
    let e: Vec<f64> = poses.iter().map(|p| p.residual).collect();
    let n = poses.len();
    let linear = (n >= 3)
        .then(|| least_squares(&q, &e, &[Basis::One, Basis::Q]))
        .flatten()
        .map(|(c, rms)| LinearTrend { slope: c[1], rms });
    let revolute = kind == JointKind::Revolute;
    let sinusoid = (revolute && n >= 4)
        .then(|| least_squares(&q, &e, &[Basis::One, Basis::Cos, Basis::Sin]))
        .flatten()
        .map(|(c, rms)| SinusoidTrend {
            amplitude: c[1].hypot(c[2]),
            phase: c[1].atan2(c[2]),
            rms,
        });
    let combined = (revolute && n >= 5 && span >= PI)
        .then(|| least_squares(&q, &e, &[Basis::One, Basis::Q, Basis::Cos, Basis::Sin]))
        .flatten()
        .map(|(c, rms)| CombinedTrend {
            slope: c[1],
            amplitude: c[2].hypot(c[3]),
            phase: c[2].atan2(c[3]),
            rms,
        });
    MotionCheck {
        rms: rms(e.iter().copied()),
        poses,
        linear,
        sinusoid,
        combined,
    }
}

#[derive(Clone, Copy)]
enum Basis {
    One,
    Q,
    Cos,
    Sin,
}

/// Least squares of `e` on the basis functions of `q`: coefficients and residual RMS; `None`
/// when the design is rank-deficient.
fn least_squares(q: &[f64], e: &[f64], basis: &[Basis]) -> Option<(Vec<f64>, f64)> {
    let a = DMatrix::from_fn(q.len(), basis.len(), |i, j| match basis[j] {
        Basis::One => 1.0,
        Basis::Q => q[i],
        Basis::Cos => q[i].cos(),
        Basis::Sin => q[i].sin(),
    });
    let b = DVector::from_column_slice(e);
    let svd = a.clone().svd(true, true);
    let max = svd.singular_values.max();
    // Rank: singular values below the rounding level of the largest one are zero.
    let tiny = max * f64::EPSILON * (q.len().max(basis.len()) as f64);
    if svd.singular_values.iter().any(|&s| s <= tiny) {
        return None;
    }
    let x = svd.solve(&b, tiny).ok()?;
    let r = &b - &a * &x;
    Some((x.iter().copied().collect(), rms(r.iter().copied())))
}

/// The tip pose at the last joint's sweep configuration with the last joint at zero (module
/// docs).
fn tip_pose(
    m: &Measurements,
    poses: &[Pose],
    sweep: &Sweep,
    joint: &JointCpa,
) -> Result<Isometry3<f64>, CpaError> {
    let z = joint.axis.direction();
    match joint.kind {
        JointKind::Prismatic => {
            let origin = joint.axis.point();
            Ok(frame(origin, perpendicular(&z), z))
        }
        JointKind::Revolute => {
            let groups = groups(m, poses, sweep);
            let far = joint.targets.iter().enumerate().max_by(|a, b| {
                a.1.radius
                    .unwrap_or(0.0)
                    .total_cmp(&b.1.radius.unwrap_or(0.0))
            });
            let Some((k, target)) = far else {
                return Ok(frame(joint.axis.point(), perpendicular(&z), z));
            };
            let centre = joint.axis.foot_of(&target.centre);
            // The target's angle at q_n = 0: mean of (measured angle − commanded) over the poses.
            let fit = Coaxial {
                point: centre,
                normal: z,
                radii: Vec::new(),
                heights: Vec::new(),
            };
            let angles = pose_angles(&groups[k].1, &fit);
            let Some(&(q0, a0)) = angles.first() else {
                return Ok(frame(centre, perpendicular(&z), z));
            };
            let offset = a0 - q0
                + angles
                    .iter()
                    .map(|(q, a)| wrap(a - q - (a0 - q0)))
                    .sum::<f64>()
                    / angles.len() as f64;
            let (b1, b2) = basis(&z);
            let x = b1 * offset.cos() + b2 * offset.sin();
            Ok(frame(centre, x, z))
        }
    }
}

/// The pose with origin `origin`, x axis `x`, z axis `z` (unit, orthogonal).
fn frame(origin: Vector3<f64>, x: Vector3<f64>, z: Vector3<f64>) -> Isometry3<f64> {
    let y = z.cross(&x);
    let r = Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[x, y, z]));
    Isometry3::from_parts(
        Translation3::from(origin),
        UnitQuaternion::from_rotation_matrix(&r),
    )
}

/// The motion of joints `0..axes.len()` at serial values `theta`, as one rigid transform
/// (product of exponentials about the axes at `q = 0`).
fn chain_motion(axes: &[(JointKind, Line)], theta: &[f64]) -> Isometry3<f64> {
    let mut t = Isometry3::identity();
    for ((kind, line), &th) in axes.iter().zip(theta) {
        let e = line.direction();
        let step = match kind {
            JointKind::Prismatic => Isometry3::translation(e.x * th, e.y * th, e.z * th),
            JointKind::Revolute => {
                let r = UnitQuaternion::from_axis_angle(&Unit::new_unchecked(e), th);
                let c = line.point();
                Isometry3::from_parts(Translation3::from(c - r * c), r)
            }
        };
        t *= step;
    }
    t
}

/// How a circle is fitted in its plane.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CircleMethod {
    /// Kåsa's algebraic fit: linear least squares on `x² + y² + D x + E y + F = 0`. Fast and
    /// closed-form, but it shrinks circles fitted to short noisy arcs.
    Kasa,
    /// Geometric fit: least squares of the orthogonal distances to the circle
    /// (Levenberg-Marquardt from the Kåsa fit; Gander, Golub & Strebel 1994).
    Geometric,
}

/// A circle in space fitted to points.
#[derive(Clone, Debug, PartialEq)]
pub struct Circle {
    /// Centre (metres, the points' frame).
    pub centre: Vector3<f64>,
    /// Unit normal of the plane (sign arbitrary: the SVD's).
    pub normal: Vector3<f64>,
    /// Radius (metres).
    pub radius: f64,
    /// RMS in-plane distance of the points from the circle (metres).
    pub circle_rms: f64,
    /// RMS distance of the points from the plane (metres).
    pub plane_rms: f64,
    /// Number of points.
    pub points: usize,
    /// Each point's in-plane radial residual, distance from the centre minus radius (metres).
    pub radial: Vec<f64>,
}

/// Fits a plane by SVD and then a circle in it by `method` (see [`CircleMethod`]).
///
/// # Errors
/// [`CpaError::Degenerate`] (with empty joint and target names) for fewer than three points,
/// non-finite coordinates, or points on a line or at one place.
pub fn fit_circle(points: &[Vector3<f64>], method: CircleMethod) -> Result<Circle, CpaError> {
    let degenerate = |what: &str| CpaError::Degenerate {
        joint: String::new(),
        target: String::new(),
        what: what.into(),
    };
    if points.len() < 3 {
        return Err(degenerate("a circle needs at least three points"));
    }
    if points.iter().any(|p| !p.iter().all(|c| c.is_finite())) {
        return Err(degenerate("a point has a non-finite coordinate"));
    }
    let c = mean(points);
    let centred: Vec<Vector3<f64>> = points.iter().map(|p| p - c).collect();
    let (values, vectors) = principal_axes(&centred);
    // Collinear points (second singular value at rounding level of the first) span no plane.
    if values[1] <= values[0] * 1e3 * f64::EPSILON {
        return Err(degenerate(
            "the points lie on a line, so they fit no circle",
        ));
    }
    let (e1, e2, normal) = (vectors[0], vectors[1], vectors[2]);
    let plane_rms = rms(centred.iter().map(|d| d.dot(&normal)));
    let xy: Vec<Vector2<f64>> = centred
        .iter()
        .map(|d| Vector2::new(d.dot(&e1), d.dot(&e2)))
        .collect();
    let (mut centre2, mut radius) =
        kasa(&xy).ok_or_else(|| degenerate("the points fit no circle (algebraic fit singular)"))?;
    if method == CircleMethod::Geometric {
        (centre2, radius) = geometric_circle(&xy, centre2, radius);
    }
    let radial: Vec<f64> = xy.iter().map(|p| (p - centre2).norm() - radius).collect();
    Ok(Circle {
        centre: c + e1 * centre2.x + e2 * centre2.y,
        normal,
        radius,
        circle_rms: rms(radial.iter().copied()),
        plane_rms,
        points: points.len(),
        radial,
    })
}

/// Kåsa's fit: minimise Σ (x² + y² + D x + E y + F)² (linear), centre `(−D/2, −E/2)`.
fn kasa(xy: &[Vector2<f64>]) -> Option<(Vector2<f64>, f64)> {
    let a = DMatrix::from_fn(xy.len(), 3, |i, j| match j {
        0 => xy[i].x,
        1 => xy[i].y,
        _ => 1.0,
    });
    let b = DVector::from_fn(xy.len(), |i, _| -xy[i].norm_squared());
    let svd = a.svd(true, true);
    let max = svd.singular_values.max();
    if svd.singular_values.min() <= max * 1e3 * f64::EPSILON {
        return None;
    }
    let x = svd.solve(&b, 0.0).ok()?;
    let centre = Vector2::new(-x[0] / 2.0, -x[1] / 2.0);
    let r2 = centre.norm_squared() - x[2];
    (r2 > 0.0 && r2.is_finite()).then(|| (centre, r2.sqrt()))
}

/// Geometric circle fit in the plane: minimise Σ (|p − c| − r)² by Levenberg-Marquardt.
fn geometric_circle(xy: &[Vector2<f64>], c0: Vector2<f64>, r0: f64) -> (Vector2<f64>, f64) {
    let eval = |x: &DVector<f64>| {
        let c = Vector2::new(x[0], x[1]);
        let mut r = DVector::zeros(xy.len());
        let mut j = DMatrix::zeros(xy.len(), 3);
        for (i, p) in xy.iter().enumerate() {
            let d = p - c;
            let dist = d.norm();
            r[i] = dist - x[2];
            if dist > 0.0 {
                j[(i, 0)] = -d.x / dist;
                j[(i, 1)] = -d.y / dist;
            }
            j[(i, 2)] = -1.0;
        }
        (r, j)
    };
    let x = levenberg_marquardt(DVector::from_vec(vec![c0.x, c0.y, r0]), eval, |x, dx| {
        x + dx
    });
    (Vector2::new(x[0], x[1]), x[2])
}

/// Concentric circles about one axis: a point on the axis, the axis direction, and per group a
/// radius and a position of its plane along the axis.
struct Coaxial {
    point: Vector3<f64>,
    normal: Vector3<f64>,
    radii: Vec<f64>,
    heights: Vec<f64>,
}

impl Coaxial {
    /// Radial and axial residuals of every point.
    fn residuals(&self, groups: &[Vec<Vector3<f64>>]) -> (Vec<f64>, Vec<f64>) {
        let mut radial = Vec::new();
        let mut axial = Vec::new();
        for (k, pts) in groups.iter().enumerate() {
            for p in pts {
                let d = p - self.point;
                let z = d.dot(&self.normal);
                radial.push((d - self.normal * z).norm() - self.radii[k]);
                axial.push(z - self.heights[k]);
            }
        }
        (radial, axial)
    }
}

/// Fits concentric circles sharing one axis to the point groups (each point's squared
/// orthogonal distance to its circle, split into radial and axial parts), by Levenberg-Marquardt
/// started from `point`, `normal` and the groups' own circles.
fn fit_coaxial(
    groups: &[Vec<Vector3<f64>>],
    point: Vector3<f64>,
    normal: Vector3<f64>,
    own: &[Circle],
) -> Coaxial {
    let k = groups.len();
    // State: point (3), normal (3), radii (k), heights (k).
    let mut x0 = Vec::with_capacity(6 + 2 * k);
    x0.extend(point.iter());
    x0.extend(normal.iter());
    x0.extend(own.iter().map(|c| c.radius));
    x0.extend(own.iter().map(|c| (c.centre - point).dot(&normal)));
    let unpack = |x: &DVector<f64>| {
        let a = Vector3::new(x[0], x[1], x[2]);
        let n = Vector3::new(x[3], x[4], x[5]);
        (a, n)
    };
    let m: usize = groups.iter().map(Vec::len).sum();
    let eval = |x: &DVector<f64>| {
        let (a, n) = unpack(x);
        let (b1, b2) = basis(&n);
        let mut r = DVector::zeros(2 * m);
        let mut j = DMatrix::zeros(2 * m, 4 + 2 * k);
        let mut row = 0;
        for (g, pts) in groups.iter().enumerate() {
            for p in pts {
                let d = p - a;
                let z = d.dot(&n);
                let rho = (d - n * z).norm();
                let (d1, d2) = (d.dot(&b1), d.dot(&b2));
                // Axial residual: local parameters (tilt along b1, b2; shift along b1, b2).
                r[row] = z - x[6 + k + g];
                j[(row, 0)] = d1;
                j[(row, 1)] = d2;
                j[(row, 4 + k + g)] = -1.0;
                // Radial residual.
                r[row + 1] = rho - x[6 + g];
                if rho > 0.0 {
                    j[(row + 1, 0)] = -z * d1 / rho;
                    j[(row + 1, 1)] = -z * d2 / rho;
                    j[(row + 1, 2)] = -d1 / rho;
                    j[(row + 1, 3)] = -d2 / rho;
                }
                j[(row + 1, 4 + g)] = -1.0;
                row += 2;
            }
        }
        (r, j)
    };
    let update = |x: &DVector<f64>, dx: &DVector<f64>| {
        let (a, n) = unpack(x);
        let (b1, b2) = basis(&n);
        let n2 = (n + b1 * dx[0] + b2 * dx[1]).normalize();
        let a2 = a + b1 * dx[2] + b2 * dx[3];
        let mut y = x.clone();
        y.fixed_rows_mut::<3>(0).copy_from(&a2);
        y.fixed_rows_mut::<3>(3).copy_from(&n2);
        for i in 0..2 * k {
            y[6 + i] += dx[4 + i];
        }
        y
    };
    let x = levenberg_marquardt(DVector::from_vec(x0), eval, update);
    let (a, n) = unpack(&x);
    Coaxial {
        point: a,
        normal: n,
        radii: (0..k).map(|g| x[6 + g]).collect(),
        heights: (0..k).map(|g| x[6 + k + g]).collect(),
    }
}

/// Levenberg-Marquardt iterations of a solver setting, not a geometric decision: enough for
/// the small well-started problems here, which converge in a handful.
const LM_MAX_ITERATIONS: usize = 200;

/// Minimises |r(x)|² with Marquardt's scaled damping. `eval` gives residuals and the Jacobian
/// with respect to a local step; `update` applies a step (for manifold parameters such as a unit
/// vector). Stops when a step no longer lowers the cost by more than rounding.
fn levenberg_marquardt(
    mut x: DVector<f64>,
    eval: impl Fn(&DVector<f64>) -> (DVector<f64>, DMatrix<f64>),
    update: impl Fn(&DVector<f64>, &DVector<f64>) -> DVector<f64>,
) -> DVector<f64> {
    let (mut r, mut j) = eval(&x);
    let mut cost = r.norm_squared();
    let mut lambda = 1e-3;
    for _ in 0..LM_MAX_ITERATIONS {
        let jt = j.transpose();
        let jtj = &jt * &j;
        let g = &jt * &r;
        let max_diag = jtj.diagonal().max();
        if max_diag <= 0.0 || !max_diag.is_finite() {
            break;
        }
        let mut improved = false;
        while lambda < 1e16 {
            let mut a = jtj.clone();
            for i in 0..a.nrows() {
                // Floor the scaling so that parameters without effect stay put.
                a[(i, i)] += lambda * jtj[(i, i)].max(max_diag * f64::EPSILON);
            }
            let Some(chol) = a.cholesky() else {
                lambda *= 10.0;
                continue;
            };
            let dx = -chol.solve(&g);
            let candidate = update(&x, &dx);
            let (r2, j2) = eval(&candidate);
            let cost2 = r2.norm_squared();
            if cost2.is_finite() && cost2 < cost {
                let gain = cost - cost2;
                x = candidate;
                (r, j, cost) = (r2, j2, cost2);
                lambda = (lambda / 10.0).max(1e-12);
                improved = gain > cost * 16.0 * f64::EPSILON;
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    x
}

/// Singular values (descending) and the matching unit vectors of the scatter of `centred`.
fn principal_axes(centred: &[Vector3<f64>]) -> ([f64; 3], [Vector3<f64>; 3]) {
    let scatter = centred
        .iter()
        .fold(Matrix3::zeros(), |acc, d| acc + d * d.transpose());
    let eig = scatter.symmetric_eigen();
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let values = order.map(|i| eig.eigenvalues[i].max(0.0).sqrt());
    let vectors = order.map(|i| eig.eigenvectors.column(i).into_owned());
    (values, vectors)
}

/// Two unit vectors completing `n` to a right-handed frame `(b1, b2, n)`.
fn basis(n: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let b1 = perpendicular(n);
    (b1, n.cross(&b1))
}

/// A unit vector perpendicular to the unit vector `n`: from the world x axis, or y when x is
/// too close to `n` (the rule `dh_core::extract` uses for frame 0).
fn perpendicular(n: &Vector3<f64>) -> Vector3<f64> {
    let pick = |v: Vector3<f64>| v - n * v.dot(n);
    let x = pick(Vector3::x());
    if x.norm() >= FRAC_1_SQRT_2 {
        x.normalize()
    } else {
        pick(Vector3::y()).normalize()
    }
}

fn mean(points: &[Vector3<f64>]) -> Vector3<f64> {
    points.iter().sum::<Vector3<f64>>() / points.len().max(1) as f64
}

fn rms(values: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v * v, n + 1));
    if n == 0 {
        0.0
    } else {
        (sum / n as f64).sqrt()
    }
}

/// `a` wrapped into `(−pi, pi]`.
fn wrap(a: f64) -> f64 {
    let w = a - TAU * (a / TAU).round();
    if w <= -PI {
        w + TAU
    } else {
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn set(qs: &[[f64; 2]]) -> Measurements {
        Measurements {
            sessions: Vec::new(),
            joint_names: vec!["a".into(), "b".into()],
            targets: vec!["t".into()],
            samples: qs
                .iter()
                .enumerate()
                .map(|(i, q)| crate::data::Sample {
                    session: 0,
                    q: q.to_vec(),
                    target: 0,
                    point: Vector3::zeros(),
                    sigma: None,
                    config: None,
                    split: crate::data::Split::Calibration,
                    line: i + 1,
                    socket: None,
                })
                .collect(),
        }
    }

    /// Lead joint, (follower, ratio), poses, first and last line.
    type Summary = (usize, Vec<(usize, f64)>, usize, (usize, usize));

    #[test]
    fn sweeps_by_hand_repeats_transitions_coupling_and_shared_ends() {
        let m = set(&[
            // a alone, the first pose measured twice.
            [0.0, 0.0],
            [0.0, 0.0],
            [1.0, 0.0],
            [2.0, 0.0],
            [3.0, 0.0],
            // Transition: both change, in another proportion than what follows.
            [2.5, 1.0],
            // a with b = -a.
            [3.5, 0.0],
            [4.5, -1.0],
            [5.5, -2.0],
            // b alone, starting where the coupled sweep ends.
            [5.5, -1.0],
            [5.5, 0.0],
            [5.5, 1.0],
        ]);
        let opts = CpaOptions::default();
        let poses = group_poses(&m, opts.unchanged);
        assert_eq!(poses.len(), 11);
        let sweeps = find_sweeps(&m, &poses, &opts);
        let summary: Vec<Summary> = sweeps
            .iter()
            .map(|s| {
                let c = s.coupled.iter().map(|c| (c.joint, c.ratio)).collect();
                (s.joint, c, s.poses, s.lines)
            })
            .collect();
        assert_eq!(
            summary,
            vec![
                (0, vec![], 4, (1, 5)),
                (0, vec![(1, -1.0)], 4, (6, 9)),
                (1, vec![], 4, (9, 12)),
            ]
        );
        assert_eq!(sweeps[0].samples, vec![0, 1, 2, 3, 4]);
        assert_relative_eq!(sweeps[0].span, 3.0);
        assert_eq!(sweeps[2].start, vec![5.5, -2.0]);
    }

    #[test]
    fn bad_input_is_named() {
        let mut m = set(&[[0.0, 0.0], [1.0, 0.0]]);
        m.samples[1].point.y = f64::NAN;
        let e = analyse(&m, &CpaOptions::default()).unwrap_err();
        assert_eq!(
            e.to_string(),
            "line 2: expected finite joint values and coordinates, found NaN"
        );
        m.samples[1].q.pop();
        let e = analyse(&m, &CpaOptions::default()).unwrap_err();
        assert_eq!(e.to_string(), "line 2: expected 2 joint values, found 1");
        let opts = CpaOptions {
            min_poses: 2,
            ..CpaOptions::default()
        };
        let e = analyse(&set(&[[0.0, 0.0]]), &opts).unwrap_err();
        assert_eq!(
            e.to_string(),
            "option min_poses: expected at least 3, found 2"
        );
        let e = analyse(&set(&[[0.0, 0.0], [1.0, 0.0]]), &CpaOptions::default()).unwrap_err();
        assert_eq!(
            e.to_string(),
            "no sweep of 'a', 'b' found; sweeps found: none"
        );
    }

    #[test]
    fn values_within_the_unchanged_tolerance_are_one_pose() {
        let m = set(&[
            [0.0, 0.0],
            [1e-6, -1e-6],
            [1.0, 0.0],
            [2.0, 3e-6],
            [3.0, 0.0],
        ]);
        let opts = CpaOptions::default();
        let poses = group_poses(&m, opts.unchanged);
        assert_eq!(poses.len(), 4);
        let sweeps = find_sweeps(&m, &poses, &opts);
        assert_eq!(sweeps.len(), 1);
        assert!(sweeps[0].coupled.is_empty());
    }

    #[test]
    fn wrap_stays_in_half_open_interval() {
        assert_relative_eq!(wrap(3.0 * PI), PI, epsilon = 1e-15);
        assert_relative_eq!(wrap(-PI), PI, epsilon = 1e-15);
        assert_relative_eq!(wrap(0.1 - TAU), 0.1, epsilon = 1e-15);
    }

    #[test]
    fn exact_circle_by_hand() {
        // Circle of radius 2 about (1, 2, 3) in the plane x + z = const, normal (1, 0, 1)/√2.
        let n = Vector3::new(1.0, 0.0, 1.0).normalize();
        let u = Vector3::y();
        let v = n.cross(&u);
        let c = Vector3::new(1.0, 2.0, 3.0);
        let pts: Vec<Vector3<f64>> = (0..5)
            .map(|i| {
                let a = 0.3 * f64::from(i);
                c + (u * a.cos() + v * a.sin()) * 2.0
            })
            .collect();
        for method in [CircleMethod::Kasa, CircleMethod::Geometric] {
            let fit = fit_circle(&pts, method).unwrap();
            assert_relative_eq!(fit.centre, c, epsilon = 1e-12);
            assert_relative_eq!(fit.radius, 2.0, epsilon = 1e-12);
            assert_relative_eq!(fit.normal.dot(&n).abs(), 1.0, epsilon = 1e-12);
            assert!(fit.circle_rms < 1e-12 && fit.plane_rms < 1e-12);
        }
    }

    #[test]
    fn collinear_points_are_an_error_not_nan() {
        let pts: Vec<Vector3<f64>> = (0..4).map(|i| Vector3::x() * f64::from(i)).collect();
        let e = fit_circle(&pts, CircleMethod::Geometric).unwrap_err();
        assert!(e.to_string().contains("lie on a line"), "{e}");
        assert!(fit_circle(&pts[..2], CircleMethod::Kasa).is_err());
    }

    #[test]
    fn least_squares_recovers_a_line_and_refuses_rank_deficiency() {
        let q = [0.0, 1.0, 2.0, 3.0];
        let e: Vec<f64> = q.iter().map(|x| 0.5 + 2.0 * x).collect();
        let (c, r) = least_squares(&q, &e, &[Basis::One, Basis::Q]).unwrap();
        assert_relative_eq!(c[1], 2.0, epsilon = 1e-12);
        assert!(r < 1e-12);
        // Every q a multiple of 2π: cos is the constant.
        let q = [0.0, TAU, 2.0 * TAU, 3.0 * TAU];
        assert!(least_squares(&q, &e, &[Basis::One, Basis::Cos, Basis::Sin]).is_none());
    }
}
