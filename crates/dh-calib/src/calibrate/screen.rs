//! The outlier screen of a calibration ([`screen`]; the procedure and its options are
//! [`crate::outliers`]'s): the geometric fit iterated with the flagged points left out.
//! Residuals in the device frame, metres.

use std::collections::BTreeSet;

use super::*;
use crate::data::Split;
use crate::outliers::{
    threshold, GivenBack, Judged, Outlier, OutlierReport, ScaleSource, CHI2_3_MEDIAN, MAX_ROUNDS,
    MIN_SCALE,
};

fn median(mut v: Vec<f64>) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    // The middle order statistics without a sort (linear time: millions of residuals).
    let n = v.len();
    let (below, &mut upper, _) = v.select_nth_unstable_by(n / 2, f64::total_cmp);
    Some(if n % 2 == 1 {
        upper
    } else {
        let lower = below.iter().copied().max_by(f64::total_cmp)?;
        0.5 * (lower + upper)
    })
}

/// Finds the outliers of `data` against the geometric model of `tree` (see the module docs),
/// and with `options.effects` against the geometry and those effects, each round fitting
/// every parameter the kept points identify: a pose that only an unmodelled effect puts far
/// off the geometric fit (a gravity-loaded pose before the compliance is added) is judged
/// against the model that has the effect.
///
/// # Errors
/// [`CalibError::BadOption`] for a level outside (0, 1); those of
/// [`crate::calibrate::calibrate_tree`] for the data as given or without the flagged points.
pub fn screen(
    tree: &DhTree,
    data: &Measurements,
    options: &CalibrationOptions,
) -> Result<OutlierReport, CalibError> {
    check_level(options)?;
    screen_from(tree, data, options, None, &options.effects, None)
}

/// Refuses an outlier level outside (0, 1).
pub(crate) fn check_level(options: &CalibrationOptions) -> Result<(), CalibError> {
    let level = options.outliers.level;
    if !(level > 0.0 && level < 1.0) {
        return Err(CalibError::BadOption {
            what: "outlier level".into(),
            reason: format!("expected a level in (0, 1), found {level}"),
        });
    }
    Ok(())
}

/// How a screen judges the points of `data` at one fit: where each sample went, the
/// thresholds, the known noise, the points that may be flagged (those the judgement `before`
/// left out, when given: a second judgement gives points back, never takes more) and those
/// whose figures it reports (those `before` left out or gave back).
struct Judge<'a> {
    data: &'a Measurements,
    sigma: Option<f64>,
    before: Option<&'a OutlierReport>,
    within: Option<BTreeSet<usize>>,
    watched: BTreeSet<usize>,
    labels: Vec<String>,
    /// Where each sample of `data` went: (validation?, index in its list). Listed only when
    /// there are validation samples; else sample `i` is calibration sample `i` (a list held
    /// 32 MB on 2 000 000 samples).
    places: Option<Vec<(bool, usize)>>,
    t_cal: f64,
    t_val: f64,
}

/// One judgement of every point at one fit.
struct Verdicts {
    /// The samples (calibration and validation) beyond their threshold that may be flagged.
    now: BTreeSet<usize>,
    found: Vec<Outlier>,
    /// The watched samples' residual (metres) and size in units of the scale.
    seen: std::collections::HashMap<usize, (f64, f64)>,
    source: ScaleSource,
    robust: f64,
}

impl<'a> Judge<'a> {
    fn new(
        data: &'a Measurements,
        options: &CalibrationOptions,
        effects: &[Arc<dyn Effect>],
        before: Option<&'a OutlierReport>,
    ) -> Self {
        let within: Option<BTreeSet<usize>> =
            before.map(|b| b.outliers.iter().map(|o| o.sample).collect());
        let watched: BTreeSet<usize> = before
            .iter()
            .flat_map(|b| {
                b.outliers
                    .iter()
                    .map(|o| o.sample)
                    .chain(b.given_back.iter().map(|g| g.sample))
            })
            .collect();
        let labels: Vec<String> = effects
            .iter()
            .map(|e| crate::effects::label_of(e.as_ref()))
            .collect();
        let n = data.samples.len();
        let nv = data
            .samples
            .iter()
            .filter(|s| s.split == Split::Validation)
            .count();
        let places: Option<Vec<(bool, usize)>> = (nv > 0).then(|| {
            let (mut c, mut v) = (0, 0);
            data.samples
                .iter()
                .map(|s| match s.split {
                    Split::Calibration => {
                        c += 1;
                        (false, c - 1)
                    }
                    Split::Validation => {
                        v += 1;
                        (true, v - 1)
                    }
                })
                .collect()
        });
        let level = options.outliers.level;
        Self {
            data,
            sigma: options.sigma,
            before,
            within,
            watched,
            labels,
            places,
            t_cal: threshold(n - nv, level),
            t_val: threshold(nv, level),
        }
    }

