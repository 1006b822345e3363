//! The measurement model: analytic Jacobians against central differences, Hayati pairs, and
//! folding `beta` back into exact DH values.
mod fit_support;

use std::sync::Arc;

use dh_calib::fit::{numeric_jacobian, Problem};
use dh_calib::model::{Block, GearRatio, Model, ModelOptions, ModelProblem, Observation, Observed};
use dh_core::{Convention, JointSampler};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn device() -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(1.5, -0.7, 0.4),
        UnitQuaternion::from_euler_angles(0.4, -0.9, 2.2),
    )
}

/// A model with two targets, a gear-ratio effect, and random non-zero parameters.
fn model_and_x(table: &dh_core::DhTable, seed: u64) -> (Model, Vec<f64>) {
    let mut m = Model::new(
        table,
        &["a".to_string(), "b".to_string()],
        &ModelOptions::default(),
    )
    .unwrap();
    m.set_device(&device());
    m.set_target(0, Vector3::new(0.05, -0.02, 0.1));
    m.set_target(1, Vector3::new(-0.03, 0.06, 0.02));
    let joint = table.rows[1].name.clone();
    m.add_effect(Arc::new(GearRatio::new(table, &joint).unwrap()))
        .unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let x = (0..m.parameter_count())
        .map(|_| rng.random_range(-0.01..0.01))
        .collect();
    (m, x)
}

fn observations(m: &Model, x: &[f64], table: &dh_core::DhTable) -> Vec<Observed> {
    let mut sampler = JointSampler::new(&table.rows, table.size(), 3);
    let mut q = Vec::new();
    let mut out = Vec::new();
    for i in 0..6 {
        sampler.next_into(&mut q);
        // Measurements a little off the model so that residuals are not zero.
        let point = m.point(x, &q, i % 2) + Vector3::new(1e-3, -2e-3, 5e-4);
        out.push(Observed {
            session: 0,
            q: q.as_slice().into(),
            observation: Observation::Point {
                target: i % 2,
                point,
            },
            context: Default::default(),
        });
        let pose = m.tip(x, &q)
            * Isometry3::from_parts(
                Translation3::new(1e-3, 0.0, -1e-3),
                UnitQuaternion::from_euler_angles(0.02, -0.03, 0.05),
            );
        out.push(Observed {
            session: 0,
            q: q.as_slice().into(),
            observation: Observation::Pose(Box::new(pose)),
            context: Default::default(),
        });
    }
    out
}

fn check_jacobian(table: &dh_core::DhTable) {
    let (m, x) = model_and_x(table, 11);
    let obs = observations(&m, &x, table);
    let p = ModelProblem {
        model: &m,
        observations: &obs,
    };
    let cols: Vec<usize> = (0..m.parameter_count()).collect();
    let steps = vec![1e-6; cols.len()];
    let mut worst: f64 = 0.0;
    for b in 0..p.block_count() {
        let rows = p.block_size(b);
        let mut r = vec![0.0; rows];
        let mut j = vec![0.0; rows * cols.len()];
        p.jacobian(&x, b, &cols, &mut r, &mut j);
        let num = numeric_jacobian(&p, &x, b, &cols, &steps);
        let mut r2 = vec![0.0; rows];
        p.residuals(&x, b, &mut r2);
        assert_eq!(r, r2);
        for i in 0..rows {
            for (k, c) in cols.iter().enumerate() {
                let d = (j[i * cols.len() + k] - num[(i, k)]).abs();
                assert!(
                    d < 1e-7,
                    "block {b} row {i} {}: analytic {} numeric {}",
                    m.parameters()[*c].name,
                    j[i * cols.len() + k],
                    num[(i, k)]
                );
                worst = worst.max(d);
            }
        }
    }
    // Every parameter moves something in some block (no silently dead column).
    assert!(worst < 1e-7);
}

#[test]
fn analytic_jacobian_matches_central_differences_standard() {
    check_jacobian(&fit_support::ur5());
    check_jacobian(&fit_support::kr_like());
}

#[test]
fn analytic_jacobian_matches_central_differences_modified() {
    check_jacobian(&fit_support::ur5().to_convention(Convention::Modified));
}

#[test]
fn every_column_moves_the_points() {
    let t = fit_support::ur5();
    let (m, x) = model_and_x(&t, 5);
    let obs = observations(&m, &x, &t);
    let p = ModelProblem {
        model: &m,
        observations: &obs,
    };
    let cols: Vec<usize> = (0..m.parameter_count()).collect();
    let mut norms = vec![0.0; cols.len()];
    for b in 0..p.block_count() {
        let rows = p.block_size(b);
        let mut r = vec![0.0; rows];
        let mut j = vec![0.0; rows * cols.len()];
        p.jacobian(&x, b, &cols, &mut r, &mut j);
        for i in 0..rows {
            for k in 0..cols.len() {
                norms[k] += j[i * cols.len() + k].powi(2);
            }
        }
    }
    for (k, n) in norms.iter().enumerate() {
        assert!(*n > 1e-8, "{} has no effect", m.parameters()[k].name);
    }
}

