//! Unit tests of the residual chart.

use super::*;
use dh_calib::calibrate::{calibrate as run_calibration, CalibrationOptions};
use dh_calib::simulate::{simulate, Errors, SimulationOptions};
use dh_core::{Convention, DhRow};

fn arm() -> DhTable {
    let h = std::f64::consts::FRAC_PI_2;
    DhTable {
        convention: Convention::Standard,
        base: Isometry3::identity(),
        tool: Isometry3::identity(),
        rows: vec![
            DhRow::revolute("j1", 0.0, h, 0.4, 0.0),
            DhRow::revolute("j2", 0.5, 0.0, 0.0, 0.0),
            DhRow::revolute("j3", 0.1, h, 0.0, 0.0),
            DhRow::revolute("j4", 0.0, -h, 0.45, 0.0),
            DhRow::revolute("j5", 0.0, h, 0.0, 0.0),
            DhRow::revolute("j6", 0.0, 0.0, 0.1, 0.0),
        ],
    }
}

/// The chart recomputes every residual from the report (nominal-step frames, calibrated
/// table, effect estimates): its RMS must be the report's, or the chart shows another fit.
#[test]
fn chart_residuals_reproduce_the_reported_rms() {
    let table = arm();
    let (data, _) = simulate(
        &table,
        &SimulationOptions {
            poses: 60,
            sigma: 2e-5,
            target_count: 2,
            errors: Errors::Explicit(vec![("j2.a".into(), 4e-4), ("j3.theta".into(), 1e-3)]),
            ..SimulationOptions::default()
        },
    )
    .unwrap();
    let effects: Vec<Arc<dyn Effect>> =
        vec![dh_calib::effects::parse_label("gear_ratio:j2", &table).unwrap()];
    for with_effects in [false, true] {
        let options = CalibrationOptions {
            effects: if with_effects {
                effects.clone()
            } else {
                vec![]
            },
            ..CalibrationOptions::default()
        };
        let report = run_calibration(&table, &data, &options).unwrap();
        let inputs = Inputs {
            table: table.clone(),
            model_name: "arm".into(),
            robot: None,
            units: (LengthUnit::M, AngleUnit::Rad),
            links: ("base_link".into(), "tool0".into()),
            coupled: vec![],
            data: data.clone(),
            cpa: false,
        };
        let chart = chart("d.csv", &inputs, &report, &effects, LengthUnit::Mm).unwrap();
        let rms = |p: &Panel| {
            let d: Vec<f64> = p.residuals.iter().map(|r| r.distance).collect();
            (d.iter().map(|v| v * v).sum::<f64>() / d.len() as f64).sqrt()
        };
        assert!(
            (rms(&chart.panels[0]) - report.rms_before).abs() < 1e-9,
            "before {} {}",
            rms(&chart.panels[0]),
            report.rms_before
        );
        assert!(
            // The calibrated table folds Hayati tilts into DH values to within
            // dh_calib::model::FOLD_TOLERANCE (1e-9 m, 1e-9 rad).
            (rms(&chart.panels[1]) - report.rms_after).abs() < 1e-8,
            "after {} {}",
            rms(&chart.panels[1]),
            report.rms_after
        );
        assert_eq!(chart.poses, 60);
    }
}
