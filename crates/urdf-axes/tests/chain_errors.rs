//! Errors of choosing a chain in a valid URDF (unknown or misplaced base and tip, a chain
//! without a moving joint, the wrong number of joint values, overflow) and the default tip:
//! the variant, the names it carries and the message.

mod common;

use common::{assert_message, lines, parse_err};
use urdf_axes::{UrdfError, UrdfModel};

/// A tree: root `base` with an arm `base -> upper -> hand` and a branch `base -> camera`.
fn tree() -> UrdfModel {
    UrdfModel::parse(&lines(&[
        "<robot name=\"tree\">",
        "  <link name=\"base\"/><link name=\"upper\"/><link name=\"hand\"/><link name=\"camera\"/>",
        "  <joint name=\"shoulder\" type=\"continuous\"><parent link=\"base\"/><child link=\"upper\"/></joint>",
        "  <joint name=\"wrist\" type=\"continuous\"><parent link=\"upper\"/><child link=\"hand\"/></joint>",
        "  <joint name=\"mount\" type=\"fixed\"><parent link=\"base\"/><child link=\"camera\"/></joint>",
        "</robot>",
    ]))
    .unwrap()
}

#[test]
fn unknown_base_or_tip() {
    let m = tree();
    let e = m.chain(None, Some("hnad")).unwrap_err();
    let UrdfError::UnknownLink {
        role,
        link,
        candidates,
    } = &e
    else {
        panic!("got {e:?}")
    };
    assert_eq!((*role, link.as_str()), ("tip", "hnad"));
    assert_eq!(candidates.len(), 4, "few links: all are listed");
    assert_message(&e, &["tip link 'hnad'", "'hand'"]);
    // With many links only close names are suggested.
    let mut l = vec!["<robot name=\"many\">".to_owned()];
    for i in 0..30 {
        l.push(format!("<link name=\"link_{i}\"/>"));
    }
    for i in 1..30 {
        l.push(format!(
            "<joint name=\"j{i}\" type=\"continuous\"><parent link=\"link_{}\"/><child link=\"link_{i}\"/></joint>",
            i - 1
        ));
    }
    l.push("</robot>".into());
    let m = UrdfModel::parse(&l.join("\n")).unwrap();
    let e = m.chain(Some("link_O"), None).unwrap_err();
    let UrdfError::UnknownLink {
        role, candidates, ..
    } = &e
    else {
        panic!("got {e:?}")
    };
    assert_eq!(*role, "base");
    assert!(
        candidates.len() <= 5 && candidates.contains(&"link_0".to_owned()),
        "{candidates:?}"
    );
    // Nothing close: the leaves for a tip, the root for a base.
    let e = m.chain(None, Some("gripper")).unwrap_err();
    assert_message(&e, &["tip link 'gripper'", "candidates: 'link_29'"]);
    let e = m.chain(Some("world"), None).unwrap_err();
    assert_message(&e, &["base link 'world'", "candidates: 'link_0'"]);
}

#[test]
fn default_tip_is_the_end_of_the_longest_arm() {
    // The arm (2 moving joints) wins over the camera (fixed).
    assert_eq!(tree().chain(None, None).unwrap().tip(), "hand");
    assert_eq!(tree().chain(Some("upper"), None).unwrap().tip(), "hand");
    // Two arms of equal length: refused, listing both with their moving-joint counts.
    let two = lines(&[
        "<robot name=\"two\">",
        "  <link name=\"torso\"/><link name=\"l1\"/><link name=\"l2\"/><link name=\"r1\"/><link name=\"r2\"/>",
        "  <joint name=\"lj1\" type=\"continuous\"><parent link=\"torso\"/><child link=\"l1\"/></joint>",
        "  <joint name=\"lj2\" type=\"continuous\"><parent link=\"l1\"/><child link=\"l2\"/></joint>",
        "  <joint name=\"rj1\" type=\"continuous\"><parent link=\"torso\"/><child link=\"r1\"/></joint>",
        "  <joint name=\"rj2\" type=\"continuous\"><parent link=\"r1\"/><child link=\"r2\"/></joint>",
        "</robot>",
    ]);
    let e = UrdfModel::parse(&two)
        .unwrap()
        .chain(None, None)
        .unwrap_err();
    assert_eq!(
        e,
        UrdfError::SeveralLeaves {
            base: "torso".into(),
            leaves: vec!["l2".into(), "r2".into()],
            moving: vec![2, 2],
        }
    );
    assert_message(
        &e,
        &[
            "'torso'",
            "'l2' (2 moving joints)",
            "'r2' (2 moving joints)",
            "found 2",
        ],
    );
}

