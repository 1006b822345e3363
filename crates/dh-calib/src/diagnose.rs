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
//!    difference; then the loop repeats. It stops when none of the
//!    [`DiagnoseOptions::trials`] best candidates passes, or after
//!    [`DiagnoseOptions::max_effects`] (a guard, reported in the notes when it stops the
//!    loop). With explicit labels every non-aliased, identifiable candidate is added in the
//!    order of its score, without tests.
//! 5. **Structure that no candidate explains**: the final residuals, averaged over the repeats
//!    of a pose and target, are regressed on `1, sin q_j, cos q_j, sin 2q_j, cos 2q_j` for every
//!    joint `j` (F test of the explained part against what is left, degrees of freedom reduced
//!    by the parameters fitted), and tested for correlation between consecutive poses (pose order,
//!    i.e. time: the self-normalised lag-1 statistic `Σ a_i / sqrt(Σ a_i²)`,
//!    `a_i = r̄_i · r̄_{i+1}` over pose-mean residuals), each at `alpha / (joints + 1)`. What is
//!    significant is reported with binned residuals rather than fitted.

use std::collections::HashMap;
use std::sync::Arc;

use dh_core::{DhTable, JointKind};
use nalgebra::{DMatrix, DVector, Vector3};

use crate::calibrate::{CalibrationOptions, Prepared, Report, Session, StepReport, Validation};
use crate::data::Measurements;
use crate::effects::{self, EffectContext};
use crate::fit::{CalibError, FitOutcome};
use crate::gravity::{GravityModel, Inertials};
use crate::model::{Effect, Model, Observation, Observed};
use crate::rivals;
use crate::stats;
use crate::tree::DhTree;

/// A candidate whose projected columns keep less than this fraction of their length is aliased
/// with the parameters already estimated (0.1 %).
pub const ALIAS_SINE: f64 = 1e-3;

/// The selection rule, as reported in [`Diagnosis::rule`].
pub const RULE: &str = "rank candidates by score (first-order SSR reduction beyond the estimated \
parameters) minus k*sigma^2*ln(m); refit the best in turn until one passes (a) F-to-enter \
at alpha/K (Bonferroni over the K eligible candidates), (b) lower BIC on calibration data, (c) a \
one-sided Wilcoxon signed-rank test at alpha, paired over pose groups, of the held-out squared errors \
(validation split, else cross-validation); then refit its rivals (eligible candidates changing \
the same quantity of the same joint, or the device scale) and add the best of those that pass \
(lowest BIC; within 2 of it, lowest held-out RMS); stop when none of the tried candidates passes; \
aliased candidates (sine < 1e-3) are never selected";

/// Significance level of the tests by default (the diagnosis's and the final verdict's).
pub const DEFAULT_ALPHA: f64 = 0.01;

/// The verdict on the final model: its residual tested against the noise (chi-square with a
/// known sigma, lack of fit against the pure error of repeated poses; neither: no test), what
/// that means, and the structure the residual still has.
#[derive(Clone, Debug, PartialEq)]
pub struct Verdict {
    /// The test of the final model's residual (the same tests as the diagnosis's step 1).
    pub test: ResidualTest,
    /// Its level.
    pub alpha: f64,
    /// `Some(true)` when nothing significant remains, `Some(false)` when something does,
    /// `None` when no test is possible.
    pub complete: Option<bool>,
    /// Final calibration RMS over the noise floor, when there is a floor.
    pub ratio: Option<f64>,
    /// `model complete`, `residual remains: N x the floor` (or `residual remains` without a
    /// floor), or `no test possible`.
    pub summary: String,
    /// Residual structure of the final model against each joint and the pose order (see the
    /// module docs, step 5).
    pub structure: Vec<StructureCheck>,
    /// What the verdict means for the selected effects and the residual's structure.
    pub notes: Vec<String>,
}

/// The verdict on the fit `fit` of `session` (final calibration RMS `rms`, noise floor
/// `floor`, effects `selected` estimated in it).
pub(crate) fn verdict(
    session: &Session<'_>,
    fit: &FitOutcome,
    alpha: f64,
    floor: Option<&crate::calibrate::NoiseFloor>,
    rms: f64,
    selected: &[String],
) -> Verdict {
    let test = residual_test(session, fit, alpha);
    let structure = structure_checks(session, fit, alpha);
    let ratio = floor.filter(|f| f.rms > 0.0).map(|f| rms / f.rms);
    let complete = (test.kind != NoiseTest::None).then_some(!test.significant);
    let summary = match (complete, ratio) {
        (Some(true), _) => "model complete".to_string(),
        (Some(false), Some(r)) => format!("residual remains: {r:.2} x the floor"),
        (Some(false), None) => "residual remains".to_string(),
        (None, _) => "no test possible".to_string(),
    };
    let mut notes = Vec::new();
    let significant: Vec<&str> = structure
        .iter()
        .filter(|s| s.significant)
        .map(|s| s.variable.as_str())
        .collect();
    let shape = if significant.is_empty() {
        "no structure against the joints or the pose order that the tests resolve".to_string()
    } else {
        format!(
            "structure against {} (see the bins)",
            significant.join(", ")
        )
    };
    match complete {
        None => notes.push(
            "no test of the final model is possible: no known sigma and no repeated poses \
             (give --sigma or repeat poses under one config)"
                .into(),
        ),
        Some(false) => {
            if !selected.is_empty() {
                notes.push(format!(
                    "the residual is still above the noise with the selected effects ({}): they \
                     may stand in for something unmodelled rather than be its cause",
                    selected.join(", ")
                ));
            }
            notes.push(format!("the final residual has {shape}"));
        }
        Some(true) => {}
    }
    Verdict {
        test,
        alpha,
        complete,
        ratio,
        summary,
        structure,
        notes,
    }
}

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

/// What became of a candidate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CandidateStatus {
    /// Added to the model.
    Selected,
    /// Mimicked by the parameters already estimated; never selected.
    Aliased,
    /// Refitted and rejected by the rule (see the round's trials).
    Rejected,
    /// Not added (score too small, not tried, or selection stopped).
    NotSelected,
    /// Its columns are zero on these data, it couples two joints one of which moved less
    /// than [`MIN_JOINT_MOTION`] in them, or it is a `backlash_direction` of a joint that
    /// reverses fewer than [`crate::effects_order::MIN_REVERSALS`] times in them: never
    /// selected.
    Inert,
    /// Passed the rule's tests but a rival effect of the same joint's quantity did better
    /// (see [`crate::rivals`]; the reason names it).
    Rival,
}

