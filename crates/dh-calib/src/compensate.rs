//! Compensation: the joint values with which the calibrated robot reaches what the nominal
//! model reaches at the commanded ones (what vendors' absolute-accuracy options do).
//!
//! A robot program's joint values `q_c` were computed with the nominal model: its tool is meant
//! to be at `T* = FK_nominal(q_c)` in the base link frame. The real (calibrated) robot is there
//! at `q*` with `FK_calibrated(q*) = T*`, found by Gauss-Newton on the pose error
//! `e = [p* − p(q); L · log(R* R(q)ᵀ)]` (`L` the robot's characteristic length, so that
//! a radian weighs like a metre at the robot's size) over the measured joint columns
//! ([`JointMap`]: mimic and coupled rows follow theirs), seeded at `q_c`. Each step is the
//! minimum-norm least-squares step of the SVD of the Jacobian (central differences, steps of
//! [`JOINT_STEP`]), halved until the error falls: a redundant arm stays nearest the
//! commanded values, an arm with fewer than six joints gets the least-squares pose. With
//! [`CompensateOptions::orientation`] off only the position is matched.
//!
//! For a tree ([`crate::tree`]) the tool is one branch's tip ([`CompensateOptions::chain`])
//! and only the columns that drive its chain (the trunk's and the branch's joints) move; a
//! trunk joint moved for one branch moves every other branch too.

use nalgebra::{DMatrix, DVector, Isometry3, Vector3};

use crate::joints::JointMap;
use crate::predict::{Calibrated, Frame};

/// Central-difference step of a joint value (radians or metres).
pub const JOINT_STEP: f64 = 1e-7;

/// Smallest damping of a step, relative to the mean squared singular value of the Jacobian:
/// Gauss-Newton away from singularities, a bounded step near them.
const MIN_DAMPING: f64 = 1e-12;

/// Default of [`CompensateOptions::max_change`]: 0.05 rad (2.9°) or 50 mm.
pub const DEFAULT_MAX_CHANGE: f64 = 0.05;

/// Options of [`compensate`].
#[derive(Clone, Debug, PartialEq)]
pub struct CompensateOptions {
    /// Match the orientation as well as the position (with fewer than six joint columns the
    /// pose is matched in the least-squares sense).
    pub orientation: bool,
    /// Stop when the position error is below this (metres) ...
    pub position_tolerance: f64,
    /// ... and the orientation error below this (radians).
    pub orientation_tolerance: f64,
    /// Iterations at most.
    pub max_iterations: usize,
    /// Largest change of any joint column from its commanded value (radians, or metres for a
    /// prismatic joint): a calibration corrects by fractions of a degree, and a pose that needs
    /// more is at or near a singularity, where a large reconfiguration is no correction.
    pub max_change: f64,
    /// The chain whose tool is compensated: a tree's branch (index into its branches, see
    /// [`crate::tree`]), 0 for a serial robot. Only the joints of that chain (the trunk's and
    /// the branch's) move: the other columns do not move its tool, and the minimum-norm step
    /// leaves them at their commanded values.
    pub chain: usize,
}

impl Default for CompensateOptions {
    fn default() -> Self {
        CompensateOptions {
            orientation: true,
            position_tolerance: 1e-9,
            orientation_tolerance: 1e-9,
            max_iterations: 100,
            max_change: DEFAULT_MAX_CHANGE,
            chain: 0,
        }
    }
}

/// One compensated pose.
#[derive(Clone, Debug, PartialEq)]
pub struct Compensated {
    /// Corrected joint columns (radians, metres), in [`JointMap::columns`] order.
    pub q: Vec<f64>,
    /// Distance (metres) between the calibrated tool at `q` and the nominal goal: what
    /// remains.
    pub position_error: f64,
    /// Angle (radians) between their orientations.
    pub orientation_error: f64,
    /// The same two at the commanded values: the error compensation removes.
    pub error_before: (f64, f64),
    /// Iterations taken.
    pub iterations: usize,
    /// Both errors within the tolerances (when orientation is not matched, the position).
    pub converged: bool,
    /// Not converged, and no step reduced the error before the iteration limit: the pose is a
    /// least-squares minimum, the nearest the calibrated robot gets from the commanded values
    /// (the goal lies beyond its reach, such as past a stretched arm's boundary).
    pub stalled: bool,
    /// Rows whose value at `q` is outside the row's joint limits.
    pub beyond_limits: Vec<String>,
    /// Columns whose change reached [`CompensateOptions::max_change`].
    pub at_max_change: Vec<usize>,
}

