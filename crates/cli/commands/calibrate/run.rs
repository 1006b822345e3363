//! Running `calibrate`: [`calibrate`] itself (the serial path; contacts go to
//! `crate::commands::sockets`, trees to `crate::commands::calibrate_tree`), `--effects auto`
//! ([`auto_report`]), and the JSON document of a report ([`CalibrationDoc`]; metres, radians).

use super::*;

/// `--effects auto`: calibrate with the effects the diagnosis of `dh-calib` selects
/// (`dh_calib::diagnose`), returning its report (steps `nominal`, `geometric`, then one
/// `+<label>` per effect added, and the candidate table) and the effects it selected (for the
/// residual chart).
///
/// # Errors
/// A calibration or diagnosis that fails (bad inertials, too few samples).
pub fn auto_report(
    table: &DhTable,
    data: &Measurements,
    options: &CalibrationOptions,
    diag: &DiagnoseOptions,
    ctx: &EffectContext,
) -> Result<(Report, Vec<Arc<dyn Effect>>)> {
    let report = diagnose(table, data, options, diag)
        .map_err(|e| anyhow::anyhow!("calibration failed: {e}"))?;
    let effects = report
        .selected_effects
        .iter()
        .map(|l| parse_label_in(l, ctx).map_err(|e| anyhow::anyhow!("{e}")))
        .collect::<Result<_>>()?;
    Ok((report, effects))
}

