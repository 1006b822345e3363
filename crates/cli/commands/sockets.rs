//! `urdf-dh calibrate` on contact data (a `socket` column, e.g. `urdf-dh import --layout
//! mukca`): unknown socket centres instead of measured points, see `dh_calib::socket`.
//!
//! `--effects auto|LIST` runs `dh_calib::socket::diagnose_sockets`; `--out` writes the
//! calibrated model as for measured points, with a single target (the ball) folded into the
//! tool so that the written model predicts the ball centre itself; `--plot` draws each
//! contact's distance to its socket's modelled mean, as given and after the last step.

use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

use anyhow::Result;
use dh_calib::pipeline::{self, Calibration, ContactDoc, Silent, SocketDoc, Start};
use dh_calib::socket::SocketReport;
use dh_core::DhTable;
use nalgebra::{Isometry3, Translation3};
use serde::Serialize;

use crate::commands::calibrate::{check_sigma, pipeline_options, serial_error};
use crate::commands::calibrate_args::{CalibrateArgs, CalibrateFormat};
use crate::commands::calibrate_doc::{calibrated_bytes, unit_of, TargetDoc};
use crate::commands::calibrate_inputs::{gravity_inputs, Inputs};
use crate::error::Outcome;
use crate::input::display_name;
use crate::plot::{residuals_svg, Panel, Residual, ResidualChart};
use crate::units::LengthUnit;

fn mm(v: f64) -> String {
    format!("{:.3}", v * 1e3)
}

fn opt_mm(v: Option<f64>) -> String {
    v.map_or_else(|| "-".into(), mm)
}

fn text(doc: &ContactDoc) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "calibrate: {} against {} (ball-in-socket contacts: unknown socket centres)",
        doc.model, doc.data
    );
    let _ = writeln!(
        s,
        "consistency: mean distance of each modelled point to its socket's mean, per placement, \
         then averaged (MUKCa's mean absolute error); distance error: |socket means' distance - \
         known distance|; mm"
    );
    let w = crate::guard::column_width(doc.steps.iter().map(|st| st.label.as_str()), 10);
    let _ = writeln!(
        s,
        "  {:<w$} {:>5} {:>9} {:>11} {:>10} {:>10} {:>10}",
        "step", "free", "rms", "train", "train dist", "test", "test dist"
    );
    for st in &doc.steps {
        let _ = writeln!(
            s,
            "  {:<w$} {:>5} {:>9} {:>11} {:>10} {:>10} {:>10}",
            st.label,
            st.free.map_or_else(|| "-".into(), |f| f.to_string()),
            opt_mm(st.rms),
            mm(st.train.mean_abs),
            opt_mm(st.train.distance_error),
            opt_mm(st.test.as_ref().map(|t| t.mean_abs)),
            opt_mm(st.test.as_ref().and_then(|t| t.distance_error)),
        );
    }
    let _ = writeln!(
        s,
        "contact noise weighting the distances: {} mm; condition number {:.3e}",
        mm(doc.sigma_point),
        doc.condition_number
    );
    let _ = writeln!(s, "sockets (base link frame, m):");
    for k in &doc.sockets {
        let _ = writeln!(
            s,
            "  {:<16} {:>12.6} {:>12.6} {:>12.6}  ({} contacts)",
            k.name, k.position[0], k.position[1], k.position[2], k.samples
        );
    }
    let _ = writeln!(s, "parameters (m, rad):");
    for p in doc
        .parameters
        .iter()
        .filter(|p| p.free && !p.name.starts_with("socket."))
    {
        let _ = writeln!(
            s,
            "  {:<20} {:>14.8} -> {:>14.8} ± {}",
            p.name,
            p.nominal,
            p.estimate,
            p.std_error
                .map_or_else(|| "-".into(), |e| format!("{e:.2e}"))
        );
    }
    let fixed: Vec<&str> = doc.fixed.iter().map(|f| f.name.as_str()).collect();
    let _ = writeln!(s, "fixed (not identifiable): {}", fixed.join(", "));
    if !doc.candidates.is_empty() {
        let _ = writeln!(
            s,
            "effect candidates (first round, best score first; score = SSR reduction beyond the \
             geometric fit; test rms = held-out rms distance to the socket means after a full \
             refit, for those refitted):"
        );
        let _ = writeln!(
            s,
            "  {:<32} {:>12} {:>12} {:>13}  status",
            "label", "score [mm²]", "independence", "test rms [mm]"
        );
        for c in doc.candidates.iter().take(15) {
            let _ = writeln!(
                s,
                "  {:<32} {:>12.4e} {:>12.4} {:>13}  {}",
                c.label,
                c.score * 1e6,
                c.independence,
                opt_mm(c.val_rms),
                c.status
            );
        }
        if doc.candidates.len() > 15 {
            let _ = writeln!(
                s,
                "  ... {} more (see --format json)",
                doc.candidates.len() - 15
            );
        }
        for t in &doc.trials {
            let _ = writeln!(
                s,
                "  refit {}: F p = {:.2e} (threshold {:.2e}), held-out p = {}: {}",
                t.label,
                t.f_p,
                t.f_threshold,
                t.held_out_p
                    .map_or_else(|| "-".into(), |p| format!("{p:.2e}")),
                if t.accepted {
                    "selected".to_string()
                } else {
                    format!("rejected ({})", t.reason)
                }
            );
        }
    }
    if doc.selected_effects.is_empty() {
        if !doc.candidates.is_empty() {
            let _ = writeln!(s, "effects: none selected");
        }
    } else {
        let _ = writeln!(s, "effects: {}", doc.selected_effects.join(", "));
        for p in doc.parameters.iter().filter(|p| p.is_estimated_effect()) {
            let _ = writeln!(
                s,
                "  {} = {:.6e}{} {}",
                p.name,
                p.estimate,
                p.std_error
                    .map(|e| format!(" +- {e:.1e}"))
                    .unwrap_or_default(),
                unit_of(&p.name)
            );
        }
    }
    for n in &doc.notes {
        let _ = writeln!(s, "note: {n}");
    }
    s
}

