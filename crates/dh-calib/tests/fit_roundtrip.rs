//! Simulated round trips: planted errors recovered, residuals at the noise floor, rank
//! deficiency reported with aliases, Hayati on near-parallel pairs, far-off device frames.
mod fit_support;

use std::sync::Arc;

use dh_calib::calibrate::{calibrate, CalibrationOptions, NoiseSource, Report, Validation};
use dh_calib::data::Measurements;
use dh_calib::fit::{CalibError, FitOptions};
use dh_calib::model::{Block, GearRatio, Model, ModelOptions};
use dh_calib::simulate::{simulate, Errors, SimulationOptions};
use dh_core::{Convention, DhTable};
use nalgebra::{Isometry3, Translation3, UnitQuaternion};

/// Free DH parameters of a calibration of `table` (from a noise-free run).
fn free_dh(table: &DhTable, targets: usize) -> Vec<String> {
    let (data, _) = simulate(
        table,
        &SimulationOptions {
            poses: 60,
            target_count: targets,
            ..Default::default()
        },
    )
    .unwrap();
    let r = calibrate(table, &data, &CalibrationOptions::default()).unwrap();
    let m = Model::new(table, &data.targets, &ModelOptions::default()).unwrap();
    r.parameters
        .iter()
        .filter(|p| p.free)
        .filter(|p| {
            let i = m.index_of(&p.name).unwrap();
            matches!(m.parameters()[i].block, Block::Joint(_))
        })
        .map(|p| p.name.clone())
        .collect()
}

/// 1 mm and 0.05 degree errors with alternating signs on the given parameters.
fn planted(names: &[String]) -> Vec<(String, f64)> {
    names
        .iter()
        .enumerate()
        .map(|(i, n)| {
            let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
            let is_angle = [".alpha", ".theta", ".beta"].iter().any(|s| n.ends_with(s));
            let v = if is_angle {
                0.05_f64.to_radians()
            } else {
                1e-3
            };
            (n.clone(), sign * v)
        })
        .collect()
}

fn estimate(r: &Report, name: &str) -> (f64, f64, Option<f64>) {
    let p = r.parameters.iter().find(|p| p.name == name).unwrap();
    (p.nominal, p.estimate, p.std_error)
}

fn assert_recovered(r: &Report, errors: &[(String, f64)]) {
    for (name, truth) in errors {
        let (nom, est, se) = estimate(r, name);
        let se = se.unwrap();
        let z = (est - nom - truth) / se;
        assert!(
            z.abs() < 3.0,
            "{name}: planted {truth:e}, found {:e} ± {se:e} (z = {z:.2})",
            est - nom
        );
    }
}

fn assert_at_noise_floor(r: &Report) {
    let floor = r.noise_floor.as_ref().unwrap();
    let ratio = r.rms_after / floor.rms;
    assert!(
        (ratio - 1.0).abs() < 0.05,
        "rms {} vs floor {} (ratio {ratio})",
        r.rms_after,
        floor.rms
    );
}

fn noisy_round_trip(table: &DhTable, seed: u64, sigma: f64) {
    let free = free_dh(table, 3);
    let errors = planted(&free);
    let (data, truth) = simulate(
        table,
        &SimulationOptions {
            seed,
            poses: 200,
            target_count: 3,
            sigma,
            errors: Errors::Explicit(errors.clone()),
            ..Default::default()
        },
    )
    .unwrap();
    let r = calibrate(table, &data, &CalibrationOptions::default()).unwrap();
    assert_recovered(&r, &errors);
    assert_at_noise_floor(&r);
    assert!(matches!(
        r.noise_floor.as_ref().unwrap().source,
        NoiseSource::Samples
    ));
    assert!(matches!(
        r.validation,
        Validation::CrossValidation { folds: 5, .. }
    ));
    // The nominal model is millimetres off; the calibrated one is at the noise.
    assert!(r.rms_before > 10.0 * r.rms_after);
    let (vb, va) = (r.val_rms_before.unwrap(), r.val_rms_after.unwrap());
    assert!(va < vb && va < 1.2 * r.rms_after, "{vb} {va}");
    // Device and targets are found too.
    let (dp, dr) = dh_core::pose::pose_error(&r.device, &truth.device);
    assert!(dp < 1e-3 && dr < 1e-3, "{dp} {dr}");
    assert!(r.condition_number.is_finite() && r.condition_number < 1e3);
}

#[test]
fn ur5_planted_errors_are_recovered_within_three_standard_errors() {
    noisy_round_trip(&fit_support::ur5(), 7, 20e-6);
}

#[test]
fn large_industrial_arm_planted_errors_are_recovered_within_three_standard_errors() {
    noisy_round_trip(&fit_support::kr_like(), 8, 50e-6);
}

