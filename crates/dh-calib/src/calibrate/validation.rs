//! Held-out errors: the Euclidean distances between modelled and measured points (metres) on
//! the validation split, or k-fold cross-validation over poses (samples sharing `config`, or
//! else the same joint values, stay in one fold; beyond [`CV_TRAINING_MAX`] samples, each fold
//! trained on about that many), and the noise floor they are compared with.

use super::*;
use std::collections::BTreeMap;

/// Calibration samples beyond which a cross-validation fold is fitted on a subsample of its
/// training samples (see [`Validation::CrossValidation`]): 100 000 points fix a few dozen
/// kinematic parameters far below any tracker's noise, and the folds then cost one fit of the
/// whole data between them instead of `folds` fits.
///
/// The folds share their subsample: a pool of `CV_TRAINING_MAX · k/(k − 1)` evenly spaced
/// samples (`k` folds; 125 000 for 5), each fold trained on its training samples among them
/// (about `CV_TRAINING_MAX`: exactly when the pose groups spread evenly over the folds). Every
/// fold starts at the fit of all samples, so the Gram matrix there of each fold's part of the
/// pool is made once (one pass over the pool), and each fold's first factor is that of the
/// other parts' sum instead of a pass over its own training samples.
pub const CV_TRAINING_MAX: usize = 100_000;

/// RMS per axis (radians) of the orientation residuals of the 6-DoF poses in `obs` (the
/// weight undone, see [`Observation::TargetPose`]); `None` without poses.
pub(crate) fn angle_rms(model: &Model, x: &[f64], obs: &[Observed]) -> Option<f64> {
    let (mut ss, mut n) = (0.0, 0usize);
    let mut r = [0.0; 6];
    for o in obs {
        if let Observation::TargetPose { weight, .. } = o.observation {
            model.residuals(x, o, &mut r);
            ss += r[3..].iter().map(|v| (v / weight).powi(2)).sum::<f64>();
            n += 3;
        }
    }
    (n > 0).then(|| (ss / n as f64).sqrt())
}

/// Held-out errors of some samples, in sample order: the position distance of each and, for a
/// sample that measures an orientation too, its orientation residual. The figures the report
/// lists are the distances' ([`set_val`]); the diagnosis's held-out test pairs the samples'
/// errors of both kinds, each over its own sigma ([`HeldOut::weighed`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct HeldOut {
    /// 3-D distance between model and measurement (metres).
    pub(crate) distances: Vec<f64>,
    /// Per sample: `None` for a point; for a 6-DoF pose, the norm of its orientation rows as
    /// the fit weighs them (`weight · ‖log(R_model R_measuredᵀ)‖`, metres: the angle over
    /// `sigma_rot`, times `sigma`) and, for a target pose, the angle itself (radians).
    /// Empty when no sample measures an orientation.
    pub(crate) turns: Vec<Option<(f64, Option<f64>)>>,
}

impl HeldOut {
    /// Each sample's error with its orientation weighed in, `sqrt(d² + (w θ)²)` (metres, the
    /// norm of the sample's residual rows as the fit weighs them): the distances themselves
    /// for points. What the held-out test compares.
    pub(crate) fn weighed(&self) -> Vec<f64> {
        if self.turns.is_empty() {
            return self.distances.clone();
        }
        self.distances
            .iter()
            .zip(&self.turns)
            .map(|(d, t)| match t {
                Some((w, _)) => d.hypot(*w),
                None => *d,
            })
            .collect()
    }

    /// RMS per axis (radians) of the orientation errors of the target poses, as
    /// [`angle_rms`]; `None` without them.
    pub(crate) fn angle_rms(&self) -> Option<f64> {
        let angles: Vec<f64> = self
            .turns
            .iter()
            .filter_map(|t| t.and_then(|t| t.1))
            .collect();
        (!angles.is_empty())
            .then(|| (angles.iter().map(|a| a * a).sum::<f64>() / (3 * angles.len()) as f64).sqrt())
    }

