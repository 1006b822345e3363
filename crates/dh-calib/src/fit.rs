//! Generic nonlinear least squares with identifiability analysis.
//!
//! A [`Problem`] is a sum of squared residuals split into small blocks (one measured point: 3
//! residuals; one measured pose: 6). [`solve`] minimises it over a chosen subset of the
//! parameters by Levenberg-Marquardt whose steps are truncated to the numerically identifiable
//! subspace (singular values of the column-scaled Jacobian above `rank_tolerance` times the
//! largest), and [`identifiability`] decides which parameters the data can determine and which
//! others each one aliases with.
//!
//! # Memory and numerics
//! The Jacobian is never stored whole: blocks are stacked a few hundred rows at a time under
//! the triangular factor of everything seen so far and re-factored with nalgebra's Householder
//! QR (a "tall skinny QR"), so memory is `O(p²)` beyond the problem's own data and the
//! factor has the accuracy of a QR of the full Jacobian (no squared condition number as with
//! normal equations). The residual vector rides along as an extra column, which gives `Qᵀr`
//! for free. Singular values and vectors come from nalgebra's SVD of the `p × p` factor.
//!
//! The `levenberg-marquardt` crate is not used: it needs the dense Jacobian and has no
//! truncation to an identifiable subspace.
//!
//! # Column scaling
//! Every column `j` of the Jacobian is multiplied by `scales[j]` before any rank decision or
//! step, so that lengths (metres) and angles (radians times a characteristic length of the
//! robot, metres) are compared in one unit. Standard errors are reported in the parameters'
//! own units. See Mooring, Roth & Driels, *Fundamentals of Manipulator Calibration* (1991),
//! ch. 9, and Hollerbach & Wampler, "The calibration index and taxonomy for robot kinematic
//! calibration methods", IJRR 15(6), 1996, §4 on scaling and observability.

use nalgebra::{DMatrix, DVector, SVD};
use thiserror::Error;

/// Everything that can go wrong while modelling, simulating or fitting measurements.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum CalibError {
    /// A residual or Jacobian entry is NaN or infinite.
    #[error("{what}: expected finite numbers, found a NaN or infinite value")]
    NonFinite {
        /// Where it was found.
        what: String,
    },
    /// A parameter index is out of range, or a scale is not a positive finite number.
    #[error("parameter {index}: {reason}")]
    BadParameter {
        /// Parameter index.
        index: usize,
        /// What is wrong with it.
        reason: String,
    },
    /// Lengths of inputs that must agree do not.
    #[error("{what}: expected {expected} values, found {found}")]
    Length {
        /// What was measured.
        what: String,
        /// Expected length.
        expected: usize,
        /// Actual length.
        found: usize,
    },
    /// The SVD did not converge.
    #[error("singular value decomposition did not converge ({what})")]
    NoConvergence {
        /// Which decomposition.
        what: String,
    },
    /// A joint of the model has no column in the measurements and follows no joint that has.
    #[error("joint '{joint}': expected a column in the measurements, found none")]
    MissingJoint {
        /// Joint name.
        joint: String,
    },
    /// A sample names a target that does not exist.
    #[error("sample at line {line}: expected a target index below {count}, found {target}")]
    BadTarget {
        /// 1-based source line (0 when generated).
        line: usize,
        /// The index given.
        target: usize,
        /// Number of targets.
        count: usize,
    },
    /// Too few samples to determine what must be estimated.
    #[error("{what}: expected at least {needed} samples, found {found}")]
    TooFewSamples {
        /// What needed them.
        what: String,
        /// Samples needed.
        needed: usize,
        /// Samples available.
        found: usize,
    },
    /// The measured or modelled points are degenerate (all on one line) so no frame fits them.
    #[error("{what}: points are collinear or coincident, no unique rigid registration")]
    Degenerate {
        /// What was being registered.
        what: String,
    },
    /// A name in the input matches no parameter of the model.
    #[error("expected a parameter name of the model, found '{name}'")]
    UnknownParameter {
        /// The unknown name.
        name: String,
    },
    /// An option is out of its range.
    #[error("{what}: {reason}")]
    BadOption {
        /// Which option.
        what: String,
        /// Expected range.
        reason: String,
    },
    /// The model's kinematics are invalid.
    #[error(transparent)]
    Core(#[from] dh_core::CoreError),
}

