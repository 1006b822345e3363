//! The pieces the diagnosis rests on: Jacobians of trees and of every effect against central
//! differences, a tree calibration that recovers a planted compliance, and residual structure
//! that no candidate explains (a drift in time) reported instead of fitted.
mod diagnose_support;

use std::sync::Arc;

use dh_calib::calibrate::CalibrationOptions;
use dh_calib::data::{Measurements, Sample, Split};
use dh_calib::diagnose::{diagnose, diagnose_tree, DiagnoseOptions, EffectSelection};
use dh_calib::effects::{parse_label_in, EffectContext};
use dh_calib::fit::{numeric_jacobian, Problem};
use dh_calib::gravity::{GravityModel, Inertial, Inertials};
use dh_calib::model::{Model, ModelOptions, ModelProblem, Observation, Observed};
use dh_calib::tree::{Branch, DhTree};
use dh_core::{Convention, DhRow, DhTable, JointSampler};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

/// A torso with two arms (modified DH), like a small humanoid upper body.
fn humanoid() -> DhTree {
    let arm = |p: &str, side: f64| DhTable {
        convention: Convention::Modified,
        base: Isometry3::from_parts(
            Translation3::new(0.1, 0.2 * side, 0.0),
            UnitQuaternion::from_euler_angles(std::f64::consts::FRAC_PI_2 * side, 0.0, 0.0),
        ),
        tool: Isometry3::translation(0.0, 0.0, 0.1),
        rows: vec![
            DhRow::revolute(&format!("{p}1"), 0.0, 0.0, 0.0, 0.0),
            DhRow::revolute(&format!("{p}2"), 0.0, std::f64::consts::FRAC_PI_2, 0.0, 0.0),
            DhRow::revolute(&format!("{p}3"), 0.35, 0.0, 0.0, 0.0),
            DhRow::revolute(
                &format!("{p}4"),
                0.0,
                -std::f64::consts::FRAC_PI_2,
                0.3,
                0.0,
            ),
        ],
    };
    let trunk = DhTable {
        convention: Convention::Modified,
        base: Isometry3::translation(0.0, 0.0, 0.5),
        tool: Isometry3::translation(0.0, 0.0, 0.3),
        rows: vec![
            DhRow::revolute("t1", 0.0, 0.0, 0.1, 0.0),
            DhRow::revolute("t2", 0.0, -std::f64::consts::FRAC_PI_2, 0.0, 0.0),
        ],
    };
    DhTree::new(
        trunk,
        vec![
            Branch {
                name: "right".into(),
                table: arm("r", -1.0),
            },
            Branch {
                name: "left".into(),
                table: arm("l", 1.0),
            },
        ],
    )
    .unwrap()
}

fn humanoid_context(tree: &DhTree) -> EffectContext {
    let mut links = Vec::new();
    for r in tree.rows() {
        links.push((
            r.name.clone(),
            Inertial {
                mass: 2.0,
                com: Vector3::new(0.05, 0.1, -0.05),
            },
        ));
    }
    let inertials = Inertials {
        links,
        payloads: vec![
            (
                0,
                Inertial {
                    mass: 1.0,
                    com: Vector3::new(0.0, 0.0, 0.05),
                },
            ),
            (
                1,
                Inertial {
                    mass: 1.5,
                    com: Vector3::zeros(),
                },
            ),
        ],
    };
    EffectContext {
        tree: tree.clone(),
        gravity: Some(Arc::new(
            GravityModel::new(tree, &inertials, GravityModel::default_gravity()).unwrap(),
        )),
        gravity_vector: GravityModel::default_gravity(),
    }
}

