//! The calibration's diagnosis on simulated UR5 sets with a fault or effect planted: a far
//! point named by its line and left out, and `--effects auto` naming a backlash that follows
//! the last motion and a drift of the lengths in time.

use serde_json::Value;

use crate::calibrate::{path, recovered, UR5};
use crate::common::{ok, simulate};

/// A point planted a metre off in the CSV is named by its file line, left out (the fit and the
/// validation sit on the noise), kept with `--keep-outliers`, and the verdict is in the JSON.
#[test]
fn a_far_point_is_named_by_its_line_and_the_verdict_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    let data = path(dir.path(), "far.csv");
    simulate(UR5, "150", &data, &["--noise", "1e-4", "--seed", "5"]);
    // Move the x of the 40th data row by 1 m; its 1-based file line is remembered.
    let text = std::fs::read_to_string(&data).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let header = lines.iter().position(|l| l.contains(",x,y,z,")).unwrap();
    let at = header + 40;
    let mut fields: Vec<String> = lines[at].split(',').map(String::from).collect();
    let x = lines[header].split(',').position(|c| c == "x").unwrap();
    fields[x] = format!("{}", fields[x].parse::<f64>().unwrap() + 1.0);
    lines[at] = fields.join(",");
    std::fs::write(&data, lines.join("\n") + "\n").unwrap();
    let json = |extra: &[&str]| -> Value {
        let mut args = vec![
            "calibrate",
            "--model",
            UR5,
            "--data",
            &data,
            "--format",
            "json",
        ];
        args.extend_from_slice(extra);
        serde_json::from_str(&ok(&args)).unwrap()
    };
    let r = json(&[]);
    let points = r["outliers"]["points"].as_array().unwrap();
    assert_eq!(points.len(), 1, "{:#}", r["outliers"]);
    assert_eq!(points[0]["line"], at + 1);
    assert_eq!(points[0]["split"], "calibration");
    assert!((points[0]["residual"].as_f64().unwrap() - 1.0).abs() < 0.01);
    assert!(points[0]["sigmas"].as_f64().unwrap() > 1000.0);
    assert_eq!(r["outliers"]["kept"], false);
    assert!(r["outliers"]["rms_with"].as_f64().unwrap() > 0.01);
    assert!(r["rms_after"].as_f64().unwrap() < 2e-4);
    assert_eq!(r["verdict"]["summary"], "model complete");
    assert_eq!(r["verdict"]["test"]["kind"], "chi-square");
    assert_eq!(r["verdict"]["complete"], true);
    let k = json(&["--keep-outliers"]);
    assert_eq!(k["outliers"]["kept"], true);
    assert_eq!(k["outliers"]["points"].as_array().unwrap().len(), 1);
    assert!(k["rms_after"].as_f64().unwrap() > 0.01);
    assert_eq!(k["verdict"]["complete"], false);
    assert!(k["verdict"]["summary"]
        .as_str()
        .unwrap()
        .starts_with("residual remains: "));
    let text = ok(&["calibrate", "--model", UR5, "--data", &data]);
    assert!(
        text.contains(&format!("  line {}, config ", at + 1)),
        "{text}"
    );
    assert!(text.contains("verdict: model complete ("), "{text}");
}

/// Simulates UR5 with the effect `planted` (LABEL=VALUE, in the file's pose order) and
/// calibrates it with `--effects auto`: the JSON report and the text report.
fn auto_on_planted(planted: &str, seed: &str) -> (Value, String) {
    let dir = tempfile::tempdir().unwrap();
    let data = path(dir.path(), "order.csv");
    let out = path(dir.path(), "order.yaml");
    simulate(
        UR5,
        "200",
        &data,
        &[
            "--noise",
            "2e-5",
            "--targets",
            "2",
            "--effect",
            planted,
            "--seed",
            seed,
        ],
    );
    let args = [
        "calibrate",
        "--model",
        UR5,
        "--data",
        &data,
        "--effects",
        "auto",
    ];
    let mut json = args.to_vec();
    json.extend(["--format", "json", "--out", &out]);
    let report: Value = serde_json::from_str(&ok(&json)).unwrap();
    // The written sheet reads back with the effect (the proof of `--out` passed).
    let sheet = std::fs::read_to_string(&out).unwrap();
    let label = planted.split('=').next().unwrap();
    assert!(sheet.contains(label), "{sheet}");
    (report, ok(&args))
}

