//! A measurement simulator: known truth, noisy points, for testing calibration end to end.
//!
//! The true robot is the nominal table's [`Model`] with errors on its parameters (same names
//! and layout as the fit uses, Hayati `beta` included), seen by a device at a random or given
//! frame, measuring targets at random or given positions in the tip frame, with Gaussian noise
//! of a given standard deviation on each device axis. Everything is drawn from one ChaCha8
//! stream seeded by [`SimulationOptions::seed`], so a seed reproduces a data set exactly.
//!
//! Effects of the true robot are either part of the simulated model
//! ([`SimulationOptions::effects`], their values among [`Errors::Explicit`]) or planted
//! afterwards in data simulated without them, with values of their own ([`plant_effects`],
//! what `urdf-dh simulate --effect` uses, whatever the geometric errors): both give the
//! positions and, for a 6-DoF device, the orientations of the robot with the effects.

use dh_core::{DhTable, JointSampler};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

use crate::data::{Measurements, Sample, Split};
use crate::fit::CalibError;
use crate::model::{Block, Field, Model, ModelOptions, Unit};

mod plant;
pub use plant::{plant_effects, PlantedEffect, POSE_INTERVAL};

/// Which parameter errors the true robot has.
#[derive(Clone, Debug, PartialEq, Default)]
pub enum Errors {
    /// The nominal table is the truth.
    #[default]
    None,
    /// Every DH row parameter (`a`, `alpha`, `d`, `theta`, `beta`) off by a uniform draw in
    /// `±length` metres or `±angle` radians; base, tool and effects untouched.
    Random {
        /// Largest length error (metres).
        length: f64,
        /// Largest angle error (radians).
        angle: f64,
    },
    /// Given errors by parameter name (see [`crate::model`]), in metres or radians.
    Explicit(Vec<(String, f64)>),
}

/// How joint values are chosen.
#[derive(Clone, Debug, PartialEq, Default)]
pub enum Mode {
    /// [`SimulationOptions::poses`] random poses, uniform within the joint limits (continuous
    /// joints within ±pi), the first one the zero pose.
    #[default]
    Random,
    /// Circle-point analysis: each joint in turn sweeps `angles` values evenly over `arc`
    /// (radians, metres for prismatic joints) centred on the home pose while the others rest at
    /// home; `config` is `cpa:<joint>:<k>`.
    Cpa {
        /// Values per joint (at least 1).
        angles: usize,
        /// Width of the sweep.
        arc: f64,
        /// Home pose, one value per row; `None` is all zeros.
        home: Option<Vec<f64>>,
    },
}

/// Options of [`simulate`].
#[derive(Clone, Debug, PartialEq)]
pub struct SimulationOptions {
    /// Seed of the ChaCha8 stream.
    pub seed: u64,
    /// Number of poses in [`Mode::Random`].
    pub poses: usize,
    /// How poses are chosen.
    pub mode: Mode,
    /// Noise standard deviation on each device axis (metres).
    pub sigma: f64,
    /// Target positions in the tip frame; `None` draws `target_count` of them uniformly in
    /// `±target_offset` per axis.
    pub targets: Option<Vec<Vector3<f64>>>,
    /// Number of random targets.
    pub target_count: usize,
    /// Half-width of the random target box (metres).
    pub target_offset: f64,
    /// `T_device_base`; `None` draws a random rotation and a position at `device_distance`
    /// from the base origin.
    pub device: Option<Isometry3<f64>>,
    /// Distance of a random device from the base (metres); `None` is twice the table's size.
    pub device_distance: Option<f64>,
    /// Errors of the true robot.
    pub errors: Errors,
    /// Fraction of poses (the last ones) marked [`Split::Validation`].
    pub validation_fraction: f64,
    /// Measurements of each pose (at least 1); repeats share `config`, giving pure error.
    pub repeats: usize,
    /// Parametrisation of the truth (Hayati threshold decides which rows have `beta`).
    pub model: ModelOptions,
    /// Measurement sessions (at least 1): the poses are split into this many consecutive
    /// blocks, session `s1`, `s2`, …; the first is measured from `device`, each later one from
    /// its own frame `device · M` with `M` a random motion of the robot in its base frame (up to
    /// [`SESSION_SHIFT`] metres and [`SESSION_TURN`] radians). With more than one the samples
    /// name their session (see [`crate::sessions`]).
    pub sessions: usize,
    /// Effects of the true robot, by label ([`crate::effects`]; gravity effects need
    /// inertials and are refused): added to the truth model, their values set by
    /// [`Errors::Explicit`] through their parameter names (zero otherwise). Effects of the
    /// sample order see the poses in the order simulated, repeats of one pose sharing its
    /// place ([`crate::effects_order`]); with an effect of time (`thermal_growth`) the samples
    /// carry times, [`POSE_INTERVAL`] apart.
    pub effects: Vec<String>,
    /// With `Some(sigma_rot)` (radians, > 0): a 6-DoF device. Every target is a frame with a
    /// random orientation on the tip, and every sample also measures its orientation in the
    /// device frame, with noise `exp(n) · R`, `n` of standard deviation `sigma_rot` per axis
    /// of the device frame ([`crate::data::Orientation`]). Needs `sigma > 0` (the position
    /// sigma weighs the angle against the position). `None` (default): points, and the same
    /// random draws as without the option.
    pub orientation_sigma: Option<f64>,
}

