//! Do two DH tables describe the same mechanism? And if not, which joint and which parameter
//! differ?
//!
//! Comparing tables entry by entry fails on representation freedoms: the sign of x at
//! intersecting axes, where the common normal of parallel axes sits, the convention, equivalent
//! `alpha`/`theta` sign combinations, units. Instead the tables are walked together, row by row,
//! keeping the transform `C_i` between their frames `i` (standard convention). Both frames have
//! their z axis on the same joint axis line when the mechanisms agree, so `C_i` must be a motion
//! along that line: `C_i = Tz(t) Rz(phi) Rx(pi)^f` (`f` set when the two tables give the joint
//! opposite directions). Row `i` then holds when
//!
//! ```text
//! C_(i-1) · A_ref,i(q) = A_sheet,i(s_i q + o_i) · C_i     for all q,
//! ```
//!
//! with `s_i = ±1` the direction (fixed by `f` of `C_(i-1)`) and `o_i` the zero-pose offset. For
//! each row the offset (and a shift along the axis, the `d` difference) is solved, and whatever
//! is left is read as a difference of the sheet's `a` and `alpha`. Free base or tool transforms
//! make the first row's `theta`, `d` (or the last row's parameters) unobservable, and they are
//! never reported.

use std::f64::consts::PI;

use nalgebra::{Isometry3, Matrix3, Translation3, UnitQuaternion, Vector3};

use crate::pose::{pose_error, rot_x, rot_z, trans_z};
use crate::table::{Convention, DhTable, JointKind};
use crate::Tolerance;

/// Which parameter differs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Parameter {
    /// Link length `a` (metres).
    A,
    /// Link twist `alpha` (radians).
    Alpha,
    /// Link offset `d` (metres), or a prismatic joint's zero offset.
    D,
    /// Joint angle offset `theta` (radians): a different zero pose.
    Theta,
    /// The joint turns (slides) the other way: `urdf` and `sheet` are the signs.
    Direction,
    /// The base transform given by the sheet (position error m, orientation error rad).
    Base,
    /// The tool transform given by the sheet.
    Tool,
}

impl Parameter {
    /// The name used in reports: `a|alpha|d|theta|direction|base|tool`.
    pub fn as_str(self) -> &'static str {
        match self {
            Parameter::A => "a",
            Parameter::Alpha => "alpha",
            Parameter::D => "d",
            Parameter::Theta => "theta",
            Parameter::Direction => "direction",
            Parameter::Base => "base",
            Parameter::Tool => "tool",
        }
    }
}

/// One difference between a reference table (from the URDF) and a sheet.
#[derive(Clone, Debug, PartialEq)]
pub struct Difference {
    /// Row index in the sheet's convention (`None` for base and tool).
    pub row: Option<usize>,
    /// Which parameter.
    pub parameter: Parameter,
    /// The value the sheet would need to match the reference (SI units; the sign for a
    /// direction; the position error for base and tool).
    pub reference: f64,
    /// The sheet's value (the sign +1 for a direction; 0 for base and tool).
    pub sheet: f64,
    /// Other rows whose same parameter the data cannot tell apart from this one (`d` along a
    /// run of parallel axes).
    pub aliases: Vec<usize>,
}

/// The result of [`compare_tables`].
#[derive(Clone, Debug, PartialEq)]
pub struct Equivalence {
    /// Every difference found (empty: the tables agree within the tolerance).
    pub differences: Vec<Difference>,
    /// Joint direction of the sheet relative to the reference, per row.
    pub signs: Vec<f64>,
    /// Zero-pose offset per row (`q_sheet = sign · q_ref + offset`; radians or metres).
    pub offsets: Vec<f64>,
}

/// What the sheet leaves open.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Freedom {
    /// The sheet gives no base transform: any base is accepted.
    pub base_free: bool,
    /// The sheet gives no tool transform: any tool is accepted.
    pub tool_free: bool,
}

