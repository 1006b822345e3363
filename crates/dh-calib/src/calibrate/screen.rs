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
    let within: Option<BTreeSet<usize>> =
        before.map(|b| b.outliers.iter().map(|o| o.sample).collect());
    // The points whose figures the report gives: those `before` left out or gave back.
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
    let level = options.outliers.level;
    let own_full;
    let full = match first {
        Some((s, _)) => &s.prep,
        None => {
            own_full = prepare(tree, data, None, effects.iter().any(|e| e.uses_sequence()))?;
            &own_full
        }
    };
    // Where each sample of `data` went: (validation?, index in its list). Listed only when
    // there are validation samples; else sample `i` is calibration sample `i` (a list held
    // 32 MB on 2 000 000 samples).
    let n = data.samples.len();
    let nv = data
        .samples
        .iter()
        .filter(|s| s.split == Split::Validation)
        .count();
    let nc = n - nv;
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
    let place = |i: usize| places.as_ref().map_or((false, i), |p| p[i]);
    // The known per-axis noise of sample `i` (computed where read: a vector of them held
    // 64 MB on 2 000 000 samples).
    let known = |i: usize| -> Option<Vector3<f64>> {
        match options.sigma {
            Some(v) => Some(Vector3::repeat(v)),
            None => data.samples[i].sigma.filter(|v| v.iter().all(|a| *a > 0.0)),
        }
    };
    let screen_options = CalibrationOptions {
        effects: vec![],
        ..options.clone()
    };
    let (t_cal, t_val) = (threshold(nc, level), threshold(nv, level));
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
                let kept = if flagged.is_empty() && nv == 0 {
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
        let p = free as f64;
        let n_kept = session.prep.cal.len().max(1) as f64;
        let kept_norms: Vec<f64> = (0..n)
            .map(place)
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
            match known(i) {
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
        for (i, (v, k)) in (0..n).map(place).enumerate() {
            let r = if v { &val_r[k] } else { &cal_r[k] };
            let t = if v {
                standardised(i, r, robust.max(val_robust)).0
            } else {
                let (t, src) = standardised(i, r, robust);
                source = src;
                t
            };
            if watched.contains(&i) {
                seen.insert(i, (r.norm(), t));
            }
            let eligible = within.as_ref().is_none_or(|w| w.contains(&i));
            if eligible && t > if v { t_val } else { t_cal } {
                now.insert(i);
                let s = &data.samples[i];
                found.push(Outlier {
                    sample: i,
                    line: s.line,
                    config: s.config.as_deref().map(str::to_string),
                    target: data.targets.get(s.target).cloned().unwrap_or_default(),
                    validation: v,
                    residual: r.norm(),
                    sigmas: t,
                    first: before.and_then(|b| {
                        b.outliers
                            .iter()
                            .find(|o| o.sample == i)
                            .map(|o| o.first_judged(b))
                    }),
                });
            }
        }
        let now_cal: BTreeSet<usize> = now.iter().copied().filter(|&i| !place(i).0).collect();
        let settled = now_cal == flagged;
        if settled || rounds >= MAX_ROUNDS {
            let judged = |i: usize, validation: bool| {
                let (residual, sigmas) = seen.get(&i).copied().unwrap_or((0.0, 0.0));
                Judged {
                    residual,
                    sigmas,
                    threshold: if validation { t_val } else { t_cal },
                    effects: labels.clone(),
                }
            };
            let given_back = match before {
                None => Vec::new(),
                Some(b) => {
                    let mut g: Vec<GivenBack> =
                        b.given_back
                            .iter()
                            .map(|g| GivenBack {
                                after: judged(g.sample, g.validation),
                                ..g.clone()
                            })
                            .chain(b.outliers.iter().filter(|o| !now.contains(&o.sample)).map(
                                |o| GivenBack {
                                    sample: o.sample,
                                    line: o.line,
                                    config: o.config.clone(),
                                    target: o.target.clone(),
                                    validation: o.validation,
                                    before: o.first_judged(b),
                                    after: judged(o.sample, o.validation),
                                },
                            ))
                            .collect();
                    g.sort_by_key(|g| g.sample);
                    g
                }
            };
            let known_scale = (0..data.samples.len())
                .filter_map(known)
                .map(|s| s.norm() / 3f64.sqrt())
                .fold(0.0, f64::max);
            let without = if own_fit {
                cal_r.iter().map(|r| r.norm()).collect()
            } else {
                distances(&session.model, x, &session.prep.cal)
            };
            return Ok(OutlierReport {
                level,
                scale: if source == ScaleSource::Known {
                    known_scale
                } else {
                    robust
                },
                source,
                threshold: t_cal,
                validation_threshold: t_val,
                outliers: found,
                given_back,
                kept: options.outliers.keep,
                rms_with: rms_with.unwrap_or(rms),
                rms_without: Stats::of(&without).map_or(0.0, |s| s.rms),
                rounds,
                converged: settled,
                effects: labels,
            });
        }
        flagged = now_cal;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
