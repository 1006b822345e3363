//! Cross-validation without refits: each fold's held-out distances from one Gauss-Newton step
//! away from the fit of all samples, for the diagnosis's candidate trials.
//!
//! With `r_i` (metres, 3 per point, 6 per pose) and `J_i` the residuals and Jacobian of sample
//! `i` over the free parameters at the fit `x̂` of all calibration samples, the fit without fold
//! `F` (training rows `T`) is, to first order, `x̂ + δ_F` with
//!
//! `(Σ_T J_iᵀ J_i) δ_F = −Σ_T J_iᵀ r_i`,
//!
//! the Gauss-Newton step of the training problem from `x̂`; both sums are the sums over all
//! samples less fold `F`'s, so one pass accumulates every fold. A held-out sample's residual is
//! then `r_i + J_i δ_F`, and its distance the norm of the position part (as
//! [`super::validation::held_out`] measures it). At `x̂` the full problem's gradient is zero and
//! the training problem's small, so the step is short and the linearisation error is of its
//! square: far below the noise for a converged fit of small residuals. The exact refits cost a
//! Levenberg-Marquardt solve per fold; this costs two passes over the samples.
//!
//! Rank: directions of `Σ_T J_iᵀ J_i` whose eigenvalue is below `rank_tolerance²` of the
//! largest (the fit's own singular-value threshold, squared) take no step, as in the fit.

use nalgebra::{DMatrix, DVector};

use super::validation::{held_at, pose_weight, HeldOut};
use super::*;
use crate::fit;

/// Samples per segment of the first pass (whose sums are added segment by segment, so the
/// segments fix the rounding).
const SEGMENT: usize = 4096;

/// Samples per piece of work of the second pass.
const PIECE: usize = 256;

/// One-step held-out distances of every calibration sample under `folds`-fold
/// cross-validation over `prep.groups` (fold of a sample: its group modulo `folds`), in
/// sample order, at the fit `x` of `free` (column scales `scales`).
///
/// # Errors
/// Only a worker thread's failure ([`fit::parallel_map`]).
pub(crate) fn one_step_cross_validation(
    model: &Model,
    prep: &Prepared,
    folds: usize,
    x: &[f64],
    free: &[usize],
    scales: &[f64],
    rank_tolerance: f64,
) -> Result<HeldOut, CalibError> {
    let at = FitPoint {
        x,
        free,
        scales,
        rank_tolerance,
    };
    one_step_distances(model, prep, folds, &at, true)
}

/// The point and columns of a fit, and its rank tolerance.
struct FitPoint<'a> {
    x: &'a [f64],
    free: &'a [usize],
    scales: &'a [f64],
    rank_tolerance: f64,
}

/// [`one_step_cross_validation`]; `rows_once`: the rows at `x` made once when they fit in
/// memory (else made by the model in each pass, as for a larger set: the same values).
fn one_step_distances(
    model: &Model,
    prep: &Prepared,
    folds: usize,
    at: &FitPoint<'_>,
    rows_once: bool,
) -> Result<HeldOut, CalibError> {
    let (x, free, scales, rank_tolerance) = (at.x, at.free, at.scales, at.rank_tolerance);
    let n = free.len();
    let cal = &prep.cal;
    let folds = folds.max(1);
    if n == 0 {
        let all: Vec<usize> = (0..cal.len()).collect();
        return Ok(held_at(model, x, cal, &all));
    }
    let fold_of = |i: usize| prep.groups.get(i).map_or(0, |g| g % folds);
    let segments = cal.len().div_ceil(SEGMENT);
    // Both passes read every sample's rows at `x`: made once when they fit in memory.
    let at_x = rows_once
        .then(|| super::rows_at::RowsAt::new(model, cal, x, free))
        .flatten();
    let rows_of = |i: usize, o: &Observed, res: &mut [f64; 6], jac: &mut [f64]| -> usize {
        let rows = block_rows(o);
        match &at_x {
            Some(at) => {
                let (r, j) = at.sample(i);
                res[..rows].copy_from_slice(r);
                jac[..rows * n].copy_from_slice(j);
            }
            None => model.jacobian(x, o, free, &mut res[..rows], &mut jac[..rows * n]),
        }
        rows
    };
    let column_scales: Vec<f64> = free.iter().map(|&c| scales[c]).collect();
    // Pass 1: per fold, Σ JᵀJ and Σ Jᵀr over its samples (scaled columns). Each element
    // `(a, b)`, `b ≤ a`, of the lower triangle adds `(j_a s_a) j_b s_b` of every row in sample
    // order (skipped when `j_a s_a` is zero), a column at a time; a segment's sums start at
    // zero and are added in segment order. When the rows are made once, each (segment, fold)
    // is a piece of work of its own (the same sums in the same order, on more cores).
    let split = if at_x.is_some() { folds } else { 1 };
    let parts = fit::parallel_map(segments * split, |k| {
        let (s, only) = (k / split, (split > 1).then_some(k % split));
        let mut normal = vec![DMatrix::<f64>::zeros(n, n); if split > 1 { 1 } else { folds }];
        let mut gradient = vec![DVector::<f64>::zeros(n); normal.len()];
        let (mut res, mut jac) = ([0.0; 6], vec![0.0; 6 * n]);
        let mut scaled = vec![0.0; n];
        for (i, o) in cal.iter().enumerate().skip(s * SEGMENT).take(SEGMENT) {
            let f = fold_of(i);
            if only.is_some_and(|g| g != f) {
                continue;
            }
            let rows = rows_of(i, o, &mut res, &mut jac);
            let f = if split > 1 { 0 } else { f };
            let lower = normal[f].as_mut_slice();
            for r in 0..rows {
                let row = &jac[r * n..(r + 1) * n];
                for (ja, (j, s)) in scaled.iter_mut().zip(row.iter().zip(&column_scales)) {
                    *ja = j * s;
                }
                for (g, &ja) in gradient[f].iter_mut().zip(&scaled) {
                    if ja != 0.0 {
                        *g += ja * res[r];
                    }
                }
                for (b, (&jb, &sb)) in row.iter().zip(&column_scales).enumerate() {
                    let column = &mut lower[b * n + b..(b + 1) * n];
                    for (v, &ja) in column.iter_mut().zip(&scaled[b..]) {
                        if ja != 0.0 {
                            *v += ja * jb * sb;
                        }
                    }
                }
            }
        }
        Ok((only, normal, gradient))
    })?;
    let mut normal = vec![DMatrix::<f64>::zeros(n, n); folds];
    let mut gradient = vec![DVector::<f64>::zeros(n); folds];
    for (only, nf, gf) in parts {
        for (k, (a, b)) in nf.iter().zip(&gf).enumerate() {
            let f = only.unwrap_or(k);
            normal[f] += a;
            gradient[f] += b;
        }
    }
    let total_n: DMatrix<f64> = normal.iter().fold(DMatrix::zeros(n, n), |a, b| a + b);
    let total_g: DVector<f64> = gradient.iter().fold(DVector::zeros(n), |a, b| a + b);
    // Each fold's step, in scaled parameters (one fold per piece of work).
    let steps: Vec<DVector<f64>> = fit::parallel_map(folds, |f| {
        let mut m = &total_n - &normal[f];
        symmetrise_lower(&mut m);
        let g = &total_g - &gradient[f];
        Ok(fit::pseudo_inverse(&m, rank_tolerance) * -g)
    })?;
    // Pass 2: each sample's residual after its fold's step, a sample's own computation (so in
    // pieces of any size).
    let pieces = fit::parallel_map(cal.len().div_ceil(PIECE), |s| {
        let (mut res, mut jac) = ([0.0; 6], vec![0.0; 6 * n]);
        let mut out = HeldOut::default();
        for (i, o) in cal.iter().enumerate().skip(s * PIECE).take(PIECE) {
            let rows = rows_of(i, o, &mut res, &mut jac);
            let step = &steps[fold_of(i)];
            let mut moved = [0.0; 6];
            for (r, m) in moved.iter_mut().enumerate().take(rows) {
                let row = &jac[r * n..(r + 1) * n];
                *m = res[r]
                    + (0..n)
                        .map(|a| row[a] * scales[free[a]] * step[a])
                        .sum::<f64>();
            }
            out.push(&moved, rows, pose_weight(o));
        }
        Ok(out)
    })?;
    let mut all = HeldOut::default();
    for piece in pieces {
        all.distances.extend(piece.distances);
        all.turns.extend(piece.turns);
    }
    Ok(all.finish())
}

