//! Running `calibrate`: [`calibrate`] loads and fits through the library
//! ([`dh_workflows::calibration`]: points, contacts or a tree), then writes the calibrated model and
//! the chart (all or nothing) and renders the report (the contact and tree reports in
//! `crate::commands::sockets` and `crate::commands::calibrate_tree`).

use super::*;

/// Runs `calibrate`: outputs checked against the inputs, a tree sheet model calibrated as a
/// tree, else as a serial chain (points, or contacts when the data has a socket column). The
/// report goes to `out` (to `err` when an artefact is piped to `-`), warnings and progress to
/// `err`.
///
/// # Errors
/// Bad model or data files (naming the file, line and column), unknown effects, a calibration
/// that cannot start (too few samples, collinear points), failed writes.
pub fn calibrate(
    args: &CalibrateArgs,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> Result<Outcome> {
    let request = &args.request;
    let mut more: Vec<(&str, &str)> = args.plot.iter().map(|p| ("--plot", p.as_str())).collect();
    more.extend(args.report.iter().map(|p| ("--report", p.as_str())));
    request.check_destinations(&more)?;
    let loaded = match calibration::identify(request)? {
        Some((sheet, origin)) => Loaded::Tree(Box::new(calibration::load_tree(
            request, sheet, origin, err,
        )?)),
        None => Loaded::Serial(Box::new(calibration::load_inputs(request, err)?)),
    };
    let data_name = display_name(&request.data);
    let mut calibrated = if loaded.is_contacts() {
        loaded.calibrate(request, &mut Silent)?
    } else {
        let subject = loaded.subject();
        let notice = |p: &Plan| subject.notice(p);
        let label = |p: &Plan| subject.label(p, &data_name);
        let mut progress = PipelineProgress::new(err, args.quiet, &notice, &label);
        let run = loaded.calibrate(request, &mut progress);
        progress.check()?;
        drop(progress);
        run?
    };
    // Every output file is built (and the model proved as written) before any is written, and
    // all are written or none; a model that fails its proof is not written, and neither is
    // anything else.
    let mut files = Vec::new();
    if let Some(path) = &request.out {
        if let Some(text) = calibrated.model_file(path, request.model.as_deref(), err)? {
            files.push((Path::new(path), text));
        }
    }
    let proved = calibrated.proved();
    if let Some(path) = &args.plot {
        let chart = match &calibrated {
            // Residuals are millimetres or less on any arm: the chart reads best in mm
            // whatever the report's unit.
            Calibrated::Points(p) => chart(
                &data_name,
                &p.inputs,
                &p.calibration.report,
                &p.calibration.effects,
                LengthUnit::Mm,
            )?,
            Calibrated::Contacts(c) => crate::commands::sockets::chart(
                &c.inputs.model_name,
                &data_name,
                &c.calibration.report,
            ),
            // Two panels a branch: a tree's arms differ in length and in what they carry.
            Calibrated::Tree(t) => tree_chart(&data_name, t, LengthUnit::Mm)?,
        };
        files.push((Path::new(path), residuals_svg(&chart)));
    }
    if let Some(path) = &args.report {
        let inputs: Vec<(&str, &str)> = [
            ("--model", request.model.as_deref()),
            (
                "--data",
                request.given.is_none().then_some(request.data.as_str()),
            ),
            ("--validate", request.validate.as_deref()),
            ("--inertials", request.inertials.as_deref()),
        ]
        .into_iter()
        .filter_map(|(o, p)| Some((o, p?)))
        .collect();
        let provenance = crate::commands::report_provenance(&args.command_line, &inputs);
        let page = dh_workflows::report_html::calibration_page(&calibrated, request, &provenance)?;
        files.push((Path::new(path), page));
    }
    // `--out -` or `--plot -`: that artefact on standard output, the report on standard error.
    // Otherwise the report goes to standard output first, and the files land only once it has
    // been written and flushed (all or nothing, standard output included).
    let piped = dh_workflows::output::any_stdout([
        request.out.as_deref(),
        args.plot.as_deref(),
        args.report.as_deref(),
    ]);
    let report = match args.format {
        CalibrateFormat::Json => calibrated.json()?,
        CalibrateFormat::Text => match &calibrated {
            Calibrated::Points(p) => text(&p.calibration.doc, &p.inputs),
            Calibrated::Contacts(c) => crate::commands::sockets::text(&c.calibration.doc),
            Calibrated::Tree(t) => crate::commands::calibrate_tree::text(t),
        },
    };
    if !piped {
        out.write_all(report.as_bytes())?;
    }
    if proved {
        let files: Vec<(&Path, &[u8])> = files.iter().map(|(p, b)| (*p, b.as_bytes())).collect();
        let written = dh_workflows::output::write_all_or_stdout(&files, out);
        match (&calibrated, &request.out) {
            (Calibrated::Tree(_), Some(path)) => written.with_context(|| {
                format!(
                    "writing the calibrated tree to {}",
                    crate::guard::output_name(path)
                )
            })?,
            _ => written?,
        }
    }
    if piped {
        err.write_all(report.as_bytes())?;
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
