//! The orientation columns of a 6-DoF device: `qw`, `qx`, `qy`, `qz` (a unit quaternion,
//! scalar first, the rotation of the target frame in the device frame) and `sigma_rot` (the
//! standard deviation of each component of the rotation vector, radians).

use nalgebra::{Quaternion, UnitQuaternion};

use super::*;
use crate::data::Orientation;

/// The quaternion columns, scalar first.
pub const QUATERNION_COLUMNS: [&str; 4] = ["qw", "qx", "qy", "qz"];

/// How far from 1 a quaternion's norm may be (dimensionless): exports round each component
/// to 6 or 7 digits, which moves the norm by about 1e-6; a norm off by more than this is not
/// rounding but a wrong column or unit, and the row is refused. Within it the quaternion is
/// normalised.
pub const QUATERNION_NORM_TOLERANCE: f64 = 1e-3;

/// Largest plausible `sigma_rot` (radians): a standard deviation of a radian says nothing.
const MAX_SIGMA_ROT: f64 = 1.0;

/// What a `sigma_rot` of 0 is floored at (radians): a device that rounds its angles (to a
/// microradian) gives 0 for the standard deviation of a rounded value; the fit divides by it.
pub const SIGMA_ROT_FLOOR: f64 = 1e-6;

/// Column indices of `qw`, `qx`, `qy`, `qz` and `sigma_rot`.
pub(super) struct OrientationColumns {
    quaternion: [usize; 4],
    sigma: usize,
}

/// The orientation columns of a header, `None` when it has none of `qw`, `qx`, `qy`, `qz`.
///
/// # Errors
/// [`DataError::MissingCoordinate`] when some of the four are there but not all, or
/// `sigma_rot` is missing.
pub(super) fn orientation_columns(
    line: usize,
    find: &impl Fn(&str) -> Option<usize>,
    names: &[String],
) -> Result<Option<OrientationColumns>, DataError> {
    if QUATERNION_COLUMNS.iter().all(|c| find(c).is_none()) {
        return Ok(None);
    }
    let column = |column: &'static str| {
        find(column).ok_or_else(|| DataError::MissingCoordinate {
            line,
            column,
            found: names.to_vec(),
        })
    };
    let mut quaternion = [0; 4];
    for (slot, c) in quaternion.iter_mut().zip(QUATERNION_COLUMNS) {
        *slot = column(c)?;
    }
    Ok(Some(OrientationColumns {
        quaternion,
        sigma: column("sigma_rot")?,
    }))
}

/// The rotation of the quaternion `[w, x, y, z]` read from `columns` at `line`, normalised.
///
/// # Errors
/// [`DataError::Format`] when its norm is more than [`QUATERNION_NORM_TOLERANCE`] from 1.
pub fn unit_quaternion(
    v: [f64; 4],
    line: usize,
    columns: &str,
) -> Result<UnitQuaternion<f64>, DataError> {
    let q = Quaternion::new(v[0], v[1], v[2], v[3]);
    let norm = q.norm();
    if (norm - 1.0).abs() > QUATERNION_NORM_TOLERANCE {
        return Err(DataError::Format {
            line,
            expected: format!(
                "a unit quaternion in columns {columns} (norm within \
                 {QUATERNION_NORM_TOLERANCE} of 1)"
            ),
            found: format!("norm {norm}"),
        });
    }
    Ok(UnitQuaternion::from_quaternion(q))
}

/// The orientation of one row, `None` when its four quaternion cells are empty (a point), and
/// whether its `sigma_rot` of 0 was floored at [`SIGMA_ROT_FLOOR`].
///
/// # Errors
/// [`DataError::Format`] naming the line and columns when some quaternion cells are empty,
/// the norm is more than [`QUATERNION_NORM_TOLERANCE`] from 1, or `sigma_rot` is empty,
/// negative or above a radian; [`DataError::NotANumber`] / [`DataError::NonFinite`] for a
/// cell that is not a finite number.
pub(super) fn orientation_cells<'a>(
    cols: &OrientationColumns,
    line: usize,
    cell: &impl Fn(usize) -> &'a str,
    name: &impl Fn(usize) -> &'a str,
) -> Result<Option<(Orientation, bool)>, DataError> {
    let empty = cols.quaternion.map(|c| cell(c).is_empty());
    if empty.iter().all(|e| *e) {
        return Ok(None);
    }
    if let Some(k) = empty.iter().position(|e| *e) {
        return Err(DataError::Format {
            line,
            expected: "all of qw, qx, qy, qz or none".into(),
            found: format!("an empty '{}'", name(cols.quaternion[k])),
        });
    }
    let mut v = [0.0; 4];
    for (slot, &c) in v.iter_mut().zip(&cols.quaternion) {
        *slot = number(cell(c), line, name(c))?;
    }
    let rotation = unit_quaternion(v, line, "qw, qx, qy, qz")?;
    let s = cols.sigma;
    if cell(s).is_empty() {
        return Err(DataError::Format {
            line,
            expected: "a standard deviation in column 'sigma_rot' (radians) for an orientation"
                .into(),
            found: "an empty cell".into(),
        });
    }
    let sigma = number(cell(s), line, name(s))?;
    let (sigma, floored) = floored_sigma_rot(sigma).ok_or_else(|| DataError::Format {
        line,
        expected: sigma_rot_expected(sigma, "in column 'sigma_rot'"),
        found: format!("'{}'", cell(s)),
    })?;
    Ok(Some((Orientation { rotation, sigma }, floored)))
}

/// What a refused `sigma_rot` should have been (`place`: where it is): a positive value below
/// [`crate::MIN_SIGMA`] is told so, any other the whole range.
pub(crate) fn sigma_rot_expected(sigma: f64, place: &str) -> String {
    if sigma > 0.0 && sigma < crate::MIN_SIGMA {
        format!(
            "a standard deviation of 0 (floored) or at least {:e} rad {place}",
            crate::MIN_SIGMA
        )
    } else {
        format!("a standard deviation >= 0 and <= {MAX_SIGMA_ROT} rad {place}")
    }
}

/// A `sigma_rot` (radians) as the fit takes it, and whether it was 0 and floored at
/// [`SIGMA_ROT_FLOOR`]; `None` when it is neither 0 nor in `[MIN_SIGMA, 1]` rad (negative,
/// NaN, below a nanoradian, above a radian: see [`crate::MIN_SIGMA`]).
pub(crate) fn floored_sigma_rot(sigma: f64) -> Option<(f64, bool)> {
    if !(sigma == 0.0 || (crate::MIN_SIGMA..=MAX_SIGMA_ROT).contains(&sigma)) {
        return None;
    }
    Some(if sigma == 0.0 {
        (SIGMA_ROT_FLOOR, true)
    } else {
        (sigma, false)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `sigma_rot` is 0 (floored) or in [1e-9, 1] rad: a subnormal or 1e-300 would make the
    /// chi-square infinite (issue 30).
    #[test]
    fn sigma_rot_is_zero_or_at_least_a_nanoradian() {
        assert_eq!(floored_sigma_rot(0.0), Some((SIGMA_ROT_FLOOR, true)));
        assert_eq!(floored_sigma_rot(1e-9), Some((1e-9, false)));
        assert_eq!(floored_sigma_rot(1.0), Some((1.0, false)));
        for bad in [1e-300, 5e-324, 9.9e-10, -1e-6, 1.5, f64::NAN] {
            assert_eq!(floored_sigma_rot(bad), None, "{bad}");
        }
    }
}
