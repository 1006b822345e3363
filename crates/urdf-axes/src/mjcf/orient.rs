//! Numbers, `<compiler>` settings and frames of MJCF: `pos` with one of `quat`, `axisangle`,
//! `euler`, `xyaxes` or `zaxis`, converted as MuJoCo's compiler converts them
//! (mujoco `src/user/user_util.cc`: `mjuu_frame2quat`, `mjuu_z2quat`, and the euler loop of
//! `mjsFrame`/`ResolveOrientation`). Lengths in metres; angles in the unit `<compiler angle>`
//! names (MuJoCo's default is degrees), converted to radians here.

use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, Unit, UnitQuaternion, Vector3};

use super::error::MjcfError;
use super::xml::Node;

/// Smallest norm of a vector MuJoCo normalizes (an axis, a quaternion, an `xyaxes` or `zaxis`
/// vector); below it the compiler refuses the model (`mjEPS`, 1e-14, in `user_util.cc`).
pub(crate) const MIN_NORM: f64 = 1e-14;

/// The `<compiler>` settings that change kinematics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Compiler {
    /// Angles in degrees (`angle="degree"`, MuJoCo's default) rather than radians.
    pub degree: bool,
    /// `eulerseq`: three of `xyzXYZ`; lowercase rotates about the moving (intrinsic) axes,
    /// uppercase about the fixed (extrinsic) ones.
    pub eulerseq: [u8; 3],
    /// `autolimits` (default true): a joint with a `range` and `limited="auto"` is limited.
    pub autolimits: bool,
}

impl Default for Compiler {
    fn default() -> Self {
        Compiler {
            degree: true,
            eulerseq: *b"xyz",
            autolimits: true,
        }
    }
}

impl Compiler {
    /// Applies one `<compiler>` element (MuJoCo applies every one, in document order).
    pub fn apply(&mut self, e: &Node) -> Result<(), MjcfError> {
        if let Some(a) = e.attr("angle") {
            self.degree = match a {
                "degree" => true,
                "radian" => false,
                other => {
                    return Err(e.error(format!(
                        "attribute 'angle': expected 'degree' or 'radian', found '{other}'"
                    )))
                }
            };
        }
        if let Some(s) = e.attr("eulerseq") {
            let b = s.as_bytes();
            match b {
                [x, y, z] if b.iter().all(|c| b"xyzXYZ".contains(c)) => {
                    self.eulerseq = [*x, *y, *z]
                }
                _ => {
                    return Err(e.error(format!(
                        "attribute 'eulerseq': expected three of x, y, z, X, Y, Z, found '{s}'"
                    )))
                }
            }
        }
        if let Some(a) = e.attr("autolimits") {
            self.autolimits = boolean(e, "autolimits", a)?;
        }
        if let Some(c) = e.attr("coordinate") {
            if c != "local" {
                return Err(e.error(format!(
                    "attribute 'coordinate': expected 'local' (MuJoCo removed 'global' in 2.3.3), found '{c}'"
                )));
            }
        }
        Ok(())
    }

    /// An angle of the document in radians.
    pub fn radians(&self, angle: f64) -> f64 {
        if self.degree {
            angle.to_radians()
        } else {
            angle
        }
    }
}

/// `true` or `false`.
pub(crate) fn boolean(e: &Node, attr: &str, value: &str) -> Result<bool, MjcfError> {
    match value {
        "true" => Ok(true),
        "false" => Ok(false),
        other => Err(e.error(format!(
            "attribute '{attr}': expected 'true' or 'false', found '{other}'"
        ))),
    }
}

/// `N` finite numbers from the text `value` of attribute `attr` of `e`.
pub(crate) fn numbers<const N: usize>(
    e: &Node,
    attr: &str,
    value: &str,
) -> Result<[f64; N], MjcfError> {
    let bad = || {
        e.error(format!(
            "attribute '{attr}': expected {N} finite numbers, found '{}'",
            value.trim()
        ))
    };
    let mut out = [0.0; N];
    let mut count = 0;
    for t in value.split_whitespace() {
        let x: f64 = t.parse().map_err(|_| bad())?;
        if !x.is_finite() {
            return Err(bad());
        }
        *out.get_mut(count).ok_or_else(bad)? = x;
        count += 1;
    }
    if count == N {
        Ok(out)
    } else {
        Err(bad())
    }
}