/// A least-squares problem `min ½ Σ_b ‖r_b(x)‖²` over blocks `b` of residuals.
///
/// `x` always holds every parameter; solvers ask only for the Jacobian columns of the free ones.
/// Implementations must be deterministic and return finite numbers for finite `x`; they are
/// shared between threads (`Sync`) when a problem has more than [`SEGMENT_BLOCKS`] blocks.
pub trait Problem: Sync {
    /// Number of parameters (length of `x`).
    fn parameter_count(&self) -> usize;
    /// Number of residual blocks.
    fn block_count(&self) -> usize;
    /// Number of residuals in block `block` (at most [`MAX_BLOCK`]).
    fn block_size(&self, block: usize) -> usize;
    /// Writes the residuals of block `block` at `x` into `out` (length `block_size(block)`).
    fn residuals(&self, x: &[f64], block: usize, out: &mut [f64]);
    /// Writes residuals into `residuals` and the Jacobian `∂r/∂x_c` for `c` in `columns` into
    /// `jacobian`, row-major (`jacobian[i * columns.len() + k] = ∂r_i/∂x_{columns[k]}`).
    fn jacobian(
        &self,
        x: &[f64],
        block: usize,
        columns: &[usize],
        residuals: &mut [f64],
        jacobian: &mut [f64],
    );
}

/// Largest residual block a [`Problem`] may have.
pub const MAX_BLOCK: usize = 16;

/// Options of [`solve`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitOptions {
    /// Most Levenberg-Marquardt iterations (each one Jacobian evaluation).
    pub max_iterations: usize,
    /// Singular values of the scaled Jacobian below `rank_tolerance · σ_max` are treated as zero
    /// (their directions are neither stepped along nor given a standard error). Default 1e-6.
    pub rank_tolerance: f64,
    /// Converged when the predicted decrease of the sum of squares is below this fraction of it.
    /// Default 1e-14.
    pub cost_tolerance: f64,
    /// Converged when the scaled step is below this fraction of the scaled parameter vector's
    /// norm (plus itself). Default 1e-12.
    pub step_tolerance: f64,
    /// Initial damping as a fraction of the largest squared singular value. Default 1e-6
    /// (almost Gauss-Newton: the callers start close to the optimum).
    pub initial_damping: f64,
    /// Smallest sensitivity of an identifiable combination of parameters, in metres of RMS
    /// point displacement per metre of scaled parameter (an angle counts as metres at the
    /// column's scale, the robot's characteristic length). Used by the calibration's
    /// identifiability test ([`crate::calibrate`]), not by [`solve`]: a singular direction of
    /// the scaled Jacobian whose singular value is below `min_sensitivity · sqrt(rows / 3)`
    /// moves the measured points by less than that RMS and is held fixed, however far it is
    /// from rounding. Default [`MIN_SENSITIVITY`].
    pub min_sensitivity: f64,
}

/// Default [`FitOptions::min_sensitivity`]: 1e-3 m/m, a combination that moves the measured
/// points by less than one micrometre RMS per millimetre of change is not identifiable.
///
/// Why not the relative `rank_tolerance` alone: a combination can be far above rounding and
/// still be left to the noise. Targets measured with one tool orientation only (the poses of a
/// total station's stationing, all with the same commanded tool attitude) alias with the device
/// translation up to the joints' few-millidegree orientation differences: their singular values
/// are 1e-5 of the largest, their standard errors metres with a millimetre of noise, and a fit
/// that steps along them puts the target metres away, which poses with other tool orientations
/// then see. A micrometre per millimetre is below what any coordinate measuring device resolves
/// over a millimetre's change and far above rounding.
pub const MIN_SENSITIVITY: f64 = 1e-3;

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            max_iterations: 100,
            rank_tolerance: 1e-6,
            cost_tolerance: 1e-14,
            step_tolerance: 1e-12,
            initial_damping: 1e-6,
            min_sensitivity: MIN_SENSITIVITY,
        }
    }
}

/// Why [`solve`] stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Termination {
    /// The sum of squares cannot decrease by more than `cost_tolerance` of itself.
    Converged,
    /// The step became smaller than `step_tolerance`.
    SmallStep,
    /// `max_iterations` reached.
    MaxIterations,
    /// Damping grew without finding a decrease: the current point is a minimum to rounding.
    Stalled,
}

