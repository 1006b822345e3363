//! The geometric calibration pipeline: register, fit the device frame and targets, find what
//! the data can identify, fit the identifiable DH errors, validate each step.
//!
//! # Steps
//! 1. Closed-form start: the device frame by rigid registration (Kabsch, "A solution for the
//!    best rotation to relate two sets of vectors", Acta Cryst. A32, 1976; Horn, "Closed-form
//!    solution of absolute orientation using unit quaternions", JOSA A 4(4), 1987) of the
//!    nominal model's points to the measured ones, alternated with the closed-form target
//!    positions given the frame, so that any device pose converges.
//! 2. `nominal`: only the device frame and the targets are estimated.
//! 3. Identifiability at that estimate over every geometric parameter
//!    ([`crate::fit::identifiability`]): the non-identifiable ones are fixed at nominal and
//!    reported with their aliases.
//! 4. `geometric`: the identifiable DH, base, tool, device and target parameters together.
//! 5. `effects` (only when effects are given): the same with the effect parameters added.
//!
//! Each step reports the RMS, mean and largest Euclidean distance between modelled and measured
//! points on the calibration samples and on validation samples: the validation split when
//! there is one, else k-fold cross-validation over poses (samples sharing `config`, or else the
//! same joint values, stay in one fold).

use std::collections::HashMap;
use std::sync::Arc;

use dh_core::DhTable;
use nalgebra::{DMatrix, Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};

use crate::data::{Measurements, Split};
use crate::fit::{self, CalibError, FitOptions, FitOutcome, Termination};
use crate::model::{
    xyz_rpy, Block, Effect, Model, ModelOptions, ModelProblem, Observation, Observed,
    PairParametrisation, SampleContext, SubsetProblem,
};
use crate::tree::DhTree;

/// Options of [`calibrate`].
#[derive(Clone, Debug)]
pub struct CalibrationOptions {
    /// Parametrisation (Hayati threshold, scales).
    pub model: ModelOptions,
    /// Solver options; `fit.rank_tolerance` also decides identifiability.
    pub fit: FitOptions,
    /// Folds of cross-validation when there is no validation split (at least 2). Default 5.
    pub folds: usize,
    /// A start for `T_device_base` instead of the closed-form registration.
    pub device_guess: Option<Isometry3<f64>>,
    /// Starts for the target positions in the tip frame (one per target).
    pub target_guesses: Option<Vec<Vector3<f64>>>,
    /// Known per-axis measurement noise (metres); overrides the samples' own `sigma`.
    pub sigma: Option<f64>,
    /// Non-geometric effects to estimate in a last step.
    pub effects: Vec<Arc<dyn Effect>>,
    /// For a tree ([`calibrate_tree`]): `(target, branch)` pairs saying which branch a target
    /// rides on. A target without an entry rides on the branch of its own name, or on the only
    /// chain of a serial robot.
    pub target_branches: Vec<(String, String)>,
    /// Outlier screening before the fit ([`crate::outliers`]): on by default, flagged points
    /// left out unless `keep`.
    pub outliers: crate::outliers::OutlierOptions,
}

impl Default for CalibrationOptions {
    fn default() -> Self {
        Self {
            model: ModelOptions::default(),
            fit: FitOptions::default(),
            folds: 5,
            device_guess: None,
            target_guesses: None,
            sigma: None,
            effects: Vec::new(),
            target_branches: Vec::new(),
            outliers: crate::outliers::OutlierOptions::default(),
        }
    }
}

/// Distances between modelled and measured points (metres).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stats {
    /// Root mean square of the 3-D distances.
    pub rms: f64,
    /// Mean distance.
    pub mean: f64,
    /// Largest distance.
    pub max: f64,
    /// Number of points.
    pub count: usize,
}

impl Stats {
    /// Statistics of `distances`; `None` when empty.
    pub fn of(distances: &[f64]) -> Option<Stats> {
        if distances.is_empty() {
            return None;
        }
        let n = distances.len() as f64;
        Some(Stats {
            rms: (distances.iter().map(|d| d * d).sum::<f64>() / n).sqrt(),
            mean: distances.iter().sum::<f64>() / n,
            max: distances.iter().copied().fold(0.0, f64::max),
            count: distances.len(),
        })
    }
}

/// One step of the pipeline.
#[derive(Clone, Debug, PartialEq)]
pub struct StepReport {
    /// `nominal`, `geometric` or `effects`; the effect steps of [`crate::diagnose`] are
    /// `+<label>`.
    pub label: String,
    /// Calibration RMS before the step (the previous step's), metres; `None` for the first.
    pub rms_before: Option<f64>,
    /// Validation RMS before the step (the previous step's), metres.
    pub val_rms_before: Option<f64>,
    /// RMS distance on the calibration samples (metres).
    pub rms: f64,
    /// Mean distance on the calibration samples (metres).
    pub mean: f64,
    /// Largest distance on the calibration samples (metres).
    pub max: f64,
    /// RMS distance on validation (metres); `None` when there is nothing to validate on.
    pub val_rms: Option<f64>,
    /// Mean distance on validation (metres).
    pub val_mean: Option<f64>,
    /// Largest distance on validation (metres).
    pub val_max: Option<f64>,
    /// Number of free parameters.
    pub free: usize,
    /// Solver iterations.
    pub iterations: usize,
    /// Why the solver stopped.
    pub termination: Termination,
    /// Parameters this step would estimate but held at their start because the data cannot
    /// identify them, with the free parameters that absorb them: in `nominal`, device or target
    /// coordinates (targets seen at one tool orientation only alias with the device frame); in
    /// later steps the same list as [`Report::fixed`].
    pub fixed: Vec<FixedParameter>,
}

/// How validation figures were obtained.
#[derive(Clone, Debug, PartialEq)]
pub enum Validation {
    /// On the samples marked [`Split::Validation`].
    Split {
        /// Their number.
        samples: usize,
    },
    /// k-fold cross-validation over pose groups of the calibration samples.
    CrossValidation {
        /// Number of folds.
        folds: usize,
        /// Number of pose groups.
        groups: usize,
        /// Beyond [`CV_TRAINING_MAX`] calibration samples, each fold is fitted on an evenly
        /// spaced subsample of this many of its training samples (every held-out sample is
        /// still predicted): the held-out figure is then that of a model fitted on fewer
        /// samples, so it errs on the high side. `None`: every training sample.
        training_subsample: Option<usize>,
    },
    /// Too few pose groups for either.
    None,
}

/// Where the noise floor comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum NoiseSource {
    /// The `sigma` option.
    Given,
    /// Every sample's own `sigma`.
    Samples,
    /// Pure error of repeated measurements (samples sharing `config` and target).
    Repeats {
        /// Groups with at least two samples.
        groups: usize,
        /// Degrees of freedom of the pooled estimate.
        dof: usize,
    },
}

/// The RMS 3-D residual that noise alone would leave after the fit.
#[derive(Clone, Debug, PartialEq)]
pub struct NoiseFloor {
    /// `sqrt(E‖e‖² · (1 − p / (3N)))` with `E‖e‖²` the expected squared 3-D noise of one point
    /// (`3σ²` for isotropic σ), `p` free parameters and `N` calibration points (metres).
    pub rms: f64,
    /// Per-axis noise standard deviation it corresponds to, `sqrt(E‖e‖² / 3)` (metres).
    pub sigma: f64,
    /// Where it comes from.
    pub source: NoiseSource,
}

