//! The diagnosis's rules on simulated sets made for them (issue 33): orientation counts in
//! every test of a 6-DoF set (§1), nested rivals are compared and the simpler kept (§3), and a
//! point stays out only if it is an outlier of the final model (§4). Each set is small (a
//! second or two in a debug build) and its effect sits near the edge of what it can show.

use serde_json::Value;

use crate::common::{ok, simulate};

const UR5: &str = "fixtures/robots/ur5/vendor.yaml";

fn calibrate_json(model: &str, data: &str, extra: &[&str]) -> Value {
    let mut args = vec![
        "calibrate",
        "--model",
        model,
        "--data",
        data,
        "--effects",
        "auto",
        "--format",
        "json",
    ];
    args.extend_from_slice(extra);
    serde_json::from_str(&ok(&args)).unwrap()
}

fn selected(report: &Value) -> Vec<String> {
    report["selected_effects"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e.as_str().unwrap().to_string())
        .collect()
}

/// §1: a 400 µrad once-per-turn error of the UR5's last joint on a 6-DoF probe 70 mm off the
/// flange moves the probe's position by about its noise (30 µm) but turns it by five times its
/// orientation noise (80 µrad). Every test must weigh the angles: the harmonic passes the F
/// test and BIC on both (it did before), and the held-out check too (before: position only,
/// p = 0.03-0.3, rejected on five seeds of five); the verdict's ratio to the floor is that of
/// both, each over its own sigma ("1.02 x the floor", position only, before), and the steps give
/// the held-out angle RMS beside the position's. With nothing planted nothing is selected.
#[test]
fn an_error_the_angles_show_is_selected_and_the_verdict_weighs_them() {
    let dir = tempfile::tempdir().unwrap();
    for (seed, validation) in [("331", true), ("334", false)] {
        let data = dir
            .path()
            .join(format!("j6_{seed}.csv"))
            .to_string_lossy()
            .into_owned();
        let mut sim = vec![
            "--noise",
            "30e-6",
            "--orientation-noise",
            "80e-6",
            "--random-errors",
            "0.0005,0.0005",
            "--effect",
            "gear_harmonic:wrist_3_joint=4e-4,0",
            "--seed",
            seed,
        ];
        if validation {
            sim.extend(["--validation", "0.4"]);
        }
        simulate(UR5, "150", &data, &sim);
        let folds: &[&str] = if validation { &[] } else { &["--folds", "6"] };
        let report = calibrate_json(UR5, &data, folds);
        assert_eq!(
            selected(&report),
            ["gear_harmonic:wrist_3_joint"],
            "seed {seed}: {:#}",
            report["diagnosis"]["rounds"][0]["trials"]
        );
        let verdict = &report["verdict"];
        assert_eq!(verdict["summary"], "model complete", "seed {seed}");
        let (angle_floor, floor) = (
            report["angle_noise_floor"].as_f64().unwrap(),
            report["noise_floor"].as_f64().unwrap(),
        );
        let last = report["steps"].as_array().unwrap().last().unwrap().clone();
        let steps = report["steps"].as_array().unwrap();
        let geometric = steps.iter().find(|s| s["label"] == "geometric").unwrap();
        // The geometric step leaves the angles at twice their floor, the harmonic at it.
        let geo_angle = geometric["angle_rms"].as_f64().unwrap();
        assert!(geo_angle > 1.5 * angle_floor, "seed {seed}: {geo_angle:e}");
        let angle = last["angle_rms"].as_f64().unwrap();
        assert!((angle / angle_floor - 1.0).abs() < 0.1, "{angle:e}");
        let val_angle = last["val_angle_rms"].as_f64().unwrap();
        let geo_val_angle = geometric["val_angle_rms"].as_f64().unwrap();
        assert!(
            val_angle < 0.7 * geo_val_angle && val_angle < 1.2 * angle_floor,
            "seed {seed}: held-out angle {geo_val_angle:e} -> {val_angle:e}"
        );
        // The ratios: each part's own, and both together.
        let (position, orientation) = (
            verdict["position_ratio"].as_f64().unwrap(),
            verdict["angle_ratio"].as_f64().unwrap(),
        );
        assert!((position - last["rms"].as_f64().unwrap() / floor).abs() < 1e-9);
        assert!((orientation - angle / angle_floor).abs() < 1e-9);
        let both = verdict["ratio"].as_f64().unwrap();
        assert!(
            (both - ((position * position + orientation * orientation) / 2.0).sqrt()).abs() < 1e-9,
            "{verdict:#}"
        );
        // Before the harmonic, the geometric fit's residual: its test and ratio saw the angles.
        let text = ok(&[
            "calibrate",
            "--model",
            UR5,
            "--data",
            &data,
            "--effects",
            "none",
        ]);
        assert!(
            text.contains("x the floor (position 1.0") && text.contains(" x, orientation 2."),
            "{text}"
        );
    }
    // Nothing planted: nothing selected, and the verdict is complete.
    let data = dir.path().join("none.csv").to_string_lossy().into_owned();
    simulate(
        UR5,
        "150",
        &data,
        &[
            "--noise",
            "30e-6",
            "--orientation-noise",
            "80e-6",
            "--random-errors",
            "0.0005,0.0005",
            "--validation",
            "0.4",
            "--seed",
            "336",
        ],
    );
    let report = calibrate_json(UR5, &data, &[]);
    assert!(selected(&report).is_empty(), "{:?}", selected(&report));
    assert_eq!(report["verdict"]["summary"], "model complete");
}

