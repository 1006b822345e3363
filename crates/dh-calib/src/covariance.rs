//! The covariance of a calibration's free parameters ([`Covariance`]): what a calibration
//! reports and [`crate::predict`] propagates. Parameters by name (see [`crate::model`]), each in
//! its own unit (metres, radians, an effect's unit).

use nalgebra::DMatrix;

use crate::fit::CalibError;

/// Relative asymmetry a covariance may have (it is written to 17 digits and read back).
const SYMMETRY_TOLERANCE: f64 = 1e-9;

/// The covariance of a calibration's free parameters, by name, in their own units (metres,
/// radians, an effect's unit); parameter names as in [`crate::model`].
#[derive(Clone, Debug, PartialEq)]
pub struct Covariance {
    /// The parameters, in the matrix's order.
    pub parameters: Vec<String>,
    /// Symmetric, positive semi-definite.
    pub matrix: DMatrix<f64>,
}

impl Covariance {
    /// Checks and builds a covariance.
    ///
    /// # Errors
    /// [`CalibError::BadOption`] for a matrix that is not square, not of the names' size, not
    /// finite, not symmetric or has a negative variance, or for a name given twice.
    pub fn new(parameters: Vec<String>, matrix: DMatrix<f64>) -> Result<Self, CalibError> {
        let bad = |reason: String| CalibError::BadOption {
            what: "covariance".into(),
            reason,
        };
        let n = parameters.len();
        if matrix.nrows() != n || matrix.ncols() != n {
            return Err(bad(format!(
                "expected a {n} x {n} matrix for {n} parameters, found {} x {}",
                matrix.nrows(),
                matrix.ncols()
            )));
        }
        if let Some(v) = matrix.iter().find(|v| !v.is_finite()) {
            return Err(bad(format!("expected finite values, found {v}")));
        }
        for (i, p) in parameters.iter().enumerate() {
            if parameters[..i].contains(p) {
                return Err(bad(format!("parameter '{p}' is given twice")));
            }
            if matrix[(i, i)] < 0.0 {
                return Err(bad(format!(
                    "expected a non-negative variance of '{p}', found {}",
                    matrix[(i, i)]
                )));
            }
        }
        let largest = matrix.amax();
        for i in 0..n {
            for j in 0..i {
                if (matrix[(i, j)] - matrix[(j, i)]).abs() > SYMMETRY_TOLERANCE * largest {
                    return Err(bad(format!(
                        "expected a symmetric matrix, found {} and {} at '{}' x '{}'",
                        matrix[(i, j)],
                        matrix[(j, i)],
                        parameters[i],
                        parameters[j]
                    )));
                }
            }
        }
        Ok(Covariance { parameters, matrix })
    }

    /// The standard uncertainty of each parameter, in the order of [`Covariance::parameters`].
    pub fn std_errors(&self) -> Vec<f64> {
        (0..self.parameters.len())
            .map(|i| self.matrix[(i, i)].max(0.0).sqrt())
            .collect()
    }

    /// The covariance of the parameters a prediction in one measurement session uses. A
    /// calibration of several sessions estimates the first session's device frame
    /// (`device.*`) and every other's (`session.<name>.*`, see [`crate::sessions`]): `None`
    /// keeps the first's, `Some(name)` takes session `name`'s as the device frame's (renamed
    /// `device.*`, the same six small motions). The other sessions' frames are left out, which
    /// is exact for a Gaussian (their rows and columns dropped: the marginal covariance).
    pub fn in_session(&self, session: Option<&str>) -> Covariance {
        let prefix = session.map(|n| format!("session.{n}."));
        let kept: Vec<(usize, String)> = self
            .parameters
            .iter()
            .enumerate()
            .filter_map(|(i, name)| {
                if name.starts_with("session.") {
                    let rest = name.strip_prefix(prefix.as_deref()?)?;
                    Some((i, format!("device.{rest}")))
                } else if name.starts_with("device.") {
                    session.is_none().then(|| (i, name.clone()))
                } else {
                    Some((i, name.clone()))
                }
            })
            .collect();
        Covariance {
            parameters: kept.iter().map(|(_, n)| n.clone()).collect(),
            matrix: DMatrix::from_fn(kept.len(), kept.len(), |a, b| {
                self.matrix[(kept[a].0, kept[b].0)]
            }),
        }
    }
}
