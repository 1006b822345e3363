//! `urdf-dh extract`: one snapshot per fixture robot, every format, stdin, warnings, bad input.

use crate::common::{exit_code, fixture_robots, run, settings};

#[test]
fn every_fixture_robot_extracts_and_verifies() {
    let _snap = settings().bind_to_scope();
    let robots = fixture_robots();
    assert!(
        robots.len() >= 7,
        "expected at least 7 fixture robots, found {robots:?}"
    );
    for id in robots {
        let path = format!("fixtures/robots/{id}/robot.urdf");
        insta::with_settings!({snapshot_suffix => id.clone()}, {
            insta::assert_snapshot!("extract_yaml", run(&["extract", &path, "--format", "yaml"], None));
        });
        for convention in ["standard", "modified"] {
            assert_eq!(
                exit_code(&[
                    "extract",
                    &path,
                    "--convention",
                    convention,
                    "--samples",
                    "300"
                ]),
                0,
                "{id} {convention}"
            );
        }
    }
}

#[test]
fn text_is_the_default_format() {
    let _snap = settings().bind_to_scope();
    insta::assert_snapshot!(run(
        &[
            "extract",
            "fixtures/robots/ur5/robot.urdf",
            "--angle-unit",
            "deg"
        ],
        None
    ));
}

#[test]
fn every_format_of_the_panda_in_craig_convention() {
    let _snap = settings().bind_to_scope();
    for format in ["text", "yaml", "json", "csv", "markdown"] {
        insta::with_settings!({snapshot_suffix => format}, {
            insta::assert_snapshot!("panda_modified", run(&[
                "extract", "fixtures/robots/franka_panda/robot.urdf", "--convention", "modified",
                "--format", format, "--length-unit", "mm", "--angle-unit", "deg",
            ], None));
        });
    }
}

#[test]
fn reads_standard_input() {
    let _snap = settings().bind_to_scope();
    let urdf =
        std::fs::read(crate::common::root().join("fixtures/robots/scara_prismatic/robot.urdf"))
            .unwrap();
    insta::assert_snapshot!(run(&["extract", "-", "--format", "yaml"], Some(&urdf)));
}

#[test]
fn json_and_yaml_carry_the_same_keys() {
    let _snap = settings().bind_to_scope();
    let get = |format: &str| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_urdf-dh"))
            .args([
                "extract",
                "fixtures/robots/kuka_kr5_arc/robot.urdf",
                "--format",
                format,
            ])
            .current_dir(crate::common::root())
            .output()
            .unwrap();
        String::from_utf8(out.stdout).unwrap()
    };
    let yaml: serde_json::Value = serde_yaml::from_str(&get("yaml")).unwrap();
    let json: serde_json::Value = serde_json::from_str(&get("json")).unwrap();
    assert!(same(&yaml, &json), "{yaml}\n{json}");
    for key in [
        "convention",
        "length_unit",
        "angle_unit",
        "base",
        "tool",
        "joints",
        "tolerances",
        "warnings",
        "verification",
    ] {
        assert!(json.get(key).is_some(), "missing key {key}");
    }
}

/// A UR-like arm written with rpy="1.5708": sane table, a warning naming the pair.
#[test]
fn rounded_half_pi_gives_a_sane_table_and_a_warning() {
    let _snap = settings().bind_to_scope();
    // j2's frame is turned by rpy 1.5708 (3.7e-6 rad past pi/2) and j3's turned back by
    // -1.5708: their axes are meant to be parallel but are tilted within the plane they span,
    // the ill-conditioned direction (exactly, they meet about 115 km away).
    let urdf = r#"<robot name="rounded">
  <link name="base"/><link name="l1"/><link name="l2"/><link name="l3"/><link name="l4"/><link name="tip"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.1" rpy="0 0 0"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0 0 0.05" rpy="1.5708 0 0"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/>
    <origin xyz="0 0.425 0" rpy="-1.5708 0 0"/><axis xyz="0 -1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j4" type="revolute"><parent link="l3"/><child link="l4"/>
    <origin xyz="0 0 0.39" rpy="0 0 0"/><axis xyz="0 -1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="flange" type="fixed"><parent link="l4"/><child link="tip"/>
    <origin xyz="0.1 0 0" rpy="0 1.5708 0"/></joint>
</robot>"#;
    insta::assert_snapshot!(run(
        &["extract", "-", "--angle-unit", "deg"],
        Some(urdf.as_bytes())
    ));
    // Beyond the tolerance the exact, ill-conditioned table comes with a loud warning.
    insta::assert_snapshot!(
        "rounded_half_pi_exact",
        run(
            &["extract", "-", "--angular-tol", "1e-6", "--format", "yaml"],
            Some(urdf.as_bytes())
        )
    );
}

