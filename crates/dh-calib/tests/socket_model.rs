//! Ball-in-socket contacts (`dh_calib::socket`): the analytic Jacobian against central
//! differences, and a simulated Panda touching two sockets 50 mm apart in three placements with
//! planted geometric errors, recovered within three standard errors.

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4};

use dh_calib::calibrate::CalibrationOptions;
use dh_calib::data::{Measurements, Sample, Socket, SocketDistance, Split};
use dh_calib::fit::Problem;
use dh_calib::model::{Model, ModelOptions};
use dh_calib::socket::{
    calibrate_sockets, numeric_jacobian, Contact, SocketConstraint, SocketProblem,
};
use dh_calib::tree::DhTree;
use dh_core::pose::from_xyz_rpy;
use dh_core::{Convention, DhRow, DhTable};
use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

/// Franka's modified DH with the tool to the ball centre (as `fixtures/measured/mukca_panda`).
fn panda() -> DhTable {
    let r = |i: usize, a: f64, alpha: f64, d: f64| {
        DhRow::revolute(&format!("joint_{i}"), a, alpha, d, 0.0)
    };
    DhTable {
        convention: Convention::Modified,
        base: nalgebra::Isometry3::identity(),
        tool: from_xyz_rpy([2.5e-5, -8.5e-5, 0.2405], [0.0, 0.0, -FRAC_PI_4]),
        rows: vec![
            r(1, 0.0, 0.0, 0.333),
            r(2, 0.0, -FRAC_PI_2, 0.0),
            r(3, 0.0, FRAC_PI_2, 0.316),
            r(4, 0.0825, FRAC_PI_2, 0.0),
            r(5, -0.0825, -FRAC_PI_2, 0.384),
            r(6, 0.0, FRAC_PI_2, 0.0),
            r(7, 0.088, FRAC_PI_2, 0.0),
        ],
    }
}

#[test]
fn analytic_jacobian_matches_central_differences() {
    let table = panda();
    let model = Model::new(&table, &["ball".into()], &ModelOptions::default()).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let contacts: Vec<Contact> = (0..6)
        .map(|i| Contact {
            q: (0..7).map(|_| rng.random_range(-1.5..1.5)).collect(),
            target: 0,
            socket: i % 2,
        })
        .collect();
    let constraints = [SocketConstraint {
        a: 0,
        b: 1,
        distance: 0.05,
        sigma: 1e-4,
    }];
    let p = SocketProblem {
        model: &model,
        contacts: &contacts,
        constraints: &constraints,
        sockets: 2,
        sigma_point: 2e-4,
    };
    let n = p.parameter_count();
    let mut x: Vec<f64> = (0..n).map(|_| rng.random_range(-1e-3..1e-3)).collect();
    let o = p.socket_offset();
    x[o..o + 3].copy_from_slice(&[0.4, 0.0, 0.1]);
    x[o + 3..o + 6].copy_from_slice(&[0.4, 0.06, 0.1]);
    let numeric = numeric_jacobian(&p, &x, 1e-6);
    let columns: Vec<usize> = (0..n).collect();
    let mut row = 0;
    let mut worst: f64 = 0.0;
    for b in 0..p.block_count() {
        let m = p.block_size(b);
        let mut r = vec![0.0; m];
        let mut j = vec![0.0; m * n];
        p.jacobian(&x, b, &columns, &mut r, &mut j);
        let mut direct = vec![0.0; m];
        p.residuals(&x, b, &mut direct);
        assert_eq!(
            r, direct,
            "block {b}: residuals of jacobian() and residuals() differ"
        );
        for i in 0..m {
            for c in 0..n {
                worst = worst.max((j[i * n + c] - numeric[(row + i, c)]).abs());
            }
        }
        row += m;
    }
    // Central differences at h = 1e-6 are good to about h² times the third derivative (metres
    // per radian, the robot's size) plus rounding 1e-16 / h.
    assert!(worst < 1e-7, "largest difference {worst:e}");
}

/// Joint values that put the target at `goal` under the model at `x` (damped Gauss-Newton from
/// a random start, numeric joint Jacobian); `None` when it does not converge.
fn touch(model: &Model, x: &[f64], goal: Vector3<f64>, rng: &mut ChaCha8Rng) -> Option<Vec<f64>> {
    let mut q: Vec<f64> = [0.0, 0.3, 0.0, -2.0, 0.0, 2.2, 0.8]
        .iter()
        .map(|v| v + rng.random_range(-0.7..0.7))
        .collect();
    for _ in 0..100 {
        let e = model.point(x, &q, 0) - goal;
        if e.norm() < 1e-12 {
            return Some(q);
        }
        let mut j = nalgebra::DMatrix::zeros(3, 7);
        for k in 0..7 {
            let mut qp = q.clone();
            qp[k] += 1e-7;
            let d = (model.point(x, &qp, 0) - model.point(x, &q, 0)) / 1e-7;
            j.set_column(k, &d);
        }
        let jjt = &j * j.transpose() + nalgebra::DMatrix::identity(3, 3) * 1e-6;
        let step = j.transpose()
            * jjt
                .lu()
                .solve(&nalgebra::DVector::from_column_slice(e.as_slice()))?;
        for k in 0..7 {
            q[k] -= step[k];
        }
    }
    None
}

