//! 6-DoF poses of a target frame ([`Observation::TargetPose`]): planted errors of a UR5 are
//! recovered from simulated poses with position and orientation noise, the fit reaches the
//! noise floor in both, and orientation data shrinks the standard errors against the same
//! poses measured as points.

mod fit_support;

use dh_calib::fit::{self, FitOptions, FitOutcome};
use dh_calib::model::{Block, Model, ModelOptions, ModelProblem, Observation, Observed};
use nalgebra::{DMatrix, Isometry3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_distr::StandardNormal;

/// Position noise per axis (metres) and orientation noise per axis (radians).
const SIGMA_P: f64 = 20e-6;
const SIGMA_R: f64 = 50e-6;

fn model() -> Model {
    let mut m = Model::new(
        &fit_support::ur5(),
        &["probe".to_string()],
        &ModelOptions::default(),
    )
    .unwrap();
    m.set_device(&Isometry3::from_parts(
        Translation3::new(2.0, -0.5, 0.3),
        UnitQuaternion::from_euler_angles(0.02, -0.01, 2.5),
    ));
    m.set_target(0, Vector3::new(0.03, -0.02, 0.12));
    assert_eq!(
        m.add_target_orientation(0),
        Some(m.parameter_count() - 3..m.parameter_count())
    );
    m.set_target_rotation(0, &UnitQuaternion::from_euler_angles(0.3, 0.0, -0.7));
    m
}

fn dense_jacobian(model: &Model, obs: &[Observed], x: &[f64]) -> DMatrix<f64> {
    let n = model.parameter_count();
    let columns: Vec<usize> = (0..n).collect();
    let rows: usize = obs.iter().map(|o| o.observation.residual_count()).sum();
    let mut j = DMatrix::zeros(rows, n);
    let mut row = 0;
    for o in obs {
        let m = o.observation.residual_count();
        let mut r = vec![0.0; m];
        let mut block = vec![0.0; m * n];
        model.jacobian(x, o, &columns, &mut r, &mut block);
        for i in 0..m {
            for c in 0..n {
                j[(row + i, c)] = block[i * n + c];
            }
        }
        row += m;
    }
    j
}

/// Identifiability at `x0`, then the fit of the free parameters from `x0`.
fn fit(model: &Model, obs: &[Observed], x0: &[f64]) -> FitOutcome {
    let scales = model.scales();
    let options = FitOptions::default();
    let ident = fit::identifiability(
        &dense_jacobian(model, obs, x0),
        &scales,
        &model.priorities(),
        options.rank_tolerance,
    )
    .unwrap();
    let problem = ModelProblem {
        model,
        observations: obs,
    };
    fit::solve(&problem, x0, &ident.free, &scales, &options).unwrap()
}

struct Set {
    truth: Vec<f64>,
    poses: Vec<Observed>,
    points: Vec<Observed>,
}

/// 80 random poses of the true robot (planted errors in the parameters free for pose data),
/// measured as target frames with noise and, the same ones, as points.
fn simulate(model: &Model) -> Set {
    let mut rng = rand::rngs::StdRng::seed_from_u64(61);
    let n = model.parameter_count();
    let qs: Vec<Vec<f64>> = (0..80)
        .map(|_| (0..6).map(|_| rng.random_range(-2.5..2.5)).collect())
        .collect();
    // Which parameters pose data determines (at the nominal model): plant errors there only,
    // so that every recovered value is comparable with its planted one.
    let nominal: Vec<Observed> = qs
        .iter()
        .map(|q| {
            Observed::new(
                q.clone(),
                Observation::TargetPose {
                    target: 0,
                    pose: Box::new(model.target_pose_in(
                        &vec![0.0; n],
                        q,
                        &Default::default(),
                        0,
                        0,
                    )),
                    weight: SIGMA_P / SIGMA_R,
                },
            )
        })
        .collect();
    let free = fit(model, &nominal, &vec![0.0; n]).free;
    let mut truth = vec![0.0; n];
    for &c in &free {
        let p = &model.parameters()[c];
        let big = matches!(p.block, Block::Device | Block::Target(_));
        truth[c] = match (p.unit, big) {
            (dh_calib::model::Unit::Length, true) => 2e-3,
            (dh_calib::model::Unit::Length, false) => 0.5e-3,
            (_, true) => 0.2_f64.to_radians(),
            (_, false) => 0.02_f64.to_radians(),
        } * if rng.random_bool(0.5) { 1.0 } else { -1.0 };
    }
    let mut poses = Vec::new();
    let mut points = Vec::new();
    for q in &qs {
        let exact = model.target_pose_in(&truth, q, &Default::default(), 0, 0);
        let dp = Vector3::from_fn(|_, _| rng.sample::<f64, _>(StandardNormal) * SIGMA_P);
        let dr = Vector3::from_fn(|_, _| rng.sample::<f64, _>(StandardNormal) * SIGMA_R);
        let measured = Isometry3::from_parts(
            Translation3::from(exact.translation.vector + dp),
            UnitQuaternion::from_scaled_axis(dr) * exact.rotation,
        );
        poses.push(Observed::new(
            q.clone(),
            Observation::TargetPose {
                target: 0,
                pose: Box::new(measured),
                weight: SIGMA_P / SIGMA_R,
            },
        ));
        points.push(Observed::new(
            q.clone(),
            Observation::Point {
                target: 0,
                point: measured.translation.vector,
            },
        ));
    }
    Set {
        truth,
        poses,
        points,
    }
}

/// RMS of the position residuals (metres, per axis) and of the angle residuals (radians, per
/// axis, the weight undone).
fn rms(model: &Model, x: &[f64], obs: &[Observed]) -> (f64, f64) {
    let (mut sp, mut sr, mut n) = (0.0, 0.0, 0.0);
    for o in obs {
        let mut r = [0.0; 6];
        model.residuals(x, o, &mut r);
        let w = match o.observation {
            Observation::TargetPose { weight, .. } => weight,
            _ => 1.0,
        };
        sp += r[..3].iter().map(|v| v * v).sum::<f64>();
        sr += r[3..].iter().map(|v| (v / w) * (v / w)).sum::<f64>();
        n += 3.0;
    }
    ((sp / n).sqrt(), (sr / n).sqrt())
}

#[test]
fn target_pose_jacobian_matches_central_differences() {
    let m = model();
    let set = simulate(&m);
    let problem = ModelProblem {
        model: &m,
        observations: &set.poses,
    };
    let n = m.parameter_count();
    let columns: Vec<usize> = (0..n).collect();
    let steps = vec![1e-7; n];
    for block in [0, 17, 42] {
        let numeric = fit::numeric_jacobian(&problem, &set.truth, block, &columns, &steps);
        let mut r = [0.0; 6];
        let mut j = vec![0.0; 6 * n];
        m.jacobian(&set.truth, &set.poses[block], &columns, &mut r, &mut j);
        let analytic = DMatrix::from_row_slice(6, n, &j);
        let err = (&analytic - &numeric).abs().max();
        assert!(err < 1e-7, "block {block}: {err}\n{analytic}\n{numeric}");
    }
}

#[test]
fn planted_errors_are_recovered_from_six_dof_poses_at_the_noise_floor() {
    let m = model();
    let set = simulate(&m);
    let n = m.parameter_count();
    let out = fit(&m, &set.poses, &vec![0.0; n]);
    // The target's orientation is identifiable with orientation data.
    for name in ["target.probe.rx", "target.probe.ry", "target.probe.rz"] {
        assert!(
            out.free.contains(&m.index_of(name).unwrap()),
            "{name} not free"
        );
    }
    for &c in &out.free {
        let se = out.std_errors[c].unwrap();
        let z = (out.x[c] - set.truth[c]) / se;
        assert!(
            z.abs() < 3.0,
            "{}: planted {:e}, recovered {:e}, standard error {:e}",
            m.parameters()[c].name,
            set.truth[c],
            out.x[c],
            se
        );
    }
    let (rp, rr) = rms(&m, &out.x, &set.poses);
    // The residual is the noise less what the free parameters absorb: sqrt(1 − p/m) of it.
    let floor = (1.0 - out.free.len() as f64 / out.residual_count as f64).sqrt();
    for (rms, sigma) in [(rp, SIGMA_P), (rr, SIGMA_R)] {
        let ratio = rms / (sigma * floor);
        assert!(
            (0.85..1.15).contains(&ratio),
            "RMS {rms:e} against noise {sigma:e}"
        );
    }
}

#[test]
fn orientation_data_shrinks_the_standard_errors_of_the_same_poses() {
    let m = model();
    let set = simulate(&m);
    let n = m.parameter_count();
    let poses = fit(&m, &set.poses, &vec![0.0; n]);
    let points = fit(&m, &set.points, &vec![0.0; n]);
    assert!(
        points.free.len() < poses.free.len(),
        "points free {}, poses free {}",
        points.free.len(),
        poses.free.len()
    );
    for name in ["target.probe.rx", "target.probe.ry", "target.probe.rz"] {
        assert!(!points.free.contains(&m.index_of(name).unwrap()));
    }
    // Standard errors at one noise level (the known σ_p instead of each fit's own estimate
    // σ̂, which differs by chance): what the data's geometry gives.
    let at_sigma =
        |out: &FitOutcome, c: usize| out.std_errors[c].unwrap() / out.sigma.unwrap() * SIGMA_P;
    let extra: Vec<&str> = poses
        .free
        .iter()
        .filter(|c| !points.free.contains(c))
        .map(|&c| m.parameters()[c].name.as_str())
        .collect();
    assert_eq!(
        extra,
        ["target.probe.rx", "target.probe.ry", "target.probe.rz"]
    );
    for &c in &points.free {
        let (sp, so) = (at_sigma(&points, c), at_sigma(&poses, c));
        assert!(
            so < sp,
            "{}: poses {so:e}, points {sp:e}",
            m.parameters()[c].name
        );
    }
}
