//! Hand-checked chains: a planar 2R arm, a UR5-like arm, fixed joints mid-chain, mimic and
//! prismatic joints, a branched tree, URDF defaults, and a 10,000-joint chain.

mod common;

use std::f64::consts::{FRAC_PI_2, PI};

use approx::assert_relative_eq;
use common::lines;
use dh_core::{JointKind, Limits, Line, Mimic};
use nalgebra::{Isometry3, Rotation3, Translation3, UnitQuaternion, Vector3};
use urdf_axes::{MimicJoint, UrdfModel};

fn line(point: [f64; 3], direction: [f64; 3]) -> Line {
    Line::through(Vector3::from(point), Vector3::from(direction)).unwrap()
}

fn position(iso: &Isometry3<f64>) -> Vector3<f64> {
    iso.translation.vector
}

const PLANAR_2R: &str = r#"<robot name="planar_2r">
  <link name="base"/>
  <link name="upper"/>
  <link name="tool"/>
  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="upper"/>
    <axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/>
  </joint>
  <joint name="elbow" type="continuous">
    <parent link="upper"/><child link="tool"/>
    <origin xyz="0.7 0 0"/>
    <axis xyz="0 0 2"/>
  </joint>
</robot>"#;

#[test]
fn planar_2r_axes_and_fk_by_hand() {
    let model = UrdfModel::parse(PLANAR_2R).unwrap();
    assert_eq!(model.robot_name(), "planar_2r");
    assert_eq!(model.root_link(), "base");
    assert_eq!(model.leaves(), vec!["tool"]);
    assert_eq!(model.links(), vec!["base", "upper", "tool"]);
    assert_eq!(model.joints(), vec!["shoulder", "elbow"]);
    assert_eq!(model.joint_line("elbow"), Some(10));
    assert_eq!(model.link_line("upper"), Some(3));
    assert_eq!(model.joint_line("nope"), None);

    let chain = model.chain(None, None).unwrap();
    assert_eq!((chain.base(), chain.tip()), ("base", "tool"));
    let axes = chain.axes();
    assert_eq!(axes.len(), 2);
    assert_eq!(axes[0].name, "shoulder");
    assert_eq!(axes[0].kind, JointKind::Revolute);
    assert_eq!(
        axes[0].limits,
        Some(Limits {
            lower: -3.0,
            upper: 3.0
        })
    );
    assert_eq!(axes[1].limits, None, "continuous joints have no limits");
    assert_relative_eq!(
        axes[0].line,
        line([0.0; 3], [0.0, 0.0, 1.0]),
        epsilon = 1e-15
    );
    assert_relative_eq!(
        axes[1].line,
        line([0.7, 0.0, 0.0], [0.0, 0.0, 1.0]),
        epsilon = 1e-15
    );
    assert!(chain.folded_fixed().is_empty());
    assert_eq!(chain.joints(), ["shoulder", "elbow"]);

    // Tool frame = Rz(q1) T(0.7) Rz(q2): position (0.7 c1, 0.7 s1, 0), heading q1 + q2.
    for (q1, q2) in [(0.0, 0.0), (0.3, -1.2), (PI, FRAC_PI_2), (-2.0, 2.5)] {
        let t = chain.fk(&[q1, q2]);
        assert_relative_eq!(
            position(&t),
            Vector3::new(0.7 * q1.cos(), 0.7 * q1.sin(), 0.0),
            epsilon = 1e-14
        );
        assert_relative_eq!(
            t.rotation,
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), q1 + q2),
            epsilon = 1e-14
        );
    }
    assert_eq!(chain.tip_pose(), chain.fk(&[0.0, 0.0]));
}

