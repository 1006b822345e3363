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
//! The geometric fit knows no effect, so a pose that only an unmodelled effect puts far off
//! (the most gravity-loaded poses before a compliance is added) is flagged too. The diagnosis
//! ([`crate::diagnose::diagnose_tree`]) therefore judges the flagged points again against the
//! geometry and the effects it selected ([`crate::calibrate::screen`] with
//! `CalibrationOptions::effects`: each round fits every parameter the kept points identify),
//! gives back those that are no outliers of that model and selects again with them; a
//! second judgement only gives points back. Declared effects are judged with from the start.
//!
//! The scale is the larger of the known noise (the `sigma` option, else every sample's own)
//! and a robust estimate from the kept points, `median ‖r‖ / sqrt(median χ²₃)` corrected for
//! the `p` fitted parameters by `1 / sqrt(1 − p / 3N)`: a median is not moved by the outliers
//! it must find, and never going below it keeps an unmodelled effect, which raises every
//! residual, from making the bulk of the points outliers. A gross outlier (a metre off) moves
//! the first round's least-squares fit, but its own residual stays far beyond any threshold,
//! and the next round fits without it.
//!
//! Every judgement after the first carries the points it gave back ([`OutlierReport::given_back`]):
//! how far off each was against the model that first left it out and against the model that gave it
//! back (a later judgement updates the latter, so the diagnosis's report gives the figures
//! against the final model). Validation points are judged again in the same way: a clean
//! held-out pose that only an unmodelled effect put far off comes back into the held-out
//! figures once the model has the effect.
//!
//! Validation samples are judged against the fit of the kept calibration points with the
//! bound over their own number, and with a scale no smaller than the robust one of the
//! validation residuals themselves (a fit that extrapolates badly to every held-out pose is a
//! finding of the validation, not a set of outliers); they never move the fit, but one far-off
//! point spoils the validation figures, so a flagged one is left out of them too.

use std::collections::BTreeSet;

use crate::data::Measurements;
use crate::stats;

/// Family-wise level of the outlier test by default: the probability that a clean Gaussian set
/// flags at least one point.
pub const DEFAULT_LEVEL: f64 = 0.01;

/// Most fit-and-flag rounds; the flagged set is usually stable after two or three.
pub const MAX_ROUNDS: usize = 10;

/// Smallest per-axis scale (metres, 1 nm): residuals below it are the rounding of a noise-free
/// fit, not measurement, and no point is an outlier against them.
pub const MIN_SCALE: f64 = 1e-9;

/// Median of the chi-square distribution with 3 degrees of freedom.
pub(crate) const CHI2_3_MEDIAN: f64 = 2.365_973_884_375_338;

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
    /// When an earlier judgement (against a model with fewer effects) left the point out
    /// too, its figures there: the first judgement's (the geometric model's, in a diagnosis).
    pub first: Option<Judged>,
}

impl Outlier {
    /// The figures of the judgement that first left the point out: [`Outlier::first`], else
    /// this one's, made by `report` (whose outlier it is).
    pub fn first_judged(&self, report: &OutlierReport) -> Judged {
        self.first.clone().unwrap_or_else(|| Judged {
            residual: self.residual,
            sigmas: self.sigmas,
            threshold: if self.validation {
                report.validation_threshold
            } else {
                report.threshold
            },
            effects: report.effects.clone(),
        })
    }
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
    /// Threshold on `‖r / s‖` for the validation points (the bound over their own number).
    pub validation_threshold: f64,
    /// The flagged points, in file order.
    pub outliers: Vec<Outlier>,
    /// `true` when they were kept in the fit (`--keep-outliers`).
    pub kept: bool,
    /// RMS of the screen's fit over every calibration point, outliers included (metres).
    pub rms_with: f64,
    /// RMS of the screen's fit over the other calibration points, fitted without the outliers
    /// (metres).
    pub rms_without: f64,
    /// The effects the screen's model had besides the geometry (labels; empty: the geometric
    /// model alone).
    pub effects: Vec<String>,
    /// Fit-and-flag rounds run.
    pub rounds: usize,
    /// `false` when [`MAX_ROUNDS`] ended the iteration before the flagged set settled.
    pub converged: bool,
    /// The points an earlier judgement left out and a later one gave back (a judgement
    /// against a model with effects the first did not have), in file order: they are in the
    /// fit (calibration) or the held-out figures (validation). Empty for a first judgement.
    pub given_back: Vec<GivenBack>,
}

