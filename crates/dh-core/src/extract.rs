//! The recursive DH frame construction of the paper (§3.1), generalised to real robots: any
//! first axis (a base transform), a tool transform to the tip link, prismatic and mimic joints,
//! and both conventions from one skeleton of frames.
//!
//! # Frames and free choices
//! Input lines and the tip pose are in the base link frame. The construction walks the axes
//! keeping `S`, the current standard DH frame, whose z axis is the table's version of the
//! current joint axis. Every row is computed in `S`'s own coordinates and `S` then advances by
//! that row's transform, so snapping one pair never makes a later row inconsistent; after an
//! unsnapped step `S` lies on the next axis as given, and is put back there when its rounding
//! has drifted (`reanchor`), so that errors do not compound along a long chain of skew axes.
//! The tool is taken from the rows composed, the table's own forward kinematics. The free
//! choices, made so that tables read like vendor sheets:
//! - frame 0: z along joint 1 (its URDF direction, so `q` keeps its sign), origin at the point of
//!   axis 1 nearest the base origin, x along x_1 so that `theta_1 = 0`; the base transform
//!   carries the rest;
//! - intersecting axes: x = ±(z_i × z_{i+1}) (eq. 17, normalised), sign chosen so that
//!   `theta ∈ (−90°, 90°]`;
//! - skew axes: x along the common normal (eq. 19), `a` the signed distance along it;
//! - parallel axes: the common normal through the current origin (§2.3), so `d = 0`, x along
//!   the offset between the axes (eq. 18), `a` the signed distance along it;
//! - the sign of x at skew, parallel and intersecting pairs: `theta` within 90° of the
//!   previous x (see `orient`), so that zero offsets appear wherever the zero pose allows;
//! - coincident axes: `a = 0`, `d = 0`, x unchanged (`theta = 0`);
//! - last frame (standard): z along the last axis, origin at the tip link's origin when it is off
//!   the axis (x pointing at it), else at the tip origin's foot with x from the tip's own x
//!   axis (its y axis when x is along the joint axis); the tool transform is then a rotation
//!   (ERRATA: the paper excludes a tip on the last axis);
//! - last frame (modified): Craig's rule, `d_n = 0` and `theta_n = 0`; the tool carries the rest.

use std::f64::consts::{FRAC_1_SQRT_2, FRAC_PI_2, PI};
use std::fmt;

use nalgebra::{Isometry3, Vector3};

use crate::pose::{from_axes, rot_z};
use crate::relation::{classify_from_z, PairGeometry, Relation};
use crate::table::{standard_from_halves, Convention, DhRow, DhTable, JointKind, Limits, Mimic};
use crate::tolerance::NOISE_RELATIVE;
use crate::{CoreError, Line, Tolerance};

/// One moving joint as a line in the base link frame at `q = 0`.
#[derive(Clone, Debug, PartialEq)]
pub struct JointAxis {
    /// Joint name.
    pub name: String,
    /// Revolute or prismatic.
    pub kind: JointKind,
    /// The axis line; its direction is the positive sense of the joint (for prismatic joints
    /// any parallel line would do; the given one is kept).
    pub line: Line,
    /// Joint limits, `None` for continuous joints.
    pub limits: Option<Limits>,
    /// Set for a joint that follows another.
    pub mimic: Option<Mimic>,
}

/// How one consecutive pair of axes was classified.
#[derive(Clone, Debug, PartialEq)]
pub struct PairReport {
    /// Row index of the earlier joint (the later one is `first + 1`).
    pub first: usize,
    /// Class, angle and distance (the earlier axis as the table has it, the later as given).
    pub geometry: PairGeometry,
}