/// One parameter's estimate.
#[derive(Clone, Debug, PartialEq)]
pub struct ParameterEstimate {
    /// Name (see [`crate::model`]).
    pub name: String,
    /// Nominal value: the table's value for DH parameters (0 for `beta`), the table's base and
    /// tool as `x y z` metres and roll-pitch-yaw radians (`R = Rz(rz) Ry(ry) Rx(rx)`, URDF
    /// convention), and for the device frame (`T_device_base`, same layout) and targets the
    /// `nominal` step's estimate.
    pub nominal: f64,
    /// Estimated value, same layout.
    pub estimate: f64,
    /// Standard error (same unit), `None` when held fixed. For pose blocks it is propagated from
    /// the fit's small motions to `x y z` / roll-pitch-yaw to first order.
    pub std_error: Option<f64>,
    /// `true` when estimated, `false` when held at nominal.
    pub free: bool,
}

/// A parameter held at nominal because the data cannot identify it.
#[derive(Clone, Debug, PartialEq)]
pub struct FixedParameter {
    /// Its name.
    pub name: String,
    /// Names of the free parameters that absorb its error (its null-space partners), empty
    /// when it has no effect on the data at all.
    pub aliases: Vec<String>,
}

/// The calibration's result. Lengths in metres, angles in radians.
#[derive(Clone, Debug, PartialEq)]
pub struct Report {
    /// One entry per step, in order.
    pub steps: Vec<StepReport>,
    /// Calibration RMS of the `nominal` step.
    pub rms_before: f64,
    /// Calibration RMS of the last step.
    pub rms_after: f64,
    /// Validation RMS of the `nominal` step.
    pub val_rms_before: Option<f64>,
    /// Validation RMS of the last step.
    pub val_rms_after: Option<f64>,
    /// How validation was done.
    pub validation: Validation,
    /// Noise floor, when the noise is known or can be estimated from repeats.
    pub noise_floor: Option<NoiseFloor>,
    /// Condition number of the scaled Jacobian of the free parameters at the estimate.
    pub condition_number: f64,
    /// Number of free parameters in the last step.
    pub rank: usize,
    /// Residual standard deviation per coordinate, `sqrt(ssr / (3N − p))` (metres).
    pub sigma_hat: Option<f64>,
    /// Characteristic length that scaled the angle columns (metres).
    pub length_scale: f64,
    /// The relative singular value threshold used for identifiability.
    pub rank_tolerance: f64,
    /// Every parameter of the model.
    pub parameters: Vec<ParameterEstimate>,
    /// The parameters held at nominal, with their aliases.
    pub fixed: Vec<FixedParameter>,
    /// Classic DH or Hayati-Mirmirani for each consecutive pair of joints.
    pub parametrisation: Vec<PairParametrisation>,
    /// The calibrated table, Hayati tilts in their rows' `beta` (see [`Model::table_at`]).
    pub calibrated: DhTable,
    /// Estimated `T_device_base` (of the first calibration session when there are several).
    pub device: Isometry3<f64>,
    /// Every session's device frame and RMS (one entry for a set without sessions); the first
    /// is the session of `device`.
    pub sessions: Vec<crate::sessions::SessionReport>,
    /// Estimated target positions in the tip frame.
    pub targets: Vec<(String, Vector3<f64>)>,
    /// Remarks for the user (unused targets, approximations).
    pub notes: Vec<String>,
    /// For a tree: the calibrated tree (its trunk is `calibrated`); `None` for a serial robot.
    pub tree: Option<crate::tree::DhTree>,
    /// The effects' candidate table of the automatic diagnosis ([`crate::diagnose`]), in the
    /// order scored in its first round; empty otherwise.
    pub candidates: Vec<crate::diagnose::CandidateReport>,
    /// Labels of the effects estimated in the last step, in the order added.
    pub selected_effects: Vec<String>,
    /// What the automatic diagnosis found; `None` when it did not run.
    pub diagnosis: Option<crate::diagnose::Diagnosis>,
    /// What the outlier screen found; `None` when it did not run.
    pub outliers: Option<crate::outliers::OutlierReport>,
    /// The test of the final model against the noise, and what it means.
    pub verdict: crate::diagnose::Verdict,
    /// Covariance of the last step's free parameters (see [`crate::predict`]); `None` when
    /// the residual's sigma is unknown (no more coordinates than parameters).
    pub covariance: Option<crate::predict::Covariance>,
}

/// Calibration samples, validation samples and the pose group of each calibration sample.
pub(crate) struct Prepared {
    pub(crate) cal: Vec<Observed>,
    pub(crate) val: Vec<Observed>,
    pub(crate) groups: Vec<usize>,
    pub(crate) group_count: usize,
    pub(crate) repeat_keys: Vec<Option<(String, usize)>>,
    pub(crate) sigmas: Vec<Option<Vector3<f64>>>,
    /// Pose group of each validation sample (numbered apart from the calibration groups).
    pub(crate) val_groups: Vec<usize>,
}

/// Each sample's joint values per row of `tree` (mimic rows from their driver's column).
///
/// # Errors
/// [`CalibError::MissingJoint`] for a row without a column; [`CalibError::Length`] for a
/// sample with the wrong number of values; [`CalibError::NonFinite`] for a non-finite value.
pub(crate) fn rows_of(tree: &DhTree, data: &Measurements) -> Result<Vec<Vec<f64>>, CalibError> {
    enum Source {
        Column(usize),
        Mimic(usize, f64, f64),
    }
    let column = |name: &str| data.joint_names.iter().position(|n| n == name);
    let mut sources = Vec::with_capacity(tree.rows().len());
    for r in tree.rows() {
        let s = match (column(&r.name), &r.mimic) {
            (Some(c), _) => Source::Column(c),
            (None, Some(m)) => match column(&m.joint) {
                Some(c) => Source::Mimic(c, m.multiplier, m.offset),
                None => {
                    return Err(CalibError::MissingJoint {
                        joint: r.name.clone(),
                    })
                }
            },
            (None, None) => {
                return Err(CalibError::MissingJoint {
                    joint: r.name.clone(),
                })
            }
        };
        sources.push(s);
    }
    let mut rows_q: Vec<Vec<f64>> = Vec::with_capacity(data.samples.len());
    for s in &data.samples {
        if s.q.len() != data.joint_names.len() {
            return Err(CalibError::Length {
                what: format!("joint values at line {}", s.line),
                expected: data.joint_names.len(),
                found: s.q.len(),
            });
        }
        if s.q.iter().any(|v| !v.is_finite()) {
            return Err(CalibError::NonFinite {
                what: format!("sample at line {}", s.line),
            });
        }
        rows_q.push(
            sources
                .iter()
                .map(|src| match *src {
                    Source::Column(c) => s.q[c],
                    Source::Mimic(c, m, o) => m * s.q[c] + o,
                })
                .collect(),
        );
    }
    Ok(rows_q)
}

/// The place of each sample of `data` in its sequence, from its row values `rows_q`.
fn sequence_of(rows_q: &[Vec<f64>], data: &Measurements) -> Vec<SampleContext> {
    crate::effects_order::contexts_of(rows_q.iter().map(Vec::as_slice), data)
}

