//! `predict` and `compensate` on a simulated UR5 with planted errors: the calibrated model's
//! uncertainty matches its real error against the truth, its predictions read back as a
//! measurement file, and compensated joint values put the true robot's tool where the nominal
//! model puts it at the commanded ones.

use std::path::Path;

use crate::common::{csv_rows, exec, ok, simulate};

const UR5: &str = "fixtures/robots/ur5/vendor.yaml";

/// `(column name -> values)` rows of a CSV file written by the tool.
fn table(path: &Path) -> Vec<std::collections::HashMap<String, String>> {
    csv_rows(&std::fs::read_to_string(path).unwrap())
}

fn num(row: &std::collections::HashMap<String, String>, k: &str) -> f64 {
    row[k].parse().unwrap()
}

fn xyz(row: &std::collections::HashMap<String, String>) -> [f64; 3] {
    [num(row, "x"), num(row, "y"), num(row, "z")]
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
}

/// Simulated UR5 data (0.5 mm and 1 mrad planted, 50 µm noise), its calibration, and a robot
/// program of 100 other poses.
fn calibrated(dir: &Path) -> (String, String, String, String) {
    let p = |f: &str| dir.join(f).to_str().unwrap().to_string();
    let (data, truth, cal, program) = (
        p("ur5.csv"),
        p("truth.yaml"),
        p("cal.yaml"),
        p("program.csv"),
    );
    simulate(
        UR5,
        "200",
        &data,
        &[
            "--noise",
            "5e-5",
            "--targets",
            "3",
            "--error",
            "shoulder_lift_joint.a=0.0005",
            "--error",
            "elbow_joint.theta=0.001",
            "--seed",
            "7",
            "--truth",
            &truth,
        ],
    );
    ok(&["calibrate", "--model", UR5, "--data", &data, "--out", &cal]);
    simulate(
        UR5,
        "100",
        &program,
        &["--seed", "99", "--truth", &p("program.truth.yaml")],
    );
    (data, truth, cal, program)
}