    /// Builds it from each sample's residual rows (`rows` of 3 or 6; `weight` the target
    /// pose's, when it is one).
    pub(crate) fn push(&mut self, r: &[f64], rows: usize, weight: Option<f64>) {
        self.distances.push(Vector3::new(r[0], r[1], r[2]).norm());
        self.turns.push((rows >= 6).then(|| {
            let t = Vector3::new(r[3], r[4], r[5]).norm();
            (t, weight.filter(|w| *w > 0.0).map(|w| t / w))
        }));
    }

    /// Drops [`HeldOut::turns`] when no sample has one, so that a point set's carries none.
    pub(crate) fn finish(mut self) -> HeldOut {
        if self.turns.iter().all(Option::is_none) {
            self.turns.clear();
        }
        self
    }
}

/// The weight of a target pose's orientation rows (`None` for other observations).
pub(crate) fn pose_weight(o: &Observed) -> Option<f64> {
    match o.observation {
        Observation::TargetPose { weight, .. } => Some(weight),
        _ => None,
    }
}

/// Held-out errors of the observations `obs[i]` for `i` in `at` at `x`, in parallel segments
/// for long lists.
pub(super) fn held_at(model: &Model, x: &[f64], obs: &[Observed], at: &[usize]) -> HeldOut {
    let rows = fit::in_segments(at, |i| {
        let mut r = [0.0; 6];
        model.residuals(x, &obs[*i], &mut r);
        (
            r,
            obs[*i].observation.residual_count(),
            pose_weight(&obs[*i]),
        )
    });
    let mut out = HeldOut::default();
    for (r, n, w) in &rows {
        out.push(r, *n, *w);
    }
    out.finish()
}

/// Distance (metres) between model and measurement of every observation in `obs`.
pub(crate) fn distances(model: &Model, x: &[f64], obs: &[Observed]) -> Vec<f64> {
    let idx: Vec<usize> = (0..obs.len()).collect();
    distances_at(model, x, obs, &idx)
}

/// [`distances`] of the observations `obs[i]` for `i` in `at`, in parallel segments for long
/// lists.
pub(super) fn distances_at(model: &Model, x: &[f64], obs: &[Observed], at: &[usize]) -> Vec<f64> {
    fit::in_segments(at, |i| {
        let mut r = [0.0; 6];
        model.residuals(x, &obs[*i], &mut r);
        Vector3::new(r[0], r[1], r[2]).norm()
    })
}

/// The position residuals (model minus measured, device frame, metres) of every observation
/// in `obs` at `x`, in parallel segments for long lists (each the same value as on one thread).
/// Their norms are [`distances`].
pub(crate) fn residual_vectors(model: &Model, x: &[f64], obs: &[Observed]) -> Vec<Vector3<f64>> {
    fit::in_segments(obs, |o| {
        let mut r = [0.0; 6];
        model.residuals(x, o, &mut r);
        Vector3::new(r[0], r[1], r[2])
    })
}

/// Distances of the validation samples at `x`. A target that no calibration sample measured
/// (a test point: another reflector, mounted only for validation) has no estimated position on
/// the tip, so its validation samples first locate it: the point `p` in the tip frame that
/// minimises `Σ |t_i + s_i R_i p − m_i|²` over them (closed form, 3 parameters, as a tool
/// is taught), and they are then compared with the model at that point. The figure then
/// measures how well the model predicts the target's motion between poses, the quantity a
/// test set of a new tool can measure.
pub(super) fn split_distances(model: &Model, x: &[f64], prep: &Prepared) -> Vec<f64> {
    split_held(model, x, prep).distances
}

