//! Keeping the extraction's numbers: the walking DH frame put back on its axis when its
//! rounding drifts ([`reanchor`]), and a table that lost all precision refused where it is born
//! ([`check_extracted_finite`]).

use nalgebra::{Isometry3, Vector3};

use crate::pose::from_axes;
use crate::table::DhTable;
use crate::{CoreError, Line};

/// Drift of the walking frame from the axis it should lie on (radians of its z axis, and its
/// origin's distance in units of the input scale) beyond which it is put back on that axis
/// ([`reanchor`]): a thousand rounding units. A frame advanced row by row carries the rounding
/// of every row before it, and on a long chain of skew axes each step amplifies what it
/// receives (the feet of a common normal move by the error over the sine of the pair's
/// angle): a helix of axes 0.3 rad apart grew it about 1.3x per joint, failing its proof at 80
/// joints and reaching NaN at 103. Below this the frame is left as advanced, so that
/// well-conditioned chains keep their values to the bit.
pub(super) const REANCHOR_DRIFT: f64 = 1e3 * f64::EPSILON;

/// `frame` (a DH frame whose z axis should be `line`, in the same coordinates) moved onto
/// `line` when it has drifted from it by more than [`REANCHOR_DRIFT`]: z along the line's
/// direction (with the frame's sense), the origin at its foot on the line, x made orthogonal
/// to the new z. `scale` (metres) turns the relative drift into a distance.
pub(super) fn reanchor(frame: Isometry3<f64>, line: &Line, scale: f64) -> Isometry3<f64> {
    let z = frame.rotation * Vector3::z();
    let origin = frame.translation.vector;
    let e = line.direction();
    let e = if z.dot(&e) < 0.0 { -e } else { e };
    let foot = line.foot_of(&origin);
    let tilt = (z - e).norm();
    let shift = (origin - foot).norm();
    if tilt <= REANCHOR_DRIFT && shift <= REANCHOR_DRIFT * scale {
        return frame;
    }
    let x = frame.rotation * Vector3::x();
    let x = (x - e * x.dot(&e)).normalize();
    from_axes(foot, x, e)
}

/// Refuses a table with a value that is not a finite number, naming the first joint whose
/// parameters, or the base or tool, are lost, so that no writer carries NaN (JSON `null`). A
/// guard: the frames of a long chain of skew axes once grew their rounding about 1.3x per joint
/// (NaN at joint 103 of a helix of axes 0.3 rad apart), which [`reanchor`] now stops.
pub(super) fn check_extracted_finite(table: &DhTable) -> Result<(), CoreError> {
    let lost = |what: String, value: f64| CoreError::NonFinite {
        what: format!(
            "{what} (the chain's frames lost all precision: a chain too long or too \
             ill-conditioned for double precision)"
        ),
        value,
    };
    for r in &table.rows {
        for (field, v) in [
            ("a", r.a),
            ("alpha", r.alpha),
            ("d", r.d),
            ("theta", r.theta),
        ] {
            if !v.is_finite() {
                return Err(lost(format!("joint '{}': {field}", r.name), v));
            }
        }
    }
    for (what, pose) in [("base", &table.base), ("tool", &table.tool)] {
        let values = pose
            .translation
            .vector
            .iter()
            .chain(pose.rotation.coords.iter());
        if let Some(v) = values.copied().find(|v| !v.is_finite()) {
            return Err(lost(what.to_string(), v));
        }
    }
    Ok(())
}