/// `N` numbers of attribute `attr` of `e`, `None` when absent.
pub(crate) fn attr_numbers<const N: usize>(
    e: &Node,
    attr: &str,
) -> Result<Option<[f64; N]>, MjcfError> {
    e.attr(attr).map(|v| numbers::<N>(e, attr, v)).transpose()
}

/// The unit vector of `v`, refused below [`MIN_NORM`] as MuJoCo refuses it.
pub(crate) fn unit(e: &Node, attr: &str, v: [f64; 3]) -> Result<Unit<Vector3<f64>>, MjcfError> {
    let v = Vector3::from(v);
    let n = v.norm();
    if n < MIN_NORM {
        return Err(e.error(format!(
            "attribute '{attr}': expected a vector of nonzero length, found {} {} {}",
            v.x, v.y, v.z
        )));
    }
    Ok(Unit::new_unchecked(v / n))
}

/// The pose of element `e` in its parent's frame: `pos` (default 0) and its orientation.
pub(crate) fn pose(e: &Node, c: &Compiler) -> Result<Isometry3<f64>, MjcfError> {
    let pos = attr_numbers::<3>(e, "pos")?.unwrap_or_default();
    Ok(Isometry3::from_parts(
        Translation3::from(Vector3::from(pos)),
        orientation(e, c)?,
    ))
}

/// The orientation of `e`: at most one of `quat` (w x y z, normalized), `axisangle`, `euler`,
/// `xyaxes` and `zaxis`; the identity without any.
pub(crate) fn orientation(e: &Node, c: &Compiler) -> Result<UnitQuaternion<f64>, MjcfError> {
    const KEYS: [&str; 5] = ["quat", "axisangle", "euler", "xyaxes", "zaxis"];
    let given: Vec<&str> = KEYS
        .iter()
        .copied()
        .filter(|k| e.attr(k).is_some())
        .collect();
    match given.as_slice() {
        [] => Ok(UnitQuaternion::identity()),
        [key] => {
            let value = e.attr(key).unwrap_or_default();
            match *key {
                "quat" => {
                    let [w, x, y, z] = numbers::<4>(e, key, value)?;
                    let q = nalgebra::Quaternion::new(w, x, y, z);
                    if q.norm() < MIN_NORM {
                        return Err(e.error(format!(
                            "attribute 'quat': expected a quaternion of nonzero norm, found '{}'",
                            value.trim()
                        )));
                    }
                    Ok(UnitQuaternion::from_quaternion(q))
                }
                "axisangle" => {
                    let [x, y, z, a] = numbers::<4>(e, key, value)?;
                    let axis = unit(e, key, [x, y, z])?;
                    Ok(UnitQuaternion::from_axis_angle(&axis, c.radians(a)))
                }
                "euler" => {
                    let angles = numbers::<3>(e, key, value)?;
                    Ok(euler(c, angles))
                }
                "xyaxes" => {
                    let [x0, x1, x2, y0, y1, y2] = numbers::<6>(e, key, value)?;
                    let x = unit(e, key, [x0, x1, x2])?;
                    let y = Vector3::new(y0, y1, y2);
                    let y = y - x.into_inner() * x.dot(&y);
                    let y = unit(e, key, y.into())?;
                    let z = x.cross(&y);
                    let m = Matrix3::from_columns(&[x.into_inner(), y.into_inner(), z]);
                    Ok(UnitQuaternion::from_rotation_matrix(
                        &Rotation3::from_matrix_unchecked(m),
                    ))
                }
                _ => {
                    let z = unit(e, key, numbers::<3>(e, key, value)?)?;
                    Ok(z_to_quat(&z))
                }
            }
        }
        several => Err(e.error(format!(
            "expected at most one orientation attribute, found {}",
            several.join(", ")
        ))),
    }
}

/// `euler` angles (in the compiler's unit) in the order of `eulerseq`: a lowercase axis
/// multiplies on the right (moving axes), an uppercase one on the left (fixed axes).
fn euler(c: &Compiler, angles: [f64; 3]) -> UnitQuaternion<f64> {
    let mut q = UnitQuaternion::identity();
    for (&axis, angle) in c.eulerseq.iter().zip(angles) {
        let v = match axis.to_ascii_lowercase() {
            b'x' => Vector3::x_axis(),
            b'y' => Vector3::y_axis(),
            _ => Vector3::z_axis(),
        };
        let r = UnitQuaternion::from_axis_angle(&v, c.radians(angle));
        q = if axis.is_ascii_lowercase() {
            q * r
        } else {
            r * q
        };
    }
    q
}

