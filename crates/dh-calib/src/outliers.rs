//! Outliers: points a lost tracker beam, a reflection or a mistyped row put far off the model.
//!
//! # Procedure
//! Iterated hard rejection around the geometric fit (the `nominal` and `geometric` steps of
//! [`crate::calibrate`], without validation):
//! 1. fit the kept calibration points (all of them in the first round);
//! 2. standardise every point's 3-D residual `r` (device frame, metres) by the per-axis scale
//!    `s`: `t = ‖r / s‖`, which for Gaussian noise is `χ` with 3 degrees of freedom;
//! 3. flag the points with `P(χ²₃ > t²) < level / N` (a Bonferroni bound over the `N` points:
//!    a clean Gaussian set of any size flags nothing with probability at least `1 − level`;
//!    the threshold grows like `sqrt(2 ln N)`, 5.1 σ at N = 1000 and `level` = 0.01);
//! 4. refit without them and repeat until the flagged set no longer changes.
//!
//! The scale is the larger of the known noise (the `sigma` option, else every sample's own)
//! and a robust estimate from the kept points, `median ‖r‖ / sqrt(median χ²₃)` corrected for
//! the `p` fitted parameters by `1 / sqrt(1 − p / 3N)`: a median is not moved by the outliers
//! it must find, and never going below it keeps an unmodelled effect, which raises every
//! residual, from making the bulk of the points outliers. A gross outlier (a metre off) moves
//! the first round's least-squares fit, but its own residual stays far beyond any threshold,
//! and the next round fits without it.
//!
//! Validation samples are judged against the fit of the kept calibration points with the
//! bound over their own number, and with a scale no smaller than the robust one of the
//! validation residuals themselves (a fit that extrapolates badly to every held-out pose is a
//! finding of the validation, not a set of outliers); they never move the fit, but one far-off
//! point spoils the validation figures, so a flagged one is left out of them too.

use std::collections::BTreeSet;

use nalgebra::Vector3;

use crate::calibrate::{
    distances, prepare, CalibrationOptions, Geometric, Session, Stats, Validation,
};
use crate::data::{Measurements, Split};
use crate::fit::CalibError;
use crate::model::Observed;
use crate::stats;
use crate::tree::DhTree;

/// Family-wise level of the outlier test by default: the probability that a clean Gaussian set
/// flags at least one point.
pub const DEFAULT_LEVEL: f64 = 0.01;

/// Most fit-and-flag rounds; the flagged set is usually stable after two or three.
pub const MAX_ROUNDS: usize = 10;

/// Smallest per-axis scale (metres, 1 nm): residuals below it are the rounding of a noise-free
/// fit, not measurement, and no point is an outlier against them.
pub const MIN_SCALE: f64 = 1e-9;

/// Median of the chi-square distribution with 3 degrees of freedom.
const CHI2_3_MEDIAN: f64 = 2.365_973_884_375_338;

/// How outliers are handled.
#[derive(Clone, Debug, PartialEq)]
pub struct OutlierOptions {
    /// Look for outliers at all (default `true`).
    pub screen: bool,
    /// Fit every point, flagged or not, but still name the flagged ones (default `false`).
    pub keep: bool,
    /// Family-wise level of the test, in (0, 1) (default [`DEFAULT_LEVEL`]).
    pub level: f64,
}

impl Default for OutlierOptions {
    fn default() -> Self {
        Self {
            screen: true,
            keep: false,
            level: DEFAULT_LEVEL,
        }
    }
}

/// Where the scale of the standardised residuals comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ScaleSource {
    /// The known noise (the `sigma` option or every sample's own).
    Known,
    /// The robust estimate from the residuals (no known noise, or one below the residual).
    Robust,
}

/// One flagged point.
#[derive(Clone, Debug, PartialEq)]
pub struct Outlier {
    /// Index into [`Measurements::samples`].
    pub sample: usize,
    /// 1-based line of the sample in its file (0 when generated).
    pub line: usize,
    /// Pose identifier of the sample, when it has one.
    pub config: Option<String>,
    /// Target name.
    pub target: String,
    /// `true` for a validation sample.
    pub validation: bool,
    /// 3-D distance between modelled and measured point at the fit without the outliers
    /// (metres).
    pub residual: f64,
    /// The same in units of the per-axis scale (`‖r / s‖`).
    pub sigmas: f64,
}

