//! Automatic diagnosis: trace the residual of a geometric calibration to the effect the model
//! lacks, add it, and report the error before and after.
//!
//! # Procedure
//! 1. **Is anything left?** After the `nominal` and `geometric` steps of
//!    [`crate::calibrate`], the geometric residual is compared with the noise: with a known
//!    noise (the `sigma` option or every sample's own) by the chi-square test
//!    `Σ (r/σ)² ~ χ²(m − p)`; with repeated poses (samples sharing `config`) by the
//!    lack-of-fit F test against the pure error (N. R. Draper, H. Smith, *Applied Regression
//!    Analysis*, 3rd ed., 1998, §2.1); without either there is no independent noise estimate
//!    and the held-out comparison below decides alone. A test that finds nothing left (at
//!    [`DiagnoseOptions::alpha`]) stops the automatic selection.
//! 2. **Which effect explains it?** Every candidate's Jacobian columns `C` are projected onto
//!    the orthogonal complement of the columns `J` of the parameters already estimated
//!    (`C⊥ = (I − Q Qᵀ) C` with `J = Q R`, all columns scaled to metres as in [`crate::fit`]);
//!    its **score** is the reduction of the residual sum of squares that adding it would give
//!    to first order, `‖P_{C⊥} r‖²` (m²): what the candidate explains that the geometric
//!    parameters cannot. Its **held-out RMS** is the validation (or cross-validation) RMS after
//!    the same linearised (one Gauss-Newton step) refit with it added.
//! 3. **Aliasing**: a candidate whose projected columns keep less than [`ALIAS_SINE`] of their
//!    length (the sine of the angle between its column space and the estimated one) is
//!    mimicked by the geometric parameters (a device scale when every length is free); it is
//!    reported as aliased and never selected.
//! 4. **Selection rule** (automatic mode): candidates are ranked by score minus the BIC
//!    penalty `k σ̂² ln m` (`k` parameters, `m` residuals); the best ones are refitted in
//!    full (nonlinear) in turn until one passes all of
//!    - (a) the F-to-enter test `F = (ΔSSR / k) / (SSR / (m − p))` at `alpha / K`
//!      (Bonferroni over the `K` eligible candidates of the round),
//!    - (b) a lower BIC `m ln(SSR/m) + p ln m` on the calibration data,
//!    - (c) a significant held-out improvement: the one-sided Wilcoxon signed-rank test at
//!      `alpha`, paired over pose groups, of `Σ (d_before² − d_after²)` on the validation
//!      samples, or on the cross-validation predictions when there is no validation split
//!      (skipped when there is neither),
//!
//!    Its **rivals** (the other eligible candidates that change the same quantity of
//!    the same joint, or the device scale: [`crate::rivals`]) are then refitted and judged
//!    too, and the best of those that pass (lowest BIC, the held-out RMS deciding within
//!    [`crate::rivals::BIC_TIE`]) is added, the others reported as rivals with the
//!    difference. A **nested** rival (its terms among the other's: `gear_harmonic:J` in
//!    `gear_harmonic:J:2`), refitted in the round whether it passed or not, is compared with
//!    the winner by the extra-sum-of-squares F test, and the simpler is kept unless the extra
//!    terms are significant at `alpha` (`nested`: the held-out check, which compares the two
//!    on a handful of poses, no longer picks the bigger on noise); then the loop repeats. It stops when none of the
//!    [`DiagnoseOptions::trials`] best candidates passes, or after
//!    [`DiagnoseOptions::max_effects`] (a guard, reported in the notes when it stops the
//!    loop). With explicit labels every non-aliased, identifiable candidate is added in the
//!    order of its score, without tests.
//! 5. **Structure that no candidate explains**: the final residuals, averaged over the repeats
//!    of a pose and target, are regressed on `1, sin q_j, cos q_j, sin 2q_j, cos 2q_j` for every
//!    joint `j` (F test of the explained part against what is left, degrees of freedom reduced
//!    by the parameters fitted), and tested for correlation between consecutive poses (pose order,
//!    i.e. time: the self-normalised lag-1 statistic `Σ a_i / sqrt(Σ a_i²)`,
//!    `a_i = r̄_i · r̄_{i+1}` over pose-mean residuals); against time (the pose order), by a
//!    cubic trend and a length change growing as a cubic in time (a warm-up); and against the
//!    gravity lever arm of each joint (`1, l, l², l³`: a sag that grows with the reach), all
//!    at `alpha / K` (Bonferroni over the `K` tests; see `calibrate::structure`). What is
//!    significant is reported with binned residuals rather than fitted.
//!
//! # Layout
//! The options and constants are here; the entry points and the selection loop are in
//! `selection`, the scoring and judging of candidates in `scoring` (both re-exported here); the
//! findings' data types are in [`crate::findings`] and the residual tests of steps 1 and 5 in
//! [`crate::calibrate`] (each has that one path).

use std::collections::HashMap;
use std::sync::Arc;

use dh_core::DhTable;
use nalgebra::{DMatrix, DVector, Vector3};

