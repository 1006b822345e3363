//! What `calibrate --out` writes is the fit: a 6R with parallel J2/J3 and planted tilts is
//! written with `beta`, never with a common normal kilometres away; the written sheet and URDF
//! read back to the fitted model's predictions (the proof on the artefact, echoed in the
//! report), the estimated effects are in the sheet's `effects` section, and every command reads
//! the written sheet.

use std::path::Path;

use serde_json::Value;

use crate::common::{exec, ok, simulate};

/// A 6R in the standard convention whose J2 and J3 axes are parallel (a Motoman-like arm).
const ARM: &str = "convention: standard
length_unit: m
angle_unit: deg
robot: parallel_6r
joints:
  - {name: joint_1, type: revolute, a: 0.15, alpha: -90, d: 0.45, theta: 0, lower: -170, upper: 170}
  - {name: joint_2, type: revolute, a: 0.6, alpha: 0, d: 0, theta: -90, lower: -90, upper: 120}
  - {name: joint_3, type: revolute, a: 0.1, alpha: -90, d: 0, theta: 0, lower: -80, upper: 150}
  - {name: joint_4, type: revolute, a: 0, alpha: 90, d: 0.64, theta: 0, lower: -180, upper: 180}
  - {name: joint_5, type: revolute, a: 0, alpha: -90, d: 0, theta: 0, lower: -120, upper: 120}
  - {name: joint_6, type: revolute, a: 0, alpha: 0, d: 0.1, theta: 0, lower: -360, upper: 360}
";

/// The arm's reach bound: the sum of its lengths (`DhTable::size`), plus the metre the writer
/// may add at most.
const LENGTH_BOUND: f64 = 0.15 + 0.45 + 0.6 + 0.1 + 0.64 + 0.1 + 1.0;

fn path(dir: &Path, name: &str) -> String {
    dir.join(name).to_string_lossy().into_owned()
}

/// Every length a sheet writes (metres): `a`, `d`, base and tool offsets.
fn lengths(sheet: &Value) -> Vec<f64> {
    let mut out: Vec<f64> = sheet["joints"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|j| [j["a"].as_f64().unwrap(), j["d"].as_f64().unwrap()])
        .collect();
    for t in ["base", "tool"] {
        let xyz = sheet[t]["xyz"].as_array().unwrap();
        out.push(
            xyz.iter()
                .map(|v| v.as_f64().unwrap().powi(2))
                .sum::<f64>()
                .sqrt(),
        );
    }
    out
}

