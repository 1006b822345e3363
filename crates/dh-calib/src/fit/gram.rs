//! The factor of a large problem from the Gram matrix of its scaled Jacobian: `[A | r]ᵀ[A | r]`
//! summed over the rows ([`Gram`]), then `R` from the Cholesky factor of `AᵀA` and
//! `Qᵀr = R⁻ᵀ·Aᵀr` ([`factor_of`]).
//!
//! Folding a row into the Gram matrix takes `p²/2` multiply-adds over contiguous memory; folding
//! it into the triangular factor by Householder reflections ([`super::Tsqr`]) takes `2p²`, and
//! on millions of samples that is most of a fit's time. The price is accuracy: the Cholesky
//! factor of `AᵀA` is exact to about `ε·κ(A)²` relative in the weakest direction (Golub & Van
//! Loan, *Matrix Computations*, 4th ed., §5.3.7, "normal equations versus QR"), against `ε·κ(A)`
//! for the QR. So the Gram matrix is used only when `κ(A) ≤` [`GRAM_MAX_CONDITION`] (then
//! `ε·κ² ≤ 2e-8`); a worse conditioned problem, or one whose `AᵀA` is not positive definite,
//! is factored by the QR.

use nalgebra::{DMatrix, DVector};

use super::factor::{accumulate, check_columns, Factor, RowSink};
use super::{CalibError, Problem};

/// Largest condition number of the column-scaled Jacobian whose factor is taken from its Gram
/// matrix: `ε·κ²` is then at most 2.2e-8, the relative accuracy of its weakest direction.
pub const GRAM_MAX_CONDITION: f64 = 1e4;

/// Rows folded into the Gram matrix together (each element read and written once per group).
const STAGE_ROWS: usize = 4;

/// The lower triangle of `[A | r]ᵀ[A | r]` over the rows pushed so far.
#[derive(Clone, Debug)]
pub(super) struct Gram {
    cols: usize,
    /// Element `(i, j)`, `j ≤ i`, at `i · cols + j`.
    g: Vec<f64>,
    /// Up to [`STAGE_ROWS`] rows not folded yet, row after row.
    stage: Vec<f64>,
    staged: usize,
}

impl Gram {
    /// Nothing pushed yet, for rows of `cols` values (the scaled Jacobian's and the residual).
    pub(super) fn new(cols: usize) -> Self {
        Gram {
            cols,
            g: vec![0.0; cols * cols],
            stage: vec![0.0; STAGE_ROWS * cols],
            staged: 0,
        }
    }

    /// Folds the staged rows into the triangle.
    fn fold(&mut self) {
        let c = self.cols;
        if self.staged == STAGE_ROWS {
            let (s0, rest) = self.stage.split_at(c);
            let (s1, rest) = rest.split_at(c);
            let (s2, s3) = rest.split_at(c);
            for i in 0..c {
                let (a0, a1, a2, a3) = (s0[i], s1[i], s2[i], s3[i]);
                let gi = &mut self.g[i * c..i * c + i + 1];
                let rows = gi.iter_mut().zip(s0).zip(s1).zip(s2).zip(s3);
                for ((((g, b0), b1), b2), b3) in rows {
                    *g += a0 * b0 + a1 * b1 + a2 * b2 + a3 * b3;
                }
            }
        } else {
            for row in self.stage.chunks_exact(c).take(self.staged) {
                for (i, &a) in row.iter().enumerate() {
                    for (g, b) in self.g[i * c..i * c + i + 1].iter_mut().zip(row) {
                        *g += a * b;
                    }
                }
            }
        }
        self.staged = 0;
    }

    /// The triangle of every row pushed to `self`, then to `other`.
    pub(super) fn add(&mut self, mut other: Gram) {
        self.fold();
        other.fold();
        for (g, o) in self.g.iter_mut().zip(&other.g) {
            *g += o;
        }
    }
}

impl RowSink for Gram {
    fn push_scaled(&mut self, a: &[f64], s: &[f64], last: f64) -> bool {
        let c = self.cols;
        let row = &mut self.stage[self.staged * c..(self.staged + 1) * c];
        let mut finite = last.is_finite();
        for ((v, a), s) in row.iter_mut().zip(a).zip(s).take(c - 1) {
            *v = a * s;
            finite &= v.is_finite();
        }
        row[c - 1] = last;
        self.staged += 1;
        if self.staged == STAGE_ROWS {
            self.fold();
        }
        finite
    }
}