/// Something the user must know about a table that is not exact or not well conditioned.
#[derive(Clone, Debug, PartialEq)]
pub enum Warning {
    /// A pair within the angular tolerance of parallel was treated as parallel (or coincident):
    /// the table's axis of `second` is tilted from the given one by `angle_deviation`.
    SnappedParallel {
        /// Earlier joint.
        first: String,
        /// Later joint.
        second: String,
        /// The class it was put in.
        relation: Relation,
        /// Angle from exact parallelism (radians).
        angle_deviation: f64,
        /// The angular tolerance used (radians).
        tolerance: f64,
        /// Largest position change this can cause at the tip (metres; a bound).
        position_cost: f64,
        /// Largest orientation change (radians; a bound).
        orientation_cost: f64,
        /// The axis of `first` was itself snapped, and the deviation is measured from the
        /// table's version of it.
        after_snap: bool,
    },
    /// A pair within the linear tolerance of intersecting was treated as intersecting.
    SnappedIntersecting {
        /// Earlier joint.
        first: String,
        /// Later joint.
        second: String,
        /// Length of the common normal that was set to zero (metres).
        distance: f64,
        /// The linear tolerance used (metres).
        tolerance: f64,
        /// Largest position change this can cause at the tip (metres; a bound).
        position_cost: f64,
    },
    /// A nearly parallel pair beyond the tolerance gives an exact but ill-conditioned row whose
    /// common normal lies far from the robot.
    IllConditioned {
        /// Earlier joint.
        first: String,
        /// Later joint.
        second: String,
        /// Angle from exact parallelism (radians).
        angle_from_parallel: f64,
        /// The largest of `|a|`, `|d|` in the row (metres).
        offset: f64,
        /// An angular tolerance that would treat the pair as parallel (radians).
        suggested_tolerance: f64,
    },
    /// A joint whose lower and upper limits are equal cannot move (a URDF `<limit>` that leaves
    /// out `lower` and `upper` means 0 and 0). Verification moves it all the same
    /// ([`crate::JointSampler`]), so the table is proved for every value.
    FrozenJoint {
        /// The joint.
        joint: String,
        /// Its one allowed value (radians or metres).
        value: f64,
    },
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Warning::SnappedParallel {
                first,
                second,
                relation,
                angle_deviation,
                tolerance,
                position_cost,
                orientation_cost,
                after_snap,
            } => write!(
                f,
                "axes of '{first}' and '{second}' are {angle_deviation:.3e} rad from {relation} \
                 (angular tolerance {tolerance:.1e} rad){}: treated as {relation}; FK cost of \
                 snapping at most {position_cost:.3e} m, {orientation_cost:.3e} rad",
                if *after_snap {
                    format!(" measured from the snapped axis of '{first}'")
                } else {
                    String::new()
                }
            ),
            Warning::SnappedIntersecting {
                first,
                second,
                distance,
                tolerance,
                position_cost,
            } => write!(
                f,
                "axes of '{first}' and '{second}' miss each other by {distance:.3e} m (linear \
                 tolerance {tolerance:.1e} m): treated as intersecting; FK cost of snapping at \
                 most {position_cost:.3e} m"
            ),
            Warning::IllConditioned {
                first,
                second,
                angle_from_parallel,
                offset,
                suggested_tolerance,
            } => write!(
                f,
                "ILL-CONDITIONED: axes of '{first}' and '{second}' are {angle_from_parallel:.3e} \
                 rad from parallel, beyond the angular tolerance, so their common normal lies \
                 {offset:.3e} m away and the row is exact but meaningless to a reader; if the \
                 axes are meant to be parallel, pass --angular-tol {suggested_tolerance:.1e}"
            ),
            Warning::FrozenJoint { joint, value } => write!(
                f,
                "joint '{joint}' cannot move: its lower and upper limits are both {value} (a \
                 URDF <limit> without lower and upper means 0); verification moves it over a \
                 full range all the same"
            ),
        }
    }
}

/// Largest deviations an extraction may show against its source and still be exact (or exact
/// up to the reported snaps), never more than [`Bound::MAX_POSITION`] and
/// [`Bound::MAX_ORIENTATION`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bound {
    /// Position (metres).
    pub position: f64,
    /// Orientation (radians).
    pub orientation: f64,
}

impl Bound {
    /// Cap of the position bound (metres), whatever the tolerances: 1 mm. Snaps with loose
    /// tolerances on a large arm could otherwise bound the deviation by metres, and a table
    /// that misses its source by that much would still verify. A table more than 1 mm off is
    /// another robot for any calibration or check this tool makes.
    pub const MAX_POSITION: f64 = 1e-3;
    /// Cap of the orientation bound (radians): 1 mrad (0.057°), as [`Bound::MAX_POSITION`].
    pub const MAX_ORIENTATION: f64 = 1e-3;
}