/// An arm `base -> l1 -> l2 -> l3 -> l4` (4 revolute joints) with `extra` appended inside
/// `<robot>`.
fn arm_with(extra: &[&str]) -> String {
    let mut l = vec!["<robot name=\"arm\">".to_owned()];
    l.push("<link name=\"base\"/>".into());
    for i in 1..=4 {
        l.push(format!("<link name=\"l{i}\"/>"));
        l.push(format!(
            "<joint name=\"j{i}\" type=\"continuous\"><parent link=\"{}\"/><child link=\"l{i}\"/><axis xyz=\"0 0 1\"/></joint>",
            if i == 1 { "base".to_owned() } else { format!("l{}", i - 1) }
        ));
    }
    l.extend(extra.iter().map(|s| (*s).to_owned()));
    l.push("</robot>".into());
    l.join("\n")
}

#[test]
fn default_tip_prefers_a_tool_frame_and_stops_at_the_hand() {
    // Fixed links off the last moving link: the tool-named one.
    let m = UrdfModel::parse(&arm_with(&[
        "<link name=\"camera\"/><link name=\"tool0\"/><link name=\"cable\"/>",
        "<joint name=\"c\" type=\"fixed\"><parent link=\"l4\"/><child link=\"camera\"/></joint>",
        "<joint name=\"t\" type=\"fixed\"><parent link=\"l4\"/><child link=\"tool0\"/></joint>",
        "<joint name=\"k\" type=\"fixed\"><parent link=\"base\"/><child link=\"cable\"/></joint>",
    ]))
    .unwrap();
    assert_eq!(m.chain(None, None).unwrap().tip(), "tool0");
    // Several fixed links, none tool-like: the last moving link.
    let m = UrdfModel::parse(&arm_with(&[
        "<link name=\"camera\"/><link name=\"light\"/>",
        "<joint name=\"c\" type=\"fixed\"><parent link=\"l4\"/><child link=\"camera\"/></joint>",
        "<joint name=\"t\" type=\"fixed\"><parent link=\"l4\"/><child link=\"light\"/></joint>",
    ]))
    .unwrap();
    assert_eq!(m.chain(None, None).unwrap().tip(), "l4");
    // Two prismatic fingers (one mimics the other) off the hand: the hand's flange.
    let m = UrdfModel::parse(&arm_with(&[
        "<link name=\"flange\"/><link name=\"left\"/><link name=\"right\"/>",
        "<joint name=\"f\" type=\"fixed\"><parent link=\"l4\"/><child link=\"flange\"/></joint>",
        "<joint name=\"fl\" type=\"prismatic\"><parent link=\"l4\"/><child link=\"left\"/><limit lower=\"0\" upper=\"0.04\" effort=\"1\" velocity=\"1\"/></joint>",
        "<joint name=\"fr\" type=\"prismatic\"><parent link=\"l4\"/><child link=\"right\"/><limit lower=\"0\" upper=\"0.04\" effort=\"1\" velocity=\"1\"/><mimic joint=\"fl\"/></joint>",
    ]))
    .unwrap();
    let c = m.chain(None, None).unwrap();
    assert_eq!((c.tip(), c.axes().len()), ("flange", 4));
}

#[test]
fn tip_not_below_base() {
    let m = tree();
    let e = m.chain(Some("camera"), Some("hand")).unwrap_err();
    assert_eq!(
        e,
        UrdfError::Disconnected {
            base: "camera".into(),
            tip: "hand".into(),
            reversed: false
        }
    );
    assert_message(&e, &["'camera'", "'hand'", "not below"]);
    let e = m.chain(Some("hand"), Some("upper")).unwrap_err();
    assert!(matches!(e, UrdfError::Disconnected { reversed: true, .. }));
    assert_message(&e, &["swap"]);
}

#[test]
fn floating_and_planar_only_matter_inside_the_chain() {
    for kind in ["floating", "planar"] {
        let text = lines(&[
            "<robot name=\"r\">",
            "  <link name=\"world\"/><link name=\"base\"/><link name=\"tool\"/><link name=\"other\"/>",
            &format!("  <joint name=\"free\" type=\"{kind}\"><parent link=\"world\"/><child link=\"base\"/></joint>"),
            "  <joint name=\"j\" type=\"continuous\"><parent link=\"base\"/><child link=\"tool\"/></joint>",
            &format!("  <joint name=\"side\" type=\"{kind}\"><parent link=\"world\"/><child link=\"other\"/></joint>"),
            "</robot>",
        ]);
        let m = UrdfModel::parse(&text).unwrap();
        let e = m.chain(None, Some("tool")).unwrap_err();
        let UrdfError::JointTypeInChain {
            joint, found, line, ..
        } = &e
        else {
            panic!("got {e:?}")
        };
        assert_eq!((joint.as_str(), *found, *line), ("free", kind, Some(3)));
        assert_message(&e, &["joint 'free'", kind, "line 3", "'world'", "'tool'"]);
        // From `base` the floating joint is outside the chain.
        assert_eq!(m.chain(Some("base"), Some("tool")).unwrap().axes().len(), 1);
    }
}

