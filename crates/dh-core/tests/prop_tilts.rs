//! Forward kinematics of tables whose rows carry a Hayati-Mirmirani tilt `beta`, against an
//! oracle that shares no code with `DhRow::transform`: each row is the textbook product of
//! homogeneous 4x4 matrices written out from sines and cosines. Random tables mix tilted and
//! untilted, revolute and prismatic rows, in both conventions; conversion between conventions
//! must keep them exact.

use std::f64::consts::PI;

use dh_core::{Convention, DhRow, DhTable, JointKind};
use nalgebra::{Isometry3, Matrix4, Translation3, UnitQuaternion, Vector3};
use proptest::prelude::*;

fn rz(t: f64) -> Matrix4<f64> {
    let (s, c) = t.sin_cos();
    Matrix4::new(
        c, -s, 0.0, 0.0, s, c, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
    )
}

fn rx(t: f64) -> Matrix4<f64> {
    let (s, c) = t.sin_cos();
    Matrix4::new(
        1.0, 0.0, 0.0, 0.0, 0.0, c, -s, 0.0, 0.0, s, c, 0.0, 0.0, 0.0, 0.0, 1.0,
    )
}

fn ry(t: f64) -> Matrix4<f64> {
    let (s, c) = t.sin_cos();
    Matrix4::new(
        c, 0.0, s, 0.0, 0.0, 1.0, 0.0, 0.0, -s, 0.0, c, 0.0, 0.0, 0.0, 0.0, 1.0,
    )
}

fn tr(x: f64, z: f64) -> Matrix4<f64> {
    Matrix4::new(
        1.0, 0.0, 0.0, x, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, z, 0.0, 0.0, 0.0, 1.0,
    )
}

/// The oracle: `base · A_1 ⋯ A_n · tool` with every row written out as matrices.
fn oracle(table: &DhTable, q: &[f64]) -> Matrix4<f64> {
    let mut m = table.base.to_homogeneous();
    for (r, &qi) in table.rows.iter().zip(q) {
        let (theta, d) = match r.kind {
            JointKind::Revolute => (r.theta + qi, r.d),
            JointKind::Prismatic => (r.theta, r.d + qi),
        };
        m *= match table.convention {
            Convention::Standard => {
                rz(theta) * tr(0.0, d) * tr(r.a, 0.0) * rx(r.alpha) * ry(r.beta)
            }
            Convention::Modified => {
                rx(r.alpha) * tr(r.a, 0.0) * ry(r.beta) * rz(theta) * tr(0.0, d)
            }
        };
    }
    m * table.tool.to_homogeneous()
}

fn pose() -> impl Strategy<Value = Isometry3<f64>> {
    (
        prop::array::uniform3(-1.0..1.0f64),
        prop::array::uniform3(-PI..PI),
    )
        .prop_map(|(t, r)| {
            Isometry3::from_parts(
                Translation3::new(t[0], t[1], t[2]),
                UnitQuaternion::from_euler_angles(r[0], r[1], r[2]),
            )
        })
}

/// A row; a third of them untilted, the rest tilted by up to 0.1 rad or by a near-parallel
/// 1e-6..1e-3 rad.
fn row() -> impl Strategy<Value = DhRow> {
    (
        prop::bool::weighted(0.2),
        -1.0..1.0f64,
        -PI..PI,
        -1.0..1.0f64,
        -PI..PI,
        prop_oneof![Just(0.0), -0.1..0.1f64, 1e-6..1e-3f64],
    )
        .prop_map(|(prismatic, a, alpha, d, theta, beta)| {
            let mut r = if prismatic {
                DhRow::prismatic("p", a, alpha, d, theta)
            } else {
                DhRow::revolute("r", a, alpha, d, theta)
            };
            r.beta = beta;
            r
        })
}

fn table() -> impl Strategy<Value = DhTable> {
    (
        prop::bool::ANY,
        pose(),
        pose(),
        prop::collection::vec(row(), 1..=8),
    )
        .prop_map(|(modified, base, tool, rows)| DhTable {
            convention: if modified {
                Convention::Modified
            } else {
                Convention::Standard
            },
            base,
            tool,
            rows,
        })
}

fn joint_values() -> impl Strategy<Value = Vec<f64>> {
    prop::collection::vec(-PI..PI, 8)
}

fn distance(a: &Matrix4<f64>, b: &Matrix4<f64>) -> f64 {
    (a - b).abs().max()
}

fn cases() -> u32 {
    std::env::var("URDF_DH_PROPTEST_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(512)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(cases()))]

    /// FK and the prepared FK of a table with tilts are the matrix product (to 1e-12 in each
    /// entry: metres for the translation of chains of up to 8 rows of at most 1 m, unitless for
    /// the rotation). The prepared FK turns the running pose about z and x instead of
    /// composing each row's transform (`table/prepared.rs`), so it agrees with `fk` to rounding,
    /// no longer bit for bit.
    #[test]
    fn fk_of_tilted_rows_is_the_matrix_product(t in table(), q in joint_values()) {
        let q = &q[..t.rows.len()];
        let fk = t.fk(q).unwrap();
        let expected = oracle(&t, q);
        prop_assert!(distance(&fk.to_homogeneous(), &expected) < 1e-12);
        let prepared = t.prepare().fk(q).unwrap();
        prop_assert!(distance(&prepared.to_homogeneous(), &expected) < 1e-12);
    }

    /// Converting a tilted table to the other convention and back keeps its kinematics, and the
    /// tilts move with `a` and `alpha`.
    #[test]
    fn conversion_keeps_tilted_kinematics(t in table(), q in joint_values()) {
        let q = &q[..t.rows.len()];
        let other = match t.convention {
            Convention::Standard => Convention::Modified,
            Convention::Modified => Convention::Standard,
        };
        let converted = t.to_convention(other);
        let back = converted.to_convention(t.convention);
        let want = oracle(&t, q);
        prop_assert!(distance(&oracle(&converted, q), &want) < 1e-12);
        prop_assert!(distance(&back.fk(q).unwrap().to_homogeneous(), &want) < 1e-12);
        let tilts = |t: &DhTable| t.rows.iter().filter(|r| r.beta != 0.0).count();
        let end = match t.convention {
            Convention::Standard => t.rows.last(),
            Convention::Modified => t.rows.first(),
        };
        let lost = usize::from(end.is_some_and(|r| r.beta != 0.0));
        prop_assert_eq!(tilts(&converted), tilts(&t) - lost);
    }
}

/// A row without a tilt takes the closed form untouched: the same bits as the untilted
/// formula's product, and a tilt of exactly zero is no tilt.
#[test]
fn an_untilted_row_is_bit_identical_to_plain_dh() {
    let plain = DhRow::revolute("j", 0.3, 0.7, -0.2, 0.4);
    let mut zero = plain.clone();
    zero.beta = 0.0;
    for c in [Convention::Standard, Convention::Modified] {
        assert_eq!(plain.transform(c, 0.9), zero.transform(c, 0.9));
    }
    let mut tilted = plain.clone();
    tilted.beta = 1e-3;
    let p = tilted
        .transform(Convention::Standard, 0.0)
        .translation
        .vector;
    let q = plain
        .transform(Convention::Standard, 0.0)
        .translation
        .vector;
    // The tilt turns about y at the far end of the link: it moves no origin.
    assert!((p - q).norm() < 1e-15);
    let z = tilted.transform(Convention::Standard, 0.0).rotation * Vector3::z();
    let z0 = plain.transform(Convention::Standard, 0.0).rotation * Vector3::z();
    assert!((z.angle(&z0) - 1e-3).abs() < 1e-12);
}