/// A DH table with the facts behind it.
#[derive(Clone, Debug, PartialEq)]
pub struct Extraction {
    /// The table, with base and tool.
    pub table: DhTable,
    /// Classification of every consecutive pair of axes.
    pub pairs: Vec<PairReport>,
    /// Snaps and ill-conditioned rows.
    pub warnings: Vec<Warning>,
    /// Tolerance used.
    pub tolerance: Tolerance,
    /// How far forward kinematics of the table may stray from the source: floating-point
    /// rounding over the chain plus the cost of every snap, capped at [`Bound::MAX_POSITION`]
    /// and [`Bound::MAX_ORIENTATION`] (a table beyond them fails its verification).
    pub bound: Bound,
    /// The same before the cap: what the snaps can cost at most (a bound whatever the
    /// tolerances, not a promise that the table verifies).
    pub cost: Bound,
}

/// Pairs farther than this from parallel (radians, about 6°) are never ill-conditioned.
const ILL_CONDITIONED_ANGLE: f64 = 0.1;

/// Relative rounding allowance per transform in a chain, in units of machine epsilon.
const ROUNDING_ULPS: f64 = 64.0;

/// A row computed in the current frame's coordinates, with the snap it needed.
struct Step {
    theta: f64,
    d: f64,
    a: f64,
    alpha: f64,
    geometry: PairGeometry,
    /// Tilt (radians) and displacement (metres) between the table's next axis and the given one.
    snap: Option<(f64, f64)>,
    /// `(sin, cos)` of `theta / 2` and of `alpha / 2`, from the unit vectors the angles were
    /// read from (see [`half_angle`]), so that advancing the frame needs no trigonometry.
    halves: ((f64, f64), (f64, f64)),
}

/// `(sin, cos)` of `angle / 2` for `angle = atan2(s, c)` with `(c, s)` a unit vector, by the
/// half-angle identities with no cancellation: `cos(angle/2) = sqrt((1 + c)/2)` for `c ≥ 0`,
/// else `sin(angle/2) = ±sqrt((1 − c)/2)`, the other from `sin(angle) = 2 sin cos`.
fn half_angle(c: f64, s: f64) -> (f64, f64) {
    if c >= 0.0 {
        let ch = (0.5 * (1.0 + c)).sqrt();
        (s / (2.0 * ch), ch)
    } else {
        let sh = (0.5 * (1.0 - c)).sqrt().copysign(s);
        (sh, s / (2.0 * sh))
    }
}

/// `(sin, cos)` of the half of an angle that is exactly 0.
const HALF_OF_ZERO: (f64, f64) = (0.0, 1.0);

