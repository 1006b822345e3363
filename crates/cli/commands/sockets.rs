//! `urdf-dh calibrate` on contact data (a `socket` column, e.g. `urdf-dh import --layout
//! mukca`): unknown socket centres instead of measured points, see `dh_calib::socket`.

use std::fmt::Write as _;
use std::io::Write;

use anyhow::Result;
use dh_calib::calibrate::CalibrationOptions;
use dh_calib::data::Measurements;
use dh_calib::socket::{calibrate_sockets, Consistency, SocketReport};
use dh_calib::tree::DhTree;
use dh_core::DhTable;
use serde::Serialize;

use crate::commands::calibrate::{CalibrateArgs, CalibrateFormat, EffectsChoice};
use crate::error::{hinted, Outcome};
use crate::input::display_name;

/// Consistency figures in metres (JSON).
#[derive(Serialize)]
struct ConsistencyDoc {
    mean_abs: f64,
    rms: f64,
    max: f64,
    distance_error: Option<f64>,
    placements: usize,
    points: usize,
}

impl From<&Consistency> for ConsistencyDoc {
    fn from(c: &Consistency) -> Self {
        Self {
            mean_abs: c.mean_abs,
            rms: c.rms,
            max: c.max,
            distance_error: c.distance_error,
            placements: c.placements,
            points: c.points,
        }
    }
}

#[derive(Serialize)]
struct StepDoc {
    label: String,
    free: Option<usize>,
    rms: Option<f64>,
    train: ConsistencyDoc,
    test: Option<ConsistencyDoc>,
}

#[derive(Serialize)]
struct ParameterDoc {
    name: String,
    nominal: f64,
    estimate: f64,
    std_error: Option<f64>,
    free: bool,
}

#[derive(Serialize)]
struct FixedDoc {
    name: String,
    aliases: Vec<String>,
}

#[derive(Serialize)]
struct SocketDoc {
    name: String,
    position: [f64; 3],
    samples: usize,
}

/// The JSON report: metres and radians.
#[derive(Serialize)]
struct ContactDoc {
    model: String,
    data: String,
    kind: &'static str,
    steps: Vec<StepDoc>,
    sigma_point: f64,
    condition_number: f64,
    sockets: Vec<SocketDoc>,
    parameters: Vec<ParameterDoc>,
    fixed: Vec<FixedDoc>,
    notes: Vec<String>,
}

fn document(model: &str, data: &str, r: &SocketReport) -> ContactDoc {
    ContactDoc {
        model: model.into(),
        data: data.into(),
        kind: "contacts",
        steps: r
            .consistency
            .iter()
            .map(|c| {
                let s = r.steps.iter().find(|s| s.label == c.label);
                StepDoc {
                    label: c.label.clone(),
                    free: s.map(|s| s.free),
                    rms: s.map(|s| s.rms),
                    train: (&c.train).into(),
                    test: c.test.as_ref().map(Into::into),
                }
            })
            .collect(),
        sigma_point: r.sigma_point,
        condition_number: r.condition_number,
        sockets: r
            .sockets
            .iter()
            .map(|s| SocketDoc {
                name: s.name.clone(),
                position: [s.position.x, s.position.y, s.position.z],
                samples: s.samples,
            })
            .collect(),
        parameters: r
            .parameters
            .iter()
            .map(|p| ParameterDoc {
                name: p.name.clone(),
                nominal: p.nominal,
                estimate: p.estimate,
                std_error: p.std_error,
                free: p.free,
            })
            .collect(),
        fixed: r
            .fixed
            .iter()
            .map(|f| FixedDoc {
                name: f.name.clone(),
                aliases: f.aliases.clone(),
            })
            .collect(),
        notes: r.notes.clone(),
    }
}

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
    let _ = writeln!(
        s,
        "  {:<10} {:>5} {:>9} {:>11} {:>10} {:>10} {:>10}",
        "step", "free", "rms", "train", "train dist", "test", "test dist"
    );
    for st in &doc.steps {
        let _ = writeln!(
            s,
            "  {:<10} {:>5} {:>9} {:>11} {:>10} {:>10} {:>10}",
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
    for n in &doc.notes {
        let _ = writeln!(s, "note: {n}");
    }
    s
}

/// Runs `calibrate` on contact data.
///
/// # Errors
/// Options that do not apply to contacts (`--effects auto`, `--plot`, `--out`), a calibration
/// that fails, a failed write.
pub fn calibrate_contacts(
    args: &CalibrateArgs,
    table: &DhTable,
    model_name: &str,
    data: &Measurements,
    out: &mut dyn Write,
) -> Result<Outcome> {
    let unsupported = [
        (args.effects != EffectsChoice::None, "--effects"),
        (args.plot.is_some(), "--plot"),
        (args.out.is_some(), "--out"),
    ];
    if let Some((_, opt)) = unsupported.iter().find(|(on, _)| *on) {
        return Err(hinted(
            format!("{opt} is not supported for contact data (a 'socket' column) yet"),
            "run without it: the geometric steps and the consistency figures are reported",
        ));
    }
    let options = CalibrationOptions {
        sigma: args.sigma.map(|s| s * args.units.length.metres()),
        ..CalibrationOptions::default()
    };
    let name = display_name(&args.data);
    let r = calibrate_sockets(&DhTree::serial(table), data, &options)
        .map_err(|e| anyhow::anyhow!("{name}: calibration failed: {e}"))?;
    let doc = document(model_name, &name, &r);
    match args.format {
        CalibrateFormat::Json => {
            out.write_all((serde_json::to_string_pretty(&doc)? + "\n").as_bytes())?;
        }
        CalibrateFormat::Text => out.write_all(text(&doc).as_bytes())?,
    }
    Ok(Outcome::Pass)
}
