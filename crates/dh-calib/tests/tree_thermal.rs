//! A warm-up (`thermal_growth`) of a tree robot: a torso with two arms whose every length grows
//! along an exponential in time, measured at both hands with each sample's time, is fitted by
//! a tree calibration that names the effect, its growth and time constant recovered.
// The figures of a run are printed for `--nocapture`, as the other diagnosis tests do.
#![allow(clippy::print_stdout)]

use dh_calib::calibrate::CalibrationOptions;
use dh_calib::data::{Measurements, Sample, Split};
use dh_calib::diagnose::{diagnose_tree, DiagnoseOptions, EffectSelection};
use dh_calib::effects::{parse_label_in, EffectContext};
use dh_calib::model::{Block, Model, ModelOptions, SampleContext};
use dh_calib::tree::{Branch, DhTree};
use dh_core::{Convention, DhRow, DhTable, JointSampler};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use std::f64::consts::FRAC_PI_2;

/// A torso of one joint with two arms of three (modified DH), about a metre across.
fn torso_with_arms() -> DhTree {
    let arm = |p: &str, side: f64| DhTable {
        convention: Convention::Modified,
        base: Isometry3::from_parts(
            Translation3::new(0.1, 0.2 * side, 0.0),
            UnitQuaternion::from_euler_angles(FRAC_PI_2 * side, 0.0, 0.0),
        ),
        tool: Isometry3::translation(0.0, 0.0, 0.1),
        rows: vec![
            DhRow::revolute(&format!("{p}1"), 0.0, 0.0, 0.0, 0.0),
            DhRow::revolute(&format!("{p}2"), 0.0, FRAC_PI_2, 0.0, 0.0),
            DhRow::revolute(&format!("{p}3"), 0.35, 0.0, 0.0, 0.0),
        ],
    };
    let trunk = DhTable {
        convention: Convention::Modified,
        base: Isometry3::translation(0.0, 0.0, 0.5),
        tool: Isometry3::translation(0.0, 0.0, 0.3),
        rows: vec![DhRow::revolute("t1", 0.0, 0.0, 0.1, 0.0)],
    };
    let branch = |name: &str, table| Branch {
        name: name.into(),
        table,
    };
    DhTree::new(
        trunk,
        vec![
            branch("right", arm("r", -1.0)),
            branch("left", arm("l", 1.0)),
        ],
    )
    .expect("a valid tree")
}

/// 150 poses 30 s apart (75 min), both hands measured at each with `sigma` of noise per axis,
/// small random errors of every joint's parameters, and `thermal_growth` planted at `k` and
/// `tau` (seconds); the last third held out.
fn warm_tree(tree: &DhTree, k: f64, tau: f64, sigma: f64, seed: u64) -> Measurements {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let ctx = EffectContext {
        tree: tree.clone(),
        gravity: None,
        gravity_vector: Vector3::new(0.0, 0.0, -9.80665),
    };
    let targets = [("right".to_string(), 0), ("left".to_string(), 1)];
    let mut m = Model::new_tree(tree, &targets, &ModelOptions::default()).unwrap();
    m.set_device(&Isometry3::from_parts(
        Translation3::new(-2.0, 1.5, 0.2),
        UnitQuaternion::from_euler_angles(0.0, 0.0, 1.4),
    ));
    m.set_target(0, Vector3::new(-0.05, 0.02, 0.08));
    m.set_target(1, Vector3::new(0.04, -0.03, 0.06));
    m.add_effect(parse_label_in("thermal_growth", &ctx).unwrap())
        .unwrap();
    let mut x = vec![0.0; m.parameter_count()];
    for (c, p) in m.parameters().iter().enumerate() {
        if matches!(p.block, Block::Joint(_)) {
            x[c] = rng.random_range(-1.0..1.0) * 1e-3;
        }
    }
    x[m.index_of("thermal_growth.k").unwrap()] = k;
    x[m.index_of("thermal_growth.ln_tau").unwrap()] = tau.ln();
    let mut sampler = JointSampler::new(tree.rows(), tree.size(), rng.random());
    let poses = 150;
    let mut samples = Vec::new();
    let mut q = Vec::new();
    for i in 0..poses {
        sampler.next_into(&mut q);
        let time = i as f64 * 30.0;
        let at = SampleContext {
            time: Some(time),
            ..SampleContext::default()
        };
        for target in 0..2 {
            let noise = Vector3::from_fn(|_, _| rng.sample::<f64, _>(StandardNormal) * sigma);
            samples.push(Sample {
                time: Some(time),
                orientation: None,
                session: 0,
                q: q.as_slice().into(),
                target,
                point: m.point_in(&x, &q, &at, target) + noise,
                sigma: Some(Vector3::repeat(sigma)),
                config: Some(format!("p{i}").into()),
                split: if i % 3 == 2 {
                    Split::Validation
                } else {
                    Split::Calibration
                },
                line: 0,
                socket: None,
            });
        }
    }
    Measurements {
        sessions: Vec::new(),
        joint_names: tree.rows().iter().map(|r| r.name.clone()).collect(),
        targets: vec!["right".into(), "left".into()],
        samples,
    }
}