#[test]
fn chain_without_moving_joint() {
    let m = tree();
    let e = m.chain(None, Some("camera")).unwrap_err();
    assert_eq!(
        e,
        UrdfError::NoMovingJoint {
            base: "base".into(),
            tip: "camera".into()
        }
    );
    assert_message(&e, &["'base'", "'camera'", "at least one"]);
    assert!(matches!(
        m.chain(Some("hand"), Some("hand")),
        Err(UrdfError::NoMovingJoint { .. })
    ));
}

#[test]
fn wrong_number_of_joint_values() {
    let chain = tree().chain(None, Some("hand")).unwrap();
    let e = chain.try_fk(&[0.0]).unwrap_err();
    assert_eq!(
        e,
        UrdfError::JointCount {
            expected: 2,
            found: 1
        }
    );
    assert_message(&e, &["expected 2", "found 1"]);
    assert!(chain.axis_lines(&[0.0; 3]).is_err());
    // fk reads a missing value as 0 and ignores extra ones.
    assert_eq!(chain.fk(&[]), chain.tip_pose());
    assert_eq!(chain.fk(&[0.0, 0.0, 5.0]), chain.tip_pose());
}

#[test]
fn overflow_while_composing() {
    let text = lines(&[
        "<robot name=\"r\">",
        "  <link name=\"a\"/><link name=\"b\"/><link name=\"c\"/>",
        "  <joint name=\"far\" type=\"fixed\"><parent link=\"a\"/><child link=\"b\"/><origin xyz=\"1e308 0 0\"/></joint>",
        "  <joint name=\"farther\" type=\"continuous\"><parent link=\"b\"/><child link=\"c\"/><origin xyz=\"1e308 0 0\"/></joint>",
        "</robot>",
    ]);
    // Finite origins whose sum overflows are refused as out of range before any composing.
    let e = parse_err(&text);
    assert!(
        matches!(&e, UrdfError::OutOfRange { joint, .. } if joint == "far"),
        "{e:?}"
    );
    assert_message(&e, &["joint 'far'", "origin xyz", "1e308", "line 3"]);
}

/// A serial chain `l0 -> l1 -> ... -> ln` of revolute joints `j1..jn`, each `jk` (k > 1)
/// mimicking `j(k-1)` with `multiplier` and `offset`.
fn mimic_chain(n: usize, multiplier: &str, offset: &str) -> UrdfModel {
    let mut l = vec![
        "<robot name=\"mimics\">".to_owned(),
        "<link name=\"l0\"/>".to_owned(),
    ];
    for k in 1..=n {
        let mimic = if k > 1 {
            format!(
                "<mimic joint=\"j{}\" multiplier=\"{multiplier}\" offset=\"{offset}\"/>",
                k - 1
            )
        } else {
            String::new()
        };
        l.push(format!(
            "<link name=\"l{k}\"/><joint name=\"j{k}\" type=\"revolute\"><parent link=\"l{}\"/>\
             <child link=\"l{k}\"/><origin xyz=\"0 0 0.1\"/><axis xyz=\"0 {} {}\"/>\
             <limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/>{mimic}</joint>",
            k - 1,
            k % 2,
            (k + 1) % 2
        ));
    }
    l.push("</robot>".to_owned());
    let refs: Vec<&str> = l.iter().map(String::as_str).collect();
    UrdfModel::parse(&lines(&refs)).expect("each mimic is within range")
}

/// Mimics within range one by one can compose beyond any joint value (1e9 per link over 40
/// links overflows to infinity, which the proof then printed as `inf m`): the first joint
/// whose composed multiplier or offset is beyond 1e9 is refused, naming the root; the chain
/// before it is still read.
#[test]
fn a_chain_of_mimics_that_composes_beyond_range_is_refused() {
    let m = mimic_chain(40, "1e9", "0");
    let e = m.chain(None, Some("l40")).unwrap_err();
    let UrdfError::MimicChainOutOfRange {
        joint, root, what, ..
    } = &e
    else {
        panic!("got {e:?}")
    };
    assert_eq!(
        (joint.as_str(), root.as_str(), *what),
        ("j3", "j1", "multiplier")
    );
    assert_message(&e, &["joint 'j3'", "'j1'", "multiplier 1e18"]);
    assert!(
        m.chain(None, Some("l2")).is_ok(),
        "j2 = 1e9 q1 is within range"
    );
    // Offsets compose too: o3 = m3 o2 + o3 = 1e4 · 1e5 + 1e5 (the multiplier 1e8 is in range).
    let offsets = mimic_chain(3, "1e4", "1e5");
    let e = offsets.chain(None, Some("l3")).unwrap_err();
    assert_message(&e, &["joint 'j3'", "offset 1.0001e9"]);
    // A long chain of unit mimics (4000 links) stays within range and costs linear time.
    assert!(mimic_chain(4000, "1", "0.001")
        .chain(None, Some("l4000"))
        .is_ok());
}
