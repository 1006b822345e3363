//! Unit tests of `table`.

use super::*;
use crate::pose::{from_xyz_rpy, pose_error, rot_z, trans_z};
use nalgebra::Vector3;
use std::f64::consts::FRAC_PI_2;

fn ur5() -> DhTable {
    DhTable {
        convention: Convention::Standard,
        base: from_xyz_rpy([0.1, -0.2, 0.3], [0.1, 0.2, 0.3]),
        tool: from_xyz_rpy([0.0, 0.0, 0.05], [0.0, 0.0, 0.7]),
        rows: vec![
            DhRow::revolute("j1", 0.0, FRAC_PI_2, 0.089159, 0.0),
            DhRow::revolute("j2", -0.425, 0.0, 0.0, 0.0),
            DhRow::revolute("j3", -0.39225, 0.0, 0.0, 0.0),
            DhRow::revolute("j4", 0.0, FRAC_PI_2, 0.10915, 0.0),
            DhRow::revolute("j5", 0.0, -FRAC_PI_2, 0.09465, 0.0),
            DhRow::prismatic("j6", 0.0, 0.0, 0.0823, 0.0),
        ],
    }
}

#[test]
fn closed_forms_equal_the_products_they_stand_for() {
    let row = DhRow::revolute("j", 0.3, 0.7, -0.2, 0.4);
    let q = 0.9;
    let std = rot_z(0.4 + q) * trans_z(-0.2) * trans_x(0.3) * rot_x(0.7);
    let md = rot_x(0.7) * trans_x(0.3) * rot_z(0.4 + q) * trans_z(-0.2);
    let (dp, dr) = pose_error(&row.transform(Convention::Standard, q), &std);
    assert!(dp < 1e-15 && dr < 1e-15);
    let (dp, dr) = pose_error(&row.transform(Convention::Modified, q), &md);
    assert!(dp < 1e-15 && dr < 1e-15);
    let p = DhRow::prismatic("p", 0.3, 0.7, -0.2, 0.4);
    let std = rot_z(0.4) * trans_z(-0.2 + q) * trans_x(0.3) * rot_x(0.7);
    let (dp, dr) = pose_error(&p.transform(Convention::Standard, q), &std);
    assert!(dp < 1e-15 && dr < 1e-15);
}

/// The prepared FK is the row-by-row one to rounding: positions within `ROUNDING` metres
/// (the UR5's reach is about 1 m), orientations within `ROUNDING` radians, tilted rows too.
#[test]
fn prepared_fk_is_fk_to_rounding() {
    /// A few units in the last place of a metre-sized chain's values.
    const ROUNDING: f64 = 1e-14;
    let mut table = ur5();
    table.rows[2].kind = JointKind::Prismatic;
    for tilt in [0.0, 0.02] {
        table.rows[3].beta = tilt;
        for convention in [Convention::Standard, Convention::Modified] {
            let t = table.to_convention(convention);
            let prepared = t.prepare();
            for k in 0..50 {
                let q: Vec<f64> = (0..6)
                    .map(|i| ((k * 7 + i * 3) as f64).sin() * 3.0)
                    .collect();
                let (a, b) = (prepared.fk(&q).unwrap(), t.fk(&q).unwrap());
                let position = (a.translation.vector - b.translation.vector).norm();
                let orientation = a.rotation.angle_to(&b.rotation);
                assert!(
                    position < ROUNDING && orientation < ROUNDING,
                    "{position} {orientation}"
                );
            }
            assert!(prepared.fk(&[0.0; 5]).is_err());
        }
    }
}

#[test]
fn ur5_zero_pose_reaches_where_the_vendor_says() {
    let mut t = ur5();
    t.base = Isometry3::identity();
    t.tool = Isometry3::identity();
    let p = t.fk(&[0.0; 6]).unwrap().translation.vector;
    // UR5 at zero: x = a2 + a3, y = -(d4 + d6) (z5 points along -y), z = d1 - d5.
    assert!((p - Vector3::new(-0.81725, -0.19145, -0.005491)).norm() < 1e-12);
}

