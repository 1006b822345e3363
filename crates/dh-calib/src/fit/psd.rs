//! The pseudo-inverse of a symmetric positive semi-definite matrix (normal equations `JᵀJ` of
//! scaled columns), with the fit's rank rule: directions whose eigenvalue is below
//! `rank_tolerance²` of the largest (singular values of `J` below `rank_tolerance` of the
//! largest) are left out, as [`super::solve`] leaves them out of its steps.

use nalgebra::DMatrix;

/// `m⁺` for a symmetric positive semi-definite `m` (its two triangles are averaged first),
/// eigen-directions below `rank_tolerance²` of the largest eigenvalue left out; zero when `m`
/// has no positive finite eigenvalue.
pub(crate) fn pseudo_inverse(m: &DMatrix<f64>, rank_tolerance: f64) -> DMatrix<f64> {
    let n = m.nrows();
    let sym = DMatrix::from_fn(n, n, |a, b| 0.5 * (m[(a, b)] + m[(b, a)]));
    let eig = sym.symmetric_eigen();
    let largest = eig.eigenvalues.iter().copied().fold(0.0, f64::max);
    let mut out = DMatrix::zeros(n, n);
    if !(largest > 0.0 && largest.is_finite()) {
        return out;
    }
    let floor = largest * rank_tolerance * rank_tolerance;
    for (i, &lambda) in eig.eigenvalues.iter().enumerate() {
        if lambda > floor {
            let v = eig.eigenvectors.column(i);
            out += v * v.transpose() / lambda;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DVector;

    #[test]
    fn a_rank_deficient_system_steps_only_where_it_is_determined() {
        // x0 + x1 = 2 determined, x0 - x1 free: the minimum-norm solution is (1, 1).
        let m = DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 1.0, 1.0]);
        let g = DVector::from_row_slice(&[2.0, 2.0]);
        let d = pseudo_inverse(&m, 1e-6) * g;
        assert!(
            (d[0] - 1.0).abs() < 1e-12 && (d[1] - 1.0).abs() < 1e-12,
            "{d}"
        );
        assert_eq!(
            pseudo_inverse(&DMatrix::zeros(2, 2), 1e-6),
            DMatrix::zeros(2, 2)
        );
    }
}
