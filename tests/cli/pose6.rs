//! 6-DoF poses end to end: `simulate --orientation-noise` writes orientation columns,
//! `calibrate` fits them (angle RMS at its noise floor, JSON and text), and bad orientation
//! cells exit 2 naming the file, line and column; an effect planted with `--effect` turns the
//! orientations too.

use serde_json::Value;

use crate::common::{csv_rows, exec, ok, simulate};

const MODEL: &str = "fixtures/robots/ur5/vendor.yaml";
const HEADER: &str = "shoulder_pan_joint,shoulder_lift_joint,elbow_joint,wrist_1_joint,wrist_2_joint,wrist_3_joint,x,y,z,sigma,qw,qx,qy,qz,sigma_rot\n";

#[test]
fn simulated_six_dof_poses_calibrate_to_both_noise_floors() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("p.csv").to_string_lossy().into_owned();
    simulate(
        MODEL,
        "120",
        &data,
        &[
            "--noise",
            "20e-6",
            "--orientation-noise",
            "50e-6",
            "--random-errors",
            "0.0005, 0.0003",
            "--seed",
            "3",
        ],
    );
    let text = std::fs::read_to_string(&data).unwrap();
    assert!(text.contains(",qw,qx,qy,qz,sigma_rot\n"), "{text}");
    let report: Value = serde_json::from_str(&ok(&[
        "calibrate",
        "--model",
        MODEL,
        "--data",
        &data,
        "--format",
        "json",
    ]))
    .unwrap();
    let last = report["steps"].as_array().unwrap().last().unwrap().clone();
    let angle = last["angle_rms"].as_f64().unwrap();
    let angle_floor = report["angle_noise_floor"].as_f64().unwrap();
    let (rms, floor) = (
        report["rms_after"].as_f64().unwrap(),
        report["noise_floor"].as_f64().unwrap(),
    );
    for (r, f) in [(rms, floor), (angle, angle_floor)] {
        assert!((r / f - 1.0).abs() < 0.1, "rms {r:e}, floor {f:e}");
    }
    let free: Vec<&str> = report["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|p| p["free"] == true)
        .map(|p| p["name"].as_str().unwrap())
        .collect();
    assert!(free.contains(&"target.t1.rz"), "{free:?}");
    let text = ok(&["calibrate", "--model", MODEL, "--data", &data]);
    assert!(text.contains("\nangle: RMS "), "{text}");
}