/// Largest translation between two simulated sessions' device frames (metres).
pub const SESSION_SHIFT: f64 = 0.5;
/// Largest rotation between two simulated sessions' device frames (radians, 30 degrees).
pub const SESSION_TURN: f64 = std::f64::consts::PI / 6.0;

impl Default for SimulationOptions {
    fn default() -> Self {
        Self {
            seed: 1,
            poses: 100,
            mode: Mode::Random,
            sigma: 0.0,
            targets: None,
            target_count: 1,
            target_offset: 0.1,
            device: None,
            device_distance: None,
            errors: Errors::None,
            validation_fraction: 0.0,
            repeats: 1,
            model: ModelOptions::default(),
            sessions: 1,
            effects: Vec::new(),
            orientation_sigma: None,
        }
    }
}

/// What the simulated data was generated from, for the CLI's side file and for tests.
#[derive(Clone, Debug, PartialEq)]
pub struct Truth {
    /// The true table (errors applied, tilts in their rows' `beta`, see [`Model::table_at`]).
    pub table: DhTable,
    /// True `T_device_base`.
    pub device: Isometry3<f64>,
    /// True target positions in the tip frame (metres).
    pub targets: Vec<(String, Vector3<f64>)>,
    /// The non-zero parameter errors, by name, in model order.
    pub errors: Vec<(String, f64)>,
    /// Noise standard deviation per axis (metres).
    pub sigma: f64,
    /// True `T_device_base` of every session (one entry, `device`, without sessions).
    pub sessions: Vec<Isometry3<f64>>,
    /// True rotation of each target's frame in the tip frame (identity for point targets,
    /// see [`SimulationOptions::orientation_sigma`]).
    pub target_rotations: Vec<UnitQuaternion<f64>>,
}

fn bad(what: &str, reason: String) -> CalibError {
    CalibError::BadOption {
        what: what.into(),
        reason,
    }
}