/// Prepares `data` for `tree`; `sequence` is each sample's place in the measurement sequence
/// when `data` is part of a longer one (the samples an outlier screen kept, placed in the
/// whole file: [`fitted_session`]), `None` to take `data`'s own order.
pub(crate) fn prepare(
    tree: &DhTree,
    data: &Measurements,
    sequence: Option<&[SampleContext]>,
) -> Result<Prepared, CalibError> {
    let rows_q = rows_of(tree, data)?;
    // The place of every sample in the sequence, calibration and validation alike (the robot
    // visited both, in file order).
    let contexts = match sequence {
        Some(c) if c.len() == data.samples.len() => c.to_vec(),
        _ => sequence_of(&rows_q, data),
    };
    let mut out = Prepared {
        cal: vec![],
        val: vec![],
        groups: vec![],
        group_count: 0,
        repeat_keys: vec![],
        sigmas: vec![],
        val_groups: vec![],
    };
    let mut val_ids: HashMap<String, usize> = HashMap::new();
    let mut group_ids: HashMap<Vec<u64>, usize> = HashMap::new();
    let mut config_ids: HashMap<String, usize> = HashMap::new();
    for s in &data.samples {
        if s.target >= data.targets.len() {
            return Err(CalibError::BadTarget {
                line: s.line,
                target: s.target,
                count: data.targets.len(),
            });
        }
        if s.point.iter().any(|v| !v.is_finite()) {
            return Err(CalibError::NonFinite {
                what: format!("sample at line {}", s.line),
            });
        }
    }
    for ((s, q), context) in data.samples.iter().zip(rows_q).zip(contexts) {
        let obs = Observed {
            session: s.session,
            q,
            observation: Observation::Point {
                target: s.target,
                point: s.point,
            },
            context,
        };
        match s.split {
            Split::Validation => {
                let key = match &s.config {
                    Some(c) => c.clone(),
                    None => format!("{:?}", obs.q),
                };
                let next = val_ids.len();
                out.val_groups.push(*val_ids.entry(key).or_insert(next));
                out.val.push(obs);
            }
            Split::Calibration => {
                let next = group_ids.len() + config_ids.len();
                let g = match &s.config {
                    Some(c) => *config_ids.entry(c.clone()).or_insert(next),
                    None => *group_ids
                        .entry(obs.q.iter().map(|v| v.to_bits()).collect())
                        .or_insert(next),
                };
                out.groups.push(g);
                out.repeat_keys
                    .push(s.config.as_ref().map(|c| (c.clone(), s.target)));
                out.sigmas.push(s.sigma);
                out.cal.push(obs);
            }
        }
    }
    out.group_count = group_ids.len() + config_ids.len();
    Ok(out)
}

/// Rigid registration: the `T` minimising `Σ ‖T·a_i − b_i‖²` (Kabsch 1976, with the reflection
/// guard of Umeyama 1991).
///
/// # Errors
/// [`CalibError::TooFewSamples`] for fewer than 3 pairs, [`CalibError::Degenerate`] when the
/// points are collinear.
pub fn register(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> Result<Isometry3<f64>, CalibError> {
    if a.len() != b.len() || a.len() < 3 {
        return Err(CalibError::TooFewSamples {
            what: "rigid registration".into(),
            needed: 3,
            found: a.len().min(b.len()),
        });
    }
    let n = a.len() as f64;
    let ca = a.iter().sum::<Vector3<f64>>() / n;
    let cb = b.iter().sum::<Vector3<f64>>() / n;
    let mut h = Matrix3::zeros();
    for (p, q) in a.iter().zip(b) {
        h += (p - ca) * (q - cb).transpose();
    }
    let svd = h.svd(true, true);
    let (Some(u), Some(vt)) = (svd.u, svd.v_t) else {
        return Err(CalibError::Degenerate {
            what: "rigid registration".into(),
        });
    };
    let s = svd.singular_values;
    let smax = s.max();
    let mut sorted = [s[0], s[1], s[2]];
    sorted.sort_by(|x, y| y.total_cmp(x));
    if smax.is_nan() || smax <= 0.0 || sorted[1] <= 1e-12 * smax {
        return Err(CalibError::Degenerate {
            what: "rigid registration".into(),
        });
    }
    let v = vt.transpose();
    let det = (v * u.transpose()).determinant();
    let d = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, det.signum()));
    let r = v * d * u.transpose();
    let rot = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
    let t = cb - rot * ca;
    Ok(Isometry3::from_parts(Translation3::from(t), rot))
}

fn observed_position(o: &Observed) -> Vector3<f64> {
    match &o.observation {
        Observation::Point { point, .. } => *point,
        Observation::Pose(p) => p.translation.vector,
    }
}

/// Closed-form target positions given the device frame: the mean of each target's measured
/// points mapped into the tip frame (the exact least-squares solution, rotations being
/// orthogonal).
fn targets_given_device(model: &mut Model, x: &[f64], cal: &[Observed]) {
    let k = model.targets().len();
    let mut sums = vec![(Vector3::zeros(), 0usize); k];
    for o in cal {
        if let Observation::Point { target, point } = &o.observation {
            let tip = model.tip_in(x, &o.q, model.target_chain(*target), o.session);
            if let Some(s) = sums.get_mut(*target) {
                s.0 += tip.inverse_transform_point(&(*point).into()).coords;
                s.1 += 1;
            }
        }
    }
    for (t, (sum, n)) in sums.into_iter().enumerate() {
        if n > 0 {
            model.set_target(t, sum / n as f64);
        }
    }
}

fn initialise(
    model: &mut Model,
    x: &[f64],
    cal: &[Observed],
    options: &CalibrationOptions,
) -> Result<(), CalibError> {
    if let Some(t) = &options.target_guesses {
        if t.len() != model.targets().len() {
            return Err(CalibError::Length {
                what: "target guesses".into(),
                expected: model.targets().len(),
                found: t.len(),
            });
        }
        for (k, v) in t.iter().enumerate() {
            model.set_target(k, *v);
        }
    }
    let sessions = crate::sessions::sessions_of(cal);
    if let Some(d) = &options.device_guess {
        model.set_device(d);
        if options.target_guesses.is_none() {
            let first: Vec<Observed> = cal
                .iter()
                .filter(|o| Some(&o.session) == sessions.first())
                .cloned()
                .collect();
            targets_given_device(model, x, &first);
        }
        // The other sessions' frames from the targets the guess gives.
        for (s, t) in
            crate::sessions::register_each(model, x, cal, sessions.get(1..).unwrap_or(&[]))?
        {
            model.set_session_device(s, &t);
        }
        return Ok(());
    }
    // Alternate registration (each session's frame) and targets; a few rounds reach the basin
    // of the least squares.
    let rounds = if options.target_guesses.is_some() {
        1
    } else {
        4
    };
    for _ in 0..rounds {
        for (s, t) in crate::sessions::register_each(model, x, cal, &sessions)? {
            model.set_session_device(s, &t);
        }
        if options.target_guesses.is_none() {
            targets_given_device(model, x, cal);
        }
    }
    Ok(())
}

/// The `d` of every Hayati pair of `model`, held at nominal and named with the `beta` that
/// replaces it.
fn replaced_by_beta(model: &Model) -> Vec<FixedParameter> {
    model
        .pairs()
        .iter()
        .filter(|p| p.hayati)
        .filter_map(|p| {
            let d = p.dropped_d.as_ref()?;
            Some(FixedParameter {
                name: format!("{d}.d"),
                aliases: p
                    .beta_row
                    .as_ref()
                    .map(|b| vec![format!("{b}.beta")])
                    .unwrap_or_default(),
            })
        })
        .collect()
}

/// Calibration samples beyond which a cross-validation fold is fitted on a subsample of its
/// training samples (see [`Validation::CrossValidation`]): 100 000 points fix a few dozen
/// kinematic parameters far below any tracker's noise, and the folds then cost one fit of the
/// whole data between them instead of `folds` fits.
pub const CV_TRAINING_MAX: usize = 100_000;

/// Distance (metres) between model and measurement of every observation in `obs`.
pub(crate) fn distances(model: &Model, x: &[f64], obs: &[Observed]) -> Vec<f64> {
    let idx: Vec<usize> = (0..obs.len()).collect();
    distances_at(model, x, obs, &idx)
}