/// 150 ppm with tau = 20 min (up to about 150 µm at the hands), 20 µm of noise: a tree
/// calibration naming `thermal_growth` fits it, `k` and `ln tau` within three standard errors
/// of the planted values and each resolved, and the fit reaches the noise floor (without the
/// effect the geometric step stays above it).
#[test]
fn a_tree_calibration_fits_a_planted_warm_up() {
    let tree = torso_with_arms();
    let (k, tau, sigma) = (150e-6, 1200.0, 20e-6);
    let data = warm_tree(&tree, k, tau, sigma, 11);
    let diag = DiagnoseOptions {
        effects: EffectSelection::Labels(vec!["thermal_growth".into()]),
        ..DiagnoseOptions::default()
    };
    let r = diagnose_tree(&tree, &data, &CalibrationOptions::default(), &diag).unwrap();
    let estimate = |name: &str| {
        let p = r.parameters.iter().find(|p| p.name == name).unwrap();
        (p.estimate, p.std_error.unwrap_or(f64::NAN))
    };
    let (k_hat, k_se) = estimate("thermal_growth.k");
    let (ln_tau, ln_tau_se) = estimate("thermal_growth.ln_tau");
    let floor = r.noise_floor.as_ref().unwrap().rms;
    let geometric = r
        .steps
        .iter()
        .find(|s| s.label == "geometric")
        .map(|s| s.rms)
        .unwrap();
    let info = format!(
        "k {:.1} +- {:.1} ppm, tau {:.0} s (ln {ln_tau:.3} +- {ln_tau_se:.3}); rms geometric {:.1} um, final {:.1} um, floor {:.1} um; steps {:?}",
        k_hat * 1e6,
        k_se * 1e6,
        ln_tau.exp(),
        geometric * 1e6,
        r.rms_after * 1e6,
        floor * 1e6,
        r.steps.iter().map(|s| s.label.as_str()).collect::<Vec<_>>()
    );
    println!("{info}");
    assert!(r.tree.is_some(), "{info}");
    assert_eq!(
        r.selected_effects,
        vec!["thermal_growth".to_string()],
        "{info}"
    );
    assert!((k_hat - k).abs() < 3.0 * k_se && k_se < 0.2 * k, "{info}");
    assert!(
        (ln_tau - tau.ln()).abs() < 3.0 * ln_tau_se && ln_tau_se < 0.3,
        "{info}"
    );
    assert!((r.rms_after / floor - 1.0).abs() < 0.1, "{info}");
    assert!(geometric > 1.2 * floor, "{info}");
}

/// The same warm-up under `--effects auto`: the tree's selection picks `thermal_growth`
/// among every candidate (its samples carry their times) and nothing else.
#[test]
fn a_tree_selection_picks_a_planted_warm_up() {
    let tree = torso_with_arms();
    let data = warm_tree(&tree, 150e-6, 1200.0, 20e-6, 11);
    let r = diagnose_tree(
        &tree,
        &data,
        &CalibrationOptions::default(),
        &DiagnoseOptions::default(),
    )
    .unwrap();
    let steps: Vec<&str> = r.steps.iter().map(|s| s.label.as_str()).collect();
    assert_eq!(
        r.selected_effects,
        vec!["thermal_growth".to_string()],
        "{steps:?} {:?}",
        r.notes
    );
}
