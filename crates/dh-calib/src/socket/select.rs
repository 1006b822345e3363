//! The automatic selection of effects for a socket calibration (as [`crate::diagnose`] does for
//! points, on contacts): its candidates, state and result, and the parameter estimates of the
//! final fit.

use super::*;

/// The candidates of an automatic selection and its options.
pub(super) struct Auto<'a> {
    pub(super) pool: Vec<Arc<dyn Effect>>,
    pub(super) skipped: Vec<String>,
    pub(super) diag: &'a DiagnoseOptions,
}

/// What the automatic selection leaves.
pub(super) struct Selection {
    pub(super) selected: Vec<usize>,
    pub(super) candidates: Vec<CandidateReport>,
    pub(super) trials: Vec<Trial>,
    pub(super) notes: Vec<String>,
}

/// The state the automatic selection advances: the last fit, its free and fixed parameters,
/// the steps and consistency figures so far.
pub(super) struct Chosen {
    pub(super) last: FitOutcome,
    pub(super) free: Vec<usize>,
    pub(super) fixed: Vec<fit::Fixed>,
    pub(super) steps: Vec<SocketStep>,
    pub(super) consistency: Vec<ConsistencyStep>,
}

/// The automatic selection of [`diagnose_sockets`] on the candidates of `auto` (the model's
/// effects, in the same order), from the geometric step in `state`.
pub(super) fn select(
    run: &mut Run<'_>,
    auto: &Auto<'_>,
    state: &mut Chosen,
) -> Result<Selection, CalibError> {
    let diag = auto.diag;
    let mut out = Selection {
        selected: Vec::new(),
        candidates: Vec::new(),
        trials: Vec::new(),
        notes: auto.skipped.clone(),
    };
    if auto.pool.is_empty() {
        return Ok(out);
    }
    let residuals = 3 * run.cal.contacts.len() + run.cal.constraints.len();
    let m = residuals as f64;
    // Step 1: anything left?
    let mut proceed = true;
    match run.options.sigma {
        Some(sigma) => {
            let ssr = fit::sum_of_squares(&run.problem(sigma), &state.last.x).unwrap_or(f64::NAN);
            let chi2 = ssr / (sigma * sigma);
            let dof = (m - state.free.len() as f64).max(1.0);
            let p = stats::chi2_sf(chi2, dof);
            let summary = format!(
                "chi-square {chi2:.1} on {dof:.0} degrees of freedom against the given contact \
                 noise, p = {p:.2e}"
            );
            out.notes
                .push(format!("residual after the geometric step: {summary}"));
            if p >= diag.alpha {
                out.notes.push(
                    "nothing significant is left after the geometric step; no effect is selected"
                        .into(),
                );
                proceed = false;
            }
        }
        None => out.notes.push(
            "residual after the geometric step: no test (the contact noise is estimated from the \
             same residuals; give --sigma for a chi-square test)"
                .into(),
        ),
    }
    if run.val.contacts.is_empty() {
        out.notes.push(
            "no held-out contacts: the selection rests on the F-to-enter and BIC tests alone"
                .into(),
        );
    }
    let mut rejected: Vec<usize> = Vec::new();
    let mut first = true;
    loop {
        let remaining: Vec<usize> = (0..auto.pool.len())
            .filter(|e| !out.selected.contains(e))
            .collect();
        if remaining.is_empty() {
            break;
        }
        let mut table: Vec<(usize, CandidateReport)> = Vec::with_capacity(remaining.len());
        for &e in &remaining {
            table.push((e, run.score(&state.last.x, &state.free, e)?));
        }
        table.sort_by(|a, b| b.1.score.total_cmp(&a.1.score));
        if first {
            out.candidates = table.iter().map(|(_, c)| c.clone()).collect();
            first = false;
        }
        if !proceed {
            break;
        }
        if out.selected.len() >= diag.max_effects {
            out.notes.push(format!(
                "stopped after the most effects allowed ({}); candidates may remain",
                diag.max_effects
            ));
            break;
        }
        let sigma0 = run.sigma_point;
        let problem = run.problem(sigma0);
        let ssr0 = fit::sum_of_squares(&problem, &state.last.x).unwrap_or(f64::NAN);
        let p0 = state.free.len() as f64;
        let sigma2 = ssr0 / (m - p0).max(1.0);
        let mut eligible: Vec<(usize, f64, usize)> = table
            .iter()
            .filter(|(e, c)| c.status == CandidateStatus::NotSelected && !rejected.contains(e))
            .map(|(e, c)| {
                let gain = c.score - c.parameters as f64 * sigma2 * m.ln();
                (*e, gain, c.parameters)
            })
            .filter(|(_, gain, _)| *gain > 0.0)
            .collect();
        eligible.sort_by(|a, b| b.1.total_cmp(&a.1));
        let k_count = eligible.len().max(1);
        let f_threshold = diag.alpha / k_count as f64;
        let held_before = run.held_out_distances(&state.last.x);
        let mut accepted = false;
        for &(e, _, k) in eligible.iter().take(diag.trials.max(1)) {
            let label = auto.pool[e].label();
            let cols: Vec<usize> = run
                .model
                .effects()
                .get(e)
                .map(|(_, r)| r.clone().collect())
                .unwrap_or_default();
            let mut columns = state.free.clone();
            columns.extend(&cols);
            let (trial_free, trial_fixed) = run.identify(&state.last.x, &columns)?;
            if cols.iter().any(|c| !trial_free.contains(c)) {
                out.trials.push(Trial {
                    label,
                    rms: f64::NAN,
                    val_rms: None,
                    f: 0.0,
                    f_p: 1.0,
                    f_threshold,
                    bic: (f64::NAN, f64::NAN),
                    held_out: None,
                    accepted: false,
                    reason: "not identifiable with the estimated parameters".into(),
                });
                rejected.push(e);
                continue;
            }
            let (outcome, report) = run.step(&format!("+{label}"), &state.last.x, &trial_free)?;
            // Both fits judged with the distances weighted alike.
            let ssr1 = fit::sum_of_squares(&run.problem(sigma0), &outcome.x).unwrap_or(f64::NAN);
            let p1 = trial_free.len() as f64;
            let dof = (m - p1).max(1.0);
            let f = ((ssr0 - ssr1) / k as f64) / (ssr1 / dof).max(1e-300);
            let f_p = stats::f_sf(f, k as f64, dof);
            let bics = (bic(ssr0, m, p0), bic(ssr1, m, p1));
            let held_after = run.held_out_distances(&outcome.x);
            let pairs: Vec<usize> = (0..held_after.len()).collect();
            let held_out = paired_wilcoxon(&held_before, &held_after, &pairs);
            let mut reasons = Vec::new();
            if f_p.is_nan() || f_p >= f_threshold {
                reasons.push(format!("F-to-enter p = {f_p:.2e} >= {f_threshold:.2e}"));
            }
            if bics.1.is_nan() || bics.1 >= bics.0 {
                reasons.push("BIC does not decrease".to_string());
            }
            match held_out {
                Some((_, p)) if p < diag.alpha => {}
                Some((_, p)) => {
                    reasons.push(format!(
                        "held-out improvement p = {p:.2e} >= {}",
                        diag.alpha
                    ));
                }
                None if !held_after.is_empty() => {
                    reasons.push("held-out improvement cannot be tested".to_string());
                }
                None => {}
            }
            let ok = reasons.is_empty();
            out.trials.push(Trial {
                label,
                rms: report.rms,
                val_rms: report.val_rms,
                f,
                f_p,
                f_threshold,
                bic: bics,
                held_out,
                accepted: ok,
                reason: reasons.join("; "),
            });
            if let Some(c) = out
                .candidates
                .iter_mut()
                .find(|c| c.label == auto.pool[e].label() && c.val_rms.is_none())
            {
                c.val_rms = report.val_rms;
            }
            if ok {
                out.selected.push(e);
                let label = report.label.clone();
                state.steps.push(report);
                state
                    .consistency
                    .extend(run.consistency(&label, &outcome.x));
                state.last = outcome;
                state.free = trial_free;
                // What the geometric step could not identify stays fixed.
                state.fixed.extend(trial_fixed);
                accepted = true;
                // A rejection in one round may pass once another effect is in.
                rejected.clear();
                break;
            }
            run.sigma_point = sigma0;
            rejected.push(e);
        }
        if !accepted {
            break;
        }
    }
    for c in &mut out.candidates {
        let e = auto.pool.iter().position(|p| p.label() == c.label);
        c.status = match e {
            Some(e) if out.selected.contains(&e) => CandidateStatus::Selected,
            _ if out.trials.iter().any(|t| t.label == c.label && !t.accepted) => {
                CandidateStatus::Rejected
            }
            _ => c.status,
        };
    }
    Ok(out)
}

