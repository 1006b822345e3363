//! Simulated measurements with one planted effect, shared by the `diagnose_*` tests.
#![allow(dead_code)]

use std::sync::Arc;

use dh_calib::calibrate::{CalibrationOptions, Report};
use dh_calib::data::{Measurements, Sample, Split};
use dh_calib::diagnose::{diagnose, DiagnoseOptions};
use dh_calib::effects::{parse_label_in, EffectContext};
use dh_calib::effects_order::sequence_contexts;
use dh_calib::gravity::{GravityModel, Inertial, Inertials};
use dh_calib::model::{Block, Effect, Model, ModelOptions, SampleContext};
use dh_calib::tree::DhTree;
use dh_core::{DhTable, JointSampler};
use nalgebra::{Isometry3, Point3, Quaternion, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

#[path = "../fit_support/mod.rs"]
mod fit_support;

pub use fit_support::{kr_like, ur5};

/// Seeds per case: `DIAGNOSE_SEEDS` (default 3; each case uses its own seeds).
pub fn seeds() -> u64 {
    std::env::var("DIAGNOSE_SEEDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(3)
}

/// Link masses for a test arm: each body's centre half-way between its frame and the previous
/// one at `q = 0` (a uniform link), `masses` per row, and a payload at the tool.
pub fn inertials(table: &DhTable, masses: &[f64], payload: f64) -> Inertials {
    let links = table
        .rows
        .iter()
        .zip(masses)
        .map(|(r, &m)| {
            let a = r.transform(table.convention, 0.0);
            let prev = a.inverse() * Point3::origin();
            (
                r.name.clone(),
                Inertial {
                    mass: m,
                    com: prev.coords * 0.5,
                },
            )
        })
        .collect();
    Inertials {
        links,
        payloads: vec![(
            0,
            Inertial {
                mass: payload,
                com: Vector3::new(0.0, 0.0, 0.05),
            },
        )],
    }
}

/// A robot for the tests: its table, inertials and noise.
pub struct Arm {
    pub name: &'static str,
    pub table: DhTable,
    pub inertials: Inertials,
    /// Per-axis noise (metres).
    pub sigma: f64,
}

pub fn industrial() -> Arm {
    let table = kr_like();
    let inertials = inertials(&table, &[300.0, 150.0, 120.0, 40.0, 20.0, 5.0], 60.0);
    Arm {
        name: "kr_like",
        table,
        inertials,
        sigma: 50e-6,
    }
}

pub fn ur_sized() -> Arm {
    let table = ur5();
    let inertials = inertials(&table, &[3.7, 8.4, 2.3, 1.2, 1.2, 0.2], 2.0);
    Arm {
        name: "ur5",
        table,
        inertials,
        sigma: 20e-6,
    }
}

impl Arm {
    pub fn context(&self) -> EffectContext {
        let g = GravityModel::serial(
            &self.table,
            &self.inertials,
            GravityModel::default_gravity(),
        )
        .unwrap();
        EffectContext {
            tree: DhTree::serial(&self.table),
            gravity: Some(Arc::new(g)),
            gravity_vector: GravityModel::default_gravity(),
        }
    }
}

/// What was simulated.
pub struct Simulated {
    pub data: Measurements,
    pub effect: Option<Arc<dyn Effect>>,
    /// Effect parameters planted.
    pub values: Vec<f64>,
    /// RMS 3-D displacement of the calibration points due to the effect, over the noise's RMS
    /// 3-D size (`sigma · sqrt 3`).
    pub ratio: f64,
    /// The noise floor of this realisation on the calibration and validation samples: the RMS
    /// that the fit of the true model structure leaves, to first order (see [`floor`]).
    pub floor: (f64, f64),
}

fn random_pose(rng: &mut ChaCha8Rng, distance: f64) -> Isometry3<f64> {
    let mut g = || rng.sample::<f64, _>(StandardNormal);
    let rot = UnitQuaternion::from_quaternion(Quaternion::new(g(), g(), g(), g()));
    let dir = Vector3::new(g(), g(), g()).normalize();
    Isometry3::from_parts(Translation3::from(dir * distance), rot)
}

/// 150 calibration and 100 validation poses of `arm` with random geometric errors (±1 mm,
/// ±1 mrad on every row parameter), a random device frame and one random target, Gaussian
/// noise `arm.sigma` per axis, and the effect `label` (if any) planted at a random size between
/// 15 and 30 times the noise (RMS 3-D displacement of the calibration points).
pub fn simulate(arm: &Arm, label: Option<&str>, seed: u64) -> Simulated {
    simulate_sized(arm, label, None, seed)
}

/// As [`simulate`], the effect's parameters at `values` (radians, ...) instead of a random
/// size; `ratio` is then the size they give.
pub fn simulate_values(arm: &Arm, label: &str, values: &[f64], seed: u64) -> Simulated {
    simulate_sized(arm, Some(label), Some(values), seed)
}

fn simulate_sized(arm: &Arm, label: Option<&str>, given: Option<&[f64]>, seed: u64) -> Simulated {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let ctx = arm.context();
    let table = &arm.table;
    let mut m = Model::new(table, &["t1".to_string()], &ModelOptions::default()).unwrap();
    m.set_device(&random_pose(&mut rng, 2.0 * table.size()));
    let t = Vector3::from_fn(|_, _| rng.random_range(-0.1..0.1));
    m.set_target(0, t);
    let effect = label.map(|l| parse_label_in(l, &ctx).unwrap());
    let range = effect.as_ref().map(|e| m.add_effect(e.clone()).unwrap());
    let mut x = vec![0.0; m.parameter_count()];
    for (c, p) in m.parameters().iter().enumerate() {
        if matches!(p.block, Block::Joint(_)) {
            // 1 mm on lengths, 1 mrad on angles.
            x[c] = rng.random_range(-1.0..1.0) * 1e-3;
        }
    }
    let mut sampler = JointSampler::new(&table.rows, table.size(), rng.random());
    let poses: Vec<Vec<f64>> = (0..250)
        .map(|_| {
            let mut q = Vec::new();
            sampler.next_into(&mut q);
            q
        })
        .collect();
    // Each pose's place in the sequence (one sample per pose, in this order).
    let contexts = sequence_contexts(poses.iter().map(|q| (q.as_slice(), None)));
    let mut values = vec![];
    let mut ratio = 0.0;
    if let Some(r) = range.clone() {
        // A random direction in the effect's parameter space, sized to 15-30 × the noise.
        let dir: Vec<f64> = r
            .clone()
            .map(|_| rng.sample::<f64, _>(StandardNormal))
            .collect();
        let unit = |x: &mut Vec<f64>, s: f64| {
            for (c, d) in r.clone().zip(&dir) {
                x[c] = s * d;
            }
        };
        let mut x1 = x.clone();
        unit(&mut x1, 1e-6);
        let disp: f64 = poses[..150]
            .iter()
            .zip(&contexts)
            .map(|(q, c)| (m.point_in(&x1, q, c, 0) - m.point_in(&x, q, c, 0)).norm_squared())
            .sum::<f64>()
            / 150.0;
        let per_unit = disp.sqrt() / 1e-6;
        let want = rng.random_range(15.0..30.0);
        let s = want * arm.sigma * 3f64.sqrt() / per_unit;
        unit(&mut x, s);
        values = dir.iter().map(|d| d * s).collect();
        ratio = want;
        if let Some(v) = given {
            for (c, val) in r.clone().zip(v) {
                x[c] = *val;
                x1[c] = 0.0;
            }
            let disp: f64 = poses[..150]
                .iter()
                .zip(&contexts)
                .map(|(q, c)| (m.point_in(&x, q, c, 0) - m.point_in(&x1, q, c, 0)).norm_squared())
                .sum::<f64>()
                / 150.0;
            values = v.to_vec();
            ratio = disp.sqrt() / (arm.sigma * 3f64.sqrt());
        }
    }
    let mut samples = Vec::with_capacity(250);
    let mut noises = Vec::with_capacity(250);
    for (i, (q, c)) in poses.iter().zip(&contexts).enumerate() {
        let noise = Vector3::from_fn(|_, _| rng.sample::<f64, _>(StandardNormal) * arm.sigma);
        noises.push(noise);
        samples.push(Sample {
            time: None,
            orientation: None,
            session: 0,
            q: q.as_slice().into(),
            target: 0,
            point: m.point_in(&x, q, c, 0) + noise,
            sigma: Some(Vector3::repeat(arm.sigma)),
            config: Some(format!("p{i}").into()),
            split: if i < 150 {
                Split::Calibration
            } else {
                Split::Validation
            },
            line: 0,
            socket: None,
        });
    }
    let floor = floor(&m, &x, &poses, &contexts, &noises, 150);
    Simulated {
        floor,
        data: Measurements {
            sessions: Vec::new(),
            joint_names: table.rows.iter().map(|r| r.name.clone()).collect(),
            targets: vec!["t1".into()],
            samples,
        },
        effect,
        values,
        ratio,
    }
}

/// The automatic diagnosis of a simulated set.
pub fn run(arm: &Arm, sim: &Simulated) -> Report {
    let options = CalibrationOptions::default();
    let diag = DiagnoseOptions {
        inertials: Some(arm.inertials.clone()),
        ..DiagnoseOptions::default()
    };
    diagnose(&arm.table, &sim.data, &options, &diag).unwrap()
}

/// Expected RMS 3-D residual of pure noise on validation points after fitting `p` parameters
/// to `n` calibration points: `σ sqrt(3 (1 + p / 3n))`.
pub fn validation_floor(sigma: f64, p: usize, n: usize) -> f64 {
    sigma * (3.0 * (1.0 + p as f64 / (3.0 * n as f64))).sqrt()
}

/// The noise floor of one realisation, to first order: with `J` the Jacobian of every
/// parameter of the true model at the truth (calibration poses), the fit leaves
/// `(I − J J⁺) e` of the calibration noise `e` and predicts the validation points with error
/// `J_v J⁺ e − e_v`. Returns their RMS 3-D lengths.
pub fn floor(
    m: &Model,
    x: &[f64],
    poses: &[Vec<f64>],
    contexts: &[SampleContext],
    noise: &[Vector3<f64>],
    n_cal: usize,
) -> (f64, f64) {
    use dh_calib::model::{Observation, Observed};
    use nalgebra::{DMatrix, DVector};
    let cols: Vec<usize> = (0..m.parameter_count()).collect();
    let scales = m.scales();
    let jac = |qs: &[Vec<f64>], cs: &[SampleContext]| {
        let mut j = DMatrix::zeros(3 * qs.len(), cols.len());
        let mut r = [0.0; 3];
        let mut jb = vec![0.0; 3 * cols.len()];
        for (i, (q, c)) in qs.iter().zip(cs).enumerate() {
            let o = Observed {
                session: 0,
                q: q.as_slice().into(),
                observation: Observation::Point {
                    target: 0,
                    point: m.point_in(x, q, c, 0),
                },
                context: c.clone(),
            };
            m.jacobian(x, &o, &cols, &mut r, &mut jb);
            for a in 0..3 {
                for c in 0..cols.len() {
                    j[(3 * i + a, c)] = jb[a * cols.len() + c] * scales[c];
                }
            }
        }
        j
    };
    let jc = jac(&poses[..n_cal], &contexts[..n_cal]);
    let jv = jac(&poses[n_cal..], &contexts[n_cal..]);
    let ec = DVector::from_iterator(
        3 * n_cal,
        noise[..n_cal].iter().flat_map(|v| v.iter().copied()),
    );
    let n_val = poses.len() - n_cal;
    let ev = DVector::from_iterator(
        3 * n_val,
        noise[n_cal..].iter().flat_map(|v| v.iter().copied()),
    );
    let svd = jc.svd(true, true);
    let smax = svd.singular_values.max();
    let (u, vt) = (svd.u.unwrap(), svd.v_t.unwrap());
    let mut fitted = DVector::zeros(ec.len());
    let mut dx = DVector::zeros(cols.len());
    for k in 0..svd.singular_values.len() {
        let s = svd.singular_values[k];
        if s > 1e-6 * smax {
            let c = u.column(k).dot(&ec);
            fitted += u.column(k) * c;
            dx += vt.row(k).transpose() * (c / s);
        }
    }
    let rc = &ec - fitted;
    let rv = &jv * dx - ev;
    let rms = |v: &DVector<f64>| (v.norm_squared() / (v.len() / 3) as f64).sqrt();
    (rms(&rc), rms(&rv))
}

/// Each step of `r` as `label cal-RMS mm / val-RMS mm`, for the tests' printed figures.
pub fn step_summaries(r: &Report) -> Vec<String> {
    r.steps
        .iter()
        .map(|s| {
            format!(
                "{} {:.4} mm / {:.4} mm",
                s.label,
                s.rms * 1e3,
                s.val_rms.unwrap_or(f64::NAN) * 1e3
            )
        })
        .collect()
}
