//! `check` on the cases it once got wrong: right sheets with antiparallel and coincident axes
//! and a free base (../shared/repro), and sheets that change a joint's type (fixtures/check).

use serde_json::Value;

use crate::common::{exec, run, settings, skip_without_shared};

/// The generated robots of ../shared/repro: both truth sheets (base and tool given, and base
/// free) describe the URDF exactly (the rounded ones to ~1e-5), so both must be a MATCH.
#[test]
fn repro_truth_sheets_match() {
    let Some(shared) = skip_without_shared("check repro") else {
        return;
    };
    let _s = settings().bind_to_scope();
    for case in ["antico_0", "antico_1", "ind6_rounded", "ur6_rounded"] {
        let dir = shared.join("repro").join(case);
        let urdf = dir.join("robot.urdf");
        for sheet in ["truth", "truth-nobase"] {
            let path = dir.join(format!("{sheet}.yaml"));
            let args = [
                "check",
                urdf.to_str().unwrap(),
                "--sheet",
                path.to_str().unwrap(),
                "--base",
                "base",
                "--tip",
                "tip",
            ];
            insta::with_settings!({snapshot_suffix => format!("{case}_{sheet}")}, {
                insta::assert_snapshot!("repro", run(&args, None));
            });
            let mut json = args.to_vec();
            json.extend(["--format", "json"]);
            let (code, out, err) = exec(&json);
            assert_eq!(code, 0, "{case} {sheet}: {out}{err}");
            let report: Value = serde_json::from_str(&out).unwrap();
            // The literal comparison agrees to the URDF's rounding (exact cases to ~1e-15).
            let pos = report["max_position_error"].as_f64().unwrap();
            let rot = report["max_orientation_error"].as_f64().unwrap();
            assert!(
                pos < 5e-5 && rot < 5e-5,
                "{case} {sheet}: {pos} m {rot} rad"
            );
        }
    }
}

/// A sheet that makes a joint of the other type is a MISMATCH naming that joint and `type`
/// (and only that), in text and JSON.
#[test]
fn a_joint_of_the_other_type_is_named() {
    let _s = settings().bind_to_scope();
    for (sheet, robot, joint) in [
        ("ur5_prismatic_elbow", "ur5", "elbow_joint"),
        ("scara_revolute_quill", "scara_prismatic", "joint_3"),
    ] {
        let urdf = format!("fixtures/robots/{robot}/robot.urdf");
        let path = format!("fixtures/check/{sheet}.yaml");
        insta::with_settings!({snapshot_suffix => sheet}, {
            insta::assert_snapshot!("type", run(&["check", &urdf, "--sheet", &path], None));
        });
        let (code, out, _) = exec(&["check", &urdf, "--sheet", &path, "--format", "json"]);
        assert_eq!(code, 1, "{sheet}");
        let report: Value = serde_json::from_str(&out).unwrap();
        assert_eq!(report["matches"], false);
        let named: Vec<(String, String)> = report["differences"]
            .as_array()
            .unwrap()
            .iter()
            .map(|d| {
                (
                    d["joint"].as_str().unwrap_or("").to_string(),
                    d["parameter"].as_str().unwrap().to_string(),
                )
            })
            .collect();
        assert_eq!(named, [(joint.to_string(), "type".to_string())], "{sheet}");
        assert!(report["max_position_error"].as_f64().unwrap() > 1e-2);
    }
}