/// Parameter estimates of the model's own parameters in the report's layout: pose blocks as
/// `x y z` metres and roll-pitch-yaw radians (their standard errors are those of the block's
/// small-motion parameters, equal to first order for the small corrections fitted here), DH
/// parameters as nominal value plus error, targets in the tip frame.
pub(super) fn estimates(
    model: &Model,
    x: &[f64],
    fit: &FitOutcome,
    targets_nominal: &[Vector3<f64>],
) -> Vec<ParameterEstimate> {
    let params = model.parameters();
    let nominal = model.nominal();
    let free = |c: usize| fit.free.contains(&c);
    let std = |c: usize| fit.std_errors.get(c).copied().flatten();
    let mut out = Vec::with_capacity(params.len());
    for (c, p) in params.iter().enumerate() {
        let axis = match p.field {
            Field::X | Field::Rx => 0,
            Field::Y | Field::Ry => 1,
            _ => 2,
        };
        let rot = usize::from(matches!(p.field, Field::Rx | Field::Ry | Field::Rz)) * 3;
        let pose = |nom: &Isometry3<f64>| {
            (
                xyz_rpy(nom)[axis + rot],
                xyz_rpy(&model.pose_at(x, p.block))[axis + rot],
            )
        };
        let (nom, est) = match p.block {
            Block::Device | Block::Session(_) => pose(&Isometry3::identity()),
            Block::Base => pose(&nominal.base),
            Block::Tool => pose(&nominal.tool),
            Block::Mount(b) => pose(
                &model
                    .tree()
                    .branches()
                    .get(b)
                    .map_or_else(Isometry3::identity, |br| br.table.base),
            ),
            Block::Joint(r) => {
                let row = &nominal.rows[r];
                let nom = match p.field {
                    Field::A => row.a,
                    Field::Alpha => row.alpha,
                    Field::D => row.d,
                    Field::Theta => row.theta,
                    Field::Beta => row.beta,
                    _ => 0.0,
                };
                (nom, nom + x[c])
            }
            Block::Target(k) => (
                targets_nominal.get(k).map_or(0.0, |t| t[axis]),
                model.target_at(x, k)[axis],
            ),
            Block::Effect(_) => (0.0, x[c]),
        };
        out.push(ParameterEstimate {
            name: p.name.clone(),
            nominal: nom,
            estimate: est,
            std_error: std(c),
            free: free(c),
        });
    }
    out
}
