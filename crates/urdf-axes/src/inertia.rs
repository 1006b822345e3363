//! The masses a chain's joints carry, from the URDF's `<inertial>` elements, for gravity
//! torques (joint compliance in `dh-calib`).
//!
//! # What is summed
//! For each moving joint of a [`Chain`], the *body* it moves: its child link and every link
//! rigidly attached to it, that is reached from it through joints that are not moving joints of
//! the chain (fixed joints, and joints off the chain taken at zero), up to the next moving
//! joint of the chain. Links before the first moving joint (the fixed base) belong to no joint.
//! A link without `<inertial>` weighs nothing (urdf-rs reads a missing element as mass 0).
//!
//! # Frames
//! The body's centre of mass is given in the joint's child link frame (which moves with it),
//! and in the chain's base link frame with every joint at zero; `dh_calib::gravity::Inertials`
//! takes the latter through `Inertials::from_zero_pose` once the DH rows are named like the
//! joints (as `urdf-dh extract` names them).

use std::collections::HashSet;

use dh_core::pose::from_xyz_rpy;
use nalgebra::{Isometry3, Point3, Vector3};

use crate::{Chain, UrdfError, UrdfModel};

/// The body one moving joint carries (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct JointInertial {
    /// The joint's name.
    pub joint: String,
    /// Total mass of the body (kg).
    pub mass: f64,
    /// Its centre of mass in the joint's child link frame (metres; zero when massless).
    pub com: Vector3<f64>,
    /// Its centre of mass in the chain's base link frame with every joint at zero (metres).
    pub com_at_zero: Vector3<f64>,
}

fn pose_of(origin: &urdf_rs::Pose) -> Isometry3<f64> {
    from_xyz_rpy(origin.xyz.0, origin.rpy.0)
}

/// The body every moving joint of `chain` carries, base to tip (see the module docs).
///
/// # Errors
/// [`UrdfError::NonFinite`] for a negative or non-finite mass or a non-finite inertial origin
/// (named by the joint whose body holds the link).
pub fn joint_inertials(model: &UrdfModel, chain: &Chain) -> Result<Vec<JointInertial>, UrdfError> {
    let robot = model.robot();
    let moving: Vec<&String> = chain
        .joints()
        .iter()
        .filter(|name| {
            robot.joints.iter().any(|j| {
                &j.name == *name
                    && matches!(
                        j.joint_type,
                        urdf_rs::JointType::Revolute
                            | urdf_rs::JointType::Continuous
                            | urdf_rs::JointType::Prismatic
                    )
            })
        })
        .collect();
    let stop: HashSet<&str> = moving.iter().map(|s| s.as_str()).collect();
    // Every link's pose at zero in the base link frame, by walking down from the base.
    let mut at_zero: Vec<(String, Isometry3<f64>)> =
        vec![(chain.base().to_owned(), Isometry3::identity())];
    let mut i = 0;
    while let Some((link, pose)) = at_zero.get(i).cloned() {
        for j in robot.joints.iter().filter(|j| j.parent.link == link) {
            if !at_zero.iter().any(|(l, _)| *l == j.child.link) {
                at_zero.push((j.child.link.clone(), pose * pose_of(&j.origin)));
            }
        }
        i += 1;
    }
    let zero_pose = |link: &str| {
        at_zero
            .iter()
            .find(|(l, _)| l == link)
            .map_or_else(Isometry3::identity, |(_, p)| *p)
    };
    let mut out = Vec::with_capacity(moving.len());
    for name in moving {
        let Some(joint) = robot.joints.iter().find(|j| &j.name == name) else {
            continue;
        };
        let child = joint.child.link.as_str();
        // The body: links reached from the child link without crossing a chain joint.
        let mut body: Vec<(&str, Isometry3<f64>)> = vec![(child, Isometry3::identity())];
        let mut k = 0;
        while let Some(&(link, pose)) = body.get(k) {
            for j in robot
                .joints
                .iter()
                .filter(|j| j.parent.link == link && !stop.contains(j.name.as_str()))
            {
                body.push((j.child.link.as_str(), pose * pose_of(&j.origin)));
            }
            k += 1;
        }
        let mut mass = 0.0;
        let mut moment = Vector3::zeros();
        for (link, pose) in body {
            let Some(l) = robot.links.iter().find(|l| l.name == link) else {
                continue;
            };
            let m = l.inertial.mass.value;
            let c = l.inertial.origin.xyz.0;
            if !(m.is_finite() && m >= 0.0) {
                return Err(UrdfError::NonFinite {
                    joint: name.clone(),
                    what: "inertial mass of a link it carries (expected >= 0)",
                    value: m,
                    line: model.link_line(link),
                });
            }
            if let Some(v) = c.iter().find(|v| !v.is_finite()) {
                return Err(UrdfError::NonFinite {
                    joint: name.clone(),
                    what: "inertial origin of a link it carries",
                    value: *v,
                    line: model.link_line(link),
                });
            }
            moment += (pose * Point3::from(Vector3::from(c))).coords * m;
            mass += m;
        }
        let com = if mass > 0.0 {
            moment / mass
        } else {
            Vector3::zeros()
        };
        let com_at_zero = (zero_pose(child) * Point3::from(com)).coords;
        out.push(JointInertial {
            joint: name.clone(),
            mass,
            com,
            com_at_zero,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    const ARM: &str = r#"<robot name="arm">
      <link name="base"><inertial><origin xyz="0 0 0.1"/><mass value="9"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
      <link name="l1"><inertial><origin xyz="0 0 0.2"/><mass value="2"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
      <link name="l2"><inertial><origin xyz="0.25 0 0"/><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
      <link name="tool"><inertial><origin xyz="0 0 0"/><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
      <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><origin xyz="0 0 0.3"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
      <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0 0 0.4" rpy="0 0 1.5707963267948966"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
      <joint name="t" type="fixed"><parent link="l2"/><child link="tool"/><origin xyz="0.5 0 0"/></joint>
    </robot>"#;

    #[test]
    fn bodies_stop_at_chain_joints_and_take_fixed_links() {
        let m = UrdfModel::parse(ARM).unwrap();
        let c = m.chain(None, None).unwrap();
        let b = joint_inertials(&m, &c).unwrap();
        assert_eq!(b.len(), 2);
        assert_eq!(b[0].joint, "j1");
        assert!((b[0].mass - 2.0).abs() < 1e-12);
        assert!((b[0].com - Vector3::new(0.0, 0.0, 0.2)).norm() < 1e-12);
        assert!((b[0].com_at_zero - Vector3::new(0.0, 0.0, 0.5)).norm() < 1e-12);
        // l2 (1 kg at x = 0.25) with the tool (1 kg at x = 0.5): centre at x = 0.375 in l2,
        // which sits at z = 0.7 turned 90 degrees about z, so at y = 0.375 in the base.
        assert!((b[1].mass - 2.0).abs() < 1e-12);
        assert!((b[1].com - Vector3::new(0.375, 0.0, 0.0)).norm() < 1e-12);
        assert!((b[1].com_at_zero - Vector3::new(0.0, 0.375, 0.7)).norm() < 1e-9);
    }
}