/// The UR5 of ur_description: base_link to ee_link, six revolute joints.
const UR5: &str = r#"<robot name="ur5_like">
  <link name="base_link"/><link name="shoulder_link"/><link name="upper_arm_link"/>
  <link name="forearm_link"/><link name="wrist_1_link"/><link name="wrist_2_link"/>
  <link name="wrist_3_link"/><link name="ee_link"/>
  <joint name="shoulder_pan_joint" type="revolute">
    <parent link="base_link"/><child link="shoulder_link"/>
    <origin xyz="0.0 0.0 0.089159" rpy="0.0 0.0 0.0"/><axis xyz="0 0 1"/>
    <limit lower="-6.2832" upper="6.2832" effort="150.0" velocity="3.15"/>
  </joint>
  <joint name="shoulder_lift_joint" type="revolute">
    <parent link="shoulder_link"/><child link="upper_arm_link"/>
    <origin xyz="0.0 0.13585 0.0" rpy="0.0 1.5707963267948966 0.0"/><axis xyz="0 1 0"/>
    <limit lower="-6.2832" upper="6.2832" effort="150.0" velocity="3.15"/>
  </joint>
  <joint name="elbow_joint" type="revolute">
    <parent link="upper_arm_link"/><child link="forearm_link"/>
    <origin xyz="0.0 -0.1197 0.425" rpy="0.0 0.0 0.0"/><axis xyz="0 1 0"/>
    <limit lower="-3.1416" upper="3.1416" effort="150.0" velocity="3.15"/>
  </joint>
  <joint name="wrist_1_joint" type="revolute">
    <parent link="forearm_link"/><child link="wrist_1_link"/>
    <origin xyz="0.0 0.0 0.39225" rpy="0.0 1.5707963267948966 0.0"/><axis xyz="0 1 0"/>
    <limit lower="-6.2832" upper="6.2832" effort="28.0" velocity="3.2"/>
  </joint>
  <joint name="wrist_2_joint" type="revolute">
    <parent link="wrist_1_link"/><child link="wrist_2_link"/>
    <origin xyz="0.0 0.093 0.0" rpy="0.0 0.0 0.0"/><axis xyz="0 0 1"/>
    <limit lower="-6.2832" upper="6.2832" effort="28.0" velocity="3.2"/>
  </joint>
  <joint name="wrist_3_joint" type="revolute">
    <parent link="wrist_2_link"/><child link="wrist_3_link"/>
    <origin xyz="0.0 0.0 0.09465" rpy="0.0 0.0 0.0"/><axis xyz="0 1 0"/>
    <limit lower="-6.2832" upper="6.2832" effort="28.0" velocity="3.2"/>
  </joint>
  <joint name="ee_fixed_joint" type="fixed">
    <parent link="wrist_3_link"/><child link="ee_link"/>
    <origin xyz="0.0 0.0823 0.0" rpy="0.0 0.0 1.5707963267948966"/>
  </joint>
</robot>"#;

#[test]
fn ur5_like_axes_at_zero_by_hand() {
    let chain = UrdfModel::parse(UR5).unwrap().chain(None, None).unwrap();
    // Worked out by hand: Ry(pi/2) after the shoulder, Ry(pi) from wrist 1 on.
    let expected = [
        ([0.0, 0.0, 0.089159], [0.0, 0.0, 1.0]),
        ([0.0, 0.13585, 0.089159], [0.0, 1.0, 0.0]),
        ([0.425, 0.01615, 0.089159], [0.0, 1.0, 0.0]),
        ([0.81725, 0.01615, 0.089159], [0.0, 1.0, 0.0]),
        ([0.81725, 0.10915, 0.089159], [0.0, 0.0, -1.0]),
        ([0.81725, 0.10915, -0.005491], [0.0, 1.0, 0.0]),
    ];
    assert_eq!(chain.axes().len(), 6);
    for (ax, (p, d)) in chain.axes().iter().zip(expected) {
        assert_relative_eq!(ax.line, line(p, d), epsilon = 1e-12);
    }
    assert_eq!(chain.folded_fixed(), ["ee_fixed_joint"]);
    let tip = chain.tip_pose();
    assert_relative_eq!(
        position(&tip),
        Vector3::new(0.81725, 0.19145, -0.005491),
        epsilon = 1e-12
    );
    // ee_link: x along base y (the tool points out of wrist 3), after Ry(pi) Rz(pi/2).
    let r = tip.rotation.to_rotation_matrix();
    assert_relative_eq!(r * Vector3::x(), Vector3::y(), epsilon = 1e-12);
    assert_relative_eq!(r * Vector3::z(), -Vector3::z(), epsilon = 1e-12);
}