/// Extracts a DH table from joint axis lines and the tip link's pose, all in the base link
/// frame at `q = 0` (paper §3.1, eq. 16-24, generalised as the module docs say).
///
/// # Errors
/// [`CoreError::NoJoints`] for an empty chain; [`CoreError::NonFinite`] when a pose or line
/// holds NaN or infinity.
pub fn extract(
    axes: &[JointAxis],
    tip: &Isometry3<f64>,
    tol: Tolerance,
    convention: Convention,
) -> Result<Extraction, CoreError> {
    let first = axes.first().ok_or(CoreError::NoJoints)?;
    crate::line::check_finite("tip position", &tip.translation.vector)?;
    if !tip.rotation.coords.iter().all(|c| c.is_finite()) {
        return Err(CoreError::NonFinite {
            what: "tip rotation".into(),
            value: f64::NAN,
        });
    }
    // The largest distance of an input point from the base origin (metres, at least 1 mm): the
    // square root of the largest squared norm, which is the largest norm (sqrt is monotonic
    // and correctly rounded), with one square root instead of one per axis.
    let input_scale = axes
        .iter()
        .map(|ax| ax.line.point().norm_squared())
        .fold(tip.translation.vector.norm_squared(), f64::max)
        .sqrt()
        .max(1e-3);

    // Frame 0: z along joint 1, origin nearest the base origin, x from the base x (or y) for now.
    let z0 = first.line.direction();
    let pick = |v: Vector3<f64>| v - z0 * v.dot(&z0);
    let x_try = pick(Vector3::x());
    let x0 = if x_try.norm() >= FRAC_1_SQRT_2 {
        x_try.normalize()
    } else {
        pick(Vector3::y()).normalize()
    };
    let mut frame = from_axes(first.line.point(), x0, z0);
    let mut base = frame;

    let n = axes.len();
    let mut rows = Vec::with_capacity(n);
    let mut pairs = Vec::with_capacity(n.saturating_sub(1));
    // Snapped pairs `(first row, (tilt, shift))`, in row order; allocated at the first snap.
    let mut snaps: Vec<(usize, (f64, f64))> = Vec::new();
    let mut warnings: Vec<Warning> = axes
        .iter()
        .filter_map(|ax| {
            let l = ax.limits?;
            (l.lower == l.upper).then(|| Warning::FrozenJoint {
                joint: ax.name.clone(),
                value: l.lower,
            })
        })
        .collect();
    let mut last_standard_frame = frame;
    // The table's own frames, the rows composed from the base: `frame` may be put back on its
    // axis ([`reanchor`]), the table's forward kinematics is this.
    let mut composed = frame;
    for i in 0..n {
        let ax = &axes[i];
        let step = match axes.get(i + 1) {
            Some(next) => pair_step(&next.line.transformed(&frame.inverse()), tol),
            None => last_step(&(frame.inverse() * tip), tol),
        };
        let mut row = DhRow {
            name: ax.name.clone(),
            kind: ax.kind,
            a: step.a,
            alpha: step.alpha,
            d: step.d,
            theta: step.theta,
            beta: 0.0,
            limits: ax.limits,
            mimic: ax.mimic.clone(),
        };
        let (mut half_theta, half_alpha) = step.halves;
        if i == 0 {
            // Absorb theta_1 into the base so that the table starts at theta_1 = 0.
            base = frame * rot_z(row.theta);
            frame = base;
            composed = base;
            row.theta = 0.0;
            half_theta = HALF_OF_ZERO;
        }
        if let Some(next) = axes.get(i + 1) {
            pairs.push(PairReport {
                first: i,
                geometry: step.geometry,
            });
            if let Some(snap) = step.snap {
                if snaps.capacity() == 0 {
                    snaps.reserve_exact(n - 1 - i);
                }
                snaps.push((i, snap));
            }
            let from_parallel = step.geometry.angle.min(PI - step.geometry.angle);
            let offset = row.d.abs().max(row.a.abs());
            // Only a nearly parallel pair puts its common normal far away; a large offset after
            // such a pair merely cancels the previous one's and is not warned about again.
            if step.snap.is_none()
                && from_parallel < ILL_CONDITIONED_ANGLE
                && offset > 100.0 * input_scale
            {
                warnings.push(Warning::IllConditioned {
                    first: ax.name.clone(),
                    second: next.name.clone(),
                    angle_from_parallel: from_parallel,
                    offset,
                    suggested_tolerance: round_up(2.0 * from_parallel),
                });
            }
        }
        last_standard_frame = composed;
        // `row.transform(Convention::Standard, 0.0)` (rows of an extraction have no tilt), from
        // the halves the step kept.
        let advance = standard_from_halves(row.a, row.d, half_theta, half_alpha);
        frame *= advance;
        composed *= advance;
        // An unsnapped step lands on the next axis as given: keep the walking frame there.
        if let (Some(next), None) = (axes.get(i + 1), step.snap) {
            frame = reanchor(frame, &next.line, input_scale);
        }
        rows.push(row);
    }

    let mut table = DhTable {
        convention: Convention::Standard,
        base,
        tool: composed.inverse() * tip,
        rows,
    };
    if convention == Convention::Modified {
        table = table.into_convention(Convention::Modified);
        // Craig's rule for the last frame: d_n = 0, theta_n = 0, the tool carries the rest.
        let last = table.rows.len() - 1;
        table.rows[last].d = 0.0;
        table.rows[last].theta = 0.0;
        table.tool = last_standard_frame.inverse() * tip;
    }

    check_extracted_finite(&table)?;
    let size = table.size();
    let mut bound = Bound {
        position: (n as f64 + 1.0) * ROUNDING_ULPS * f64::EPSILON * size,
        orientation: (n as f64 + 1.0) * ROUNDING_ULPS * f64::EPSILON,
    };
    // The last pair seen whose snap tilted the later axis (snaps are in row order).
    let mut last_tilted = None;
    for (i, (tilt, shift)) in snaps {
        let position_cost = 4.0 * tilt * size + 2.0 * shift;
        let orientation_cost = 2.0 * tilt;
        bound.position += position_cost;
        bound.orientation += orientation_cost;
        // The names are copied only for a warning, not for every snap.
        let names = || (axes[i].name.clone(), axes[i + 1].name.clone());
        let geometry = pairs[i].geometry;
        if tilt > NOISE_RELATIVE {
            let (first, second) = names();
            warnings.push(Warning::SnappedParallel {
                first,
                second,
                relation: geometry.relation,
                angle_deviation: tilt,
                tolerance: tol.angular,
                position_cost,
                orientation_cost,
                after_snap: i > 0 && last_tilted == Some(i - 1),
            });
            last_tilted = Some(i);
        } else if shift > NOISE_RELATIVE * size {
            let (first, second) = names();
            warnings.push(Warning::SnappedIntersecting {
                first,
                second,
                distance: shift,
                tolerance: tol.linear,
                position_cost,
            });
        }
    }
    let cost = bound;
    bound.position = bound.position.min(Bound::MAX_POSITION);
    bound.orientation = bound.orientation.min(Bound::MAX_ORIENTATION);
    Ok(Extraction {
        table,
        pairs,
        warnings,
        tolerance: tol,
        bound,
        cost,
    })
}