impl CandidateStatus {
    /// Lowercase name for reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::Selected => "selected",
            Self::Aliased => "aliased",
            Self::Rejected => "rejected",
            Self::NotSelected => "not selected",
            Self::Inert => "inert",
            Self::Rival => "rival",
        }
    }
}

/// One row of the candidate table.
#[derive(Clone, Debug, PartialEq)]
pub struct CandidateReport {
    /// The effect's label.
    pub label: String,
    /// Number of parameters.
    pub parameters: usize,
    /// First-order reduction of the calibration sum of squares (m²) beyond the parameters
    /// estimated when it was scored.
    pub score: f64,
    /// Sine of the angle between its columns and the estimated ones (1: independent).
    pub independence: f64,
    /// Held-out RMS (metres) with it added, linearised; `None` without validation.
    pub val_rms: Option<f64>,
    /// What became of it.
    pub status: CandidateStatus,
    /// Why it was not added, when it was refitted and rejected or lost to a rival (its last
    /// trial's reason).
    pub reason: Option<String>,
}

/// One full refit of a candidate and the tests of the rule.
#[derive(Clone, Debug, PartialEq)]
pub struct Trial {
    /// The candidate.
    pub label: String,
    /// Calibration RMS after the refit (metres).
    pub rms: f64,
    /// Held-out RMS after the refit (metres).
    pub val_rms: Option<f64>,
    /// F-to-enter and its p-value.
    pub f: f64,
    /// p-value of `f`.
    pub f_p: f64,
    /// The Bonferroni threshold it was compared with (`alpha / K`).
    pub f_threshold: f64,
    /// BIC before and after.
    pub bic: (f64, f64),
    /// Wilcoxon signed-rank `z` of the held-out improvement over pose groups and its one-sided
    /// p-value.
    pub held_out: Option<(f64, f64)>,
    /// Whether it was added.
    pub accepted: bool,
    /// Why not, when not.
    pub reason: String,
}

/// One round of scoring.
#[derive(Clone, Debug, PartialEq)]
pub struct Round {
    /// Calibration RMS at the start of the round (metres).
    pub rms: f64,
    /// Held-out RMS at the start, linearised as the candidates' (metres).
    pub val_rms: Option<f64>,
    /// Every candidate scored, best score first.
    pub candidates: Vec<CandidateReport>,
    /// The candidates refitted, in order.
    pub trials: Vec<Trial>,
}

/// Where the noise estimate of the residual test comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NoiseTest {
    /// Known per-axis standard deviations: chi-square.
    KnownSigma,
    /// Repeated poses: lack-of-fit F test against the pure error.
    PureError,
    /// Neither: no test.
    None,
}

/// Step 1: is anything left after the geometric step?
#[derive(Clone, Debug, PartialEq)]
pub struct ResidualTest {
    /// Which test.
    pub kind: NoiseTest,
    /// The statistic (chi-square or F); `None` without a test.
    pub statistic: Option<f64>,
    /// Its degrees of freedom (one or two).
    pub dof: (f64, f64),
    /// Its p-value.
    pub p_value: Option<f64>,
    /// RMS 3-D noise implied by the estimate (metres), when there is one.
    pub noise_rms: Option<f64>,
    /// Whether something is left (true without a test).
    pub significant: bool,
    /// One line for the user.
    pub summary: String,
}

/// Step 5: residual structure against one variable.
#[derive(Clone, Debug, PartialEq)]
pub struct StructureCheck {
    /// `pose order` or a joint name.
    pub variable: String,
    /// The statistic (F, chi-square or z).
    pub statistic: f64,
    /// Its p-value.
    pub p_value: f64,
    /// Significant at `alpha / (joints + 1)`.
    pub significant: bool,
    /// Binned residuals: `(bin centre, RMS of the residual, length of the mean residual
    /// vector)` in the variable's unit (radians, metres, or pose index) and metres.
    pub bins: Vec<(f64, f64, f64)>,
}

/// An estimated effect parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct EffectEstimate {
    /// Parameter name.
    pub name: String,
    /// Estimate.
    pub value: f64,
    /// Standard error.
    pub std_error: Option<f64>,
    /// Unit.
    pub unit: String,
    /// For a compliance: the stiffness `1 / c` with its standard error (`σ_c / c²`) and unit.
    pub stiffness: Option<(f64, Option<f64>, String)>,
}

/// What the diagnosis found (the report's `diagnosis`).
#[derive(Clone, Debug, PartialEq)]
pub struct Diagnosis {
    /// The selection rule ([`RULE`]).
    pub rule: String,
    /// Significance level.
    pub alpha: f64,
    /// Step 1.
    pub residual_test: ResidualTest,
    /// Each round of scoring.
    pub rounds: Vec<Round>,
    /// Selected effects' parameters.
    pub effect_parameters: Vec<EffectEstimate>,
    /// Step 5.
    pub structure: Vec<StructureCheck>,
    /// Remarks (skipped candidates, unexplained structure).
    pub notes: Vec<String>,
}

/// [`diagnose_tree`] for a serial robot.
///
/// # Errors
/// As [`diagnose_tree`].
pub fn diagnose(
    nominal: &DhTable,
    data: &Measurements,
    options: &CalibrationOptions,
    diag: &DiagnoseOptions,
) -> Result<Report, CalibError> {
    diagnose_tree(&DhTree::serial(nominal), data, options, diag)
}

/// Checks the diagnosis options and builds what every candidate effect needs: the tree and,
/// with inertials, its gravity model (shared by the point and the contact diagnoses).
///
/// # Errors
/// [`CalibError::BadOption`] for an `alpha` outside (0, 1); those of [`GravityModel::new`].
pub(crate) fn effect_context(
    tree: &DhTree,
    diag: &DiagnoseOptions,
) -> Result<EffectContext, CalibError> {
    if !(diag.alpha > 0.0 && diag.alpha < 1.0) {
        return Err(CalibError::BadOption {
            what: "alpha".into(),
            reason: format!("expected a level in (0, 1), found {}", diag.alpha),
        });
    }
    let gravity = match &diag.inertials {
        Some(i) => Some(Arc::new(GravityModel::new(tree, i, diag.gravity)?)),
        None => None,
    };
    Ok(EffectContext {
        tree: tree.clone(),
        gravity,
    })
}