#[test]
fn ur5_like_fk_by_hand() {
    let chain = UrdfModel::parse(UR5).unwrap().chain(None, None).unwrap();
    let zero_tip = Vector3::new(0.81725, 0.19145, -0.005491);
    // Pan by 90 degrees: the whole arm turns about the base z axis.
    let t = chain.fk(&[FRAC_PI_2, 0.0, 0.0, 0.0, 0.0, 0.0]);
    assert_relative_eq!(
        position(&t),
        Vector3::new(-0.19145, 0.81725, -0.005491),
        epsilon = 1e-12
    );
    // Shoulder lift by -90 degrees about y through (0, 0.13585, 0.089159): the arm stands up.
    let t = chain.fk(&[0.0, -FRAC_PI_2, 0.0, 0.0, 0.0, 0.0]);
    assert_relative_eq!(
        position(&t),
        Vector3::new(0.09465, 0.19145, 0.906409),
        epsilon = 1e-12
    );
    // Wrist 3 turns about its own axis, which passes through the tool point: position stays.
    let t = chain.fk(&[0.0, 0.0, 0.0, 0.0, 0.0, 1.0]);
    assert_relative_eq!(position(&t), zero_tip, epsilon = 1e-12);
    // Wrist 2 by 90 degrees about -z through (0.81725, 0.10915, .): the tool offset (0, 0.0823)
    // turns to (+0.0823, 0).
    let t = chain.fk(&[0.0, 0.0, 0.0, 0.0, FRAC_PI_2, 0.0]);
    assert_relative_eq!(
        position(&t),
        Vector3::new(0.89955, 0.10915, -0.005491),
        epsilon = 1e-12
    );
}

#[test]
fn fixed_joints_mid_chain_are_folded() {
    let text = r#"<robot name="folded">
  <link name="world"/><link name="base"/><link name="a"/><link name="flange"/>
  <link name="adapter"/><link name="b"/><link name="tool"/>
  <joint name="mount" type="fixed">
    <parent link="world"/><child link="base"/><origin xyz="0 0 1" rpy="0 0 1.5707963267948966"/>
  </joint>
  <joint name="j1" type="continuous">
    <parent link="base"/><child link="a"/><origin xyz="0.1 0 0"/><axis xyz="0 0 1"/>
  </joint>
  <joint name="flange_fix" type="fixed">
    <parent link="a"/><child link="flange"/><origin xyz="0.2 0 0"/>
  </joint>
  <joint name="adapter_fix" type="fixed">
    <parent link="flange"/><child link="adapter"/><origin rpy="1.5707963267948966 0 0"/>
  </joint>
  <joint name="j2" type="continuous">
    <parent link="adapter"/><child link="b"/><origin xyz="0 0 0.3"/><axis xyz="0 0 1"/>
  </joint>
  <joint name="tool_fix" type="fixed">
    <parent link="b"/><child link="tool"/><origin xyz="0 0.05 0"/>
  </joint>
</robot>"#;
    let chain = UrdfModel::parse(text).unwrap().chain(None, None).unwrap();
    assert_eq!(
        chain.folded_fixed(),
        ["mount", "flange_fix", "adapter_fix", "tool_fix"]
    );
    assert_eq!(
        chain.joints(),
        ["mount", "j1", "flange_fix", "adapter_fix", "j2", "tool_fix"]
    );
    // In world: base at (0,0,1) turned 90 degrees about z, so base x is world y.
    // j1 at base (0.1,0,0) = world (0, 0.1, 1), along z.
    // a-frame = j1 frame; flange at a (0.2,0,0) = world (0, 0.3, 1); adapter turns x by 90:
    // adapter z = a's -y = world +x. j2 at adapter (0,0,0.3) = world (0.3, 0.3, 1), along +x.
    let axes = chain.axes();
    assert_relative_eq!(
        axes[0].line,
        line([0.0, 0.1, 1.0], [0.0, 0.0, 1.0]),
        epsilon = 1e-12
    );
    assert_relative_eq!(
        axes[1].line,
        line([0.3, 0.3, 1.0], [1.0, 0.0, 0.0]),
        epsilon = 1e-12
    );
    // Tool: b (0, 0.05, 0); adapter y = a's z = world z, so the tool is at (0.3, 0.3, 1.05).
    assert_relative_eq!(
        position(&chain.tip_pose()),
        Vector3::new(0.3, 0.3, 1.05),
        epsilon = 1e-12
    );
    // Turning j1 by 90 degrees swings everything after it about world z through (0, 0.1):
    // (0.3, 0.3) - (0, 0.1) = (0.3, 0.2) -> (-0.2, 0.3) -> (-0.2, 0.4).
    let t = chain.fk(&[FRAC_PI_2, 0.0]);
    assert_relative_eq!(position(&t), Vector3::new(-0.2, 0.4, 1.05), epsilon = 1e-12);
    // j2 about world x through (., 0.3, 1): the tool offset (0, 0, 0.05) -> (0, -0.05, 0).
    let t = chain.fk(&[0.0, FRAC_PI_2]);
    assert_relative_eq!(position(&t), Vector3::new(0.3, 0.25, 1.0), epsilon = 1e-12);
}