/// A motion along the z axis: `Tz(t) Rz(phi) Rx(pi)^flip`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct AxisMotion {
    t: f64,
    phi: f64,
    flip: bool,
}

impl AxisMotion {
    fn iso(&self) -> Isometry3<f64> {
        trans_z(self.t)
            * rot_z(self.phi)
            * if self.flip {
                rot_x(PI)
            } else {
                Isometry3::identity()
            }
    }

    /// The nearest motion along z to `y` and what is left over: (motion, tilt of y's z axis
    /// from ±z in radians, distance of y's origin from the z axis in metres).
    fn project(y: &Isometry3<f64>) -> (AxisMotion, f64, f64) {
        let r: Matrix3<f64> = *y.rotation.to_rotation_matrix().matrix();
        let flip = r[(2, 2)] < 0.0;
        let tilt = (r[(0, 2)].powi(2) + r[(1, 2)].powi(2))
            .sqrt()
            .atan2(r[(2, 2)].abs());
        let t = y.translation.vector;
        (
            AxisMotion {
                t: t.z,
                phi: r[(1, 0)].atan2(r[(0, 0)]),
                flip,
            },
            tilt,
            t.xy().norm(),
        )
    }
}

/// Row geometry of the sheet.
#[derive(Clone, Copy, Debug)]
struct SheetRow {
    theta: f64,
    d: f64,
    a: f64,
    alpha: f64,
}

/// What one row's solve found.
#[derive(Clone, Copy, Debug)]
struct RowFit {
    psi: f64,
    cost: f64,
}

fn wrap(a: f64) -> f64 {
    let w = (a + PI).rem_euclid(2.0 * PI) - PI;
    if w <= -PI + 1e-15 {
        PI
    } else {
        w
    }
}

/// `M⁻¹ Tz(−delta) Rz(−psi) X` with `M = Tz(d) Tx(a) Rx(alpha)`, and the `delta` that puts its
/// origin on its z axis (when the axes are not parallel; else 0).
fn residual_frame(
    x: &Isometry3<f64>,
    s: &SheetRow,
    psi: f64,
    parallel: bool,
) -> (Isometry3<f64>, f64) {
    let w = rot_z(-psi) * x;
    let (sa, ca) = s.alpha.sin_cos();
    let delta = if parallel {
        0.0
    } else {
        let v = w.translation.vector;
        v.z - s.d + ca / sa * v.y
    };
    let y = rot_x(-s.alpha) * Isometry3::translation(-s.a, 0.0, -s.d - delta) * w;
    (y, delta)
}

fn cost(y: &Isometry3<f64>, scale: f64) -> f64 {
    let r = y.rotation.to_rotation_matrix();
    let m = r.matrix();
    let t = y.translation.vector;
    (scale * m[(0, 2)]).powi(2) + (scale * m[(1, 2)]).powi(2) + t.x * t.x + t.y * t.y
}