/// Calibrates `tree` against `data` as [`crate::calibrate::calibrate_tree`] does, then
/// diagnoses and adds the effects the geometric model lacks (see the module docs). The report
/// has the steps `nominal`, `geometric` and one `+<label>` per effect added, the candidate
/// table of the first round, the selected effects and the [`Diagnosis`], whose notes (and the
/// residual test's summary) are also appended to the report's notes.
/// `options.effects` is ignored: [`DiagnoseOptions::effects`] says which effects.
///
/// # Errors
/// Those of [`crate::calibrate::calibrate_tree`]; [`CalibError::BadOption`] /
/// [`CalibError::MissingJoint`] for a bad label, bad inertials or a bad `alpha`.
pub fn diagnose_tree(
    tree: &DhTree,
    data: &Measurements,
    options: &CalibrationOptions,
    diag: &DiagnoseOptions,
) -> Result<Report, CalibError> {
    let ctx = effect_context(tree, diag)?;
    let mut notes = Vec::new();
    // Which candidates the model can carry.
    let probe = Model::new_tree(tree, &[], &options.model)?;
    let (pool, forced) = match &diag.effects {
        EffectSelection::None => (vec![], false),
        EffectSelection::Auto => {
            let c = effects::candidates(&ctx, &probe.tilt_rows());
            notes.extend(c.skipped);
            (c.effects, false)
        }
        EffectSelection::Labels(labels) => {
            let mut v = Vec::new();
            for l in labels {
                let e = effects::parse_label_in(l, &ctx)?;
                probe.clone().add_effect(e.clone())?;
                v.push(e);
            }
            (v, true)
        }
    };
    let crate::calibrate::Fitted { session, geo, scan } =
        crate::calibrate::fitted_session(tree, data, options, &pool)?;
    let mut steps = geo.steps;
    let mut last = geo.last.outcome;
    let mut held = geo.last.held_out;
    let mut free = geo.free;
    let mut fixed = geo.fixed;
    let all_effects: Vec<usize> = (0..pool.len()).collect();

    let residual_test = residual_test(&session, &last, diag.alpha);
    let mut rounds: Vec<Round> = Vec::new();
    let mut selected: Vec<usize> = Vec::new();
    let mut first_table: Vec<CandidateReport> = Vec::new();
    let mut rejected: Vec<usize> = Vec::new();
    let mut aliased: Vec<usize> = Vec::new();
    if !pool.is_empty() {
        if !forced && !residual_test.significant {
            notes.push(format!(
                "nothing significant is left after the geometric step ({}); no effect is selected",
                residual_test.summary
            ));
        }
        loop {
            let remaining: Vec<usize> = all_effects
                .iter()
                .copied()
                .filter(|e| !selected.contains(e))
                .collect();
            if remaining.is_empty() {
                break;
            }
            let scored = score(&session, &last.x, &free, &remaining)?;
            let mut table: Vec<(usize, CandidateReport)> = scored.candidates;
            table.sort_by(|a, b| b.1.score.total_cmp(&a.1.score));
            for (e, c) in &table {
                if c.status == CandidateStatus::Aliased && !aliased.contains(e) {
                    aliased.push(*e);
                }
            }
            let mut round = Round {
                rms: steps.last().map_or(0.0, |s| s.rms),
                val_rms: scored.baseline_val,
                candidates: table.iter().map(|(_, c)| c.clone()).collect(),
                trials: vec![],
            };
            let stop_here =
                !forced && (!residual_test.significant || selected.len() >= diag.max_effects);
            if rounds.is_empty() {
                first_table = round.candidates.clone();
            }
            if stop_here {
                if residual_test.significant {
                    notes.push(format!(
                        "stopped after the most effects allowed ({}); candidates may remain",
                        diag.max_effects
                    ));
                }
                rounds.push(round);
                break;
            }
            let m = scored.residuals as f64;
            let p = free.len() as f64;
            let sigma2 = last.ssr / (m - p).max(1.0);
            let mut eligible: Vec<(usize, f64, usize)> = table
                .iter()
                .filter(|(e, c)| c.status == CandidateStatus::NotSelected && !rejected.contains(e))
                .map(|(e, c)| {
                    let gain = c.score - c.parameters as f64 * sigma2 * m.ln();
                    (*e, gain, c.parameters)
                })
                .filter(|(_, gain, _)| forced || *gain > 0.0)
                .collect();
            eligible.sort_by(|a, b| b.1.total_cmp(&a.1));
            let k_count = eligible.len().max(1);
            let mut accepted = None;
            let tries = if forced { 1 } else { diag.trials.max(1) };
            // Refits candidate `e` (of `k` parameters) from the current fit and judges it.
            let attempt = |e: usize, k: usize| -> Result<Attempt, CalibError> {
                let label = pool[e].label();
                let cols: Vec<usize> = session
                    .model
                    .effects()
                    .get(e)
                    .map(|(_, r)| r.clone().collect())
                    .unwrap_or_default();
                let mut columns = free.clone();
                columns.extend(&cols);
                let (trial_free, trial_fixed) = session.identify(&last.x, &columns)?;
                if cols.iter().any(|c| !trial_free.contains(c)) {
                    let trial = Trial {
                        label,
                        rms: f64::NAN,
                        val_rms: None,
                        f: 0.0,
                        f_p: 1.0,
                        f_threshold: diag.alpha / k_count as f64,
                        bic: (f64::NAN, f64::NAN),
                        held_out: None,
                        accepted: false,
                        reason: "not identifiable with the estimated parameters".into(),
                    };
                    return Ok((trial, None));
                }
                let step =
                    session.step(&format!("+{label}"), &last.x, &trial_free, steps.last())?;
                let trial = judge(
                    &session,
                    &last,
                    &held,
                    &step.outcome,
                    &step.held_out,
                    k,
                    k_count,
                    diag.alpha,
                    forced,
                    label,
                    &step.report,
                );
                Ok((trial, Some((step, trial_free, trial_fixed))))
            };
            for &(e, _, k) in eligible.iter().take(tries) {
                let (trial, fitted) = attempt(e, k)?;
                let ok = trial.accepted;
                round.trials.push(trial);
                let Some(fitted) = fitted.filter(|_| ok) else {
                    rejected.push(e);
                    continue;
                };
                // It passes: its rivals (the other eligible candidates that change the same
                // quantity of the same joint) are refitted too, and the best of those that
                // pass is added (see `rivals`).
                let mut passed = vec![(e, round.trials.len() - 1, fitted)];
                if !forced {
                    for &(r, _, kr) in &eligible {
                        if r == e
                            || rejected.contains(&r)
                            || !rivals::are_rivals(pool[e].as_ref(), pool[r].as_ref())
                        {
                            continue;
                        }
                        let (trial, fitted) = attempt(r, kr)?;
                        let ok = trial.accepted;
                        round.trials.push(trial);
                        match fitted.filter(|_| ok) {
                            Some(f) => passed.push((r, round.trials.len() - 1, f)),
                            None => rejected.push(r),
                        }
                    }
                }
                let best = rivals::best(
                    &passed
                        .iter()
                        .map(|p| &round.trials[p.1])
                        .collect::<Vec<_>>(),
                );
                let winner = round.trials[passed[best].1].clone();
                for (i, (r, t, _)) in passed.iter().enumerate() {
                    if i != best {
                        let trial = &mut round.trials[*t];
                        trial.accepted = false;
                        trial.reason = rivals::reason(&winner, trial);
                        rejected.push(*r);
                    }
                }
                let (e, _, (step, trial_free, trial_fixed)) = passed.swap_remove(best);
                accepted = Some((e, step, trial_free, trial_fixed));
                break;
            }
            rounds.push(round);
            match accepted {
                Some((e, mut step, f2, fixed2)) => {
                    selected.push(e);
                    // The trial identified only the free columns and the effect's: what an
                    // earlier step held stays held and must stay listed.
                    let now_held: Vec<usize> = fixed2.iter().map(|g| g.index).collect();
                    let mut fixed2: Vec<crate::fit::Fixed> = fixed
                        .iter()
                        .filter(|f| !f2.contains(&f.index) && !now_held.contains(&f.index))
                        .cloned()
                        .chain(fixed2)
                        .collect();
                    fixed2.sort_by_key(|f| f.index);
                    step.report.fixed = session.named_geometric(&fixed2);
                    steps.push(step.report);
                    last = step.outcome;
                    held = step.held_out;
                    free = f2;
                    fixed = fixed2;
                    // A rejection in one round may pass once another effect is in.
                    rejected.clear();
                }
                None => break,
            }
        }
    }
    // A rejected candidate's row says why: its last trial's reason (a rival's names the
    // effect that did better).
    let last_rejection = |trials: &mut dyn Iterator<Item = &Trial>, label: &str| {
        trials
            .filter(|t| t.label == label && !t.accepted)
            .last()
            .map(|t| {
                let status = if t.reason.starts_with(rivals::RIVAL_OF) {
                    CandidateStatus::Rival
                } else {
                    CandidateStatus::Rejected
                };
                (status, t.reason.clone())
            })
    };
    for c in &mut first_table {
        let e = pool.iter().position(|p| p.label() == c.label);
        let rejection = last_rejection(&mut rounds.iter().flat_map(|r| r.trials.iter()), &c.label);
        c.status = match (e, &rejection) {
            (Some(e), _) if selected.contains(&e) => CandidateStatus::Selected,
            (Some(e), _) if aliased.contains(&e) => CandidateStatus::Aliased,
            (Some(_), _) if c.status == CandidateStatus::Inert => CandidateStatus::Inert,
            (Some(_), Some((status, reason))) => {
                c.reason = Some(reason.clone());
                *status
            }
            _ => CandidateStatus::NotSelected,
        };
    }
    for r in &mut rounds {
        for c in &mut r.candidates {
            if let Some(e) = pool.iter().position(|p| p.label() == c.label) {
                if selected.contains(&e) {
                    c.status = CandidateStatus::Selected;
                } else if c.status == CandidateStatus::NotSelected {
                    if let Some((status, reason)) = last_rejection(&mut r.trials.iter(), &c.label) {
                        c.status = status;
                        c.reason = Some(reason);
                    }
                }
            }
        }
    }
    let structure = structure_checks(&session, &last, diag.alpha);
    for s in structure.iter().filter(|s| s.significant) {
        notes.push(format!(
            "structure remains that no candidate explains: the residual depends on {} \
             (statistic {:.3}, p = {:.2e}); see its bins",
            s.variable, s.statistic, s.p_value
        ));
    }
    let effect_parameters = effect_estimates(&session.model, &last, &selected);
    let hidden: Vec<usize> = all_effects
        .iter()
        .copied()
        .filter(|e| !selected.contains(e))
        .collect();
    let mut report = session.report(&last, steps, fixed, &hidden);
    report.selected_effects = selected.iter().map(|&e| pool[e].label()).collect();
    if diag.alpha != DEFAULT_ALPHA {
        report.verdict = verdict(
            &session,
            &last,
            diag.alpha,
            report.noise_floor.as_ref(),
            report.rms_after,
            &report.selected_effects,
        );
    }
    crate::calibrate::attach_outliers(&mut report, scan);
    report.candidates = first_table;
    // The report's notes carry the diagnosis's findings too, for readers of the report alone.
    if !pool.is_empty() {
        report.notes.push(format!(
            "residual after the geometric step: {}",
            residual_test.summary
        ));
    }
    report.notes.extend(notes.iter().cloned());
    report.diagnosis = Some(Diagnosis {
        rule: RULE.into(),
        alpha: diag.alpha,
        residual_test,
        rounds,
        effect_parameters,
        structure,
        notes,
    });
    Ok(report)
}