#[test]
fn auto_names_a_backlash_that_follows_the_last_motion_and_lists_its_rivals() {
    let (report, text) = auto_on_planted("backlash_direction:elbow_joint=1e-4", "11");
    assert_eq!(
        report["selected_effects"],
        serde_json::json!(["backlash_direction:elbow_joint"]),
        "{text}"
    );
    assert_eq!(report["verdict"]["summary"], "model complete", "{text}");
    // The held-out figures of the diagnosis's steps are one-step folds, and both outputs say so.
    assert_eq!(report["validation"]["fold_fits"], "one-step", "{text}");
    assert!(
        text.contains("cross-validation over 200 poses (each fold one Gauss-Newton step"),
        "{text}"
    );
    let z = recovered(&report, "backlash_direction:elbow_joint", 1e-4);
    assert!(z.abs() < 4.0, "backlash {z:.2} standard errors off");
    // The rivals of the elbow's angle that passed the tests too are listed with the reason.
    let rivals: Vec<&Value> = report["candidates"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["status"] == "rival")
        .collect();
    assert!(!rivals.is_empty(), "{text}");
    for c in rivals {
        let reason = c["reason"].as_str().unwrap();
        assert!(
            reason.starts_with("rival of backlash_direction:elbow_joint: BIC worse by"),
            "{c}"
        );
    }
    assert!(
        text.contains("rival (rival of backlash_direction:elbow_joint: BIC worse by"),
        "{text}"
    );
}

#[test]
fn auto_names_a_drift_of_the_lengths_in_time() {
    let (report, text) = auto_on_planted("drift=3e-5", "12");
    assert_eq!(
        report["selected_effects"],
        serde_json::json!(["drift"]),
        "{text}"
    );
    assert_eq!(report["verdict"]["summary"], "model complete", "{text}");
    let z = recovered(&report, "drift", 3e-5);
    assert!(z.abs() < 4.0, "drift {z:.2} standard errors off");
}

/// A warm-up planted by `simulate` (60 ppm, tau 1200 s: `ln_tau` 7.09): the CSV carries the
/// times (poses 30 s apart), `--effects auto` selects `thermal_growth` with its time constant,
/// and the sheet `--out` wrote carries it and reads back (its proof passed).
#[test]
fn auto_names_a_warm_up_of_the_robot_in_time() {
    let (report, text) = auto_on_planted("thermal_growth=6e-5,7.09", "13");
    assert_eq!(
        report["selected_effects"],
        serde_json::json!(["thermal_growth"]),
        "{text}"
    );
    assert_eq!(report["verdict"]["summary"], "model complete", "{text}");
    let z = recovered(&report, "thermal_growth.k", 6e-5);
    assert!(z.abs() < 3.0, "k {z:.2} standard errors off");
    let z = recovered(&report, "thermal_growth.ln_tau", 7.09);
    assert!(z.abs() < 3.0, "ln tau {z:.2} standard errors off");
    // Beside ln tau, tau in seconds with its standard error by the delta method (JSON and
    // text); the fitted parameter is ln tau still.
    let p = report["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["name"] == "thermal_growth.ln_tau")
        .unwrap();
    let (ln_tau, se) = (
        p["estimate"].as_f64().unwrap(),
        p["std_error"].as_f64().unwrap(),
    );
    let d = &p["derived"];
    assert_eq!(
        (&d["name"], &d["unit"]),
        (
            &serde_json::json!("thermal_growth.tau"),
            &serde_json::json!("s")
        )
    );
    let (tau, se_tau) = (
        d["estimate"].as_f64().unwrap(),
        d["std_error"].as_f64().unwrap(),
    );
    // JSON numbers round-trip: the same doubles as exp and the product give.
    assert_eq!((tau, se_tau), (ln_tau.exp(), ln_tau.exp() * se), "{d}");
    let shown = format!("(tau {tau:.4e} +- {se_tau:.1e} s)");
    assert!(
        text.lines()
            .any(|l| l.starts_with("  thermal_growth.ln_tau = ") && l.ends_with(&shown)),
        "{shown} in {text}"
    );
    assert!(!text.contains("no `time` column"), "{text}");
    // ln tau's unit, in the JSON and in the text's parameter table: the log of seconds.
    assert_eq!(p["unit"], "ln s", "{p}");
    assert!(
        text.lines()
            .any(|l| l.starts_with("  thermal_growth.ln_tau ") && l.contains(" [ln s] ")),
        "{text}"
    );
}