const GRIPPER: &str = r#"<robot name="gripper">
  <link name="base"/><link name="palm"/><link name="left"/><link name="right"/>
  <link name="left_tip"/>
  <joint name="wrist" type="continuous">
    <parent link="base"/><child link="palm"/><axis xyz="0 0 1"/>
  </joint>
  <joint name="left_finger" type="prismatic">
    <parent link="palm"/><child link="left"/><origin xyz="0 0 0.1" rpy="0 0 1.5707963267948966"/>
    <axis xyz="1 0 0"/><limit lower="0" upper="0.04" effort="10" velocity="0.2"/>
  </joint>
  <joint name="right_finger" type="prismatic">
    <parent link="palm"/><child link="right"/><origin xyz="0 0 0.1"/>
    <axis xyz="0 -1 0"/><limit lower="0" upper="0.04" effort="10" velocity="0.2"/>
    <mimic joint="left_finger"/>
  </joint>
  <joint name="left_pad" type="prismatic">
    <parent link="left"/><child link="left_tip"/><origin xyz="0 0 0.02"/>
    <axis xyz="0 0 1"/><limit lower="-0.01" upper="0.01" effort="1" velocity="0.1"/>
    <mimic joint="right_finger" multiplier="-0.5" offset="0.001"/>
  </joint>
</robot>"#;

#[test]
fn prismatic_joints_and_mimic() {
    let model = UrdfModel::parse(GRIPPER).unwrap();
    // Left finger chain: the pad mimics the right finger, which is not on it.
    let left = model.chain(None, Some("left_tip")).unwrap();
    let kinds: Vec<JointKind> = left.axes().iter().map(|a| a.kind).collect();
    assert_eq!(
        kinds,
        [
            JointKind::Revolute,
            JointKind::Prismatic,
            JointKind::Prismatic
        ]
    );
    let finger = &left.axes()[1];
    assert_eq!(
        finger.limits,
        Some(Limits {
            lower: 0.0,
            upper: 0.04
        })
    );
    // Axis x of a frame turned 90 degrees about z: world +y, through (0, 0, 0.1).
    assert_relative_eq!(
        finger.line,
        line([0.0, 0.0, 0.1], [0.0, 1.0, 0.0]),
        epsilon = 1e-12
    );
    assert_eq!(
        left.axes()[2].mimic,
        Some(Mimic {
            joint: "right_finger".into(),
            multiplier: -0.5,
            offset: 0.001
        })
    );
    assert_eq!(
        left.mimics(),
        [MimicJoint {
            joint: "left_pad".into(),
            driver: "right_finger".into(),
            multiplier: -0.5,
            offset: 0.001,
            driver_in_chain: false,
        }]
    );
    // Mimic rows take the value given: the finger opens 3 cm along world y, the pad 5 mm up.
    let t = left.fk(&[0.0, 0.03, 0.005]);
    assert_relative_eq!(
        position(&t),
        Vector3::new(0.0, 0.03, 0.125),
        epsilon = 1e-15
    );
    // With the wrist at 90 degrees the finger slides along world -x.
    let t = left.fk(&[FRAC_PI_2, 0.03, 0.0]);
    assert_relative_eq!(
        position(&t),
        Vector3::new(-0.03, 0.0, 0.12),
        epsilon = 1e-15
    );

    // Right finger chain: it mimics the left finger with the URDF defaults.
    let right = model.chain(None, Some("right")).unwrap();
    assert_eq!(
        right.axes()[1].mimic,
        Some(Mimic {
            joint: "left_finger".into(),
            multiplier: 1.0,
            offset: 0.0
        })
    );
    assert!(!right.mimics()[0].driver_in_chain);
}

