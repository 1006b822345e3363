//! Which parameters the data determines (rank of the column-scaled Jacobian by SVD), which
//! to hold fixed, and the aliases of each; a central-difference Jacobian for checks.
//!
//! Column scales as in the parent module: metres against metres, angles times the robot's
//! characteristic length (Hollerbach & Wampler, IJRR 15(6), 1996, §4).

use nalgebra::{DMatrix, DVector};

use super::solve::svd;
use super::{CalibError, Problem, MAX_BLOCK};

/// A parameter that the data cannot determine together with the free ones.
#[derive(Clone, Debug, PartialEq)]
pub struct Fixed {
    /// Its index.
    pub index: usize,
    /// Free parameters that move with it in the null space, ascending.
    pub aliases: Vec<usize>,
    /// The null-space combination in parameter units (one entry per column, 1 at `index`, 0 at
    /// every other fixed parameter): changing `x` by `t · combination` changes no prediction to
    /// first order. So a true error `e` in this parameter shows up as `−e · combination[i]` in
    /// each alias `i`.
    pub combination: Vec<f64>,
}

/// What the data can determine; the result of [`identifiability`].
#[derive(Clone, Debug, PartialEq)]
pub struct Identifiability {
    /// Numerical rank of the scaled Jacobian.
    pub rank: usize,
    /// Singular values of the scaled Jacobian, largest first.
    pub singular_values: Vec<f64>,
    /// `σ_max / σ_min` over the free columns only (scaled).
    pub condition_number: f64,
    /// Columns kept free, ascending: they are linearly independent to the tolerance.
    pub free: Vec<usize>,
    /// Columns to hold fixed, in the order chosen.
    pub fixed: Vec<Fixed>,
}

/// A coefficient of a null-space combination below this fraction of the combination's largest
/// (scaled, so metres against metres) is rounding, not an alias.
pub const ALIAS_THRESHOLD: f64 = 1e-3;

/// A row of the null-space basis whose part outside the rows already chosen is shorter than
/// this (the basis is orthonormal, so 1 is "entirely new") is not used to fix a parameter
/// while better candidates remain.
const PARTICIPATION_THRESHOLD: f64 = 1e-2;

/// Which parameters the data determines: the numerical rank of the column-scaled Jacobian by
/// SVD, then a choice of `n − rank` parameters to hold fixed such that the others are
/// independent, and for each fixed one the free parameters it aliases with.
///
/// `jacobian` is the Jacobian of all `n` parameters or any matrix with the same Gram matrix
/// `JᵀJ` (such as [`Factor::r`](super::Factor::r) of all columns, with `scales` all 1 since it is scaled already).
/// `priorities` (one per column) says which to fix first: among the parameters that take part
/// in the null space, lower priority values are fixed first; within one priority the one that
/// takes the largest part is fixed first (a pivoted selection on the rows of the null-space
/// basis, as in the observability analyses of Mooring, Roth & Driels 1991, §9.3). For each
/// fixed parameter, the null-space vector with 1 at it and 0 at the other fixed ones names its
/// aliases.
///
/// # Errors
/// [`CalibError::Length`] when `scales` or `priorities` do not match the columns,
/// [`CalibError::NonFinite`] for NaN entries, [`CalibError::NoConvergence`] if the SVD fails.
pub fn identifiability(
    jacobian: &DMatrix<f64>,
    scales: &[f64],
    priorities: &[u32],
    rank_tolerance: f64,
) -> Result<Identifiability, CalibError> {
    identifiability_above(jacobian, scales, priorities, rank_tolerance, 0.0)
}