/// Below this sine of the angle between `zaxis` and z, MuJoCo's `mjuu_z2quat` takes the x axis
/// as the rotation axis.
const Z_PARALLEL: f64 = 1e-10;

/// The shortest rotation taking the z axis to `z` (MuJoCo's `mjuu_z2quat`: a half turn about x
/// when `z` points down).
fn z_to_quat(z: &Unit<Vector3<f64>>) -> UnitQuaternion<f64> {
    let cross = Vector3::z().cross(z);
    let s = cross.norm();
    let axis = if s < Z_PARALLEL {
        Vector3::x_axis()
    } else {
        Unit::new_unchecked(cross / s)
    };
    UnitQuaternion::from_axis_angle(&axis, s.atan2(z.z))
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use std::f64::consts::FRAC_PI_2;

    fn node(attrs: &[(&str, &str)]) -> Node {
        Node {
            name: "body".into(),
            attrs: attrs
                .iter()
                .map(|(k, v)| ((*k).into(), (*v).into()))
                .collect(),
            children: vec![],
            line: 3,
            file: None,
        }
    }

    fn radian() -> Compiler {
        Compiler {
            degree: false,
            ..Compiler::default()
        }
    }

    #[test]
    fn each_orientation_form_gives_the_same_quarter_turn_about_z() {
        let want = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), FRAC_PI_2);
        let deg = Compiler::default();
        for (attrs, c) in [
            (vec![("quat", "1 0 0 1")], radian()),
            (vec![("axisangle", "0 0 2 90")], deg),
            (vec![("euler", "0 0 1.5707963267948966")], radian()),
            (vec![("xyaxes", "0 1 0 -1 0.5 0")], radian()),
        ] {
            let q = orientation(&node(&attrs), &c).unwrap();
            assert_relative_eq!(q, want, epsilon = 1e-15);
        }
        // zaxis: the shortest rotation taking z to x is a quarter turn about y.
        let q = orientation(&node(&[("zaxis", "3 0 0")]), &deg).unwrap();
        assert_relative_eq!(q * Vector3::z(), Vector3::x(), epsilon = 1e-15);
        let down = orientation(&node(&[("zaxis", "0 0 -1")]), &deg).unwrap();
        assert_relative_eq!(down * Vector3::y(), -Vector3::y(), epsilon = 1e-15);
    }

    #[test]
    fn euler_sequences_are_intrinsic_in_lowercase_and_extrinsic_in_uppercase() {
        let a = [0.3, -0.4, 1.1];
        let r = |v: Unit<Vector3<f64>>, t: f64| UnitQuaternion::from_axis_angle(&v, t);
        let (x, y, z) = (Vector3::x_axis(), Vector3::y_axis(), Vector3::z_axis());
        let mut c = radian();
        assert_relative_eq!(
            euler(&c, a),
            r(x, a[0]) * r(y, a[1]) * r(z, a[2]),
            epsilon = 1e-15
        );
        c.eulerseq = *b"XYZ";
        assert_relative_eq!(
            euler(&c, a),
            r(z, a[2]) * r(y, a[1]) * r(x, a[0]),
            epsilon = 1e-15
        );
        c.eulerseq = *b"zYx";
        assert_relative_eq!(
            euler(&c, a),
            r(y, a[1]) * r(z, a[0]) * r(x, a[2]),
            epsilon = 1e-15
        );
    }

    #[test]
    fn bad_orientations_are_refused_naming_the_element_and_line() {
        let c = Compiler::default();
        let e = orientation(&node(&[("quat", "0 0 0 0")]), &c).unwrap_err();
        assert_eq!(
            e.to_string(),
            "<body> (line 3): attribute 'quat': expected a quaternion of nonzero norm, found '0 0 0 0'"
        );
        let e = orientation(&node(&[("quat", "1 0 0"), ("euler", "0 0 0")]), &c).unwrap_err();
        assert!(
            e.to_string()
                .contains("expected at most one orientation attribute, found quat, euler"),
            "{e}"
        );
        let e = orientation(&node(&[("xyaxes", "1 0 0 2 0 0")]), &c).unwrap_err();
        assert!(e.to_string().contains("nonzero length"), "{e}");
        let e = pose(&node(&[("pos", "1 nan 0")]), &c).unwrap_err();
        assert!(
            e.to_string()
                .contains("expected 3 finite numbers, found '1 nan 0'"),
            "{e}"
        );
    }
}