#[test]
fn bad_orientations_exit_2_naming_file_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let good = "0,0,0,0,0,0,1,2,3,2e-5,1,0,0,0,5e-5\n";
    for (row, header, message) in [
        (
            "0,0,0,0,0.1,0,1,2,3,2e-5,1.2,0,0,0,5e-5\n",
            HEADER,
            "bad.csv: line 3: expected a unit quaternion in columns qw, qx, qy, qz (norm within 0.001 of 1), found norm 1.2",
        ),
        (
            "0,0,0,0,0.1,0,1,2,3,2e-5,1,NaN,0,0,5e-5\n",
            HEADER,
            "bad.csv: line 3",
        ),
        (
            "0,0,0,0,0.1,0,1,2,3,2e-5,1,0,0,0,\n",
            HEADER,
            "bad.csv: line 3: expected a standard deviation in column 'sigma_rot' (radians) for an orientation, found an empty cell",
        ),
    ] {
        let path = dir.path().join("bad.csv");
        std::fs::write(&path, format!("{header}{good}{row}")).unwrap();
        let (code, out, err) = exec(&[
            "calibrate",
            "--model",
            MODEL,
            "--data",
            &path.to_string_lossy(),
        ]);
        assert_eq!(code, 2, "{err}");
        assert!(out.is_empty());
        assert!(err.contains(message), "{err}");
        if row.contains("NaN") {
            assert!(err.contains("qx"), "{err}");
        }
    }
    // The column sigma_rot itself missing.
    let path = dir.path().join("bad.csv");
    let header = HEADER.replace(",sigma_rot", "");
    std::fs::write(
        &path,
        format!("{header}0,0,0,0,0,0,1,2,3,2e-5,1,0,0,0\n0,0,0,0,0.1,0,1,2,3,2e-5,1,0,0,0\n"),
    )
    .unwrap();
    let (code, _, err) = exec(&[
        "calibrate",
        "--model",
        MODEL,
        "--data",
        &path.to_string_lossy(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("bad.csv: line 1: missing point column 'sigma_rot'"),
        "{err}"
    );
}

/// The truth file gives every 6-DoF target's rotation, and the report the estimated one, both
/// as URDF roll-pitch-yaw of the target's frame in the tip frame: with no geometric error
/// planted (nothing for the targets to absorb), they agree to the noise.
#[test]
fn target_rotations_are_in_the_truth_and_the_report() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("r.csv").to_string_lossy().into_owned();
    let truth_path = dir.path().join("r.truth.yaml");
    simulate(
        MODEL,
        "120",
        &data,
        &[
            "--noise",
            "20e-6",
            "--orientation-noise",
            "50e-6",
            "--targets",
            "2",
            "--seed",
            "3",
        ],
    );
    let truth: serde_yaml::Value =
        serde_yaml::from_str(&std::fs::read_to_string(&truth_path).unwrap()).unwrap();
    let report: Value = serde_json::from_str(&ok(&[
        "calibrate",
        "--model",
        MODEL,
        "--data",
        &data,
        "--format",
        "json",
    ]))
    .unwrap();
    let targets = report["targets"].as_array().unwrap();
    assert_eq!(targets.len(), 2);
    for (k, t) in targets.iter().enumerate() {
        let true_t = &truth["truth"]["targets"][k];
        assert_eq!(t["name"].as_str(), true_t["name"].as_str());
        for a in 0..3 {
            let (est, tru) = (
                t["rpy"][a].as_f64().unwrap(),
                true_t["rpy"][a].as_f64().unwrap(),
            );
            // 240 poses at 50 µrad per axis: the frame is known to a few µrad; 1e-4 rad is
            // twice the single-pose noise.
            assert!(
                (est - tru).abs() < 1e-4,
                "{}: rpy[{a}] {est} vs {tru}",
                t["name"]
            );
            let (est, tru) = (
                t["xyz"][a].as_f64().unwrap(),
                true_t["xyz"][a].as_f64().unwrap(),
            );
            assert!(
                (est - tru).abs() < 2e-5,
                "{}: xyz[{a}] {est} vs {tru}",
                t["name"]
            );
        }
    }
    // A point set has no rotations, in the truth or the report.
    let points = dir.path().join("p.csv").to_string_lossy().into_owned();
    simulate(MODEL, "30", &points, &[]);
    let report: Value = serde_json::from_str(&ok(&[
        "calibrate",
        "--model",
        MODEL,
        "--data",
        &points,
        "--format",
        "json",
    ]))
    .unwrap();
    assert!(report["targets"][0].get("rpy").is_none());
    let truth: serde_yaml::Value =
        serde_yaml::from_str(&std::fs::read_to_string(dir.path().join("p.truth.yaml")).unwrap())
            .unwrap();
    let target = &truth["truth"]["targets"][0];
    assert!(
        target.get("xyz").is_some() && target.get("rpy").is_none(),
        "{target:?}"
    );
}

