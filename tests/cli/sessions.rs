//! Measurement sessions (`simulate --sessions`, the `session` column): each session's device
//! frame is estimated with the shared geometry, an unseen validation session's frame is fitted
//! on its own samples, and one frame for moved-device data leaves the residual.

use std::path::Path;

use serde_json::Value;

use crate::common::{ok, run};

const UR5: &str = "fixtures/robots/ur5/vendor.yaml";
const NOISE: f64 = 2e-5;
const PLANTED: [(&str, f64); 3] = [
    ("shoulder_lift_joint.a", 5e-4),
    ("elbow_joint.a", -5e-4),
    ("wrist_2_joint.d", 5e-4),
];

fn path(dir: &Path, name: &str) -> String {
    dir.join(name).to_string_lossy().into_owned()
}

/// Three sessions of 60 poses, the third for validation, with the planted errors.
fn simulated(dir: &Path) -> String {
    let data = path(dir, "days.csv");
    let errors: Vec<String> = PLANTED.iter().map(|(n, v)| format!("{n}={v}")).collect();
    let noise = NOISE.to_string();
    let mut args = vec![
        "simulate",
        "--model",
        UR5,
        "--poses",
        "180",
        "--sessions",
        "3",
        "--validation",
        "0.3333333333333333",
        "--noise",
        &noise,
        "--targets",
        "3",
        "--seed",
        "7",
        "--out",
        &data,
    ];
    for e in &errors {
        args.extend(["--error", e]);
    }
    ok(&args);
    data
}

fn calibrate_json(data: &str, out: Option<&str>) -> Value {
    let mut args = vec![
        "calibrate",
        "--model",
        UR5,
        "--data",
        data,
        "--format",
        "json",
    ];
    if let Some(o) = out {
        args.extend(["--out", o]);
    }
    serde_json::from_str(&ok(&args)).unwrap()
}

/// The JSON report of `calibrate` on `data` with the validation file `val`.
fn calibrate_validated(data: &str, val: &str) -> Value {
    serde_json::from_str(&ok(&[
        "calibrate",
        "--model",
        UR5,
        "--data",
        data,
        "--validate",
        val,
        "--format",
        "json",
    ]))
    .unwrap()
}