/// What the screen found.
#[derive(Clone, Debug, PartialEq)]
pub struct OutlierReport {
    /// Family-wise level of the test.
    pub level: f64,
    /// Per-axis scale of the final round (metres).
    pub scale: f64,
    /// Where the scale comes from.
    pub source: ScaleSource,
    /// Threshold on `‖r / s‖` for the calibration points.
    pub threshold: f64,
    /// The flagged points, in file order.
    pub outliers: Vec<Outlier>,
    /// `true` when they were kept in the fit (`--keep-outliers`).
    pub kept: bool,
    /// Geometric-fit RMS over every calibration point, outliers included (metres).
    pub rms_with: f64,
    /// Geometric-fit RMS over the other calibration points, fitted without the outliers
    /// (metres).
    pub rms_without: f64,
    /// Fit-and-flag rounds run.
    pub rounds: usize,
    /// `false` when [`MAX_ROUNDS`] ended the iteration before the flagged set settled.
    pub converged: bool,
}

impl OutlierReport {
    /// `data` without the flagged samples.
    pub fn without(&self, data: &Measurements) -> Measurements {
        let drop: BTreeSet<usize> = self.outliers.iter().map(|o| o.sample).collect();
        data.filtered(|i, _| !drop.contains(&i))
    }
}

/// The threshold on `‖r / s‖` that a `χ₃` variable exceeds with probability `level / n`.
pub fn threshold(n: usize, level: f64) -> f64 {
    let p = level / n.max(1) as f64;
    let (mut lo, mut hi) = (0.0f64, 100.0f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if stats::chi2_sf(mid * mid, 3.0) > p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Residual vectors of `obs` at `x` (device frame, metres).
fn residual_vectors(session: &Session<'_>, x: &[f64], obs: &[Observed]) -> Vec<Vector3<f64>> {
    let mut r = [0.0; 6];
    obs.iter()
        .map(|o| {
            session.model.residuals(x, o, &mut r);
            Vector3::new(r[0], r[1], r[2])
        })
        .collect()
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    })
}

/// Finds the outliers of `data` against the geometric model of `tree` (see the module docs).
/// `options.effects` are not used: the screen fits the geometric model only.
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
    screen_from(tree, data, options, None)
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

