//! `urdf-dh cpa` on simulated sweeps: the measured axes reproduce the true robot's geometry.

use crate::common::{ok, simulate};
use std::process::Command;

use serde_json::Value;

use crate::common::root;

#[test]
fn sweeps_of_a_simulated_arm_give_its_axes_back() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("sweeps.csv").to_string_lossy().into_owned();
    let truth = dir
        .path()
        .join("sweeps.truth.yaml")
        .to_string_lossy()
        .into_owned();
    simulate(
        "fixtures/robots/ur5/vendor.yaml",
        "7",
        &data,
        &[
            "--cpa",
            "--noise",
            "1e-5",
            "--targets",
            "3",
            "--error",
            "elbow_joint.a=0.002",
            "--error",
            "wrist_1_joint.alpha=0.003",
            "--seed",
            "9",
        ],
    );
    // Compared with the truth (the simulated robot, errors included).
    let doc: Value =
        serde_json::from_str(&ok(&["cpa", &data, "--model", &truth, "--format", "json"])).unwrap();
    let cpa = &doc["cpa"];
    assert_eq!(cpa["joints"].as_array().unwrap().len(), 6);
    assert_eq!(cpa["sweeps"].as_array().unwrap().len(), 6);
    for j in cpa["joints"].as_array().unwrap() {
        assert_eq!(j["poses"], 7, "{}", j["name"]);
        // Noise of 10 um: the points sit on their circles to about that.
        assert!(j["circle_rms"].as_f64().unwrap() < 3e-5, "{j}");
        assert!(j["plane_rms"].as_f64().unwrap() < 3e-5, "{j}");
        // Commanded and measured motion agree: no transmission error was simulated.
        assert!(j["motion"]["rms"].as_f64().unwrap() < 1e-3, "{j}");
    }
    let pairs = cpa["pairs"].as_array().unwrap();
    assert_eq!(pairs.len(), 5);
    for p in pairs {
        let da =
            (p["measured_angle"].as_f64().unwrap() - p["nominal_angle"].as_f64().unwrap()).abs();
        let dd = (p["measured_distance"].as_f64().unwrap()
            - p["nominal_distance"].as_f64().unwrap())
        .abs();
        // 10 um of noise on circles of 0.1 m (the wrist) over a quarter turn: axis directions to
        // a few 1e-4 rad, positions to tens of micrometres.
        assert!(da < 5e-4 && dd < 1e-4, "{p}");
    }
    // The planted 2 mm on the elbow's link length is seen in the axis spacing.
    let elbow = pairs
        .iter()
        .find(|p| p["joints"][0] == "elbow_joint")
        .unwrap();
    assert!(
        (elbow["measured_distance"].as_f64().unwrap() - 0.39025).abs() < 2e-4,
        "{elbow}"
    );
    // The sheet part reads back as a model.
    let yaml = ok(&["cpa", &data, "--format", "yaml"]);
    let sheet = dir.path().join("cpa.yaml");
    std::fs::write(&sheet, yaml).unwrap();
    ok(&["convert", &sheet.to_string_lossy(), "--to", "modified"]);
}

#[test]
fn text_output_names_sweeps_and_joints() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("s.csv").to_string_lossy().into_owned();
    simulate(
        "fixtures/robots/puma560/vendor.yaml",
        "6",
        &data,
        &["--cpa", "--noise", "1e-5", "--targets", "2", "--seed", "1"],
    );
    let text = ok(&["cpa", &data]);
    assert!(
        text.starts_with("circle-point analysis of s.csv: 72 samples of 2 target(s)"),
        "{text}"
    );
    assert!(text.contains("extracted DH table"), "{text}");
    assert_eq!(text.matches(", 6 poses, span").count(), 6, "{text}");
}

#[test]
fn data_without_sweeps_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("random.csv").to_string_lossy().into_owned();
    simulate("fixtures/robots/ur5/vendor.yaml", "30", &data, &[]);
    let out = Command::new(env!("CARGO_BIN_EXE_urdf-dh"))
        .args(["cpa", &data])
        .current_dir(root())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("urdf-dh: error: random.csv: circle-point analysis failed"),
        "{err}"
    );
    assert!(err.contains("hint: "), "{err}");
}