/// Simulates measurements of `nominal` with errors (see the module docs).
///
/// # Errors
/// [`CalibError::BadOption`] for negative or non-finite sizes, no targets, or a home pose of
/// the wrong length; [`CalibError::UnknownParameter`] for an explicit error that names no
/// parameter; any error of [`Model::new`].
pub fn simulate(
    nominal: &DhTable,
    options: &SimulationOptions,
) -> Result<(Measurements, Truth), CalibError> {
    let o = options;
    for (what, v) in [
        ("sigma", o.sigma),
        ("target offset", o.target_offset),
        ("validation fraction", o.validation_fraction),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(bad(
                what,
                format!("expected a finite value >= 0, found {v}"),
            ));
        }
    }
    if o.validation_fraction > 1.0 {
        return Err(bad(
            "validation fraction",
            format!(
                "expected a value in [0, 1], found {}",
                o.validation_fraction
            ),
        ));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(o.seed);
    let n = nominal.rows.len();
    let size = nominal.size();

    let target_pos: Vec<Vector3<f64>> = match &o.targets {
        Some(t) => t.clone(),
        None => (0..o.target_count)
            .map(|_| Vector3::from_fn(|_, _| rng.random_range(-1.0..=1.0) * o.target_offset))
            .collect(),
    };
    if target_pos.is_empty() {
        return Err(bad("targets", "expected at least one target".into()));
    }
    let names: Vec<String> = (1..=target_pos.len()).map(|k| format!("t{k}")).collect();

    let device = match o.device {
        Some(d) => d,
        None => {
            let dist = o.device_distance.unwrap_or(2.0 * size);
            if !(dist.is_finite() && dist >= 0.0) {
                return Err(bad(
                    "device distance",
                    format!("expected a finite value >= 0, found {dist}"),
                ));
            }
            random_pose(&mut rng, dist)
        }
    };

    let mut model = Model::new(nominal, &names, &o.model)?;
    model.set_device(&device);
    for (k, t) in target_pos.iter().enumerate() {
        model.set_target(k, *t);
    }
    for label in &o.effects {
        model.add_effect(crate::effects::parse_label(label, nominal)?)?;
    }
    let sigma_rot = match o.orientation_sigma {
        None => None,
        Some(s) if s.is_finite() && s > 0.0 && o.sigma > 0.0 => Some(s),
        Some(s) => {
            return Err(bad(
                "orientation sigma",
                format!(
                    "expected a finite value > 0 with a position sigma > 0, found {s} (position \
                     sigma {})",
                    o.sigma
                ),
            ))
        }
    };
    // Drawn only for a 6-DoF device: point sets keep their random draws.
    let target_rot: Vec<UnitQuaternion<f64>> = match sigma_rot {
        Some(_) => (0..target_pos.len())
            .map(|k| {
                let r = random_pose(&mut rng, 0.0).rotation;
                model.add_target_orientation(k);
                model.set_target_rotation(k, &r);
                r
            })
            .collect(),
        None => vec![UnitQuaternion::identity(); target_pos.len()],
    };
    let mut x = vec![0.0; model.parameter_count()];
    match &o.errors {
        Errors::None => {}
        Errors::Random { length, angle } => {
            for (c, p) in model.parameters().iter().enumerate() {
                if matches!(p.block, Block::Joint(_)) && !matches!(p.field, Field::Effect(_)) {
                    let m = match p.unit {
                        Unit::Angle => *angle,
                        _ => *length,
                    };
                    x[c] = rng.random_range(-1.0..=1.0) * m;
                }
            }
        }
        Errors::Explicit(list) => {
            for (name, v) in list {
                let c = model
                    .index_of(name)
                    .ok_or_else(|| CalibError::UnknownParameter { name: name.clone() })?;
                x[c] = *v;
            }
        }
    }

    // Joint values and the config of each pose.
    let mut poses: Vec<(Vec<f64>, String)> = Vec::new();
    match &o.mode {
        Mode::Random => {
            let mut sampler = JointSampler::new(&nominal.rows, size, rng.random());
            let mut q = Vec::with_capacity(n);
            for i in 0..o.poses {
                sampler.next_into(&mut q);
                poses.push((q.clone(), format!("p{i}")));
            }
        }
        Mode::Cpa { angles, arc, home } => {
            let home = home.clone().unwrap_or_else(|| vec![0.0; n]);
            if home.len() != n {
                return Err(bad(
                    "home pose",
                    format!("expected {n} joint values, found {}", home.len()),
                ));
            }
            if !arc.is_finite() {
                return Err(bad("arc", format!("expected a finite value, found {arc}")));
            }
            for (j, row) in nominal.rows.iter().enumerate() {
                for k in 0..*angles {
                    let f = if *angles > 1 {
                        k as f64 / (*angles - 1) as f64 - 0.5
                    } else {
                        0.0
                    };
                    let mut q = home.clone();
                    q[j] += arc * f;
                    poses.push((q, format!("cpa:{}:{k}", row.name)));
                }
            }
        }
    }
    let sessions = o.sessions.max(1);
    // Drawn only with sessions: a seed gives the same single-session set as before.
    let frames: Vec<Isometry3<f64>> = std::iter::once(device)
        .chain((1..sessions).map(|_| device * session_motion(&mut rng)))
        .collect();
    let n_val = (o.validation_fraction * poses.len() as f64).round() as usize;
    let first_val = poses.len() - n_val.min(poses.len());
    let mut samples = Vec::with_capacity(poses.len() * target_pos.len() * o.repeats.max(1));
    let pose_count = poses.len().max(1);
    // Each pose's place in the sequence (its repeats and targets are measured there).
    let mut contexts = crate::effects_order::sequence_contexts(
        poses.iter().map(|(q, c)| (q.as_slice(), Some(c.as_str()))),
    );
    // An effect of time sees (and the samples carry) the poses' times, `POSE_INTERVAL` apart.
    let timed = model.effects().iter().any(|(e, _)| e.uses_time());
    if timed {
        for (i, c) in contexts.iter_mut().enumerate() {
            c.time = Some(i as f64 * POSE_INTERVAL);
        }
    }
    for (i, ((q, config), context)) in poses.iter().zip(&contexts).enumerate() {
        let session = i * sessions / pose_count;
        model.set_device(&frames[session]);
        let split = if i >= first_val {
            Split::Validation
        } else {
            Split::Calibration
        };
        for _ in 0..o.repeats.max(1) {
            for k in 0..target_pos.len() {
                let p = model.point_in(&x, q, context, k);
                let noise = Vector3::from_fn(|_, _| rng.sample::<f64, _>(StandardNormal) * o.sigma);
                let orientation = sigma_rot.map(|s| {
                    let r = model.target_pose_in(&x, q, context, k, 0).rotation;
                    let n = Vector3::from_fn(|_, _| rng.sample::<f64, _>(StandardNormal) * s);
                    crate::data::Orientation {
                        rotation: UnitQuaternion::from_scaled_axis(n) * r,
                        sigma: s,
                    }
                });
                samples.push(Sample {
                    time: context.time,
                    orientation: orientation.map(Box::new),
                    session,
                    q: q.as_slice().into(),
                    target: k,
                    point: p + noise,
                    // Noise-free data has no standard deviation to state (a sigma of 0 is
                    // refused by the CSV reader: it would weight the point infinitely).
                    sigma: (o.sigma > 0.0).then(|| Vector3::repeat(o.sigma)),
                    config: Some(config.as_str().into()),
                    split,
                    line: 0,
                    socket: None,
                });
            }
        }
    }
    let table = model.table_at(&x);
    let errors = model
        .parameters()
        .iter()
        .zip(&x)
        .filter(|(_, v)| **v != 0.0)
        .map(|(p, v)| (p.name.clone(), *v))
        .collect();
    let data = Measurements {
        sessions: if sessions > 1 {
            (1..=sessions).map(|s| format!("s{s}")).collect()
        } else {
            Vec::new()
        },
        joint_names: nominal.rows.iter().map(|r| r.name.clone()).collect(),
        targets: names.clone(),
        samples,
    };
    let truth = Truth {
        table,
        device,
        targets: names.into_iter().zip(target_pos).collect(),
        errors,
        sigma: o.sigma,
        sessions: frames,
        target_rotations: target_rot,
    };
    Ok((data, truth))
}