#[test]
fn noise_free_data_converges_to_rounding() {
    for table in [
        fit_support::ur5(),
        fit_support::kr_like(),
        fit_support::ur5().to_convention(Convention::Modified),
    ] {
        let (data, truth) = simulate(
            &table,
            &SimulationOptions {
                poses: 80,
                target_count: 2,
                errors: Errors::Random {
                    length: 2e-3,
                    angle: 0.1_f64.to_radians(),
                },
                validation_fraction: 0.2,
                ..Default::default()
            },
        )
        .unwrap();
        let r = calibrate(&table, &data, &CalibrationOptions::default()).unwrap();
        assert!(r.rms_after < 1e-12, "{}", r.rms_after);
        assert!(r.val_rms_after.unwrap() < 1e-12);
        assert!(matches!(r.validation, Validation::Split { samples: 32 }));
        // The calibrated table is the true robot up to the aliased (fixed) parameters, which
        // the device frame and the targets absorb: predictions agree everywhere.
        for s in &data.samples {
            let tip = r.device * r.calibrated.fk(&s.q).unwrap();
            let p = tip * nalgebra::Point3::from(r.targets[s.target].1);
            assert!((p.coords - s.point).norm() < 1e-9);
        }
        // And the true table predicts the same points from the true frames.
        let s = &data.samples[5];
        let p = truth.device
            * truth.table.fk(&s.q).unwrap()
            * nalgebra::Point3::from(truth.targets[s.target].1);
        assert!((p.coords - s.point).norm() < 1e-9);
    }
}

#[test]
fn rank_deficiency_is_reported_with_aliases() {
    let table = fit_support::ur5();
    let (data, _) = simulate(
        &table,
        &SimulationOptions {
            poses: 60,
            sigma: 1e-5,
            ..Default::default()
        },
    )
    .unwrap();
    let r = calibrate(&table, &data, &CalibrationOptions::default()).unwrap();
    let aliases = |name: &str| {
        r.fixed
            .iter()
            .find(|f| f.name == name)
            .unwrap_or_else(|| panic!("{name} not fixed: {:?}", r.fixed))
            .aliases
            .clone()
    };
    assert_eq!(aliases("j1.theta"), vec!["device.rz"]);
    assert_eq!(aliases("j1.d"), vec!["device.z"]);
    assert_eq!(aliases("base.x"), vec!["device.x"]);
    // The last row moves the tip frame rigidly: the targets absorb it.
    assert!(aliases("j6.theta")
        .iter()
        .all(|a| a.starts_with("target.t1.")));
    // The `d` of each Hayati pair has no parameter (its row's `beta` replaces it) and is
    // listed as held, with that `beta`.
    let replaced: Vec<&str> = r
        .fixed
        .iter()
        .filter(|f| f.aliases.len() == 1 && f.aliases[0].ends_with(".beta"))
        .map(|f| f.name.as_str())
        .collect();
    assert_eq!(replaced.len(), 2, "{:?}", r.fixed);
    for f in &r.fixed {
        match r.parameters.iter().find(|p| p.name == f.name) {
            Some(p) => assert!(!p.free && p.std_error.is_none() && p.estimate == p.nominal),
            None => assert!(replaced.contains(&f.name.as_str()), "{}", f.name),
        }
    }
    // 6 device + 3 target + (24 DH - 2 dropped d + 2 beta - 2 first row - 4 last row) = 27.
    assert_eq!(r.rank, 27);
    // 45 parameters: device 6, base 6, DH 24, tool 6, target 3.
    assert_eq!(r.parameters.len(), 45);
    assert_eq!(r.fixed.len(), 45 - 27 + 2);
}