/// [`split_distances`] with the orientation errors of the 6-DoF samples ([`HeldOut`]; a sample
/// of a session no calibration sample saw is compared by its position alone).
pub(super) fn split_held(model: &Model, x: &[f64], prep: &Prepared) -> HeldOut {
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
    let mut out = HeldOut::default();
    for o in &prep.val {
        match &o.observation {
            _ if unseen.iter().any(|(s, _)| *s == o.session) => {
                let frame = unseen
                    .iter()
                    .find(|(s, _)| *s == o.session)
                    .map(|(_, t)| *t);
                out.distances.push(crate::sessions::distance_in(
                    model,
                    x,
                    o,
                    &frame.unwrap_or_default(),
                ));
                out.turns.push(None);
            }
            Observation::Point { target, point } => match located.get(*target).copied().flatten() {
                Some(p) => {
                    let tip = model.tip_in(x, &o.q, model.target_chain(*target), o.session);
                    let s = model.scale_at(x, &o.q);
                    out.distances
                        .push((tip.translation.vector + tip.rotation * p * s - point).norm());
                    out.turns.push(None);
                }
                None => {
                    model.residuals(x, o, &mut r);
                    out.push(&r, 3, None);
                }
            },
            Observation::Pose(_) | Observation::TargetPose { .. } => {
                model.residuals(x, o, &mut r);
                out.push(&r, o.observation.residual_count(), pose_weight(o));
            }
        }
    }
    out.finish()
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
pub(super) fn evenly_spaced(all: Vec<usize>, keep: usize) -> Vec<usize> {
    if all.len() <= keep || keep == 0 {
        return all;
    }
    let n = all.len();
    (0..keep).map(|k| all[k * n / keep]).collect()
}

/// Samples of each (session, target) kept in a coarse subset whatever its share: enough for
/// the stratum's own parameters (a target's 3, a session frame's 6) far above the noise.
pub(super) const COARSE_STRATUM_MIN: usize = 1000;

/// At most about `keep` calibration samples of `cal`, evenly spaced within each (session,
/// target) stratum in proportion to its size, with at least [`COARSE_STRATUM_MIN`] of each
/// (all of a smaller one): a target or session with few samples is never left out, which
/// would leave its parameters unidentified in the coarse fit. Sorted; for a set of one
/// session and one target, [`evenly_spaced`] itself.
pub(super) fn coarse_subset(cal: &[Observed], keep: usize) -> Vec<usize> {
    let mut place: HashMap<(usize, usize), usize> = HashMap::new();
    let mut strata: Vec<Vec<usize>> = Vec::new();
    // The last sample's stratum: runs of one session and target are the rule, so most samples
    // skip the map.
    let mut last: Option<((usize, usize), usize)> = None;
    for (i, o) in cal.iter().enumerate() {
        let target = match o.observation {
            Observation::Point { target, .. } | Observation::TargetPose { target, .. } => target,
            Observation::Pose(_) => usize::MAX,
        };
        let key = (o.session, target);
        let k = match last {
            Some((previous, k)) if previous == key => k,
            _ => {
                let next = strata.len();
                let k = *place.entry(key).or_insert(next);
                if k == next {
                    strata.push(Vec::new());
                }
                last = Some((key, k));
                k
            }
        };
        strata[k].push(i);
    }
    if strata.len() == 1 {
        return evenly_spaced(strata.pop().unwrap_or_default(), keep);
    }
    let n = cal.len().max(1);
    let mut out: Vec<usize> = strata
        .into_iter()
        .flat_map(|v| {
            let share = (keep * v.len()).div_ceil(n).max(COARSE_STRATUM_MIN);
            evenly_spaced(v, share)
        })
        .collect();
    out.sort_unstable();
    out
}

/// How cross-validation's folds are fitted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Folds {
    /// Each fold refitted by Levenberg-Marquardt from the full fit: the reported figures.
    Refit,
    /// Each fold one Gauss-Newton step from the full fit (`one_step`): the diagnosis's
    /// candidate trials, compared with each other and with the fit they extend.
    OneStep,
    /// None yet: the step's held-out figures are left empty for the caller to fill in.
    Later,
}