/// [`screen`] whose first round is `first`: a session of all of `data` (prepared in its own
/// order) whose geometric step has run. Its calibration samples are those the first round
/// fits, and its geometric parameters are fitted without effects, so the round needs no fit
/// of its own (on millions of samples, the fit is most of a calibration's time).
pub(crate) fn screen_from(
    tree: &DhTree,
    data: &Measurements,
    options: &CalibrationOptions,
    first: Option<(&Session<'_>, &Geometric)>,
) -> Result<OutlierReport, CalibError> {
    let level = options.outliers.level;
    let own_full;
    let full = match first {
        Some((s, _)) => &s.prep,
        None => {
            own_full = prepare(tree, data, None)?;
            &own_full
        }
    };
    // Where each sample of `data` went: (validation?, index in its list).
    let mut place = Vec::with_capacity(data.samples.len());
    let (mut nc, mut nv) = (0, 0);
    for s in &data.samples {
        match s.split {
            Split::Calibration => {
                place.push((false, nc));
                nc += 1;
            }
            Split::Validation => {
                place.push((true, nv));
                nv += 1;
            }
        }
    }
    let known: Vec<Option<Vector3<f64>>> = data
        .samples
        .iter()
        .map(|s| match options.sigma {
            Some(v) => Some(Vector3::repeat(v)),
            None => s.sigma.filter(|v| v.iter().all(|a| *a > 0.0)),
        })
        .collect();
    let screen_options = CalibrationOptions {
        effects: vec![],
        ..options.clone()
    };
    let (t_cal, t_val) = (threshold(nc, level), threshold(nv, level));
    let mut flagged: BTreeSet<usize> = BTreeSet::new();
    let mut rms_with = None;
    let mut rounds = 0;
    loop {
        rounds += 1;
        let own;
        let (session, geo) = match first {
            Some((s, g)) if flagged.is_empty() => (s, g),
            _ => {
                // The data themselves while nothing is left out and all are calibration
                // samples (no copy of millions of samples), else the calibration samples not
                // flagged.
                let kept =
                    if flagged.is_empty() && nv == 0 {
                        std::borrow::Cow::Borrowed(data)
                    } else {
                        std::borrow::Cow::Owned(data.filtered(|i, s| {
                            s.split == Split::Calibration && !flagged.contains(&i)
                        }))
                    };
                let mut session = Session::new(tree, &kept, &screen_options, &[], None)?;
                session.validation = Validation::None;
                let geo = session.geometric()?;
                own = (session, geo);
                (&own.0, &own.1)
            }
        };
        let x = &geo.last.outcome.x;
        let rms = geo.last.report.rms;
        rms_with.get_or_insert(rms);
        let cal_r = residual_vectors(session, x, &full.cal);
        let val_r = residual_vectors(session, x, &full.val);
        let p = geo.free.len() as f64;
        let n_kept = session.prep.cal.len().max(1) as f64;
        let kept_norms: Vec<f64> = place
            .iter()
            .enumerate()
            .filter(|(i, (v, _))| !v && !flagged.contains(i))
            .map(|(_, (_, k))| cal_r[*k].norm())
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
            match known[i] {
                Some(s) if s.norm() / 3f64.sqrt() >= floor => {
                    (r.component_div(&s).norm(), ScaleSource::Known)
                }
                _ => (r.norm() / floor, ScaleSource::Robust),
            }
        };
        let mut now = BTreeSet::new();
        let mut found = Vec::new();
        let mut source = ScaleSource::Robust;
        for (i, &(v, k)) in place.iter().enumerate() {
            let r = if v { &val_r[k] } else { &cal_r[k] };
            let t = if v {
                standardised(i, r, robust.max(val_robust)).0
            } else {
                let (t, src) = standardised(i, r, robust);
                source = src;
                t
            };
            if t > if v { t_val } else { t_cal } {
                now.insert(i);
                let s = &data.samples[i];
                found.push(Outlier {
                    sample: i,
                    line: s.line,
                    config: s.config.clone(),
                    target: data.targets.get(s.target).cloned().unwrap_or_default(),
                    validation: v,
                    residual: r.norm(),
                    sigmas: t,
                });
            }
        }
        let now_cal: BTreeSet<usize> = now.iter().copied().filter(|&i| !place[i].0).collect();
        let settled = now_cal == flagged;
        if settled || rounds >= MAX_ROUNDS {
            let known_scale = known
                .iter()
                .flatten()
                .map(|s| s.norm() / 3f64.sqrt())
                .fold(0.0, f64::max);
            return Ok(OutlierReport {
                level,
                scale: if source == ScaleSource::Known {
                    known_scale
                } else {
                    robust
                },
                source,
                threshold: t_cal,
                outliers: found,
                kept: options.outliers.keep,
                rms_with: rms_with.unwrap_or(rms),
                rms_without: Stats::of(&distances(&session.model, x, &session.prep.cal))
                    .map_or(0.0, |s| s.rms),
                rounds,
                converged: settled,
            });
        }
        flagged = now_cal;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn threshold_grows_like_a_bonferroni_bound() {
        // P(chi2_3 > 11.345) = 0.01: one point at level 0.01.
        assert!((threshold(1, 0.01) - 11.344_866_730_144_37f64.sqrt()).abs() < 1e-6);
        let (a, b) = (threshold(100, 0.01), threshold(10_000, 0.01));
        assert!(a > 4.0 && a < b && b < 6.5, "{a} {b}");
        assert!((stats::chi2_sf(b * b, 3.0) - 1e-6).abs() < 1e-9);
    }

    #[test]
    fn median_of_odd_and_even() {
        assert_eq!(median(vec![3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), Some(2.5));
        assert_eq!(median(vec![]), None);
    }
}
