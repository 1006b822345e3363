//! The entry points [`calibrate_sockets`] and [`diagnose_sockets`], and the shared sequence of
//! steps they run (nominal, geometric, effects).

use super::*;

/// Calibrates `tree` from the contact samples of `data` (see the module docs): the samples for
/// calibration are fitted, those marked for validation (other placements, whose sockets are
/// never fitted) give the held-out figures. The effects of `options` are estimated in one
/// `effects` step after the geometric one. The device guess and the folds of `options` are not
/// used (there is no device, and validation is by split only).
///
/// # Errors
/// [`CalibError::BadOption`] for a set with measured points, a partner socket that is not in
/// the same split or a socket whose partner differs between samples;
/// [`CalibError::TooFewSamples`] with fewer than 3 calibration contacts; and the errors of
/// [`Model::new_tree`] and [`fit::solve`].
pub fn calibrate_sockets(
    tree: &DhTree,
    data: &Measurements,
    options: &CalibrationOptions,
) -> Result<SocketReport, CalibError> {
    run_sockets(tree, data, options, None)
}

/// [`calibrate_sockets`] with the effects chosen as [`crate::diagnose`] chooses them for
/// measured points, adapted to contacts (`diag.effects`: `None` stops after the geometric step,
/// `Labels` are all estimated in one `effects` step, `Auto` selects; `options.effects` is
/// ignored).
///
/// # Automatic selection
/// 1. **Anything left?** With a known contact noise (`options.sigma`, metres per axis) the
///    chi-square `SSR / σ²` of the geometric step on `m − p` degrees of freedom (`m` residuals:
///    three per contact and one per distance, `p` free parameters, sockets included); a test
///    that finds nothing left at `diag.alpha` selects nothing. Without it the noise is
///    estimated from the same residuals and there is no test (contacts have no repeated
///    measured points for a pure error).
/// 2. **Score**: for every candidate of [`effects::candidates`], the first-order reduction of
///    the SSR (m²) by its Jacobian columns beyond those of the estimated parameters (sockets
///    included), from the QR factor of `[J_free C]`: `‖(Qᵀr)_C‖²`; its independence is the
///    smallest singular value of the `C` block of `R` over the largest column norm of `C`;
///    below [`ALIAS_SINE`] it is aliased (a scale, when one distance is all that fixes the
///    scale, is aliased only with the distances' weight) and never selected.
/// 3. **Rule**: ranked by score minus `k σ̂² ln m`, the [`DiagnoseOptions::trials`] best are
///    refitted in full in turn; the first that passes (a) F-to-enter at `alpha / K`, (b) a lower
///    BIC (both with the distances weighted as before the refit) and (c) a one-sided Wilcoxon
///    signed-rank test at `alpha` of the squared distances of the held-out contacts to their
///    socket's modelled mean, paired per contact (skipped without held-out contacts), is added
///    as a step `+<label>`; the loop repeats, up to [`DiagnoseOptions::max_effects`].
///
/// # Errors
/// Those of [`calibrate_sockets`]; [`CalibError::BadOption`] for a bad `alpha`, label or
/// inertials.
pub fn diagnose_sockets(
    tree: &DhTree,
    data: &Measurements,
    options: &CalibrationOptions,
    diag: &DiagnoseOptions,
) -> Result<SocketReport, CalibError> {
    let ctx = effect_context(tree, diag)?;
    let mut plain = options.clone();
    plain.effects.clear();
    match &diag.effects {
        EffectSelection::None => run_sockets(tree, data, &plain, None),
        EffectSelection::Labels(labels) => {
            for l in labels {
                let e = effects::parse_label_in(l, &ctx)?;
                if e.uses_sequence() {
                    return Err(CalibError::BadOption {
                        what: format!("effect '{l}'"),
                        reason: "expected an effect of the joint values, found one of the \
                                 sample order, which contact data does not carry"
                            .into(),
                    });
                }
                plain.effects.push(e);
            }
            run_sockets(tree, data, &plain, None)
        }
        EffectSelection::Auto => {
            let probe = Model::new_tree(tree, &[], &options.model)?;
            let c = effects::candidates(&ctx, &probe.tilt_rows());
            let mut skipped = c.skipped;
            skipped.push(
                "backlash_direction, drift, thermal_growth: not searched on contacts (contact data \
                 carries no sample order); gear_harmonic2, gear_harmonic:J:2, gravity_sag: not \
                 searched on contacts (the contact selection does not compare rival effects of one \
                 joint or one load), name them with --effects"
                    .into(),
            );
            let pool = c
                .effects
                .into_iter()
                .filter(|e| {
                    let l = e.label();
                    let both_harmonics = l.starts_with("gear_harmonic:") && l.ends_with(":2");
                    // A sag along gravity is a rival of the compliances carrying the same load,
                    // decided by the held-out RMS (`crate::rivals`), which the contact selection
                    // does not compare: named with a label only.
                    !(e.uses_sequence()
                        || l.starts_with("gear_harmonic2:")
                        || both_harmonics
                        || l.starts_with("gravity_sag:"))
                })
                .collect();
            let auto = Auto {
                pool,
                skipped,
                diag,
            };
            run_sockets(tree, data, &plain, Some(&auto))
        }
    }
}