/// Puts the validation figures of the held-out errors `held` into `report`.
pub(crate) fn set_val(report: &mut StepReport, held: &HeldOut) {
    let val = Stats::of(&held.distances);
    report.val_rms = val.map(|v| v.rms);
    report.val_mean = val.map(|v| v.mean);
    report.val_max = val.map(|v| v.max);
    report.val_angle_rms = held.angle_rms();
}

pub(crate) struct StepResult {
    pub(crate) outcome: FitOutcome,
    pub(crate) report: StepReport,
    /// Held-out errors of every validation sample (split) or calibration sample
    /// (cross-validation), in sample order; empty without validation.
    pub(crate) held_out: HeldOut,
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
) -> Result<HeldOut, CalibError> {
    match validation {
        Validation::Split { .. } => Ok(split_held(model, x, prep)),
        Validation::CrossValidation {
            folds,
            training_subsample,
            ..
        } => {
            let folds = *folds;
            let fold_of = |i: usize| prep.groups[i] % folds;
            // Every fold starts at `x`: its first factor is of rows made once for all folds.
            let at_x = if training_subsample.is_none() {
                super::rows_at::RowsAt::new(model, &prep.cal, x, free)
            } else {
                None
            };
            // Beyond `CV_TRAINING_MAX` samples, the folds train on their samples among one pool
            // of evenly spaced ones; the Gram matrix at `x` of each fold's part of the pool is
            // made once, and each fold's first factor is that of the other parts' sum.
            let pool = training_subsample.map(|keep| {
                let size = (keep * folds).div_ceil(folds.saturating_sub(1).max(1));
                evenly_spaced((0..prep.cal.len()).collect(), size)
            });
            let parts = match &pool {
                Some(pool) => Some(fit::parallel_map(folds, |f| {
                    let part: Vec<usize> =
                        pool.iter().copied().filter(|&i| fold_of(i) == f).collect();
                    let p = SubsetProblem {
                        model,
                        observations: &prep.cal,
                        subset: &part,
                    };
                    fit::GramSum::of(&p, x, free, scales)
                })?),
                None => None,
            };
            // The folds are independent fits: run on every core, gathered in fold order.
            let per_fold = fit::parallel_map(folds, |f| {
                let at: Vec<usize> = (0..prep.cal.len()).filter(|&i| fold_of(i) == f).collect();
                let train: Vec<usize> = match &pool {
                    Some(pool) => pool.iter().copied().filter(|&i| fold_of(i) != f).collect(),
                    None => (0..prep.cal.len()).filter(|&i| fold_of(i) != f).collect(),
                };
                let p = SubsetProblem {
                    model,
                    observations: &prep.cal,
                    subset: &train,
                };
                let first = match (&at_x, &parts) {
                    (Some(rows), _) => Some(fit::factor(&rows.subset(&train), x, free, scales)?),
                    (None, Some(parts)) => trained_on_others(parts, f),
                    (None, None) => None,
                };
                // Only the fold's parameters are read (not its outcome's covariance).
                let fold = fit::solve_point_from(&p, x, free, scales, fit_options, first)?;
                let d = held_at(model, &fold, &prep.cal, &at);
                Ok((at, d))
            })?;
            let mut d = vec![0.0; prep.cal.len()];
            let mut turns = vec![None; prep.cal.len()];
            for (at, fold) in per_fold {
                let fold_turns = fold.turns.into_iter().chain(std::iter::repeat(None));
                for ((i, v), t) in at.into_iter().zip(fold.distances).zip(fold_turns) {
                    d[i] = v;
                    turns[i] = t;
                }
            }
            Ok(HeldOut {
                distances: d,
                turns,
            }
            .finish())
        }
        Validation::None => Ok(HeldOut::default()),
    }
}