/// Residual rows of an observation: 3 for a point, 6 for a pose.
fn block_rows(o: &Observed) -> usize {
    o.observation.residual_count()
}

/// Copies the lower triangle (where the passes accumulate) to the upper.
fn symmetrise_lower(m: &mut DMatrix<f64>) {
    let n = m.nrows();
    for a in 0..n {
        for b in 0..a {
            m[(b, a)] = m[(a, b)];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simulate::{simulate, Errors, SimulationOptions};

    /// A UR5 (vendor DH) measured at 120 poses with 20 um noise and millimetre errors: the
    /// one-step folds give the refitted folds' held-out distances to far below the noise.
    #[test]
    fn one_step_folds_give_the_refitted_folds_distances() {
        let table = crate::test_robots::ur5();
        let (data, _) = simulate(
            &table,
            &SimulationOptions {
                poses: 120,
                sigma: 2e-5,
                target_count: 3,
                errors: Errors::Random {
                    length: 1e-3,
                    angle: 2e-3,
                },
                ..SimulationOptions::default()
            },
        )
        .expect("a simulated set");
        let options = CalibrationOptions {
            folds: 10,
            ..CalibrationOptions::default()
        };
        let fitted = super::super::fitted_for_tests(&table, &data, &options);
        let (session, geo) = (fitted.session, fitted.geo);
        assert!(matches!(
            session.validation,
            Validation::CrossValidation { .. }
        ));
        let x = &geo.last.outcome.x;
        let exact = session.held_out_with(x, &geo.free, Folds::Refit).unwrap();
        let approx = session.held_out_with(x, &geo.free, Folds::OneStep).unwrap();
        let (exact, approx) = (exact.distances, approx.distances);
        assert_eq!(exact.len(), approx.len());
        let rms = |d: &[f64]| (d.iter().map(|v| v * v).sum::<f64>() / d.len() as f64).sqrt();
        let worst = exact
            .iter()
            .zip(&approx)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        // Held-out distances are about 35 um (20 um per axis); the step's error is of its
        // square: 1e-10 m measured (2026-11-26).
        assert!(worst < 1e-9, "largest difference {worst} m");
        assert!((rms(&exact) - rms(&approx)).abs() < 1e-6 * rms(&exact));
        assert!(rms(&exact) > 2e-5 && rms(&exact) < 6e-5, "{}", rms(&exact));
        // The rows made once and the sums per (segment, fold) give the distances of the rows
        // made in each pass and the sums per segment, bit for bit.
        let at = FitPoint {
            x,
            free: &geo.free,
            scales: &session.scales,
            rank_tolerance: options.fit.rank_tolerance,
        };
        let by_fold = one_step_distances(&session.model, &session.prep, 10, &at, true).unwrap();
        let by_segment = one_step_distances(&session.model, &session.prep, 10, &at, false).unwrap();
        assert_eq!(by_fold, by_segment);
        assert_eq!(by_fold.distances, approx);
    }
}
