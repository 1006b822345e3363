//! The linearised cross-validation RMS of a candidate (module docs, step 2) from each fold's
//! normal equations, built once per round: for fold `F` with training rows `T`, the fit of
//! `r_T + J_T δ_F + C_T δ_C` (scaled columns; `J` the estimated parameters', `C` the
//! candidate's) is, with `A = J_TᵀJ_T`, `B = J_TᵀC_T`, `D = C_TᵀC_T`, `a = J_Tᵀr_T`,
//! `b = C_Tᵀr_T` and the Schur complement `S = D − BᵀA⁺B`:
//!
//! `δ_C = −S⁺ (b − BᵀA⁺a)`, `δ_F = −A⁺ (a + B δ_C)`,
//!
//! and each held-out row is predicted as `r + J δ_F + C δ_C`. Every training sum is the sum over
//! all rows less the fold's own, and `A⁺` is computed once per fold and round, so a candidate
//! costs one pass over its columns instead of a QR projection per fold. `A⁺` and `S⁺` leave out
//! eigen-directions below 1e-12 of the largest (singular values below 1e-6, the fit's rank
//! tolerance).

use nalgebra::{DMatrix, DVector};

use crate::fit::pseudo_inverse;

/// A fold's own products with a candidate's columns `C_F`: `J_FᵀC_F`, `C_FᵀC_F`, `C_Fᵀr_F`,
/// and `C_F` itself.
type OwnProducts = (DMatrix<f64>, DMatrix<f64>, DVector<f64>, DMatrix<f64>);

/// Singular values below this fraction of the largest are left out (the fit's default rank
/// tolerance, [`crate::fit::FitOptions::rank_tolerance`]).
const RANK_TOLERANCE: f64 = 1e-6;

/// One fold's rows and its training normal equations of the estimated parameters.
struct Fold {
    /// The fold's residual rows (indices into the stacked residuals).
    rows: Vec<usize>,
    /// First row of each of its samples (indices into the stacked residuals).
    samples: Vec<usize>,
    /// Its rows of `J`.
    j: DMatrix<f64>,
    /// Its rows of `r`.
    r: DVector<f64>,
    /// `A⁺` of its training rows.
    a_inv: DMatrix<f64>,
    /// `a` of its training rows.
    a: DVector<f64>,
}

/// Per-fold normal equations of the estimated parameters (see the module docs).
pub(super) struct FoldNormals {
    folds: Vec<Fold>,
}

impl FoldNormals {
    /// Folds of `jf` (scaled Jacobian of the estimated parameters) and `r` (residuals):
    /// `folds[f]` lists the first row of each of fold `f`'s samples and `sizes` gives every
    /// sample's row count by its first row.
    pub(super) fn new(
        jf: &DMatrix<f64>,
        r: &DVector<f64>,
        folds: &[Vec<usize>],
        size_at: impl Fn(usize) -> usize,
    ) -> Self {
        let p = jf.ncols();
        let mut built: Vec<Fold> = folds
            .iter()
            .map(|samples| {
                let rows: Vec<usize> = samples.iter().flat_map(|&s| s..s + size_at(s)).collect();
                let j = jf.select_rows(rows.iter());
                let rr = r.select_rows(rows.iter());
                Fold {
                    rows,
                    samples: samples.clone(),
                    j,
                    r: rr,
                    a_inv: DMatrix::zeros(p, p),
                    a: DVector::zeros(p),
                }
            })
            .collect();
        let own: Vec<(DMatrix<f64>, DVector<f64>)> = built
            .iter()
            .map(|f| (f.j.tr_mul(&f.j), f.j.tr_mul(&f.r)))
            .collect();
        let total_a = own.iter().fold(DMatrix::zeros(p, p), |acc, (n, _)| acc + n);
        let total_g = own.iter().fold(DVector::zeros(p), |acc, (_, g)| acc + g);
        // Each fold's pseudo-inverse on its own, on the machine's cores.
        let inverse = |k: usize| pseudo_inverse(&(&total_a - &own[k].0), RANK_TOLERANCE);
        let inverses = dh_core::parallel::map(own.len(), inverse)
            .unwrap_or_else(|| (0..own.len()).map(inverse).collect());
        for ((f, (_, g)), a_inv) in built.iter_mut().zip(&own).zip(inverses) {
            f.a_inv = a_inv;
            f.a = &total_g - g;
        }
        Self { folds: built }
    }

