//! What is strict on the chosen chain and lenient (a warning) elsewhere, as ROS's urdfdom
//! reads URDFs; mimic drivers over the whole model.

mod common;

use common::{assert_message, lines};
use urdf_axes::{UrdfError, UrdfModel};

/// An arm `base -> l1 -> l2` (joints j1, j2) with a wheel `base -> wheel` (joint `w`), with
/// `j2_extra` inside j2 (from line 10) and `w_extra` inside w (from line 15).
fn arm(j2_extra: &str, w_extra: &str) -> String {
    lines(&[
        "<robot name=\"r\">",
        "  <link name=\"base\"/>",
        "  <link name=\"l1\"/>",
        "  <link name=\"l2\"/>",
        "  <link name=\"wheel\"/>",
        "  <joint name=\"j1\" type=\"continuous\">",
        "    <parent link=\"base\"/><child link=\"l1\"/><axis xyz=\"0 0 1\"/>",
        "  </joint>",
        "  <joint name=\"j2\" type=\"continuous\"><parent link=\"l1\"/><child link=\"l2\"/>",
        &format!("    <origin xyz=\"0.5 0 0\"/>{j2_extra}"),
        "  </joint>",
        "  <joint name=\"w\" type=\"revolute\">",
        "    <parent link=\"base\"/><child link=\"wheel\"/>",
        "    <axis xyz=\"0 1 0\"/>",
        &format!("    {w_extra}"),
        "  </joint>",
        "</robot>",
    ])
}

const LIMIT: &str = "<limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/>";

#[test]
fn faults_of_joints_off_the_chain_are_warnings() {
    for (w_extra, what) in [
        (
            "<limit lower=\"-1e16\" upper=\"1\" effort=\"1\" velocity=\"1\"/>",
            "1e9",
        ),
        (
            "<limit lower=\"2\" upper=\"1\" effort=\"1\" velocity=\"1\"/>",
            "lower <= upper",
        ),
        ("", "<limit>"),
        (
            "<limit lower=\"x\" upper=\"1\" effort=\"1\" velocity=\"1\"/>",
            "'x'",
        ),
        (&format!("{LIMIT}<mimic joint=\"ghost\"/>"), "'ghost'"),
    ] {
        let m = UrdfModel::parse(&arm("", w_extra)).unwrap_or_else(|e| panic!("{w_extra}: {e}"));
        let c = m.chain(None, Some("l2")).unwrap();
        assert_eq!(c.axes().len(), 2);
        let w = m.warnings_for(&c);
        assert_eq!(w.len(), 1, "{w:?}");
        let text = w[0].to_string();
        assert!(text.starts_with("joint 'w' (line 12): "), "{text}");
        assert!(
            text.contains(what) && text.contains("not on the chain"),
            "{text}"
        );
        // On the chain, the same fault is an error.
        let e = m.chain(None, Some("wheel")).unwrap_err();
        assert_message(&e, &["joint 'w'", what]);
    }
}

#[test]
fn faults_of_visuals_materials_and_inertials_are_warnings() {
    let text = lines(&[
        "<robot name=\"r\">",
        "  <material name=\"grey\"><color rgba=\"0.5 0.5\"/></material>",
        "  <link name=\"a\">",
        "    <visual><geometry><box size=\"1 1 1\"/></geometry>",
        "      <material name=\"m1\"><texture/></material><material name=\"m2\"/></visual>",
        "    <collision><geometry><blob/></geometry></collision>",
        "    <inertial><mass/></inertial>",
        "  </link>",
        "  <link name=\"b\"/>",
        "  <joint name=\"j\" type=\"continuous\"><parent link=\"a\"/><child link=\"b\"/></joint>",
        "  <gazebo><anything at=\"all\"/></gazebo>",
        "</robot>",
    ]);
    let m = UrdfModel::parse(&text).unwrap();
    let w: Vec<String> = m.warnings().iter().map(ToString::to_string).collect();
    let expected = [
        "material 'grey', <color> (line 2): attribute 'rgba': expected 4 numbers, found '0.5 0.5'",
        "link 'a', <inertial> (line 7): <mass>: expected attribute 'value', found none",
        "link 'a', <visual>, <material>, <texture> (line 5): expected attribute 'filename'",
        "link 'a', <visual> (line 4): expected one <material>, found 2; the first is used",
        "link 'a', <collision>, <blob> (line 6): expected <box>, <cylinder>, <capsule>, <sphere> or <mesh>, found <blob>",
    ];
    assert_eq!(w.len(), expected.len(), "{w:#?}");
    for e in expected {
        assert!(w.iter().any(|x| x.starts_with(e)), "{e} not in {w:#?}");
    }
    assert_eq!(m.chain(None, None).unwrap().axes().len(), 1);
    // A body that needs the malformed inertial refuses to weigh it.
    let c = m.chain(None, None).unwrap();
    assert!(
        urdf_axes::inertia::joint_inertials(&m, &c).is_ok(),
        "link a is the fixed base"
    );
}