/// The result of [`solve`].
#[derive(Clone, Debug, PartialEq)]
pub struct FitOutcome {
    /// All parameters; only the free ones differ from `x0`.
    pub x: Vec<f64>,
    /// The free parameters, as given.
    pub free: Vec<usize>,
    /// Sum of squared residuals at `x`.
    pub ssr: f64,
    /// Number of residuals.
    pub residual_count: usize,
    /// Jacobian evaluations after the first.
    pub iterations: usize,
    /// Why the iteration stopped.
    pub termination: Termination,
    /// Numerical rank of the scaled Jacobian of the free columns at `x`.
    pub rank: usize,
    /// Its singular values, largest first (metres: scaled columns).
    pub singular_values: Vec<f64>,
    /// `σ_max / σ_min` of the scaled free columns (infinite when rank deficient).
    pub condition_number: f64,
    /// Residual standard deviation `σ̂ = sqrt(ssr / (m − rank))`, `None` when `m ≤ rank`.
    pub sigma: Option<f64>,
    /// Covariance of the free parameters in their own units, `σ̂² (JᵀJ)⁺` restricted to the
    /// identifiable subspace, ordered as `free`; `None` when `sigma` is.
    pub covariance: Option<DMatrix<f64>>,
    /// Per parameter (all of `x`): `σ̂ · sqrt(diag((JᵀJ)⁺))`, `None` for parameters that are
    /// not free or when `sigma` is `None`.
    pub std_errors: Vec<Option<f64>>,
}

/// The triangular factor of the column-scaled Jacobian of some columns, with the residuals.
///
/// `[J·diag(s) | r] = Q [[r_factor, qtr], [0, ρ]]`, so `‖r + J·diag(s)·u‖² = ‖qtr + r_factor·u‖² + ρ²`.
#[derive(Clone, Debug, PartialEq)]
pub struct Factor {
    /// Upper triangular `p × p` factor of the scaled Jacobian.
    pub r: DMatrix<f64>,
    /// `Qᵀ r` restricted to the first `p` rows.
    pub qtr: DVector<f64>,
    /// Sum of squared residuals.
    pub ssr: f64,
    /// Number of residuals.
    pub rows: usize,
}

/// Incremental QR of a tall matrix given a row at a time: the triangular factor `R` of the
/// rows so far, and a chunk of new rows `B` that is folded into it by Householder reflections
/// when full (the QR of `[R; B]`).
///
/// The reflections use the structure of `[R; B]`: the reflection of column `j` touches row `j`
/// of `R` and the chunk only (the rows of `R` below `j` are zero in that column), so a chunk
/// of `m` rows costs `2 m p²` operations, with no copy of the stack. Both are stored by
/// column, so every reflection runs over contiguous memory.
struct Tsqr {
    cols: usize,
    chunk: usize,
    /// `R`, `cols × cols`, by column: element `(i, k)` at `k · cols + i`.
    r: Vec<f64>,
    /// The chunk, `chunk × cols`, by column: element `(i, k)` at `k · chunk + i`.
    b: Vec<f64>,
    filled: usize,
}

impl Tsqr {
    fn new(cols: usize) -> Self {
        let chunk = (8 * cols).max(256);
        Self {
            cols,
            chunk,
            r: vec![0.0; cols * cols],
            b: vec![0.0; chunk * cols],
            filled: 0,
        }
    }

    fn push(&mut self, row: &[f64]) {
        if self.filled == self.chunk {
            self.flush();
        }
        for (k, v) in row.iter().enumerate().take(self.cols) {
            self.b[k * self.chunk + self.filled] = *v;
        }
        self.filled += 1;
    }

    /// Folds the chunk into `R` (Golub & Van Loan, Matrix Computations, 4th ed., §5.1.2,
    /// Householder vectors with `v₀ = x₀ − α`, `α = −sign(x₀)‖x‖`).
    fn flush(&mut self) {
        let (p, n, m) = (self.cols, self.chunk, self.filled);
        if m == 0 {
            return;
        }
        for j in 0..p {
            let (before, rest) = self.b.split_at_mut((j + 1) * n);
            let bj = &before[j * n..j * n + m];
            let sigma = dot(bj, bj);
            if sigma == 0.0 {
                continue;
            }
            let x0 = self.r[j * p + j];
            let norm = (x0 * x0 + sigma).sqrt();
            let alpha = if x0 >= 0.0 { -norm } else { norm };
            let v0 = x0 - alpha;
            let beta = 2.0 / (v0 * v0 + sigma);
            for k in j + 1..p {
                let bk = &mut rest[(k - j - 1) * n..(k - j - 1) * n + m];
                let rjk = self.r[k * p + j];
                let w = beta * (v0 * rjk + dot(bj, bk));
                self.r[k * p + j] = rjk - w * v0;
                for (y, x) in bk.iter_mut().zip(bj) {
                    *y -= w * x;
                }
            }
            self.r[j * p + j] = alpha;
        }
        self.filled = 0;
    }

