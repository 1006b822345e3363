//! Unit tests of the calibration pipeline.

use super::*;
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
