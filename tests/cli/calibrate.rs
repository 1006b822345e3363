//! `urdf-dh simulate | urdf-dh calibrate` round trips: planted errors and effects come back
//! within their standard errors and the final RMS sits on the noise floor; the report, the
//! calibrated model and the residual chart as files.

use crate::common::{ok, simulate};
use std::path::Path;

use serde_json::Value;

use crate::common::{run, settings};

pub(crate) const UR5: &str = "fixtures/robots/ur5/vendor.yaml";

pub(crate) fn path(dir: &Path, name: &str) -> String {
    dir.join(name).to_string_lossy().into_owned()
}

/// A parameter of the JSON report.
fn parameter<'a>(report: &'a Value, name: &str) -> &'a Value {
    report["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["name"] == name)
        .unwrap_or_else(|| panic!("no parameter {name}"))
}

/// `estimate - nominal` of a parameter, in units of its standard error.
pub(crate) fn recovered(report: &Value, name: &str, planted: f64) -> f64 {
    let p = parameter(report, name);
    assert_eq!(p["free"], true, "{name} is not estimated: {p}");
    let change = p["estimate"].as_f64().unwrap() - p["nominal"].as_f64().unwrap();
    (change - planted) / p["std_error"].as_f64().unwrap()
}

const PLANTED: [(&str, f64); 6] = [
    ("shoulder_lift_joint.a", 5e-4),
    ("elbow_joint.a", -3e-4),
    ("elbow_joint.theta", 1e-3),
    ("wrist_1_joint.d", -4e-4),
    ("wrist_1_joint.alpha", 8e-4),
    ("wrist_2_joint.theta", -6e-4),
];

#[test]
fn planted_geometric_errors_come_back_and_the_fit_reaches_the_noise_floor() {
    let dir = tempfile::tempdir().unwrap();
    let data = path(dir.path(), "ur5.csv");
    let errors: Vec<String> = PLANTED.iter().map(|(n, v)| format!("{n}={v}")).collect();
    let mut args = vec![
        "simulate",
        "--model",
        UR5,
        "--poses",
        "300",
        "--noise",
        "5e-5",
        "--targets",
        "3",
        "--seed",
        "11",
        "--out",
        &data,
    ];
    for e in &errors {
        args.extend(["--error", e]);
    }
    ok(&args);
    let truth: serde_yaml::Value =
        serde_yaml::from_str(&std::fs::read_to_string(path(dir.path(), "ur5.truth.yaml")).unwrap())
            .unwrap();
    assert_eq!(truth["truth"]["errors"].as_sequence().unwrap().len(), 6);

    let out = path(dir.path(), "calibrated.yaml");
    let json = ok(&[
        "calibrate",
        "--model",
        UR5,
        "--data",
        &data,
        "--format",
        "json",
        "--out",
        &out,
    ]);
    crate::common::assert_library_calibrates_as_the_cli(UR5, &data, None, Some(&out), &json);
    let report: Value = serde_json::from_str(&json).unwrap();
    let steps: Vec<&str> = report["steps"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["label"].as_str().unwrap())
        .collect();
    assert_eq!(steps, ["nominal", "geometric"]);
    for (name, planted) in PLANTED {
        let z = recovered(&report, name, planted);
        assert!(z.abs() < 4.0, "{name}: {z:.2} standard errors off");
    }
    let floor = report["noise_floor"].as_f64().unwrap();
    let after = report["rms_after"].as_f64().unwrap();
    assert!(
        (after / floor - 1.0).abs() < 0.05,
        "rms after {after} against noise floor {floor}"
    );
    assert_eq!(report["noise"]["source"], "samples");
    // The planted errors are millimetres: the nominal model is far above the floor.
    assert!(report["rms_before"].as_f64().unwrap() > 5.0 * floor);
    // k-fold cross-validation: held-out residuals near the fit's.
    assert_eq!(report["validation"]["method"], "k-fold");
    let val = report["val_rms_after"].as_f64().unwrap();
    assert!(val < 1.1 * after, "validation {val} against {after}");
    assert_eq!(report["units"]["length"], "m");
    assert!(report["selected_effects"].as_array().unwrap().is_empty());
    assert!(report["condition_number"].as_f64().unwrap() >= 1.0);
    // What cannot be told from the device frame or the targets is fixed, with its aliases.
    let fixed = report["fixed"].as_array().unwrap();
    let base_z = fixed.iter().find(|f| f["name"] == "base.z").unwrap();
    assert!(base_z["aliases"]
        .as_array()
        .unwrap()
        .iter()
        .any(|a| a == "device.z"));

    // The calibrated sheet reads back as a model and fits the data as well as the report says.
    let again: Value = serde_json::from_str(&ok(&[
        "calibrate",
        "--model",
        &out,
        "--data",
        &data,
        "--format",
        "json",
    ]))
    .unwrap();
    let nominal_again = again["rms_before"].as_f64().unwrap();
    assert!(
        nominal_again < 1.01 * after,
        "the calibrated sheet's nominal RMS {nominal_again} against {after}"
    );
}