    fn finish(mut self) -> DMatrix<f64> {
        self.flush();
        DMatrix::from_column_slice(self.cols, self.cols, &self.r)
    }
}

/// `Σ aᵢ bᵢ` in four independent sums (which the compiler can keep in vector registers).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for l in 0..4 {
            acc[l] += x[l] * y[l];
        }
    }
    let tail: f64 = ra.iter().zip(rb).map(|(x, y)| x * y).sum();
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

fn check_columns(n: usize, columns: &[usize], scales: &[f64]) -> Result<(), CalibError> {
    if scales.len() != n {
        return Err(CalibError::Length {
            what: "scales".into(),
            expected: n,
            found: scales.len(),
        });
    }
    for &c in columns {
        if c >= n {
            return Err(CalibError::BadParameter {
                index: c,
                reason: format!("expected an index below {n}"),
            });
        }
        let s = scales[c];
        if !(s.is_finite() && s > 0.0) {
            return Err(CalibError::BadParameter {
                index: c,
                reason: format!("expected a positive finite scale, found {s}"),
            });
        }
    }
    Ok(())
}

/// Factors the column-scaled Jacobian of `columns` at `x` (see [`Factor`]); the columns of
/// `r` are in the order of `columns`.
///
/// # Errors
/// [`CalibError::NonFinite`] when a residual or derivative is not finite;
/// [`CalibError::BadParameter`] / [`CalibError::Length`] for bad `columns` or `scales`.
pub fn factor<P: Problem + ?Sized>(
    problem: &P,
    x: &[f64],
    columns: &[usize],
    scales: &[f64],
) -> Result<Factor, CalibError> {
    let n = problem.parameter_count();
    check_columns(n, columns, scales)?;
    let p = columns.len();
    let blocks = problem.block_count();
    if blocks <= SEGMENT_BLOCKS {
        let (full, ssr, rows) = factor_blocks(problem, x, columns, scales, 0..blocks)?;
        return Ok(split_factor(&full, p, ssr, rows));
    }
    // Segments in parallel, their factors stacked in segment order: the same result whatever
    // the number of threads.
    let parts = segments(blocks, |range| {
        factor_blocks(problem, x, columns, scales, range)
    })?;
    let mut tsqr = Tsqr::new(p + 1);
    let (mut ssr, mut rows) = (0.0, 0);
    let mut row = vec![0.0; p + 1];
    for (r, s, m) in parts {
        for i in 0..r.nrows() {
            for (j, v) in row.iter_mut().enumerate() {
                *v = r[(i, j)];
            }
            tsqr.push(&row);
        }
        ssr += s;
        rows += m;
    }
    Ok(split_factor(&tsqr.finish(), p, ssr, rows))
}

/// Blocks per segment of a problem factored (or summed) in parallel: problems of at most this
/// many blocks take the serial path, bit for bit as before threads were used.
pub const SEGMENT_BLOCKS: usize = 16_384;

/// Runs `work` on consecutive ranges of [`SEGMENT_BLOCKS`] blocks on up to
/// `available_parallelism` threads; returns the results in range order (the first error in
/// that order, if any).
fn segments<T: Send>(
    blocks: usize,
    work: impl Fn(std::ops::Range<usize>) -> Result<T, CalibError> + Sync,
) -> Result<Vec<T>, CalibError> {
    parallel_map(blocks.div_ceil(SEGMENT_BLOCKS), |k| {
        work(k * SEGMENT_BLOCKS..((k + 1) * SEGMENT_BLOCKS).min(blocks))
    })
}