/// §3: a once-per-turn error of the UR5's first joint, 120 µrad (about 50 µm at the tool, the
/// noise's size), labelled `gear_harmonic:J:2` (once and twice per turn) on today's code in
/// both ways the rule allowed: (seed 442, validation split) the smaller label failed its
/// held-out check by a hair (p = 0.0102) and the bigger one passed, the two never compared;
/// (seed 423, 6 folds) the two were within the BIC tie and the held-out RMS picked the bigger.
/// Nested rivals are compared by the extra-sum-of-squares F test and the simpler kept; the
/// report says which were compared. With both harmonics planted the bigger one is kept.
#[test]
fn nested_rivals_are_compared_and_the_simpler_kept() {
    let dir = tempfile::tempdir().unwrap();
    let j1 = "gear_harmonic:shoulder_pan_joint";
    let both = "gear_harmonic:shoulder_pan_joint:2";
    for (seed, validation, planted, expected) in [
        ("442", true, format!("{j1}=120e-6,0"), j1),
        ("423", false, format!("{j1}=120e-6,0"), j1),
        ("423", false, format!("{both}=120e-6,0,150e-6,0"), both),
    ] {
        let data = dir
            .path()
            .join(format!("h_{seed}_{expected}.csv"))
            .to_string_lossy()
            .into_owned();
        let mut sim = vec![
            "--noise",
            "50e-6",
            "--random-errors",
            "0.0005,0.0005",
            "--effect",
            &planted,
            "--seed",
            seed,
        ];
        if validation {
            sim.extend(["--validation", "0.4"]);
        }
        simulate(UR5, "120", &data, &sim);
        let folds: &[&str] = if validation { &[] } else { &["--folds", "6"] };
        let report = calibrate_json(UR5, &data, folds);
        let trials = &report["diagnosis"]["rounds"][0]["trials"];
        assert_eq!(
            selected(&report),
            [expected],
            "seed {seed}, {planted}: {trials:#}"
        );
        if expected == j1 {
            let bigger = trials
                .as_array()
                .unwrap()
                .iter()
                .find(|t| t["label"] == both)
                .unwrap();
            let reason = bigger["reason"].as_str().unwrap();
            assert!(
                reason.starts_with(&format!(
                    "rival of {j1}, nested in it: the extra terms are not significant (F = "
                )),
                "{reason}"
            );
            let note = format!("nested rivals compared: {j1} kept over {both}");
            assert!(
                report["notes"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .any(|n| n.as_str().unwrap().starts_with(&note)),
                "{:#}",
                report["notes"]
            );
            let row = report["candidates"]
                .as_array()
                .unwrap()
                .iter()
                .find(|c| c["label"] == both)
                .unwrap();
            assert_eq!(row["status"], "rival", "{row:#}");
        }
    }
}