use crate::calibrate::{
    residual_test, verdict, CalibrationOptions, Folds, Report, Session, StepReport, Validation,
};
use crate::data::Measurements;
use crate::effects::{self, EffectContext};
use crate::fit::{CalibError, FitOutcome};
use crate::gravity::{GravityModel, Inertials};
use crate::model::{Effect, Model, Observed};
use crate::rivals;
use crate::stats;
use crate::tree::DhTree;

use crate::findings::{
    CandidateReport, CandidateStatus, Diagnosis, EffectEstimate, Round, Trial, DEFAULT_ALPHA,
};

// The submodules import what they use through `use super::*`: the imports above and each
// other's items, re-exported here.
mod selection;
pub use selection::*;
mod rejudge;
pub use rejudge::{diagnose_tree, MAX_REJUDGE};
mod attempts;
mod evidence;
mod fold_normals;
use attempts::{Attempts, Wanted};
mod nested;
mod scoring;
use fold_normals::FoldNormals;
pub(crate) use scoring::*;

/// A candidate whose projected columns keep less than this fraction of their length is aliased
/// with the parameters already estimated (0.1 %).
pub const ALIAS_SINE: f64 = 1e-3;

/// The selection rule, as reported in [`Diagnosis::rule`].
pub const RULE: &str = "rank candidates by score (first-order SSR reduction beyond the estimated \
parameters) minus k*sigma^2*ln(m); refit the best in turn until one passes (a) F-to-enter \
at alpha/K (Bonferroni over the K eligible candidates), (b) lower BIC on calibration data, (c) a \
one-sided Wilcoxon signed-rank test at alpha, paired over pose groups, of the held-out squared errors \
(validation split, else cross-validation); then refit its rivals (eligible candidates changing \
the same quantity of the same joint, or the device scale; a sag along gravity and the effects of \
the gravity torques, one load) and add the best of those that pass (lowest BIC; within 2 of it, \
lowest held-out RMS; rivals of one load, lowest held-out RMS); of nested rivals (the terms of one among the \
other's) keep the simpler unless an extra-sum-of-squares F test finds the extra terms significant \
at alpha; stop when none of the tried candidates passes; aliased candidates (sine < 1e-3) are \
never selected";

/// Which effects to consider.
#[derive(Clone, Debug, PartialEq, Default)]
pub enum EffectSelection {
    /// Every applicable candidate ([`effects::candidates`]), selected by the rule.
    #[default]
    Auto,
    /// None: stop after the geometric step.
    None,
    /// These labels, each added unless aliased or unidentifiable.
    Labels(Vec<String>),
}

/// Options of [`diagnose`].
#[derive(Clone, Debug, PartialEq)]
pub struct DiagnoseOptions {
    /// Which effects.
    pub effects: EffectSelection,
    /// Link masses for the gravity effects; `None` skips them (and says so).
    pub inertials: Option<Inertials>,
    /// Gravity in the base link frame (m/s²). Default `(0, 0, -9.80665)`.
    pub gravity: Vector3<f64>,
    /// Significance level of every test. Default 0.01.
    pub alpha: f64,
    /// Most effects added by the automatic selection (explicit labels are all added). Default
    /// 12.
    pub max_effects: usize,
    /// Candidates refitted per round before giving up. Default 3.
    pub trials: usize,
}

impl Default for DiagnoseOptions {
    fn default() -> Self {
        Self {
            effects: EffectSelection::Auto,
            inertials: None,
            gravity: GravityModel::default_gravity(),
            alpha: DEFAULT_ALPHA,
            max_effects: 12,
            trials: 3,
        }
    }
}

/// A joint that moved less than this over the calibration samples (radians, or metres for a
/// prismatic joint) takes part in no coupling candidate.
pub const MIN_JOINT_MOTION: f64 = 1e-3;

fn effect_estimates(model: &Model, fit: &FitOutcome, selected: &[usize]) -> Vec<EffectEstimate> {
    let effects = model.effects();
    let mut out = Vec::new();
    for &e in selected {
        let Some((eff, range)) = effects.get(e) else {
            continue;
        };
        let units = eff.units();
        let names = eff.parameter_names();
        for (k, c) in range.clone().enumerate() {
            let value = fit.x[c];
            let se = fit.std_errors.get(c).copied().flatten();
            let unit = units.get(k).cloned().unwrap_or_default();
            let stiffness = (eff.label().starts_with("compliance:")
                || eff.label().starts_with("lateral_compliance:"))
            .then(|| {
                let s = 1.0 / value;
                let unit = if unit == "m/N" { "N/m" } else { "N m/rad" };
                (s, se.map(|v| v / (value * value)), unit.to_string())
            })
            .filter(|(s, _, _)| s.is_finite());
            out.push(EffectEstimate {
                name: names.get(k).cloned().unwrap_or_default(),
                value,
                std_error: se,
                unit,
                stiffness,
            });
        }
    }
    out
}

/// Lists the effect labels a [`Report`] may carry, for callers that only need the names.
pub fn effect_labels(effects: &[Arc<dyn Effect>]) -> Vec<String> {
    effects.iter().map(|e| e.label()).collect()
}
