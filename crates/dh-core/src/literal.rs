//! A sheet taken literally: the same joint values drive the sheet's table and the robot, and a
//! base or tool the sheet leaves free is fitted to the robot's own forward kinematics. The
//! largest tip deviation that remains is the number a CI job can bound.
//!
//! The fit starts where it can reach the right answer: a free base from the closed-form
//! registration of the two descriptions' joint axes at the zero pose ([`crate::registration`]),
//! a free tool from the zero pose itself, then Levenberg–Marquardt on the base and tool
//! (position residuals in metres, orientation residuals scaled by the chain's size) from every
//! candidate start, keeping the best.

use nalgebra::{DMatrix, DVector, Isometry3, Vector3};

use crate::equivalence::Freedom;
use crate::registration::{axis_lines, register_axes};
use crate::table::DhTable;
use crate::verify::{compare, Deviation, JointSampler};
use crate::{CoreError, Tolerance};

/// Joint-value samples the free base and tool are fitted to.
const FIT_SAMPLES: usize = 60;
/// Joint-value samples of the reported deviation (after the fit, a different seed).
pub const LITERAL_SAMPLES: usize = 500;
/// Seeds of the fit's and the report's samples.
const FIT_SEED: u64 = 17;
const REPORT_SEED: u64 = 29;
/// Levenberg–Marquardt iterations per start.
const ITERATIONS: usize = 100;
/// Finite-difference step of the fit's Jacobian (metres for the translation part, radians for
/// the rotation part): far above rounding of poses of a few metres, far below any residual the
/// fit must see.
const STEP: f64 = 1e-7;
/// The fit stops when an accepted step lowers the squared residual by less than this share.
const CONVERGED: f64 = 1e-14;

/// The result of [`fit_literal`].
#[derive(Clone, Debug, PartialEq)]
pub struct LiteralFit {
    /// DH frame 0 in the robot's base link (the sheet's own when it gives one).
    pub base: Isometry3<f64>,
    /// The tip link in the last DH frame (the sheet's own when it gives one).
    pub tool: Isometry3<f64>,
    /// Largest deviations of the sheet so completed from the robot over
    /// [`LITERAL_SAMPLES`] joint values.
    pub deviation: Deviation,
}

/// Fits the free base and tool of `sheet` (as `freedom` says) so that `sheet` at joint values
/// `q` gives `oracle(q)`, the tip link's pose in the robot's base link, and measures what is
/// left. `reference` is a table known to be exact for the robot (extracted from its URDF): its
/// joint axes start the fit and its limits and mimic couplings draw the joint values.
///
/// # Errors
/// [`CoreError::JointCount`] when the two tables have different numbers of rows.
pub fn fit_literal<F>(
    sheet: &DhTable,
    reference: &DhTable,
    freedom: Freedom,
    mut oracle: F,
    tol: Tolerance,
) -> Result<LiteralFit, CoreError>
where
    F: FnMut(&[f64]) -> Isometry3<f64>,
{
    if sheet.rows.len() != reference.rows.len() {
        return Err(CoreError::JointCount {
            expected: reference.rows.len(),
            found: sheet.rows.len(),
        });
    }
    let mut table = sheet.clone();
    for (row, r) in table.rows.iter_mut().zip(&reference.rows) {
        row.limits = r.limits;
        row.mimic = r.mimic.clone();
    }
    let mut bare = table.clone();
    bare.base = Isometry3::identity();
    bare.tool = Isometry3::identity();
    let mut sampler = JointSampler::new(&table.rows, table.size(), FIT_SEED);
    let mut q = Vec::new();
    let mut samples = Vec::with_capacity(FIT_SAMPLES);
    let prepared = bare.prepare();
    for _ in 0..FIT_SAMPLES {
        sampler.next_into(&mut q);
        samples.push(Sample {
            chain: prepared.fk(&q)?,
            tip: oracle(&q),
        });
    }
    // The first sample is the zero pose (mimic offsets applied).
    sampler = JointSampler::new(&table.rows, table.size(), FIT_SEED);
    sampler.next_into(&mut q);
    let zero = &samples[0];
    let tool_at_zero = |base: &Isometry3<f64>| (base * zero.chain).inverse() * zero.tip;
    let mut starts: Vec<(Isometry3<f64>, Isometry3<f64>)> = Vec::new();
    if freedom.base_free {
        let lines = register_axes(&axis_lines(&bare, &q)?, &axis_lines(reference, &q)?, tol);
        for base in lines {
            let tool = if freedom.tool_free {
                tool_at_zero(&base)
            } else {
                table.tool
            };
            starts.push((base, tool));
        }
        // The zero poses made to coincide with the sheet's tool (given, or the identity when
        // free): exact for a right sheet with a given tool, and for a wrong sheet one more
        // basin the best fit may lie in.
        starts.push((zero.tip * (zero.chain * table.tool).inverse(), table.tool));
    } else if freedom.tool_free {
        starts.push((table.base, tool_at_zero(&table.base)));
    } else {
        starts.push((table.base, table.tool));
    }
    let scale = table.size().max(reference.size());
    let problem = Problem {
        samples: &samples,
        scale,
        freedom,
    };
    let mut best: Option<(f64, Isometry3<f64>, Isometry3<f64>)> = None;
    for (base, tool) in starts {
        let (cost, base, tool) = problem.refine(base, tool);
        if best.as_ref().is_none_or(|b| cost < b.0) {
            best = Some((cost, base, tool));
        }
    }
    let (base, tool) = best.map_or((table.base, table.tool), |b| (b.1, b.2));
    table.base = base;
    table.tool = tool;
    let deviation = compare(&table, oracle, LITERAL_SAMPLES, REPORT_SEED)?;
    Ok(LiteralFit {
        base,
        tool,
        deviation,
    })
}

