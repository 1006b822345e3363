//! The report of `urdf-dh calibrate` on contact data (a `socket` column, e.g. `urdf-dh import
//! --layout mukca`): unknown socket centres instead of measured points, see `dh_workflows::fit::SocketReport`;
//! the run and the calibrated model are the library's (`dh_workflows::calibration`).
//!
//! `text` renders the report; `chart` (`--plot`) draws each contact's distance to its
//! socket's modelled mean, as given and after the last step.

use std::fmt::Write as _;

use dh_workflows::fit::{unit_of, ContactDistance, ContactDoc, SocketReport};
use dh_workflows::units::LengthUnit;

use crate::plot::{Panel, Residual, ResidualChart};

fn mm(v: f64) -> String {
    format!("{:.3}", v * 1e3)
}

fn opt_mm(v: Option<f64>) -> String {
    v.map_or_else(|| "-".into(), mm)
}

/// The text report of a contact calibration.
pub(crate) fn text(doc: &ContactDoc) -> String {
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
        for p in doc.parameters.iter().filter(|p| p.is_effect()) {
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

/// The chart: each contact's distance to its socket's modelled mean (file order, so the
/// placements follow each other), with the model as given and after the last step.
pub(crate) fn chart(model: &str, data: &str, r: &SocketReport) -> ResidualChart {
    let panel = |label: String, pick: fn(&ContactDistance) -> f64| {
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
