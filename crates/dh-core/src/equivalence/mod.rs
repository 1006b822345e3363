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

mod row;

use std::f64::consts::PI;

use nalgebra::{Isometry3, Vector3};

use crate::pose::{pose_error, rot_x, rot_z, trans_z};
use crate::table::{Convention, DhTable, JointKind};
use crate::Tolerance;
use row::{residual_frame, solve_row, wrap, AxisMotion, SheetRow};

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
    /// The joint type: `urdf` and `sheet` are 0 for revolute, 1 for prismatic
    /// ([`kind_code`]).
    Type,
    /// The sheet taken literally (same joint values, free base and tool fitted) puts the tip
    /// farther from the URDF's than the linear tolerance although no parameter was found to
    /// differ: `urdf` is the largest position deviation (metres). See [`crate::check`].
    FkPosition,
    /// As [`Parameter::FkPosition`] for the orientation (radians).
    FkOrientation,
}

/// The number a [`Parameter::Type`] difference carries for a joint kind: 0 revolute,
/// 1 prismatic.
pub fn kind_code(kind: JointKind) -> f64 {
    match kind {
        JointKind::Revolute => 0.0,
        JointKind::Prismatic => 1.0,
    }
}

impl Parameter {
    /// The name used in reports:
    /// `a|alpha|d|theta|direction|base|tool|type|fk_position|fk_orientation`.
    pub fn as_str(self) -> &'static str {
        match self {
            Parameter::A => "a",
            Parameter::Alpha => "alpha",
            Parameter::D => "d",
            Parameter::Theta => "theta",
            Parameter::Direction => "direction",
            Parameter::Base => "base",
            Parameter::Tool => "tool",
            Parameter::Type => "type",
            Parameter::FkPosition => "fk_position",
            Parameter::FkOrientation => "fk_orientation",
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
            free_run: freedom.base_free,
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
    let mut found = match beam.into_iter().next() {
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
    };
    // The walk compares the zero pose only; a joint that slides where the other turns moves
    // differently however its row is placed.
    for (i, (r, s)) in reference.rows.iter().zip(&sheet.rows).enumerate() {
        if r.kind != s.kind {
            found.differences.push(Difference {
                row: Some(i),
                parameter: Parameter::Type,
                reference: kind_code(r.kind),
                sheet: kind_code(s.kind),
                aliases: vec![],
            });
        }
    }
    found
}

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
    /// Still on the run of parallel axes that starts at joint 1 under a free base: a free base
    /// may slide along that run's common direction, so no `d` on it is observable, up to and
    /// including the row whose common normal ends the run.
    free_run: bool,
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
    let d_free = first_free || st.free_run;
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
            if delta.abs() > tol.linear && !d_free {
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
        next.free_run = st.free_run && parallel;
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
        if delta.abs() > tol.linear && !st.free_run {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::table::DhRow;

    /// Axes 1, 2 antiparallel, 2 and 3 coincident, 4 and 5 antiparallel (the repro `antico`
    /// shape), with a base and tool far from identity.
    fn antico() -> DhTable {
        DhTable {
            convention: Convention::Standard,
            base: Isometry3::new(Vector3::new(0.2, -0.1, 0.4), Vector3::new(2.0, 0.9, -1.3)),
            tool: Isometry3::new(Vector3::new(0.01, 0.02, 0.15), Vector3::new(-0.3, 1.4, 0.2)),
            rows: vec![
                DhRow::revolute("j1", 0.22, PI, 0.11, 0.0),
                DhRow::revolute("j2", 0.0, 0.0, 0.15, 0.6),
                DhRow::revolute("j3", 0.28, PI / 2.0, 0.0, 0.0),
                DhRow::revolute("j4", 0.13, -PI, 0.02, PI / 2.0),
                DhRow::revolute("j5", 0.0, PI / 2.0, 0.24, 0.0),
            ],
        }
    }

    fn tol() -> Tolerance {
        Tolerance::new(1e-4, 2e-4).unwrap()
    }

    fn named(e: &Equivalence) -> Vec<(Option<usize>, Parameter)> {
        e.differences.iter().map(|d| (d.row, d.parameter)).collect()
    }

    /// Under a free base the run of parallel axes that starts at joint 1 has no observable `d`,
    /// including the row whose common normal ends it (the sheet's `d` there was reported).
    #[test]
    fn a_free_base_frees_the_d_of_the_leading_parallel_run() {
        let truth = antico();
        let mut sheet = truth.clone();
        sheet.base = Isometry3::identity();
        sheet.tool = Isometry3::identity();
        let free = Freedom {
            base_free: true,
            tool_free: true,
        };
        assert_eq!(named(&compare_tables(&truth, &sheet, free, tol())), []);
        // Another split of the run's d, and a shift the free base absorbs: still the same.
        sheet.rows[0].d += 0.05;
        sheet.rows[1].d -= 0.03;
        sheet.rows[2].d += 0.2;
        assert_eq!(named(&compare_tables(&truth, &sheet, free, tol())), []);
        // Joints 4 and 5 are a run under a free tool: their d are free as well.
        sheet.rows[3].d += 0.01;
        sheet.rows[4].d -= 0.07;
        assert_eq!(named(&compare_tables(&truth, &sheet, free, tol())), []);
        // Where joint 4's common normals point is observable.
        sheet.rows[3].theta += 0.01;
        assert_eq!(
            named(&compare_tables(&truth, &sheet, free, tol())),
            [(Some(3), Parameter::Theta)]
        );
    }

    /// All axes parallel (a SCARA with its quill), base free, tool given: the free base slides
    /// along the whole run, so no `d` is observable; `a` still is.
    #[test]
    fn a_free_base_frees_every_d_of_an_all_parallel_chain() {
        let truth = DhTable {
            convention: Convention::Standard,
            base: Isometry3::new(Vector3::new(0.1, 0.2, 0.3), Vector3::new(0.3, -0.2, 0.1)),
            tool: Isometry3::new(Vector3::new(0.0, 0.01, 0.05), Vector3::new(0.0, 0.0, 0.4)),
            rows: vec![
                DhRow::revolute("j1", 0.325, 0.0, 0.387, 0.0),
                DhRow::revolute("j2", 0.275, PI, 0.0, 0.0),
                DhRow::prismatic("j3", 0.0, 0.0, 0.0, 0.0),
                DhRow::revolute("j4", 0.0, 0.0, 0.0, 0.0),
            ],
        };
        let free = Freedom {
            base_free: true,
            tool_free: false,
        };
        let mut sheet = truth.clone();
        sheet.base = Isometry3::identity();
        sheet.rows[0].d = 0.0;
        sheet.rows[1].d = 0.1;
        sheet.rows[3].d = -0.05;
        assert_eq!(named(&compare_tables(&truth, &sheet, free, tol())), []);
        sheet.rows[1].a += 0.001;
        assert_eq!(
            named(&compare_tables(&truth, &sheet, free, tol())),
            [(Some(1), Parameter::A)]
        );
    }

    /// With the base given only the signed sum of `d` along the run is observable: moving d
    /// between antiparallel joints 1 and 2 takes the same sign on both; a wrong sum is named
    /// with the run's other joints as aliases.
    #[test]
    fn a_given_base_compares_the_signed_sum_along_the_run() {
        let truth = antico();
        let fixed = Freedom {
            base_free: false,
            tool_free: false,
        };
        let mut same = truth.clone();
        same.rows[0].d += 0.05;
        same.rows[1].d += 0.05;
        same.rows[2].d -= 0.02;
        same.rows[1].d += 0.02;
        assert_eq!(named(&compare_tables(&truth, &same, fixed, tol())), []);
        let mut wrong = truth.clone();
        wrong.rows[0].d += 0.05;
        wrong.rows[1].d -= 0.05;
        let e = compare_tables(&truth, &wrong, fixed, tol());
        assert_eq!(named(&e), [(Some(2), Parameter::D)]);
        assert_eq!(e.differences[0].aliases, [0, 1]);
        assert!((e.differences[0].reference - e.differences[0].sheet - 0.1).abs() < 1e-9);
    }

    /// A joint that slides where the other turns is named, whatever the zero pose says.
    #[test]
    fn a_different_joint_type_is_named() {
        let truth = antico();
        let mut sheet = truth.clone();
        sheet.rows[2].kind = JointKind::Prismatic;
        let free = Freedom {
            base_free: true,
            tool_free: true,
        };
        let e = compare_tables(&truth, &sheet, free, tol());
        assert_eq!(named(&e), [(Some(2), Parameter::Type)]);
        assert_eq!(
            (e.differences[0].reference, e.differences[0].sheet),
            (0.0, 1.0)
        );
    }
}