#[test]
fn tree_and_effect_jacobians_match_central_differences() {
    let tree = humanoid();
    let ctx = humanoid_context(&tree);
    let targets = [("a".to_string(), 0), ("b".to_string(), 1)];
    let mut m = Model::new_tree(&tree, &targets, &ModelOptions::default()).unwrap();
    m.set_device(&Isometry3::from_parts(
        Translation3::new(1.0, -2.0, 0.3),
        UnitQuaternion::from_euler_angles(0.3, 0.2, -1.1),
    ));
    m.set_target(0, Vector3::new(0.02, -0.03, 0.05));
    m.set_target(1, Vector3::new(-0.01, 0.04, 0.02));
    for l in [
        "compliance:t2",
        "compliance:r3",
        "lateral_compliance:l2",
        "lateral_compliance:t1",
        "coupling:r4:r3",
        "gear_harmonic:l3:2",
        "gear_ratio:t1",
        "gear_harmonic2:r3",
        "backlash_direction:t2",
        "backlash_direction:l2",
        "scale",
        "drift",
        "thermal_growth",
    ] {
        m.add_effect(parse_label_in(l, &ctx).unwrap()).unwrap();
    }
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let x: Vec<f64> = m
        .parameters()
        .iter()
        .map(|p| {
            if p.name.starts_with("compliance") || p.name.starts_with("lateral") {
                rng.random_range(-1e-4..1e-4)
            } else {
                rng.random_range(-0.01..0.01)
            }
        })
        .collect();
    let mut sampler = JointSampler::new(tree.rows(), tree.size(), 9);
    let mut obs = Vec::new();
    let mut q = Vec::new();
    for i in 0..6 {
        sampler.next_into(&mut q);
        let target = i % 2;
        obs.push(Observed {
            session: 0,
            q: q.as_slice().into(),
            observation: Observation::Point {
                target,
                point: m.point(&x, &q, target) + Vector3::new(1e-3, 0.0, -2e-3),
            },
            // Every sample at its own place in a sequence (the order effects' columns).
            context: dh_calib::model::SampleContext {
                // Seconds, read by the thermal growth (`ln_tau` near 0: tau near 1 s).
                time: Some(i as f64 * 0.4),
                direction: (0..q.len())
                    .map(|k| if (i + k) % 3 == 0 { 1.0 } else { -1.0 })
                    .collect(),
                order: i as f64 / 5.0,
            },
        });
    }
    let p = ModelProblem {
        model: &m,
        observations: &obs,
    };
    let cols: Vec<usize> = (0..m.parameter_count()).collect();
    let steps: Vec<f64> = m
        .parameters()
        .iter()
        .map(|p| {
            if p.name.starts_with("compliance") || p.name.starts_with("lateral") {
                1e-8
            } else {
                1e-6
            }
        })
        .collect();
    let mut worst: f64 = 0.0;
    for b in 0..p.block_count() {
        let n = cols.len();
        let mut r = vec![0.0; 3];
        let mut j = vec![0.0; 3 * n];
        p.jacobian(&x, b, &cols, &mut r, &mut j);
        let num = numeric_jacobian(&p, &x, b, &cols, &steps);
        for i in 0..3 {
            for c in 0..n {
                // Compare in metres per unit step.
                let d = (j[i * n + c] - num[(i, c)]).abs() * steps[c];
                worst = worst.max(d);
            }
        }
    }
    assert!(
        worst < 1e-12,
        "largest Jacobian mismatch {worst} m per step"
    );
    // A target on the left arm does not move with the right arm's joints.
    let r3 = m.index_of("r3.theta").unwrap();
    let mut r = vec![0.0; 3];
    let mut j = vec![0.0; 3];
    p.jacobian(&x, 1, &[r3], &mut r, &mut j);
    assert_eq!(j, vec![0.0; 3]);
}