/// The standard row from the current frame (its z axis is the current joint axis) to the frame
/// on the next axis `next`, given in the current frame's coordinates.
fn pair_step(next: &Line, tol: Tolerance) -> Step {
    // `sin` = |z × u|, the sine of the pair's angle.
    let (geometry, sin) = classify_from_z(next, tol);
    let u = next.direction();
    // The point of the next axis nearest the current origin (metres).
    let foot = next.point();
    match geometry.relation {
        Relation::Parallel | Relation::Antiparallel | Relation::Coincident { .. } => {
            let (alpha, half_alpha) = if u.z < 0.0 {
                (PI, (1.0, 0.0))
            } else {
                (0.0, HALF_OF_ZERO)
            };
            let (x, theta, a) = match geometry.relation {
                Relation::Coincident { .. } => (Vector3::x(), 0.0, 0.0),
                _ => {
                    let radial = foot.xy().norm();
                    orient(Vector3::new(foot.x, foot.y, 0.0) / radial, radial, tol)
                }
            };
            let origin = x * a;
            Step {
                theta,
                d: 0.0,
                a,
                alpha,
                geometry,
                snap: Some((geometry.angle_deviation, next.distance_to_point(&origin))),
                halves: (half_angle(x.x, x.y), half_alpha),
            }
        }
        Relation::Intersecting | Relation::Skew => {
            // `classify_from_z` returned non-parallel, so `sin` is not zero. The unit common
            // normal n = (z × u) / sin (eq. 14-15, ERRATA: normalised).
            let n = Vector3::new(-u.y / sin, u.x / sin, 0.0);
            // eq. (14) with line 1 the z axis (e1 = z, k1 = 0): the foot of the common normal
            // on the current axis is f1 = (0, 0, (k2 · n) / sin); eq. (21) makes its height d.
            let k = next.moment();
            let k2n = k.x * n.x + k.y * n.y;
            let d = k2n / sin;
            let (x, theta, a, snap) = if geometry.relation == Relation::Skew {
                // The signed length of the common normal, (f2 − f1) · n = f2 · n (f1 is on the z
                // axis), with f2 = u (cos · (k2 · n) / sin) + foot by eq. (15).
                let t = (u.z * k2n) / sin;
                let a = (u.x * t + foot.x) * n.x + (u.y * t + foot.y) * n.y;
                let (x, theta, a) = orient(n, a, tol);
                (x, theta, a, None)
            } else {
                let (x, theta, _) = orient(n, 0.0, tol);
                (x, theta, 0.0, Some((0.0, geometry.distance)))
            };
            // eq. (24): alpha = atan2((z_i × z_{i+1}) · x_{i+1}, z_i · z_{i+1}). With x_{i+1} the
            // unit common normal, |(z_i × z_{i+1}) · x_{i+1}| = sin(angle), so alpha is the
            // pair's angle (from `classify_from_z`, in (0, π)) with the sign of that triple
            // product.
            let sign = -u.y * x.x + u.x * x.y;
            let alpha = geometry.angle.copysign(sign);
            Step {
                // cos(alpha) = z · u, sin(alpha) = ±|z × u| = ±sin.
                halves: (half_angle(x.x, x.y), half_angle(u.z, sin.copysign(sign))),
                // eq. (22) with x_i = (1, 0, 0) in the current frame.
                theta,
                d,
                a,
                alpha,
                geometry,
                snap,
            }
        }
    }
}