#[test]
fn mimic_driver_inside_the_chain() {
    let text = r#"<robot name="coupled">
  <link name="a"/><link name="b"/><link name="c"/>
  <joint name="drive" type="continuous"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/></joint>
  <joint name="follow" type="continuous">
    <parent link="b"/><child link="c"/><origin xyz="1 0 0"/><axis xyz="0 0 1"/>
    <mimic joint="drive" multiplier="-1"/>
  </joint>
</robot>"#;
    let chain = UrdfModel::parse(text).unwrap().chain(None, None).unwrap();
    assert_eq!(chain.mimics().len(), 1);
    assert!(chain.mimics()[0].driver_in_chain);
    assert_eq!(chain.mimics()[0].multiplier, -1.0);
    // q_follow = -q_drive keeps the tip's heading.
    let t = chain.fk(&[0.4, -0.4]);
    assert_relative_eq!(t.rotation, UnitQuaternion::identity(), epsilon = 1e-15);
}

#[test]
fn branched_tree_and_tip_choice() {
    let text = r#"<robot name="two_arms">
  <link name="torso"/>
  <link name="l1"/><link name="l2"/><link name="l_hand"/>
  <link name="r1"/><link name="r2"/>
  <link name="head"/>
  <joint name="l_j1" type="continuous"><parent link="torso"/><child link="l1"/><origin xyz="0 0.2 0"/><axis xyz="0 1 0"/></joint>
  <joint name="l_j2" type="continuous"><parent link="l1"/><child link="l2"/><origin xyz="0 0.3 0"/><axis xyz="1 0 0"/></joint>
  <joint name="l_fix" type="fixed"><parent link="l2"/><child link="l_hand"/><origin xyz="0 0.1 0"/></joint>
  <joint name="r_j1" type="continuous"><parent link="torso"/><child link="r1"/><origin xyz="0 -0.2 0"/><axis xyz="0 -1 0"/></joint>
  <joint name="r_j2" type="continuous"><parent link="r1"/><child link="r2"/><origin xyz="0 -0.3 0"/><axis xyz="1 0 0"/></joint>
  <joint name="neck" type="fixed"><parent link="torso"/><child link="head"/><origin xyz="0 0 0.5"/></joint>
</robot>"#;
    let model = UrdfModel::parse(text).unwrap();
    assert_eq!(model.root_link(), "torso");
    assert_eq!(model.leaves(), vec!["l_hand", "r2", "head"]);
    let left = model.chain(None, Some("l_hand")).unwrap();
    let names: Vec<&str> = left.axes().iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["l_j1", "l_j2"]);
    assert_relative_eq!(
        position(&left.tip_pose()),
        Vector3::new(0.0, 0.6, 0.0),
        epsilon = 1e-15
    );
    let right = model.chain(Some("torso"), Some("r2")).unwrap();
    assert_relative_eq!(
        right.axes()[0].line,
        line([0.0, -0.2, 0.0], [0.0, -1.0, 0.0]),
        epsilon = 1e-15
    );
    // A base inside the tree: everything is in l1's frame.
    let forearm = model.chain(Some("l1"), None).unwrap();
    assert_eq!(forearm.tip(), "l_hand");
    assert_eq!(forearm.axes().len(), 1);
    assert_relative_eq!(
        forearm.axes()[0].line,
        line([0.0, 0.3, 0.0], [1.0, 0.0, 0.0]),
        epsilon = 1e-15
    );
}