/// The Gram matrix of the scaled Jacobian and residuals of one part of a problem's samples at one
/// point, with the residuals' sum of squares and number: the parts of a problem are factored once
/// each, and the factor of any union of them is that of their sum ([`GramSum::factor`]), as
/// cross-validation's folds share the samples they are trained on.
#[derive(Clone, Debug)]
pub(crate) struct GramSum {
    gram: Gram,
    ssr: f64,
    rows: usize,
}

impl GramSum {
    /// No rows yet, of `cols` values each (the scaled Jacobian's and the residual).
    pub(super) fn empty(cols: usize) -> GramSum {
        GramSum {
            gram: Gram::new(cols),
            ssr: 0.0,
            rows: 0,
        }
    }

    /// The sum over every block of `problem` at `x`, for the columns `columns` scaled by
    /// `scales`, in block order on this thread (the same bits whatever the machine).
    ///
    /// # Errors
    /// As [`super::factor`]: a residual or derivative that is not finite, bad `columns` or
    /// `scales`.
    pub(crate) fn of<P: Problem + ?Sized>(
        problem: &P,
        x: &[f64],
        columns: &[usize],
        scales: &[f64],
    ) -> Result<GramSum, CalibError> {
        check_columns(problem.parameter_count(), columns, scales)?;
        Self::over(problem, x, columns, scales, 0..problem.block_count())
    }

    /// The sum over the blocks `range` of `problem` (columns already checked), in block order
    /// on this thread.
    pub(super) fn over<P: Problem + ?Sized>(
        problem: &P,
        x: &[f64],
        columns: &[usize],
        scales: &[f64],
        range: std::ops::Range<usize>,
    ) -> Result<GramSum, CalibError> {
        let empty = Gram::new(columns.len() + 1);
        let (mut gram, ssr, rows) = accumulate(problem, x, columns, scales, range, false, empty)?;
        gram.fold();
        Ok(GramSum { gram, ssr, rows })
    }

    /// Adds the rows of `other` (of the same columns).
    pub(crate) fn add(&mut self, other: GramSum) {
        self.gram.add(other.gram);
        self.ssr += other.ssr;
        self.rows += other.rows;
    }

    /// The factor of the rows summed (see [`factor_of`]): `None` when their Gram matrix is
    /// singular or too ill-conditioned to give it.
    pub(crate) fn factor(self) -> Option<Factor> {
        factor_of(self.gram, self.ssr, self.rows)
    }
}

