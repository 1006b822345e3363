//! The page of a calibration from contacts (ball-in-socket, unknown socket centres): the
//! consistency per step, each contact's distance to its socket's modelled mean before and
//! after, the sockets, the parameters, the effect search, the settings and the provenance.

use dh_calib::pipeline::unit_of;

use super::calibration::verdict_class;
use super::page::{self, esc, fixed, mm, sci, table, table_with, tiles, Page, NA};
use super::parameters::{shown, shown_error};
use super::svg::{Kind, Point, Scatter};
use super::Provenance;
use crate::calibration::{CalibrationRequest, Contacts};

/// The contact page.
pub(super) fn page(c: &Contacts, request: &CalibrationRequest, provenance: &Provenance) -> String {
    let doc = &c.calibration.doc;
    let r = &c.calibration.report;
    let mut p = Page::new(
        &format!("Calibration report: {}", doc.model),
        &format!(
            "{} against {} (ball-in-socket contacts: unknown socket centres); lengths in mm, angles in degrees",
            doc.model, doc.data
        ),
    );
    let first = doc.steps.first();
    let last = doc.steps.last();
    let improved = match (first, last) {
        (Some(a), Some(b)) => Some(b.train.mean_abs <= a.train.mean_abs),
        _ => None,
    };
    let mut summary = format!(
        "<p class=\"big\">consistency {} \u{2192} {} mm (mean distance of each contact to its socket's mean)</p>\n",
        mm(first.map(|s| s.train.mean_abs)),
        mm(last.map(|s| s.train.mean_abs))
    );
    summary.push_str(&tiles(&[
        (
            "held-out consistency, first \u{2192} last",
            format!(
                "{} \u{2192} {} mm",
                mm(first.and_then(|s| s.test.as_ref().map(|t| t.mean_abs))),
                mm(last.and_then(|s| s.test.as_ref().map(|t| t.mean_abs)))
            ),
        ),
        (
            "contact noise weighting",
            format!("{} mm", mm(doc.sigma_point)),
        ),
        ("condition number", sci(doc.condition_number, 2)),
        ("sockets", doc.sockets.len().to_string()),
        ("contacts", r.distances.len().to_string()),
        (
            "effects selected",
            if doc.selected_effects.is_empty() {
                "none".into()
            } else {
                doc.selected_effects.join(", ")
            },
        ),
    ]));
    summary.push_str(&page::muted(
        "A contact calibration has no noise test: its verdict is the consistency of the sockets on held-out placements.",
    ));
    p.section(
        "summary",
        "Summary",
        &format!("verdict {}", verdict_class(improved)),
        &summary,
    );
    let rows: Vec<Vec<String>> = doc
        .steps
        .iter()
        .map(|st| {
            vec![
                esc(&st.label),
                st.free.map_or_else(|| NA.into(), |f| f.to_string()),
                mm(st.rms),
                mm(st.train.mean_abs),
                mm(st.train.rms),
                mm(st.train.max),
                mm(st.train.distance_error),
                mm(st.test.as_ref().map(|t| t.mean_abs)),
                mm(st.test.as_ref().and_then(|t| t.distance_error)),
            ]
        })
        .collect();
    p.section(
        "steps",
        "Steps",
        "",
        &table(
            &[
                "step",
                "#free",
                "#fit RMS [mm]",
                "#train consistency [mm]",
                "#train RMS [mm]",
                "#train max [mm]",
                "#train distance error [mm]",
                "#test consistency [mm]",
                "#test distance error [mm]",
            ],
            &rows,
        ),
    );
    let mut plots = String::new();
    let last_label = last.map_or("last step", |s| s.label.as_str());
    for (title, pick) in [
        (
            "before: the model as given".to_string(),
            (|d: &dh_calib::socket::ContactDistance| d.as_given) as fn(&_) -> f64,
        ),
        (format!("after: {last_label}"), |d| d.last),
    ] {
        let points: Vec<Point> = r
            .distances
            .iter()
            .enumerate()
            .map(|(i, d)| Point {
                x: i as f64 + 1.0,
                y: pick(d) * 1e3,
                kind: if d.validation {
                    Kind::Validation
                } else {
                    Kind::Calibration
                },
                marked: false,
            })
            .collect();
        let (svg, note) = Scatter {
            title: &format!("distance to the socket's modelled mean, {title}"),
            x_label: "contact (file order)",
            y_label: "distance [mm]",
            points: &points,
            lines: Vec::new(),
            y_from_zero: true,
            compact: false,
        }
        .render();
        plots.push_str(&page::figure(
            &svg,
            &format!("{note}Each contact's distance to the mean of its socket's modelled contacts, in file order (placements follow each other)."),
        ));
    }
    p.section("residuals", "Residuals", "", &plots);
    p.section(
        "outliers",
        "Outliers",
        "",
        &page::muted("Contacts are not screened for outliers: each socket's contacts are judged by their consistency."),
    );
    let mut diag = String::new();
    if doc.candidates.is_empty() {
        diag.push_str(&page::muted(
            "No effect search ran (--effects auto runs one).",
        ));
    } else {
        let rows: Vec<Vec<String>> = doc
            .candidates
            .iter()
            .map(|c| {
                vec![
                    esc(&c.label),
                    sci(c.score * 1e6, 3),
                    fixed(c.independence, 4),
                    mm(c.val_rms),
                    esc(&c.status),
                    c.reason.as_deref().map_or_else(String::new, esc),
                ]
            })
            .collect();
        let classes: Vec<&str> = doc
            .candidates
            .iter()
            .map(|c| if c.status == "selected" { "taken" } else { "" })
            .collect();
        diag.push_str(&table_with(
            &[
                "effect",
                "#score [mm\u{b2}]",
                "#independence",
                "#test RMS [mm]",
                "status",
                "why",
            ],
            &rows,
            &classes,
        ));
        let rows: Vec<Vec<String>> = doc
            .trials
            .iter()
            .map(|t| {
                vec![
                    esc(&t.label),
                    mm(t.rms),
                    sci(t.f_p, 2),
                    sci(t.f_threshold, 2),
                    sci(t.held_out_p, 2),
                    if t.accepted {
                        "selected".into()
                    } else {
                        format!("rejected: {}", esc(&t.reason))
                    },
                ]
            })
            .collect();
        diag.push_str(&table(
            &[
                "refit",
                "#RMS [mm]",
                "#F-test p",
                "#must beat",
                "#held-out p",
                "result",
            ],
            &rows,
        ));
    }
    p.section("diagnosis", "Diagnosis", "", &diag);
    let socket_rows: Vec<Vec<String>> = doc
        .sockets
        .iter()
        .map(|k| {
            vec![
                esc(&k.name),
                fixed(k.position[0] * 1e3, 3),
                fixed(k.position[1] * 1e3, 3),
                fixed(k.position[2] * 1e3, 3),
                k.samples.to_string(),
            ]
        })
        .collect();
    let mut params = String::from("<h3>Sockets (base link frame)</h3>\n");
    params.push_str(&table(
        &["socket", "#x [mm]", "#y [mm]", "#z [mm]", "#contacts"],
        &socket_rows,
    ));
    let rows: Vec<Vec<String>> = doc
        .parameters
        .iter()
        .filter(|p| p.free && !p.name.starts_with("socket."))
        .map(|p| {
            let unit = unit_of(&p.name);
            let (nominal, u) = shown(p.nominal, unit);
            let (estimate, _) = shown(p.estimate, unit);
            vec![
                esc(&p.name),
                u.into(),
                nominal,
                estimate,
                shown_error(p.std_error, unit),
            ]
        })
        .collect();
    params.push_str("<h3>Estimated parameters</h3>\n");
    params.push_str(&table(
        &[
            "parameter",
            "unit",
            "#nominal",
            "#estimate",
            "#standard error",
        ],
        &rows,
    ));
    if !doc.fixed.is_empty() {
        let fixed_names: Vec<String> = doc.fixed.iter().map(|f| f.name.clone()).collect();
        params.push_str(&page::para(&format!(
            "Held at nominal (not identifiable): {}.",
            fixed_names.join(", ")
        )));
    }
    p.section("parameters", "Parameters", "", &params);
    p.section(
        "correlations",
        "Identifiability and correlations",
        "",
        &(tiles(&[(
            "condition number (scaled Jacobian)",
            sci(doc.condition_number, 3),
        )]) + &page::muted(
            "The contact fit keeps no covariance matrix, so no correlated pairs are listed.",
        )),
    );
    let mut verdict = page::para(&format!(
        "Consistency on the training placements {} \u{2192} {} mm; on the test placements {} \u{2192} {} mm.",
        mm(first.map(|s| s.train.mean_abs)),
        mm(last.map(|s| s.train.mean_abs)),
        mm(first.and_then(|s| s.test.as_ref().map(|t| t.mean_abs))),
        mm(last.and_then(|s| s.test.as_ref().map(|t| t.mean_abs))),
    ));
    verdict.push_str(&page::list(&doc.notes));
    p.section("verdict", "Verdict", "", &verdict);
    let settings = table(
        &["setting", "value"],
        &[
            vec![
                "effects asked for".into(),
                esc(&match &request.effects {
                    dh_calib::pipeline::EffectsChoice::None => "none".to_string(),
                    dh_calib::pipeline::EffectsChoice::Auto => {
                        format!("auto (at most {})", request.max_effects)
                    }
                    dh_calib::pipeline::EffectsChoice::List(l) => l.join(", "),
                }),
            ],
            vec!["significance level (alpha)".into(), fixed(request.alpha, 4)],
            vec![
                "contact noise weighting the distances".into(),
                format!("{} mm", mm(doc.sigma_point)),
            ],
            vec![
                "units of the input files".into(),
                format!(
                    "{}, {}",
                    request.units.length.symbol(),
                    request.units.angle.symbol()
                ),
            ],
        ],
    );
    p.section("settings", "Settings and levels", "", &settings);
    p.section("provenance", "Provenance", "", &provenance.html());
    p.finish()
}