#[test]
fn urdf_defaults_for_missing_axis_origin_and_1_2_limits() {
    let text = r#"<robot name="defaults" version="1.2">
  <link name="a"/><link name="b"/><link name="c"/>
  <joint name="no_axis" type="revolute">
    <parent link="a"/><child link="b"/>
    <limit effort="1" velocity="1"/>
  </joint>
  <joint name="one_sided" type="prismatic">
    <parent link="b"/><child link="c"/><origin xyz="0 0 1"/><axis xyz="0 0 1"/>
    <limit upper="0.5" effort="1" velocity="1"/>
  </joint>
</robot>"#;
    let chain = UrdfModel::parse(text).unwrap().chain(None, None).unwrap();
    // No <origin>: identity; no <axis>: 1 0 0.
    assert_relative_eq!(
        chain.axes()[0].line,
        line([0.0; 3], [1.0, 0.0, 0.0]),
        epsilon = 1e-15
    );
    // URDF 1.2: omitted limits are infinite and read as "no limit".
    assert_eq!(chain.axes()[0].limits, None);
    assert_eq!(chain.axes()[1].limits, None);
}

#[test]
fn rounded_rpy_is_kept_as_written() {
    // 1.5708 is 3.7e-6 rad off pi/2; the axis must show exactly that tilt, not a snapped one.
    let text = r#"<robot name="rounded">
  <link name="a"/><link name="b"/>
  <joint name="j" type="continuous"><parent link="a"/><child link="b"/>
    <origin rpy="1.5708 0 0"/><axis xyz="0 0 1"/></joint>
</robot>"#;
    let chain = UrdfModel::parse(text).unwrap().chain(None, None).unwrap();
    let d = chain.axes()[0].line.direction();
    let rounded: f64 = "1.5708".parse().unwrap();
    let want = Rotation3::from_axis_angle(&Vector3::x_axis(), rounded) * Vector3::z();
    assert_relative_eq!(d, want, epsilon = 1e-15);
    assert!((d.y + 1.0).abs() > 1e-12, "the tilt is not snapped");
}

#[test]
fn byte_order_mark_and_bytes_input() {
    let with_bom = format!("\u{feff}{PLANAR_2R}");
    let model = UrdfModel::from_bytes(with_bom.as_bytes()).unwrap();
    assert_eq!(model.joint_line("elbow"), Some(10));
}

/// A straight chain of `n` revolute joints, each 1 mm along z and turned 0.01 rad about x.
fn long_chain(n: usize) -> String {
    let mut l = vec!["<robot name=\"long\">".to_owned()];
    l.extend((0..=n).map(|i| format!("<link name=\"l{i}\"/>")));
    l.extend((0..n).map(|i| {
        format!(
            "<joint name=\"j{i}\" type=\"revolute\"><parent link=\"l{i}\"/><child link=\"l{}\"/>\
             <origin xyz=\"0 0 0.001\" rpy=\"0.01 0 0\"/><axis xyz=\"0 0 1\"/>\
             <limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>",
            i + 1
        )
    }));
    l.push("</robot>".into());
    lines(&l.iter().map(String::as_str).collect::<Vec<_>>())
}

#[test]
fn ten_thousand_joints_build_and_agree() {
    let text = long_chain(10_000);
    let model = UrdfModel::parse(&text).unwrap();
    assert_eq!(model.joint_line("j9999"), Some(10_003 + 9_999));
    let chain = model.chain(None, Some("l10000")).unwrap();
    assert_eq!(chain.axes().len(), 10_000);
    let q = vec![0.0; 10_000];
    assert_relative_eq!(chain.fk(&q), chain.tip_pose(), epsilon = 1e-9);
    // Its growth with the chain's length is measured by `cargo bench -p urdf-axes --bench parse`
    // (chain_1k to chain_10k), not timed here.
}

#[test]
fn fk_agrees_with_an_explicit_product_on_a_long_chain() {
    let chain = UrdfModel::parse(&long_chain(200))
        .unwrap()
        .chain(None, None)
        .unwrap();
    let q: Vec<f64> = (0..200).map(|i| (i as f64 * 0.37).sin()).collect();
    let mut want = Isometry3::identity();
    for &qi in &q {
        want = want
            * Translation3::new(0.0, 0.0, 0.001)
            * UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 0.01)
            * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), qi);
    }
    assert_relative_eq!(chain.fk(&q), want, epsilon = 1e-12);
}