    /// Whether `data` has validation samples.
    fn has_validation(&self) -> bool {
        self.places.is_some()
    }

    fn place(&self, i: usize) -> (bool, usize) {
        self.places.as_ref().map_or((false, i), |p| p[i])
    }

    /// The known per-axis noise of sample `i` (computed where read: a vector of them held
    /// 64 MB on 2 000 000 samples).
    fn known(&self, i: usize) -> Option<Vector3<f64>> {
        match self.sigma {
            Some(v) => Some(Vector3::repeat(v)),
            None => self.data.samples[i]
                .sigma
                .filter(|v| v.iter().all(|a| *a > 0.0)),
        }
    }

    /// Every point judged at a fit: `cal_r` and `val_r` the residual vectors of every
    /// calibration and validation sample of `data` there (metres, device frame), `flagged`
    /// the calibration samples the fit left out, `free` its free parameters and `n_kept` the
    /// calibration samples it fitted.
    fn judge(
        &self,
        cal_r: &[Vector3<f64>],
        val_r: &[Vector3<f64>],
        flagged: &BTreeSet<usize>,
        free: usize,
        n_kept: usize,
    ) -> Verdicts {
        let n = self.data.samples.len();
        let p = free as f64;
        let n_kept = n_kept.max(1) as f64;
        let kept_norms: Vec<f64> = (0..n)
            .map(|i| self.place(i))
            .enumerate()
            .filter(|(i, (v, _))| !v && !flagged.contains(i))
            .map(|(_, (_, k))| cal_r[k].norm())
            .collect();
        let correction = (1.0 - p / (3.0 * n_kept)).max(0.1).sqrt();
        let robust =
            (median(kept_norms).unwrap_or(0.0) / CHI2_3_MEDIAN.sqrt() / correction).max(MIN_SCALE);
        // Predictions of poses the fit never saw may all be off (an extrapolation): the
        // validation points are judged against their own bulk too, so that only a point far
        // from both is named and a uniformly bad validation stays in the figures.
        let val_robust =
            median(val_r.iter().map(|r| r.norm()).collect()).unwrap_or(0.0) / CHI2_3_MEDIAN.sqrt();
        let standardised = |i: usize, r: &Vector3<f64>, floor: f64| -> (f64, ScaleSource) {
            match self.known(i) {
                Some(s) if s.norm() / 3f64.sqrt() >= floor => {
                    (r.component_div(&s).norm(), ScaleSource::Known)
                }
                _ => (r.norm() / floor, ScaleSource::Robust),
            }
        };
        let mut now = BTreeSet::new();
        let mut found = Vec::new();
        let mut seen = std::collections::HashMap::new();
        let mut source = ScaleSource::Robust;
        for (i, (v, k)) in (0..n).map(|i| self.place(i)).enumerate() {
            let r = if v { &val_r[k] } else { &cal_r[k] };
            let t = if v {
                standardised(i, r, robust.max(val_robust)).0
            } else {
                let (t, src) = standardised(i, r, robust);
                source = src;
                t
            };
            if self.watched.contains(&i) {
                seen.insert(i, (r.norm(), t));
            }
            let eligible = self.within.as_ref().is_none_or(|w| w.contains(&i));
            if eligible && t > if v { self.t_val } else { self.t_cal } {
                now.insert(i);
                let s = &self.data.samples[i];
                found.push(Outlier {
                    sample: i,
                    line: s.line,
                    config: s.config.as_deref().map(str::to_string),
                    target: self.data.targets.get(s.target).cloned().unwrap_or_default(),
                    validation: v,
                    residual: r.norm(),
                    sigmas: t,
                    first: self.before.and_then(|b| {
                        b.outliers
                            .iter()
                            .find(|o| o.sample == i)
                            .map(|o| o.first_judged(b))
                    }),
                });
            }
        }
        Verdicts {
            now,
            found,
            seen,
            source,
            robust,
        }
    }

