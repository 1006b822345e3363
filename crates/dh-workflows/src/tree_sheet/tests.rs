//! Tests of reading, checking and writing tree sheets.

use super::*;

/// A two-branch tree: trunk `t1`, branches `r` and `l` of two joints each.
const TREE: &str = "\
convention: modified
length_unit: m
angle_unit: deg
base: {xyz: [0, 0, 0.5], rpy: [0, 0, 0]}
tool: {xyz: [0, 0, 0.1], rpy: [0, 0, 0]}
joints:
  - {name: t1, type: revolute, a: 0, alpha: 0, d: 0.2, theta: 0}
  - {name: t2, type: revolute, a: 0.3, alpha: 90, d: 0, theta: 0}
branches:
  - name: r
    base: {xyz: [0, -0.2, 0], rpy: [90, 0, 0]}
    tool: {xyz: [0, 0, 0.05], rpy: [0, 0, 0]}
    joints:
      - {name: r1, type: revolute, a: 0, alpha: 0, d: 0, theta: 0}
      - {name: r2, type: revolute, a: 0.25, alpha: -90, d: 0, theta: 0}
  - name: l
    base: {xyz: [0, 0.2, 0], rpy: [-90, 0, 0]}
    joints:
      - {name: l1, type: revolute, a: 0, alpha: 0, d: 0, theta: 0}
      - {name: l2, type: revolute, a: 0.25, alpha: 90, d: 0, theta: 0}
";

fn err(text: &str) -> String {
    format!("{:#}", TreeSheet::parse(text, "tree.yaml").unwrap_err())
}