    /// The held-out distances (norms of the first three rows of each sample) of the fit with
    /// the candidate's columns `c` (all rows; no columns: the estimated parameters alone), in
    /// fold order; `size_at` as in [`FoldNormals::new`].
    pub(super) fn distances(&self, c: &DMatrix<f64>, size_at: impl Fn(usize) -> usize) -> Vec<f64> {
        let k = c.ncols();
        let p = self.folds.first().map_or(0, |f| f.j.ncols());
        // Each fold's own sums of the candidate's products, then the totals.
        let own: Vec<OwnProducts> = self
            .folds
            .iter()
            .map(|f| {
                let cf = c.select_rows(f.rows.iter());
                let b = f.j.tr_mul(&cf);
                let d = cf.tr_mul(&cf);
                let bv = cf.tr_mul(&f.r);
                (b, d, bv, cf)
            })
            .collect();
        let total_b = own.iter().fold(DMatrix::zeros(p, k), |acc, o| acc + &o.0);
        let total_d = own.iter().fold(DMatrix::zeros(k, k), |acc, o| acc + &o.1);
        let total_bv = own.iter().fold(DVector::zeros(k), |acc, o| acc + &o.2);
        let mut out = Vec::new();
        for (f, (b_own, d_own, bv_own, cf)) in self.folds.iter().zip(&own) {
            let (df, dc) = if k == 0 {
                (-(&f.a_inv * &f.a), DVector::zeros(0))
            } else {
                let b = &total_b - b_own;
                let d = &total_d - d_own;
                let bv = &total_bv - bv_own;
                let x = &f.a_inv * &b;
                let s = &d - b.tr_mul(&x);
                let dc = -(pseudo_inverse(&s, RANK_TOLERANCE) * (&bv - x.tr_mul(&f.a)));
                let df = -(&f.a_inv * (&f.a + &b * &dc));
                (df, dc)
            };
            let mut pred = &f.r + &f.j * &df;
            if k > 0 {
                pred += cf * &dc;
            }
            let mut at = 0;
            for &s in &f.samples {
                let n = size_at(s);
                let v = pred.rows(at, n.min(3));
                out.push(v.norm());
                at += n;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::super::scoring::Projector;
    use super::*;

    /// The normal-equation folds give the QR projections' held-out distances.
    #[test]
    fn fold_normals_match_the_fold_projections() {
        // 40 samples of 3 rows, 5 parameters, a 2-column candidate, 4 folds; a fixed
        // pseudo-random fill.
        let (samples, p, k, folds) = (40, 5, 2, 4);
        let m = samples * 3;
        let mut state = 12345u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let jf = DMatrix::from_fn(m, p, |_, _| next());
        let c = DMatrix::from_fn(m, k, |_, _| next());
        let r = DVector::from_fn(m, |_, _| next());
        let fold_samples: Vec<Vec<usize>> = (0..folds)
            .map(|f| {
                (0..samples)
                    .filter(|s| s % folds == f)
                    .map(|s| 3 * s)
                    .collect()
            })
            .collect();
        let normals = FoldNormals::new(&jf, &r, &fold_samples, |_| 3);
        for cand in [c.clone(), DMatrix::zeros(m, 0)] {
            let fast = normals.distances(&cand, |_| 3);
            let mut slow = Vec::new();
            for samples_f in &fold_samples {
                let train: Vec<usize> = (0..samples)
                    .filter(|s| !samples_f.contains(&(3 * s)))
                    .flat_map(|s| 3 * s..3 * s + 3)
                    .collect();
                let proj = Projector::new(&jf, &r, train);
                let (df, dc, _, _) = proj.solve(&cand);
                for &s in samples_f {
                    let mut v = r.rows(s, 3).into_owned() + jf.rows(s, 3) * &df;
                    if cand.ncols() > 0 {
                        v += cand.rows(s, 3) * &dc;
                    }
                    slow.push(v.norm());
                }
            }
            assert_eq!(fast.len(), slow.len());
            for (a, b) in fast.iter().zip(&slow) {
                assert!((a - b).abs() < 1e-9 * b.max(1.0), "{a} against {b}");
            }
        }
    }
}
