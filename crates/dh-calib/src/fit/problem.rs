//! The least-squares problem a solver minimises, the solver's options and its outcome.
//!
//! A [`Problem`] is `min ½ Σ_b ‖r_b(x)‖²` over small blocks of residuals (one measured
//! point: 3 residuals, metres; one measured pose: 6). Parameters are in their own units
//! (metres, radians, an effect's unit); column scales (see the parent module) make them
//! comparable.

use nalgebra::DMatrix;

/// A least-squares problem `min ½ Σ_b ‖r_b(x)‖²` over blocks `b` of residuals.
///
/// `x` always holds every parameter; solvers ask only for the Jacobian columns of the free ones.
/// Implementations must be deterministic and return finite numbers for finite `x`; they are
/// shared between threads (`Sync`) when a problem has more than [`SEGMENT_BLOCKS`](super::SEGMENT_BLOCKS) blocks.
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
    /// Sum of squared residuals at `x`, or `None` when one is not finite:
    /// [`sum_of_squares`](super::sum_of_squares), the number an implementation that overrides
    /// it must give too (the same residuals summed in the same order).
    fn sum_of_squares(&self, x: &[f64]) -> Option<f64> {
        super::sum_of_squares(self, x)
    }
}

/// Largest residual block a [`Problem`] may have.
pub const MAX_BLOCK: usize = 16;

/// Options of [`solve`](super::solve).
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
    /// identifiability test ([`crate::calibrate`]), not by [`solve`](super::solve): a singular direction of
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

/// Why [`solve`](super::solve) stopped.
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

/// The result of [`solve`](super::solve).
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
