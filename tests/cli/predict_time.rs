//! `predict` and `compensate` with an effect of time (`thermal_growth`, a warm-up): each row is
//! evaluated at its own time (the joint file's `time` column, seconds), and without one the
//! commands refuse, naming the column and the effect.

use crate::common::{csv_rows, exec, ok, simulate};

const UR5: &str = "fixtures/robots/ur5/vendor.yaml";

fn xyz(row: &std::collections::HashMap<String, String>) -> [f64; 3] {
    ["x", "y", "z"].map(|k| row[k].parse::<f64>().unwrap())
}

/// RMS distance (m) between the points of two files, row by row.
fn rms_between(a: &str, b: &str) -> f64 {
    let (a, b) = (csv_rows(a), csv_rows(b));
    assert_eq!(a.len(), b.len());
    let sum: f64 = a
        .iter()
        .zip(&b)
        .map(|(r, s)| {
            let (p, q) = (xyz(r), xyz(s));
            (0..3).map(|i| (p[i] - q[i]).powi(2)).sum::<f64>()
        })
        .sum();
    (sum / a.len() as f64).sqrt()
}

/// A warm-up of 100 ppm (tau 1200 s, `ln_tau` 7.09) planted by `simulate` over 60 poses 30 s
/// apart, 1 µm of noise: its truth file predicts every measured point at the row's time to the
/// noise (about 70 µm at the end of the set if the growth were left out), and the rows without
/// their `time` column are refused by `predict` and `compensate` (exit 2, naming the column
/// and the effect), as are rows of which one lacks its time.
#[test]
fn a_warm_up_is_predicted_at_each_rows_time_and_refused_without_one() {
    let dir = tempfile::tempdir().unwrap();
    let p = |f: &str| dir.path().join(f).to_str().unwrap().to_string();
    let (data, truth) = (p("warm.csv"), p("warm.truth.yaml"));
    simulate(
        UR5,
        "60",
        &data,
        &[
            "--noise",
            "1e-6",
            "--effect",
            "thermal_growth=1e-4,7.09",
            "--seed",
            "21",
        ],
    );
    let measured = std::fs::read_to_string(&data).unwrap();
    assert!(measured.lines().any(|l| l.ends_with(",time")), "{measured}");
    ok(&[
        "predict",
        "--model",
        &truth,
        "--joints",
        &data,
        "--out",
        &p("pred.csv"),
    ]);
    let predicted = std::fs::read_to_string(p("pred.csv")).unwrap();
    let rms = rms_between(&measured, &predicted);
    assert!(rms < 3e-6, "predicted against measured: {rms} m RMS");

    // The same rows without their times: no `time` column.
    let mut lines = measured.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let at = header.iter().position(|c| *c == "time").unwrap();
    let drop = |l: &str| {
        let mut cells: Vec<&str> = l.split(',').collect();
        cells.remove(at);
        cells.join(",")
    };
    let untimed: Vec<String> = std::iter::once(drop(&header.join(",")))
        .chain(lines.map(drop))
        .collect();
    std::fs::write(p("untimed.csv"), untimed.join("\n") + "\n").unwrap();
    for args in [
        vec!["predict", "--model", &truth, "--joints", &p("untimed.csv")],
        vec![
            "compensate",
            "--nominal",
            UR5,
            "--model",
            &truth,
            "--joints",
            &p("untimed.csv"),
        ],
    ] {
        let (code, _, err) = exec(&args);
        assert_eq!(code, 2, "{err}");
        assert!(
            err.contains(
                "untimed.csv: the calibration's thermal_growth needs each row's time: expected a 'time' column (seconds), found none"
            ) && err.contains("hint: "),
            "{err}"
        );
    }
    // One row without its time.
    let mut gap: Vec<String> = measured.lines().map(String::from).collect();
    let last = gap.len() - 1;
    gap[last] = gap[last].rsplit_once(',').unwrap().0.to_string() + ",";
    std::fs::write(p("gap.csv"), gap.join("\n") + "\n").unwrap();
    let (code, _, err) = exec(&["predict", "--model", &truth, "--joints", &p("gap.csv")]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains(&format!(
            "gap.csv: line {}, column 'time': expected the row's time (seconds) for thermal_growth, found an empty cell",
            last + 1
        )),
        "{err}"
    );
    // Compensation at the rows' times reaches the nominal tool poses.
    ok(&[
        "compensate",
        "--nominal",
        UR5,
        "--model",
        &truth,
        "--joints",
        &data,
        "--out",
        &p("corrected.csv"),
    ]);
    let corrected = csv_rows(&std::fs::read_to_string(p("corrected.csv")).unwrap());
    assert_eq!(corrected.len(), 60);
    assert!(corrected.iter().all(|r| r["status"] == "compensated"));
}

/// The rows of the measurement file `text` without its `time` column.
fn without_time(text: &str) -> String {
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let at = header.iter().position(|c| *c == "time").unwrap();
    let drop = |l: &str| {
        let mut cells: Vec<&str> = l.split(',').collect();
        cells.remove(at);
        cells.join(",")
    };
    std::iter::once(drop(&header.join(",")))
        .chain(lines.map(drop))
        .map(|l| l + "\n")
        .collect()
}

