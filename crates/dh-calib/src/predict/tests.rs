use super::*;

#[test]
fn a_session_covariance_is_the_marginal_with_its_frame_as_the_device() {
    let names = ["device.x", "a.d", "session.s2.x", "session.s3.x"];
    let m = DMatrix::from_fn(4, 4, |i, j| if i == j { 1.0 + i as f64 } else { 0.1 });
    let c = Covariance::new(names.iter().map(|n| n.to_string()).collect(), m).unwrap();
    let first = c.in_session(None);
    assert_eq!(first.parameters, ["device.x", "a.d"]);
    assert_eq!(first.matrix[(1, 1)], 2.0);
    let s3 = c.in_session(Some("s3"));
    assert_eq!(s3.parameters, ["a.d", "device.x"]);
    assert_eq!(
        (s3.matrix[(0, 0)], s3.matrix[(1, 1)], s3.matrix[(0, 1)]),
        (2.0, 4.0, 0.1)
    );
    assert_eq!(c.in_session(Some("s9")).parameters, ["a.d"]);
}
use dh_core::{Convention, DhRow};

fn table() -> DhTable {
    DhTable {
        convention: Convention::Standard,
        base: Isometry3::identity(),
        tool: Isometry3::translation(0.0, 0.0, 0.1),
        rows: vec![
            DhRow::revolute("j1", 0.0, std::f64::consts::FRAC_PI_2, 0.3, 0.0),
            DhRow::revolute("j2", 0.4, 0.0, 0.0, 0.0),
            DhRow::revolute("j3", 0.3, 0.0, 0.0, 0.0),
        ],
    }
}

#[test]
fn effects_group_by_label_and_bad_names_are_named() {
    let t = table();
    let ctx = EffectContext::serial(&t);
    let values = vec![
        ("gear_harmonic:j1.sin".to_string(), 1e-4),
        ("gear_ratio:j2".to_string(), 2e-3),
        ("gear_harmonic:j1.cos".to_string(), -1e-4),
    ];
    let e = effects_from_parameters(&values, &ctx).unwrap();
    assert_eq!(e.len(), 2);
    assert_eq!(e[0].0.label(), "gear_harmonic:j1");
    assert_eq!(e[0].1, vec![1e-4, -1e-4]);
    assert_eq!(e[1].1, vec![2e-3]);
    let missing = vec![("gear_harmonic:j1.sin".to_string(), 1e-4)];
    let err = effects_from_parameters(&missing, &ctx)
        .unwrap_err()
        .to_string();
    assert!(err.contains("gear_harmonic:j1.cos"), "{err}");
    let unknown = vec![("gear_ratio:j9".to_string(), 1e-4)];
    assert!(effects_from_parameters(&unknown, &ctx).is_err());
}

#[test]
fn predictions_carry_effects_frames_and_first_order_uncertainty() {
    let t = table();
    let ctx = EffectContext::serial(&t);
    let effects = effects_from_parameters(&[("gear_ratio:j2".to_string(), 0.01)], &ctx).unwrap();
    let device = Isometry3::translation(1.0, 2.0, 3.0);
    let target = vec![("t".to_string(), Vector3::new(0.0, 0.05, 0.0))];
    let c = Calibrated::new(&t, &effects, &device, &target).unwrap();
    let q = [0.3, -0.7, 1.1];
    // The gear ratio is theta += 0.01 q.
    let mut geometric = t.clone();
    geometric.rows[1].theta += 0.01 * q[1];
    let fk = geometric.fk(&q).unwrap();
    let want = fk
        .transform_point(&Vector3::new(0.0, 0.05, 0.0).into())
        .coords;
    assert!((c.point(&q, 0, Frame::Base) - want).norm() < 1e-14);
    assert!((c.point(&q, 0, Frame::Device) - (want + Vector3::new(1.0, 2.0, 3.0))).norm() < 1e-14);
    assert!((c.tool(&q, Frame::Base).translation.vector - fk.translation.vector).norm() < 1e-14);
    assert!(c.point_uncertainty(&q, 0, Frame::Base).is_none());

    // A variance on j3.a alone: the point moves by exactly da along j3's x axis.
    let s = 1e-4;
    let cov = Covariance::new(vec!["j3.a".into()], DMatrix::from_element(1, 1, s * s)).unwrap();
    let c = c.with_covariance(&cov).unwrap();
    let u = c.point_uncertainty(&q, 0, Frame::Base).unwrap();
    let x3 = (fk * t.tool.inverse()).rotation * Vector3::x();
    let want = x3.map(|v| v.abs() * s);
    assert!((u - want).norm() < 1e-12, "{u} vs {want}");
    // Orientation does not depend on a.
    let ut = c.tool_uncertainty(&q, Frame::Base).unwrap();
    assert!(ut.fixed_rows::<3>(3).norm() < 1e-12);
    // The device frame is a rigid motion of the base frame here: the same norm.
    let ud = c.point_uncertainty(&q, 0, Frame::Device).unwrap();
    assert!((ud.norm() - u.norm()).abs() < 1e-12);

    let bad = Covariance::new(vec!["j9.a".into()], DMatrix::from_element(1, 1, 1.0)).unwrap();
    let err = c.clone().with_covariance(&bad).unwrap_err().to_string();
    assert!(err.contains("j9.a"), "{err}");
}