/// Stacks the scaled Jacobian of `columns` and the residuals of `obs` at `x`; returns them
/// with the first row of each observation.
fn dense(
    model: &Model,
    obs: &[Observed],
    x: &[f64],
    columns: &[usize],
    scales: &[f64],
) -> (DMatrix<f64>, DVector<f64>, Vec<usize>) {
    let sizes: Vec<usize> = obs
        .iter()
        .map(|o| match o.observation {
            Observation::Pose(_) => 6,
            Observation::Point { .. } => 3,
        })
        .collect();
    let m: usize = sizes.iter().sum();
    let n = columns.len();
    let mut j = DMatrix::zeros(m, n);
    let mut r = DVector::zeros(m);
    let mut starts = Vec::with_capacity(obs.len());
    let mut row = 0;
    let mut res = [0.0; 6];
    let mut jac = vec![0.0; 6 * n];
    for (o, &s) in obs.iter().zip(&sizes) {
        starts.push(row);
        model.jacobian(x, o, columns, &mut res[..s], &mut jac[..s * n]);
        for i in 0..s {
            r[row + i] = res[i];
            for (k, &c) in columns.iter().enumerate() {
                j[(row + i, k)] = jac[i * n + k] * scales[c];
            }
        }
        row += s;
    }
    (j, r, starts)
}