/// The last standard row: from the frame on the last axis to a frame with z parallel to it at
/// the tip link's origin (see the module docs). `tip` is in the current frame's coordinates.
fn last_step(tip: &Isometry3<f64>, tol: Tolerance) -> Step {
    let t = tip.translation.vector;
    let radial = t.xy().norm();
    let (theta, a, half_theta) = if radial > tol.linear {
        (
            t.y.atan2(t.x),
            radial,
            half_angle(t.x / radial, t.y / radial),
        )
    } else {
        let tx = tip.rotation * Vector3::x();
        let axis = if tx.xy().norm() >= FRAC_1_SQRT_2 {
            tx
        } else {
            tip.rotation * Vector3::y()
        };
        let r = axis.xy().norm();
        (
            axis.y.atan2(axis.x),
            0.0,
            half_angle(axis.x / r, axis.y / r),
        )
    };
    Step {
        halves: (half_theta, HALF_OF_ZERO),
        theta,
        d: t.z,
        a,
        alpha: 0.0,
        geometry: PairGeometry {
            relation: Relation::Parallel,
            angle: 0.0,
            distance: radial,
            angle_deviation: 0.0,
            distance_deviation: 0.0,
        },
        snap: None,
    }
}

/// Chooses the sign of a common normal `x` (unit, in the current frame's xy plane) and of the
/// link length `a` measured along it, so that `theta = atan2(x.y, x.x)` lies within 90° of the
/// current x axis: the table then reads like a vendor sheet (zero offsets where the zero pose
/// allows, a negative `a` rather than a 180° offset). At exactly ±90° (within the angular
/// tolerance) `a ≥ 0` wins, and for `a = 0` the +90° side. Returns `(x, theta, a)`.
fn orient(x: Vector3<f64>, a: f64, tol: Tolerance) -> (Vector3<f64>, f64, f64) {
    let theta = x.y.atan2(x.x);
    let boundary = (theta.abs() - FRAC_PI_2).abs() <= tol.angular;
    let flip = if boundary {
        a < 0.0 || (a == 0.0 && theta < 0.0)
    } else {
        theta.abs() > FRAC_PI_2
    };
    if flip {
        // atan2 of the reversed vector, without a second atan2: theta ∓ π lands in (−π, π].
        let flipped = if theta > 0.0 { theta - PI } else { theta + PI };
        (-x, flipped, -a)
    } else {
        (x, theta, a)
    }
}

/// `x` rounded up to one significant digit (for a suggested tolerance).
fn round_up(x: f64) -> f64 {
    if x <= 0.0 || !x.is_finite() {
        return x;
    }
    let p = 10f64.powf(x.log10().floor());
    (x / p).ceil() * p
}

mod precision;
use precision::{check_extracted_finite, reanchor};

#[cfg(test)]
mod tests;