#[test]
fn what_defines_the_tree_stays_strict() {
    // A joint naming an undefined parent (bd_spot_arm's fault) is refused at once.
    let e = UrdfModel::parse(&arm("", LIMIT).replace(
        "<parent link=\"base\"/><child link=\"wheel\"/>",
        "<parent link=\"body\"/><child link=\"wheel\"/>",
    ))
    .unwrap_err();
    assert!(matches!(e, UrdfError::MissingLink { .. }), "{e}");
    assert_message(&e, &["joint 'w'", "'body'", "line 13"]);
}

#[test]
fn mimic_cycles_and_mimics_of_fixed_joints_are_refused() {
    let cycle = arm("<mimic joint=\"j1\"/>", LIMIT).replace(
        "<axis xyz=\"0 0 1\"/>",
        "<axis xyz=\"0 0 1\"/><mimic joint=\"j2\" multiplier=\"2\"/>",
    );
    let m = UrdfModel::parse(&cycle).unwrap();
    let e = m.chain(None, Some("l2")).unwrap_err();
    assert_eq!(
        e,
        UrdfError::MimicCycle {
            joints: vec!["j1".into(), "j2".into(), "j1".into()],
            line: Some(7)
        }
    );
    assert_message(&e, &["joint 'j1'", "line 7", "cycle j1 -> j2 -> j1"]);
    // Off the chain (the wheel alone) the cycle is a warning.
    let c = m.chain(None, Some("wheel")).unwrap();
    assert_eq!(m.warnings_for(&c).len(), 2);

    let fixed = arm("<mimic joint=\"f\"/>", LIMIT).replace(
        "</robot>",
        "<link name=\"cam\"/><joint name=\"f\" type=\"fixed\"><parent link=\"base\"/><child link=\"cam\"/></joint>\n</robot>",
    );
    let e = UrdfModel::parse(&fixed)
        .unwrap()
        .chain(None, Some("l2"))
        .unwrap_err();
    assert!(matches!(e, UrdfError::MimicOfFixed { .. }), "{e}");
    assert_message(&e, &["joint 'j2'", "'f'", "fixed", "line 10"]);
}

/// A serial chain of `n` continuous joints in which joint i mimics joint i + 1.
fn mimic_chain(n: usize) -> String {
    let mut s = String::from("<robot name=\"m\">\n<link name=\"l0\"/>\n");
    for i in 1..=n {
        s.push_str(&format!("<link name=\"l{i}\"/>\n"));
    }
    for i in 1..=n {
        let mimic = if i < n {
            format!(
                "<mimic joint=\"j{}\" multiplier=\"0.5\" offset=\"0.1\"/>",
                i + 1
            )
        } else {
            String::new()
        };
        s.push_str(&format!(
            "<joint name=\"j{i}\" type=\"continuous\"><parent link=\"l{}\"/><child link=\"l{i}\"/>\
             <origin xyz=\"0 0 0.01\"/><axis xyz=\"0 0 1\"/>{mimic}</joint>\n",
            i - 1
        ));
    }
    s.push_str("</robot>\n");
    s
}

#[test]
fn a_long_chain_of_mimics_is_valid() {
    let n = 4000;
    let m = UrdfModel::parse(&mimic_chain(n)).unwrap();
    assert!(m.warnings().is_empty());
    let c = m.chain(None, None).unwrap();
    assert_eq!(c.axes().len(), n);
    assert_eq!(c.mimics().len(), n - 1);
    for (i, mj) in c.mimics().iter().enumerate() {
        assert_eq!(mj.joint, format!("j{}", i + 1));
        assert_eq!(mj.driver, format!("j{}", i + 2));
        assert_eq!(
            (mj.multiplier, mj.offset, mj.driver_in_chain),
            (0.5, 0.1, true)
        );
    }
    // Closing the chain into a ring makes one cycle of n joints, reported shortened.
    let ring = mimic_chain(n).replace(
        &format!("<axis xyz=\"0 0 1\"/></joint>\n</robot>"),
        "<axis xyz=\"0 0 1\"/><mimic joint=\"j1\"/></joint>\n</robot>",
    );
    let e = UrdfModel::parse(&ring)
        .unwrap()
        .chain(None, None)
        .unwrap_err();
    assert_message(
        &e,
        &["joint 'j1'", "cycle j1 -> j2", &format!("({n} links)")],
    );
}

#[test]
fn names_with_bidirectional_overrides_are_refused() {
    let e = common::parse_err(&arm("", LIMIT).replace("name=\"j2\"", "name=\"j\u{202e}2\""));
    assert!(matches!(e, UrdfError::ControlCharacterInName { .. }), "{e}");
    assert_message(&e, &["U+202E", "line 9"]);
    let e = UrdfModel::parse(&arm("", LIMIT).replace("name=\"l1\"", "name=\"l\u{2067}1\""))
        .unwrap_err();
    assert_message(&e, &["link", "U+2067", "line 3"]);
}