pub(super) fn run_sockets(
    tree: &DhTree,
    data: &Measurements,
    options: &CalibrationOptions,
    auto: Option<&Auto<'_>>,
) -> Result<SocketReport, CalibError> {
    if data.session_count() > 1 {
        return Err(CalibError::BadOption {
            what: "contact calibration".into(),
            reason: format!(
                "expected one measurement session (the socket model has one device frame), found {} ({})",
                data.session_count(),
                data.sessions.join(", ")
            ),
        });
    }
    let prep = prepare(tree, data, None, true)?;
    let cal = contacts_of(data, &prep.cal, Split::Calibration)?;
    let val = contacts_of(data, &prep.val, Split::Validation)?;
    if cal.contacts.len() < 3 {
        return Err(CalibError::TooFewSamples {
            what: "socket calibration".into(),
            needed: 3,
            found: cal.contacts.len(),
        });
    }
    let targets: Vec<(String, usize)> = data.targets.iter().map(|t| (t.clone(), 0)).collect();
    let mut model = Model::new_tree(tree, &targets, &options.model)?;
    for e in &options.effects {
        model.add_effect(Arc::clone(e))?;
    }
    // The candidates ride along at zero (outside every step's free set) until selected.
    for e in auto.map_or(&[][..], |a| &a.pool) {
        model.add_effect(Arc::clone(e))?;
    }
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
    let n_model = model.parameter_count();
    let n_sockets = cal.names.len();
    let mut scales = model.scales();
    scales.extend(std::iter::repeat_n(1.0, 3 * n_sockets));
    let mut run = Run {
        model,
        cal,
        val,
        scales,
        options,
        sigma_point: MIN_SIGMA,
    };

    // As given: sockets at the means of their nominal points.
    let mut x = vec![0.0; n_model + 3 * n_sockets];
    let start = means(
        &positions(&run.model, &x, &run.cal.contacts),
        &run.cal.contacts,
        n_sockets,
    );
    for (s, (m, _)) in start.iter().enumerate() {
        x[n_model + 3 * s..n_model + 3 * s + 3].copy_from_slice(m.as_slice());
    }
    let sockets_given: Vec<Vector3<f64>> = start.iter().map(|m| m.0).collect();
    let x_given = x.clone();
    let mut consistency: Vec<ConsistencyStep> =
        run.consistency("as given", &x).into_iter().collect();

    let measured_target = |k: usize| run.cal.contacts.iter().any(|c| c.target == k);
    let targets_used: Vec<bool> = (0..run.model.targets().len())
        .map(measured_target)
        .collect();
    let socket_cols: Vec<usize> = (n_model..n_model + 3 * n_sockets).collect();
    let mut nominal_free = run
        .model
        .indices(|b| matches!(b, Block::Target(k) if targets_used[k]));
    nominal_free.extend(&socket_cols);
    let (out, report) = run.step("nominal", &x, &nominal_free)?;
    x = out.x;
    let targets_nominal: Vec<Vector3<f64>> = (0..run.model.targets().len())
        .map(|k| run.model.target_at(&x, k))
        .collect();
    let mut steps = vec![report];
    consistency.extend(run.consistency("nominal", &x));

    let mut geometric = run.model.indices(|b| {
        !matches!(b, Block::Effect(_)) && !matches!(b, Block::Target(k) if !targets_used[k])
    });
    geometric.extend(&socket_cols);
    let (free, mut fixed) = run.identify(&x, &geometric)?;
    let (mut last, report) = run.step("geometric", &x, &free)?;
    steps.push(report);
    consistency.extend(run.consistency("geometric", &last.x));

    let mut selection = None;
    if let Some(a) = auto {
        let mut state = Chosen {
            last,
            free,
            fixed,
            steps,
            consistency,
        };
        selection = Some(select(&mut run, a, &mut state)?);
        Chosen {
            last,
            fixed,
            steps,
            consistency,
            ..
        } = state;
    } else if !options.effects.is_empty() {
        let mut all: Vec<usize> = run
            .model
            .indices(|b| !matches!(b, Block::Target(k) if !targets_used[k]));
        all.extend(&socket_cols);
        let (free, fixed2) = run.identify(&last.x, &all)?;
        fixed = fixed2;
        let (o, report) = run.step("effects", &last.x, &free)?;
        last = o;
        steps.push(report);
        consistency.extend(run.consistency("effects", &last.x));
    }

    let x = last.x.clone();
    let problem = run.problem(run.sigma_point);
    let sockets: Vec<SocketEstimate> = (0..n_sockets)
        .map(|s| {
            let o = n_model + 3 * s;
            let se = |i: usize| last.std_errors.get(o + i).copied().flatten();
            SocketEstimate {
                name: run.cal.names[s].clone(),
                position: problem.socket_at(&x, s),
                std_error: match (se(0), se(1), se(2)) {
                    (Some(a), Some(b), Some(c)) => Some(Vector3::new(a, b, c)),
                    _ => None,
                },
                samples: run.cal.contacts.iter().filter(|c| c.socket == s).count(),
            }
        })
        .collect();
    // Candidates never selected are no parameters of the result.
    let unselected = |b: Block| match (b, &selection) {
        (Block::Effect(e), Some(sel)) => !sel.selected.contains(&e),
        _ => false,
    };
    let mut parameters: Vec<ParameterEstimate> = estimates(&run.model, &x, &last, &targets_nominal)
        .into_iter()
        .zip(run.model.parameters())
        .filter(|(_, p)| !unselected(p.block))
        .map(|(e, _)| e)
        .collect();
    for (s, est) in sockets.iter().enumerate() {
        for (axis, name) in ["x", "y", "z"].iter().enumerate() {
            parameters.push(ParameterEstimate {
                name: format!("socket.{}.{name}", est.name),
                nominal: sockets_given[s][axis],
                estimate: est.position[axis],
                std_error: est.std_error.map(|v| v[axis]),
                free: last.free.contains(&(n_model + 3 * s + axis)),
            });
        }
    }
    let mut notes = vec![
        "the device frame is not observable from contacts with unknown sockets (gauge freedom): \
         it is held at the robot's base link frame and the sockets are in that frame"
            .to_string(),
    ];
    if run.cal.constraints.is_empty() {
        notes.push(
            "no distance between sockets is known: the scale of the robot is not observable".into(),
        );
    }
    let tree_at = run.model.tree_at(&x);
    let fixed: Vec<FixedParameter> = fixed
        .iter()
        .filter(|f| {
            !run.model
                .parameters()
                .get(f.index)
                .is_some_and(|p| unselected(p.block))
        })
        .map(|f| FixedParameter {
            name: run.name_of(f.index),
            aliases: f.aliases.iter().map(|&a| run.name_of(a)).collect(),
        })
        .collect();
    let effects = run.model.effects();
    let selected_effects: Vec<String> = match &selection {
        Some(sel) => sel
            .selected
            .iter()
            .filter_map(|&e| effects.get(e).map(|(eff, _)| eff.label()))
            .collect(),
        None => options.effects.iter().map(|e| e.label()).collect(),
    };
    let mut distances = Vec::with_capacity(data.samples.len());
    for (split, part) in [
        (Split::Calibration, &run.cal),
        (Split::Validation, &run.val),
    ] {
        let before = distances_to_means(&run.model, &x_given, part);
        let after = distances_to_means(&run.model, &x, part);
        let samples = data
            .samples
            .iter()
            .enumerate()
            .filter(|(_, s)| s.split == split);
        for (((i, _), c), (b, a)) in samples.zip(&part.contacts).zip(before.iter().zip(&after)) {
            distances.push(ContactDistance {
                sample: i,
                validation: split == Split::Validation,
                socket: part.names.get(c.socket).cloned().unwrap_or_default(),
                as_given: *b,
                last: *a,
            });
        }
    }
    distances.sort_by_key(|d| d.sample);
    let (candidates, trials) = match selection {
        Some(sel) => {
            notes.extend(sel.notes);
            (sel.candidates, sel.trials)
        }
        None => (Vec::new(), Vec::new()),
    };
    Ok(SocketReport {
        steps,
        parameters,
        fixed,
        calibrated: tree_at.trunk().clone(),
        targets: (0..run.model.targets().len())
            .map(|k| (run.model.targets()[k].0.clone(), run.model.target_at(&x, k)))
            .collect(),
        condition_number: last.condition_number,
        sigma_hat: last.sigma,
        notes,
        consistency,
        sockets,
        constraints: run.cal.constraints.clone(),
        sigma_point: run.sigma_point,
        selected_effects,
        candidates,
        trials,
        distances,
    })
}