#[test]
fn near_parallel_axes_are_better_conditioned_with_hayati() {
    // UR5 with its shoulder-elbow pair tilted by 0.3 degree: classic DH puts the common
    // normal ~80 m away and its d is nearly unobservable.
    let mut table = fit_support::ur5();
    table.rows[1].alpha = 0.3_f64.to_radians();
    let (data, _) = simulate(
        &table,
        &SimulationOptions {
            poses: 100,
            target_count: 2,
            sigma: 1e-5,
            ..Default::default()
        },
    )
    .unwrap();
    // The conditioning of the parametrisations themselves: without the sensitivity floor,
    // which would hold the classic d (see the end).
    let raw = FitOptions {
        min_sensitivity: 0.0,
        ..Default::default()
    };
    let hayati_opts = CalibrationOptions {
        fit: raw,
        ..Default::default()
    };
    let hayati = calibrate(&table, &data, &hayati_opts).unwrap();
    let classic_opts = CalibrationOptions {
        model: ModelOptions {
            hayati_threshold: 0.0,
            ..Default::default()
        },
        fit: raw,
        ..Default::default()
    };
    let classic = calibrate(&table, &data, &classic_opts).unwrap();
    let pair = &hayati.parametrisation[1];
    assert!(pair.hayati && (pair.angle - 0.3_f64.to_radians()).abs() < 1e-9);
    assert!(!classic.parametrisation[1].hayati);
    assert!(hayati
        .parameters
        .iter()
        .any(|p| p.name == "j2.beta" && p.free));
    assert!(
        classic.condition_number > 10.0 * hayati.condition_number,
        "classic {} hayati {}",
        classic.condition_number,
        hayati.condition_number
    );
    // The classic d of the tilted pair is either fixed or far less certain than a length
    // measured with 10 µm noise should be.
    let d2 = classic
        .parameters
        .iter()
        .find(|p| p.name == "j2.d")
        .unwrap();
    assert!(!d2.free || d2.std_error.unwrap() > 1e-3);
    // With the default floor the classic d's combination, which moves the points by less than
    // 1 µm per mm, is held: one more parameter fixed, and the rest as well conditioned as
    // Hayati's.
    let floored = calibrate(
        &table,
        &data,
        &CalibrationOptions {
            fit: FitOptions::default(),
            ..classic_opts
        },
    )
    .unwrap();
    assert_eq!(floored.fixed.len(), classic.fixed.len() + 1);
    assert!(
        floored.condition_number < 2.0 * hayati.condition_number,
        "floored {} hayati {}",
        floored.condition_number,
        hayati.condition_number
    );
}

#[test]
fn exactly_parallel_classic_d_is_fixed_with_its_partner() {
    let table = fit_support::ur5();
    let (data, _) = simulate(
        &table,
        &SimulationOptions {
            poses: 60,
            sigma: 1e-5,
            ..Default::default()
        },
    )
    .unwrap();
    let opts = CalibrationOptions {
        model: ModelOptions {
            hayati_threshold: 0.0,
            ..Default::default()
        },
        ..Default::default()
    };
    let r = calibrate(&table, &data, &opts).unwrap();
    // Exactly parallel axes are still "within 0 of parallel": Hayati applies. Tilt them a
    // hair beyond a zero threshold instead.
    assert!(r.parametrisation[1].hayati);
    let mut tilted = table.clone();
    tilted.rows[1].alpha = 1e-9;
    tilted.rows[2].alpha = -1e-9;
    let r = calibrate(&tilted, &data, &opts).unwrap();
    assert!(!r.parametrisation[1].hayati);
    let fixed: Vec<&str> = r.fixed.iter().map(|f| f.name.as_str()).collect();
    assert!(
        fixed.contains(&"j2.d") || fixed.contains(&"j3.d"),
        "{fixed:?}"
    );
    let f = r
        .fixed
        .iter()
        .find(|f| f.name == "j2.d" || f.name == "j3.d")
        .unwrap();
    assert!(
        f.aliases.iter().any(|a| a.ends_with(".d")),
        "{:?}",
        f.aliases
    );
}

#[test]
fn a_far_off_device_frame_is_found_in_closed_form() {
    let table = fit_support::kr_like();
    let device = Isometry3::from_parts(
        Translation3::new(-6.0, 9.0, 2.5),
        UnitQuaternion::from_euler_angles(3.0, -1.4, -2.9),
    );
    let (data, truth) = simulate(
        &table,
        &SimulationOptions {
            poses: 50,
            target_count: 2,
            target_offset: 0.3,
            device: Some(device),
            sigma: 3e-5,
            ..Default::default()
        },
    )
    .unwrap();
    let r = calibrate(&table, &data, &CalibrationOptions::default()).unwrap();
    let (dp, dr) = dh_core::pose::pose_error(&r.device, &truth.device);
    assert!(dp < 1e-3 && dr < 1e-4, "{dp} {dr}");
    // The nominal model is the truth here: the nominal step is already at the noise.
    let floor = r.noise_floor.as_ref().unwrap();
    assert!(
        r.rms_before < 1.1 * floor.rms,
        "{} {}",
        r.rms_before,
        floor.rms
    );
    for (k, (_, t)) in r.targets.iter().enumerate() {
        assert!((t - truth.targets[k].1).norm() < 1e-3);
    }
}

#[test]
fn noise_floor_from_repeats() {
    let table = fit_support::ur5();
    let (mut data, _) = simulate(
        &table,
        &SimulationOptions {
            poses: 80,
            repeats: 3,
            sigma: 4e-5,
            ..Default::default()
        },
    )
    .unwrap();
    for s in &mut data.samples {
        s.sigma = None;
    }
    let r = calibrate(&table, &data, &CalibrationOptions::default()).unwrap();
    let floor = r.noise_floor.unwrap();
    assert_eq!(
        floor.source,
        NoiseSource::Repeats {
            groups: 80,
            dof: 160
        }
    );
    assert!((floor.sigma / 4e-5 - 1.0).abs() < 0.1, "{}", floor.sigma);
    // Cross-validation keeps repeats of a pose together: 80 groups, not 240.
    assert_eq!(
        r.validation,
        Validation::CrossValidation {
            folds: 5,
            groups: 80,
            training_subsample: None,
            one_step: false,
        }
    );
}