/// `cpa --plot`: one panel per joint with its points and trend; a planted gear-ratio error is
/// the slope drawn on its joint's panel. `--plot -` pipes the chart alone (the report goes to
/// standard error); a chart over the data is refused before anything is written.
#[test]
fn the_plot_draws_each_joints_motion_and_its_trend() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name).to_string_lossy().into_owned();
    let (data, truth, svg) = (path("g.csv"), path("g.truth.yaml"), path("g.svg"));
    simulate(
        "fixtures/robots/ur5/vendor.yaml",
        "9",
        &data,
        &[
            "--cpa",
            "--noise",
            "1e-5",
            "--targets",
            "3",
            "--effect",
            "gear_ratio:elbow_joint=0.001",
            "--seed",
            "9",
        ],
    );
    let report = ok(&["cpa", &data, "--model", &truth, "--plot", &svg]);
    assert!(report.contains("elbow_joint"), "{report}");
    let chart = std::fs::read_to_string(&svg).unwrap();
    assert_eq!(chart.matches("<g>").count(), 6, "{chart}");
    // 9 poses per sweep: 54 points, one trend curve per joint.
    assert_eq!(chart.matches("<circle").count(), 54);
    assert_eq!(chart.matches("<polyline").count(), 6);
    assert!(!chart.contains("NaN") && !chart.contains("inf"));
    // The planted ratio is the elbow's slope, to the noise: 10 um at radii of about 0.4 m is
    // about 15 urad per pose, so the slope of 9 poses over 90 degrees has a standard error of
    // about 1e-5. Three of them.
    let elbow = chart
        .split("<g>")
        .find(|g| g.contains(">elbow_joint ("))
        .expect("an elbow panel");
    let slope: f64 = elbow
        .split("trend: slope ")
        .nth(1)
        .and_then(|t| t.split([',', ' ']).next())
        .and_then(|v| v.parse().ok())
        .expect("the elbow's trend is a slope");
    assert!((slope - 0.001).abs() < 3e-5, "slope {slope}");

    let (code, stdout, stderr) = crate::common::exec(&["cpa", &data, "--plot", "-"]);
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.starts_with("<?xml") && stdout.trim_end().ends_with("</svg>"));
    assert!(stderr.contains("elbow_joint"), "{stderr}");

    let before = std::fs::read(&data).unwrap();
    let (code, _, stderr) = crate::common::exec(&["cpa", &data, "--plot", &data]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("--plot"), "{stderr}");
    assert_eq!(std::fs::read(&data).unwrap(), before);
}

/// The joint's axis as (point nearest the origin, direction) from `cpa --format json`.
fn axes(doc: &Value) -> Vec<([f64; 3], [f64; 3])> {
    let v = |a: &Value| -> [f64; 3] {
        let a = a.as_array().unwrap();
        [0, 1, 2].map(|k| a[k].as_f64().unwrap())
    };
    doc["cpa"]["joints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| (v(&j["axis"]["point"]), v(&j["axis"]["direction"])))
        .collect()
}

#[test]
fn a_point_a_metre_off_is_left_out_and_named() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("sweeps.csv").to_string_lossy().into_owned();
    simulate(
        "fixtures/robots/ur5/vendor.yaml",
        "7",
        &data,
        &["--cpa", "--noise", "1e-5", "--targets", "3", "--seed", "4"],
    );
    let clean: Value = serde_json::from_str(&ok(&["cpa", &data, "--format", "json"])).unwrap();
    for j in clean["cpa"]["joints"].as_array().unwrap() {
        assert_eq!(j["screen"]["left_out"].as_array().unwrap().len(), 0, "{j}");
        assert_eq!(j["screen"]["sound"], true, "{j}");
    }
    // One point of the elbow's sweep 1 m off along x (a lost beam's reflection).
    let text = std::fs::read_to_string(&data).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let header: Vec<&str> = lines
        .iter()
        .find(|l| !l.starts_with('#'))
        .unwrap()
        .split(',')
        .collect();
    let col = |n: &str| header.iter().position(|c| *c == n).unwrap();
    let clean_doc = &clean["cpa"];
    let elbow = clean_doc["sweeps"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["joint"] == "elbow_joint")
        .unwrap();
    let line = elbow["lines"][0].as_u64().unwrap() as usize + 4;
    let mut cells: Vec<String> = lines[line - 1].split(',').map(String::from).collect();
    let x: f64 = cells[col("x")].parse().unwrap();
    cells[col("x")] = (x + 1.0).to_string();
    let target = cells[col("target")].clone();
    let mut out: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
    out[line - 1] = cells.join(",");
    let bad = dir.path().join("bad.csv").to_string_lossy().into_owned();
    std::fs::write(&bad, out.join("\n") + "\n").unwrap();

    let (code, stdout, stderr) = crate::common::exec(&["cpa", &bad, "--format", "json"]);
    assert_eq!(code, 0, "{stderr}");
    let doc: Value = serde_json::from_str(&stdout).unwrap();
    for (k, (a, b)) in axes(&clean).iter().zip(axes(&doc)).enumerate() {
        let d = |u: [f64; 3], v: [f64; 3]| {
            ((u[0] - v[0]).powi(2) + (u[1] - v[1]).powi(2) + (u[2] - v[2]).powi(2)).sqrt()
        };
        // The clean fit less one clean point, at 10 um of noise: the same axis to within the
        // noise (the point a metre off moved it by 0.3 m).
        assert!(
            d(a.0, b.0) < 5e-5 && d(a.1, b.1) < 5e-5,
            "joint {k}: {a:?} {b:?}"
        );
    }
    let joint = doc["cpa"]["joints"]
        .as_array()
        .unwrap()
        .iter()
        .find(|j| j["name"] == "elbow_joint")
        .unwrap();
    let left = joint["screen"]["left_out"].as_array().unwrap();
    assert_eq!(left.len(), 1, "{joint}");
    assert_eq!(left[0]["line"], line, "{joint}");
    assert_eq!(left[0]["target"], target.as_str(), "{joint}");
    let distance = left[0]["distance"].as_f64().unwrap();
    assert!((0.5..=1.0 + 1e-3).contains(&distance), "{distance}");
    // The text report names it.
    let text = ok(&["cpa", &bad]);
    assert!(
        text.contains("elbow_joint: 1 point(s) left out")
            && text.contains(&format!("  line {line}, target {target}: ")),
        "{text}"
    );
}
