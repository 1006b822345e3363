//! Levenberg-Marquardt truncated to the numerically identifiable subspace, and the outcome
//! (standard errors, covariance) of a fit.
//!
//! Nielsen's damping update ("Damping parameter in Marquardt's method", IMM-REP-1999-05) on
//! the column-scaled problem; standard errors `σ̂ · sqrt(diag((JᵀJ)⁺))` in the parameters'
//! own units (metres, radians).

use nalgebra::{DMatrix, DVector, SVD};

use super::factor::{check_columns, factor, Factor, SEGMENT_BLOCKS};
use super::{CalibError, FitOptions, FitOutcome, Problem, Termination};

/// Least ratio `ρ` of actual to predicted decrease for which a large fit's last step (see
/// [`solve`]) ends the fit: the linear model then describes the cost where it stepped (Moré's
/// "very successful" threshold is 0.75; 0.25 is the usual "successful" one).
const LAST_STEP_MIN_RHO: f64 = 0.25;

/// Number of SVD sweeps allowed before giving up (nalgebra's default is unbounded).
const SVD_MAX_ITERATIONS: usize = 10_000;

pub(super) fn svd(
    m: DMatrix<f64>,
    what: &str,
) -> Result<SVD<f64, nalgebra::Dyn, nalgebra::Dyn>, CalibError> {
    if m.iter().any(|v| !v.is_finite()) {
        return Err(CalibError::NonFinite { what: what.into() });
    }
    SVD::try_new(m, true, true, f64::EPSILON, SVD_MAX_ITERATIONS)
        .ok_or_else(|| CalibError::NoConvergence { what: what.into() })
}

/// Minimises the problem's sum of squares over the parameters `free`, starting at `x0`.
///
/// Levenberg-Marquardt (Nielsen's damping update, "Damping parameter in Marquardt's method",
/// IMM-REP-1999-05) on the column-scaled problem `J·diag(scales)`, with each step restricted to
/// singular directions above `options.rank_tolerance · σ_max`: unidentifiable combinations stay
/// where `x0` puts them instead of wandering off along the null space. Standard errors are
/// `σ̂ · sqrt(diag((JᵀJ)⁺))` with `σ̂² = ssr / (m − rank)` (the usual linearised estimate).
///
/// **The last step of a large fit.** On a problem of more than [`SEGMENT_BLOCKS`] blocks, a
/// factor is a pass over every sample (2 000 000 poses: seconds). There, a step is known to be
/// the last before it is taken when the decrease it predicts, `p₁`, and the one the step before
/// predicted, `p₀`, put the next one, `p₁ · (p₁ / p₀)` at the observed rate of convergence, under
/// `cost_tolerance · ssr`, the test that would stop the fit at the new point. Its point is then
/// checked by a sum of squares instead of a factor, and the fit stops there when the step is
/// taken with `ρ ≥ 0.25` (otherwise it goes on as usual). The point is the one
/// the full iteration reaches (the same step from the same factor); the sum of squares is that
/// point's; the standard errors, singular values and covariance are those of the factor one step
/// before, a Jacobian that differs from the point's by that last step (on the 2 000 000-row Panda
/// set, a predicted decrease of 1.2e-12 of the sum of squares).
///
/// # Errors
/// [`CalibError::Length`] / [`CalibError::BadParameter`] for inconsistent inputs,
/// [`CalibError::NonFinite`] when the problem returns NaN or infinity at `x0`,
/// [`CalibError::NoConvergence`] when an SVD fails.
pub fn solve<P: Problem + ?Sized>(
    problem: &P,
    x0: &[f64],
    free: &[usize],
    scales: &[f64],
    options: &FitOptions,
) -> Result<FitOutcome, CalibError> {
    solve_from(problem, x0, free, scales, options, None)
}

/// [`solve`], given the factor of `free` at `x0` when the caller has it (`first`: what
/// [`factor`] of `problem`, `x0`, `free` and `scales` returns), which is then not computed again.
///
/// # Errors
/// As [`solve`].
pub(crate) fn solve_from<P: Problem + ?Sized>(
    problem: &P,
    x0: &[f64],
    free: &[usize],
    scales: &[f64],
    options: &FitOptions,
    first: Option<Factor>,
) -> Result<FitOutcome, CalibError> {
    let end = iterate(problem, x0, free, scales, options, first, large(problem))?;
    outcome(end, free, scales, options)
}

/// Whether `problem` is large enough for its last step to be checked by a sum of squares
/// (see [`solve`]): more than [`SEGMENT_BLOCKS`] blocks, where a factor is a pass over every
/// sample on every core.
fn large<P: Problem + ?Sized>(problem: &P) -> bool {
    problem.block_count() > SEGMENT_BLOCKS
}