#[test]
fn a_planted_gear_ratio_is_found_by_the_effect_step() {
    let dir = tempfile::tempdir().unwrap();
    let data = path(dir.path(), "gear.csv");
    let out = path(dir.path(), "gear.yaml");
    simulate(
        UR5,
        "200",
        &data,
        &[
            "--noise",
            "3e-5",
            "--targets",
            "2",
            "--effect",
            "gear_ratio:elbow_joint=0.002",
            "--seed",
            "3",
        ],
    );
    let report: Value = serde_json::from_str(&ok(&[
        "calibrate",
        "--model",
        UR5,
        "--data",
        &data,
        "--format",
        "json",
        "--effects",
        "gear_ratio:elbow_joint",
        "--out",
        &out,
    ]))
    .unwrap();
    // The written sheet keeps the effect beside the table (effects are no DH parameters).
    let sheet: serde_yaml::Value =
        serde_yaml::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let effects = sheet["calibration"]["effects"].as_sequence().unwrap();
    assert_eq!(effects.len(), 1);
    assert_eq!(effects[0][0].as_str(), Some("gear_ratio:elbow_joint"));
    assert!((effects[0][1].as_f64().unwrap() - 0.002).abs() < 1e-4);
    let steps: Vec<&str> = report["steps"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["label"].as_str().unwrap())
        .collect();
    assert_eq!(steps, ["nominal", "geometric", "effects"]);
    assert_eq!(
        report["selected_effects"],
        serde_json::json!(["gear_ratio:elbow_joint"])
    );
    let z = recovered(&report, "gear_ratio:elbow_joint", 0.002);
    assert!(z.abs() < 4.0, "gear ratio {z:.2} standard errors off");
    // Without the effect the geometric step cannot reach the floor; with it, it does.
    let floor = report["noise_floor"].as_f64().unwrap();
    let geometric = report["steps"][1]["rms"].as_f64().unwrap();
    let after = report["rms_after"].as_f64().unwrap();
    assert!(
        geometric > 3.0 * floor,
        "geometric {geometric}, floor {floor}"
    );
    assert!(
        (after / floor - 1.0).abs() < 0.05,
        "after {after}, floor {floor}"
    );
}

#[test]
fn the_text_report_shows_every_step() {
    let _snap = settings().bind_to_scope();
    let dir = tempfile::tempdir().unwrap();
    let data = path(dir.path(), "small.csv");
    simulate(
        UR5,
        "40",
        &data,
        &[
            "--noise",
            "1e-4",
            "--seed",
            "5",
            "--error",
            "elbow_joint.a=0.001",
            "--validation",
            "0.25",
        ],
    );
    let mut s = settings();
    s.add_filter(
        regex_escape(&dir.path().to_string_lossy()).as_str(),
        "[tmp]",
    );
    s.bind(|| {
        insta::assert_snapshot!(run(&["calibrate", "--model", UR5, "--data", &data], None));
    });
}

fn regex_escape(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '/' || c == '_' {
                c.to_string()
            } else {
                format!("\\{c}")
            }
        })
        .collect()
}

#[test]
fn the_calibrated_model_is_written_as_a_sheet_or_a_urdf_and_the_chart_is_xml() {
    let dir = tempfile::tempdir().unwrap();
    let data = path(dir.path(), "d.csv");
    simulate(
        "fixtures/robots/franka_panda/robot.urdf",
        "60",
        &data,
        &["--noise", "2e-5", "--targets", "2", "--seed", "2"],
    );
    let (urdf, json, svg) = (
        path(dir.path(), "cal.urdf"),
        path(dir.path(), "cal.json"),
        path(dir.path(), "res.svg"),
    );
    ok(&[
        "calibrate",
        "--model",
        "fixtures/robots/franka_panda/robot.urdf",
        "--data",
        &data,
        "--out",
        &urdf,
        "--plot",
        &svg,
    ]);
    ok(&[
        "calibrate",
        "--model",
        "fixtures/robots/franka_panda/robot.urdf",
        "--data",
        &data,
        "--out",
        &json,
    ]);
    // The URDF's own extraction verifies, and it names the chain's links.
    let text = std::fs::read_to_string(&urdf).unwrap();
    assert!(text.contains("<link name=\"base_link\"/>") && text.contains("panda_link8"));
    ok(&["extract", &urdf, "--samples", "100"]);
    // The JSON sheet has the calibration section (metres, radians).
    let sheet: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(sheet["joints"].as_array().unwrap().len(), 7);
    assert!(sheet["calibration"]["rms_after"].as_f64().unwrap() < 1e-4);
    assert_eq!(sheet["calibration"]["targets"].as_array().unwrap().len(), 2);
    // The chart: well-formed XML, an SVG root, a dot per sample in each of its two panels.
    let svg = std::fs::read_to_string(&svg).unwrap();
    let doc = roxmltree::Document::parse(&svg).expect("well-formed XML");
    assert_eq!(doc.root_element().tag_name().name(), "svg");
    let dots = doc
        .descendants()
        .filter(|n| n.has_tag_name("circle"))
        .count();
    assert_eq!(
        dots,
        2 * 120 + 2,
        "two panels of 120 samples and the legend"
    );
    // No temporary files are left beside the outputs.
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        ["cal.json", "cal.urdf", "d.csv", "d.truth.yaml", "res.svg"]
    );
}