/// [`identifiability`] with an absolute floor as well: singular values of the scaled Jacobian
/// at or below `floor` (the scaled Jacobian's unit: metres of residual per metre of scaled
/// parameter, summed in quadrature over the rows) count as zero too, so that a combination the
/// data determines only to many times the noise is held fixed and named with its aliases
/// instead of being estimated. The calibration passes
/// `FitOptions::min_sensitivity · sqrt(rows / 3)` (see [`MIN_SENSITIVITY`](super::MIN_SENSITIVITY)).
///
/// # Errors
/// As [`identifiability`].
pub fn identifiability_above(
    jacobian: &DMatrix<f64>,
    scales: &[f64],
    priorities: &[u32],
    rank_tolerance: f64,
    floor: f64,
) -> Result<Identifiability, CalibError> {
    let n = jacobian.ncols();
    for (what, len) in [("scales", scales.len()), ("priorities", priorities.len())] {
        if len != n {
            return Err(CalibError::Length {
                what: what.into(),
                expected: n,
                found: len,
            });
        }
    }
    if n == 0 {
        return Ok(Identifiability {
            rank: 0,
            singular_values: vec![],
            condition_number: 1.0,
            free: vec![],
            fixed: vec![],
        });
    }
    let mut js = jacobian.clone();
    for (j, s) in scales.iter().enumerate() {
        js.column_mut(j).scale_mut(*s);
    }
    // A square (or taller) matrix keeps all n right singular vectors.
    if js.nrows() < n {
        let mut padded = DMatrix::zeros(n, n);
        padded.view_mut((0, 0), js.shape()).copy_from(&js);
        js = padded;
    }
    let dec = svd(js.clone(), "identifiability")?;
    let s: Vec<f64> = dec.singular_values.iter().copied().collect();
    let smax = s.first().copied().unwrap_or(0.0);
    let floor = if floor.is_finite() {
        floor.max(0.0)
    } else {
        0.0
    };
    let rank = s
        .iter()
        .filter(|&&v| v > rank_tolerance * smax && v > floor && v > 0.0)
        .count();
    let Some(vt) = &dec.v_t else {
        return Err(CalibError::NoConvergence {
            what: "identifiability".into(),
        });
    };
    let k = n - rank;
    // Null-space basis N (n × k), scaled coordinates.
    let null = DMatrix::from_fn(n, k, |i, j| vt[(rank + j, i)]);
    let mut chosen: Vec<usize> = Vec::with_capacity(k);
    let mut basis: Vec<DVector<f64>> = Vec::with_capacity(k);
    let residual_of = |i: usize, basis: &[DVector<f64>]| {
        let mut r = null.row(i).transpose();
        for b in basis {
            let c = b.dot(&r);
            r -= b * c;
        }
        r
    };
    let mut tiers: Vec<u32> = priorities.to_vec();
    tiers.sort_unstable();
    tiers.dedup();
    for threshold in [PARTICIPATION_THRESHOLD, 1e-8] {
        for &tier in &tiers {
            while chosen.len() < k {
                let mut best: Option<(usize, f64)> = None;
                for i in (0..n).filter(|i| priorities[*i] == tier && !chosen.contains(i)) {
                    let norm = residual_of(i, &basis).norm();
                    // Ties (within rounding) go to the earlier column: deterministic choice.
                    if best.is_none_or(|(_, b)| norm > b * (1.0 + 1e-9) + 1e-15) {
                        best = Some((i, norm));
                    }
                }
                match best {
                    Some((i, norm)) if norm > threshold => {
                        let r = residual_of(i, &basis);
                        basis.push(r / norm);
                        chosen.push(i);
                    }
                    _ => break,
                }
            }
        }
    }
    // Combinations: N c with (N c)_f = δ_{f, fixed} over the chosen rows.
    let mut fixed = Vec::with_capacity(chosen.len());
    if !chosen.is_empty() {
        let sub = DMatrix::from_fn(chosen.len(), k, |a, j| null[(chosen[a], j)]);
        let sub_svd = svd(sub, "null-space selection")?;
        for (a, &index) in chosen.iter().enumerate() {
            let mut e = DVector::zeros(chosen.len());
            e[a] = 1.0;
            let c = sub_svd
                .solve(&e, 1e-12)
                .map_err(|_| CalibError::NoConvergence {
                    what: "null-space selection".into(),
                })?;
            let v_scaled = &null * c;
            let big = v_scaled.amax();
            let mut aliases = Vec::new();
            let mut combination = vec![0.0; n];
            for i in 0..n {
                let is_fixed = chosen.contains(&i);
                // Back to parameter units: x = diag(scales) u.
                let coeff = v_scaled[i] * scales[i] / (v_scaled[index] * scales[index]);
                if i == index {
                    combination[i] = 1.0;
                } else if !is_fixed && v_scaled[i].abs() > ALIAS_THRESHOLD * big {
                    combination[i] = coeff;
                    aliases.push(i);
                }
            }
            fixed.push(Fixed {
                index,
                aliases,
                combination,
            });
        }
    }
    let free: Vec<usize> = (0..n).filter(|i| !chosen.contains(i)).collect();
    let sub = DMatrix::from_fn(js.nrows(), free.len(), |r, c| js[(r, free[c])]);
    let condition_number = if free.is_empty() {
        1.0
    } else {
        let sv = svd(sub, "identifiability")?.singular_values;
        let (hi, lo) = (sv.max(), sv.min());
        if lo > 0.0 {
            hi / lo
        } else {
            f64::INFINITY
        }
    };
    Ok(Identifiability {
        rank,
        singular_values: s,
        condition_number,
        free,
        fixed,
    })
}

/// Central-difference Jacobian of one block, for checking analytic Jacobians and for problems
/// without one. `steps[c]` is the step of parameter `c` (in its own unit).
pub fn numeric_jacobian<P: Problem + ?Sized>(
    problem: &P,
    x: &[f64],
    block: usize,
    columns: &[usize],
    steps: &[f64],
) -> DMatrix<f64> {
    let m = problem.block_size(block).min(MAX_BLOCK);
    let mut out = DMatrix::zeros(m, columns.len());
    let mut xp = x.to_vec();
    let (mut rp, mut rm) = ([0.0; MAX_BLOCK], [0.0; MAX_BLOCK]);
    for (k, &c) in columns.iter().enumerate() {
        let h = steps.get(c).copied().unwrap_or(1e-6);
        xp[c] = x[c] + h;
        problem.residuals(&xp, block, &mut rp[..m]);
        xp[c] = x[c] - h;
        problem.residuals(&xp, block, &mut rm[..m]);
        xp[c] = x[c];
        for i in 0..m {
            out[(i, k)] = (rp[i] - rm[i]) / (2.0 * h);
        }
    }
    out
}
