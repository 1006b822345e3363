//! Property tests on random serial chains, degenerate geometry included on purpose: axes along
//! coordinate axes (so consecutive axes are often parallel, antiparallel or coincident), zero
//! offsets (intersecting at the origin), right-angle and arbitrary rpy, unnormalised and
//! defaulted axes, prismatic and fixed joints.

mod common;

use std::f64::consts::{FRAC_PI_2, PI};

use common::{serial_urdf, JointSpec};
use dh_core::Line;
use nalgebra::{Isometry3, Matrix4, Rotation3, Translation3, Unit, Vector3};
use proptest::prelude::*;
use urdf_axes::{Chain, UrdfModel};

fn unit_vector() -> impl Strategy<Value = [f64; 3]> {
    prop_oneof![
        (0usize..3, any::<bool>()).prop_map(|(i, negative)| {
            let mut v = [0.0; 3];
            v[i] = if negative { -1.0 } else { 1.0 };
            v
        }),
        (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64)
            .prop_filter("non-zero", |(x, y, z)| x * x + y * y + z * z > 1e-4)
            .prop_map(|(x, y, z)| {
                let n = (x * x + y * y + z * z).sqrt();
                [x / n, y / n, z / n]
            }),
    ]
}

fn axis() -> impl Strategy<Value = Option<[f64; 3]>> {
    prop_oneof![
        Just(None),
        unit_vector().prop_map(Some),
        (unit_vector(), 0.01..100.0f64).prop_map(|(v, s)| Some(v.map(|c| c * s))),
    ]
}

fn angle() -> impl Strategy<Value = f64> {
    prop_oneof![
        Just(0.0),
        (-4i32..=4).prop_map(|k| f64::from(k) * FRAC_PI_2),
        -PI..PI,
    ]
}

fn offset() -> impl Strategy<Value = f64> {
    prop_oneof![Just(0.0), -1.0..1.0f64]
}

fn joint_spec() -> impl Strategy<Value = JointSpec> {
    (
        prop::sample::select(vec!["revolute", "continuous", "prismatic", "fixed"]),
        [offset(), offset(), offset()],
        [angle(), angle(), angle()],
        axis(),
    )
        .prop_map(|(kind, xyz, rpy, axis)| JointSpec {
            kind,
            xyz,
            rpy,
            axis,
        })
}

fn serial_chain(len: std::ops::RangeInclusive<usize>) -> impl Strategy<Value = Vec<JointSpec>> {
    prop::collection::vec(joint_spec(), len).prop_filter("at least one moving joint", |v| {
        v.iter().any(|j| j.kind != "fixed")
    })
}

/// A chain with joint values: one per moving joint, within ±pi (radians) or ±1 (metres).
fn chain_and_q() -> impl Strategy<Value = (Vec<JointSpec>, Vec<f64>)> {
    serial_chain(1..=8).prop_flat_map(|specs| {
        let moving = specs.iter().filter(|j| j.kind != "fixed").count();
        (Just(specs), prop::collection::vec(-PI..PI, moving))
    })
}

fn moving(j: &JointSpec) -> bool {
    j.kind != "fixed"
}

fn local_axis(j: &JointSpec) -> Unit<Vector3<f64>> {
    Unit::new_normalize(Vector3::from(j.axis.unwrap_or([1.0, 0.0, 0.0])))
}

/// URDF forward kinematics written out with 4x4 matrices, independent of the crate:
/// `T = Π Trans(xyz) Rz(y) Ry(p) Rx(r) Motion(q)`.
fn oracle(specs: &[JointSpec], q: &[f64]) -> Matrix4<f64> {
    let mut t = Matrix4::identity();
    let mut values = q.iter();
    for j in specs {
        let [r, p, y] = j.rpy;
        let rot = Rotation3::from_axis_angle(&Vector3::z_axis(), y)
            * Rotation3::from_axis_angle(&Vector3::y_axis(), p)
            * Rotation3::from_axis_angle(&Vector3::x_axis(), r);
        t = t * Translation3::from(Vector3::from(j.xyz)).to_homogeneous() * rot.to_homogeneous();
        if moving(j) {
            let v = values.next().copied().unwrap_or(0.0);
            let a = local_axis(j);
            t *= if j.kind == "prismatic" {
                Translation3::from(a.into_inner() * v).to_homogeneous()
            } else {
                Rotation3::from_axis_angle(&a, v).to_homogeneous()
            };
        }
    }
    t
}