/// `work(0..count)` on up to `available_parallelism` threads, results in index order (the
/// first error in that order, if any): the same results whatever the number of threads, as
/// long as `work(k)` depends on `k` alone.
pub(crate) fn parallel_map<T: Send>(
    count: usize,
    work: impl Fn(usize) -> Result<T, CalibError> + Sync,
) -> Result<Vec<T>, CalibError> {
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::sync::Mutex;
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(count);
    if threads <= 1 {
        return (0..count).map(work).collect();
    }
    let next = AtomicUsize::new(0);
    let slots: Mutex<Vec<Option<Result<T, CalibError>>>> =
        Mutex::new((0..count).map(|_| None).collect());
    std::thread::scope(|scope| {
        for _ in 0..threads {
            scope.spawn(|| loop {
                let k = next.fetch_add(1, Ordering::Relaxed);
                if k >= count {
                    break;
                }
                let out = work(k);
                if let Ok(mut s) = slots.lock() {
                    s[k] = Some(out);
                }
            });
        }
    });
    let slots = slots.into_inner().map_err(|_| CalibError::NonFinite {
        what: "a worker thread panicked".into(),
    })?;
    slots
        .into_iter()
        .map(|s| {
            s.unwrap_or_else(|| {
                Err(CalibError::NonFinite {
                    what: "a worker thread panicked".into(),
                })
            })
        })
        .collect()
}

/// `(r_factor, qtr)` out of the `(p + 1) × (p + 1)` factor of `[J | r]`.
fn split_factor(full: &DMatrix<f64>, p: usize, ssr: f64, rows: usize) -> Factor {
    Factor {
        r: full.view((0, 0), (p, p)).clone_owned(),
        qtr: full.view((0, p), (p, 1)).column(0).clone_owned(),
        ssr,
        rows,
    }
}

/// The triangular factor of `[J·diag(s) | r]` over `range` of blocks, its sum of squared
/// residuals and its number of rows.
fn factor_blocks<P: Problem + ?Sized>(
    problem: &P,
    x: &[f64],
    columns: &[usize],
    scales: &[f64],
    range: std::ops::Range<usize>,
) -> Result<(DMatrix<f64>, f64, usize), CalibError> {
    let p = columns.len();
    let mut tsqr = Tsqr::new(p + 1);
    let mut res = [0.0; MAX_BLOCK];
    let mut jac = vec![0.0; MAX_BLOCK * p];
    let mut row = vec![0.0; p + 1];
    let mut ssr = 0.0;
    let mut rows = 0;
    for b in range {
        let m = problem.block_size(b).min(MAX_BLOCK);
        problem.jacobian(x, b, columns, &mut res[..m], &mut jac[..m * p]);
        for i in 0..m {
            for (k, &c) in columns.iter().enumerate() {
                row[k] = jac[i * p + k] * scales[c];
            }
            row[p] = res[i];
            if row.iter().any(|v| !v.is_finite()) {
                return Err(CalibError::NonFinite {
                    what: format!("residual block {b}"),
                });
            }
            ssr += res[i] * res[i];
            tsqr.push(&row);
        }
        rows += m;
    }
    Ok((tsqr.finish(), ssr, rows))
}

/// Sum of squared residuals at `x`, or `None` when one is not finite.
pub fn sum_of_squares<P: Problem + ?Sized>(problem: &P, x: &[f64]) -> Option<f64> {
    let blocks = problem.block_count();
    let ssr = if blocks <= SEGMENT_BLOCKS {
        sum_blocks(problem, x, 0..blocks)
    } else {
        segments(blocks, |range| Ok(sum_blocks(problem, x, range)))
            .ok()?
            .into_iter()
            .sum()
    };
    ssr.is_finite().then_some(ssr)
}

fn sum_blocks<P: Problem + ?Sized>(problem: &P, x: &[f64], range: std::ops::Range<usize>) -> f64 {
    let mut res = [0.0; MAX_BLOCK];
    let mut ssr = 0.0;
    for b in range {
        let m = problem.block_size(b).min(MAX_BLOCK);
        problem.residuals(x, b, &mut res[..m]);
        for v in &res[..m] {
            ssr += v * v;
        }
    }
    ssr
}

/// Number of SVD sweeps allowed before giving up (nalgebra's default is unbounded).
const SVD_MAX_ITERATIONS: usize = 10_000;