/// Solves one row: the rotations `psi` about the current axis (with the shift `delta` along it)
/// that make `X = C·A_ref(0)` agree with the sheet's row.
fn solve_row(
    x: &Isometry3<f64>,
    s: &SheetRow,
    parallel: bool,
    scale: f64,
    tol: Tolerance,
) -> Vec<RowFit> {
    const STEPS: usize = 720;
    let eval = |psi: f64| {
        let (y, _) = residual_frame(x, s, psi, parallel);
        RowFit {
            psi,
            cost: cost(&y, scale),
        }
    };
    let grid: Vec<RowFit> = (0..STEPS)
        .map(|k| eval(s.theta - PI + 2.0 * PI * k as f64 / STEPS as f64))
        .collect();
    let mut minima = Vec::new();
    for k in 0..STEPS {
        let (prev, here, next) = (
            &grid[(k + STEPS - 1) % STEPS],
            &grid[k],
            &grid[(k + 1) % STEPS],
        );
        if here.cost <= prev.cost && here.cost <= next.cost {
            // Golden-section refinement inside the bracket.
            let (mut lo, mut hi) = (
                here.psi - 2.0 * PI / STEPS as f64,
                here.psi + 2.0 * PI / STEPS as f64,
            );
            let g = 0.5 * (5f64.sqrt() - 1.0);
            let (mut c, mut d) = (hi - g * (hi - lo), lo + g * (hi - lo));
            let (mut fc, mut fd) = (eval(c).cost, eval(d).cost);
            for _ in 0..80 {
                if fc < fd {
                    hi = d;
                    d = c;
                    fd = fc;
                    c = hi - g * (hi - lo);
                    fc = eval(c).cost;
                } else {
                    lo = c;
                    c = d;
                    fc = fd;
                    d = lo + g * (hi - lo);
                    fd = eval(d).cost;
                }
            }
            minima.push(eval(0.5 * (lo + hi)));
        }
    }
    // A row "holds" when its residual is within the tolerances; every holding solution is a
    // candidate (x flipped at intersecting axes, or the next joint reversed, are different
    // descriptions, to be told apart by the rows after); with none, the best fit is.
    let good = (tol.linear.max(scale * tol.angular)).powi(2);
    let mut holding: Vec<RowFit> = Vec::new();
    // The sheet's own theta first: where the row leaves x free (coincident axes) the cost is
    // flat and its minima are rounding noise.
    let own = eval(s.theta);
    if own.cost <= good {
        holding.push(own);
    }
    for f in minima.iter().filter(|f| f.cost <= good) {
        if !holding.iter().any(|h| wrap(h.psi - f.psi).abs() < 1e-6) {
            holding.push(*f);
        }
    }
    if holding.is_empty() {
        // Nothing holds: a parameter differs. Keep the few best descriptions anyway, since the
        // best fit of this row alone may not lead to the fewest differences overall.
        let mut sorted = minima.clone();
        sorted.sort_by(|a, b| a.cost.total_cmp(&b.cost));
        for f in sorted {
            if holding.len() == MAX_CANDIDATES {
                break;
            }
            if !holding.iter().any(|h| wrap(h.psi - f.psi).abs() < 1e-6) {
                holding.push(f);
            }
        }
    }
    holding
}

/// Compares `sheet` with `reference`, a table known to be exact for the robot (extracted from
/// its URDF), both in any convention and with the same number of rows (same order). Tolerances
/// decide what counts as a difference: lengths against `linear` (metres), angles against
/// `angular` (radians).
///
/// Differences are reported against the sheet's own rows (for a modified sheet, the `a` and
/// `alpha` of row `i + 1` are the standard `a`, `alpha` of row `i`).
pub fn compare_tables(
    reference: &DhTable,
    sheet: &DhTable,
    freedom: Freedom,
    tol: Tolerance,
) -> Equivalence {
    let reference = reference.to_convention(Convention::Standard);
    let std = sheet.to_convention(Convention::Standard);
    let scale = reference.size().max(std.size());
    let starts: Vec<AxisMotion> = if freedom.base_free {
        vec![
            AxisMotion {
                t: 0.0,
                phi: 0.0,
                flip: false,
            },
            AxisMotion {
                t: 0.0,
                phi: 0.0,
                flip: true,
            },
        ]
    } else {
        vec![AxisMotion::project(&(std.base.inverse() * reference.base)).0]
    };
    let mut beam: Vec<State> = starts
        .into_iter()
        .map(|c| State {
            c,
            differences: vec![],
            signs: vec![],
            offsets: vec![],
            parallel_run: vec![],
        })
        .collect();
    if !freedom.base_free {
        let (_, tilt, off) = AxisMotion::project(&(std.base.inverse() * reference.base));
        if tilt > tol.angular || off > tol.linear {
            for st in &mut beam {
                st.differences.push(Difference {
                    row: None,
                    parameter: Parameter::Base,
                    reference: off,
                    sheet: 0.0,
                    aliases: vec![],
                });
            }
        }
    }
    let n = std.rows.len().min(reference.rows.len());
    for i in 0..n {
        let mut next = Vec::new();
        for st in &beam {
            next.extend(step(
                st,
                i,
                &reference,
                &std,
                sheet.convention,
                freedom,
                tol,
                scale,
            ));
        }
        next.sort_by(|a, b| a.rank().total_cmp(&b.rank()));
        next.truncate(BEAM);
        beam = next;
    }
    match beam.into_iter().next() {
        Some(st) => Equivalence {
            differences: st.differences,
            signs: st.signs,
            offsets: st.offsets,
        },
        None => Equivalence {
            differences: vec![],
            signs: vec![],
            offsets: vec![],
        },
    }
}