/// Least squares of `r + J_F δ_F + C δ_C` on a subset of rows, through the QR of `J_F`.
struct Projector {
    q: DMatrix<f64>,
    r: DMatrix<f64>,
    qtr: DVector<f64>,
    /// The residuals of the rows, less what `J_F` explains.
    r_perp: DVector<f64>,
    rows: Vec<usize>,
    /// All rows, in order (no selection needed).
    all: bool,
}

impl Projector {
    fn new(jf: &DMatrix<f64>, res: &DVector<f64>, rows: Vec<usize>) -> Projector {
        let sub = jf.select_rows(rows.iter());
        let rr = res.select_rows(rows.iter());
        let (q, r) = if sub.ncols() == 0 {
            (DMatrix::zeros(rows.len(), 0), DMatrix::zeros(0, 0))
        } else {
            let qr = sub.qr();
            (qr.q(), qr.r())
        };
        let qtr = q.transpose() * &rr;
        let r_perp = &rr - &q * &qtr;
        let all = rows.iter().enumerate().all(|(i, &r)| i == r) && rows.len() == res.len();
        Projector {
            q,
            r,
            qtr,
            r_perp,
            rows,
            all,
        }
    }

    /// `(δ_F, δ_C, reduction, independence)` for candidate columns `c` (all rows);
    /// independence is NaN when the columns are zero.
    fn solve(&self, c: &DMatrix<f64>) -> (DVector<f64>, DVector<f64>, f64, f64) {
        let selected;
        let cs = if self.all {
            c
        } else {
            selected = c.select_rows(self.rows.iter());
            &selected
        };
        let qtc = self.q.transpose() * cs;
        let c_perp = cs - &self.q * &qtc;
        let r_perp = &self.r_perp;
        let k = c.ncols();
        let mut dc = DVector::zeros(k);
        let mut reduction = 0.0;
        let mut independence = 1.0;
        if k > 0 {
            let big = (0..k).map(|j| cs.column(j).norm()).fold(0.0, f64::max);
            let svd = c_perp.clone().svd(true, true);
            let smin = svd.singular_values.min();
            independence = if big > 0.0 { smin / big } else { f64::NAN };
            if let (Some(u), Some(vt)) = (&svd.u, &svd.v_t) {
                let smax = svd.singular_values.max();
                for i in 0..svd.singular_values.len() {
                    let s = svd.singular_values[i];
                    if s > 1e-12 * smax.max(1e-300) && s > 0.0 {
                        let coef = u.column(i).dot(r_perp);
                        reduction += coef * coef;
                        dc -= vt.row(i).transpose() * (coef / s);
                    }
                }
            }
        }
        let rhs = -(&self.qtr + &qtc * &dc);
        let df = if self.r.nrows() == 0 {
            DVector::zeros(0)
        } else {
            self.r
                .solve_upper_triangular(&rhs)
                .unwrap_or_else(|| DVector::zeros(rhs.len()))
        };
        (df, dc, reduction, independence)
    }
}

/// A judged refit and, when it ran, its step with the free and held parameters.
type Attempt = (
    Trial,
    Option<(
        crate::calibrate::StepResult,
        Vec<usize>,
        Vec<crate::fit::Fixed>,
    )>,
);

struct Scored {
    candidates: Vec<(usize, CandidateReport)>,
    baseline_val: Option<f64>,
    residuals: usize,
}

fn distances_of(res: &DVector<f64>, starts: &[usize], idx: &[usize]) -> Vec<f64> {
    idx.iter()
        .map(|&i| {
            let s = starts[i];
            Vector3::new(res[s], res[s + 1], res[s + 2]).norm()
        })
        .collect()
}

fn rms(d: &[f64]) -> Option<f64> {
    (!d.is_empty()).then(|| (d.iter().map(|v| v * v).sum::<f64>() / d.len() as f64).sqrt())
}