fn svd(m: DMatrix<f64>, what: &str) -> Result<SVD<f64, nalgebra::Dyn, nalgebra::Dyn>, CalibError> {
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
    let mut f = factor(problem, &x, free, scales)?;
    let mut iterations = 0;
    let mut termination = Termination::MaxIterations;
    let mut lambda = f64::NAN;
    let mut nu = 2.0;
    let mut x_new = x.clone();
    'outer: loop {
        if p == 0 {
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
                break 'outer;
            }
            let du_norm = du.norm();
            for (k, &c) in free.iter().enumerate() {
                x_new[c] = x[c] + du[k] * scales[c];
            }
            let actual = sum_of_squares(problem, &x_new).map(|new| f.ssr - new);
            let rho = actual.map_or(-1.0, |a| a / predicted);
            if rho > 1e-4 {
                x.copy_from_slice(&x_new);
                lambda *= (1.0 / 3.0_f64).max(1.0 - (2.0 * rho - 1.0).powi(3));
                nu = 2.0;
                iterations += 1;
                let small = du_norm <= options.step_tolerance * (u_norm + options.step_tolerance);
                let flat = actual.is_some_and(|a| a <= options.cost_tolerance * f.ssr);
                f = factor(problem, &x, free, scales)?;
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
    outcome(x, free, scales, f, iterations, termination, options)
}

fn outcome(
    x: Vec<f64>,
    free: &[usize],
    scales: &[f64],
    f: Factor,
    iterations: usize,
    termination: Termination,
    options: &FitOptions,
) -> Result<FitOutcome, CalibError> {
    let p = free.len();
    let n = x.len();
    let mut std_errors = vec![None; n];
    if p == 0 {
        return Ok(FitOutcome {
            x,
            free: vec![],
            ssr: f.ssr,
            residual_count: f.rows,
            iterations,
            termination,
            rank: 0,
            singular_values: vec![],
            condition_number: 1.0,
            sigma: (f.rows > 0).then(|| (f.ssr / f.rows as f64).sqrt()),
            covariance: None,
            std_errors,
        });
    }
    let dec = svd(f.r.clone(), "jacobian factor")?;
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
    let sigma = (f.rows > rank).then(|| (f.ssr / (f.rows - rank) as f64).sqrt());
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
        ssr: f.ssr,
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
/// `JᵀJ` (such as [`Factor::r`] of all columns, with `scales` all 1 since it is scaled already).
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
/// `FitOptions::min_sensitivity · sqrt(rows / 3)` (see [`MIN_SENSITIVITY`]).
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The chunked, structured QR gives the factor of the whole matrix: `RᵀR = AᵀA`, `R`
    /// upper triangular, with several flushes, a rank-deficient column and a zero column.
    #[test]
    fn tsqr_factors_a_tall_matrix_in_chunks() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let (rows, cols) = (1000, 6);
        let mut a = DMatrix::from_fn(rows, cols, |_, _| rng.random_range(-1.0..1.0));
        for i in 0..rows {
            a[(i, 3)] = 2.0 * a[(i, 0)] - a[(i, 1)];
            a[(i, 4)] = 0.0;
        }
        let mut t = Tsqr::new(cols);
        assert!(rows > 3 * t.chunk);
        for i in 0..rows {
            let row: Vec<f64> = (0..cols).map(|k| a[(i, k)]).collect();
            t.push(&row);
        }
        let r = t.finish();
        for i in 0..cols {
            for k in 0..i {
                assert_eq!(r[(i, k)], 0.0);
            }
        }
        let (ata, rtr) = (a.transpose() * &a, r.transpose() * &r);
        assert!((ata - rtr).abs().max() < 1e-10 * rows as f64);
        assert!(r[(3, 3)].abs() < 1e-10 && r[(4, 4)] == 0.0);
    }

    /// Fit a circle's centre and radius to points: residual = |p − c| − r (1 per block).
    struct Circle(Vec<(f64, f64)>);

    impl Problem for Circle {
        fn parameter_count(&self) -> usize {
            3
        }
        fn block_count(&self) -> usize {
            self.0.len()
        }
        fn block_size(&self, _: usize) -> usize {
            1
        }
        fn residuals(&self, x: &[f64], b: usize, out: &mut [f64]) {
            let (px, py) = self.0[b];
            out[0] = ((px - x[0]).powi(2) + (py - x[1]).powi(2)).sqrt() - x[2];
        }
        fn jacobian(&self, x: &[f64], b: usize, cols: &[usize], r: &mut [f64], j: &mut [f64]) {
            self.residuals(x, b, r);
            let (px, py) = self.0[b];
            let d = ((px - x[0]).powi(2) + (py - x[1]).powi(2)).sqrt();
            for (k, &c) in cols.iter().enumerate() {
                j[k] = match c {
                    0 => -(px - x[0]) / d,
                    1 => -(py - x[1]) / d,
                    _ => -1.0,
                };
            }
        }
    }

    #[test]
    fn circle_fit_recovers_centre_and_radius() {
        let pts: Vec<_> = (0..40)
            .map(|i| {
                let t = i as f64 * 0.3;
                (1.0 + 2.0 * t.cos(), -0.5 + 2.0 * t.sin())
            })
            .collect();
        let p = Circle(pts);
        let out = solve(
            &p,
            &[0.2, 0.3, 1.0],
            &[0, 1, 2],
            &[1.0; 3],
            &Default::default(),
        )
        .unwrap();
        assert!((out.x[0] - 1.0).abs() < 1e-12, "{:?}", out.x);
        assert!((out.x[1] + 0.5).abs() < 1e-12);
        assert!((out.x[2] - 2.0).abs() < 1e-12);
        assert!(out.ssr < 1e-24);
        assert_eq!(out.rank, 3);
        // Holding the radius fixed leaves it at x0 and fits the centre only.
        let out = solve(
            &p,
            &[0.2, 0.3, 2.0],
            &[0, 1],
            &[1.0; 3],
            &Default::default(),
        )
        .unwrap();
        assert_eq!(out.x[2], 2.0);
        assert!(out.std_errors[2].is_none() && out.std_errors[0].is_some());
    }

    #[test]
    fn factor_matches_dense_qr_across_chunks() {
        // 700 rows forces several chunk flushes.
        let pts: Vec<_> = (0..700)
            .map(|i| ((i as f64 * 0.01).sin() * 3.0, (i as f64 * 0.017).cos()))
            .collect();
        let p = Circle(pts);
        let x = [0.1, 0.2, 1.5];
        let f = factor(&p, &x, &[0, 1, 2], &[1.0, 2.0, 3.0]).unwrap();
        let mut j = DMatrix::zeros(700, 3);
        let mut r = DVector::zeros(700);
        for b in 0..700 {
            let (mut rb, mut jb) = ([0.0], [0.0; 3]);
            p.jacobian(&x, b, &[0, 1, 2], &mut rb, &mut jb);
            r[b] = rb[0];
            for c in 0..3 {
                j[(b, c)] = jb[c] * [1.0, 2.0, 3.0][c];
            }
        }
        let gram = j.transpose() * &j;
        let gram_f = f.r.transpose() * &f.r;
        assert!((gram - gram_f).amax() < 1e-9);
        let jtr = j.transpose() * &r;
        assert!((jtr - f.r.transpose() * &f.qtr).amax() < 1e-9);
        assert!((f.ssr - r.norm_squared()).abs() < 1e-9);
    }

    #[test]
    fn aliased_columns_are_found_with_their_partners() {
        // Columns: a, b = 2a (alias), c independent, d = 0 (no effect).
        let j = DMatrix::from_row_slice(
            4,
            4,
            &[
                1.0, 2.0, 0.0, 0.0, //
                0.5, 1.0, 1.0, 0.0, //
                -1.0, -2.0, 3.0, 0.0, //
                2.0, 4.0, 0.1, 0.0,
            ],
        );
        // Prefer fixing b (priority 0) over a (priority 1).
        let id = identifiability(&j, &[1.0; 4], &[1, 0, 1, 1], 1e-9).unwrap();
        assert_eq!(id.rank, 2);
        assert_eq!(id.free, vec![0, 2]);
        assert_eq!(id.fixed.len(), 2);
        let b = id.fixed.iter().find(|f| f.index == 1).unwrap();
        assert_eq!(b.aliases, vec![0]);
        // Moving b by t and a by −2t changes nothing.
        assert!((b.combination[0] + 2.0).abs() < 1e-9, "{:?}", b.combination);
        let d = id.fixed.iter().find(|f| f.index == 3).unwrap();
        assert!(d.aliases.is_empty());
        assert!(id.condition_number.is_finite());
    }
}