/// [`distances`] of the observations `obs[i]` for `i` in `at`, in parallel segments for long
/// lists.
fn distances_at(model: &Model, x: &[f64], obs: &[Observed], at: &[usize]) -> Vec<f64> {
    let one = |i: &usize| {
        let mut r = [0.0; 6];
        model.residuals(x, &obs[*i], &mut r);
        Vector3::new(r[0], r[1], r[2]).norm()
    };
    let parts: Vec<&[usize]> = at.chunks(fit::SEGMENT_BLOCKS).collect();
    if parts.len() <= 1 {
        return at.iter().map(one).collect();
    }
    match fit::parallel_map(parts.len(), |k| {
        Ok(parts[k].iter().map(one).collect::<Vec<f64>>())
    }) {
        Ok(d) => d.concat(),
        // Only a worker's panic gets here: compute on this thread instead.
        Err(_) => at.iter().map(one).collect(),
    }
}

/// Distances of the validation samples at `x`. A target that no calibration sample measured
/// (a test point: another reflector, mounted only for validation) has no estimated position on
/// the tip, so its validation samples first locate it: the point `p` in the tip frame that
/// minimises `Σ |t_i + s_i R_i p − m_i|²` over them (closed form, 3 parameters, as a tool
/// is taught), and they are then compared with the model at that point. The figure then
/// measures how well the model predicts the target's motion between poses, the quantity a
/// test set of a new tool can measure.
fn split_distances(model: &Model, x: &[f64], prep: &Prepared) -> Vec<f64> {
    let mut measured = vec![false; model.targets().len()];
    for o in &prep.cal {
        if let Observation::Point { target, .. } = &o.observation {
            if let Some(m) = measured.get_mut(*target) {
                *m = true;
            }
        }
    }
    // Located positions of the targets only validation samples measured.
    let mut located: Vec<Option<Vector3<f64>>> = vec![None; measured.len()];
    let mut sums: Vec<(Vector3<f64>, f64)> = vec![(Vector3::zeros(), 0.0); measured.len()];
    for o in &prep.val {
        if let Observation::Point { target, point } = &o.observation {
            if measured.get(*target) == Some(&false) {
                let tip = model.tip_in(x, &o.q, model.target_chain(*target), o.session);
                let s = model.scale_at(x, &o.q);
                let acc = &mut sums[*target];
                acc.0 += tip.rotation.inverse() * (point - tip.translation.vector) * s;
                acc.1 += s * s;
            }
        }
    }
    for (k, (sum, weight)) in sums.iter().enumerate() {
        if !measured[k] && *weight > 0.0 {
            located[k] = Some(sum / *weight);
        }
    }
    let unseen = crate::sessions::unseen_frames(model, x, prep);
    let mut r = [0.0; 6];
    prep.val
        .iter()
        .map(|o| match &o.observation {
            _ if unseen.iter().any(|(s, _)| *s == o.session) => {
                let frame = unseen
                    .iter()
                    .find(|(s, _)| *s == o.session)
                    .map(|(_, t)| *t);
                crate::sessions::distance_in(model, x, o, &frame.unwrap_or_default())
            }
            Observation::Point { target, point } => match located.get(*target).copied().flatten() {
                Some(p) => {
                    let tip = model.tip_in(x, &o.q, model.target_chain(*target), o.session);
                    let s = model.scale_at(x, &o.q);
                    (tip.translation.vector + tip.rotation * p * s - point).norm()
                }
                None => {
                    model.residuals(x, o, &mut r);
                    Vector3::new(r[0], r[1], r[2]).norm()
                }
            },
            Observation::Pose(_) => {
                model.residuals(x, o, &mut r);
                Vector3::new(r[0], r[1], r[2]).norm()
            }
        })
        .collect()
}

/// For each target that only validation samples measured (see [`split_distances`]): the
/// indices of its validation samples and the tip's rotation at each, at `x`. The linearised
/// held-out figures of the effect search project the 3-parameter location out of those
/// samples' residuals with them (the device scale, within 1e-4 of 1, left out).
pub(crate) fn validation_locations(
    model: &Model,
    x: &[f64],
    prep: &Prepared,
) -> Vec<(Vec<usize>, Vec<Matrix3<f64>>)> {
    let count = model.targets().len();
    let mut measured = vec![false; count];
    for o in &prep.cal {
        if let Observation::Point { target, .. } = &o.observation {
            if let Some(m) = measured.get_mut(*target) {
                *m = true;
            }
        }
    }
    let mut groups: Vec<(Vec<usize>, Vec<Matrix3<f64>>)> = vec![(vec![], vec![]); count];
    for (i, o) in prep.val.iter().enumerate() {
        if let Observation::Point { target, .. } = &o.observation {
            if measured.get(*target) == Some(&false) {
                let tip = model.tip_in(x, &o.q, model.target_chain(*target), o.session);
                groups[*target].0.push(i);
                groups[*target]
                    .1
                    .push(*tip.rotation.to_rotation_matrix().matrix());
            }
        }
    }
    groups.retain(|g| !g.0.is_empty());
    groups
}

/// Every `len / keep`-th index of `all` (evenly spaced, deterministic), at most `keep` of them.
fn evenly_spaced(all: Vec<usize>, keep: usize) -> Vec<usize> {
    if all.len() <= keep || keep == 0 {
        return all;
    }
    let n = all.len();
    (0..keep).map(|k| all[k * n / keep]).collect()
}

pub(crate) struct StepResult {
    pub(crate) outcome: FitOutcome,
    pub(crate) report: StepReport,
    /// Held-out distance of every validation sample (split) or calibration sample
    /// (cross-validation), in sample order; empty without validation.
    pub(crate) held_out: Vec<f64>,
}

/// Held-out distances of `free` fitted from `x0`: the validation split's, or k-fold
/// cross-validation's over pose groups (each calibration sample predicted by the fit without
/// its fold), in sample order.
pub(crate) fn held_out(
    model: &Model,
    prep: &Prepared,
    validation: &Validation,
    x: &[f64],
    free: &[usize],
    scales: &[f64],
    fit_options: &FitOptions,
) -> Result<Vec<f64>, CalibError> {
    match validation {
        Validation::Split { .. } => Ok(split_distances(model, x, prep)),
        Validation::CrossValidation {
            folds,
            training_subsample,
            ..
        } => {
            // The folds are independent fits: run on every core, gathered in fold order.
            let per_fold = fit::parallel_map(*folds, |f| {
                let (mut train, mut at) = (Vec::new(), Vec::new());
                for (i, g) in prep.groups.iter().enumerate() {
                    if g % folds == f {
                        at.push(i);
                    } else {
                        train.push(i);
                    }
                }
                if let Some(keep) = training_subsample {
                    train = evenly_spaced(train, *keep);
                }
                let p = SubsetProblem {
                    model,
                    observations: &prep.cal,
                    subset: &train,
                };
                let fold = fit::solve(&p, x, free, scales, fit_options)?;
                let d = distances_at(model, &fold.x, &prep.cal, &at);
                Ok((at, d))
            })?;
            let mut d = vec![0.0; prep.cal.len()];
            for (at, fold) in per_fold {
                for (i, v) in at.into_iter().zip(fold) {
                    d[i] = v;
                }
            }
            Ok(d)
        }
        Validation::None => Ok(vec![]),
    }
}