#[test]
fn an_effect_step_estimates_a_gear_ratio() {
    let table = fit_support::ur5();
    let (data, _) = simulate(
        &table,
        &SimulationOptions {
            poses: 80,
            sigma: 1e-5,
            validation_fraction: 0.25,
            ..Default::default()
        },
    )
    .unwrap();
    let opts = CalibrationOptions {
        effects: vec![Arc::new(GearRatio::new(&table, "j2").unwrap())],
        ..Default::default()
    };
    let r = calibrate(&table, &data, &opts).unwrap();
    let labels: Vec<&str> = r.steps.iter().map(|s| s.label.as_str()).collect();
    assert_eq!(labels, vec!["nominal", "geometric", "effects"]);
    let g = r
        .parameters
        .iter()
        .find(|p| p.name == "gear_ratio:j2")
        .unwrap();
    // No gear error was simulated.
    assert!(g.free && (g.estimate / g.std_error.unwrap()).abs() < 3.0);
}

#[test]
fn bad_input_is_an_error() {
    let table = fit_support::ur5();
    let (data, _) = simulate(&table, &SimulationOptions::default()).unwrap();
    let mut missing = data.clone();
    missing.joint_names[2] = "other".into();
    assert_eq!(
        calibrate(&table, &missing, &CalibrationOptions::default()).unwrap_err(),
        CalibError::MissingJoint { joint: "j3".into() }
    );
    let mut bad_target = data.clone();
    bad_target.samples[3].target = 4;
    assert!(matches!(
        calibrate(&table, &bad_target, &CalibrationOptions::default()),
        Err(CalibError::BadTarget { target: 4, .. })
    ));
    let few = Measurements {
        sessions: Vec::new(),
        samples: data.samples[..2].to_vec(),
        ..data.clone()
    };
    assert!(matches!(
        calibrate(&table, &few, &CalibrationOptions::default()),
        Err(CalibError::TooFewSamples { .. })
    ));
}

/// Found by the invalid-input corpus: four poses of a UR5 (12 coordinates) were "calibrated"
/// to RMS 0 by freeing 12 parameters. Data that leaves no residual degree of freedom is refused,
/// saying how many samples the model's identifiable parameters need.
#[test]
fn too_few_samples_for_the_geometric_model_say_how_many() {
    let table = fit_support::ur5();
    let data = |poses| {
        simulate(
            &table,
            &SimulationOptions {
                poses,
                sigma: 1e-5,
                ..Default::default()
            },
        )
        .unwrap()
        .0
    };
    let e = calibrate(&table, &data(4), &CalibrationOptions::default()).unwrap_err();
    let CalibError::TooFewSamples { needed, found, .. } = &e else {
        panic!("{e}")
    };
    assert_eq!(*found, 4);
    // 6 device + 3 target + the arm's identifiable DH parameters, 3 coordinates per sample.
    assert!((8..=12).contains(needed), "{e}");
    assert!(e.to_string().contains("identifiable parameters"), "{e}");
    assert!(calibrate(&table, &data(*needed + 5), &CalibrationOptions::default()).is_ok());
}

/// A test point that no calibration sample measured (another reflector, mounted for the test
/// set only) is located on the tip from its own validation samples before they are compared:
/// the validation figure is then at the noise, not the reflector's offset from the tip.
#[test]
fn a_validation_only_target_is_located_before_it_is_compared() {
    use dh_calib::data::Split;
    let table = fit_support::ur5();
    let (mut data, _) = simulate(
        &table,
        &SimulationOptions {
            poses: 120,
            sigma: 2e-5,
            target_count: 2,
            target_offset: 0.05,
            validation_fraction: 0.3,
            errors: dh_calib::simulate::Errors::Random {
                length: 1e-3,
                angle: 2e-3,
            },
            ..Default::default()
        },
    )
    .unwrap();
    // Target 0 calibrates, target 1 only validates.
    data.samples.retain(|s| match s.split {
        Split::Calibration => s.target == 0,
        Split::Validation => s.target == 1,
    });
    let r = calibrate(&table, &data, &CalibrationOptions::default()).unwrap();
    let val = r.val_rms_after.unwrap();
    // Noise floor: sqrt(3) * 2e-5 = 3.5e-5 m RMS.
    assert!(val < 6e-5, "validation RMS {val}");
    assert!(
        r.notes
            .iter()
            .any(|n| n.contains("located from its own") && n.contains("validation samples")),
        "{:?}",
        r.notes
    );
}