#[test]
fn bad_input_exits_2_with_a_message() {
    let _snap = settings().bind_to_scope();
    insta::assert_snapshot!(
        "missing_file",
        run(&["extract", "fixtures/robots/nope.urdf"], None)
    );
    insta::assert_snapshot!("not_xml", run(&["extract", "-"], Some(b"this is not xml")));
    insta::assert_snapshot!("empty", run(&["extract", "-"], Some(b"")));
    insta::assert_snapshot!(
        "unknown_tip",
        run(
            &[
                "extract",
                "fixtures/robots/ur5/robot.urdf",
                "--tip",
                "wrist"
            ],
            None
        )
    );
    insta::assert_snapshot!(
        "bad_tolerance",
        run(
            &[
                "extract",
                "fixtures/robots/ur5/robot.urdf",
                "--linear-tol",
                "-1"
            ],
            None
        )
    );
    insta::assert_snapshot!(
        "bad_format",
        run(
            &[
                "extract",
                "fixtures/robots/ur5/robot.urdf",
                "--format",
                "xml"
            ],
            None
        )
    );
    // Without xacro on PATH a .xacro file is expanded natively.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_urdf-dh"))
        .args(["extract", "fixtures/xacro/two_link.urdf.xacro"])
        .current_dir(crate::common::root())
        .env("PATH", "/nonexistent")
        .output()
        .unwrap();
    insta::assert_snapshot!(
        "xacro_without_xacro",
        format!(
            "exit: {}\n--- stdout\n{}--- stderr\n{}",
            out.status.code().unwrap_or(-1),
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        )
    );
}

/// Equal up to the last digit of floats (YAML and JSON print shortest forms independently).
fn same(a: &serde_json::Value, b: &serde_json::Value) -> bool {
    use serde_json::Value::*;
    match (a, b) {
        (Number(x), Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            (x - y).abs() <= 1e-15 * x.abs().max(y.abs()).max(1e-300)
        }
        (Array(x), Array(y)) => x.len() == y.len() && x.iter().zip(y).all(|(x, y)| same(x, y)),
        (Object(x), Object(y)) => {
            x.len() == y.len() && x.iter().all(|(k, v)| y.get(k).is_some_and(|w| same(v, w)))
        }
        _ => a == b,
    }
}

/// The frame picture is well-formed SVG with every frame label, both views and every joint.
#[test]
fn svg_shows_every_frame() {
    let dir = tempfile::tempdir().unwrap();
    for (id, q) in [
        ("kuka_kr5_arc", None),
        ("scara_prismatic", Some("0.3,-0.5,0.1,1.0")),
    ] {
        let path = dir.path().join(format!("{id}.svg"));
        let mut args = vec![
            "extract".to_string(),
            format!("fixtures/robots/{id}/robot.urdf"),
            "--svg".into(),
            path.to_string_lossy().into_owned(),
        ];
        if let Some(q) = q {
            args.push("--q".into());
            args.push(q.into());
        }
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        assert_eq!(exit_code(&args), 0, "{id}");
        let text = std::fs::read_to_string(&path).unwrap();
        let doc = roxmltree::Document::parse(&text).expect("well-formed SVG");
        assert_eq!(doc.root_element().tag_name().name(), "svg");
        let texts: Vec<&str> = doc
            .descendants()
            .filter(|n| n.has_tag_name("text"))
            .filter_map(|n| n.text())
            .collect();
        let n = if id == "scara_prismatic" { 4 } else { 6 };
        for label in (0..=n)
            .map(|i| format!("F{i}"))
            .chain(["tool".to_string(), "isometric".to_string()])
        {
            assert!(
                texts
                    .iter()
                    .any(|t| t.split_whitespace().any(|w| w == label)),
                "{id}: no label {label}"
            );
        }
        // No label covers another (frames on one spot share a label): boxes of 6 units a
        // character and 10 high, slimmer than the writer's own spacing.
        let boxes: Vec<(f64, f64, f64, f64)> = doc
            .descendants()
            .filter(|n| n.has_tag_name("text") && n.attribute("x").is_some())
            .filter(|n| n.attribute("font-size").is_none())
            .filter_map(|n| {
                let (x, y): (f64, f64) = (
                    n.attribute("x")?.parse().ok()?,
                    n.attribute("y")?.parse().ok()?,
                );
                let w = 6.0 * n.text()?.chars().count() as f64;
                Some((x, y - 10.0, x + w, y))
            })
            .collect();
        for (i, a) in boxes.iter().enumerate() {
            for b in &boxes[i + 1..] {
                let apart = a.2 <= b.0 || b.2 <= a.0 || a.3 <= b.1 || b.3 <= a.1;
                assert!(apart, "{id}: labels overlap: {a:?} {b:?}");
            }
        }
        // Every frame is drawn in both views, three axes each.
        let lines = doc.descendants().filter(|n| n.has_tag_name("line")).count();
        assert!(lines >= 2 * (3 * (n + 2) + 2 * n), "{id}: {lines} lines");
    }
    let code = exit_code(&[
        "extract",
        "fixtures/robots/ur5/robot.urdf",
        "--svg",
        "/nonexistent-dir/x.svg",
    ]);
    assert_eq!(code, 2);
    let code = exit_code(&[
        "extract",
        "fixtures/robots/ur5/robot.urdf",
        "--svg",
        "/tmp/x.svg",
        "--q",
        "1,2",
    ]);
    assert_eq!(code, 2);
}

/// A .xacro file is expanded natively (the table Python's `xacro` gave before, unchanged).
#[test]
fn xacro_input_is_expanded() {
    let _snap = settings().bind_to_scope();
    insta::assert_snapshot!(run(
        &[
            "extract",
            "fixtures/xacro/two_link.urdf.xacro",
            "--format",
            "yaml"
        ],
        None
    ));
}