#[test]
fn a_separate_validation_file_is_used_for_validation() {
    let dir = tempfile::tempdir().unwrap();
    let (all, cal, val) = (
        path(dir.path(), "all.csv"),
        path(dir.path(), "cal.csv"),
        path(dir.path(), "val.csv"),
    );
    simulate(
        UR5,
        "80",
        &all,
        &[
            "--noise",
            "2e-5",
            "--seed",
            "7",
            "--error",
            "elbow_joint.a=0.001",
            "--validation",
            "0.25",
        ],
    );
    // Split the file by its `set` column into two files of the same layout.
    let text = std::fs::read_to_string(&all).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header = lines.next().unwrap();
    let (mut c, mut v) = (format!("{header}\n"), format!("{header}\n"));
    for l in lines {
        if l.ends_with(",validation") {
            v += &format!("{l}\n");
        } else {
            c += &format!("{l}\n");
        }
    }
    std::fs::write(&cal, c).unwrap();
    std::fs::write(&val, v).unwrap();
    let report: Value = serde_json::from_str(&ok(&[
        "calibrate",
        "--model",
        UR5,
        "--data",
        &cal,
        "--validate",
        &val,
        "--format",
        "json",
    ]))
    .unwrap();
    let whole: Value = serde_json::from_str(&ok(&[
        "calibrate",
        "--model",
        UR5,
        "--data",
        &all,
        "--format",
        "json",
    ]))
    .unwrap();
    assert_eq!(report["validation"]["method"], "split");
    assert_eq!(report["validation_samples"], 20);
    assert_eq!(report["validate"], "val.csv");
    // The same split as the file's own `set` column, so the same figures.
    for key in ["rms_after", "val_rms_after", "val_rms_before"] {
        let (a, b) = (report[key].as_f64().unwrap(), whole[key].as_f64().unwrap());
        assert!((a - b).abs() <= 1e-9 * b, "{key}: {a} against {b}");
    }
    assert!(report["val_rms_after"].as_f64().unwrap() < 1e-4);
}

#[test]
fn without_a_model_the_start_is_the_circle_point_analysis() {
    let dir = tempfile::tempdir().unwrap();
    let data = path(dir.path(), "cpa.csv");
    simulate(
        UR5,
        "8",
        &data,
        &["--cpa", "--noise", "2e-5", "--targets", "3", "--seed", "4"],
    );
    let report: Value =
        serde_json::from_str(&ok(&["calibrate", "--data", &data, "--format", "json"])).unwrap();
    assert_eq!(report["model"], "circle-point analysis of cpa.csv");
    let floor = report["noise_floor"].as_f64().unwrap();
    let after = report["rms_after"].as_f64().unwrap();
    assert!(after < 1.2 * floor, "after {after}, floor {floor}");
}

#[test]
fn bad_input_exits_2_naming_the_line_and_column() {
    let _snap = settings().bind_to_scope();
    let dir = tempfile::tempdir().unwrap();
    let bad = path(dir.path(), "bad.csv");
    std::fs::write(
        &bad,
        "# a comment\nshoulder_pan_joint,shoulder_lift_joint,elbow_joint,wrist_1_joint,wrist_2_joint,wrist_3_joint,x,y,z\n0,0,0,0,0,0,1,2,3\n0,0.1,0,0,0,0,1,2,x3\n",
    )
    .unwrap();
    let mut s = settings();
    s.add_filter(
        regex_escape(&dir.path().to_string_lossy()).as_str(),
        "[tmp]",
    );
    s.bind(|| {
        insta::assert_snapshot!(
            "bad_number",
            run(&["calibrate", "--model", UR5, "--data", &bad], None)
        );
        std::fs::write(&bad, "joint_1,joint_2,x,y,z\n0,0,1,2,3\n").unwrap();
        insta::assert_snapshot!(
            "missing_joints",
            run(&["calibrate", "--model", UR5, "--data", &bad], None)
        );
        let good = path(dir.path(), "good.csv");
        simulate(UR5, "10", &good, &[]);
        insta::assert_snapshot!(
            "unknown_effect",
            run(
                &[
                    "calibrate",
                    "--model",
                    UR5,
                    "--data",
                    &good,
                    "--effects",
                    "wobble:elbow_joint"
                ],
                None
            )
        );
    });
}
