//! Unit tests of `extract`.

/// What hand-written URDFs say for pi/2: 3.7e-6 rad off, on purpose.
#[allow(clippy::approx_constant)]
const ROUNDED_HALF_PI: f64 = 1.5708;
use super::*;
use crate::pose::{from_xyz_rpy, pose_error};
use approx::assert_relative_eq;

fn axis(name: &str, p: [f64; 3], d: [f64; 3]) -> JointAxis {
    JointAxis {
        name: name.into(),
        kind: JointKind::Revolute,
        line: Line::through(Vector3::from(p), Vector3::from(d)).unwrap(),
        limits: None,
        mimic: None,
    }
}

/// A planar 2R arm along x: both axes along z, 1 m apart, tip 0.5 m further.
#[test]
fn planar_2r_by_hand() {
    let axes = [
        axis("j1", [0.0; 3], [0.0, 0.0, 1.0]),
        axis("j2", [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
    ];
    let tip = Isometry3::translation(1.5, 0.0, 0.0);
    let ex = extract(&axes, &tip, Tolerance::default(), Convention::Standard).unwrap();
    let r = &ex.table.rows;
    assert_eq!(ex.pairs[0].geometry.relation, Relation::Parallel);
    assert_relative_eq!(r[0].a, 1.0, epsilon = 1e-15);
    assert_relative_eq!(r[1].a, 0.5, epsilon = 1e-15);
    for row in r {
        assert_eq!((row.alpha, row.d, row.theta), (0.0, 0.0, 0.0));
    }
    let (dp, dr) = pose_error(&ex.table.base, &Isometry3::identity());
    assert!(dp < 1e-15 && dr < 1e-15);
    assert!(ex.warnings.is_empty());
}

/// Two skew axes: z through the origin and x through (0, 0.3, 0.2): common normal along
/// +y of length 0.3 at height 0.2; turning z about +y by +90° gives x.
#[test]
fn skew_pair_by_hand() {
    let axes = [
        axis("j1", [0.0; 3], [0.0, 0.0, 1.0]),
        axis("j2", [0.0, 0.3, 0.2], [1.0, 0.0, 0.0]),
    ];
    let tip = Isometry3::translation(0.5, 0.3, 0.2);
    let ex = extract(&axes, &tip, Tolerance::default(), Convention::Standard).unwrap();
    let r0 = &ex.table.rows[0];
    assert_eq!(ex.pairs[0].geometry.relation, Relation::Skew);
    assert_relative_eq!(r0.a, 0.3, epsilon = 1e-15);
    assert_relative_eq!(r0.d, 0.2, epsilon = 1e-15);
    assert_relative_eq!(r0.alpha, FRAC_PI_2, epsilon = 1e-15);
    let fk = ex.table.fk(&[0.0, 0.0]).unwrap();
    let (dp, dr) = pose_error(&fk, &tip);
    assert!(dp < 1e-15 && dr < 1e-15);
}

/// An axis through the base origin in a plane through the origin: eq. (4) divides by zero
/// here; the closest-point form does not.
#[test]
fn intersection_in_a_plane_through_the_origin() {
    let axes = [
        axis("j1", [0.0; 3], [0.0, 0.0, 1.0]),
        axis("j2", [0.0, 0.0, 0.4], [0.0, 1.0, 0.0]),
    ];
    let tip = from_xyz_rpy([0.0, 0.0, 0.9], [0.0, 0.0, 0.0]);
    let ex = extract(&axes, &tip, Tolerance::default(), Convention::Standard).unwrap();
    let r0 = &ex.table.rows[0];
    assert_eq!(ex.pairs[0].geometry.relation, Relation::Intersecting);
    assert_relative_eq!(r0.d, 0.4, epsilon = 1e-15);
    assert_eq!(r0.a, 0.0);
}

#[test]
fn rounded_pi_half_snaps_with_a_warning_and_exact_tolerance_does_not() {
    // Two parallel axes written with rpy 1.5708: axis 2 is 3.7e-6 rad off, tilted in the
    // plane of the two axes (the ill-conditioned direction: the axes meet 115 km away).
    let tilt = ROUNDED_HALF_PI - FRAC_PI_2;
    let axes = [
        axis("j1", [0.0; 3], [0.0, 1.0, 0.0]),
        axis("j2", [0.425, 0.0, 0.0], [tilt.sin(), tilt.cos(), 0.0]),
    ];
    let tip = Isometry3::translation(0.8, 0.0, 0.0);
    let ex = extract(&axes, &tip, Tolerance::default(), Convention::Standard).unwrap();
    assert!(ex.table.rows.iter().all(|r| r.d.abs() < 1.0));
    assert!(
        matches!(ex.warnings[0], Warning::SnappedParallel { .. }),
        "{:?}",
        ex.warnings
    );
    assert!(ex.bound.position > 1e-6 && ex.bound.position < 1e-4);
    let exact = extract(&axes, &tip, Tolerance::EXACT, Convention::Standard).unwrap();
    assert!(exact.table.rows[0].d.abs() > 1e4);
    assert!(
        matches!(exact.warnings[0], Warning::IllConditioned { .. }),
        "{:?}",
        exact.warnings
    );
}

#[test]
fn tilt_about_the_offset_direction_is_well_conditioned_even_exactly() {
    let tilt = ROUNDED_HALF_PI - FRAC_PI_2;
    let axes = [
        axis("j1", [0.0; 3], [0.0, 1.0, 0.0]),
        axis("j2", [0.425, 0.0, 0.0], [0.0, tilt.cos(), tilt.sin()]),
    ];
    let tip = Isometry3::translation(0.8, 0.0, 0.0);
    let exact = extract(&axes, &tip, Tolerance::EXACT, Convention::Standard).unwrap();
    assert!(exact.warnings.is_empty());
    assert_relative_eq!(exact.table.rows[0].a, 0.425, epsilon = 1e-12);
    assert_relative_eq!(exact.table.rows[0].alpha.abs(), tilt.abs(), epsilon = 1e-12);
}

#[test]
fn round_up_keeps_one_digit() {
    assert_relative_eq!(round_up(7.4e-6), 8e-6, epsilon = 1e-20);
    assert_relative_eq!(round_up(1e-4), 1e-4, epsilon = 1e-18);
}

/// A helix of `n` revolute joints, each 0.3 rad about x from the last and (1 cm, 0, 2 cm) off
/// it, as a URDF writes it: the axes at `q = 0`, the tip link's pose there (the last joint's
/// child, at its joint frame), and the joint origin every joint repeats.
fn helix(n: usize) -> (Vec<JointAxis>, Isometry3<f64>, Isometry3<f64>) {
    let origin = from_xyz_rpy([0.01, 0.0, 0.02], [0.3, 0.0, 0.0]);
    let mut pose = Isometry3::identity();
    let mut axes = Vec::with_capacity(n);
    for k in 0..n {
        pose *= origin;
        let mut a = axis(&format!("j{k}"), [0.0; 3], [0.0, 0.0, 1.0]);
        a.line = Line::through(pose.translation.vector, pose.rotation * Vector3::z()).unwrap();
        a.limits = Some(Limits {
            lower: -1.0,
            upper: 1.0,
        });
        axes.push(a);
    }
    (axes, pose, origin)
}

/// The walking frame stays on the given axes ([`reanchor`]): on a helix of skew axes its
/// rounding grew about 1.3x per joint (80 joints: 4e-4 m off, a failed proof; 103: NaN). Now
/// the table's forward kinematics stays within rounding of the source at 80, 200 and 600
/// joints, in both conventions.
#[test]
fn a_long_helix_of_skew_axes_keeps_its_precision() {
    for n in [80, 200, 600] {
        let (axes, tip, origin) = helix(n);
        let fk = |q: &[f64]| {
            q.iter()
                .fold(Isometry3::identity(), |t, &qk| t * origin * rot_z(qk))
        };
        for convention in [Convention::Standard, Convention::Modified] {
            let ex = extract(&axes, &tip, Tolerance::default(), convention).unwrap();
            let dev = crate::verify::compare(&ex.table, &fk, 50, 1).unwrap();
            assert!(
                dev.max_position_error < 1e-10 && dev.max_orientation_error < 1e-10,
                "{n} joints, {convention:?}: {:.3e} m, {:.3e} rad (bound {:.3e} m)",
                dev.max_position_error,
                dev.max_orientation_error,
                ex.bound.position
            );
            assert!(
                dev.max_position_error <= ex.bound.position,
                "{n}: within its bound"
            );
        }
    }
}