/// `sqrt(diag(G C Gᵀ))` with `G` by central differences of `f` (steps of 1e-7 in every
/// parameter): what the analytic derivative must match.
fn numeric(c: &Calibrated, cov: &DMatrix<f64>, f: impl Fn(&[f64]) -> Vec<f64>) -> Vec<f64> {
    let x0 = c.parameters().to_vec();
    let n = x0.len();
    let rows = f(&x0).len();
    let mut g = DMatrix::zeros(rows, n);
    for j in 0..n {
        let (mut a, mut b) = (x0.clone(), x0.clone());
        a[j] += 1e-7;
        b[j] -= 1e-7;
        let (fa, fb) = (f(&a), f(&b));
        for r in 0..rows {
            g[(r, j)] = (fa[r] - fb[r]) / 2e-7;
        }
    }
    let gc = &g * cov;
    (0..rows).map(|r| gc.row(r).dot(&g.row(r)).sqrt()).collect()
}

#[test]
fn analytic_uncertainty_matches_central_differences_in_both_frames() {
    let t = table();
    let ctx = EffectContext::serial(&t);
    let effects = effects_from_parameters(
        &[
            ("gear_ratio:j2".to_string(), 0.01),
            ("scale".to_string(), 2e-4),
        ],
        &ctx,
    )
    .unwrap();
    let device = Isometry3::new(Vector3::new(1.0, 2.0, 3.0), Vector3::new(0.3, -0.2, 0.9));
    let targets = vec![
        ("t".to_string(), Vector3::new(0.0, 0.05, 0.02)),
        ("probe".to_string(), Vector3::new(0.03, 0.0, 0.04)),
    ];
    let rotation = UnitQuaternion::from_euler_angles(0.2, 0.4, -0.1);
    let c = Calibrated::new(&t, &effects, &device, &targets)
        .unwrap()
        .with_target_rotations(&[None, Some(rotation)]);
    // Every parameter of the model, correlated.
    let names: Vec<String> = c
        .model()
        .parameters()
        .iter()
        .map(|p| p.name.clone())
        .collect();
    let n = names.len();
    let a = DMatrix::from_fn(n, n, |i, j| ((i * 7 + j * 3) as f64).sin() * 1e-4);
    let cov = &a * a.transpose() + DMatrix::identity(n, n) * 1e-9;
    let c = c
        .with_covariance(&Covariance::new(names, cov.clone()).unwrap())
        .unwrap();
    let q = [0.3, -0.7, 1.1];
    for frame in [Frame::Device, Frame::Base] {
        let close = |got: &[f64], want: &[f64]| {
            for (g, w) in got.iter().zip(want) {
                assert!(
                    (g - w).abs() <= 1e-6 * w.abs() + 1e-12,
                    "{frame:?}: {got:?} vs {want:?}"
                );
            }
        };
        for k in 0..2 {
            let got = c.point_uncertainty(&q, k, frame).unwrap();
            let want = numeric(&c, &cov, |x| {
                c.point_at(x, &q, k, frame).as_slice().to_vec()
            });
            close(got.as_slice(), &want);
        }
        let at = c.target_orientation(&q, 1, frame).unwrap();
        let got = c.target_orientation_uncertainty(&q, 1, frame).unwrap();
        let want = numeric(&c, &cov, |x| {
            let r = (c.orientation_at(x, &q, 1, frame) * at.inverse()).scaled_axis();
            r.as_slice().to_vec()
        });
        close(got.as_slice(), &want);
        assert!(c.target_orientation_uncertainty(&q, 0, frame).is_none());
        let at = c.tool(&q, frame);
        let got = c.tool_uncertainty(&q, frame).unwrap();
        let want = numeric(&c, &cov, |x| {
            let p = c.tool_at(x, &q, 0, frame);
            let r = (p.rotation * at.rotation.inverse()).scaled_axis();
            let v = p.translation.vector;
            vec![v.x, v.y, v.z, r.x, r.y, r.z]
        });
        close(got.as_slice(), &want);
    }
}

#[test]
fn bad_covariances_are_refused() {
    let names = vec!["a".to_string(), "b".to_string()];
    let ok = DMatrix::from_row_slice(2, 2, &[1.0, 0.5, 0.5, 1.0]);
    assert!(Covariance::new(names.clone(), ok).is_ok());
    let asym = DMatrix::from_row_slice(2, 2, &[1.0, 0.5, 0.4, 1.0]);
    assert!(Covariance::new(names.clone(), asym).is_err());
    let neg = DMatrix::from_row_slice(2, 2, &[-1.0, 0.0, 0.0, 1.0]);
    assert!(Covariance::new(names.clone(), neg).is_err());
    assert!(Covariance::new(names, DMatrix::zeros(1, 1)).is_err());
    let twice = vec!["a".to_string(), "a".to_string()];
    assert!(Covariance::new(twice, DMatrix::identity(2, 2)).is_err());
}