/// One joint-value sample: the sheet's chain without base and tool, and the robot's tip.
struct Sample {
    chain: Isometry3<f64>,
    tip: Isometry3<f64>,
}

/// The least-squares problem of the free base and tool.
struct Problem<'a> {
    samples: &'a [Sample],
    /// Metres per radian of orientation residual.
    scale: f64,
    freedom: Freedom,
}

impl Problem<'_> {
    /// Unknowns: 6 per free transform (translation, rotation vector).
    fn unknowns(&self) -> usize {
        6 * (usize::from(self.freedom.base_free) + usize::from(self.freedom.tool_free))
    }

    /// `base · Exp(x_base)` and `Exp(x_tool) · tool` for a step `x`.
    fn apply(
        &self,
        base: &Isometry3<f64>,
        tool: &Isometry3<f64>,
        x: &DVector<f64>,
    ) -> (Isometry3<f64>, Isometry3<f64>) {
        let twist = |k: usize| {
            Isometry3::new(
                Vector3::new(x[k], x[k + 1], x[k + 2]),
                Vector3::new(x[k + 3], x[k + 4], x[k + 5]),
            )
        };
        let mut k = 0;
        let mut b = *base;
        let mut t = *tool;
        if self.freedom.base_free {
            b *= twist(k);
            k += 6;
        }
        if self.freedom.tool_free {
            t = twist(k) * t;
        }
        (b, t)
    }

    /// Residuals (metres): position and scaled rotation vector per sample.
    fn residuals(&self, base: &Isometry3<f64>, tool: &Isometry3<f64>) -> DVector<f64> {
        let mut r = DVector::zeros(6 * self.samples.len());
        for (k, s) in self.samples.iter().enumerate() {
            let p = base * s.chain * tool;
            let dp = p.translation.vector - s.tip.translation.vector;
            let dr = (s.tip.rotation.inverse() * p.rotation).scaled_axis() * self.scale;
            for j in 0..3 {
                r[6 * k + j] = dp[j];
                r[6 * k + 3 + j] = dr[j];
            }
        }
        r
    }

    /// Levenberg–Marquardt from `(base, tool)`: the squared residual and the pair reached.
    fn refine(
        &self,
        base: Isometry3<f64>,
        tool: Isometry3<f64>,
    ) -> (f64, Isometry3<f64>, Isometry3<f64>) {
        let (mut base, mut tool) = (base, tool);
        let mut r = self.residuals(&base, &tool);
        let mut cost = r.norm_squared();
        let m = self.unknowns();
        if m == 0 || !cost.is_finite() {
            return (cost, base, tool);
        }
        let mut lambda = 1e-3;
        for _ in 0..ITERATIONS {
            let mut jac = DMatrix::zeros(r.len(), m);
            for c in 0..m {
                let mut x = DVector::zeros(m);
                x[c] = STEP;
                let (b, t) = self.apply(&base, &tool, &x);
                jac.set_column(c, &((self.residuals(&b, &t) - &r) / STEP));
            }
            let jtj = jac.transpose() * &jac;
            let g = jac.transpose() * &r;
            let mut improved = false;
            for _ in 0..10 {
                let mut a = jtj.clone();
                for c in 0..m {
                    a[(c, c)] += lambda * jtj[(c, c)].max(f64::MIN_POSITIVE);
                }
                let Some(step) = a.cholesky().map(|ch| -ch.solve(&g)) else {
                    lambda *= 10.0;
                    continue;
                };
                let (b, t) = self.apply(&base, &tool, &step);
                let rn = self.residuals(&b, &t);
                let cn = rn.norm_squared();
                if cn < cost {
                    let gain = (cost - cn) / cost.max(f64::MIN_POSITIVE);
                    (base, tool, r, cost) = (b, t, rn, cn);
                    lambda = (lambda / 10.0).max(1e-12);
                    improved = gain > CONVERGED;
                    break;
                }
                lambda *= 10.0;
            }
            if !improved {
                break;
            }
        }
        (cost, base, tool)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::table::{Convention, DhRow};

    fn arm() -> DhTable {
        let pi = std::f64::consts::PI;
        DhTable {
            convention: Convention::Standard,
            base: Isometry3::new(Vector3::new(0.2, -0.1, 0.4), Vector3::new(2.0, 0.9, -1.3)),
            tool: Isometry3::new(Vector3::new(0.01, 0.02, 0.15), Vector3::new(-0.3, 1.4, 0.2)),
            rows: vec![
                DhRow::revolute("j1", 0.22, pi, 0.11, 0.0),
                DhRow::revolute("j2", 0.0, 0.0, 0.15, 0.6),
                DhRow::revolute("j3", 0.28, pi / 2.0, 0.0, 0.0),
                DhRow::revolute("j4", 0.13, -pi, 0.02, pi / 2.0),
                DhRow::revolute("j5", 0.0, pi / 2.0, 0.24, 0.0),
            ],
        }
    }

    /// Free base and tool far from identity, antiparallel and coincident axes: the fit finds
    /// them (a start at the identity would not).
    #[test]
    fn free_base_and_tool_are_found() {
        let truth = arm();
        let mut sheet = truth.clone();
        sheet.base = Isometry3::identity();
        sheet.tool = Isometry3::identity();
        for (base_free, tool_free) in [(true, true), (true, false), (false, true)] {
            let mut s = sheet.clone();
            if !base_free {
                s.base = truth.base;
            }
            if !tool_free {
                s.tool = truth.tool;
            }
            let fit = fit_literal(
                &s,
                &truth,
                Freedom {
                    base_free,
                    tool_free,
                },
                |q| truth.fk(q).unwrap(),
                Tolerance::default(),
            )
            .unwrap();
            assert!(
                fit.deviation.max_position_error < 1e-9,
                "{base_free} {tool_free}: {:?}",
                fit.deviation
            );
            assert!(
                fit.deviation.max_orientation_error < 1e-9,
                "{:?}",
                fit.deviation
            );
        }
    }

    /// A wrong sheet stays wrong: a 5 mm longer link cannot be fitted away.
    #[test]
    fn a_wrong_link_is_not_fitted_away() {
        let truth = arm();
        let mut sheet = truth.clone();
        sheet.base = Isometry3::identity();
        sheet.tool = Isometry3::identity();
        sheet.rows[2].a += 0.005;
        let fit = fit_literal(
            &sheet,
            &truth,
            Freedom {
                base_free: true,
                tool_free: true,
            },
            |q| truth.fk(q).unwrap(),
            Tolerance::default(),
        )
        .unwrap();
        assert!(
            fit.deviation.max_position_error > 1e-3,
            "{:?}",
            fit.deviation
        );
    }
}
