//! Named tolerances for every discrete geometric decision.

use crate::CoreError;

/// Tolerances in physical units that decide whether two joint axes are intersecting, parallel
/// or coincident.
///
/// Two consecutive axes whose angle is within `angular` of 0 or pi are treated as parallel
/// (antiparallel); two axes whose common normal is shorter than `linear` are treated as
/// intersecting (coincident when also parallel). Every such snap changes the kinematics by a
/// bounded amount, which [`crate::extract()`] reports and [`crate::verify`] measures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerance {
    /// Length tolerance in metres.
    pub linear: f64,
    /// Angle tolerance in radians.
    pub angular: f64,
}

impl Tolerance {
    /// Default length tolerance: 10 µm.
    ///
    /// URDF lengths are written to the micrometre at best (rounding ≤ 0.5 µm), and no industrial
    /// arm repeats its pose better than about 10 µm, so a common normal shorter than this is no
    /// link dimension anyone can build or measure.
    pub const DEFAULT_LINEAR: f64 = 1e-5;

    /// Default angle tolerance: 1e-4 rad (0.0057 deg, 21 arc-seconds).
    ///
    /// Hand-written URDFs say `1.5708` for pi/2 (3.7e-6 rad off) and CAD exports round angles to
    /// four decimals (up to 5e-5 rad off); both must read as the parallel or perpendicular axes
    /// the designer meant. `1.57` (8e-4 rad off) is beyond it on purpose: that is a visible tilt,
    /// and the extraction says so loudly instead of hiding it.
    pub const DEFAULT_ANGULAR: f64 = 1e-4;

    /// Builds a tolerance, checking that both values are finite and not negative.
    ///
    /// # Errors
    /// [`CoreError::InvalidTolerance`] when a value is negative, NaN or infinite.
    pub fn new(linear: f64, angular: f64) -> Result<Self, CoreError> {
        for (what, value) in [("linear", linear), ("angular", angular)] {
            if !value.is_finite() || value < 0.0 {
                return Err(CoreError::InvalidTolerance { what, value });
            }
        }
        Ok(Self { linear, angular })
    }

    /// Exact decisions only (both tolerances zero): every near-degenerate pair is kept as it is.
    pub const EXACT: Tolerance = Tolerance {
        linear: 0.0,
        angular: 0.0,
    };
}

impl Default for Tolerance {
    fn default() -> Self {
        Self {
            linear: Self::DEFAULT_LINEAR,
            angular: Self::DEFAULT_ANGULAR,
        }
    }
}

/// Relative size of floating-point noise in a chain's kinematics: deviations below
/// `NOISE_RELATIVE * chain size` are rounding, not geometry, and are never reported.
pub const NOISE_RELATIVE: f64 = 1e-12;