/// Descriptions of one row kept when none holds.
const MAX_CANDIDATES: usize = 4;

/// Partial descriptions kept while walking the rows: the fewest differences win, ties go to
/// the smallest offsets.
const BEAM: usize = 16;

/// One partial description of the sheet in terms of the reference.
#[derive(Clone, Debug)]
struct State {
    c: AxisMotion,
    differences: Vec<Difference>,
    signs: Vec<f64>,
    offsets: Vec<f64>,
    /// Rows whose `d` cannot be told apart from the next one's (parallel axes), pending.
    parallel_run: Vec<usize>,
}

impl State {
    fn rank(&self) -> f64 {
        self.differences.len() as f64 * 1e3 + self.offsets.iter().map(|o| o.abs()).sum::<f64>()
    }
}

/// Extends `st` by row `i`: one new state per way the row can hold.
#[allow(clippy::too_many_arguments)]
fn step(
    st: &State,
    i: usize,
    reference: &DhTable,
    std: &DhTable,
    convention: Convention,
    freedom: Freedom,
    tol: Tolerance,
    scale: f64,
) -> Vec<State> {
    let n = std.rows.len().min(reference.rows.len());
    let sign = if st.c.flip { -1.0 } else { 1.0 };
    let srow = &std.rows[i];
    let s = SheetRow {
        theta: srow.theta,
        d: srow.d,
        a: srow.a,
        alpha: srow.alpha,
    };
    let x = st.c.iso() * reference.rows[i].transform(Convention::Standard, 0.0);
    let parallel = s.alpha.sin().abs() <= tol.angular.sin();
    let first_free = i == 0 && freedom.base_free;
    let last_free = i + 1 == n && freedom.tool_free;
    let prismatic = srow.kind == JointKind::Prismatic;
    if i + 1 == n && !freedom.tool_free {
        return vec![last_with_tool(st, i, &x, reference, std, first_free, tol)];
    }
    let mut out = Vec::new();
    for fit in solve_row(&x, &s, parallel, scale, tol) {
        let mut next = st.clone();
        let (y, delta) = residual_frame(&x, &s, fit.psi, parallel);
        let theta_offset = wrap(fit.psi - s.theta);
        next.signs.push(sign);
        next.offsets
            .push(if prismatic { delta } else { theta_offset });
        if sign < 0.0 {
            next.differences.push(Difference {
                row: Some(i),
                parameter: Parameter::Direction,
                reference: -1.0,
                sheet: 1.0,
                aliases: vec![],
            });
        }
        if !first_free && !last_free {
            if theta_offset.abs() > tol.angular {
                next.differences.push(Difference {
                    row: Some(i),
                    parameter: Parameter::Theta,
                    reference: s.theta + theta_offset,
                    sheet: s.theta,
                    aliases: vec![],
                });
            }
            if delta.abs() > tol.linear {
                let aliases = st
                    .parallel_run
                    .iter()
                    .copied()
                    .filter(|&r| r != i)
                    .collect();
                next.differences.push(Difference {
                    row: Some(i),
                    parameter: Parameter::D,
                    reference: s.d + delta,
                    sheet: s.d,
                    aliases,
                });
            }
        }
        // What the reference's next axis needs of this row's a and alpha.
        let w = rot_z(-fit.psi) * Isometry3::translation(0.0, 0.0, -s.d - delta) * x;
        let wz = w.rotation * Vector3::z();
        let next_flip = wz.dot(&(rot_x(s.alpha).rotation * Vector3::z())) < 0.0;
        let a_ref = w.translation.vector.x;
        let alpha_ref = wrap((-wz.y).atan2(wz.z) + if next_flip { PI } else { 0.0 });
        if !last_free {
            // Standard row i's a, alpha are the modified sheet's row i + 1.
            let row = match convention {
                Convention::Standard => Some(i),
                Convention::Modified => Some(i + 1),
            };
            if (a_ref - s.a).abs() > tol.linear {
                next.differences.push(Difference {
                    row,
                    parameter: Parameter::A,
                    reference: a_ref,
                    sheet: s.a,
                    aliases: vec![],
                });
            }
            if wrap(alpha_ref - s.alpha).abs() > tol.angular {
                next.differences.push(Difference {
                    row,
                    parameter: Parameter::Alpha,
                    reference: alpha_ref,
                    sheet: s.alpha,
                    aliases: vec![],
                });
            }
        }
        if parallel {
            if next.parallel_run.is_empty() {
                next.parallel_run.push(i);
            }
            next.parallel_run.push(i + 1);
        } else {
            next.parallel_run.clear();
        }
        next.c = AxisMotion::project(&y).0;
        out.push(next);
    }
    out
}

