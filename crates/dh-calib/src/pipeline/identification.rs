//! Whether the data identify a geometric parameter ([`Identification`]): its standard error as
//! a length at the measured points, against the set's noise floor.
//!
//! A geometric parameter's correction can legitimately be about zero (the data confirm the
//! nominal to its precision), so it is not judged by estimate over standard error as an
//! effect's parameter is ([`super::IDENTIFIED_SIGMAS`]). It is judged by how far the
//! measured points may move within its standard error: `u_j = SE_j · l_j`, with `l_j` its lever
//! at the points, the RMS over the `N` calibration samples of how far a unit change moves them,
//! `l_j = ‖J_j‖ / √N` (`J_j` its column of the fit's Jacobian, metres per unit). The fit's
//! covariance `C = σ̂² (JᵀJ)⁻¹` gives `‖J_j‖² = σ̂² (C⁻¹)_jj`, so
//!
//! ```text
//! u_j = σ̂ · sqrt(VIF_j / N),   VIF_j = C_jj · (C⁻¹)_jj   (the variance inflation factor)
//! ```
//!
//! with no Jacobian kept: one parameter alone (`VIF = 1`) is pinned to `σ̂ / √N`; one the
//! poses barely tell from the others (a joint barely turned, lengths that only add up) has its
//! variance inflated by its correlations. `VIF_j` comes from the correlation matrix
//! `D⁻¹ C D⁻¹` (`D = sqrt(diag C)`), so the parameters' units do not matter.

use std::collections::HashMap;

use nalgebra::DMatrix;

use crate::calibrate::Report;

/// How many times the set's noise floor (the RMS 3-D distance one calibration point is
/// expected to keep from the fitted model, [`crate::calibrate::NoiseFloor::rms`]) a geometric
/// parameter's standard error may reach as a length at the measured points (see the module
/// docs) and still count as identified. Above it the data locate the parameter less well than
/// one measurement locates a point: a change of it that moves the points by more than the noise
/// leaves the fit as good. With `σ̂` at the noise, this is `VIF_j > 3 N (1 − p / 3N)`, i.e. the
/// parameter's variance inflated beyond the residuals' degrees of freedom.
pub const GEOMETRIC_FLOOR_RATIO: f64 = 1.0;

/// The name prefixes of the measurement setup's parameters (the device frame, a session's
/// frame, a target on the tool), not judged by [`Identification::identifies`].
pub const SETUP_PREFIXES: [&str; 3] = ["device.", "session.", "target."];

/// The standard errors of a calibration's free geometric parameters as lengths at the measured
/// points, and the floor they are judged against ([`Identification::identifies`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Identification {
    /// The set's noise floor ([`crate::calibrate::Report::noise_floor`]), else the fit's RMS
    /// 3-D residual ([`crate::calibrate::Report::rms_after`]) (metres); `None`: nothing to
    /// judge by, every parameter counts as identified.
    pub floor: Option<f64>,
    /// Per free parameter of the covariance: `u_j` (metres, see the module docs).
    pub at_points: HashMap<String, f64>,
}

impl Identification {
    /// The judgement of `report`'s free parameters, fitted on `samples` calibration samples.
    /// Empty (every parameter identified) without a covariance or `σ̂`, or when the correlation
    /// matrix is not positive definite.
    pub fn new(report: &Report, samples: usize) -> Self {
        // Without a known noise, the fit's own RMS residual stands for it.
        let floor = report
            .noise_floor
            .as_ref()
            .map(|n| n.rms)
            .or((report.rms_after > 0.0).then_some(report.rms_after));
        let (Some(c), Some(sigma)) = (&report.covariance, report.sigma_hat) else {
            return Self::default();
        };
        let Some(vif) = inflation(&c.matrix) else {
            return Self::default();
        };
        let n = samples.max(1) as f64;
        Identification {
            floor,
            at_points: c
                .parameters
                .iter()
                .cloned()
                .zip(vif.into_iter().map(|v| sigma * (v / n).sqrt()))
                .collect(),
        }
    }

    /// Whether free parameter `name` is identified: its [`Identification::at_points`] within
    /// [`GEOMETRIC_FLOOR_RATIO`] times the floor (true when either is unknown). Only the
    /// robot's parameters are judged: the measurement setup's ([`SETUP_PREFIXES`]) are what
    /// the fit needs to compare, not part of the calibrated robot, and a device frame is often
    /// told from the base's first joint only to within the noise, which says nothing of the robot.
    pub fn identifies(&self, name: &str) -> bool {
        if SETUP_PREFIXES.iter().any(|p| name.starts_with(p)) {
            return true;
        }
        match (self.at_points.get(name), self.floor) {
            (Some(u), Some(floor)) => *u <= GEOMETRIC_FLOOR_RATIO * floor,
            _ => true,
        }
    }
}

/// The variance inflation factor of every parameter of covariance `c`: the diagonal of the
/// inverse of its correlation matrix (1 for a parameter uncorrelated with the others); `None`
/// when a variance is not positive or the correlation matrix is not positive definite.
fn inflation(c: &DMatrix<f64>) -> Option<Vec<f64>> {
    let d: Vec<f64> = c.diagonal().iter().map(|v| v.sqrt()).collect();
    if d.iter().any(|v| !(*v > 0.0 && v.is_finite())) {
        return None;
    }
    let r = DMatrix::from_fn(c.nrows(), c.ncols(), |i, j| c[(i, j)] / (d[i] * d[j]));
    let inverse = r.cholesky()?.inverse();
    Some(inverse.diagonal().iter().copied().collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inflation_is_one_alone_and_grows_with_correlation() {
        // Uncorrelated, whatever the units: 1 each.
        let c = DMatrix::from_row_slice(2, 2, &[4e-6, 0.0, 0.0, 9e-10]);
        let v = inflation(&c).unwrap();
        assert!((v[0] - 1.0).abs() < 1e-12 && (v[1] - 1.0).abs() < 1e-12);
        // Correlation rho: 1 / (1 - rho²) for both.
        let rho: f64 = 0.999;
        let c = DMatrix::from_row_slice(2, 2, &[1e-6, rho * 1e-3 * 2e-5, rho * 1e-3 * 2e-5, 4e-10]);
        let v = inflation(&c).unwrap();
        let expected = 1.0 / (1.0 - rho * rho);
        assert!(v.iter().all(|x| (x / expected - 1.0).abs() < 1e-6), "{v:?}");
        // Perfectly correlated or a zero variance: nothing to judge by.
        assert!(inflation(&DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 1.0, 1.0])).is_none());
        assert!(inflation(&DMatrix::from_row_slice(2, 2, &[0.0, 0.0, 0.0, 1.0])).is_none());
    }
}