/// [`solve`] with a factor at every point, the last one too (no last step by a sum of squares
/// whatever the problem's size): what the last step's test compares with.
#[cfg(test)]
pub(super) fn solve_with_every_factor<P: Problem + ?Sized>(
    problem: &P,
    x0: &[f64],
    free: &[usize],
    scales: &[f64],
    options: &FitOptions,
) -> Result<FitOutcome, CalibError> {
    let end = iterate(problem, x0, free, scales, options, None, false)?;
    outcome(end, free, scales, options)
}

/// The point [`solve_from`] reaches, without its outcome (the singular value decomposition
/// and covariance of its last factor): for a fit whose parameters alone are read, as a
/// cross-validation fold's. The same `x`, bit for bit.
///
/// # Errors
/// As [`solve`] (but none from the outcome's decomposition, which is not made).
pub(crate) fn solve_point_from<P: Problem + ?Sized>(
    problem: &P,
    x0: &[f64],
    free: &[usize],
    scales: &[f64],
    options: &FitOptions,
    first: Option<Factor>,
) -> Result<Vec<f64>, CalibError> {
    Ok(iterate(problem, x0, free, scales, options, first, large(problem))?.x)
}

/// Where the iterations of [`solve_from`] stop: the point, its sum of squares, the factor there
/// (or one step before, after a large fit's last step: see [`solve`]), and the singular value
/// decomposition of that factor when the last iteration made it.
struct End {
    x: Vec<f64>,
    ssr: f64,
    f: Factor,
    iterations: usize,
    termination: Termination,
    dec: Option<Svd>,
}

type Svd = SVD<f64, nalgebra::Dyn, nalgebra::Dyn>;

/// The Levenberg-Marquardt iterations of [`solve_from`]; `last_step`: a step known to be the
/// last is checked by a sum of squares instead of a factor (see [`solve`]).
fn iterate<P: Problem + ?Sized>(
    problem: &P,
    x0: &[f64],
    free: &[usize],
    scales: &[f64],
    options: &FitOptions,
    first: Option<Factor>,
    last_step: bool,
) -> Result<End, CalibError> {
    let n = problem.parameter_count();
    if x0.len() != n {
        return Err(CalibError::Length {
            what: "x0".into(),
            expected: n,
            found: x0.len(),
        });
    }
    check_columns(n, free, scales)?;
    let p = free.len();
    let mut x = x0.to_vec();
    let mut f = match first {
        Some(f) => f,
        None => factor(problem, &x, free, scales)?,
    };
    let mut iterations = 0;
    let mut termination = Termination::MaxIterations;
    let mut lambda = f64::NAN;
    let mut nu = 2.0;
    let mut x_new = x.clone();
    let mut kept = None;
    // The decrease the last taken step predicted, and the sum of squares a large fit's last
    // step reached (see `solve`).
    let mut previous_predicted: Option<f64> = None;
    let mut last_ssr = None;
    'outer: loop {
        if p == 0 {
            break;
        }
        // Any step's predicted decrease `‖qtr‖² − ‖qtr + R du‖²` is at most `‖qtr‖²` (the
        // same sum, less a sum of squares): when that is within the cost tolerance, the test
        // below stops at this point whatever the step, so it stops here without the
        // decomposition (the outcome makes it once, instead of twice).
        if f.qtr.norm_squared() <= options.cost_tolerance * f.ssr {
            termination = Termination::Converged;
            break;
        }
        let dec = svd(f.r.clone(), "jacobian factor")?;
        let s = &dec.singular_values;
        let (Some(u), Some(vt)) = (&dec.u, &dec.v_t) else {
            return Err(CalibError::NoConvergence {
                what: "jacobian factor".into(),
            });
        };
        let smax = s.max();
        if smax <= 0.0 {
            termination = Termination::Converged;
            break;
        }
        if lambda.is_nan() {
            lambda = options.initial_damping * smax * smax;
        }
        let rank = s
            .iter()
            .filter(|&&v| v > options.rank_tolerance * smax)
            .count();
        let utz: Vec<f64> = (0..rank).map(|i| u.column(i).dot(&f.qtr)).collect();
        let u_norm: f64 = free
            .iter()
            .map(|&c| (x[c] / scales[c]).powi(2))
            .sum::<f64>()
            .sqrt();
        let mut rejections = 0;
        loop {
            // Step in scaled coordinates: du = −Σ v_i s_i/(s_i² + λ) (u_iᵀ z).
            let mut du = DVector::zeros(p);
            for i in 0..rank {
                let w = s[i] / (s[i] * s[i] + lambda) * utz[i];
                du -= vt.row(i).transpose() * w;
            }
            let pred_res = &f.qtr + &f.r * &du;
            let predicted = f.qtr.norm_squared() - pred_res.norm_squared();
            if predicted.is_nan() || predicted <= options.cost_tolerance * f.ssr {
                termination = Termination::Converged;
                // The decomposition of the last factor, which the outcome needs.
                kept = Some(dec);
                break 'outer;
            }
            let du_norm = du.norm();
            for (k, &c) in free.iter().enumerate() {
                x_new[c] = x[c] + du[k] * scales[c];
            }
            // A large fit's last step: the next predicted decrease, at the rate the last two
            // show, is under the cost tolerance (`p₁ · p₁ / p₀ ≤ tol · ssr`).
            let last = last_step
                && previous_predicted
                    .is_some_and(|p0| predicted * predicted <= options.cost_tolerance * f.ssr * p0);
            // The factor at the trial point is made at once (its sum of squares is the same
            // number, summed in the same order, as `sum_of_squares`), which saves a pass over
            // every sample when the step is taken, as it nearly always is after a taken step.
            let trial = if rejections == 0 && !last {
                Some(factor(problem, &x_new, free, scales))
            } else {
                None
            };
            let new_ssr = match &trial {
                Some(Ok(t)) => t.ssr.is_finite().then_some(t.ssr),
                _ => problem.sum_of_squares(&x_new),
            };
            let actual = new_ssr.map(|new| f.ssr - new);
            let rho = actual.map_or(-1.0, |a| a / predicted);
            if rho > 1e-4 {
                x.copy_from_slice(&x_new);
                lambda *= (1.0 / 3.0_f64).max(1.0 - (2.0 * rho - 1.0).powi(3));
                nu = 2.0;
                iterations += 1;
                if last && rho >= LAST_STEP_MIN_RHO {
                    // `new_ssr` is `Some` whenever `rho` is above zero.
                    last_ssr = new_ssr;
                    termination = Termination::Converged;
                    kept = Some(dec);
                    break 'outer;
                }
                previous_predicted = Some(predicted);
                let small = du_norm <= options.step_tolerance * (u_norm + options.step_tolerance);
                let flat = actual.is_some_and(|a| a <= options.cost_tolerance * f.ssr);
                f = match trial {
                    Some(t) => t?,
                    None => factor(problem, &x, free, scales)?,
                };
                if small {
                    termination = Termination::SmallStep;
                    break 'outer;
                }
                if flat {
                    termination = Termination::Converged;
                    break 'outer;
                }
                if iterations >= options.max_iterations {
                    termination = Termination::MaxIterations;
                    break 'outer;
                }
                continue 'outer;
            }
            lambda *= nu;
            nu *= 2.0;
            rejections += 1;
            if rejections > 60 || !lambda.is_finite() {
                termination = Termination::Stalled;
                break 'outer;
            }
        }
    }
    if p == 0 {
        termination = Termination::Converged;
    }
    Ok(End {
        x,
        ssr: last_ssr.unwrap_or(f.ssr),
        f,
        iterations,
        termination,
        dec: kept,
    })
}