/// The factor of every part of `parts` but `fold`'s, summed in part order; `None` when that
/// sum cannot give it (the fold's fit then makes its own, see [`fit::GramSum::factor`]).
fn trained_on_others(parts: &[fit::GramSum], fold: usize) -> Option<fit::Factor> {
    let mut others = parts.iter().enumerate().filter(|(k, _)| *k != fold);
    let (_, first) = others.next()?;
    let mut sum = first.clone();
    for (_, part) in others {
        sum.add(part.clone());
    }
    sum.factor()
}

/// The noise floor of a fit with `p` free parameters, or `None` ([`floor_or_why`] says why).
#[cfg(test)]
pub(super) fn noise_floor(
    prep: &Prepared,
    options: &CalibrationOptions,
    p: usize,
) -> Option<NoiseFloor> {
    floor_or_why(prep, options, p).ok()
}

/// Why a fit has no noise floor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum NoFloor {
    /// No known sigma and no repeated poses.
    Unknown,
    /// Repeated poses whose pure error (metres per axis) is below [`crate::MIN_SIGMA`]: copies
    /// of one record, not repeated measurements; no floor can be estimated from them.
    IdenticalRepeats(f64),
}

/// The noise floor of a fit with `p` free parameters: from the `sigma` option, the samples'
/// own sigmas, or the pooled pure error of repeated poses; [`NoFloor`] says why there is none.
pub(super) fn floor_or_why(
    prep: &Prepared,
    options: &CalibrationOptions,
    p: usize,
) -> Result<NoiseFloor, NoFloor> {
    let n = prep.cal.len();
    if n == 0 {
        return Err(NoFloor::Unknown);
    }
    let (e2, source) = if let Some(s) = options.sigma {
        (3.0 * s * s, NoiseSource::Given)
    } else if prep.sigmas.iter().all(|s| s.is_some()) {
        let sum: f64 = prep.sigmas.iter().flatten().map(|s| s.norm_squared()).sum();
        (sum / n as f64, NoiseSource::Samples)
    } else {
        // Pooled pure error of repeated points, ordered by key: the sum is the same in every
        // process (a hash map's order is not, and the last bit of the floor moved with it).
        let mut groups: BTreeMap<(usize, usize), Vec<Vector3<f64>>> = BTreeMap::new();
        for (o, key) in prep.cal.iter().zip(prep.repeat_keys()) {
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
            return Err(NoFloor::Unknown);
        }
        // `ss / dof` is the expected squared 3-D error of one point: 3 sigma² per axis.
        let per_axis = (ss / dof as f64 / 3.0).sqrt();
        if per_axis < crate::MIN_SIGMA {
            return Err(NoFloor::IdenticalRepeats(per_axis));
        }
        (ss / dof as f64, NoiseSource::Repeats { groups: count, dof })
    };
    // 3 per point, 6 per 6-DoF target pose (a tip pose counts its position only, as before).
    let m: usize = prep
        .cal
        .iter()
        .map(|o| match o.observation {
            Observation::TargetPose { .. } => 6,
            _ => 3,
        })
        .sum();
    let factor = (1.0 - p as f64 / m as f64).max(0.0);
    let angle = &prep.sigmas_rot;
    let angle_rms = (!angle.is_empty())
        .then(|| (angle.iter().map(|s| s * s).sum::<f64>() / angle.len() as f64 * factor).sqrt());
    Ok(NoiseFloor {
        rms: (e2 * factor).sqrt(),
        sigma: (e2 / 3.0).sqrt(),
        source,
        angle_rms,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::{Measurements, Sample};

    /// A fold's first factor from the other folds' parts of the pool (`trained_on_others`) is
    /// the factor of the fold's own training samples: the same rows summed in another order,
    /// so `R` and `Qᵀr` agree with the QR of those rows up to the signs of their rows, to 1e-9
    /// of their largest element; and the part left out is the fold's own.
    #[test]
    fn a_fold_factored_from_the_other_parts_has_its_own_factor() {
        let table = crate::test_robots::ur5();
        let model = Model::new(&table, &["t".into()], &Default::default()).unwrap();
        let x: Vec<f64> = (0..model.parameter_count())
            .map(|i| 1e-3 * (i as f64 * 0.7).sin())
            .collect();
        let cal: Vec<Observed> = (0..3001)
            .map(|i| {
                let q: Vec<f64> = (0..6)
                    .map(|j| ((i * 6 + j) as f64 * 1.3).sin() * 2.5)
                    .collect();
                let point = Vector3::new((i as f64).sin(), (i as f64).cos(), 0.5);
                Observed::new(q, Observation::Point { target: 0, point })
            })
            .collect();
        // The device frame and the target: 9 well-identified columns.
        let free = model.indices(|b| matches!(b, Block::Device | Block::Target(_)));
        assert_eq!(free.len(), 9);
        let scales = model.scales();
        let folds = 5;
        let fold_of = |i: usize| (i * 7) % folds;
        let pool = evenly_spaced((0..cal.len()).collect(), 2000);
        let parts: Vec<fit::GramSum> = (0..folds)
            .map(|f| {
                let part: Vec<usize> = pool.iter().copied().filter(|&i| fold_of(i) == f).collect();
                let p = SubsetProblem {
                    model: &model,
                    observations: &cal,
                    subset: &part,
                };
                fit::GramSum::of(&p, &x, &free, &scales).unwrap()
            })
            .collect();
        for f in 0..folds {
            let train: Vec<usize> = pool.iter().copied().filter(|&i| fold_of(i) != f).collect();
            let p = SubsetProblem {
                model: &model,
                observations: &cal,
                subset: &train,
            };
            let want = fit::factor(&p, &x, &free, &scales).unwrap();
            let got = trained_on_others(&parts, f).expect("well conditioned");
            assert_eq!(got.rows, want.rows);
            assert!((got.ssr - want.ssr).abs() <= 1e-12 * want.ssr);
            let scale = want.r.abs().max();
            for i in 0..free.len() {
                let sign = got.r[(i, i)].signum() * want.r[(i, i)].signum();
                for j in 0..free.len() {
                    let d = (got.r[(i, j)] - sign * want.r[(i, j)]).abs();
                    assert!(d < 1e-9 * scale, "fold {f}: R[{i},{j}] off by {d}");
                }
                let d = (got.qtr[i] - sign * want.qtr[i]).abs();
                assert!(d < 1e-9 * scale, "fold {f}: qtr[{i}] off by {d}");
            }
        }
    }

    /// The pooled pure error of many repeated poses is summed in the same order every time:
    /// the floor is the same bit for bit in every run (it was summed in a hash map's order,
    /// which differs between maps and processes).
    #[test]
    fn the_noise_floor_of_repeats_is_the_same_every_time() {
        let tree = crate::tree::DhTree::serial(&crate::test_robots::ur5());
        let samples = (0..600)
            .map(|i| Sample {
                config: Some(format!("p{}", i / 3).into()),
                // Three repeats of each pose, a little apart, by irrational steps.
                ..Sample::test_point(
                    &[0.01 * (i / 3) as f64, 0.1, 0.2, 0.3, 0.4, 0.5],
                    Vector3::new(
                        (i as f64 * 0.618).fract(),
                        (i as f64 * 0.414).fract(),
                        (i as f64 * 0.732).fract(),
                    ) * 1e-4,
                    i + 2,
                )
            })
            .collect();
        let data = Measurements::test_ur5(samples);
        let prep = crate::prepare::prepare(&tree, &data, None, false).unwrap();
        let options = CalibrationOptions::default();
        let first = noise_floor(&prep, &options, 10).unwrap();
        assert!(matches!(
            first.source,
            NoiseSource::Repeats {
                groups: 200,
                dof: 400
            }
        ));
        for _ in 0..20 {
            let again = noise_floor(&prep, &options, 10).unwrap();
            assert_eq!(again.rms.to_bits(), first.rms.to_bits());
            assert_eq!(again.sigma.to_bits(), first.sigma.to_bits());
        }
    }
}
