//! Unit tests of the calibration pipeline.

use super::*;
use nalgebra::{Translation3, UnitQuaternion};
#[test]
fn registration_recovers_a_pose() {
    let t = Isometry3::from_parts(
        Translation3::new(1.0, -2.0, 0.5),
        UnitQuaternion::from_euler_angles(0.3, -1.2, 2.5),
    );
    let a: Vec<Vector3<f64>> = (0..10)
        .map(|i| {
            let f = i as f64;
            Vector3::new(f.sin(), (1.7 * f).cos(), 0.3 * f)
        })
        .collect();
    let b: Vec<Vector3<f64>> = a
        .iter()
        .map(|p| t * nalgebra::Point3::from(*p))
        .map(|p| p.coords)
        .collect();
    let r = register(&a, &b).unwrap();
    let (dp, dr) = dh_core::pose::pose_error(&r, &t);
    assert!(dp < 1e-12 && dr < 1e-12, "{dp} {dr}");
}

/// A coarse subset keeps every sample of a rare target and session, and is the plain evenly
/// spaced subset for one target of one session.
#[test]
fn a_coarse_subset_keeps_rare_targets_and_sessions() {
    let obs = |target: usize, session: usize| {
        let mut o = Observed::new(
            vec![0.0],
            Observation::Point {
                target,
                point: Vector3::zeros(),
            },
        );
        o.session = session;
        o
    };
    let one: Vec<Observed> = (0..5000).map(|_| obs(0, 0)).collect();
    assert_eq!(
        validation::coarse_subset(&one, 1000),
        validation::evenly_spaced((0..5000).collect(), 1000)
    );
    let mut mixed: Vec<Observed> = (0..200_000).map(|_| obs(0, 0)).collect();
    mixed.extend((0..40).map(|_| obs(1, 0)));
    mixed.extend((0..60).map(|_| obs(0, 1)));
    let subset = validation::coarse_subset(&mixed, CV_TRAINING_MAX);
    assert!(subset.windows(2).all(|w| w[0] < w[1]));
    assert!((200_000..200_100).all(|i| subset.contains(&i)));
    let common = subset.iter().filter(|&&i| i < 200_000).count();
    assert!((99_000..=100_000).contains(&common), "{common}");
}
