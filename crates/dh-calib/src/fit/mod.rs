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
//! A problem of more than [`SEGMENT_BLOCKS`] blocks (a pass over millions of samples) is
//! factored from the Gram matrix of its scaled Jacobian when that is accurate: when the
//! Jacobian's condition number is at most [`GRAM_MAX_CONDITION`], so that the squared one
//! costs at most 2.2e-8 of relative accuracy in the weakest direction (module `gram`). Else,
//! and for every smaller problem, by the QR above.
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

mod error;
mod factor;
mod gram;
mod identify;
mod problem;
mod psd;
mod solve;
#[cfg(test)]
mod tests;

pub use error::CalibError;
pub use factor::{factor, factor_by_qr, sum_of_squares, Factor, SEGMENT_BLOCKS};
pub(crate) use factor::{in_segments, parallel_map, Tsqr};
pub(crate) use gram::GramSum;
pub use gram::GRAM_MAX_CONDITION;
pub use identify::{
    identifiability, identifiability_above, numeric_jacobian, Fixed, Identifiability,
    ALIAS_THRESHOLD,
};
pub use problem::{FitOptions, FitOutcome, Problem, Termination, MAX_BLOCK, MIN_SENSITIVITY};
pub(crate) use psd::pseudo_inverse;
pub use solve::solve;
pub(crate) use solve::{solve_from, solve_point_from};