/// The last row when the sheet gives the tool: the row's link and the tool are one rigid body,
/// so only the joint's zero pose (`theta`), its shift along the axis (`d`) and the tool as a
/// whole are compared. With `P = C·A_ref,n(0)·tool_ref` and `Q = A_sheet,n(0)·tool_sheet`,
/// `P·Q⁻¹` must be `Rz(o) Tz(delta)`; whatever else it holds is a tool difference.
fn last_with_tool(
    st: &State,
    i: usize,
    x: &Isometry3<f64>,
    reference: &DhTable,
    std: &DhTable,
    first_free: bool,
    tol: Tolerance,
) -> State {
    let srow = &std.rows[i];
    let p = x * reference.tool;
    let q = srow.transform(Convention::Standard, 0.0) * std.tool;
    let z = p * q.inverse();
    let (motion, tilt, off) = AxisMotion::project(&z);
    let sign = if st.c.flip { -1.0 } else { 1.0 };
    let mut next = st.clone();
    next.signs.push(sign);
    let (offset, delta) = (wrap(motion.phi), motion.t);
    let prismatic = srow.kind == JointKind::Prismatic;
    next.offsets.push(if prismatic { delta } else { offset });
    if sign < 0.0 {
        next.differences.push(Difference {
            row: Some(i),
            parameter: Parameter::Direction,
            reference: -1.0,
            sheet: 1.0,
            aliases: vec![],
        });
    }
    if !first_free {
        if offset.abs() > tol.angular {
            next.differences.push(Difference {
                row: Some(i),
                parameter: Parameter::Theta,
                reference: srow.theta + offset,
                sheet: srow.theta,
                aliases: vec![],
            });
        }
        if delta.abs() > tol.linear {
            next.differences.push(Difference {
                row: Some(i),
                parameter: Parameter::D,
                reference: srow.d + delta,
                sheet: srow.d,
                aliases: st
                    .parallel_run
                    .iter()
                    .copied()
                    .filter(|&r| r != i)
                    .collect(),
            });
        }
    }
    if motion.flip || tilt > tol.angular || off > tol.linear {
        let (dp, _) = pose_error(&p, &(rot_z(offset) * trans_z(delta) * q));
        next.differences.push(Difference {
            row: None,
            parameter: Parameter::Tool,
            reference: dp,
            sheet: 0.0,
            aliases: vec![],
        });
    }
    next.c = motion;
    next
}

/// Helper for tests and callers: a pose from a translation and unit quaternion.
#[allow(dead_code)]
fn pose(t: Vector3<f64>, r: UnitQuaternion<f64>) -> Isometry3<f64> {
    Isometry3::from_parts(Translation3::from(t), r)
}
