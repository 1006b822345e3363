//! The diagnosis's entry point for serial robots ([`diagnose`]; [`diagnose_tree`] reruns it
//! when outliers are given back, see `rejudge`) and its selection loop
//! (module docs, steps 1, 4 and 5): test the geometric fit's residual, rank the candidates,
//! refit and judge the best and their rivals, add the winner, repeat; then the final
//! residual's structure and the notes.

use super::rejudge::{rejudge, Judgement, Rejudged, Rejudgement};
use super::*;

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
        gravity_vector: diag.gravity,
    })
}

/// One diagnosis whose outlier screen judges the points against the geometry and the effects
/// of `judged`, flagging only its samples (`None`: the geometric model, or the declared
/// labels, flagging any); `judged` carries that screen's findings, made by the run before.
/// With `may_rejudge`, the points it left out are judged again ([`rejudge()`]) against the
/// effects selected so far once it has added 1, 2, 4, 8... of them, and against all it
/// selected before the report is finished, so that a run whose selection runs again stops
/// there and spends nothing on the rest of its rounds or on its report (the structure
/// checks).
pub(super) fn diagnose_judged(
    tree: &DhTree,
    data: &Measurements,
    options: &CalibrationOptions,
    diag: &DiagnoseOptions,
    judged: Option<Rejudged>,
    may_rejudge: bool,
) -> Result<Judgement, CalibError> {
    let ctx = effect_context(tree, diag)?;
    // The verdict's gravity structure tests read the gravity (and masses) of the effects.
    let options = &CalibrationOptions {
        gravity: Some(match &ctx.gravity {
            Some(g) => g.clone(),
            None => Arc::new(GravityModel::new(
                tree,
                &crate::gravity::Inertials::default(),
                diag.gravity,
            )?),
        }),
        ..options.clone()
    };
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
    let (judged_with, within, screened) = match &judged {
        Some((e, w, scan)) => (&e[..], Some(w), Some(scan.clone())),
        None => (if forced { &pool[..] } else { &[][..] }, None, None),
    };
    // The held-out figures of the geometric step and of every step after it (the trials and
    // the steps the report lists) step each fold once from the fit (`Folds::OneStep`); without
    // candidates the geometric step's folds are refitted.
    let folds = if pool.is_empty() {
        Folds::Refit
    } else {
        Folds::OneStep
    };
    let crate::calibrate::Fitted {
        mut session,
        geo,
        scan,
    } = crate::calibrate::fitted_session(
        tree,
        data,
        options,
        &pool,
        (judged_with, within),
        screened,
        folds,
    )?;
    // The points left out, judged against each candidate's fit too.
    let directions = pool.iter().any(|e| e.uses_sequence());
    let kept_val_groups = session.prep.val_groups.clone();
    session.left_out = crate::calibrate::LeftOut::new(
        tree,
        data,
        options,
        scan.as_ref(),
        directions,
        (&kept_val_groups, evidence::MIN_POSES),
    )?;
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
    // The last judgement again of the points left out, and after how many selected effects.
    let mut confirmed = None;
    let mut judged_last = 0;
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
                // An effect with a shape (a time constant) starts from a grid over it.
                let start = crate::calibrate::shape_start(&session, &last.x, &columns)?;
                let (trial_free, trial_fixed, factor) =
                    session.identify_factored(&start, &columns)?;
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
                // The identifiability's factor is the fit's first when every column is free.
                let step = session.step_from(
                    &format!("+{label}"),
                    &start,
                    &trial_free,
                    steps.last(),
                    Folds::OneStep,
                    factor.filter(|_| trial_free == columns),
                )?;
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
            let mut made = Attempts::new(&attempt);
            // The refits of this round that failed, kept for the comparison of nested rivals.
            let mut failed: HashMap<usize, (usize, nested::Fitted)> = HashMap::new();
            let tried: Vec<Wanted> = eligible.iter().take(tries).map(|c| (c.0, c.2)).collect();
            for (t, &(e, _)) in tried.iter().enumerate() {
                // One at a time: the next is needed only when this one fails.
                let (trial, fitted) = made.take(&tried[t..=t])?;
                let ok = trial.accepted;
                round.trials.push(trial);
                let fitted = match fitted {
                    Some(f) if ok => f,
                    other => {
                        if let Some(f) = other {
                            failed.insert(e, (round.trials.len() - 1, f));
                        }
                        rejected.push(e);
                        continue;
                    }
                };
                // It passes: its rivals (the other eligible candidates that change the same
                // quantity of the same joint) are refitted too, and the best of those that
                // pass is added (see `rivals`).
                let mut passed = vec![(e, round.trials.len() - 1, fitted)];
                if !forced {
                    // The round's linearised held-out RMS of a candidate.
                    let val = |x: usize| {
                        table
                            .iter()
                            .find(|(y, _)| *y == x)
                            .and_then(|(_, c)| c.val_rms)
                    };
                    let rivals: Vec<Wanted> = eligible
                        .iter()
                        .filter(|&&(r, _, _)| {
                            r != e
                                && !rejected.contains(&r)
                                && rivals::are_rivals(pool[e].as_ref(), pool[r].as_ref())
                                && !rivals::cannot_win(
                                    pool[e].as_ref(),
                                    pool[r].as_ref(),
                                    val(e),
                                    val(r),
                                )
                        })
                        .map(|c| (c.0, c.2))
                        .collect();
                    for (i, &(r, _)) in rivals.iter().enumerate() {
                        let (trial, fitted) = made.take(&rivals[i..])?;
                        let ok = trial.accepted;
                        round.trials.push(trial);
                        let at = round.trials.len() - 1;
                        match fitted {
                            Some(f) if ok => passed.push((r, at, f)),
                            other => {
                                if let Some(f) = other {
                                    failed.insert(r, (at, f));
                                }
                                rejected.push(r);
                            }
                        }
                    }
                }
                let best = rivals::best(
                    &passed
                        .iter()
                        .map(|p| &round.trials[p.1])
                        .collect::<Vec<_>>(),
                );
                // Nested rivals: the simpler kept unless the extra terms are significant.
                let (best, displaced) = if forced {
                    (best, None)
                } else {
                    nested::settle(
                        &pool,
                        &mut round.trials,
                        &mut passed,
                        &mut failed,
                        &mut rejected,
                        best,
                        diag.alpha,
                        &mut notes,
                    )
                };
                let winner = round.trials[passed[best].1].clone();
                for (i, (r, t, _)) in passed.iter().enumerate() {
                    if i != best {
                        let trial = &mut round.trials[*t];
                        trial.accepted = false;
                        trial.reason = rivals::reason(&winner, trial);
                        rejected.push(*r);
                    }
                }
                if let Some((t, reason)) = displaced {
                    round.trials[t].reason = reason;
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
                    // The points left out are judged again once the first, second, fourth,
                    // eighth... effect is in: when it gives some back, the rest of this run
                    // would select on data without them, so the selection runs again at once.
                    // (A judgement costs a fit with the effects; doubling the count between
                    // them bounds what points that stay out cost to about log2 of it.)
                    if may_rejudge && !forced && selected.len().is_power_of_two() {
                        let so_far: Vec<Arc<dyn Effect>> =
                            selected.iter().map(|&e| pool[e].clone()).collect();
                        let at = (&session, &last.x[..], free.len());
                        match rejudge(tree, data, options, scan.as_ref(), &so_far, at)? {
                            Rejudgement::Changed(judged) => {
                                let (before, again) = *judged;
                                return Ok(Judgement::Again(Box::new((so_far, before, again))));
                            }
                            Rejudgement::Nothing => confirmed = None,
                            Rejudgement::Confirmed(labels, again) => {
                                confirmed = Some((labels, again))
                            }
                        }
                        judged_last = selected.len();
                    }
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
            // A rival that lost is that, even when a later round finds it aliased with what
            // was added (a bigger harmonic once the smaller is in).
            (Some(_), Some((CandidateStatus::Rival, reason))) => {
                c.reason = Some(reason.clone());
                CandidateStatus::Rival
            }
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
    let effects: Vec<Arc<dyn Effect>> = selected.iter().map(|&e| pool[e].clone()).collect();
    if may_rejudge && judged_last != selected.len() {
        confirmed = None;
        let at = (&session, &last.x[..], free.len());
        match rejudge(tree, data, options, scan.as_ref(), &effects, at)? {
            Rejudgement::Changed(judged) => {
                let (before, again) = *judged;
                return Ok(Judgement::Again(Box::new((effects, before, again))));
            }
            Rejudgement::Nothing => {}
            Rejudgement::Confirmed(labels, again) => confirmed = Some((labels, again)),
        }
    }
    // Points still left out that a candidate explains are its evidence: the selection runs
    // again with them (see `evidence`).
    if may_rejudge && !forced {
        let found = evidence::left_out_evidence(
            tree,
            data,
            options,
            &session,
            &last.x,
            &pool,
            (&selected, &free),
            scan.as_ref(),
            diag.alpha,
        )?;
        if let Some(again) = found {
            return Ok(Judgement::Again(Box::new(again)));
        }
    }
    let effect_parameters = effect_estimates(&session.model, &last, &selected);
    let hidden: Vec<usize> = all_effects
        .iter()
        .copied()
        .filter(|e| !selected.contains(e))
        .collect();
    let mut report = session.report(&last, steps, fixed, &hidden);
    if let Validation::CrossValidation { one_step, .. } = &mut report.validation {
        *one_step = folds == Folds::OneStep;
    }
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
    // The verdict's structure checks are those of the final fit at `diag.alpha`: the
    // diagnosis reads them rather than running them again.
    let structure = report.verdict.structure.clone();
    for s in structure.iter().filter(|s| s.significant) {
        notes.push(format!(
            "structure remains that no candidate explains: the residual depends on {} \
             (statistic {:.3}, p = {:.2e}); see its bins",
            s.variable, s.statistic, s.p_value
        ));
    }
    if let Some(note) = time_note(data, &report.selected_effects) {
        notes.push(note);
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
    Ok(Judgement::Final(Box::new(report), confirmed, effects))
}

/// The note that a selected effect of time read the pose order because the samples carry no
/// time (its time constant is then a fraction of the session, poses taken as evenly spaced).
fn time_note(data: &Measurements, selected: &[String]) -> Option<String> {
    let timed = selected.iter().any(|l| l == crate::effects_thermal::LABEL);
    (timed && !crate::effects_order::has_times(data)).then(|| {
        format!(
            "{}: the samples carry no time (no `time` column), so t is the pose order in [0, 1] \
             and tau a fraction of the session (poses taken as evenly spaced in time)",
            crate::effects_thermal::LABEL
        )
    })
}