/// The calibrated sheet records what the `t` of its `thermal_growth` was
/// (`calibration.time_unit`: `s` when the data had a `time` column, `pose_order` when not),
/// reads it back, and `predict` and `compensate` refuse rows in the other unit (exit 2, naming
/// both files and the column): a seconds sheet given rows in `--sequence` without times, a
/// pose-order sheet given a `time` column. Each predicts its own kind of rows; a sheet without
/// the key (written before it was kept) takes the rows as given. `simulate`'s truth says `s`.
#[test]
fn the_sheet_records_its_time_unit_and_predictions_refuse_the_other() {
    let dir = tempfile::tempdir().unwrap();
    let p = |f: &str| dir.path().join(f).to_str().unwrap().to_string();
    let (data, truth) = (p("warm.csv"), p("warm.truth.yaml"));
    simulate(
        UR5,
        "60",
        &data,
        &[
            "--noise",
            "1e-6",
            "--effect",
            "thermal_growth=1e-4,7.09",
            "--seed",
            "23",
        ],
    );
    let measured = std::fs::read_to_string(&data).unwrap();
    std::fs::write(p("untimed.csv"), without_time(&measured)).unwrap();
    let has_key = |file: &str, word: &str| {
        std::fs::read_to_string(file)
            .unwrap()
            .lines()
            .any(|l| l.trim() == format!("time_unit: {word}"))
    };
    assert!(has_key(&truth, "s"));
    for (input, out) in [(&data, "timed.yaml"), (&p("untimed.csv"), "order.yaml")] {
        ok(&[
            "calibrate",
            "--model",
            UR5,
            "--data",
            input,
            "--effects",
            "thermal_growth",
            "--out",
            &p(out),
        ]);
    }
    assert!(has_key(&p("timed.yaml"), "s") && !has_key(&p("timed.yaml"), "pose_order"));
    assert!(has_key(&p("order.yaml"), "pose_order") && !has_key(&p("order.yaml"), "s"));

    let untimed = p("untimed.csv");
    let compensate = |model: &str, joints: &str, sequence: bool| {
        let mut a = vec!["compensate", "--nominal", UR5, "--model"];
        a.extend([model, "--joints", joints]);
        if sequence {
            a.push("--sequence");
        }
        a.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let predict = |model: &str, joints: &str, sequence: bool| {
        let mut a = vec!["predict", "--model", model, "--joints", joints];
        if sequence {
            a.push("--sequence");
        }
        a.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let run = |args: Vec<String>| exec(&args.iter().map(String::as_str).collect::<Vec<_>>());
    // Each sheet predicts and compensates its own kind of rows (compensate exits 1 when a
    // pose does not converge, which is no refusal of its rows).
    for args in [
        predict(&p("timed.yaml"), &data, false),
        predict(&p("order.yaml"), &untimed, true),
        compensate(&p("timed.yaml"), &data, false),
        compensate(&p("order.yaml"), &untimed, true),
    ] {
        let (code, _, err) = run(args.clone());
        assert!(
            (code == 0 || args[0] == "compensate" && code == 1) && !err.contains("urdf-dh: error:"),
            "{args:?}: exit {code}: {err}"
        );
    }
    // Seconds sheets (calibrated and simulated) given the rows' order without times.
    for model in [p("timed.yaml"), truth.clone()] {
        let name = std::path::Path::new(&model)
            .file_name()
            .unwrap()
            .to_str()
            .unwrap()
            .to_string();
        for args in [
            predict(&model, &untimed, true),
            compensate(&model, &untimed, true),
        ] {
            let (code, _, err) = run(args.clone());
            assert_eq!(code, 2, "{args:?}: {err}");
            assert!(
                err.contains(&format!(
                    "untimed.csv: the calibration's thermal_growth needs each row's time: expected a 'time' column (seconds), found none ({name} was fitted on times in seconds, `time_unit: s`)"
                )) && err.contains("hint: add each row's time in seconds")
                    && err.contains("the rows' order given with --sequence is no time in seconds"),
                "{err}"
            );
        }
    }
    // The pose-order sheet given a time column (with or without --sequence).
    for args in [
        predict(&p("order.yaml"), &data, false),
        predict(&p("order.yaml"), &data, true),
        compensate(&p("order.yaml"), &data, false),
    ] {
        let (code, _, err) = run(args.clone());
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(
            err.contains(
                "warm.csv: column 'time': the calibration's thermal_growth was fitted on the pose order in [0, 1] (order.yaml: `time_unit: pose_order`, its data had no times): expected no 'time' column, found one (seconds)"
            ) && err.contains("hint: drop the 'time' column"),
            "{err}"
        );
    }
    // A sheet written before the key was kept: the rows are taken as given, either way.
    let old: String = std::fs::read_to_string(p("timed.yaml"))
        .unwrap()
        .lines()
        .filter(|l| l.trim() != "time_unit: s")
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(p("old.yaml"), old).unwrap();
    for args in [
        predict(&p("old.yaml"), &data, false),
        predict(&p("old.yaml"), &untimed, true),
    ] {
        let (code, _, err) = run(args.clone());
        assert_eq!(code, 0, "{args:?}: {err}");
    }
}