#[test]
fn a_parallel_pair_is_written_with_beta_and_the_artefact_reproduces_the_fit() {
    let dir = tempfile::tempdir().unwrap();
    let model = path(dir.path(), "arm.yaml");
    std::fs::write(&model, ARM).unwrap();
    let data = path(dir.path(), "d.csv");
    simulate(
        &model,
        "80",
        &data,
        &[
            "--noise",
            "1e-5",
            "--targets",
            "3",
            "--error",
            "joint_2.beta=4e-4",
            "--error",
            "joint_3.a=1.5e-3",
            "--error",
            "joint_2.theta=-1e-3",
            "--error",
            "joint_5.alpha=5e-4",
            "--effect",
            "gear_ratio:joint_3=2e-3",
            "--seed",
            "11",
        ],
    );
    let (yaml, json, urdf) = (
        path(dir.path(), "cal.yaml"),
        path(dir.path(), "cal.json"),
        path(dir.path(), "cal.urdf"),
    );
    let mut reports = Vec::new();
    for out in [&yaml, &json, &urdf] {
        let r = ok(&[
            "calibrate",
            "--model",
            &model,
            "--data",
            &data,
            "--effects",
            "gear_ratio:joint_3",
            "--format",
            "json",
            "--out",
            out,
        ]);
        let r: Value = serde_json::from_str(&r).unwrap();
        // The proof on the artefact, echoed in the report.
        let w = &r["written"];
        assert_eq!(w["passed"], true, "{w}");
        assert!(w["max_deviation"].as_f64().unwrap() < 1e-9, "{w}");
        assert!(w["points"].as_u64().unwrap() >= 200, "{w}");
        assert!(w["max_length"].as_f64().unwrap() <= LENGTH_BOUND, "{w}");
        reports.push(r);
    }
    let report = &reports[0];
    assert!(report["rms_after"].as_f64().unwrap() < 2e-5, "{report}");

    let sheet: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    // Every length is bounded: no kilometre common normal.
    for l in lengths(&sheet) {
        assert!(l.abs() <= LENGTH_BOUND, "a written length of {l} m");
    }
    // The pair's tilt is written on J2's row (standard: the row holding the link), in degrees,
    // and it is the planted one within its standard error.
    let beta = sheet["joints"][1]["beta"]
        .as_f64()
        .expect("joint_2 has beta");
    let estimate = report["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["name"] == "joint_2.beta")
        .unwrap();
    let sigma = estimate["std_error"].as_f64().unwrap();
    assert!(
        (beta.to_radians() - 4e-4).abs() < 5.0 * sigma,
        "{beta} deg, sigma {sigma}"
    );
    assert!(sheet["joints"][0].get("beta").is_none());
    // The estimated effect, with its unit and uncertainty.
    let effects = sheet["effects"].as_array().expect("an effects section");
    assert_eq!(effects.len(), 1);
    assert_eq!(effects[0]["name"], "gear_ratio:joint_3");
    assert_eq!(effects[0]["unit"], "rad/rad");
    let (g, s) = (
        effects[0]["value"].as_f64().unwrap(),
        effects[0]["std_error"].as_f64().unwrap(),
    );
    assert!((g - 2e-3).abs() < 5.0 * s, "{g} +- {s}");

    // Every command reads the written sheet. check: the written URDF and sheet are one robot,
    // the effects named in a warning.
    let (code, _, err) = exec(&["check", &urdf, "--sheet", &yaml]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("'gear_ratio:joint_3'"), "{err}");
    // to-urdf writes the tilt into the joint origins, and says what it leaves out.
    let (code, text, err) = exec(&["to-urdf", &yaml]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("effects: 'gear_ratio:joint_3'"), "{err}");
    let again = path(dir.path(), "again.urdf");
    std::fs::write(&again, text).unwrap();
    ok(&["check", &again, "--sheet", &yaml]);
    // convert keeps the tilts exact, in both directions, and the effects.
    let (code, modified, err) = exec(&["convert", &yaml, "--to", "modified", "--format", "json"]);
    assert_eq!(code, 0, "{err}");
    let m: Value = serde_json::from_str(&modified).unwrap();
    assert!(m["joints"][2]["beta"].as_f64().is_some(), "{m}");
    assert_eq!(m["effects"][0]["name"], "gear_ratio:joint_3");
    let conv = path(dir.path(), "modified.json");
    std::fs::write(&conv, modified).unwrap();
    ok(&["check", &urdf, "--sheet", &conv]);
    // calibrate --model reads the written sheet: starting there, the nominal step (device and
    // targets only) lands on the geometric fit's RMS.
    let geometric = path(dir.path(), "geo.yaml");
    let first: Value = serde_json::from_str(&ok(&[
        "calibrate",
        "--model",
        &model,
        "--data",
        &data,
        "--format",
        "json",
        "--out",
        &geometric,
    ]))
    .unwrap();
    let (code, second, err) = exec(&[
        "calibrate",
        "--model",
        &geometric,
        "--data",
        &data,
        "--format",
        "json",
    ]);
    assert_eq!(code, 0, "{err}");
    let second: Value = serde_json::from_str(&second).unwrap();
    let (a, b) = (
        first["rms_after"].as_f64().unwrap(),
        second["steps"][0]["rms"].as_f64().unwrap(),
    );
    assert!(
        (a - b).abs() < 1e-9,
        "fitted {a} m, the written model's nominal step {b} m"
    );
    // simulate --model reads it too, and names the effects it does not apply.
    let (code, _, err) = exec(&[
        "simulate",
        "--model",
        &yaml,
        "--poses",
        "5",
        "--out",
        &path(dir.path(), "s.csv"),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("'gear_ratio:joint_3'"), "{err}");
}

#[test]
fn measured_near_parallel_axes_are_written_with_beta_and_proved_against_the_axes() {
    let Some(shared) =
        crate::common::skip_without_shared("measured_near_parallel_axes_are_written_with_beta")
    else {
        return;
    };
    let set = shared.join("measured/boby_klimchik_laser_tracker_cpa/N1N2N3Jval.csv");
    let dir = tempfile::tempdir().unwrap();
    let data = path(dir.path(), "boby.csv");
    ok(&["import", &set.to_string_lossy(), "--out", &data]);
    let doc: Value = serde_json::from_str(&ok(&["cpa", &data, "--format", "json"])).unwrap();
    // J2 and J3 are 1.8e-4 rad from antiparallel: the tilt is written on J2's row.
    let beta = doc["joints"][1]["beta"].as_f64().expect("joint_2 has beta");
    assert!((beta.abs() - 1.8e-4).abs() < 1e-5, "{beta}");
    let lengths = lengths(&doc);
    assert!(lengths.iter().all(|l| l.abs() < 5.0), "{lengths:?}");
    // The written table against the measured axes: the orientation is exact, and what is
    // left in position is the J4/J5 intersection snap within the 0.1 mm linear tolerance;
    // snapping J2/J3 would cost a quarter of a millimetre and 1.7e-4 rad.
    let proof = &doc["cpa"]["proof"];
    let (written, snapped) = (&proof["written"], &proof["snapped"]);
    assert!(written[1].as_f64().unwrap() < 1e-12, "{proof}");
    assert!(written[0].as_f64().unwrap() < 1e-4, "{proof}");
    assert!(snapped[1].as_f64().unwrap() > 1e-4, "{proof}");
    assert!(snapped[0].as_f64().unwrap() > 2e-4, "{proof}");
}

#[test]
fn a_urdf_model_is_written_as_a_minimal_edit_of_itself() {
    let model = "fixtures/robots/franka_panda/robot.urdf";
    let dir = tempfile::tempdir().unwrap();
    let data = path(dir.path(), "p.csv");
    simulate(
        model,
        "60",
        &data,
        &[
            "--noise",
            "1e-5",
            "--targets",
            "2",
            "--random-errors",
            "0.001, 0.001",
            "--seed",
            "3",
        ],
    );
    let (urdf, sheet) = (path(dir.path(), "p.urdf"), path(dir.path(), "p.yaml"));
    for out in [&urdf, &sheet] {
        ok(&["calibrate", "--model", model, "--data", &data, "--out", out]);
    }
    let before = std::fs::read_to_string(crate::common::root().join(model)).unwrap();
    let after = std::fs::read_to_string(&urdf).unwrap();
    // The same document line for line; only `<origin>` lines of joints differ, and some do.
    let (b, a): (Vec<&str>, Vec<&str>) = (before.lines().collect(), after.lines().collect());
    assert_eq!(b.len(), a.len());
    let changed: Vec<(&str, &str)> = b
        .iter()
        .zip(&a)
        .filter(|(x, y)| x != y)
        .map(|(x, y)| (*x, *y))
        .collect();
    assert!(changed.len() >= 5, "{changed:?}");
    for (x, y) in &changed {
        assert!(
            x.trim_start().starts_with("<origin") && y.trim_start().starts_with("<origin"),
            "{x} -> {y}"
        );
    }
    // Extracting the written URDF reproduces the calibrated model: check against the sheet the
    // same fit wrote (base and tool given) finds no difference.
    ok(&["check", &urdf, "--sheet", &sheet]);
    // And the nominal URDF differs from it.
    let (code, _, _) = exec(&["check", model, "--sheet", &sheet]);
    assert_eq!(code, 1);
}

#[test]
fn a_urdf_whose_extraction_puts_a_common_normal_kilometres_away_is_written_bounded() {
    // The arm with J3's axis 2e-4 rad off J2's: a URDF of it (to-urdf writes the tilt into the
    // joint origins) extracts to a plain DH row kilometres long.
    let dir = tempfile::tempdir().unwrap();
    let tilted = path(dir.path(), "tilted.yaml");
    std::fs::write(
        &tilted,
        ARM.replace("d: 0, theta: -90,", "d: 0, theta: -90, beta: 0.0114592,"),
    )
    .unwrap();
    let urdf = path(dir.path(), "arm.urdf");
    std::fs::write(&urdf, ok(&["to-urdf", &tilted])).unwrap();
    let extracted: Value =
        serde_json::from_str(&ok(&["extract", &urdf, "--format", "json"])).unwrap();
    assert!(
        lengths(&extracted).iter().any(|l| l.abs() > 1000.0),
        "{extracted}"
    );
    let data = path(dir.path(), "d.csv");
    simulate(
        &tilted,
        "60",
        &data,
        &[
            "--noise",
            "1e-5",
            "--targets",
            "3",
            "--error",
            "joint_3.a=1e-3",
            "--seed",
            "5",
        ],
    );
    let out = path(dir.path(), "cal.json");
    let r: Value = serde_json::from_str(&ok(&[
        "calibrate",
        "--model",
        &urdf,
        "--data",
        &data,
        "--format",
        "json",
        "--out",
        &out,
    ]))
    .unwrap();
    assert_eq!(r["written"]["passed"], true, "{}", r["written"]);
    let sheet: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    for l in lengths(&sheet) {
        assert!(l.abs() <= LENGTH_BOUND, "a written length of {l} m");
    }
    assert!(sheet["joints"][1]["beta"].as_f64().is_some(), "{sheet}");
}