#[test]
fn simulated_panda_contacts_recover_planted_errors_within_three_standard_errors() {
    let table = panda();
    let truth_model = Model::new(&table, &["ball".into()], &ModelOptions::default()).unwrap();
    let mut x = vec![0.0; truth_model.parameter_count()];
    // Planted errors: half a millimetre, half a milliradian, on identifiable parameters.
    let planted = [
        ("joint_2.alpha", 5e-4),
        ("joint_3.d", -4e-4),
        ("joint_4.a", 5e-4),
        ("joint_5.theta", -6e-4),
        ("joint_6.alpha", 4e-4),
        ("joint_3.theta", 3e-4),
        ("target.ball.x", 3e-4),
    ];
    for (name, v) in planted {
        x[truth_model.index_of(name).unwrap()] = v;
    }
    let sigma = 5e-5;
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut samples = Vec::new();
    let placements = [
        Vector3::new(0.45, -0.15, 0.05),
        Vector3::new(0.5, 0.1, 0.15),
        Vector3::new(0.35, 0.3, 0.0),
    ];
    let offsets = [Vector3::new(0.0, 0.05, 0.0), Vector3::new(0.03, 0.0, 0.04)];
    for (p, centre) in placements.iter().enumerate() {
        let pair = [*centre, centre + offsets[p % 2]];
        for (hole, goal) in pair.iter().enumerate() {
            let mut n = 0;
            while n < 30 {
                let noise = Vector3::from_fn(|_, _| rng.sample::<f64, _>(StandardNormal) * sigma);
                let Some(q) = touch(&truth_model, &x, goal + noise, &mut rng) else {
                    continue;
                };
                samples.push(Sample {
                    time: None,
                    orientation: None,
                    session: 0,
                    q: q.into(),
                    target: 0,
                    point: Vector3::zeros(),
                    sigma: None,
                    config: None,
                    split: if p < 2 {
                        Split::Calibration
                    } else {
                        Split::Validation
                    },
                    line: 0,
                    socket: Some(Box::new(Socket {
                        name: format!("p{p}/{hole}"),
                        partner: Some(SocketDistance {
                            socket: format!("p{p}/{}", 1 - hole),
                            distance: 0.05,
                            sigma: 1e-4,
                        }),
                    })),
                });
                n += 1;
            }
        }
    }
    let data = Measurements {
        sessions: Vec::new(),
        joint_names: table.rows.iter().map(|r| r.name.clone()).collect(),
        targets: vec!["ball".into()],
        samples,
    };
    let r = calibrate_sockets(
        &DhTree::serial(&table),
        &data,
        &CalibrationOptions {
            sigma: Some(sigma),
            ..CalibrationOptions::default()
        },
    )
    .unwrap();
    assert!(r.notes[0].contains("gauge freedom"), "{:?}", r.notes);
    assert!(r.fixed.iter().any(|f| f.name == "device.x"));
    let mut checked = 0;
    for p in r
        .parameters
        .iter()
        .filter(|p| p.free && p.name.starts_with("joint_"))
    {
        let truth = planted
            .iter()
            .find(|(n, _)| *n == p.name)
            .map_or(0.0, |v| v.1);
        let se = p.std_error.unwrap();
        let err = p.estimate - p.nominal - truth;
        assert!(
            err.abs() <= 3.0 * se + 1e-9,
            "{}: error {err:e}, se {se:e}",
            p.name
        );
        checked += 1;
    }
    assert!(checked >= 20, "only {checked} joint parameters free");
    for (name, v) in &planted {
        let p = r.parameters.iter().find(|p| p.name == *name).unwrap();
        assert!(p.free, "{name} was fixed");
        // A target's reported nominal is the `nominal` step's estimate; its reference is 0.
        let reference = if name.starts_with("target.") {
            0.0
        } else {
            p.nominal
        };
        let err = p.estimate - reference - v;
        assert!(
            err.abs() <= 3.0 * p.std_error.unwrap() + 1e-9,
            "{name}: error {err:e}"
        );
    }
    // Consistency: from several times the contact noise down to it, on held-out placement p2 too.
    let (given, last) = (&r.consistency[0], &r.consistency[r.consistency.len() - 1]);
    assert!(given.train.mean_abs > 4.0 * sigma, "{given:?}");
    // Mean distance of a 3-D Gaussian point from its mean: sigma·sqrt(8/π) ≈ 1.6 sigma.
    assert!(last.train.mean_abs < 2.0 * sigma, "{last:?}");
    assert!(last.test.unwrap().mean_abs < 2.5 * sigma, "{last:?}");
}