/// Everything the steps of one calibration share: the samples, the model (with every effect
/// that any step may free), the validation scheme.
pub(crate) struct Session<'a> {
    pub(crate) model: Model,
    pub(crate) prep: Prepared,
    pub(crate) scales: Vec<f64>,
    pub(crate) options: &'a CalibrationOptions,
    pub(crate) validation: Validation,
    pub(crate) notes: Vec<String>,
    measured: Vec<bool>,
    device_nominal: Isometry3<f64>,
    targets_nominal: Vec<Vector3<f64>>,
    /// The name of every session of the data (see [`crate::sessions`]).
    session_names: Vec<String>,
    /// Beyond [`CV_TRAINING_MAX`] calibration samples, that many evenly spaced ones (indices
    /// into `prep.cal`): the closed-form start, each step's identifiability and each fit's
    /// first iterations use them, and the fit of every sample starts where theirs ends (one
    /// or two passes over millions of samples instead of one per iteration). Empty for
    /// smaller sets, which are fitted as they are.
    coarse: Vec<usize>,
}

/// The chain of each target of `data` in `tree` (see [`CalibrationOptions::target_branches`]).
fn target_chains(
    tree: &DhTree,
    data: &Measurements,
    options: &CalibrationOptions,
) -> Result<Vec<(String, usize)>, CalibError> {
    data.targets
        .iter()
        .map(|t| {
            if tree.branches().is_empty() {
                return Ok((t.clone(), 0));
            }
            let branch = options
                .target_branches
                .iter()
                .find(|(target, _)| target == t)
                .map_or(t.as_str(), |(_, b)| b.as_str());
            tree.branch_index(branch)
                .map(|b| (t.clone(), b))
                .ok_or_else(|| CalibError::BadOption {
                    what: format!("target '{t}'"),
                    reason: format!(
                        "expected a branch of the tree ({}), found '{branch}'",
                        tree.branches()
                            .iter()
                            .map(|b| b.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                })
        })
        .collect()
}

impl<'a> Session<'a> {
    /// Prepares the samples, builds the model of `tree` with `effects` (their parameters start
    /// at zero and are not estimated until a step frees them) and finds the closed-form start;
    /// `sequence` places the samples in a longer sequence (see [`prepare`]).
    pub(crate) fn new(
        tree: &DhTree,
        data: &Measurements,
        options: &'a CalibrationOptions,
        effects: &[Arc<dyn Effect>],
        sequence: Option<&[SampleContext]>,
    ) -> Result<Session<'a>, CalibError> {
        crate::sessions::check(data)?;
        let prep = prepare(tree, data, sequence)?;
        if prep.cal.len() < 3 {
            return Err(CalibError::TooFewSamples {
                what: "calibration".into(),
                needed: 3,
                found: prep.cal.len(),
            });
        }
        let chains = target_chains(tree, data, options)?;
        let mut model = Model::new_tree(tree, &chains, &options.model)?;
        crate::sessions::add_blocks(&mut model, data, &prep.cal);
        for e in effects {
            model.add_effect(e.clone())?;
        }
        let scales = model.scales();
        let x = vec![0.0; model.parameter_count()];
        let coarse = if prep.cal.len() > CV_TRAINING_MAX {
            evenly_spaced((0..prep.cal.len()).collect(), CV_TRAINING_MAX)
        } else {
            Vec::new()
        };
        if coarse.is_empty() {
            initialise(&mut model, &x, &prep.cal, options)?;
        } else {
            let sample: Vec<Observed> = coarse.iter().map(|&i| prep.cal[i].clone()).collect();
            initialise(&mut model, &x, &sample, options)?;
        }
        let validation = if !prep.val.is_empty() {
            Validation::Split {
                samples: prep.val.len(),
            }
        } else if prep.group_count >= 2 && options.folds >= 2 {
            Validation::CrossValidation {
                folds: options.folds.min(prep.group_count),
                groups: prep.group_count,
                training_subsample: (prep.cal.len() > CV_TRAINING_MAX).then_some(CV_TRAINING_MAX),
            }
        } else {
            Validation::None
        };
        let mut notes = Vec::new();
        // Targets never measured stay where they are and are reported as fixed.
        let mut measured = vec![false; model.targets().len()];
        for o in &prep.cal {
            if let Observation::Point { target, .. } = &o.observation {
                measured[*target] = true;
            }
        }
        for (k, m) in measured.iter().enumerate() {
            if !m {
                let validated = prep.val.iter().filter(
                    |o| matches!(o.observation, Observation::Point { target, .. } if target == k),
                );
                let n = validated.count();
                notes.push(if n > 0 {
                    format!(
                        "target '{}' has no calibration sample; its position on the tip is located from its own {n} validation samples (3 parameters) before they are compared",
                        model.targets()[k].0
                    )
                } else {
                    format!(
                        "target '{}' has no calibration sample; its position is not estimated",
                        model.targets()[k].0
                    )
                });
            }
        }
        notes.extend(crate::sessions::unseen_notes(data, &prep));
        if !coarse.is_empty() {
            notes.push(format!(
                "{} calibration samples: the closed-form start, the identifiability tests and \
                 each fit's first iterations use {} evenly spaced ones; every fit then \
                 converges on all of them (its figures and standard errors are of all samples)",
                prep.cal.len(),
                coarse.len()
            ));
        }
        let device_nominal = model.device();
        let targets_nominal = model.targets().iter().map(|t| t.1).collect();
        Ok(Session {
            session_names: (0..data.session_count())
                .map(|s| data.session_name(s))
                .collect(),
            model,
            prep,
            scales,
            options,
            validation,
            notes,
            measured,
            device_nominal,
            targets_nominal,
            coarse,
        })
    }

    /// Fits `free` from `x0` and reports the step; `previous` is the step before it.
    pub(crate) fn step(
        &self,
        label: &str,
        x0: &[f64],
        free: &[usize],
        previous: Option<&StepReport>,
    ) -> Result<StepResult, CalibError> {
        let problem = ModelProblem {
            model: &self.model,
            observations: &self.prep.cal,
        };
        let start = if self.coarse.is_empty() {
            x0.to_vec()
        } else {
            let sample = SubsetProblem {
                model: &self.model,
                observations: &self.prep.cal,
                subset: &self.coarse,
            };
            fit::solve(&sample, x0, free, &self.scales, &self.options.fit)?.x
        };
        let outcome = fit::solve(&problem, &start, free, &self.scales, &self.options.fit)?;
        let cal = Stats::of(&distances(&self.model, &outcome.x, &self.prep.cal));
        let held = held_out(
            &self.model,
            &self.prep,
            &self.validation,
            &outcome.x,
            free,
            &self.scales,
            &self.options.fit,
        )?;
        let val = Stats::of(&held);
        let cal = cal.unwrap_or(Stats {
            rms: 0.0,
            mean: 0.0,
            max: 0.0,
            count: 0,
        });
        let report = StepReport {
            label: label.into(),
            rms_before: previous.map(|p| p.rms),
            val_rms_before: previous.and_then(|p| p.val_rms),
            rms: cal.rms,
            mean: cal.mean,
            max: cal.max,
            val_rms: val.map(|v| v.rms),
            val_mean: val.map(|v| v.mean),
            val_max: val.map(|v| v.max),
            free: free.len(),
            iterations: outcome.iterations,
            termination: outcome.termination,
            fixed: Vec::new(),
        };
        Ok(StepResult {
            outcome,
            report,
            held_out: held,
        })
    }

    /// Identifiability of `columns` at `x` (see [`identify`]).
    pub(crate) fn identify(
        &self,
        x: &[f64],
        columns: &[usize],
    ) -> Result<(Vec<usize>, Vec<fit::Fixed>), CalibError> {
        if self.coarse.is_empty() {
            return identify(
                &self.model,
                &self.prep.cal,
                x,
                columns,
                &self.scales,
                self.options,
            );
        }
        let sample = SubsetProblem {
            model: &self.model,
            observations: &self.prep.cal,
            subset: &self.coarse,
        };
        identify_in(&sample, &self.model, x, columns, &self.scales, self.options)
    }

    /// Names of `fixed` parameters and their aliases, for a report.
    pub(crate) fn named(&self, fixed: &[fit::Fixed]) -> Vec<FixedParameter> {
        let params = self.model.parameters();
        let name = |i: usize| params.get(i).map_or_else(String::new, |p| p.name.clone());
        fixed
            .iter()
            .map(|f| FixedParameter {
                name: name(f.index),
                aliases: f.aliases.iter().map(|&a| name(a)).collect(),
            })
            .collect()
    }

    /// [`Session::named`] for a step that estimates the geometry, with the `d` of every
    /// Hayati pair: the model has no parameter for it (its row's `beta` takes its place, see
    /// [`PairParametrisation`]), so it stays at nominal too.
    pub(crate) fn named_geometric(&self, fixed: &[fit::Fixed]) -> Vec<FixedParameter> {
        let mut out = self.named(fixed);
        out.extend(replaced_by_beta(&self.model));
        out
    }

    /// The `nominal` step (the identifiable device and target coordinates; the others stay at
    /// the closed-form start), then the `geometric` one (every identifiable geometric
    /// parameter). Returns the steps, the geometric fit and its free and fixed parameters.
    pub(crate) fn geometric(&mut self) -> Result<Geometric, CalibError> {
        let mut x = vec![0.0; self.model.parameter_count()];
        let measured = self.measured.clone();
        let nominal_columns = self.model.indices(|b| match b {
            Block::Device | Block::Session(_) => true,
            Block::Target(k) => measured[k],
            _ => false,
        });
        // The nominal step steps only where the data can tell device and targets apart (see
        // `fit::MIN_SENSITIVITY`): what it cannot stays at the closed-form start.
        let (nominal_free, nominal_fixed) = self.identify(&x, &nominal_columns)?;
        let mut step = self.step("nominal", &x, &nominal_free, None)?;
        step.report.fixed = self.named(&nominal_fixed);
        x = step.outcome.x.clone();
        let mut steps = vec![step.report];
        self.model.rebase(&mut x);
        self.device_nominal = self.model.device();
        self.targets_nominal = self.model.targets().iter().map(|t| t.1).collect();
        let geometric: Vec<usize> = self.model.indices(|b| !matches!(b, Block::Effect(_)));
        let (free, fixed) = self.identify(&x, &geometric)?;
        self.enough_for(&x, &geometric, free.len())?;
        let mut step = self.step("geometric", &x, &free, steps.last())?;
        step.report.fixed = self.named_geometric(&fixed);
        steps.push(step.report.clone());
        Ok(Geometric {
            steps,
            last: step,
            free,
            fixed,
        })
    }

    /// Refuses data that leaves no residual degree of freedom for `columns`: as many free
    /// parameters (`free`, the data's rank) as measured coordinates, so the fit reproduces the
    /// data exactly and learns nothing. The error says how many samples the model needs: one
    /// more than a third of its generic rank, found at the same targets and random joint values.
    fn enough_for(&self, x: &[f64], columns: &[usize], free: usize) -> Result<(), CalibError> {
        let cal = &self.prep.cal;
        let equations: usize = cal
            .iter()
            .map(|o| match o.observation {
                Observation::Point { .. } => 3,
                Observation::Pose(_) => 6,
            })
            .sum();
        if free < equations {
            return Ok(());
        }
        let per_sample = equations.div_ceil(cal.len().max(1)).max(1);
        let mut generic = free;
        let points_only = cal
            .iter()
            .all(|o| matches!(o.observation, Observation::Point { .. }));
        if let (true, Some(first)) = (points_only, cal.first()) {
            use rand::{Rng, SeedableRng};
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
            let targets: Vec<usize> = (0..self.measured.len())
                .filter(|&k| self.measured[k])
                .collect();
            let mut synthetic = Vec::new();
            for _ in 0..columns.len().max(1) {
                let q: Vec<f64> = (0..first.q.len())
                    .map(|_| rng.random_range(-std::f64::consts::PI..std::f64::consts::PI))
                    .collect();
                for &k in &targets {
                    synthetic.push(Observed::new(
                        q.clone(),
                        Observation::Point {
                            target: k,
                            point: self.model.point(x, &q, k),
                        },
                    ));
                }
            }
            if let Ok((f, _)) = identify(
                &self.model,
                &synthetic,
                x,
                columns,
                &self.scales,
                self.options,
            ) {
                generic = generic.max(f.len());
            }
        }
        Err(CalibError::TooFewSamples {
            what: format!(
                "geometric calibration ({generic} identifiable parameters, {per_sample} \
                 coordinates per sample; {free} would fit the data exactly)"
            ),
            needed: generic / per_sample + 1,
            found: cal.len(),
        })
    }

    /// The report at the fit `last` (its free parameters `free`, the fixed ones `fixed`).
    /// Effect parameters of effects listed in `hidden` are left out of the parameter list.
    pub(crate) fn report(
        &self,
        last: &FitOutcome,
        steps: Vec<StepReport>,
        fixed: Vec<fit::Fixed>,
        hidden: &[usize],
    ) -> Report {
        let model = &self.model;
        let x = last.x.clone();
        let mut notes = self.notes.clone();
        let noise_floor = noise_floor(&self.prep, self.options, last.free.len());
        let mut parameters = estimates(model, &x, last, self.device_nominal, &self.targets_nominal);
        let hidden_names: Vec<&str> = model
            .parameters()
            .iter()
            .filter(|p| matches!(p.block, Block::Effect(e) if hidden.contains(&e)))
            .map(|p| p.name.as_str())
            .collect();
        parameters.retain(|p| !hidden_names.contains(&p.name.as_str()));
        let tree = model.tree_at(&x);
        let effect_free = last
            .free
            .iter()
            .any(|&c| matches!(model.parameters()[c].block, Block::Effect(_)));
        if effect_free {
            notes.push("effects are not part of the calibrated DH table".into());
        }
        let fixed = fixed
            .into_iter()
            .filter(|f| !hidden_names.contains(&model.parameters()[f.index].name.as_str()))
            .map(|f| FixedParameter {
                name: model.parameters()[f.index].name.clone(),
                aliases: f
                    .aliases
                    .iter()
                    .map(|&a| model.parameters()[a].name.clone())
                    .collect(),
            })
            .chain(replaced_by_beta(model))
            .collect();
        let (first, final_) = (&steps[0], &steps[steps.len() - 1]);
        let selected_effects = model
            .effects()
            .iter()
            .enumerate()
            .filter(|(e, (_, range))| {
                !hidden.contains(e) && range.clone().any(|c| last.free.contains(&c))
            })
            .map(|(_, (effect, _))| crate::effects::label_of(effect.as_ref()))
            .collect::<Vec<_>>();
        let covariance = last.covariance.as_ref().and_then(|c| {
            let names = last
                .free
                .iter()
                .map(|&i| model.parameters()[i].name.clone())
                .collect();
            crate::predict::Covariance::new(names, c.clone()).ok()
        });
        notes.extend(crate::sessions::moved_note(
            self.session_names.len(),
            final_.rms,
            final_.val_rms,
        ));
        let verdict = crate::diagnose::verdict(
            self,
            last,
            crate::diagnose::DEFAULT_ALPHA,
            noise_floor.as_ref(),
            final_.rms,
            &selected_effects,
        );
        Report {
            rms_before: first.rms,
            rms_after: final_.rms,
            val_rms_before: first.val_rms,
            val_rms_after: final_.val_rms,
            steps: steps.clone(),
            validation: self.validation.clone(),
            noise_floor,
            condition_number: last.condition_number,
            rank: last.rank,
            sigma_hat: last.sigma,
            length_scale: model.length_scale(),
            rank_tolerance: self.options.fit.rank_tolerance,
            parameters,
            fixed,
            parametrisation: model.pairs().to_vec(),
            calibrated: tree.trunk().clone(),
            device: model.device_at(&x),
            sessions: self.session_reports(&x),
            targets: (0..model.targets().len())
                .map(|k| (model.targets()[k].0.clone(), model.target_at(&x, k)))
                .collect(),
            notes,
            tree: (!tree.branches().is_empty()).then_some(tree),
            candidates: vec![],
            selected_effects,
            diagnosis: None,
            outliers: None,
            verdict,
            covariance,
        }
    }
}

impl Session<'_> {
    /// Each session's frame and RMS at `x` (see [`crate::sessions::reports`]).
    fn session_reports(&self, x: &[f64]) -> Vec<crate::sessions::SessionReport> {
        let cal_d = distances(&self.model, x, &self.prep.cal);
        let val_d = match self.validation {
            Validation::Split { .. } => split_distances(&self.model, x, &self.prep),
            _ => Vec::new(),
        };
        crate::sessions::reports(
            &self.model,
            x,
            &self.session_names,
            &self.prep,
            &cal_d,
            &val_d,
        )
    }
}