#[test]
fn ur5_parallel_pairs_use_hayati_and_kr_uses_classic_dh() {
    let m = Model::new(&fit_support::ur5(), &["t".into()], &ModelOptions::default()).unwrap();
    let hayati: Vec<(&str, &str)> = m
        .pairs()
        .iter()
        .filter(|p| p.hayati)
        .map(|p| (p.first.as_str(), p.second.as_str()))
        .collect();
    assert_eq!(hayati, vec![("j2", "j3"), ("j3", "j4")]);
    let names: Vec<&str> = m.parameters().iter().map(|p| p.name.as_str()).collect();
    for n in ["j2.beta", "j3.beta", "j4.d", "j1.d"] {
        assert!(names.contains(&n), "{n} missing");
    }
    for n in ["j2.d", "j3.d", "j1.beta", "j4.beta"] {
        assert!(!names.contains(&n), "{n} present");
    }
    let pair = &m.pairs()[1];
    assert_eq!(pair.beta_row.as_deref(), Some("j2"));
    assert_eq!(pair.dropped_d.as_deref(), Some("j2"));

    // Modified: the beta sits on the later row, the dropped d on the earlier one.
    let md = fit_support::ur5().to_convention(Convention::Modified);
    let m = Model::new(&md, &["t".into()], &ModelOptions::default()).unwrap();
    let pair = &m.pairs()[1];
    assert!(pair.hayati);
    assert_eq!(pair.beta_row.as_deref(), Some("j3"));
    assert_eq!(pair.dropped_d.as_deref(), Some("j2"));
    assert!(m.index_of("j3.beta").is_some() && m.index_of("j2.d").is_none());

    let m = Model::new(
        &fit_support::kr_like(),
        &["t".into()],
        &ModelOptions::default(),
    )
    .unwrap();
    // Only the arm's two parallel axes (A2, A3); the wrist axes are perpendicular.
    let hayati: Vec<&str> = m
        .pairs()
        .iter()
        .filter(|p| p.hayati)
        .map(|p| p.first.as_str())
        .collect();
    assert_eq!(hayati, vec!["a2"]);
    assert!((m.pairs()[0].angle - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    assert_eq!(m.indices(|b| matches!(b, Block::Joint(_))).len(), 24);

    let bad = ModelOptions {
        hayati_threshold: -1.0,
        ..Default::default()
    };
    assert!(Model::new(&fit_support::ur5(), &["t".into()], &bad).is_err());
}

#[test]
fn calibrated_table_reproduces_the_model_exactly_with_bounded_lengths() {
    for table in [
        fit_support::ur5(),
        fit_support::ur5().to_convention(Convention::Modified),
    ] {
        let (m, mut x) = model_and_x(&table, 21);
        // No effect in the table: zero its parameter.
        for i in m.indices(|b| matches!(b, Block::Effect(_))) {
            x[i] = 0.0;
        }
        let calibrated = m.table_at(&x);
        let mut sampler = JointSampler::new(&table.rows, 1.0, 9);
        let mut q = Vec::new();
        for _ in 0..20 {
            sampler.next_into(&mut q);
            let (dp, dr) =
                dh_core::pose::pose_error(&calibrated.fk(&q).unwrap(), &m.robot_fk(&x, &q));
            assert!(dp < 1e-12 && dr < 1e-12, "{dp} {dr}");
        }
        // A 0.57 degree tilt over a 0.4 m link would put a plain DH common normal tens of
        // metres away; the tilt stays a tilt and every length stays near the nominal one.
        let tilted: Vec<&str> = calibrated
            .rows
            .iter()
            .filter(|r| r.beta != 0.0)
            .map(|r| r.name.as_str())
            .collect();
        assert!(!tilted.is_empty());
        for (r, n) in calibrated.rows.iter().zip(&table.rows) {
            assert!((r.d - n.d).abs() < 0.1 && (r.a - n.a).abs() < 0.1, "{r:?}");
        }
        // A model of the calibrated table (its tilts as nominal values) predicts the same.
        let mut again = Model::new(&calibrated, &["t".into()], &ModelOptions::default()).unwrap();
        again.set_device(&m.device_at(&x));
        let y = vec![0.0; again.parameter_count()];
        sampler.next_into(&mut q);
        let (dp, dr) = dh_core::pose::pose_error(&again.robot_fk(&y, &q), &m.robot_fk(&x, &q));
        assert!(dp < 1e-12 && dr < 1e-12, "{dp} {dr}");
    }
}

#[test]
fn a_tiny_tilt_is_kept_as_it_is() {
    let table = fit_support::ur5();
    let m = Model::new(&table, &["t".into()], &ModelOptions::default()).unwrap();
    let mut x = vec![0.0; m.parameter_count()];
    x[m.index_of("j2.beta").unwrap()] = 1e-14;
    let t = m.table_at(&x);
    assert_eq!(t.rows[1].beta, 1e-14);
    assert_eq!(
        (t.rows[1].a, t.rows[1].d),
        (table.rows[1].a, table.rows[1].d)
    );
}

#[test]
fn rebase_keeps_the_predictions() {
    let t = fit_support::kr_like();
    let (mut m, mut x) = model_and_x(&t, 8);
    let q = [0.1, -1.0, 0.5, 0.2, 0.3, -0.4];
    let before = m.point(&x, &q, 1);
    m.rebase(&mut x);
    assert!((m.point(&x, &q, 1) - before).norm() < 1e-12);
    assert!(m
        .indices(|b| matches!(b, Block::Device | Block::Target(_)))
        .iter()
        .all(|&i| x[i] == 0.0));
}