/// A random rigid motion: a translation of uniform direction and length up to
/// [`SESSION_SHIFT`], a rotation about a uniform axis by up to [`SESSION_TURN`].
fn session_motion(rng: &mut ChaCha8Rng) -> Isometry3<f64> {
    let unit = |rng: &mut ChaCha8Rng| {
        let v = Vector3::from_fn(|_, _| rng.sample::<f64, _>(StandardNormal));
        v.try_normalize(1e-12).unwrap_or_else(Vector3::x)
    };
    let shift = unit(rng) * rng.random_range(0.0..=SESSION_SHIFT);
    let axis = unit(rng);
    let turn = rng.random_range(0.0..=SESSION_TURN);
    Isometry3::from_parts(
        Translation3::from(shift),
        UnitQuaternion::from_scaled_axis(axis * turn),
    )
}

/// A uniformly random rotation and a position uniformly on the sphere of radius `distance`.
fn random_pose(rng: &mut ChaCha8Rng, distance: f64) -> Isometry3<f64> {
    let mut g = || rng.sample::<f64, _>(StandardNormal);
    let (w, i, j, k) = (g(), g(), g(), g());
    let rot = UnitQuaternion::from_quaternion(Quaternion::new(w, i, j, k));
    let dir = Vector3::new(g(), g(), g());
    let dir = dir.try_normalize(1e-12).unwrap_or_else(Vector3::x);
    Isometry3::from_parts(Translation3::from(dir * distance), rot)
}