#[test]
fn a_tree_sheet_reads_into_a_tree() {
    let s = TreeSheet::parse(TREE, "tree.yaml").unwrap();
    assert_eq!(s.tree.rows().len(), 6);
    assert_eq!(s.tree.branches().len(), 2);
    assert_eq!(s.tree.branch_start(1), 4);
    let r = &s.tree.branches()[0].table;
    assert!((r.rows[1].a - 0.25).abs() < 1e-15);
    assert!((r.rows[1].alpha + std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    assert!((r.base.translation.vector.y + 0.2).abs() < 1e-15);
    assert_eq!(
        s.tree.branches()[1].table.tool,
        nalgebra::Isometry3::identity()
    );
    let names: Vec<&str> = s.tree.rows().iter().map(|r| r.name.as_str()).collect();
    assert_eq!(names, ["t1", "t2", "r1", "r2", "l1", "l2"]);
    // Targets: by their own name, or the branch before '/'.
    assert_eq!(TreeSheet::branch_of(&s.tree, "r"), Some("r"));
    assert_eq!(TreeSheet::branch_of(&s.tree, "l/wrist"), Some("l"));
    assert_eq!(TreeSheet::branch_of(&s.tree, "x/wrist"), None);
    assert_eq!(TreeSheet::branch_of(&s.tree, "right"), None);
    // Written back and read again: the same tree.
    let doc = TreeSheet::to_doc(&s.tree, &s.coupled, None, LengthUnit::Mm, AngleUnit::Rad);
    let text = serde_yaml::to_string(&doc).unwrap();
    let back = TreeSheet::parse(&text, "back.yaml").unwrap();
    for (a, b) in back.tree.rows().iter().zip(s.tree.rows()) {
        assert!((a.a - b.a).abs() < 1e-12 && (a.alpha - b.alpha).abs() < 1e-12);
    }
    let (dp, dr) = dh_core::pose::pose_error(
        &back.tree.branches()[0].table.base,
        &s.tree.branches()[0].table.base,
    );
    assert!(dp < 1e-12 && dr < 1e-12);
}

#[test]
fn an_unknown_key_in_a_branch_names_it_and_the_line() {
    let text = TREE.replace(
        "  - name: l\n",
        "  - name: l\n    mount: {xyz: [0, 0, 0], rpy: [0, 0, 0]}\n",
    );
    let e = err(&text);
    assert!(e.contains("tree.yaml (line 17, column 5)"), "{e}");
    assert!(e.contains("unknown field `mount`"), "{e}");
}

#[test]
fn a_joint_in_two_branches_is_refused_with_both_places() {
    let text = TREE.replace("{name: l2,", "{name: r2,");
    let e = err(&text);
    assert!(
        e.contains("tree.yaml (line 20): branch 'l': joint 'r2' appears twice in the tree (first in branch 'r')"),
        "{e}"
    );
    let text = TREE.replace("{name: l1,", "{name: t1,");
    assert!(err(&text).contains("(first in trunk)"), "{}", err(&text));
}

#[test]
fn an_empty_branch_and_empty_branches_are_refused() {
    let text = TREE.replace(
        "    joints:\n      - {name: l1, type: revolute, a: 0, alpha: 0, d: 0, theta: 0}\n      - {name: l2, type: revolute, a: 0.25, alpha: 90, d: 0, theta: 0}\n",
        "    joints: []\n",
    );
    let e = err(&text);
    assert!(
        e.contains("tree.yaml (line 16): branch 'l': 'joints' is empty"),
        "{e}"
    );
    let serial = TREE.split("branches:").next().unwrap().to_string() + "branches: []\n";
    assert!(
        err(&serial).contains("'branches' is empty"),
        "{}",
        err(&serial)
    );
    let twice = TREE.replace("name: l\n", "name: r\n");
    assert!(
        err(&twice).contains("branch 'r' appears twice"),
        "{}",
        err(&twice)
    );
}

#[test]
fn a_branch_joint_may_be_coupled_to_a_trunk_driver() {
    // The coupled joint's value is a sum over measured columns, wherever they sit.
    let text = format!("{TREE}coupled:\n  l2: {{t2: -1, r2: 0.5}}\n");
    let s = TreeSheet::parse(&text, "tree.yaml").unwrap();
    assert_eq!(
        s.coupled,
        [(
            "l2".to_string(),
            vec![("r2".into(), 0.5), ("t2".into(), -1.0)]
        )]
    );
    // What the coupling does to measured values is the CLI's (`measured::LoadedModel`).
    // A driver that is no joint of the tree is refused.
    let text = format!("{TREE}coupled:\n  l2: {{torso_9: 1}}\n");
    assert!(
        err(&text).contains("driver 'torso_9' is no joint of the sheet"),
        "{}",
        err(&text)
    );
}

#[test]
fn inertials_need_joints_and_branches_of_the_tree() {
    let with = |i: &str| format!("{TREE}inertials:\n{i}");
    let ok = with("  com_frame: dh\n  links: [{joint: r2, mass: 1.5, com: [0.1, 0, 0]}]\n  payloads: [{branch: l, mass: 2, com: [0, 0, 0.1]}]\n");
    let s = TreeSheet::parse(&ok, "tree.yaml").unwrap();
    let (i, g) = s
        .inertials
        .as_ref()
        .unwrap()
        .to_inertials(&s.tree, "tree.yaml", None)
        .unwrap();
    assert_eq!(i.payloads[0].0, 1);
    assert!(g.is_none());
    let e = err(&with("  links: [{joint: r9, mass: 1, com: [0, 0, 0]}]\n"));
    assert!(
        e.contains("link of joint 'r9': expected a joint of the tree"),
        "{e}"
    );
    let e = err(&with(
        "  links: []\n  payloads: [{mass: 1, com: [0, 0, 0]}]\n",
    ));
    assert!(
        e.contains("a payload without 'branch' in a tree of several tips"),
        "{e}"
    );
    let e = err(&with("  links: [{joint: r1, mass: -1, com: [0, 0, 0]}]\n"));
    assert!(e.contains("expected a mass in kg"), "{e}");
    let e = err(&with("  links: []\n  density: 3\n"));
    assert!(e.contains("unknown field `density`"), "{e}");
}

#[test]
fn serial_commands_refuse_a_tree_sheet() {
    let e = crate::sheet::Sheet::parse(TREE, "tree.yaml").unwrap_err();
    assert!(
        e.to_string()
            .contains("tree.yaml: 'branches': a tree sheet (a trunk and 2 branch(es): 'r', 'l')"),
        "{e}"
    );
}

#[test]
fn every_prefix_and_mangling_of_a_tree_is_an_answer_not_a_panic() {
    // Truncated files and swapped keys: each parses or is an error naming the file.
    let mut cut = 0;
    while cut <= TREE.len() {
        if let Err(e) = TreeSheet::parse(&TREE[..cut], "tree.yaml") {
            assert!(format!("{e:#}").starts_with("tree.yaml"), "{e:#}");
        }
        cut += 7;
    }
    for (from, to) in [
        ("name: r\n", "name: ''\n"),
        ("name: r\n", "name: 'r/x'\n"),
        ("name: l\n", "name: r\n"),
        ("t2", "t1"),
        ("branches:", "branches: []\nx:"),
        ("a: 0.25", "a: .nan"),
        ("rpy: [90, 0, 0]", "rpy: [90, 0]"),
    ] {
        let e = err(&TREE.replacen(from, to, 1));
        assert!(e.starts_with("tree.yaml"), "{from} -> {to}: {e}");
    }
}

#[test]
fn lines_are_found_for_every_spelling() {
    let t =
        "a:\n  - {name: j1}\n  - name: \"j1\"\n  - {\"name\": \"j10\"}\n  - {\"name\": \"j1\"}\n";
    assert_eq!(line_of(t, "name", "j1", 0), Some(2));
    assert_eq!(line_of(t, "name", "j1", 1), Some(3));
    assert_eq!(line_of(t, "name", "j1", 2), Some(5));
    assert_eq!(line_of(t, "name", "j1", 3), None);
}