/// The result of [`Session::geometric`].
pub(crate) struct Geometric {
    pub(crate) steps: Vec<StepReport>,
    pub(crate) last: StepResult,
    pub(crate) free: Vec<usize>,
    pub(crate) fixed: Vec<fit::Fixed>,
}

fn noise_floor(prep: &Prepared, options: &CalibrationOptions, p: usize) -> Option<NoiseFloor> {
    let n = prep.cal.len();
    if n == 0 {
        return None;
    }
    let (e2, source) = if let Some(s) = options.sigma {
        (3.0 * s * s, NoiseSource::Given)
    } else if prep.sigmas.iter().all(Option::is_some) {
        let sum: f64 = prep.sigmas.iter().flatten().map(|s| s.norm_squared()).sum();
        (sum / n as f64, NoiseSource::Samples)
    } else {
        // Pooled pure error of repeated points.
        let mut groups: HashMap<&(String, usize), Vec<Vector3<f64>>> = HashMap::new();
        for (o, key) in prep.cal.iter().zip(&prep.repeat_keys) {
            if let Some(k) = key {
                groups.entry(k).or_default().push(observed_position(o));
            }
        }
        let (mut ss, mut dof, mut count) = (0.0, 0usize, 0usize);
        for pts in groups.values().filter(|v| v.len() > 1) {
            let mean = pts.iter().sum::<Vector3<f64>>() / pts.len() as f64;
            ss += pts.iter().map(|v| (v - mean).norm_squared()).sum::<f64>();
            dof += pts.len() - 1;
            count += 1;
        }
        if dof == 0 {
            return None;
        }
        (ss / dof as f64, NoiseSource::Repeats { groups: count, dof })
    };
    let factor = (1.0 - p as f64 / (3.0 * n as f64)).max(0.0);
    Some(NoiseFloor {
        rms: (e2 * factor).sqrt(),
        sigma: (e2 / 3.0).sqrt(),
        source,
    })
}

