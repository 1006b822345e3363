//! Effects planted in simulated 6-DoF data ([`dh_calib::simulate::plant_effects`]): the
//! orientations get the rotation the effects add, so a calibration that names the effects
//! recovers their planted values within 3 standard errors, with position and angle RMS at
//! their noise floors and the targets' rotations in the tip frame unchanged.

mod fit_support;

use dh_calib::calibrate::{calibrate, CalibrationOptions};
use dh_calib::csv::{parse_measurements, write_measurements, CsvOptions};
use dh_calib::effects::parse_label;
use dh_calib::model::ModelOptions;
use dh_calib::simulate::{plant_effects, simulate, Errors, SimulationOptions};

const SIGMA_P: f64 = 20e-6;
const SIGMA_R: f64 = 50e-6;
/// A gear ratio error on the fifth joint (rad/rad): up to 1.6 mrad of rotation at ±pi, 30
/// times the orientation noise.
const GEAR: f64 = 5e-4;
/// A coupling of the sixth joint to the fifth (rad/rad).
const COUPLING: f64 = -3e-4;

#[test]
fn planted_gear_ratio_and_coupling_are_recovered_from_six_dof_poses() {
    let table = fit_support::ur5();
    let options = SimulationOptions {
        seed: 21,
        poses: 150,
        sigma: SIGMA_P,
        orientation_sigma: Some(SIGMA_R),
        errors: Errors::Explicit(vec![("j2.a".into(), 4e-4), ("j3.alpha".into(), -3e-4)]),
        ..Default::default()
    };
    let (mut data, truth) = simulate(&table, &options).unwrap();
    let before = data.clone();
    let effects = vec![
        (parse_label("gear_ratio:j5", &table).unwrap(), vec![GEAR]),
        (
            parse_label("coupling:j6:j5", &table).unwrap(),
            vec![COUPLING],
        ),
    ];
    let applied = plant_effects(
        &table,
        &mut data,
        &truth,
        &effects,
        &ModelOptions::default(),
    )
    .unwrap();
    assert_eq!(
        applied,
        vec![
            ("gear_ratio:j5".to_string(), GEAR),
            ("coupling:j6:j5".to_string(), COUPLING)
        ]
    );
    // The orientations moved by the gear ratio's rotation: far beyond their noise.
    let turned = before
        .samples
        .iter()
        .zip(&data.samples)
        .map(|(a, b)| {
            let (a, b) = (
                a.orientation.as_ref().unwrap(),
                b.orientation.as_ref().unwrap(),
            );
            a.rotation.angle_to(&b.rotation)
        })
        .fold(0.0, f64::max);
    assert!(turned > 20.0 * SIGMA_R, "largest turn {turned:e} rad");

    // Through the CSV, as a file would come.
    let text = write_measurements(&data);
    let data = parse_measurements(&text, &data.joint_names, &CsvOptions::default()).unwrap();
    let named = CalibrationOptions {
        effects: effects.iter().map(|(e, _)| e.clone()).collect(),
        ..Default::default()
    };
    let r = calibrate(&table, &data, &named).unwrap();
    for (name, planted) in &applied {
        let p = r.parameters.iter().find(|p| &p.name == name).unwrap();
        let se = p.std_error.unwrap();
        let z = (p.estimate - planted) / se;
        assert!(
            z.abs() < 3.0,
            "{name}: planted {planted:e}, found {:e} ± {se:e}",
            p.estimate
        );
    }
    let floor = r.noise_floor.as_ref().unwrap();
    let angle = r.steps.last().unwrap().angle_rms.unwrap();
    for (rms, floor) in [(r.rms_after, floor.rms), (angle, floor.angle_rms.unwrap())] {
        assert!(
            (rms / floor - 1.0).abs() < 0.1,
            "rms {rms:e}, floor {floor:e}"
        );
    }
    // The targets' frames on the tool are the simulated ones (the effects move joints and
    // not the target): within 0.1 mrad, twice one pose's noise.
    let estimated = r.target_rotations[0].unwrap();
    let error = estimated.angle_to(&truth.target_rotations[0]);
    assert!(error < 1e-4, "target rotation off by {error:e} rad");
}

#[test]
fn a_wrong_number_of_values_is_refused() {
    let table = fit_support::ur5();
    let options = SimulationOptions {
        poses: 10,
        sigma: SIGMA_P,
        orientation_sigma: Some(SIGMA_R),
        ..Default::default()
    };
    let (mut data, truth) = simulate(&table, &options).unwrap();
    let effects = vec![(
        parse_label("gear_ratio:j5", &table).unwrap(),
        vec![1e-4, 2e-4],
    )];
    let e = plant_effects(
        &table,
        &mut data,
        &truth,
        &effects,
        &ModelOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("expected 1 value(s), found 2"), "{e}");
}