/// Runs `calibrate`.
///
/// # Errors
/// Bad model or data files (naming the file, line and column), unknown effects, a calibration
/// that cannot start (too few samples, collinear points), failed writes.
pub fn calibrate(
    args: &CalibrateArgs,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> Result<Outcome> {
    let inputs = load_inputs(args, err)?;
    if inputs.data.samples.iter().any(|s| s.socket.is_some()) {
        return crate::commands::sockets::calibrate_contacts(args, &inputs, out, err);
    }
    enough_samples(&inputs.data, &display_name(&args.data))?;
    let (inertials, gravity) = gravity_inputs(args, &inputs.table)?;
    let ctx = EffectContext {
        tree: DhTree::serial(&inputs.table),
        gravity: match &inertials {
            Some(i) => Some(Arc::new(
                GravityModel::serial(&inputs.table, i, gravity)
                    .map_err(|e| anyhow::anyhow!("inertials: {e}"))?,
            )),
            None => None,
        },
    };
    let effects: Vec<Arc<dyn Effect>> = match &args.effects {
        EffectsChoice::List(labels) => labels
            .iter()
            .map(|l| match parse_label_in(l, &ctx) {
                Ok(e) => Ok(e),
                // The CLI's message names the kinds and joints.
                Err(_) => parse_effect(l, &inputs.table),
            })
            .collect::<Result<_>>()?,
        EffectsChoice::None | EffectsChoice::Auto => Vec::new(),
    };
    if let Some(s) = args.sigma {
        if !(s.is_finite() && s > 0.0) {
            anyhow::bail!("--sigma: expected a positive length, found {s}");
        }
    }
    let options = CalibrationOptions {
        folds: args.folds,
        sigma: args.sigma.map(|s| s * args.units.length.metres()),
        effects: effects.clone(),
        // The CPA table is already in the device frame: its base is DH frame 0 there.
        device_guess: inputs.cpa.then(Isometry3::identity),
        outliers: OutlierOptions {
            keep: args.keep_outliers,
            ..OutlierOptions::default()
        },
        ..CalibrationOptions::default()
    };
    let cal = inputs
        .data
        .samples
        .iter()
        .filter(|s| s.split == Split::Calibration)
        .count();
    // A rough size of the work: samples times folds times steps.
    if cal * (args.folds + 1) * (2 + usize::from(!effects.is_empty())) > 200_000 {
        writeln!(
            err,
            "urdf-dh: calibrating {} ({} samples, {} targets, {}-fold cross-validation unless there is a validation split); this may take a while",
            inputs.model_name,
            cal,
            inputs.data.targets.len(),
            args.folds
        )?;
    }
    let failed = |e: dh_calib::CalibError| {
        anyhow::anyhow!("{}: calibration failed: {e}", display_name(&args.data))
    };
    let progress = crate::progress::Progress::start(
        &format!(
            "calibrating {} against {} ({cal} samples{})",
            inputs.model_name,
            display_name(&args.data),
            if args.effects == EffectsChoice::Auto {
                ", effects searched"
            } else {
                ""
            }
        ),
        args.quiet,
    );
    let (report, effects) = match &args.effects {
        EffectsChoice::Auto => {
            let diag = DiagnoseOptions {
                inertials,
                gravity,
                max_effects: args.max_effects,
                ..DiagnoseOptions::default()
            };
            auto_report(&inputs.table, &inputs.data, &options, &diag, &ctx)?
        }
        EffectsChoice::None | EffectsChoice::List(_) => (
            run_calibration(&inputs.table, &inputs.data, &options).map_err(failed)?,
            effects,
        ),
    };
    drop(progress);
    let mut doc = document(args, &inputs, &report);
    // Every output file is built (and the model proved as written) before any is written, and
    // all are written or none.
    let mut files = Vec::new();
    if let Some(path) = &args.out {
        let (text, proof) = model_text(path, args.model.as_deref(), &inputs, &report, &doc)?;
        let passed = proof.passed;
        doc.written = Some(proof);
        if passed {
            if path.to_ascii_lowercase().ends_with(".urdf") && !report.selected_effects.is_empty() {
                writeln!(
                    err,
                    "urdf-dh: warning: {}: a URDF cannot express the estimated effects {}; it holds the geometric part (write a sheet to keep them)",
                    display_name(path),
                    report.selected_effects.iter().map(|e| format!("'{e}'")).collect::<Vec<_>>().join(", ")
                )?;
            }
            files.push((Path::new(path), text));
        }
    }
    let proved = doc.written.as_ref().is_none_or(|w| w.passed);
    if let Some(path) = &args.plot {
        // Residuals are millimetres or less on any arm: the chart reads best in mm whatever
        // the report's unit.
        let chart = chart(
            &display_name(&args.data),
            &inputs,
            &report,
            &effects,
            LengthUnit::Mm,
        )?;
        files.push((Path::new(path), residuals_svg(&chart)));
    }
    // A model that fails its proof is not written, and neither is anything else.
    // `--out -` or `--plot -`: that artefact on standard output, the report on standard error.
    let piped = crate::output::any_stdout([args.out.as_deref(), args.plot.as_deref()]);
    if proved {
        let files: Vec<(&Path, &[u8])> = files.iter().map(|(p, b)| (*p, b.as_bytes())).collect();
        crate::output::write_all_or_stdout(&files, out)?;
    }
    let report_sink: &mut dyn Write = if piped { err } else { out };
    match args.format {
        CalibrateFormat::Json => {
            report_sink.write_all((serde_json::to_string_pretty(&doc)? + "\n").as_bytes())?;
        }
        CalibrateFormat::Text => report_sink.write_all(text(&doc, &inputs).as_bytes())?,
    }
    Ok(if proved {
        Outcome::Pass
    } else {
        Outcome::Differs
    })
}

pub(super) fn document(args: &CalibrateArgs, inputs: &Inputs, report: &Report) -> CalibrationDoc {
    let validation = match &report.validation {
        Validation::Split { samples } => ValidationDoc {
            method: "split",
            samples: Some(*samples),
            folds: None,
            groups: None,
            training_subsample: None,
        },
        Validation::CrossValidation {
            folds,
            groups,
            training_subsample,
        } => ValidationDoc {
            method: "k-fold",
            samples: None,
            folds: Some(*folds),
            groups: Some(*groups),
            training_subsample: *training_subsample,
        },
        Validation::None => ValidationDoc {
            method: "none",
            samples: None,
            folds: None,
            groups: None,
            training_subsample: None,
        },
    };
    let val_count = inputs
        .data
        .samples
        .iter()
        .filter(|s| s.split == Split::Validation)
        .count();
    let (outliers, verdict, diagnosis) = crate::commands::calibrate_findings::documents(report);
    CalibrationDoc {
        model: inputs.model_name.clone(),
        data: display_name(&args.data),
        validate: args.validate.as_deref().map(display_name),
        convention: inputs.table.convention.into(),
        units: UnitsDoc {
            length: "m",
            angle: "rad",
        },
        samples: inputs.data.samples.len() - val_count,
        validation_samples: val_count,
        validation,
        steps: report
            .steps
            .iter()
            .map(|s| StepDoc {
                label: s.label.clone(),
                free: s.free,
                iterations: s.iterations,
                rms_before: s.rms_before,
                val_rms_before: s.val_rms_before,
                rms: s.rms,
                mean: s.mean,
                max: s.max,
                val_rms: s.val_rms,
                val_mean: s.val_mean,
                val_max: s.val_max,
                angle_rms: s.angle_rms,
                fixed: s.fixed.iter().map(FixedDoc::from).collect(),
            })
            .collect(),
        rms_before: report.rms_before,
        rms_after: report.rms_after,
        val_rms_before: report.val_rms_before,
        val_rms_after: report.val_rms_after,
        noise_floor: report.noise_floor.as_ref().map(|n| n.rms),
        angle_noise_floor: report.noise_floor.as_ref().and_then(|n| n.angle_rms),
        noise: report.noise_floor.as_ref().map(|n| NoiseDoc {
            sigma: n.sigma,
            source: match n.source {
                NoiseSource::Given => "given",
                NoiseSource::Samples => "samples",
                NoiseSource::Repeats { .. } => "repeats",
            },
        }),
        condition_number: report.condition_number,
        rank: report.rank,
        sigma_hat: report.sigma_hat,
        parameters: report
            .parameters
            .iter()
            .map(|p| ParameterDoc {
                name: p.name.clone(),
                unit: unit_of(&p.name),
                nominal: p.nominal,
                estimate: p.estimate,
                std_error: p.std_error,
                free: p.free,
            })
            .collect(),
        fixed: report.fixed.iter().map(FixedDoc::from).collect(),
        selected_effects: report.selected_effects.clone(),
        candidates: report.candidates.iter().map(CandidateDoc::from).collect(),
        device: PoseSi::of(&report.device),
        sessions: crate::commands::calibrate_sessions::docs(report),
        targets: report
            .targets
            .iter()
            .map(|(n, p)| TargetDoc {
                name: n.clone(),
                xyz: [p.x, p.y, p.z],
            })
            .collect(),
        notes: report.notes.clone(),
        written: None,
        outliers,
        verdict,
        diagnosis,
    }
}

// ---------------------------------------------------------------- hooks for trees
/// The JSON document and the text report of `report`, a calibration of `model` (for a tree,
/// `model.table` is its joint table) against `data`, as `calibrate` prints them.
pub(crate) fn report_for(
    args: &CalibrateArgs,
    model: &LoadedModel,
    data: &Measurements,
    report: &Report,
) -> (CalibrationDoc, String) {
    let inputs = Inputs {
        table: model.table.clone(),
        model_name: model.origin.clone(),
        robot: model.robot.clone(),
        units: model.units,
        links: model.links.clone(),
        coupled: model.coupled.clone(),
        data: data.clone(),
        cpa: false,
    };
    let doc = document(args, &inputs, report);
    let text = text(&doc, &inputs);
    (doc, text)
}