#[test]
fn a_parallel_tilt_frees_the_zero_tilt_of_a_near_parallel_pair() {
    // Joints 2 and 3 two degrees off parallel: classic DH, with a zero tilt held for the
    // candidate.
    let t = DhTable {
        convention: Convention::Standard,
        base: Isometry3::identity(),
        tool: Isometry3::identity(),
        rows: vec![
            DhRow::revolute("j1", 0.0, std::f64::consts::FRAC_PI_2, 0.4, 0.0),
            DhRow::revolute("j2", 0.5, 2f64.to_radians(), 0.0, 0.0),
            DhRow::revolute("j3", 0.4, 0.0, 0.0, 0.0),
        ],
    };
    let mut m = Model::new(&t, &["a".to_string()], &ModelOptions::default()).unwrap();
    assert_eq!(m.tilt_rows(), vec![1]);
    let ctx = EffectContext::serial(&t);
    let e = parse_label_in("parallel_tilt:j3", &ctx).unwrap();
    assert_eq!(e.joint(), "j2");
    m.add_effect(e).unwrap();
    // The tilt turns frame 2 about its y axis: the tip moves as a rotation there would.
    let c = m.index_of("parallel_tilt:j3").unwrap();
    let mut x = vec![0.0; m.parameter_count()];
    let q = [0.3, -0.4, 0.5];
    let p0 = m.point(&x, &q, 0);
    x[c] = 1e-3;
    let p1 = m.point(&x, &q, 0);
    assert!((p1 - p0).norm() > 1e-4);
    // The Hayati row of an exactly parallel pair already estimates it.
    let ur = diagnose_support::ur5();
    let mut m = Model::new(&ur, &["a".to_string()], &ModelOptions::default()).unwrap();
    assert!(m.tilt_rows().is_empty());
    let ctx = EffectContext::serial(&ur);
    assert!(m
        .add_effect(parse_label_in("parallel_tilt:j3", &ctx).unwrap())
        .is_err());
}