/// How far off one point was against one model.
#[derive(Clone, Debug, PartialEq)]
pub struct Judged {
    /// 3-D distance between modelled and measured point (metres).
    pub residual: f64,
    /// The same in units of the per-axis scale (`‖r / s‖`).
    pub sigmas: f64,
    /// The threshold on `sigmas` of that judgement (the point's split's).
    pub threshold: f64,
    /// The effects of the model besides the geometry (labels; empty: the geometric model).
    pub effects: Vec<String>,
}

impl Judged {
    /// `against the geometric model` or `against the geometry and <labels>`.
    pub fn model(&self) -> String {
        model_name(&self.effects)
    }
}

/// `the geometric model` for no effects, else `the geometry and <labels>`.
pub fn model_name(effects: &[String]) -> String {
    if effects.is_empty() {
        "the geometric model".into()
    } else {
        format!("the geometry and {}", effects.join(", "))
    }
}

/// A point left out by one judgement and given back by a later one.
#[derive(Clone, Debug, PartialEq)]
pub struct GivenBack {
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
    /// Against the model that first left it out (the geometric model, in a diagnosis).
    pub before: Judged,
    /// Against the model of the latest judgement (the final model's, in a diagnosis's report):
    /// within its threshold, unless a later model put it beyond (it stays given back: a second
    /// judgement only gives points back).
    pub after: Judged,
}

impl GivenBack {
    /// Why it was given back: `5.2 sigma against the geometric model, 1.1 sigma against the
    /// geometry and backlash_direction:j2`.
    pub fn reason(&self) -> String {
        format!(
            "{:.1} sigma against {}, {:.1} sigma against {}",
            self.before.sigmas,
            self.before.model(),
            self.after.sigmas,
            self.after.model()
        )
    }
}

impl OutlierReport {
    /// The flagged calibration samples (indices into the data), not the validation ones.
    pub fn flagged_calibration(&self) -> BTreeSet<usize> {
        self.outliers
            .iter()
            .filter(|o| !o.validation)
            .map(|o| o.sample)
            .collect()
    }

    /// Every flagged sample, calibration and validation, when they were left out (none with
    /// `--keep-outliers`).
    pub fn left_out(&self) -> BTreeSet<usize> {
        if self.kept {
            BTreeSet::new()
        } else {
            self.outliers.iter().map(|o| o.sample).collect()
        }
    }

    /// `data` without the flagged samples.
    pub fn without(&self, data: &Measurements) -> Measurements {
        let drop: BTreeSet<usize> = self.outliers.iter().map(|o| o.sample).collect();
        data.filtered(|i, _| !drop.contains(&i))
    }
}

/// The threshold on `‖r / s‖` that a `χ₃` variable exceeds with probability `level / n`.
pub fn threshold(n: usize, level: f64) -> f64 {
    threshold_in(n, level, 3.0)
}

/// [`threshold`] for a residual of `dof` components (a `χ` variable with `dof` degrees of
/// freedom): a point's distance from a fitted circle has two, in its plane and across it
/// ([`crate::cpa`]).
pub fn threshold_in(n: usize, level: f64, dof: f64) -> f64 {
    let p = level / n.max(1) as f64;
    let (mut lo, mut hi) = (0.0f64, 100.0f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if stats::chi2_sf(mid * mid, dof) > p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
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
}
