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