/// Samples of `tree` with random geometric errors and the given effects planted.
fn simulate_tree(
    tree: &DhTree,
    ctx: &EffectContext,
    planted: &[(&str, f64)],
    seed: u64,
    sigma: f64,
) -> Measurements {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let targets = [("right".to_string(), 0), ("left".to_string(), 1)];
    let mut m = Model::new_tree(tree, &targets, &ModelOptions::default()).unwrap();
    m.set_device(&Isometry3::from_parts(
        Translation3::new(-2.0, 1.5, 0.2),
        UnitQuaternion::from_euler_angles(0.0, 0.0, 1.4),
    ));
    m.set_target(0, Vector3::new(-0.05, 0.02, 0.08));
    m.set_target(1, Vector3::new(0.04, -0.03, 0.06));
    for (l, _) in planted {
        m.add_effect(parse_label_in(l, ctx).unwrap()).unwrap();
    }
    let mut x = vec![0.0; m.parameter_count()];
    for (c, p) in m.parameters().iter().enumerate() {
        if matches!(p.block, dh_calib::model::Block::Joint(_)) {
            x[c] = rng.random_range(-1.0..1.0) * 2e-3;
        }
    }
    for (l, v) in planted {
        x[m.index_of(l).unwrap()] = *v;
    }
    let mut sampler = JointSampler::new(tree.rows(), tree.size(), rng.random());
    let mut samples = Vec::new();
    let mut q = Vec::new();
    for i in 0..300 {
        sampler.next_into(&mut q);
        for k in 0..2 {
            let noise = Vector3::from_fn(|_, _| rng.sample::<f64, _>(StandardNormal) * sigma);
            samples.push(Sample {
                time: None,
                orientation: None,
                session: 0,
                q: q.as_slice().into(),
                target: k,
                point: m.point(&x, &q, k) + noise,
                sigma: Some(Vector3::repeat(sigma)),
                config: Some(format!("p{i}").into()),
                split: if i < 200 {
                    Split::Calibration
                } else {
                    Split::Validation
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

#[test]
fn a_tree_calibration_names_a_torso_compliance_shared_by_both_arms() {
    let tree = humanoid();
    let ctx = humanoid_context(&tree);
    let sigma = 0.2e-3;
    let data = simulate_tree(&tree, &ctx, &[("compliance:t2", 4e-4)], 7, sigma);
    let inertials = {
        let g = ctx.gravity.as_ref().unwrap();
        // The same masses as the truth (the context was built from them).
        let _ = g;
        let mut links = Vec::new();
        for r in tree.rows() {
            links.push((
                r.name.clone(),
                Inertial {
                    mass: 2.0,
                    com: Vector3::new(0.05, 0.1, -0.05),
                },
            ));
        }
        Inertials {
            links,
            payloads: vec![
                (
                    0,
                    Inertial {
                        mass: 1.0,
                        com: Vector3::new(0.0, 0.0, 0.05),
                    },
                ),
                (
                    1,
                    Inertial {
                        mass: 1.5,
                        com: Vector3::zeros(),
                    },
                ),
            ],
        }
    };
    let diag = DiagnoseOptions {
        inertials: Some(inertials),
        ..DiagnoseOptions::default()
    };
    let r = diagnose_tree(&tree, &data, &CalibrationOptions::default(), &diag).unwrap();
    assert_eq!(
        r.selected_effects,
        vec!["compliance:t2".to_string()],
        "{:?}",
        r.steps
    );
    let floor = r.noise_floor.as_ref().unwrap().rms;
    assert!(
        (r.rms_after / floor - 1.0).abs() < 0.1,
        "{} vs {floor}",
        r.rms_after
    );
    let t = r.tree.as_ref().unwrap();
    assert_eq!(t.branches().len(), 2);
    let est = &r.diagnosis.as_ref().unwrap().effect_parameters[0];
    assert!(
        (est.value - 4e-4).abs() < 4.0 * est.std_error.unwrap() + 1e-5,
        "{est:?}"
    );
}

#[test]
fn a_drift_no_candidate_explains_is_reported_not_fitted() {
    // A device creeping 0.4 mm along z over the session (thermal drift): no effect of the
    // list is a function of the joint values.
    let arm = diagnose_support::ur_sized();
    let mut sim = diagnose_support::simulate(&arm, None, 4242);
    let n = sim.data.samples.len() as f64;
    for (i, s) in sim.data.samples.iter_mut().enumerate() {
        s.point.z += 0.4e-3 * i as f64 / n;
        s.split = Split::Calibration;
    }
    let diag = DiagnoseOptions {
        inertials: Some(arm.inertials.clone()),
        ..DiagnoseOptions::default()
    };
    let r = diagnose(&arm.table, &sim.data, &CalibrationOptions::default(), &diag).unwrap();
    let d = r.diagnosis.as_ref().unwrap();
    assert!(d.residual_test.significant, "{}", d.residual_test.summary);
    let order = d
        .structure
        .iter()
        .find(|s| s.variable == "pose order")
        .unwrap();
    assert!(order.significant, "{order:?}");
    assert!(
        d.notes.iter().any(|n| n.contains("pose order")),
        "{:?}",
        d.notes
    );
    assert!(
        r.selected_effects.len() <= 1,
        "a drift is not fitted by effects: {:?}",
        r.selected_effects
    );
    let _ = EffectSelection::Auto;
}

/// A coupling with a joint that (nearly) never moves in the data is no candidate: a torso held
/// within 1e-4 rad would otherwise "couple" with whatever stands in for its deflection.
#[test]
fn a_coupling_with_a_joint_that_does_not_move_is_inert() {
    let mut arm = diagnose_support::ur_sized();
    let still = arm.table.rows[0].name.clone();
    arm.table.rows[0].limits = Some(dh_core::Limits {
        lower: 0.0,
        upper: 1e-4,
    });
    let sim = diagnose_support::simulate(&arm, None, 77);
    let diag = DiagnoseOptions {
        inertials: Some(arm.inertials.clone()),
        ..DiagnoseOptions::default()
    };
    let r = diagnose(&arm.table, &sim.data, &CalibrationOptions::default(), &diag).unwrap();
    let d = r.diagnosis.as_ref().unwrap();
    let first = &d.rounds[0].candidates;
    let with_still: Vec<_> = first
        .iter()
        .filter(|c| {
            c.label.starts_with("coupling:") && c.label.split(':').any(|part| part == still)
        })
        .collect();
    assert!(
        !with_still.is_empty(),
        "coupling candidates with {still} are listed"
    );
    for c in &with_still {
        assert_eq!(
            c.status,
            dh_calib::findings::CandidateStatus::Inert,
            "{}: {:?}",
            c.label,
            c.status
        );
    }
    assert!(!r.selected_effects.iter().any(|e| e.contains(&still)));
    // Couplings between joints that move are still scored.
    assert!(first.iter().any(|c| c.label.starts_with("coupling:")
        && c.status != dh_calib::findings::CandidateStatus::Inert));
}
