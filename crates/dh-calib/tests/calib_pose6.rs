//! The calibration pipeline on simulated 6-DoF data (a tracker's 6-DoF probe): planted DH
//! errors of a UR5 recovered within 3 standard errors, position and angle RMS at their noise
//! floors, the verdict's degrees of freedom counting 6 per pose, and smaller standard errors
//! than the same samples without their orientation.

mod fit_support;

use dh_calib::calibrate::{calibrate, CalibrationOptions, Report};
use dh_calib::csv::{parse_measurements, write_measurements, CsvOptions};
use dh_calib::data::Measurements;
use dh_calib::model::{Block, Model, ModelOptions};
use dh_calib::simulate::{simulate, Errors, SimulationOptions};

const SIGMA_P: f64 = 20e-6;
const SIGMA_R: f64 = 50e-6;

fn options(errors: Errors, sigma: f64) -> SimulationOptions {
    SimulationOptions {
        seed: 13,
        poses: 120,
        sigma,
        orientation_sigma: Some(SIGMA_R),
        errors,
        ..Default::default()
    }
}

/// The DH parameters a 6-DoF calibration estimates (from a run with tiny noise).
fn free_dh() -> Vec<String> {
    let table = fit_support::ur5();
    let (data, _) = simulate(&table, &options(Errors::None, 1e-9)).unwrap();
    let r = calibrate(&table, &data, &CalibrationOptions::default()).unwrap();
    let m = Model::new(&table, &data.targets, &ModelOptions::default()).unwrap();
    r.parameters
        .iter()
        .filter(|p| p.free)
        .filter(|p| {
            m.index_of(&p.name)
                .is_some_and(|i| matches!(m.parameters()[i].block, Block::Joint(_)))
        })
        .map(|p| p.name.clone())
        .collect()
}

/// 0.5 mm and 0.02 degree errors with alternating signs.
fn planted(names: &[String]) -> Vec<(String, f64)> {
    names
        .iter()
        .enumerate()
        .map(|(i, n)| {
            let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
            let angle = [".alpha", ".theta", ".beta"].iter().any(|s| n.ends_with(s));
            let v = if angle { 0.02_f64.to_radians() } else { 0.5e-3 };
            (n.clone(), sign * v)
        })
        .collect()
}

fn std_error(r: &Report, name: &str) -> Option<f64> {
    r.parameters
        .iter()
        .find(|p| p.name == name)
        .and_then(|p| p.std_error)
}

fn without_orientation(data: &Measurements) -> Measurements {
    let mut d = data.clone();
    for s in &mut d.samples {
        s.orientation = None;
    }
    d
}

#[test]
fn six_dof_calibration_recovers_planted_errors_at_both_noise_floors() {
    let table = fit_support::ur5();
    let free = free_dh();
    let errors = planted(&free);
    let (data, truth) =
        simulate(&table, &options(Errors::Explicit(errors.clone()), SIGMA_P)).unwrap();
    assert!(data.samples.iter().all(|s| s.orientation.is_some()));
    // Through the CSV, as a file would come.
    let text = write_measurements(&data);
    let data = parse_measurements(&text, &data.joint_names, &CsvOptions::default()).unwrap();
    let r = calibrate(&table, &data, &CalibrationOptions::default()).unwrap();
    for name in ["target.t1.rx", "target.t1.ry", "target.t1.rz"] {
        let p = r.parameters.iter().find(|p| p.name == name).unwrap();
        assert!(p.free, "{name} not estimated");
    }
    for (name, planted) in &errors {
        let p = r.parameters.iter().find(|p| &p.name == name).unwrap();
        let se = p.std_error.unwrap();
        let z = (p.estimate - p.nominal - planted) / se;
        assert!(
            z.abs() < 3.0,
            "{name}: planted {planted:e}, found {:e} ± {se:e}",
            p.estimate - p.nominal
        );
    }
    let floor = r.noise_floor.as_ref().unwrap();
    let last = r.steps.last().unwrap();
    let angle = last.angle_rms.unwrap();
    let angle_floor = floor.angle_rms.unwrap();
    // The true target rotation is a random one, not the identity the model starts from.
    assert!(truth.target_rotations[0].angle() > 0.1);
    for (rms, floor) in [(r.rms_after, floor.rms), (angle, angle_floor)] {
        let ratio = rms / floor;
        assert!((ratio - 1.0).abs() < 0.1, "rms {rms:e}, floor {floor:e}");
    }
    // The verdict's chi-square counts 6 residuals per pose.
    let dof = r.verdict.test.dof.0;
    assert_eq!(dof, (6 * data.samples.len() - last.free) as f64);
}

#[test]
fn the_same_samples_without_orientation_give_larger_standard_errors() {
    let table = fit_support::ur5();
    let errors = planted(&free_dh());
    let (data, _) = simulate(&table, &options(Errors::Explicit(errors.clone()), SIGMA_P)).unwrap();
    let poses = calibrate(&table, &data, &CalibrationOptions::default()).unwrap();
    let points = calibrate(
        &table,
        &without_orientation(&data),
        &CalibrationOptions::default(),
    )
    .unwrap();
    let free = |r: &Report| r.parameters.iter().filter(|p| p.free).count();
    assert!(
        free(&points) < free(&poses),
        "{} {}",
        free(&points),
        free(&poses)
    );
    for (name, _) in &errors {
        let (sp, so) = (std_error(&points, name), std_error(&poses, name).unwrap());
        // Free with points too: a larger standard error; else not identified at all.
        if let Some(sp) = sp {
            assert!(so < sp, "{name}: poses {so:e}, points {sp:e}");
        }
    }
}