/// Runs the calibration of `nominal` against `data` (see the module docs).
///
/// Joint values are matched to rows by name; a mimic row without its own column follows its
/// driver. The report's contract (names, units, layout) is described on [`Report`] and
/// [`crate::model`].
///
/// # Errors
/// [`CalibError::MissingJoint`] when a row has no column, [`CalibError::BadTarget`] /
/// [`CalibError::Length`] / [`CalibError::NonFinite`] for bad samples,
/// [`CalibError::TooFewSamples`] with fewer than 3 calibration samples,
/// [`CalibError::Degenerate`] when the measured points are collinear, and any error of
/// [`Model::new`] or [`fit::solve`].
pub fn calibrate(
    nominal: &DhTable,
    data: &Measurements,
    options: &CalibrationOptions,
) -> Result<Report, CalibError> {
    calibrate_tree(&DhTree::serial(nominal), data, options)
}

/// [`calibrate`] for a tree: the targets ride on the branches named by
/// [`CalibrationOptions::target_branches`] (or their own names), the joint values are matched
/// to the tree's rows by name, and the report's `tree` holds the calibrated tree.
///
/// # Errors
/// As [`calibrate`], and [`CalibError::BadOption`] for a target on no branch.
pub fn calibrate_tree(
    tree: &DhTree,
    data: &Measurements,
    options: &CalibrationOptions,
) -> Result<Report, CalibError> {
    let Fitted {
        session,
        geo:
            Geometric {
                mut steps,
                last,
                mut fixed,
                ..
            },
        scan,
    } = fitted_session(tree, data, options, &options.effects)?;
    let mut last = last.outcome;
    if !options.effects.is_empty() {
        let all: Vec<usize> = (0..session.model.parameter_count()).collect();
        let (free, fixed2) = session.identify(&last.x, &all)?;
        fixed = fixed2;
        let mut step = session.step("effects", &last.x, &free, steps.last())?;
        step.report.fixed = session.named_geometric(&fixed);
        last = step.outcome;
        steps.push(step.report);
    }
    let mut report = session.report(&last, steps, fixed, &[]);
    report.selected_effects = options
        .effects
        .iter()
        .map(|e| crate::effects::label_of(e.as_ref()))
        .collect();
    attach_outliers(&mut report, scan);
    Ok(report)
}

/// A session of the data with `effects` whose geometric step has run, after the outlier screen
/// of `options.outliers` ([`crate::outliers::screen`]) when it is on.
pub(crate) struct Fitted<'a> {
    pub(crate) session: Session<'a>,
    pub(crate) geo: Geometric,
    pub(crate) scan: Option<crate::outliers::OutlierReport>,
}

/// Builds the session of `data` with `effects` and runs its geometric step; the screen's first
/// round is that fit (the same calibration samples, the geometric parameters fitted without
/// effects), so data without outliers are fitted once. When the screen leaves samples out
/// (and they are not kept), the session is built anew from the samples kept, placed in the
/// whole file's sequence: a dropped pose was still visited, so the direction of the next
/// one's motion and the time are the file's.
pub(crate) fn fitted_session<'a>(
    tree: &DhTree,
    data: &Measurements,
    options: &'a CalibrationOptions,
    effects: &[Arc<dyn Effect>],
) -> Result<Fitted<'a>, CalibError> {
    if options.outliers.screen {
        crate::outliers::check_level(options)?;
    }
    let mut session = Session::new(tree, data, options, effects, None)?;
    let geo = session.geometric()?;
    if !options.outliers.screen {
        return Ok(Fitted {
            session,
            geo,
            scan: None,
        });
    }
    let scan = crate::outliers::screen_from(tree, data, options, Some((&session, &geo)))?;
    if scan.kept || scan.outliers.is_empty() {
        return Ok(Fitted {
            session,
            geo,
            scan: Some(scan),
        });
    }
    // The first session's samples are not needed any more: free them before the second.
    drop(session);
    let dropped: std::collections::BTreeSet<usize> =
        scan.outliers.iter().map(|o| o.sample).collect();
    let sequence: Vec<SampleContext> = sequence_of(&rows_of(tree, data)?, data)
        .into_iter()
        .enumerate()
        .filter(|(i, _)| !dropped.contains(i))
        .map(|(_, c)| c)
        .collect();
    let cleaned = scan.without(data);
    let mut session = Session::new(tree, &cleaned, options, effects, Some(&sequence))?;
    let geo = session.geometric()?;
    Ok(Fitted {
        session,
        geo,
        scan: Some(scan),
    })
}