/// Runs `calibrate` on contact data.
///
/// # Errors
/// A bad `--sigma`, effect label or inertials file, a calibration that fails, a failed write.
pub(crate) fn calibrate_contacts(
    args: &CalibrateArgs,
    inputs: &Inputs,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> Result<Outcome> {
    let table = &inputs.table;
    check_sigma(args)?;
    let (inertials, gravity) = gravity_inputs(args, table)?;
    let name = display_name(&args.data);
    let options = pipeline_options(args, &inputs.model_name, inertials, gravity);
    let run = pipeline::calibrate(
        &Start::Serial(table.clone()),
        &inputs.data,
        &options,
        &mut Silent,
    );
    let (r, doc) = match run {
        Ok(Calibration::Contacts(c)) => (c.report, c.doc),
        Ok(_) => anyhow::bail!("{name}: calibration took another path than contacts'"),
        Err(e) => return Err(serial_error(e, table, &name)),
    };
    // Every output file is built before any is written, and all are written or none.
    let mut files = Vec::new();
    if let Some(path) = &args.out {
        files.push((
            Path::new(path),
            contact_model_bytes(path, inputs, &r, &doc)?,
        ));
    }
    if let Some(path) = &args.plot {
        let chart = chart(&inputs.model_name, &name, &r);
        files.push((Path::new(path), residuals_svg(&chart)));
    }
    let files: Vec<(&Path, &[u8])> = files.iter().map(|(p, b)| (*p, b.as_bytes())).collect();
    crate::output::write_all_or_stdout(&files, out)?;
    // `--out -` or `--plot -`: that artefact on standard output, the report on standard error.
    let out: &mut dyn Write =
        if crate::output::any_stdout([args.out.as_deref(), args.plot.as_deref()]) {
            err
        } else {
            out
        };
    match args.format {
        CalibrateFormat::Json => {
            out.write_all((serde_json::to_string_pretty(&doc)? + "\n").as_bytes())?;
        }
        CalibrateFormat::Text => out.write_all(text(&doc).as_bytes())?,
    }
    Ok(Outcome::Pass)
}

/// The `calibration` section of a sheet calibrated from contacts (metres): the consistency
/// before and after, the sockets in the base link frame and the targets in the written tip
/// frame (zero for a ball folded into the tool).
#[derive(Serialize)]
struct ContactCalibrationSection {
    data: String,
    kind: &'static str,
    consistency_before: f64,
    consistency_after: f64,
    test_consistency_before: Option<f64>,
    test_consistency_after: Option<f64>,
    targets: Vec<TargetDoc>,
    sockets: Vec<SocketDoc>,
    effects: Vec<(String, f64)>,
}

/// The calibrated table to write: with one target (the ball), the target folded into the tool
/// (`tool · Tr(t)`, `t` in the tip frame), so that the model's tip is the ball centre and the
/// written model predicts the contacts without a target offset. Returns the table and the
/// targets left in its tip frame.
fn written_table(r: &SocketReport) -> (DhTable, Vec<TargetDoc>) {
    let mut table = r.calibrated.clone();
    match r.targets.as_slice() {
        [(name, t)] => {
            table.tool *= Isometry3::from_parts(Translation3::from(*t), Default::default());
            (
                table,
                vec![TargetDoc {
                    name: name.clone(),
                    xyz: [0.0; 3],
                    rpy: None,
                }],
            )
        }
        targets => (table, TargetDoc::list(targets)),
    }
}

/// The model calibrated from contacts (see [`written_table`]), as the point path writes it.
fn contact_model_bytes(
    path: &str,
    inputs: &Inputs,
    r: &SocketReport,
    doc: &ContactDoc,
) -> Result<String> {
    let (table, targets) = written_table(r);
    let first = doc.steps.first();
    let last = doc.steps.last();
    let section = ContactCalibrationSection {
        data: doc.data.clone(),
        kind: "contacts",
        consistency_before: first.map_or(0.0, |s| s.train.mean_abs),
        consistency_after: last.map_or(0.0, |s| s.train.mean_abs),
        test_consistency_before: first.and_then(|s| s.test.as_ref().map(|t| t.mean_abs)),
        test_consistency_after: last.and_then(|s| s.test.as_ref().map(|t| t.mean_abs)),
        targets,
        sockets: doc
            .sockets
            .iter()
            .map(|k| SocketDoc {
                name: k.name.clone(),
                position: k.position,
                samples: k.samples,
            })
            .collect(),
        effects: doc
            .parameters
            .iter()
            .filter(|p| p.is_estimated_effect())
            .map(|p| (p.name.clone(), p.estimate))
            .collect(),
    };
    let source = format!(
        "calibrated by urdf-dh calibrate from {} against the contacts of {}: consistency {:.6} m \
         -> {:.6} m",
        doc.model, doc.data, section.consistency_before, section.consistency_after
    );
    calibrated_bytes(
        path,
        &inputs.nominal(),
        &table,
        source,
        serde_yaml::to_value(&section)?,
    )
}

/// The chart: each contact's distance to its socket's modelled mean (file order, so the
/// placements follow each other), with the model as given and after the last step.
fn chart(model: &str, data: &str, r: &SocketReport) -> ResidualChart {
    let panel = |label: String, pick: fn(&dh_calib::socket::ContactDistance) -> f64| {
        let residuals: Vec<Residual> = r
            .distances
            .iter()
            .enumerate()
            .map(|(i, d)| Residual {
                pose: i,
                distance: pick(d),
                validation: d.validation,
            })
            .collect();
        let n = residuals.len().max(1) as f64;
        let rms = (residuals
            .iter()
            .map(|v| v.distance * v.distance)
            .sum::<f64>()
            / n)
            .sqrt();
        Panel {
            label,
            residuals,
            rms: Some(rms),
            floor: None,
        }
    };
    let last = r.steps.last().map_or("geometric", |s| s.label.as_str());
    ResidualChart {
        title: format!(
            "distance of each contact to its socket's modelled mean: {model} against {data} ({} \
             contacts, {} sockets fitted)",
            r.distances.len(),
            r.sockets.len()
        ),
        unit: LengthUnit::Mm,
        poses: r.distances.len(),
        panels: vec![
            panel("before: the model as given".into(), |d| d.as_given),
            panel(format!("after: {last}"), |d| d.last),
        ],
    }
}
