//! One row of the equivalence walk: the motion along the current joint axis that carries the
//! reference's frame onto the sheet's, and the rotations about that axis for which the sheet's
//! row holds (see the parent module for the frames).

use std::f64::consts::PI;

use nalgebra::{Isometry3, Matrix3};

use crate::pose::{rot_x, rot_z, trans_z};
use crate::Tolerance;

/// A motion along the z axis: `Tz(t) Rz(phi) Rx(pi)^flip`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct AxisMotion {
    pub(super) t: f64,
    pub(super) phi: f64,
    pub(super) flip: bool,
}

impl AxisMotion {
    pub(super) fn iso(&self) -> Isometry3<f64> {
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
    pub(super) fn project(y: &Isometry3<f64>) -> (AxisMotion, f64, f64) {
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
pub(super) struct SheetRow {
    pub(super) theta: f64,
    pub(super) d: f64,
    pub(super) a: f64,
    pub(super) alpha: f64,
}

/// What one row's solve found.
#[derive(Clone, Copy, Debug)]
pub(super) struct RowFit {
    pub(super) psi: f64,
    pub(super) cost: f64,
}

pub(super) fn wrap(a: f64) -> f64 {
    let w = (a + PI).rem_euclid(2.0 * PI) - PI;
    if w <= -PI + 1e-15 {
        PI
    } else {
        w
    }
}

/// `M⁻¹ Tz(−delta) Rz(−psi) X` with `M = Tz(d) Tx(a) Rx(alpha)`, and the `delta` that puts its
/// origin on its z axis (when the axes are not parallel; else 0).
pub(super) fn residual_frame(
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
pub(super) fn solve_row(
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

/// Descriptions of one row kept when none holds.
const MAX_CANDIDATES: usize = 4;