/// The factor of `[A | r]` from its Gram matrix `gram` (`ssr`: the residuals' sum of squares,
/// `rows`: their number): `R = Lᵀ` of the Cholesky factor `L` of `AᵀA` and `Qᵀr = L⁻¹·Aᵀr`
/// (so `‖r + A·u‖² = ‖Qᵀr + R·u‖² + ρ²`, as [`Factor`] says). `None` without columns, when
/// `AᵀA` is not positive definite, or when `κ(R) >` [`GRAM_MAX_CONDITION`].
fn factor_of(mut gram: Gram, ssr: f64, rows: usize) -> Option<Factor> {
    gram.fold();
    let (c, p) = (gram.cols, gram.cols.checked_sub(1)?);
    if p == 0 {
        return None;
    }
    let at = |i: usize, j: usize| gram.g[i.max(j) * c + i.min(j)];
    let ata = DMatrix::from_fn(p, p, at);
    let atr = DVector::from_fn(p, |j, _| at(p, j));
    let chol = nalgebra::Cholesky::new(ata)?;
    let l = chol.l();
    let s = l.clone().singular_values();
    let (largest, smallest) = (s.max(), s.min());
    if !(smallest > 0.0 && largest <= GRAM_MAX_CONDITION * smallest) {
        return None;
    }
    let qtr = l.solve_lower_triangular(&atr)?;
    Some(Factor {
        r: l.transpose(),
        qtr,
        ssr,
        rows,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::{factor, Problem, Tsqr, SEGMENT_BLOCKS};
    use rand::{Rng, SeedableRng};

    /// Rows of `cols` columns whose last one is a residual; `aliased` makes column 1 twice
    /// column 0 (`AᵀA` singular), `weak` scales column 2 down to that fraction.
    fn rows(n: usize, cols: usize, weak: f64, aliased: bool) -> Vec<Vec<f64>> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        (0..n)
            .map(|_| {
                let mut row: Vec<f64> = (0..cols).map(|_| rng.random_range(-1.0..1.0)).collect();
                row[2] *= weak;
                if aliased {
                    row[1] = 2.0 * row[0];
                }
                row
            })
            .collect()
    }

    fn gram_factor(rows: &[Vec<f64>]) -> Option<Factor> {
        let cols = rows[0].len();
        let ones = vec![1.0; cols - 1];
        // Two parts added, as the segments of a large problem are.
        let (first, second) = rows.split_at(rows.len() / 3);
        let mut total = Gram::new(cols);
        for part in [first, second] {
            let mut g = Gram::new(cols);
            for r in part {
                assert!(g.push_scaled(&r[..cols - 1], &ones, r[cols - 1]));
            }
            total.add(g);
        }
        let ssr = rows.iter().map(|r| r[cols - 1].powi(2)).sum();
        factor_of(total, ssr, rows.len())
    }

    /// On a well-conditioned matrix the Gram matrix's factor is the QR's: the same `R` and
    /// `Qᵀr` up to the signs of their rows, to 1e-12 of their largest element.
    #[test]
    fn the_gram_factor_is_the_qr_factor() {
        let rows = rows(5003, 7, 0.1, false);
        let f = gram_factor(&rows).expect("well conditioned");
        let mut qr = Tsqr::new(7);
        for r in &rows {
            qr.push(r);
        }
        let full = qr.finish();
        let scale = full.abs().max();
        for i in 0..6 {
            let sign = f.r[(i, i)].signum() * full[(i, i)].signum();
            for j in 0..6 {
                let d = (f.r[(i, j)] - sign * full[(i, j)]).abs();
                assert!(
                    d < 1e-12 * scale,
                    "R[{i},{j}] {} against {}",
                    f.r[(i, j)],
                    full[(i, j)]
                );
            }
            let d = (f.qtr[i] - sign * full[(i, 6)]).abs();
            assert!(
                d < 1e-12 * scale,
                "qtr[{i}] {} against {}",
                f.qtr[i],
                full[(i, 6)]
            );
        }
        assert_eq!(f.rows, 5003);
    }

    /// A singular `AᵀA`, or a condition number above the limit, is left to the QR.
    #[test]
    fn a_singular_or_ill_conditioned_gram_matrix_is_refused() {
        assert!(gram_factor(&rows(500, 5, 1.0, true)).is_none());
        assert!(gram_factor(&rows(500, 5, 1e-5, false)).is_none());
        assert!(gram_factor(&rows(500, 5, 1e-3, false)).is_some());
    }

    /// A large problem's factor: from the Gram matrix when it is well conditioned, and the
    /// QR's (a zero on the diagonal for the aliased column) when it is not.
    #[test]
    fn a_large_problem_falls_back_to_the_qr() {
        struct Table(Vec<Vec<f64>>);
        impl Problem for Table {
            fn parameter_count(&self) -> usize {
                self.0[0].len() - 1
            }
            fn block_count(&self) -> usize {
                self.0.len()
            }
            fn block_size(&self, _: usize) -> usize {
                1
            }
            fn residuals(&self, _: &[f64], b: usize, out: &mut [f64]) {
                out[0] = *self.0[b].last().expect("a residual");
            }
            fn jacobian(&self, x: &[f64], b: usize, cols: &[usize], r: &mut [f64], j: &mut [f64]) {
                self.residuals(x, b, r);
                for (k, &c) in cols.iter().enumerate() {
                    j[k] = self.0[b][c];
                }
            }
        }
        let n = SEGMENT_BLOCKS + 1000;
        let columns = [0, 1, 2, 3];
        for aliased in [false, true] {
            let p = Table(rows(n, 5, 1.0, aliased));
            let f = factor(&p, &[0.0; 4], &columns, &[1.0; 4]).expect("a factor");
            let rtr = f.r.transpose() * &f.r;
            let a = nalgebra::DMatrix::from_fn(n, 4, |i, j| p.0[i][j]);
            let ata = a.transpose() * &a;
            assert!((rtr - &ata).abs().max() < 1e-9 * ata.abs().max());
            let smallest = (0..4)
                .map(|i| f.r[(i, i)].abs())
                .fold(f64::INFINITY, f64::min);
            assert_eq!(smallest < 1e-6, aliased, "{smallest}");
            // Asked for the QR, the problem gets it whatever its conditioning: the factor the
            // fallback makes when the Gram matrix is refused, and not the Gram matrix's
            // Cholesky factor (whose diagonal is positive) when it is not.
            let q = crate::fit::factor_by_qr(&p, &[0.0; 4], &columns, &[1.0; 4]).expect("QR");
            let rtr = q.r.transpose() * &q.r;
            assert!((rtr - &ata).abs().max() < 1e-9 * ata.abs().max());
            if aliased {
                assert_eq!(q, f);
            } else {
                assert!((0..4).all(|i| f.r[(i, i)] > 0.0));
                assert_ne!(q, f);
            }
        }
    }
}
