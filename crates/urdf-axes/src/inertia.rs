//! The masses a chain's joints carry, from the URDF's `<inertial>` elements, for gravity
//! torques (joint compliance in `dh-calib`).
//!
//! # What is summed
//! For each moving joint of a [`Chain`], the *body* it moves: its child link and every link
//! rigidly attached to it, that is reached from it through joints that are not moving joints of
//! the chain (fixed joints, and joints off the chain taken at zero), up to the next moving
//! joint of the chain. Links before the first moving joint (the fixed base) belong to no joint.
//! A link without `<inertial>` weighs nothing.
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

/// The body every moving joint of `chain` carries, base to tip (see the module docs).
/// Linear in the number of links.
///
/// # Errors
/// [`UrdfError::NonFinite`] for a negative or non-finite mass, a non-finite inertial origin,
/// a malformed `<inertial>` (its reading warned; here its mass is needed) or a non-finite
/// origin of a joint inside a body (named by the joint whose body holds the link).
pub fn joint_inertials(model: &UrdfModel, chain: &Chain) -> Result<Vec<JointInertial>, UrdfError> {
    let robot = &model.robot;
    let moving: Vec<usize> = chain
        .joints()
        .iter()
        .filter_map(|name| model.joint_index_of(name))
        .filter(|&k| {
            robot
                .joints
                .get(k)
                .and_then(|j| j.kind)
                .is_some_and(|t| t.is_moving())
        })
        .collect();
    let stop: HashSet<usize> = moving.iter().copied().collect();
    let Some(base) = model.link_index_of(chain.base()) else {
        return Ok(Vec::new());
    };
    let origin_of = |k: usize| {
        robot.joints.get(k).map_or_else(Isometry3::identity, |j| {
            from_xyz_rpy(j.origin.xyz, j.origin.rpy)
        })
    };
    // Every link's pose at zero in the base link frame, by walking down from the base.
    let n = model.child_joints.len();
    let mut at_zero: Vec<Option<Isometry3<f64>>> = vec![None; n];
    if let Some(slot) = at_zero.get_mut(base) {
        *slot = Some(Isometry3::identity());
    }
    let mut queue = vec![base];
    while let Some(link) = queue.pop() {
        let pose = at_zero
            .get(link)
            .copied()
            .flatten()
            .unwrap_or_else(Isometry3::identity);
        for &k in model
            .child_joints
            .get(link)
            .map(Vec::as_slice)
            .unwrap_or(&[])
        {
            if let Some(&c) = model.joint_child.get(k) {
                if let Some(slot) = at_zero.get_mut(c) {
                    *slot = Some(pose * origin_of(k));
                }
                queue.push(c);
            }
        }
    }
    let mut out = Vec::with_capacity(moving.len());
    for k in moving {
        let (Some(joint), Some(&child)) = (robot.joints.get(k), model.joint_child.get(k)) else {
            continue;
        };
        let name = &joint.name;
        // The body: links reached from the child link without crossing a chain joint.
        let mut body: Vec<(usize, Isometry3<f64>)> = vec![(child, Isometry3::identity())];
        let mut i = 0;
        while let Some(&(link, pose)) = body.get(i) {
            for &j in model
                .child_joints
                .get(link)
                .map(Vec::as_slice)
                .unwrap_or(&[])
            {
                if stop.contains(&j) {
                    continue;
                }
                if let (Some(&c), Some(jj)) = (model.joint_child.get(j), robot.joints.get(j)) {
                    if let Some(v) = jj
                        .origin
                        .xyz
                        .iter()
                        .chain(&jj.origin.rpy)
                        .find(|v| !v.is_finite())
                    {
                        return Err(UrdfError::NonFinite {
                            joint: name.clone(),
                            what: "origin of a joint inside the body it carries",
                            value: *v,
                            line: Some(jj.line),
                        });
                    }
                    body.push((c, pose * origin_of(j)));
                }
            }
            i += 1;
        }
        let mut mass = 0.0;
        let mut moment = Vector3::zeros();
        for (link, pose) in body {
            let Some(l) = robot.links.get(link) else {
                continue;
            };
            let inertial = match &l.inertial {
                Ok(i) => i.unwrap_or_default(),
                Err(_) => {
                    return Err(UrdfError::NonFinite {
                        joint: name.clone(),
                        what: "inertial of a link it carries (malformed, see the warnings)",
                        value: f64::NAN,
                        line: Some(l.line),
                    })
                }
            };
            let (m, c) = (inertial.mass, inertial.com);
            if !(m.is_finite() && m >= 0.0) {
                return Err(UrdfError::NonFinite {
                    joint: name.clone(),
                    what: "inertial mass of a link it carries (expected >= 0)",
                    value: m,
                    line: Some(l.line),
                });
            }
            if let Some(v) = c.iter().find(|v| !v.is_finite()) {
                return Err(UrdfError::NonFinite {
                    joint: name.clone(),
                    what: "inertial origin of a link it carries",
                    value: *v,
                    line: Some(l.line),
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
        let zero = at_zero
            .get(child)
            .copied()
            .flatten()
            .unwrap_or_else(Isometry3::identity);
        let com_at_zero = (zero * Point3::from(com)).coords;
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
