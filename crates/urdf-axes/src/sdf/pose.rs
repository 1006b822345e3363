//! `<pose>` text and the SDFormat version rules that decide what a pose is relative to.
//!
//! A pose is `x y z roll pitch yaw` (metres, radians; `R = Rz(yaw) Ry(pitch) Rx(roll)`, as
//! URDF's `rpy`), or from SDFormat 1.9 on `degrees="true"` (the angles in degrees) or
//! `rotation_format="quat_xyzw"` (`x y z qx qy qz qw`, normalised). An empty `<pose/>` is the
//! identity. Source: sdformat.org/spec, `//pose` (1.4 to 1.11).

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use roxmltree::Node;

use super::line_of;
use crate::UrdfError;

/// An SDFormat version, `major.minor`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) struct Version(pub u32, pub u32);

impl Version {
    /// SDFormat 1.7 and later: `relative_to`, `<frame attached_to>`, `expressed_in` (the pose
    /// frame semantics of libsdformat 9). Before it a link's pose is relative to its model's
    /// frame, a joint's to its child link's, and `//pose/@frame` had no defined meaning.
    pub fn has_frame_semantics(self) -> bool {
        self >= Version(1, 7)
    }

    /// SDFormat 1.4 and before: a joint's `<axis><xyz>` is expressed in the model frame
    /// (libsdformat's 1.4 to 1.5 conversion adds `use_parent_model_frame true` to every axis).
    pub fn axis_in_model_frame(self) -> bool {
        self <= Version(1, 4)
    }

    /// Reads `version="1.6"`; `None` when absent or not `major.minor`.
    pub fn parse(text: Option<&str>) -> Option<Version> {
        let (major, minor) = text?.trim().split_once('.')?;
        Some(Version(major.parse().ok()?, minor.parse().ok()?))
    }
}

/// The sdformat error of element `node` at its line.
pub(crate) fn sdf_error(node: Node, message: String) -> UrdfError {
    UrdfError::Sdf {
        message,
        line: Some(line_of(node)),
    }
}

/// The numbers of an element's text, every token a finite number.
pub(crate) fn numbers(node: Node, what: &str) -> Result<Vec<f64>, UrdfError> {
    let text = node.text().unwrap_or("");
    text.split_whitespace()
        .map(|t| match t.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(sdf_error(
                node,
                format!("{what}: expected finite numbers, found '{}'", text.trim()),
            )),
        })
        .collect()
}

/// A pose element read: the transform and its `relative_to` (as written, unresolved).
#[derive(Clone, Debug)]
pub(crate) struct Pose {
    /// The transform from the frame it is relative to.
    pub transform: Isometry3<f64>,
    /// `relative_to` as written (1.7+); `None` for the element's default frame.
    pub relative_to: Option<String>,
    /// 1-based line of the `<pose>`, or of its owner when there is none.
    pub line: usize,
}

