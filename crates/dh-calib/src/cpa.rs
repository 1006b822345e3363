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
//!    The points a lost beam or a mistyped row put far off are left out first and named
//!    ([`SweepScreen`]: `calibrate`'s outlier screen, [`crate::outliers`], on each target's
//!    distance from its circle in units of the measurement noise); every later step fits
//!    without them.
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
//!
//! # Layout
//! Items live in submodules and are re-exported here: settings and errors (`options`), the
//! result's types (`result`), the analysis (`analyse`), poses and sweeps (`sweeps`), fitting a sweep's joint
//! (`joint_fit`), and the circle and coaxial fits (`circle`).

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

// The submodules import what they use through `use super::*`: the imports above and each
// other's items, re-exported here.
mod options;
pub use options::*;
mod result;
pub use result::*;
mod analyse;
pub use analyse::*;
mod sweeps;
use sweeps::*;
mod joint_fit;
use joint_fit::*;
mod circle;
pub use circle::*;
mod screen;
pub use screen::*;
#[cfg(test)]
mod tests;