/// Scores every candidate in `remaining` at `x` with `free` estimated (see the module docs).
fn score(
    session: &Session<'_>,
    x: &[f64],
    free: &[usize],
    remaining: &[usize],
) -> Result<Scored, CalibError> {
    let model = &session.model;
    let effects = model.effects();
    let mut columns = free.to_vec();
    let mut spans = Vec::with_capacity(remaining.len());
    for &e in remaining {
        let start = columns.len();
        if let Some((_, range)) = effects.get(e) {
            columns.extend(range.clone());
        }
        spans.push(start..columns.len());
    }
    let p = free.len();
    let prep = &session.prep;
    let (j, r, starts) = dense(model, &prep.cal, x, &columns, &session.scales);
    if j.iter().chain(r.iter()).any(|v| !v.is_finite()) {
        return Err(CalibError::NonFinite {
            what: "candidate scoring".into(),
        });
    }
    let jf = j.columns(0, p).into_owned();
    let all_rows: Vec<usize> = (0..r.len()).collect();
    let full = Projector::new(&jf, &r, all_rows);
    // Held-out predictions, linearised.
    let cal_idx: Vec<usize> = (0..prep.cal.len()).collect();
    enum Held {
        Split {
            jv: DMatrix<f64>,
            rv: DVector<f64>,
            starts: Vec<usize>,
            locate: Vec<(Vec<usize>, Vec<nalgebra::Matrix3<f64>>)>,
        },
        Folds(Vec<(Projector, Vec<usize>)>),
        None,
    }
    let held = match &session.validation {
        Validation::Split { .. } => {
            let val = crate::sessions::val_for_linearisation(model, x, prep);
            let (jv, rv, sv) = dense(model, &val, x, &columns, &session.scales);
            let locate = crate::calibrate::validation_locations(model, x, prep);
            Held::Split {
                jv,
                rv,
                starts: sv,
                locate,
            }
        }
        Validation::CrossValidation { folds, .. } => {
            let mut v = Vec::with_capacity(*folds);
            for f in 0..*folds {
                let (mut train_rows, mut test) = (Vec::new(), Vec::new());
                for (i, g) in prep.groups.iter().enumerate() {
                    let size = if i + 1 < starts.len() {
                        starts[i + 1] - starts[i]
                    } else {
                        r.len() - starts[i]
                    };
                    if g % folds == f {
                        test.push(i);
                    } else {
                        train_rows.extend(starts[i]..starts[i] + size);
                    }
                }
                v.push((Projector::new(&jf, &r, train_rows), test));
            }
            Held::Folds(v)
        }
        Validation::None => Held::None,
    };
    let predict = |c_span: Option<std::ops::Range<usize>>,
                   c: &DMatrix<f64>,
                   fit: &(DVector<f64>, DVector<f64>, f64, f64)|
     -> Option<f64> {
        match &held {
            Held::Split {
                jv,
                rv,
                starts,
                locate,
            } => {
                let (df, dc) = (&fit.0, &fit.1);
                let mut pred = rv + jv.columns(0, p) * df;
                if let Some(s) = &c_span {
                    pred += jv.columns(s.start, s.len()) * dc;
                }
                // Targets only the validation measured: located from their own samples first.
                for (samples, rotations) in locate {
                    let mut sum = Vector3::zeros();
                    for (&i, rot) in samples.iter().zip(rotations) {
                        sum += rot.transpose() * pred.fixed_rows::<3>(starts[i]);
                    }
                    let offset = sum / samples.len() as f64;
                    for (&i, rot) in samples.iter().zip(rotations) {
                        let mut row = pred.fixed_rows_mut::<3>(starts[i]);
                        row -= rot * offset;
                    }
                }
                let idx: Vec<usize> = (0..starts.len()).collect();
                rms(&distances_of(&pred, starts, &idx))
            }
            Held::Folds(folds) => {
                let mut d = Vec::with_capacity(cal_idx.len());
                for (proj, test) in folds {
                    let (df, dc, _, _) = proj.solve(c);
                    // Only the test rows are needed.
                    for &i in test {
                        let s = starts[i];
                        let mut v = r.rows(s, 3).into_owned() + jf.rows(s, 3) * &df;
                        if c.ncols() > 0 {
                            v += c.rows(s, 3) * &dc;
                        }
                        d.push(v.norm());
                    }
                }
                rms(&d)
            }
            Held::None => None,
        }
    };
    let empty = DMatrix::zeros(r.len(), 0);
    let baseline_val = predict(None, &empty, &full.solve(&empty));
    // How far each row's joint moved in the calibration data (radians or metres).
    let rows = model.tree().rows();
    let mut travel = vec![(f64::INFINITY, f64::NEG_INFINITY); rows.len()];
    for o in &prep.cal {
        for (t, &q) in travel.iter_mut().zip(&o.q) {
            *t = (t.0.min(q), t.1.max(q));
        }
    }
    let still = |name: &str| {
        rows.iter()
            .position(|r| r.name == name)
            .and_then(|k| travel.get(k))
            .is_some_and(|(lo, hi)| hi - lo < MIN_JOINT_MOTION)
    };
    let mut out = Vec::with_capacity(remaining.len());
    for (&e, span) in remaining.iter().zip(&spans) {
        let c = j.columns(span.start, span.len()).into_owned();
        let fit = full.solve(&c);
        let (reduction, independence) = (fit.2, fit.3);
        // A coupling between joints of which one hardly moves is no coupling these data can
        // show (a torso held still would "couple" with whatever stands in for its deflection).
        let static_coupling = effects.get(e).is_some_and(|(eff, _)| {
            eff.label()
                .strip_prefix("coupling:")
                .and_then(|rest| rest.split_once(':'))
                .is_some_and(|(joint, driver)| still(joint) || still(driver))
        });
        // A direction backlash of a joint that hardly reverses is an offset change between
        // blocks of poses (see `effects_order::MIN_REVERSALS`).
        let one_way = effects.get(e).is_some_and(|(eff, _)| {
            eff.label()
                .strip_prefix("backlash_direction:")
                .and_then(|name| rows.iter().position(|r| r.name == name))
                .is_some_and(|k| {
                    !crate::effects_order::reverses(prep.cal.iter().map(|o| &o.context), k)
                })
        });
        let inert = independence.is_nan() || static_coupling || one_way;
        let aliased = !inert && independence < ALIAS_SINE;
        let val_rms = if aliased || inert {
            None
        } else {
            predict(Some(span.clone()), &c, &fit)
        };
        let label = effects
            .get(e)
            .map(|(eff, _)| eff.label())
            .unwrap_or_default();
        out.push((
            e,
            CandidateReport {
                label,
                parameters: span.len(),
                score: if aliased || inert { 0.0 } else { reduction },
                independence: if inert { 0.0 } else { independence },
                val_rms,
                reason: None,
                status: if inert {
                    CandidateStatus::Inert
                } else if aliased {
                    CandidateStatus::Aliased
                } else {
                    CandidateStatus::NotSelected
                },
            },
        ));
    }
    Ok(Scored {
        candidates: out,
        baseline_val,
        residuals: r.len(),
    })
}

/// BIC of a least-squares fit: `m ln(SSR/m) + p ln m` (`m` residuals, `p` parameters).
pub(crate) fn bic(ssr: f64, m: f64, p: f64) -> f64 {
    m * (ssr.max(1e-300) / m).ln() + p * m.ln()
}

/// The tests of the rule for one refit (see the module docs).
#[allow(clippy::too_many_arguments)]
fn judge(
    session: &Session<'_>,
    before: &FitOutcome,
    held_before: &[f64],
    after: &FitOutcome,
    held_after: &[f64],
    k: usize,
    k_count: usize,
    alpha: f64,
    forced: bool,
    label: String,
    step: &StepReport,
) -> Trial {
    let m = after.residual_count as f64;
    let (p0, p1) = (before.free.len() as f64, after.free.len() as f64);
    let dof = (m - p1).max(1.0);
    let f = ((before.ssr - after.ssr) / k as f64) / (after.ssr / dof).max(1e-300);
    let f_p = stats::f_sf(f, k as f64, dof);
    let f_threshold = alpha / k_count as f64;
    let bic = (bic(before.ssr, m, p0), bic(after.ssr, m, p1));
    let groups = match session.validation {
        Validation::Split { .. } => Some(&session.prep.val_groups),
        Validation::CrossValidation { .. } => Some(&session.prep.groups),
        Validation::None => None,
    };
    let held_out = groups.and_then(|g| paired_wilcoxon(held_before, held_after, g));
    let mut reasons = Vec::new();
    if !forced {
        if f_p.is_nan() || f_p >= f_threshold {
            reasons.push(format!("F-to-enter p = {f_p:.2e} >= {f_threshold:.2e}"));
        }
        if bic.1.is_nan() || bic.1 >= bic.0 {
            reasons.push("BIC does not decrease".to_string());
        }
        match held_out {
            Some((_, p)) if p < alpha => {}
            Some((_, p)) => reasons.push(format!("held-out improvement p = {p:.2e} >= {alpha}")),
            None if groups.is_some() => {
                reasons.push("held-out improvement cannot be tested".to_string())
            }
            None => {}
        }
    }
    Trial {
        label,
        rms: step.rms,
        val_rms: step.val_rms,
        f,
        f_p,
        f_threshold,
        bic,
        held_out,
        accepted: reasons.is_empty(),
        reason: reasons.join("; "),
    }
}