#[test]
fn conversion_round_trips_and_keeps_the_kinematics() {
    let std = ur5();
    let md = std.to_convention(Convention::Modified);
    let back = md.to_convention(Convention::Standard);
    for q in [[0.0; 6], [0.3, -1.2, 2.0, 0.5, -0.7, 0.02]] {
        let a = std.fk(&q).unwrap();
        for other in [&md, &back] {
            let (dp, dr) = pose_error(&a, &other.fk(&q).unwrap());
            assert!(dp < 1e-14 && dr < 1e-14, "{dp} {dr}");
        }
    }
    assert_eq!(md.rows[2].a, -0.425);
    assert_eq!(md.rows[0].a, 0.0);
}

#[test]
fn the_hayati_form_keeps_the_kinematics_and_drops_the_far_common_normal() {
    // A pair 2e-4 rad off parallel written in plain DH: its common normal 2 km away.
    let plain = DhTable {
        convention: Convention::Standard,
        base: from_xyz_rpy([0.1, 0.0, 0.3], [0.0, 0.0, 0.2]),
        tool: from_xyz_rpy([0.0, 0.0, 0.1], [0.0, 0.0, 0.0]),
        rows: vec![
            DhRow::revolute("j1", 0.0, FRAC_PI_2, 0.4, 0.0),
            DhRow::revolute("j2", 0.6, 2e-4, 2000.0, 0.3),
            DhRow::revolute("j3", 0.1, -FRAC_PI_2, -2000.0, 0.1),
            DhRow::revolute("j4", 0.0, FRAC_PI_2, 0.6, 0.0),
        ],
    };
    for convention in [Convention::Standard, Convention::Modified] {
        let t = plain.to_convention(convention);
        let h = t.hayati_form(1e-2);
        for q in [[0.0; 4], [0.3, -1.2, 2.0, 0.5], [-2.0, 0.7, -0.4, 3.0]] {
            let (dp, dr) = pose_error(&t.fk(&q).unwrap(), &h.fk(&q).unwrap());
            assert!(dp < 1e-11 && dr < 1e-12, "{convention}: {dp} {dr}");
        }
        assert!(h.rows.iter().all(|r| r.d.abs() < 1.0), "{:?}", h.rows);
        let tilted: Vec<&DhRow> = h.rows.iter().filter(|r| r.beta != 0.0).collect();
        assert_eq!(tilted.len(), 1, "{convention}: {:?}", h.rows);
        // The pair's angle: `Rx(alpha) Ry(beta)` turns z by acos(cos alpha cos beta).
        let r = tilted[0];
        assert!(((r.alpha.cos() * r.beta.cos()).acos() - 2e-4).abs() < 1e-9);
        // A pair beyond the threshold stays as it was.
        assert_eq!(t.hayati_form(1e-5), t);
    }
}

#[test]
fn wrong_joint_count_is_an_error() {
    assert_eq!(
        ur5().fk(&[0.0; 3]),
        Err(CoreError::JointCount {
            expected: 6,
            found: 3
        })
    );
}

/// Each common normal is as long as its row's `a`, perpendicular to the z axes of the two
/// frames it joins, and ends on both axes; the same in the other convention.
#[test]
fn common_normals_are_the_rows_a_between_consecutive_axes() {
    let q = [0.3, -0.7, 1.1, 0.2, -0.4, 0.05];
    for table in [ur5(), ur5().to_convention(Convention::Modified)] {
        let frames = table.frames(&q).unwrap();
        let normals = table.common_normals(&q).unwrap();
        assert_eq!(normals.len(), table.rows.len());
        // In the modified convention row i's `a` is measured from frame i - 1: it holds what
        // standard row i - 1 holds.
        for (i, [start, end]) in normals.iter().enumerate() {
            let (from, to) = (&frames[i], &frames[i + 1]);
            let a = table.rows[i].a.abs();
            assert!(((end - start).norm() - a).abs() < 1e-12, "row {i}: length");
            let on_axis = |f: &Isometry3<f64>, p: &Vector3<f64>| {
                let (o, z) = (f.translation.vector, f.rotation * Vector3::z());
                ((p - o) - z * (p - o).dot(&z)).norm()
            };
            assert!(on_axis(from, start) < 1e-12, "row {i}: start on z(i-1)");
            assert!(on_axis(to, end) < 1e-12, "row {i}: end on z(i)");
            if a > 0.0 {
                let dir = (end - start) / a;
                assert!(dir.dot(&(from.rotation * Vector3::z())).abs() < 1e-12);
                assert!(dir.dot(&(to.rotation * Vector3::z())).abs() < 1e-12);
            }
        }
    }
    assert!(ur5().common_normals(&[0.0]).is_err());
}