fn outcome(
    end: End,
    free: &[usize],
    scales: &[f64],
    options: &FitOptions,
) -> Result<FitOutcome, CalibError> {
    let End {
        x,
        ssr,
        f,
        iterations,
        termination,
        dec,
    } = end;
    let p = free.len();
    let n = x.len();
    let mut std_errors = vec![None; n];
    if p == 0 {
        return Ok(FitOutcome {
            x,
            free: vec![],
            ssr,
            residual_count: f.rows,
            iterations,
            termination,
            rank: 0,
            singular_values: vec![],
            condition_number: 1.0,
            sigma: (f.rows > 0).then(|| (ssr / f.rows as f64).sqrt()),
            covariance: None,
            std_errors,
        });
    }
    let dec = match dec {
        Some(d) => d,
        None => svd(f.r.clone(), "jacobian factor")?,
    };
    let s: Vec<f64> = dec.singular_values.iter().copied().collect();
    let smax = s.first().copied().unwrap_or(0.0);
    let rank = s
        .iter()
        .filter(|&&v| v > options.rank_tolerance * smax && v > 0.0)
        .count();
    let condition_number = match s.last() {
        Some(&smin) if rank == p && smin > 0.0 => smax / smin,
        _ => f64::INFINITY,
    };
    let sigma = (f.rows > rank).then(|| (ssr / (f.rows - rank) as f64).sqrt());
    let mut covariance = None;
    if let (Some(sig), Some(vt)) = (sigma, &dec.v_t) {
        let mut cov = DMatrix::zeros(p, p);
        for (i, si) in s.iter().enumerate().take(rank) {
            let v = vt.row(i).transpose();
            cov += &v * v.transpose() / (si * si);
        }
        for a in 0..p {
            for b in 0..p {
                cov[(a, b)] *= sig * sig * scales[free[a]] * scales[free[b]];
            }
        }
        for (k, &c) in free.iter().enumerate() {
            std_errors[c] = Some(cov[(k, k)].max(0.0).sqrt());
        }
        covariance = Some(cov);
    }
    Ok(FitOutcome {
        x,
        free: free.to_vec(),
        ssr,
        residual_count: f.rows,
        iterations,
        termination,
        rank,
        singular_values: s,
        condition_number,
        sigma,
        covariance,
        std_errors,
    })
}
