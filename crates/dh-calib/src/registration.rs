//! Rigid registration of two point sets (Kabsch, "A solution for the best rotation to relate
//! two sets of vectors", Acta Cryst. A32, 1976; the reflection guard of Umeyama, IEEE PAMI
//! 13(4), 1991): the closed-form device frame of a calibration's start and of each measurement
//! session. Points in metres, in any two frames.

use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};

use crate::fit::CalibError;

/// Rigid registration: the `T` minimising `Σ ‖T·a_i − b_i‖²` (Kabsch 1976, with the reflection
/// guard of Umeyama 1991).
///
/// # Errors
/// [`CalibError::TooFewSamples`] for fewer than 3 pairs, [`CalibError::Degenerate`] when the
/// points are collinear.
pub fn register(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> Result<Isometry3<f64>, CalibError> {
    if a.len() != b.len() || a.len() < 3 {
        return Err(CalibError::TooFewSamples {
            what: "rigid registration".into(),
            needed: 3,
            found: a.len().min(b.len()),
        });
    }
    let n = a.len() as f64;
    let ca = a.iter().sum::<Vector3<f64>>() / n;
    let cb = b.iter().sum::<Vector3<f64>>() / n;
    let mut h = Matrix3::zeros();
    for (p, q) in a.iter().zip(b) {
        h += (p - ca) * (q - cb).transpose();
    }
    let svd = h.svd(true, true);
    let (Some(u), Some(vt)) = (svd.u, svd.v_t) else {
        return Err(CalibError::Degenerate {
            what: "rigid registration".into(),
        });
    };
    let s = svd.singular_values;
    let smax = s.max();
    let mut sorted = [s[0], s[1], s[2]];
    sorted.sort_by(|x, y| y.total_cmp(x));
    if smax.is_nan() || smax <= 0.0 || sorted[1] <= 1e-12 * smax {
        return Err(CalibError::Degenerate {
            what: "rigid registration".into(),
        });
    }
    let v = vt.transpose();
    let det = (v * u.transpose()).determinant();
    let d = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, det.signum()));
    let r = v * d * u.transpose();
    let rot = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
    let t = cb - rot * ca;
    Ok(Isometry3::from_parts(Translation3::from(t), rot))
}