#[test]
fn each_session_gets_its_frame_and_an_unseen_session_validates_at_the_noise_level() {
    let dir = tempfile::tempdir().unwrap();
    let data = simulated(dir.path());
    let text = std::fs::read_to_string(&data).unwrap();
    let header = text.lines().find(|l| !l.starts_with('#')).unwrap();
    assert!(header.ends_with(",session"), "{header}");
    let truth: serde_yaml::Value = serde_yaml::from_str(
        &std::fs::read_to_string(path(dir.path(), "days.truth.yaml")).unwrap(),
    )
    .unwrap();
    assert_eq!(truth["truth"]["sessions"].as_sequence().unwrap().len(), 3);

    let out = path(dir.path(), "calibrated.yaml");
    let report = calibrate_json(&data, Some(&out));
    for (name, planted) in PLANTED {
        let p = report["parameters"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| p["name"] == name)
            .unwrap();
        let change = p["estimate"].as_f64().unwrap() - p["nominal"].as_f64().unwrap();
        let z = (change - planted) / p["std_error"].as_f64().unwrap();
        assert!(z.abs() < 3.0, "{name}: {z:.2} standard errors off");
    }
    let floor = report["noise_floor"].as_f64().unwrap();
    let after = report["rms_after"].as_f64().unwrap();
    assert!(
        (after / floor - 1.0).abs() < 0.05,
        "rms {after} floor {floor}"
    );
    assert_eq!(report["verdict"]["complete"], true, "{}", report["verdict"]);
    let sessions = report["sessions"].as_array().unwrap();
    let names: Vec<&str> = sessions
        .iter()
        .map(|s| s["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["s1", "s2", "s3"]);
    assert_eq!(sessions[0]["device"], report["device"]);
    assert_eq!(sessions[2]["fitted_on_validation"], true);
    assert_eq!(sessions[2]["samples"], 0);
    let val = report["val_rms_after"].as_f64().unwrap();
    let noise = 3f64.sqrt() * NOISE;
    assert!(
        val < 1.15 * noise,
        "validation RMS {val} against noise {noise}"
    );
    assert!(report["notes"].as_array().unwrap().iter().any(|n| n
        .as_str()
        .unwrap()
        .contains("session 's3' has no calibration sample")));
    // The written sheet keeps the other sessions' frames (read back and proved).
    assert_eq!(report["written"]["passed"], true, "{}", report["written"]);
    let sheet: serde_yaml::Value =
        serde_yaml::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let written = sheet["calibration"]["sessions"].as_sequence().unwrap();
    let written: Vec<&str> = written
        .iter()
        .map(|s| s["name"].as_str().unwrap())
        .collect();
    assert_eq!(written, ["s2", "s3"]);
    // The first session's name, which a joint file's `session` column is checked against.
    assert_eq!(sheet["calibration"]["first_session"].as_str(), Some("s1"));

    // The text report lists every session.
    let text = ok(&["calibrate", "--model", UR5, "--data", &data]);
    assert!(
        text.contains("sessions (each its own device frame"),
        "{text}"
    );
    assert!(
        text.contains("frame fitted on its validation samples"),
        "{text}"
    );

    // Predictions: each row from its own session's frame by default (the file's session
    // column), every row from one session's with --session (the other sessions' frames left
    // out of the covariance).
    let per_session = |extra: &[&str]| -> Vec<(String, f64)> {
        let mut args = vec!["predict", "--model", &out, "--joints", &data];
        args.extend(extra);
        let predicted = ok(&args);
        let body = |t: &str| -> Vec<Vec<String>> {
            t.lines()
                .filter(|l| !l.starts_with('#'))
                .map(|l| l.split(',').map(str::to_string).collect())
                .collect()
        };
        let (measured, predicted) = (body(&text_of(&data)), body(&predicted));
        let col =
            |rows: &[Vec<String>], name: &str| rows[0].iter().position(|c| c == name).unwrap();
        let session = col(&measured, "session");
        let mut sums: Vec<(String, f64, usize)> = Vec::new();
        for (m, p) in measured.iter().zip(&predicted).skip(1) {
            let d2: f64 = ["x", "y", "z"]
                .iter()
                .map(|c| {
                    let a: f64 = m[col(&measured, c)].parse().unwrap();
                    let b: f64 = p[col(&predicted, c)].parse().unwrap();
                    (a - b).powi(2)
                })
                .sum();
            match sums.iter_mut().find(|s| s.0 == m[session]) {
                Some(s) => {
                    s.1 += d2;
                    s.2 += 1;
                }
                None => sums.push((m[session].clone(), d2, 1)),
            }
        }
        sums.into_iter()
            .map(|(n, ss, k)| (n, (ss / k as f64).sqrt()))
            .collect()
    };
    let noise = 3f64.sqrt() * NOISE;
    let own = per_session(&[]);
    let second = per_session(&["--session", "s2"]);
    let rms = |v: &[(String, f64)], s: &str| v.iter().find(|x| x.0 == s).unwrap().1;
    for s in ["s1", "s2", "s3"] {
        assert!(rms(&own, s) < 1.5 * noise, "{own:?}");
    }
    assert!(rms(&second, "s2") < 1.5 * noise, "{second:?}");
    assert!(rms(&second, "s1") > 100.0 * noise, "{second:?}");
    // Two of the file's sessions unknown to the model: which one is the first is unknown.
    let renamed = path(dir.path(), "renamed.csv");
    std::fs::write(
        &renamed,
        text_of(&data)
            .replace(",s1\n", ",a\n")
            .replace(",s2\n", ",b\n"),
    )
    .unwrap();
    let (code, _, err) = crate::common::exec(&["predict", "--model", &out, "--joints", &renamed]);
    assert_eq!(code, 2, "{err}");
    // The model names its first session: each unknown name is refused, with its line.
    assert!(
        err.contains("column 'session': 'a' is no session of"),
        "{err}"
    );
    assert!(err.contains("expected one of 's1', 's2', 's3'"), "{err}");
    // One unknown name among known ones was predicted in the first session's frame, silently.
    let typo = path(dir.path(), "typo.csv");
    std::fs::write(&typo, text_of(&data).replace(",s3\n", ",s9\n")).unwrap();
    let (code, _, err) = crate::common::exec(&["predict", "--model", &out, "--joints", &typo]);
    assert_eq!(code, 2, "{err}");
    let first = text_of(&typo)
        .lines()
        .position(|l| l.ends_with(",s9"))
        .unwrap()
        + 1;
    assert!(
        err.contains(&format!(
            "typo.csv: line {first}, column 'session': 's9' is no session of"
        )),
        "{err}"
    );
    // The first session named by --session is the model's own frame.
    ok(&[
        "predict",
        "--model",
        &out,
        "--joints",
        &data,
        "--session",
        "s1",
    ]);
    let (code, _, err) = crate::common::exec(&[
        "predict",
        "--model",
        &out,
        "--joints",
        &data,
        "--session",
        "s9",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("expected one of 's2', 's3'"), "{err}");
}

fn text_of(path: &str) -> String {
    std::fs::read_to_string(path).unwrap()
}

#[test]
fn without_the_session_column_one_frame_leaves_the_residual() {
    let dir = tempfile::tempdir().unwrap();
    let data = simulated(dir.path());
    let one: String = std::fs::read_to_string(&data)
        .unwrap()
        .lines()
        .map(|l| match l.starts_with('#') {
            true => format!("{l}\n"),
            false => format!("{}\n", &l[..l.rfind(',').unwrap()]),
        })
        .collect();
    let single = path(dir.path(), "one.csv");
    std::fs::write(&single, one).unwrap();
    let report = calibrate_json(&single, None);
    let floor = report["noise_floor"].as_f64().unwrap();
    let after = report["rms_after"].as_f64().unwrap();
    assert!(after > 100.0 * floor, "rms {after} floor {floor}");
    assert_eq!(report["verdict"]["complete"], false);
    assert!(report["verdict"]["summary"]
        .as_str()
        .unwrap()
        .starts_with("residual remains"));
    assert!(report.get("sessions").is_none());
    assert!(report["val_rms_after"].as_f64().unwrap() > 0.01);
}

#[test]
fn a_session_too_small_for_a_frame_or_without_a_name_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let data = simulated(dir.path());
    let text = std::fs::read_to_string(&data).unwrap();
    // The first two poses (3 targets each, data from line 4) move to session 'tiny'.
    let mut rows = 0;
    let tiny: String = text
        .lines()
        .map(|l| {
            if l.starts_with('#') || l.ends_with(",session") {
                return format!("{l}\n");
            }
            rows += 1;
            match rows <= 6 {
                true => format!("{},tiny\n", &l[..l.rfind(',').unwrap()]),
                false => format!("{l}\n"),
            }
        })
        .collect();
    let bad = path(dir.path(), "tiny.csv");
    std::fs::write(&bad, &tiny).unwrap();
    let out = run(&["calibrate", "--model", UR5, "--data", &bad], None);
    assert!(out.starts_with("exit: 2"), "{out}");
    assert!(
        out.contains("session 'tiny' (first sample at line 4)"),
        "{out}"
    );
    assert!(out.contains("at least 3 poses"), "{out}");

    let empty = tiny.replacen(",tiny\n", ",\n", 1);
    std::fs::write(&bad, empty).unwrap();
    let out = run(&["calibrate", "--model", UR5, "--data", &bad], None);
    assert!(out.starts_with("exit: 2"), "{out}");
    assert!(out.contains("line 4") && out.contains("session"), "{out}");
}

/// The CSV `text` with only the rows whose last cell `keep` accepts (comments and header kept).
fn rows_where(text: &str, keep: impl Fn(&str) -> bool) -> String {
    text.lines()
        .filter(|l| {
            l.starts_with('#') || l.ends_with(",session") || keep(l.rsplit(',').next().unwrap())
        })
        .map(|l| format!("{l}\n"))
        .collect()
}

#[test]
fn a_validation_file_of_another_day_gets_its_own_frame() {
    let dir = tempfile::tempdir().unwrap();
    let data = simulated(dir.path());
    let text = std::fs::read_to_string(&data).unwrap();
    // The set column marks s3 for validation; a separate file holds it.
    let cal = path(dir.path(), "cal.csv");
    let val = path(dir.path(), "val.csv");
    std::fs::write(&cal, rows_where(&text, |s| s != "s3")).unwrap();
    std::fs::write(&val, rows_where(&text, |s| s == "s3")).unwrap();
    let report = calibrate_validated(&cal, &val);
    let sessions = report["sessions"].as_array().unwrap();
    assert_eq!(sessions.len(), 3);
    assert_eq!(sessions[2]["name"], "s3");
    assert_eq!(sessions[2]["fitted_on_validation"], true);
    let v = report["val_rms_after"].as_f64().unwrap();
    assert!(v < 1.15 * 3f64.sqrt() * NOISE, "validation RMS {v}");

    // Without session columns, the other day's file is compared in the first day's frame:
    // metres off, and a note says what to do.
    let strip = |t: String| {
        rows_where(&t, |_| true)
            .lines()
            .map(|l| match l.starts_with('#') {
                true => format!("{l}\n"),
                false => format!("{}\n", &l[..l.rfind(',').unwrap()]),
            })
            .collect::<String>()
    };
    std::fs::write(&cal, strip(rows_where(&text, |s| s == "s1"))).unwrap();
    std::fs::write(&val, strip(rows_where(&text, |s| s == "s3"))).unwrap();
    let report = calibrate_validated(&cal, &val);
    assert!(report["val_rms_after"].as_f64().unwrap() > 0.01);
    assert!(
        report["notes"]
            .as_array()
            .unwrap()
            .iter()
            .any(|n| n.as_str().unwrap().contains("`session` column")),
        "{}",
        report["notes"]
    );
}