    /// The points `before` gave back or left out that `verdicts` does not flag, with their
    /// figures against both models, in file order (empty for a first judgement).
    fn given_back(&self, verdicts: &Verdicts) -> Vec<GivenBack> {
        let Some(b) = self.before else {
            return Vec::new();
        };
        let judged = |i: usize, validation: bool| {
            let (residual, sigmas) = verdicts.seen.get(&i).copied().unwrap_or((0.0, 0.0));
            Judged {
                residual,
                sigmas,
                threshold: if validation { self.t_val } else { self.t_cal },
                effects: self.labels.clone(),
            }
        };
        let mut g: Vec<GivenBack> = b
            .given_back
            .iter()
            .map(|g| GivenBack {
                after: judged(g.sample, g.validation),
                ..g.clone()
            })
            .chain(
                b.outliers
                    .iter()
                    .filter(|o| !verdicts.now.contains(&o.sample))
                    .map(|o| GivenBack {
                        sample: o.sample,
                        line: o.line,
                        config: o.config.clone(),
                        target: o.target.clone(),
                        validation: o.validation,
                        before: o.first_judged(b),
                        after: judged(o.sample, o.validation),
                    }),
            )
            .collect();
        g.sort_by_key(|g| g.sample);
        g
    }
}

/// A judgement again that left out the same points as the one before it: the figures of the
/// points given back before (against the model of this judgement), and its calibration
/// threshold (in units of the scale).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Confirmation {
    pub(crate) given_back: Vec<GivenBack>,
    pub(crate) threshold: f64,
}

impl Confirmation {
    /// The confirmation a screen's report makes.
    pub(crate) fn of(report: &OutlierReport) -> Self {
        Self {
            given_back: report.given_back.clone(),
            threshold: report.threshold,
        }
    }
}