/// An effect planted with `--effect` turns the simulated orientations too (the tip frame of
/// the robot with the effect): `--effects auto` finds it and recovers its value within 3
/// standard errors, position and angle RMS at their floors, and the truth's target rotation
/// is still the one calibrate estimates.
#[test]
fn a_planted_effect_turns_the_orientations_and_is_found() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("e.csv").to_string_lossy().into_owned();
    let truth_path = dir.path().join("e.truth.yaml");
    simulate(
        MODEL,
        "120",
        &data,
        &[
            "--noise",
            "20e-6",
            "--orientation-noise",
            "50e-6",
            "--effect",
            "gear_ratio:elbow_joint=1e-3",
            "--seed",
            "3",
        ],
    );
    let truth: serde_yaml::Value =
        serde_yaml::from_str(&std::fs::read_to_string(&truth_path).unwrap()).unwrap();
    assert_eq!(
        truth["truth"]["effects"][0][0].as_str(),
        Some("gear_ratio:elbow_joint")
    );
    let report: Value = serde_json::from_str(&ok(&[
        "calibrate",
        "--model",
        MODEL,
        "--data",
        &data,
        "--effects",
        "auto",
        "--format",
        "json",
    ]))
    .unwrap();
    let selected: Vec<&str> = report["selected_effects"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e.as_str().unwrap())
        .collect();
    assert_eq!(selected, ["gear_ratio:elbow_joint"]);
    let p = report["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["name"] == "gear_ratio:elbow_joint")
        .unwrap();
    let (est, se) = (
        p["estimate"].as_f64().unwrap(),
        p["std_error"].as_f64().unwrap(),
    );
    assert!((est - 1e-3).abs() < 3.0 * se, "{est:e} ± {se:e}");
    let last = report["steps"].as_array().unwrap().last().unwrap().clone();
    for (r, f) in [
        (
            report["rms_after"].as_f64().unwrap(),
            report["noise_floor"].as_f64().unwrap(),
        ),
        (
            last["angle_rms"].as_f64().unwrap(),
            report["angle_noise_floor"].as_f64().unwrap(),
        ),
    ] {
        assert!((r / f - 1.0).abs() < 0.1, "rms {r:e}, floor {f:e}");
    }
    assert_eq!(report["verdict"]["summary"], "model complete");
    let (est, tru) = (
        &report["targets"][0]["rpy"],
        &truth["truth"]["targets"][0]["rpy"],
    );
    for a in 0..3 {
        let (e, t) = (est[a].as_f64().unwrap(), tru[a].as_f64().unwrap());
        // Twice one pose's orientation noise, as above.
        assert!((e - t).abs() < 1e-4, "rpy[{a}] {e} vs {t}");
    }
}

/// A calibration on 6-DoF data predicts: the sheet `calibrate --out` writes reads back with its
/// targets' rotations (the covariance names their `rx|ry|rz`), and `predict` gives each
/// target's position and attitude with their uncertainties, which the true robot (the truth
/// file, read the same way) agrees with at the rate the uncertainties state.
#[test]
fn a_six_dof_calibration_predicts_positions_and_attitudes() {
    let dir = tempfile::tempdir().unwrap();
    let path = |n: &str| dir.path().join(n).to_string_lossy().into_owned();
    let (data, cal, truth) = (path("d.csv"), path("cal.yaml"), path("d.truth.yaml"));
    simulate(
        MODEL,
        "120",
        &data,
        &[
            "--noise",
            "20e-6",
            "--orientation-noise",
            "50e-6",
            "--random-errors",
            "0.0005, 0.0003",
            "--seed",
            "5",
        ],
    );
    ok(&[
        "calibrate",
        "--model",
        MODEL,
        "--data",
        &data,
        "--out",
        &cal,
        "--quiet",
    ]);
    let est = csv_rows(&ok(&["predict", "--model", &cal, "--joints", &data]));
    let tru = csv_rows(&ok(&["predict", "--model", &truth, "--joints", &data]));
    assert_eq!(est.len(), 120);
    let num = |r: &std::collections::HashMap<String, String>, k: &str| -> f64 {
        r[k].parse()
            .unwrap_or_else(|_| panic!("{k}: {:?}", r.get(k)))
    };
    let (mut z2, mut n, mut worst_angle_z) = (0.0, 0.0, 0.0f64);
    for (e, t) in est.iter().zip(&tru) {
        for (c, u) in [("x", "u_x"), ("y", "u_y"), ("z", "u_z")] {
            let z = (num(e, c) - num(t, c)) / num(e, u);
            z2 += z * z;
            n += 1.0;
        }
        // The attitude: the angle between the estimated and the true rotation, against the
        // largest rotation uncertainty.
        let rot = |r: &std::collections::HashMap<String, String>| {
            dh_core::pose::from_xyz_rpy([0.0; 3], [num(r, "roll"), num(r, "pitch"), num(r, "yaw")])
                .rotation
        };
        let angle = rot(e).angle_to(&rot(t));
        let u = ["u_rx", "u_ry", "u_rz"].map(|k| num(e, k));
        assert!(u.iter().all(|v| *v > 0.0 && *v < 1e-3), "{u:?}");
        worst_angle_z = worst_angle_z.max(angle / u.iter().copied().fold(0.0, f64::max));
    }
    let rms_z = (z2 / n).sqrt();
    assert!((0.3..3.0).contains(&rms_z), "position z RMS {rms_z}");
    assert!(worst_angle_z < 6.0, "worst attitude {worst_angle_z} sigma");
}