/// One-sided Wilcoxon signed-rank test that `after` is smaller than `before`, paired over the
/// groups of the samples (per group `Σ d_before² − d_after²`; zero differences dropped, ties
/// given mid-ranks, normal approximation with the tie correction; F. Wilcoxon, "Individual
/// comparisons by ranking methods", Biometrics Bulletin 1(6), 1945). Returns `(z, p)`;
/// `None` with fewer than 6 non-zero differences. Ranks rather than a t test because a few
/// poses that an effect fixes dominate the squared errors and make a t statistic erratic.
pub(crate) fn paired_wilcoxon(
    before: &[f64],
    after: &[f64],
    groups: &[usize],
) -> Option<(f64, f64)> {
    if before.len() != after.len() || before.len() != groups.len() || before.is_empty() {
        return None;
    }
    let mut sums: HashMap<usize, f64> = HashMap::new();
    for ((b, a), g) in before.iter().zip(after).zip(groups) {
        *sums.entry(*g).or_insert(0.0) += b * b - a * a;
    }
    let scale = sums.values().map(|v| v.abs()).fold(0.0, f64::max);
    let mut d: Vec<f64> = sums
        .into_values()
        .filter(|v| v.abs() > 1e-12 * scale)
        .collect();
    let n = d.len();
    if n < 6 {
        return None;
    }
    d.sort_by(|x, y| x.abs().total_cmp(&y.abs()));
    let (mut w_plus, mut ties) = (0.0, 0.0);
    let mut i = 0;
    while i < n {
        let mut k = i;
        while k + 1 < n && d[k + 1].abs() == d[i].abs() {
            k += 1;
        }
        let rank = (i + k) as f64 / 2.0 + 1.0;
        let t = (k - i + 1) as f64;
        ties += t * t * t - t;
        for v in &d[i..=k] {
            if *v > 0.0 {
                w_plus += rank;
            }
        }
        i = k + 1;
    }
    let nf = n as f64;
    let mean = nf * (nf + 1.0) / 4.0;
    let var = nf * (nf + 1.0) * (2.0 * nf + 1.0) / 24.0 - ties / 48.0;
    if var <= 0.0 {
        return None;
    }
    let z = (w_plus - mean) / var.sqrt();
    Some((z, stats::normal_sf(z)))
}

/// Pure error of repeated points: `(sum of squares, degrees of freedom)`.
fn pure_error(prep: &Prepared) -> Option<(f64, usize)> {
    let mut groups: HashMap<&(String, usize), Vec<Vector3<f64>>> = HashMap::new();
    for (o, key) in prep.cal.iter().zip(&prep.repeat_keys) {
        if let (Some(k), Observation::Point { point, .. }) = (key, &o.observation) {
            groups.entry(k).or_default().push(*point);
        }
    }
    let (mut ss, mut dof) = (0.0, 0usize);
    for pts in groups.values().filter(|v| v.len() > 1) {
        let mean = pts.iter().sum::<Vector3<f64>>() / pts.len() as f64;
        ss += pts.iter().map(|v| (v - mean).norm_squared()).sum::<f64>();
        dof += 3 * (pts.len() - 1);
    }
    (dof > 0).then_some((ss, dof))
}

/// Known per-axis noise of every calibration sample, when there is one.
fn known_sigmas(session: &Session<'_>) -> Option<Vec<Vector3<f64>>> {
    if let Some(s) = session.options.sigma {
        return Some(vec![Vector3::repeat(s); session.prep.cal.len()]);
    }
    let v: Option<Vec<Vector3<f64>>> = session.prep.sigmas.iter().copied().collect();
    v.filter(|v| v.iter().all(|s| s.iter().all(|x| *x > 0.0)))
}

fn residual_test(session: &Session<'_>, fit: &FitOutcome, alpha: f64) -> ResidualTest {
    let m = fit.residual_count as f64;
    let p = fit.free.len() as f64;
    let dof = (m - p).max(1.0);
    let model = &session.model;
    if let Some(sig) = known_sigmas(session) {
        let mut chi2 = 0.0;
        let mut r = [0.0; 6];
        for (o, s) in session.prep.cal.iter().zip(&sig) {
            model.residuals(&fit.x, o, &mut r);
            for a in 0..3 {
                chi2 += (r[a] / s[a]).powi(2);
            }
        }
        let pv = stats::chi2_sf(chi2, dof);
        let noise = (sig.iter().map(|s| s.norm_squared()).sum::<f64>() / sig.len() as f64).sqrt();
        return ResidualTest {
            kind: NoiseTest::KnownSigma,
            statistic: Some(chi2),
            dof: (dof, 0.0),
            p_value: Some(pv),
            noise_rms: Some(noise),
            significant: pv < alpha,
            summary: format!(
                "chi-square {chi2:.1} on {dof:.0} degrees of freedom against the known noise, p = {pv:.2e}"
            ),
        };
    }
    if let Some((ss_pe, df_pe)) = pure_error(&session.prep) {
        let df_lof = dof - df_pe as f64;
        let ss_lof = (fit.ssr - ss_pe).max(0.0);
        let noise = (3.0 * ss_pe / df_pe as f64).sqrt();
        if df_lof >= 1.0 {
            let f = (ss_lof / df_lof) / (ss_pe / df_pe as f64).max(1e-300);
            let pv = stats::f_sf(f, df_lof, df_pe as f64);
            return ResidualTest {
                kind: NoiseTest::PureError,
                statistic: Some(f),
                dof: (df_lof, df_pe as f64),
                p_value: Some(pv),
                noise_rms: Some(noise),
                significant: pv < alpha,
                summary: format!(
                    "lack of fit F = {f:.1} on ({df_lof:.0}, {df_pe}) degrees of freedom against the pure error of repeats, p = {pv:.2e}"
                ),
            };
        }
    }
    ResidualTest {
        kind: NoiseTest::None,
        statistic: None,
        dof: (0.0, 0.0),
        p_value: None,
        noise_rms: None,
        significant: true,
        summary: "no independent noise estimate (no known sigma, no repeated poses): held-out \
                  error decides"
            .into(),
    }
}

