//! Running `calibrate`: [`calibrate`] itself (the serial path of `dh_calib::pipeline`; contacts
//! go to `crate::commands::sockets`, trees to `crate::commands::calibrate_tree`), the pipeline's
//! options from the command line ([`pipeline_options`]) and its errors as the command line
//! words them ([`serial_error`]).

use super::*;

/// The library's effects choice of `args`.
pub(crate) fn effects_choice(args: &CalibrateArgs) -> dh_calib::pipeline::EffectsChoice {
    match &args.effects {
        EffectsChoice::None => dh_calib::pipeline::EffectsChoice::None,
        EffectsChoice::Auto => dh_calib::pipeline::EffectsChoice::Auto,
        EffectsChoice::List(l) => dh_calib::pipeline::EffectsChoice::List(l.clone()),
    }
}

/// The pipeline options of `args` with the link masses and gravity the CLI read, the report
/// naming the model `model` and the files as given.
pub(crate) fn pipeline_options(
    args: &CalibrateArgs,
    model: &str,
    inertials: Option<dh_calib::gravity::Inertials>,
    gravity: Vector3<f64>,
) -> PipelineOptions {
    PipelineOptions {
        effects: effects_choice(args),
        max_effects: args.max_effects,
        alpha: args.alpha,
        folds: args.folds,
        sigma: args.sigma.map(|s| s * args.units.length.metres()),
        keep_outliers: args.keep_outliers,
        inertials,
        gravity,
        names: Names {
            model: model.to_string(),
            data: display_name(&args.data),
            validate: args.validate.as_deref().map(display_name),
        },
    }
}

/// Refuses a `--sigma` that is not a positive length.
///
/// # Errors
/// That `--sigma`.
pub(crate) fn check_sigma(args: &CalibrateArgs) -> Result<()> {
    if let Some(s) = args.sigma {
        if !(s.is_finite() && s > 0.0) {
            anyhow::bail!("--sigma: expected a positive length, found {s}");
        }
    }
    Ok(())
}

/// The command line's message for a pipeline error of a serial model `table` (an effect label
/// named after the model's joints, the data file named).
pub(crate) fn serial_error(e: PipelineError, table: &DhTable, data_name: &str) -> anyhow::Error {
    match e {
        // The CLI's message names the kinds and joints.
        PipelineError::Effect { ref label, .. } => match parse_effect(label, table) {
            Err(message) => message,
            Ok(_) => anyhow::anyhow!("{e}"),
        },
        PipelineError::Inertials(_) | PipelineError::Search(_) => anyhow::anyhow!("{e}"),
        e => too_few(e, data_name),
    }
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
    let data_name = display_name(&args.data);
    enough_samples(&inputs.data, &data_name)?;
    let (inertials, gravity) = gravity_inputs(args, &inputs.table)?;
    check_sigma(args)?;
    let options = pipeline_options(args, &inputs.model_name, inertials, gravity);
    let start = if inputs.cpa {
        Start::Cpa(inputs.table.clone())
    } else {
        Start::Serial(inputs.table.clone())
    };
    let notice = |p: &Plan| {
        p.is_long().then(|| {
            format!(
                "urdf-dh: calibrating {} ({} samples, {} targets, {}-fold cross-validation unless there is a validation split); this may take a while",
                inputs.model_name, p.samples, p.targets, p.folds
            )
        })
    };
    let label = |p: &Plan| {
        format!(
            "calibrating {} against {data_name} ({} samples{})",
            inputs.model_name,
            p.samples,
            if p.searched { ", effects searched" } else { "" }
        )
    };
    let mut progress = PipelineProgress::new(err, args.quiet, &notice, &label);
    let run = pipeline::calibrate(&start, &inputs.data, &options, &mut progress);
    progress.check()?;
    drop(progress);
    let (mut doc, report, effects) = match run {
        Ok(Calibration::Points(c)) => (c.doc, c.report, c.effects),
        Ok(_) => anyhow::bail!("{data_name}: calibration took another path than a serial model's"),
        Err(e) => return Err(serial_error(e, &inputs.table, &data_name)),
    };
    // Every output file is built (and the model proved as written) before any is written, and
    // all are written or none.
    let mut files = Vec::new();
    if let Some(path) = &args.out {
        let (text, proof) = model_text(
            path,
            args.model.as_deref(),
            &inputs.nominal(),
            &inputs.data,
            &report,
            &doc,
        )?;
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

// ---------------------------------------------------------------- hooks for trees
/// The text report of `doc`, a calibration of `model` (for a tree, `model.table` is its joint
/// table) against `data`, as `calibrate` prints it.
pub(crate) fn text_for(model: &LoadedModel, data: &Measurements, doc: &CalibrationDoc) -> String {
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
    text(doc, &inputs)
}