fn build(specs: &[JointSpec]) -> (UrdfModel, Chain) {
    let model = UrdfModel::parse(&serial_urdf(specs)).unwrap();
    let chain = model.chain(None, None).unwrap();
    (model, chain)
}

fn assert_same_line(a: &Line, b: &Line, tol: f64, what: &str) -> Result<(), TestCaseError> {
    let dd = (a.direction() - b.direction()).norm();
    let dk = (a.moment() - b.moment()).norm();
    prop_assert!(
        dd <= tol && dk <= tol,
        "{what}: lines differ by {dd:.3e} in direction, {dk:.3e} in moment: {a:?} vs {b:?}"
    );
    Ok(())
}

fn close_poses(a: &Isometry3<f64>, b: &Isometry3<f64>) -> (f64, f64) {
    (
        (a.translation.vector - b.translation.vector).norm(),
        a.rotation.angle_to(&b.rotation),
    )
}

proptest! {
    #[test]
    fn fk_at_zero_is_the_tip_pose(specs in serial_chain(1..=8)) {
        let (_, chain) = build(&specs);
        let zero = vec![0.0; chain.axes().len()];
        let (dp, dr) = close_poses(&chain.fk(&zero), &chain.tip_pose());
        prop_assert!(dp <= 1e-12 && dr <= 1e-12, "fk(0) vs tip_pose: {dp:.3e} m, {dr:.3e} rad");
        let lines = chain.axis_lines(&zero).unwrap();
        for (l, ax) in lines.iter().zip(chain.axes()) {
            assert_same_line(l, &ax.line, 1e-12, &ax.name)?;
        }
    }

    #[test]
    fn fk_matches_the_matrix_oracle((specs, q) in chain_and_q()) {
        let (_, chain) = build(&specs);
        prop_assert_eq!(chain.axes().len(), q.len());
        let got = chain.fk(&q).to_homogeneous();
        let want = oracle(&specs, &q);
        let err = (got - want).abs().max();
        prop_assert!(err <= 1e-12, "fk differs from the matrix oracle by {err:.3e}");
        prop_assert_eq!(chain.try_fk(&q).unwrap(), chain.fk(&q));
    }

    #[test]
    fn each_axis_is_invariant_to_its_own_joint((specs, q) in chain_and_q()) {
        let (model, chain) = build(&specs);
        let lines_at_q = chain.axis_lines(&q).unwrap();
        for (k, (n, j)) in specs.iter().enumerate().filter(|(_, j)| moving(j)).enumerate() {
            // The child link of joint n + 1 is l{n + 1}: its pose from a sub-chain's FK.
            let sub = model.chain(Some("l0"), Some(&format!("l{}", n + 1))).unwrap();
            prop_assert_eq!(sub.axes().len(), k + 1);
            let line_from = |child: Isometry3<f64>| {
                Line::through(child.translation.vector, child.rotation * local_axis(j).into_inner())
                    .unwrap()
            };
            // Only this joint moved: its line is the one at q = 0.
            let mut only = vec![0.0; k + 1];
            only[k] = q[k];
            let name = format!("j{}", n + 1);
            assert_same_line(&line_from(sub.fk(&only)), &chain.axes()[k].line, 1e-9, &name)?;
            // All joints moved: the line through the moved child frame is the one axis_lines
            // gives, and moving this joint alone again leaves it where it was.
            let moved = line_from(sub.fk(&q[..=k]));
            assert_same_line(&moved, &lines_at_q[k], 1e-9, &name)?;
            let mut again = q[..=k].to_vec();
            again[k] += 1.0;
            assert_same_line(&line_from(sub.fk(&again)), &moved, 1e-9, &name)?;
        }
    }
}