/// Reads the `<pose>` child of `owner` (the identity when there is none).
///
/// Before 1.7 a `frame` attribute is ignored with a warning (`warn`), as libsdformat 6-8 did;
/// from 1.7 on `relative_to` is kept.
///
/// # Errors
/// [`UrdfError::Sdf`] for a pose that is not 6 numbers (7 with `quat_xyzw`), a zero
/// quaternion, or an unknown `rotation_format`.
pub(crate) fn read_pose(
    owner: Node,
    version: Version,
    warn: &mut dyn FnMut(usize, String),
) -> Result<Pose, UrdfError> {
    let Some(p) = owner.children().find(|c| c.has_tag_name("pose")) else {
        return Ok(Pose {
            transform: Isometry3::identity(),
            relative_to: None,
            line: line_of(owner),
        });
    };
    let line = line_of(p);
    let v = numbers(p, "<pose>")?;
    let format = p.attribute("rotation_format").unwrap_or("euler_rpy");
    let degrees = matches!(p.attribute("degrees").map(str::trim), Some("true" | "1"));
    let transform = match (format, v.as_slice()) {
        (_, []) => Isometry3::identity(),
        ("euler_rpy", &[x, y, z, r, pi, ya]) => {
            let k = if degrees {
                std::f64::consts::PI / 180.0
            } else {
                1.0
            };
            Isometry3::from_parts(
                Translation3::new(x, y, z),
                UnitQuaternion::from_euler_angles(r * k, pi * k, ya * k),
            )
        }
        ("quat_xyzw", &[x, y, z, qx, qy, qz, qw]) => {
            let q = Quaternion::new(qw, qx, qy, qz);
            if q.norm() == 0.0 {
                return Err(sdf_error(
                    p,
                    "<pose>: expected a non-zero quaternion, found 0 0 0 0".into(),
                ));
            }
            Isometry3::from_parts(
                Translation3::new(x, y, z),
                UnitQuaternion::from_quaternion(q),
            )
        }
        ("euler_rpy" | "quat_xyzw", found) => {
            let n = if format == "quat_xyzw" { 7 } else { 6 };
            return Err(sdf_error(
                p,
                format!(
                    "<pose>: expected {n} numbers ({format}), found {}",
                    found.len()
                ),
            ));
        }
        (other, _) => {
            return Err(sdf_error(
                p,
                format!("<pose>: expected rotation_format euler_rpy or quat_xyzw, found '{other}'"),
            ))
        }
    };
    let relative_to = if version.has_frame_semantics() {
        p.attribute("relative_to")
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .map(str::to_owned)
    } else {
        if let Some(f) = p.attribute("frame").filter(|f| !f.trim().is_empty()) {
            warn(
                line,
                format!(
                    "<pose frame='{f}'>: the frame attribute has no meaning before sdformat 1.7; \
                     the pose is taken relative to the element's default frame"
                ),
            );
        }
        None
    };
    Ok(Pose {
        transform,
        relative_to,
        line,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn pose_of(xml: &str, version: Version) -> Result<Pose, UrdfError> {
        let doc = roxmltree::Document::parse(xml).expect("xml");
        read_pose(doc.root_element(), version, &mut |_, _| {})
    }

    #[test]
    fn euler_degrees_and_quaternions_read_as_the_same_pose() {
        let rad = pose_of(
            "<l><pose>1 2 3 0 0 1.5707963267948966</pose></l>",
            Version(1, 9),
        )
        .expect("pose");
        let deg = pose_of(
            "<l><pose degrees='true'>1 2 3 0 0 90</pose></l>",
            Version(1, 9),
        )
        .expect("pose");
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let quat = pose_of(
            &format!("<l><pose rotation_format='quat_xyzw'>1 2 3 0 0 {h} {h}</pose></l>"),
            Version(1, 9),
        )
        .expect("pose");
        for p in [&deg, &quat] {
            assert_relative_eq!(p.transform, rad.transform, epsilon = 1e-15);
        }
        assert_relative_eq!(
            rad.transform.rotation * nalgebra::Vector3::x(),
            nalgebra::Vector3::y(),
            epsilon = 1e-15
        );
    }

    #[test]
    fn malformed_poses_are_errors_naming_the_line() {
        let e = pose_of("<l>\n<pose>1 2 3</pose></l>", Version(1, 7)).expect_err("short");
        assert!(e.to_string().contains("(line 2)"), "{e}");
        assert!(e.to_string().contains("expected 6 numbers"), "{e}");
        assert!(pose_of("<l><pose>1 2 3 0 0 nan</pose></l>", Version(1, 7)).is_err());
        assert!(pose_of(
            "<l><pose rotation_format='x'>0 0 0 0 0 0</pose></l>",
            Version(1, 9)
        )
        .is_err());
    }

    #[test]
    fn relative_to_is_kept_from_1_7_and_frame_warned_before() {
        let p = pose_of(
            "<l><pose relative_to='a'>0 0 0 0 0 0</pose></l>",
            Version(1, 7),
        )
        .expect("pose");
        assert_eq!(p.relative_to.as_deref(), Some("a"));
        let doc =
            roxmltree::Document::parse("<l><pose frame='a'>0 0 0 0 0 0</pose></l>").expect("xml");
        let mut warned = Vec::new();
        let p = read_pose(doc.root_element(), Version(1, 5), &mut |l, m| {
            warned.push((l, m))
        })
        .expect("pose");
        assert_eq!(p.relative_to, None);
        assert_eq!(warned.len(), 1);
    }
}