fn structure_checks(session: &Session<'_>, fit: &FitOutcome, alpha: f64) -> Vec<StructureCheck> {
    let model = &session.model;
    let prep = &session.prep;
    let rows = model.tree().rows();
    let mut res = Vec::with_capacity(prep.cal.len());
    let mut r = [0.0; 6];
    for o in &prep.cal {
        model.residuals(&fit.x, o, &mut r);
        res.push(Vector3::new(r[0], r[1], r[2]));
    }
    // One unit per pose and target: repeats are averaged, so that the test asks whether the
    // joint explains the lack of fit, not whether there is one (that is the residual test).
    let mut unit_of: HashMap<(usize, usize), usize> = HashMap::new();
    let mut units: Vec<(Vector3<f64>, usize, usize)> = Vec::new();
    for (i, o) in prep.cal.iter().enumerate() {
        let t = match o.observation {
            Observation::Point { target, .. } => target,
            Observation::Pose(_) => usize::MAX,
        };
        let next = units.len();
        let u = *unit_of.entry((prep.groups[i], t)).or_insert(next);
        if u == next {
            units.push((Vector3::zeros(), 0, i));
        }
        units[u].0 += res[i];
        units[u].1 += 1;
    }
    let means: Vec<Vector3<f64>> = units.iter().map(|(s, n, _)| s / *n as f64).collect();
    let ssr0: f64 = means.iter().map(|v| v.norm_squared()).sum();
    let joints: Vec<usize> = (0..rows.len())
        .filter(|&j| rows[j].mimic.is_none())
        .collect();
    let k_tests = (joints.len() + 1) as f64;
    let level = alpha / k_tests;
    let mut out = Vec::new();
    for &j in &joints {
        let prismatic = rows[j].kind == JointKind::Prismatic;
        let q: Vec<f64> = units
            .iter()
            .map(|(_, _, i)| prep.cal[*i].q.get(j).copied().unwrap_or(0.0))
            .collect();
        let basis = |v: f64| -> Vec<f64> {
            if prismatic {
                vec![1.0, v, v * v]
            } else {
                vec![1.0, v.sin(), v.cos(), (2.0 * v).sin(), (2.0 * v).cos()]
            }
        };
        let nb = basis(0.0).len();
        let x = DMatrix::from_fn(q.len(), nb, |i, c| basis(q[i])[c]);
        let svd = x.clone().svd(true, false);
        let Some(u) = &svd.u else { continue };
        let smax = svd.singular_values.max();
        let rank: Vec<usize> = (0..svd.singular_values.len())
            .filter(|&i| svd.singular_values[i] > 1e-9 * smax)
            .collect();
        let mut explained = 0.0;
        for a in 0..3 {
            let y = DVector::from_iterator(means.len(), means.iter().map(|v| v[a]));
            for &i in &rank {
                explained += u.column(i).dot(&y).powi(2);
            }
        }
        let d1 = (3 * rank.len()) as f64;
        let d2 = (3.0 * means.len() as f64 - fit.free.len() as f64 - d1).max(1.0);
        let f = (explained / d1) / ((ssr0 - explained).max(1e-300) / d2);
        let p = stats::f_sf(f, d1, d2);
        let res_q: Vec<f64> = prep
            .cal
            .iter()
            .map(|o| o.q.get(j).copied().unwrap_or(0.0))
            .collect();
        out.push(StructureCheck {
            variable: rows[j].name.clone(),
            statistic: f,
            p_value: p,
            significant: p < level,
            bins: bins(&res_q, &res, 8),
        });
    }
    // Pose order: pose-mean residuals in order of first appearance.
    let mut order: Vec<usize> = Vec::new();
    let mut sums: HashMap<usize, (Vector3<f64>, usize)> = HashMap::new();
    for (i, g) in prep.groups.iter().enumerate() {
        let e = sums.entry(*g).or_insert_with(|| {
            order.push(*g);
            (Vector3::zeros(), 0)
        });
        e.0 += res[i];
        e.1 += 1;
    }
    let means: Vec<Vector3<f64>> = order
        .iter()
        .map(|g| {
            let (s, n) = sums[g];
            s / n.max(1) as f64
        })
        .collect();
    if means.len() >= 4 {
        let a: Vec<f64> = means.windows(2).map(|w| w[0].dot(&w[1])).collect();
        let num: f64 = a.iter().sum();
        let den = a.iter().map(|v| v * v).sum::<f64>().sqrt();
        let z = if den > 0.0 { num / den } else { 0.0 };
        let p = 2.0 * stats::normal_sf(z.abs());
        let idx: Vec<f64> = (0..means.len()).map(|i| i as f64).collect();
        out.push(StructureCheck {
            variable: "pose order".into(),
            statistic: z,
            p_value: p,
            significant: p < level,
            bins: bins(&idx, &means, 8),
        });
    }
    out
}

/// `(centre, RMS, |mean|)` of `res` in `n` equal bins of `v`.
fn bins(v: &[f64], res: &[Vector3<f64>], n: usize) -> Vec<(f64, f64, f64)> {
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !(lo.is_finite() && hi.is_finite()) {
        return vec![];
    }
    let w = ((hi - lo) / n as f64).max(1e-12);
    let mut acc = vec![(Vector3::zeros(), 0.0, 0usize); n];
    for (x, r) in v.iter().zip(res) {
        let b = (((x - lo) / w) as usize).min(n - 1);
        acc[b].0 += r;
        acc[b].1 += r.norm_squared();
        acc[b].2 += 1;
    }
    acc.into_iter()
        .enumerate()
        .filter(|(_, a)| a.2 > 0)
        .map(|(b, (s, ss, c))| {
            (
                lo + (b as f64 + 0.5) * w,
                (ss / c as f64).sqrt(),
                (s / c as f64).norm(),
            )
        })
        .collect()
}

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