/// Whether the points `before` left out are outliers of a fit the caller already has, without
/// a fit of its own: `x` the fit of the geometry and `effects` (of `session`'s model, whose
/// other effects are at zero) to the calibration samples of `data` that `before` kept, with
/// `free` parameters. Every point is judged as [`screen_from`] judges it (the same scale,
/// thresholds and known noise); when every point `before` left out, calibration and
/// validation, is beyond its threshold there, that is the judgement [`screen_from`] makes
/// from those points out (its first round, settled), and its confirmation is returned.
/// `None` when one is not (the caller then judges by [`screen_from`], whose rounds may settle
/// elsewhere), or when `before` left nothing out or kept its points.
///
/// # Errors
/// Those of preparing `data` (rows, joint names).
pub(crate) fn confirmed_at(
    tree: &DhTree,
    data: &Measurements,
    options: &CalibrationOptions,
    (session, x, free): (&Session<'_>, &[f64], usize),
    effects: &[Arc<dyn Effect>],
    before: &OutlierReport,
) -> Result<Option<Confirmation>, CalibError> {
    let left_out = before.left_out();
    if left_out.is_empty() {
        return Ok(None);
    }
    let judge = Judge::new(data, options, effects, Some(before));
    let directions = session
        .model
        .effects()
        .iter()
        .any(|(e, _)| e.uses_sequence());
    let full = prepare(tree, data, None, directions)?;
    let flagged: BTreeSet<usize> = left_out
        .iter()
        .copied()
        .filter(|&i| !judge.place(i).0)
        .collect();
    let n_kept = full.cal.len() - flagged.len();
    if n_kept != session.prep.cal.len() {
        return Ok(None);
    }
    let cal_r = residual_vectors(&session.model, x, &full.cal);
    let val_r = residual_vectors(&session.model, x, &full.val);
    let verdicts = judge.judge(&cal_r, &val_r, &flagged, free, n_kept);
    if verdicts.now != left_out {
        return Ok(None);
    }
    Ok(Some(Confirmation {
        given_back: judge.given_back(&verdicts),
        threshold: judge.t_cal,
    }))
}

/// [`screen`] against the geometry and `effects`, flagging only the samples (calibration and
/// validation) that the judgement `before` left out when given (a second judgement gives
/// points back, never takes more): the report's [`OutlierReport::given_back`] lists those it
/// gives back with their figures against both models, and carries `before`'s, judged against
/// this model. Its first round is `first` (used only without `effects`): a session of all of `data` (prepared in its own order) whose geometric
/// step has run. Its calibration samples are those the first round fits, and its geometric
/// parameters are fitted without effects, so the round needs no fit of its own (on millions
/// of samples, the fit is most of a calibration's time).
pub(crate) fn screen_from(
    tree: &DhTree,
    data: &Measurements,
    options: &CalibrationOptions,
    first: Option<(&Session<'_>, &Geometric)>,
    effects: &[Arc<dyn Effect>],
    before: Option<&OutlierReport>,
) -> Result<OutlierReport, CalibError> {
    let first = first.filter(|_| effects.is_empty());
    let judge = Judge::new(data, options, effects, before);
    let level = options.outliers.level;
    let own_full;
    let full = match first {
        Some((s, _)) => &s.prep,
        None => {
            own_full = prepare(tree, data, None, effects.iter().any(|e| e.uses_sequence()))?;
            &own_full
        }
    };
    let screen_options = CalibrationOptions {
        effects: vec![],
        ..options.clone()
    };
    // The file's sequence, for effects that read the order of the poses: a sample left out
    // was still visited.
    let sequence = if effects.iter().any(|e| e.uses_sequence()) {
        Some(crate::prepare::sequence_of(
            &crate::prepare::rows_of(tree, data)?,
            data,
        ))
    } else {
        None
    };
    let mut flagged: BTreeSet<usize> = BTreeSet::new();
    let mut rms_with = None;
    let mut rounds = 0;
    loop {
        rounds += 1;
        let own;
        let (session, x, free, rms) = match first {
            Some((s, g)) if flagged.is_empty() => {
                (s, g.last.outcome.x.clone(), g.free.len(), g.last.report.rms)
            }
            _ => {
                // The data themselves while nothing is left out and all are calibration
                // samples (no copy of millions of samples), else the calibration samples not
                // flagged.
                let keep = |i: usize, s: &crate::data::Sample| {
                    s.split == Split::Calibration && !flagged.contains(&i)
                };
                let kept = if flagged.is_empty() && !judge.has_validation() {
                    std::borrow::Cow::Borrowed(data)
                } else {
                    std::borrow::Cow::Owned(data.filtered(keep))
                };
                let kept_sequence = sequence
                    .as_ref()
                    .map(|full| crate::prepare::kept_sequence(full, data, keep));
                let mut session = Session::new(
                    tree,
                    &kept,
                    &screen_options,
                    effects,
                    kept_sequence.as_deref(),
                )?;
                session.validation = Validation::None;
                let geo = session.geometric()?;
                let (x, free, rms) = if effects.is_empty() {
                    (geo.last.outcome.x, geo.free.len(), geo.last.report.rms)
                } else {
                    let all: Vec<usize> = (0..session.model.parameter_count()).collect();
                    let start = super::shape_start(&session, &geo.last.outcome.x, &all)?;
                    let (free, _) = session.identify(&start, &all)?;
                    let step = session.step("effects", &start, &free, geo.steps.last())?;
                    (step.outcome.x, free.len(), step.report.rms)
                };
                own = session;
                (&own, x, free, rms)
            }
        };
        let x = &x;
        rms_with.get_or_insert(rms);
        // The first round's session reads its own samples: their residuals at its fit are
        // those its step's distances read (computed once).
        let cal_r = if std::ptr::eq(&session.prep, full) {
            session.position_residuals(x)
        } else {
            Arc::new(residual_vectors(&session.model, x, &full.cal))
        };
        let val_r = residual_vectors(&session.model, x, &full.val);
        // The first round's session is the one `full` belongs to, at its own fit: its
        // distances are the norms of `cal_r`.
        let own_fit = first.is_some() && flagged.is_empty();
        let verdicts = judge.judge(&cal_r, &val_r, &flagged, free, session.prep.cal.len());
        let now_cal: BTreeSet<usize> = verdicts
            .now
            .iter()
            .copied()
            .filter(|&i| !judge.place(i).0)
            .collect();
        let settled = now_cal == flagged;
        if settled || rounds >= MAX_ROUNDS {
            let given_back = judge.given_back(&verdicts);
            let known_scale = (0..data.samples.len())
                .filter_map(|i| judge.known(i))
                .map(|s| s.norm() / 3f64.sqrt())
                .fold(0.0, f64::max);
            let without = if own_fit {
                cal_r.iter().map(|r| r.norm()).collect()
            } else {
                distances(&session.model, x, &session.prep.cal)
            };
            return Ok(OutlierReport {
                level,
                scale: if verdicts.source == ScaleSource::Known {
                    known_scale
                } else {
                    verdicts.robust
                },
                source: verdicts.source,
                threshold: judge.t_cal,
                validation_threshold: judge.t_val,
                outliers: verdicts.found,
                given_back,
                kept: options.outliers.keep,
                rms_with: rms_with.unwrap_or(rms),
                rms_without: Stats::of(&without).map_or(0.0, |s| s.rms),
                rounds,
                converged: settled,
                effects: judge.labels,
            });
        }
        flagged = now_cal;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simulate::{simulate, Errors, SimulationOptions};

    /// A UR5 set of 60 poses (20 µm per axis, a fifth held out) with two lost beams in the
    /// calibration points (3 mm and 2 mm) and the screen's judgement of it.
    fn lost_beams() -> (DhTree, Measurements, CalibrationOptions, OutlierReport) {
        let table = crate::test_robots::ur5();
        let (mut data, _) = simulate(
            &table,
            &SimulationOptions {
                seed: 4711,
                poses: 60,
                sigma: 2e-5,
                errors: Errors::Random {
                    length: 5e-4,
                    angle: 1e-3,
                },
                validation_fraction: 0.2,
                ..Default::default()
            },
        )
        .expect("a simulated set");
        let cal: Vec<usize> = (0..data.samples.len())
            .filter(|&i| data.samples[i].split == Split::Calibration)
            .collect();
        data.samples[cal[3]].point += Vector3::new(3e-3, 0.0, 0.0);
        data.samples[cal[20]].point += Vector3::new(0.0, -2e-3, 0.0);
        let tree = DhTree::serial(&table);
        let options = CalibrationOptions::default();
        let report = screen(&tree, &data, &options).expect("a screen");
        assert_eq!(
            report.left_out(),
            BTreeSet::from([cal[3], cal[20]]),
            "the lost beams and only they"
        );
        (tree, data, options, report)
    }

    /// The fit of `data` without the points `report` left out, and its confirmation of them.
    fn confirm(
        tree: &DhTree,
        data: &Measurements,
        options: &CalibrationOptions,
        report: &OutlierReport,
    ) -> Option<Confirmation> {
        let kept = report.without(data);
        let mut session = Session::new(tree, &kept, options, &[], None).expect("a session");
        let geo = session.geometric().expect("a fit");
        let at = (&session, &geo.last.outcome.x[..], geo.free.len());
        confirmed_at(tree, data, options, at, &[], report).expect("a judgement")
    }

    /// What the screen settled on is confirmed at the fit without its points, with its
    /// threshold, and nothing given back.
    #[test]
    fn a_screens_judgement_is_confirmed_at_the_fit_without_its_points() {
        let (tree, data, options, report) = lost_beams();
        let c = confirm(&tree, &data, &options, &report).expect("confirmed");
        assert_eq!(c.threshold, report.threshold);
        assert!(c.given_back.is_empty(), "{:?}", c.given_back);
    }

    /// A clean point named as left out is within its threshold at the fit without it: not
    /// confirmed (the screen, judging again, gives it back), and neither is a judgement that
    /// left out nothing.
    #[test]
    fn a_clean_point_named_left_out_is_not_confirmed() {
        let (tree, data, options, report) = lost_beams();
        let clean = (0..data.samples.len())
            .find(|i| {
                !report.left_out().contains(i) && data.samples[*i].split == Split::Calibration
            })
            .expect("a clean calibration point");
        let mut named = report.clone();
        let mut wrong = named.outliers[0].clone();
        wrong.sample = clean;
        wrong.line = data.samples[clean].line;
        named.outliers.push(wrong);
        named.outliers.sort_by_key(|o| o.sample);
        assert_eq!(confirm(&tree, &data, &options, &named), None);
        let nothing = OutlierReport {
            outliers: Vec::new(),
            ..report
        };
        assert_eq!(confirm(&tree, &data, &options, &nothing), None);
    }

    #[test]
    fn median_of_odd_and_even() {
        assert_eq!(median(vec![3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), Some(2.5));
        assert_eq!(median(vec![]), None);
        // As the sorted list's middle, on a long list with ties.
        let v: Vec<f64> = (0..10_001)
            .map(|i| ((i * 7919) % 1000) as f64 * 0.1)
            .collect();
        for list in [v.clone(), v[1..].to_vec()] {
            let mut sorted = list.clone();
            sorted.sort_by(f64::total_cmp);
            let n = sorted.len();
            let expected = if n % 2 == 1 {
                sorted[n / 2]
            } else {
                0.5 * (sorted[n / 2 - 1] + sorted[n / 2])
            };
            assert_eq!(median(list), Some(expected));
        }
    }
}
