//! Unit tests of the effect labels and models.

use super::*;
use crate::gravity::{Inertial, Inertials};
use dh_core::DhRow;
use nalgebra::{Isometry3, Vector3};

fn arm() -> DhTable {
    DhTable {
        convention: Convention::Standard,
        base: Isometry3::identity(),
        tool: Isometry3::identity(),
        rows: vec![
            DhRow::revolute("j1", 0.0, std::f64::consts::FRAC_PI_2, 0.4, 0.0),
            DhRow::revolute("j2", 0.5, 0.0, 0.0, 0.0),
            DhRow::revolute("j3", 0.4, 0.0, 0.0, 0.0),
        ],
    }
}

#[test]
fn labels_round_trip_and_bad_ones_say_why() {
    let t = arm();
    for l in [
        "gear_ratio:j2",
        "gear_harmonic:j1",
        "gear_harmonic:j1:2",
        "gear_harmonic2:j2",
        "backlash_direction:j3",
        "drift",
        "coupling:j2:j3",
        "scale",
        "parallel_tilt:j3",
    ] {
        let e = parse_label(l, &t).unwrap();
        assert_eq!(label_of(e.as_ref()), l);
    }
    let err = |l: &str| parse_label(l, &t).unwrap_err().to_string();
    assert!(err("compliance:j2").contains("inertials"));
    assert!(err("gear_ratio").contains("1 joint name"));
    assert!(err("warp:j1").contains("expected one of"));
    assert!(err("coupling:j2:j2").contains("different"));
    assert!(err("parallel_tilt:j1").contains("first of its table"));
    assert!(err("drift:j1").contains("0 joint names"));
    assert!(err("backlash_direction").contains("1 joint name"));
    assert!(err("gear_harmonic2:j1:2").contains("1 joint name"));
    assert!(matches!(
        parse_label("backlash_direction:j9", &t),
        Err(CalibError::MissingJoint { .. })
    ));
    // The twice-per-turn effect alone: sin 2q, cos 2q.
    let e = parse_label("gear_harmonic2:j2", &t).unwrap();
    assert_eq!(
        e.parameter_names(),
        ["gear_harmonic2:j2.sin2", "gear_harmonic2:j2.cos2"]
    );
    let q = [0.0, 0.3, 0.0];
    let want = 1e-5 * (0.6f64).sin() + 2e-5 * (0.6f64).cos();
    assert!((e.delta(&q, &[1e-5, 2e-5]) - want).abs() < 1e-18);
    assert!(matches!(
        parse_label("gear_ratio:j9", &t),
        Err(CalibError::MissingJoint { .. })
    ));
}

#[test]
fn candidates_cover_every_joint_and_name_what_is_skipped() {
    let t = arm();
    let c = candidates(&EffectContext::serial(&t), &[1]);
    let labels: Vec<String> = c.effects.iter().map(|e| e.label()).collect();
    assert!(labels.contains(&"gear_ratio:j3".to_string()));
    assert!(labels.contains(&"coupling:j1:j3".to_string()));
    assert!(labels.contains(&"scale".to_string()));
    assert!(labels.contains(&"parallel_tilt:j3".to_string()));
    for l in [
        "gear_harmonic2:j1",
        "gear_harmonic:j2:2",
        "backlash_direction:j3",
        "drift",
    ] {
        assert!(labels.contains(&l.to_string()), "{l}");
    }
    assert!(!labels.iter().any(|l| l.starts_with("compliance")));
    assert_eq!(c.skipped.len(), 1);
    let inertials = Inertials {
        links: vec![(
            "j3".into(),
            Inertial {
                mass: 5.0,
                com: Vector3::new(-0.2, 0.0, 0.0),
            },
        )],
        payloads: vec![],
    };
    let g = GravityModel::serial(&t, &inertials, GravityModel::default_gravity()).unwrap();
    let ctx = EffectContext {
        tree: DhTree::serial(&t),
        gravity: Some(Arc::new(g)),
        gravity_vector: GravityModel::default_gravity(),
    };
    let c = candidates(&ctx, &[]);
    let labels: Vec<String> = c.effects.iter().map(|e| e.label()).collect();
    assert!(labels.contains(&"compliance:j2".to_string()));
    assert!(c.skipped.is_empty());
    // A compliance turns the joint by c · tau.
    let e = parse_label_in("compliance:j2", &ctx).unwrap();
    let q = [0.0, 0.0, 0.0];
    let tau = ctx
        .gravity
        .as_ref()
        .unwrap()
        .torque(&q, 1, TorqueAxis::Joint);
    assert!((e.delta(&q, &[1e-5]) - 1e-5 * tau).abs() < 1e-15);
    assert!(tau.abs() > 1.0);
}