/// The pose of the calibrated tool of chain `chain` at columns `q`, in the base link frame.
fn pose(calibrated: &Calibrated, map: &JointMap, q: &[f64], chain: usize) -> Isometry3<f64> {
    calibrated.tool_of(&map.rows(q), chain, Frame::Base)
}

/// Position and orientation errors from `at` to `goal`: `p* − p` and the rotation vector of
/// `R* Rᵀ`.
fn errors(goal: &Isometry3<f64>, at: &Isometry3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    (
        goal.translation.vector - at.translation.vector,
        (goal.rotation * at.rotation.inverse()).scaled_axis(),
    )
}

/// The joint columns at which `calibrated` puts the tool of chain
/// [`CompensateOptions::chain`] (a serial robot's tool, or a tree's branch's) at `goal` (base
/// link frame), from `seed` (the commanded columns; see the module docs).
pub fn compensate(
    calibrated: &Calibrated,
    map: &JointMap,
    goal: &Isometry3<f64>,
    seed: &[f64],
    options: &CompensateOptions,
) -> Compensated {
    let weight = calibrated.model().length_scale().max(1e-3);
    let dims = if options.orientation { 6 } else { 3 };
    let residual = |q: &[f64]| -> DVector<f64> {
        let (p, r) = errors(goal, &pose(calibrated, map, q, options.chain));
        let mut e = DVector::zeros(dims);
        e.fixed_rows_mut::<3>(0).copy_from(&p);
        if options.orientation {
            e.fixed_rows_mut::<3>(3).copy_from(&(r * weight));
        }
        e
    };
    let done = |q: &[f64]| {
        let (p, r) = errors(goal, &pose(calibrated, map, q, options.chain));
        p.norm() <= options.position_tolerance
            && (!options.orientation || r.norm() <= options.orientation_tolerance)
    };
    // The columns that drive a row of the chain; the others stay at their commanded values,
    // even where an effect (the trunk's compliance under another branch's weight) lets them
    // move the tool a little.
    let chain_rows = calibrated.tree().chain_rows(options.chain);
    let movable: Vec<bool> = (0..map.columns.len())
        .map(|c| {
            chain_rows
                .iter()
                .any(|&r| r < map.matrix.nrows() && map.matrix[(r, c)] != 0.0)
        })
        .collect();
    let mut q = seed.to_vec();
    let mut e = residual(&q);
    let mut iterations = 0;
    let mut stalled = false;
    let mut mu = MIN_DAMPING;
    while iterations < options.max_iterations && !done(&q) {
        iterations += 1;
        let mut jac = DMatrix::zeros(dims, q.len());
        let mut qp = q.clone();
        for c in (0..q.len()).filter(|&c| movable.get(c).copied().unwrap_or(true)) {
            qp[c] = q[c] + JOINT_STEP;
            let plus = residual(&qp);
            qp[c] = q[c] - JOINT_STEP;
            let minus = residual(&qp);
            qp[c] = q[c];
            // e = goal − f(q): ∂f/∂q = −∂e/∂q.
            jac.set_column(c, &((minus - plus) / (2.0 * JOINT_STEP)));
        }
        // Levenberg-Marquardt in its minimum-norm form: Δ = Jᵀ (J Jᵀ + μ I)⁻¹ e.
        let jjt = &jac * jac.transpose();
        let size = jjt.trace().max(f64::MIN_POSITIVE) / dims as f64;
        let mut improved = false;
        for _ in 0..40 {
            let mut m = jjt.clone();
            for d in 0..dims {
                m[(d, d)] += mu * size;
            }
            let Some(chol) = m.cholesky() else {
                mu *= 10.0;
                continue;
            };
            let step = jac.transpose() * chol.solve(&e);
            // Within the bound on the change from the commanded values.
            let b = options.max_change;
            let trial: Vec<f64> = q
                .iter()
                .zip(step.iter())
                .zip(seed)
                .map(|((a, d), s)| (a + d).clamp(s - b, s + b))
                .collect();
            let et = residual(&trial);
            if et.norm() < e.norm() {
                q = trial;
                e = et;
                mu = (mu / 10.0).max(MIN_DAMPING);
                improved = true;
                break;
            }
            mu *= 10.0;
        }
        if !improved {
            stalled = true;
            break;
        }
    }
    let (p, r) = errors(goal, &pose(calibrated, map, &q, options.chain));
    let (p0, r0) = errors(goal, &pose(calibrated, map, seed, options.chain));
    let rows = map.rows(&q);
    let beyond_limits = calibrated
        .table()
        .rows
        .iter()
        .zip(&rows)
        .enumerate()
        .filter(|(i, _)| chain_rows.contains(i))
        .map(|(_, rv)| rv)
        .filter(|(row, v)| {
            row.limits
                .as_ref()
                .is_some_and(|l| **v < l.lower || **v > l.upper)
        })
        .map(|(row, _)| row.name.clone())
        .collect();
    let converged = p.norm() <= options.position_tolerance
        && (!options.orientation || r.norm() <= options.orientation_tolerance);
    let at_max_change = q
        .iter()
        .zip(seed)
        .enumerate()
        .filter(|(_, (a, s))| (*a - *s).abs() >= options.max_change * (1.0 - 1e-6))
        .map(|(c, _)| c)
        .collect();
    Compensated {
        at_max_change,
        converged,
        stalled: stalled && !converged,
        q,
        position_error: p.norm(),
        orientation_error: r.norm(),
        error_before: (p0.norm(), r0.norm()),
        iterations,
        beyond_limits,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::effects::EffectContext;
    use crate::predict::effects_from_parameters;
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn the_calibrated_robot_reaches_the_nominal_goal() {
        let nominal = crate::test_robots::ur5();
        let mut real = nominal.clone();
        real.rows[1].a += 5e-4;
        real.rows[2].theta += 1e-3;
        real.rows[3].alpha += -7e-4;
        let ctx = EffectContext::serial(&real);
        let effects = effects_from_parameters(&[("gear_ratio:j2".into(), 2e-3)], &ctx).unwrap();
        let calibrated = Calibrated::new(&real, &effects, &Isometry3::identity(), &[]).unwrap();
        let map = JointMap::new(&real, &[]);
        let options = CompensateOptions::default();
        for q in [
            [0.1, -1.2, 1.5, -0.3, 1.2, 0.4],
            [-2.0, -0.5, -1.0, 2.0, -0.8, 3.0],
            [0.0, -FRAC_PI_2, 0.3, 0.0, 0.7, 0.0],
        ] {
            let goal = nominal.fk(&q).unwrap();
            let c = compensate(&calibrated, &map, &goal, &q, &options);
            assert!(c.converged, "{c:?}");
            assert!(c.error_before.0 > 1e-4, "{c:?}");
            let reached = calibrated.tool(&map.rows(&c.q), Frame::Base);
            assert!((reached.translation.vector - goal.translation.vector).norm() < 1e-9);
            assert!(reached.rotation.angle_to(&goal.rotation) < 1e-9);
            assert!(c.beyond_limits.is_empty());
        }
        // Position only: three equations, six joints, the nearest solution.
        let q = [0.1, -1.2, 1.5, -0.3, 1.2, 0.4];
        let goal = nominal.fk(&q).unwrap();
        let only = CompensateOptions {
            orientation: false,
            ..CompensateOptions::default()
        };
        let c = compensate(&calibrated, &map, &goal, &q, &only);
        assert!(c.converged && c.position_error < 1e-9, "{c:?}");
    }
}