/// Stores the screen's findings in `report`.
pub(crate) fn attach_outliers(report: &mut Report, scan: Option<crate::outliers::OutlierReport>) {
    report.outliers = scan;
}

/// Identifiability of `columns` at `x`; returns the free parameter indices and the fixed ones
/// (indices into the model's parameters). A combination is identifiable when its singular value
/// of the scaled Jacobian is above `rank_tolerance` times the largest and moves the points by at
/// least [`FitOptions::min_sensitivity`] RMS per unit of scaled parameter.
pub(crate) fn identify(
    model: &Model,
    cal: &[Observed],
    x: &[f64],
    columns: &[usize],
    scales: &[f64],
    options: &CalibrationOptions,
) -> Result<(Vec<usize>, Vec<fit::Fixed>), CalibError> {
    let problem = ModelProblem {
        model,
        observations: cal,
    };
    identify_in(&problem, model, x, columns, scales, options)
}

/// [`identify`] over the samples of `problem` (all of them, or a subset) of `model`.
fn identify_in<P: fit::Problem>(
    problem: &P,
    model: &Model,
    x: &[f64],
    columns: &[usize],
    scales: &[f64],
    options: &CalibrationOptions,
) -> Result<(Vec<usize>, Vec<fit::Fixed>), CalibError> {
    let f = fit::factor(problem, x, columns, scales)?;
    let prio_all = model.priorities();
    let prio: Vec<u32> = columns.iter().map(|&c| prio_all[c]).collect();
    // The sensitivity floor is an RMS over points: the factor's singular values are sums in
    // quadrature over all rows, three per point.
    let floor = options.fit.min_sensitivity * (f.rows as f64 / 3.0).sqrt();
    let id = fit::identifiability_above(
        &f.r,
        &vec![1.0; columns.len()],
        &prio,
        options.fit.rank_tolerance,
        floor,
    )?;
    let free = id.free.iter().map(|&i| columns[i]).collect();
    let fixed = id
        .fixed
        .into_iter()
        .map(|f| {
            let mut combination = vec![0.0; model.parameter_count()];
            for (i, c) in f.combination.iter().enumerate() {
                // Back to parameter units: the factor was of scaled columns.
                combination[columns[i]] = c * scales[columns[i]] / scales[columns[f.index]];
            }
            fit::Fixed {
                index: columns[f.index],
                aliases: f.aliases.iter().map(|&a| columns[a]).collect(),
                combination,
            }
        })
        .collect();
    Ok((free, fixed))
}

/// Parameter estimates in the report's layout.
fn estimates(
    model: &Model,
    x: &[f64],
    fit: &FitOutcome,
    device_nominal: Isometry3<f64>,
    targets_nominal: &[Vector3<f64>],
) -> Vec<ParameterEstimate> {
    let params = model.parameters();
    let nominal = model.nominal();
    let position = |c: usize| fit.free.iter().position(|&f| f == c);
    let mut out = Vec::with_capacity(params.len());
    let mut done_blocks: Vec<Block> = Vec::new();
    for (c, p) in params.iter().enumerate() {
        match p.block {
            Block::Device | Block::Session(_) | Block::Base | Block::Tool | Block::Mount(_) => {
                if done_blocks.contains(&p.block) {
                    continue;
                }
                done_blocks.push(p.block);
                let idx = model.indices(|b| b == p.block);
                let nom = match p.block {
                    Block::Device => xyz_rpy(&device_nominal),
                    // The reference after the `nominal` step's rebase.
                    Block::Session(_) => xyz_rpy(&model.pose_at(&vec![0.0; x.len()], p.block)),
                    Block::Base => xyz_rpy(&nominal.base),
                    Block::Mount(b) => model.tree().branches().get(b).map_or_else(
                        || xyz_rpy(&Isometry3::identity()),
                        |br| xyz_rpy(&br.table.base),
                    ),
                    _ => xyz_rpy(&nominal.tool),
                };
                let est = xyz_rpy(&model.pose_at(x, p.block));
                let std = pose_std(model, x, fit, p.block, &idx);
                for (k, &i) in idx.iter().enumerate() {
                    out.push(ParameterEstimate {
                        name: params[i].name.clone(),
                        nominal: nom[k],
                        estimate: est[k],
                        std_error: std.as_ref().map(|s| s[k]),
                        free: position(i).is_some(),
                    });
                }
            }
            Block::Joint(r) => {
                let row = &nominal.rows[r];
                let nom = match p.field {
                    crate::model::Field::A => row.a,
                    crate::model::Field::Alpha => row.alpha,
                    crate::model::Field::D => row.d,
                    crate::model::Field::Theta => row.theta,
                    crate::model::Field::Beta => row.beta,
                    _ => 0.0,
                };
                out.push(ParameterEstimate {
                    name: p.name.clone(),
                    nominal: nom,
                    estimate: nom + x[c],
                    std_error: fit.std_errors[c],
                    free: position(c).is_some(),
                });
            }
            Block::Target(k) => {
                let axis = match p.field {
                    crate::model::Field::X => 0,
                    crate::model::Field::Y => 1,
                    _ => 2,
                };
                out.push(ParameterEstimate {
                    name: p.name.clone(),
                    nominal: targets_nominal.get(k).map_or(0.0, |t| t[axis]),
                    estimate: model.target_at(x, k)[axis],
                    std_error: fit.std_errors[c],
                    free: position(c).is_some(),
                });
            }
            Block::Effect(_) => out.push(ParameterEstimate {
                name: p.name.clone(),
                nominal: 0.0,
                estimate: x[c],
                std_error: fit.std_errors[c],
                free: position(c).is_some(),
            }),
        }
    }
    out
}

/// Standard errors of a pose block's `x y z rx ry rz` (absolute, roll-pitch-yaw), propagated
/// from the covariance of its six small-motion parameters by a central-difference Jacobian.
fn pose_std(
    model: &Model,
    x: &[f64],
    fit: &FitOutcome,
    block: Block,
    idx: &[usize],
) -> Option<[f64; 6]> {
    let cov = fit.covariance.as_ref()?;
    let pos: Vec<Option<usize>> = idx
        .iter()
        .map(|&i| fit.free.iter().position(|&f| f == i))
        .collect();
    if pos.iter().all(Option::is_none) {
        return None;
    }
    let h = 1e-6;
    let mut g = DMatrix::zeros(6, idx.len());
    let mut xp = x.to_vec();
    for (k, &i) in idx.iter().enumerate() {
        xp[i] = x[i] + h;
        let a = xyz_rpy(&model.pose_at(&xp, block));
        xp[i] = x[i] - h;
        let b = xyz_rpy(&model.pose_at(&xp, block));
        xp[i] = x[i];
        for r in 0..6 {
            let mut d = a[r] - b[r];
            if r >= 3 {
                // Angles wrap at ±pi.
                d = (d + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI)
                    - std::f64::consts::PI;
            }
            g[(r, k)] = d / (2.0 * h);
        }
    }
    let c = DMatrix::from_fn(idx.len(), idx.len(), |a, b| match (pos[a], pos[b]) {
        (Some(i), Some(j)) => cov[(i, j)],
        _ => 0.0,
    });
    let v = &g * c * g.transpose();
    Some(std::array::from_fn(|r| v[(r, r)].max(0.0).sqrt()))
}
#[cfg(test)]
mod tests {
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
}