#[test]
fn predictions_carry_an_uncertainty_that_matches_their_error_and_read_back_as_measurements() {
    let dir = tempfile::tempdir().unwrap();
    let (data, truth, cal, program) = calibrated(dir.path());
    let out = |f: &str| dir.path().join(f).to_str().unwrap().to_string();
    // The tool in the base frame at poses the calibration never saw, calibrated and true.
    let (code, _, err) = exec(&[
        "predict",
        "--model",
        &cal,
        "--joints",
        &program,
        "--targets",
        "tool",
        "--frame",
        "base",
        "--out",
        &out("cal.csv"),
    ]);
    assert_eq!(code, 0, "{err}");
    ok(&[
        "predict",
        "--model",
        &truth,
        "--joints",
        &program,
        "--targets",
        "tool",
        // The truth file has the simulated device frame: the base frame is asked for.
        "--frame",
        "base",
        "--out",
        &out("truth.csv"),
    ]);
    let (c, t) = (
        table(Path::new(&out("cal.csv"))),
        table(Path::new(&out("truth.csv"))),
    );
    assert_eq!(c.len(), 100);
    let mut z = Vec::new();
    for (a, b) in c.iter().zip(&t) {
        for k in ["x", "y", "z"] {
            let u = num(a, &format!("u_{k}"));
            assert!(u > 0.0 && u < 1e-4, "u_{k} = {u}");
            z.push((num(a, k) - num(b, k)) / u);
        }
    }
    // One standard uncertainty per coordinate: the standardised errors have an RMS near 1.
    let zr = rms(&z);
    assert!((0.5..2.0).contains(&zr), "RMS of error / u = {zr}");

    // Each row's own target in the device frame: a measurement file that the model fits
    // exactly (its nominal step leaves nothing).
    ok(&[
        "predict",
        "--model",
        &cal,
        "--joints",
        &data,
        "--out",
        &out("own.csv"),
    ]);
    let own = table(Path::new(&out("own.csv")));
    let measured = table(Path::new(&data));
    assert_eq!(own.len(), measured.len());
    for (a, b) in own.iter().zip(&measured) {
        assert_eq!(a["target"], b["target"]);
        assert!(dist(xyz(a), xyz(b)) < 5e-4);
    }
    let (code, report, err) = exec(&[
        "calibrate",
        "--model",
        &cal,
        "--data",
        &out("own.csv"),
        "--format",
        "json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&report).unwrap();
    let before = v["rms_before"].as_f64().unwrap();
    assert!(
        before < 1e-9,
        "the calibrated model misses its own predictions by {before} m"
    );

    // Millimetres and degrees in and out: the same predictions.
    let deg = out("program_deg.csv");
    let text = std::fs::read_to_string(&program).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header = lines.next().unwrap();
    let mut converted = format!("{header}\n");
    for l in lines {
        let cells: Vec<String> = l
            .split(',')
            .enumerate()
            .map(|(i, c)| {
                if i < 6 {
                    format!("{:?}", c.parse::<f64>().unwrap().to_degrees())
                } else {
                    c.to_string()
                }
            })
            .collect();
        converted.push_str(&(cells.join(",") + "\n"));
    }
    std::fs::write(&deg, converted).unwrap();
    ok(&[
        "predict",
        "--model",
        &cal,
        "--joints",
        &deg,
        "--targets",
        "tool",
        "--frame",
        "base",
        "--angle-unit",
        "deg",
        "--length-unit",
        "mm",
        "--out",
        &out("mm.csv"),
    ]);
    for (a, b) in table(Path::new(&out("mm.csv"))).iter().zip(&c) {
        let (pa, pb) = (xyz(a), xyz(b));
        assert!(dist([pa[0] / 1e3, pa[1] / 1e3, pa[2] / 1e3], pb) < 1e-12);
        assert!((num(a, "roll").to_radians() - num(b, "roll")).abs() < 1e-12);
        assert!((num(a, "u_x") / 1e3 - num(b, "u_x")).abs() < 1e-15);
    }
}

#[test]
fn compensated_joint_values_bring_the_true_robot_to_the_nominal_goal() {
    let dir = tempfile::tempdir().unwrap();
    let (_, truth, cal, program) = calibrated(dir.path());
    let out = |f: &str| dir.path().join(f).to_str().unwrap().to_string();
    let (code, report, err) = exec(&[
        "compensate",
        "--nominal",
        UR5,
        "--model",
        &cal,
        "--joints",
        &program,
        "--out",
        &out("corrected.csv"),
    ]);
    // The program's first pose is the zero pose: stretched arm and aligned wrist, doubly
    // singular; p44 is within 0.02 rad of both (it would need more than the 0.05 rad a joint
    // may move); a shoulder at 6.26 rad leaves its limit; a stretched elbow cannot reach past
    // the calibrated (shorter) arm (p57). Each is named, and exit 1 says not every pose is done.
    assert_eq!(code, 1, "{report}{err}");
    for line in [
        "p0 (line 4): ",
        "p14 (line 18): beyond the limits of 'shoulder_lift_joint'",
        "p44 (line 48): needs more than --max-change 0.05 (rad or m) of 'elbow_joint'",
        // Stretched: the nearest pose is at the 0.05 rad bound of the elbow.
        "p57 (line 61): needs more than --max-change 0.05 (rad or m) of 'elbow_joint'",
        "result: 4 pose(s) not compensated",
    ] {
        assert!(report.contains(line), "{line}\n{report}");
    }
    let failed = ["p0", "p14", "p44", "p57"];
    // Each row says whether it was compensated, and why not.
    for row in table(Path::new(&out("corrected.csv"))) {
        let want = match row["config"].as_str() {
            "p14" => "beyond_limits",
            "p44" | "p57" => "max_change",
            "p0" => row["status"].as_str(),
            _ => "compensated",
        };
        assert_eq!(row["status"], want, "{row:?}");
    }
    let statuses = table(Path::new(&out("corrected.csv")));
    assert_ne!(statuses[0]["status"], "compensated");

    // Where the true robot's tool goes, at the commanded and the corrected values, against the
    // nominal goal.
    for (joints, name) in [
        (&program, "before.csv"),
        (&out("corrected.csv"), "after.csv"),
    ] {
        ok(&[
            "predict",
            "--model",
            &truth,
            "--joints",
            joints,
            "--targets",
            "tool",
            "--frame",
            "base",
            "--out",
            &out(name),
        ]);
    }
    ok(&[
        "predict",
        "--model",
        UR5,
        "--joints",
        &program,
        "--targets",
        "tool",
        "--out",
        &out("goal.csv"),
    ]);
    ok(&[
        "predict",
        "--model",
        &cal,
        "--joints",
        &program,
        "--targets",
        "tool",
        "--frame",
        "base",
        "--out",
        &out("u.csv"),
    ]);
    let goal = table(Path::new(&out("goal.csv")));
    let corrected = table(Path::new(&out("corrected.csv")));
    let errors = |f: &str| -> Vec<f64> {
        table(Path::new(&out(f)))
            .iter()
            .zip(&goal)
            .zip(&corrected)
            .filter(|(_, c)| !failed.contains(&c["config"].as_str()))
            .map(|((a, b), _)| dist(xyz(a), xyz(b)))
            .collect()
    };
    let (before, after) = (rms(&errors("before.csv")), rms(&errors("after.csv")));
    // What the calibration's own uncertainty says the compensated error should be.
    let u: Vec<f64> = table(Path::new(&out("u.csv")))
        .iter()
        .map(|r| (num(r, "u_x").powi(2) + num(r, "u_y").powi(2) + num(r, "u_z").powi(2)).sqrt())
        .collect();
    let expected = rms(&u);
    assert!(before > 4e-4, "planted errors move the tool by {before} m");
    assert!(
        after < 0.1 * before,
        "compensated {after} m against {before} m"
    );
    assert!(
        after < 2.0 * expected,
        "compensated {after} m against an uncertainty of {expected} m"
    );
}

#[test]
fn joint_values_beyond_their_limits_are_predicted_with_a_warning_per_joint() {
    let dir = tempfile::tempdir().unwrap();
    let q = dir.path().join("q.csv");
    let names = "shoulder_pan_joint,shoulder_lift_joint,elbow_joint,wrist_1_joint,wrist_2_joint,wrist_3_joint";
    std::fs::write(
        &q,
        format!("{names}\n0,0,0,0,0,0\n20,0,0,0,0,0\n-7,0,7,0,0,0\n0,0,1,0,0,0\n"),
    )
    .unwrap();
    let (code, out, err) = exec(&["predict", "--model", UR5, "--joints", q.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        out.lines().filter(|l| l.ends_with(",tool,line3")).count(),
        1,
        "{out}"
    );
    let limits = "[-6.283185307179586, 6.283185307179586] rad";
    for line in [
        format!("urdf-dh: warning: q.csv: joint 'shoulder_pan_joint' is outside its limits {limits} in 2 row(s), the first at line 3 (20 rad)"),
        format!("urdf-dh: warning: q.csv: joint 'elbow_joint' is outside its limits {limits} in 1 row(s), the first at line 4 (7 rad)"),
    ] {
        assert!(err.contains(&line), "{line}\n{err}");
    }
    assert_eq!(err.matches("warning").count(), 2, "{err}");
    // Within the limits: no warning.
    let inside = dir.path().join("inside.csv");
    std::fs::write(&inside, format!("{names}\n6.28,0,-6.28,0,0,0\n")).unwrap();
    let (code, _, err) = exec(&[
        "predict",
        "--model",
        UR5,
        "--joints",
        inside.to_str().unwrap(),
    ]);
    assert_eq!((code, err.contains("warning")), (0, false), "{err}");
}

#[test]
fn bad_requests_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let q = dir.path().join("q.csv");
    std::fs::write(&q, "shoulder_pan_joint,shoulder_lift_joint\n0,0\n").unwrap();
    let q = q.to_str().unwrap();
    let (code, _, err) = exec(&["predict", "--model", UR5, "--joints", q]);
    assert_eq!(code, 2);
    assert!(
        err.contains("q.csv: line 1: missing joint column(s) 'elbow_joint'"),
        "{err}"
    );
    let full = dir.path().join("full.csv");
    std::fs::write(
        &full,
        "shoulder_pan_joint,shoulder_lift_joint,elbow_joint,wrist_1_joint,wrist_2_joint,wrist_3_joint\n0,0,0,0,0,x\n",
    )
    .unwrap();
    let bad = full.to_str().unwrap();
    let (code, _, err) = exec(&["predict", "--model", UR5, "--joints", bad]);
    assert_eq!(code, 2);
    assert!(err.contains("line 2, column 'wrist_3_joint'"), "{err}");
    let good = dir.path().join("good.csv");
    std::fs::write(
        &good,
        "shoulder_pan_joint,shoulder_lift_joint,elbow_joint,wrist_1_joint,wrist_2_joint,wrist_3_joint\n0,0,0,0,0,0\n",
    )
    .unwrap();
    let full = good.to_str().unwrap();
    let (code, _, err) = exec(&[
        "predict", "--model", UR5, "--joints", full, "--frame", "device",
    ]);
    assert_eq!(code, 2);
    assert!(err.contains("no device frame"), "{err}");
    let (code, _, err) = exec(&[
        "predict",
        "--model",
        UR5,
        "--joints",
        full,
        "--targets",
        "t1",
    ]);
    assert_eq!(code, 2);
    assert!(err.contains("has no target 't1'; it has none"), "{err}");
    let (code, _, err) = exec(&[
        "compensate",
        "--nominal",
        "fixtures/robots/puma560/vendor.yaml",
        "--model",
        UR5,
        "--joints",
        full,
    ]);
    assert_eq!(code, 2);
    assert!(err.contains("have different joints"), "{err}");
    let (code, _, err) = exec(&["predict", "--model", UR5, "--joints", full, "--out", full]);
    assert_eq!(code, 2, "{err}");
}
