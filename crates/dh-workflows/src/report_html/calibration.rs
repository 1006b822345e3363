//! The page of a calibration from measured points, serial or tree ([`calibration_page`]): the
//! summary, the steps, the residual plots, then the findings (`findings`), the parameters and
//! their correlations, the settings and the provenance. Contacts are drawn by `contacts`.

use std::collections::HashSet;
use std::fmt::Write as _;

use anyhow::Result;
use dh_calib::calibrate::Report;
use dh_calib::data::Split;
use dh_calib::pipeline::{CalibrationDoc, EffectsChoice, TableDoc};
use dh_core::JointKind;

use super::findings;
use super::page::{self, esc, fixed, mm, sci, table, tiles, Page, NA};
use super::parameters::{correlations, parameters};
use super::svg::{Bars, Kind, Point, Scatter};
use super::Provenance;
use crate::calibration::{residuals, Calibrated, CalibrationRequest, Inputs, Residuals};

/// The report page of `calibrated`, the run of `request`, with `provenance`.
///
/// # Errors
/// The residuals of a serial points model that cannot be evaluated again (as the residual
/// chart's).
pub fn calibration_page(
    calibrated: &Calibrated,
    request: &CalibrationRequest,
    provenance: &Provenance,
) -> Result<String> {
    match calibrated {
        Calibrated::Points(p) => {
            let r = residuals(&p.inputs, &p.calibration.report, &p.calibration.effects)?;
            Ok(points_page(
                &p.calibration.doc,
                &p.calibration.report,
                Some((&p.inputs, &r)),
                &[],
                request,
                provenance,
            ))
        }
        Calibrated::Tree(t) => Ok(points_page(
            &t.calibration.doc.report,
            &t.calibration.report,
            None,
            &t.calibration.doc.tree,
            request,
            provenance,
        )),
        Calibrated::Contacts(c) => Ok(super::contacts::page(c, request, provenance)),
    }
}

/// The verdict's class on the page: `pass`, `fail` or `warn` (no test).
pub(super) fn verdict_class(complete: Option<bool>) -> &'static str {
    match complete {
        Some(true) => "pass",
        Some(false) => "fail",
        None => "warn",
    }
}

fn points_page(
    doc: &CalibrationDoc,
    report: &Report,
    serial: Option<(&Inputs, &Residuals)>,
    tree: &[TableDoc],
    request: &CalibrationRequest,
    provenance: &Provenance,
) -> String {
    let kind = if tree.is_empty() { "" } else { " (tree)" };
    let mut p = Page::new(
        &format!("Calibration report: {}", doc.model),
        &format!(
            "{} against {}{kind}; {} DH convention; lengths in mm, angles in degrees",
            doc.model,
            doc.data,
            match doc.convention {
                dh_calib::pipeline::ConventionDoc::Standard => "standard",
                dh_calib::pipeline::ConventionDoc::Modified => "modified",
            }
        ),
    );
    p.section(
        "summary",
        "Summary",
        &format!("verdict {}", verdict_class(doc.verdict.complete)),
        &summary(doc),
    );
    p.section("steps", "Steps", "", &steps(doc));
    match serial {
        Some((inputs, r)) => p.section("residuals", "Residuals", "", &residual_plots(doc, inputs, r)),
        None => p.section(
            "residuals",
            "Residuals",
            "",
            &page::muted(
                "Per-sample residual plots are drawn for serial models; a tree's figures are in the steps, outliers and verdict.",
            ),
        ),
    }
    p.section("outliers", "Outliers", "", &findings::outliers(doc));
    p.section("diagnosis", "Diagnosis", "", &findings::diagnosis(doc));
    p.section("parameters", "Parameters", "", &parameters(doc));
    p.section(
        "correlations",
        "Identifiability and correlations",
        "",
        &correlations(doc, report),
    );
    if !tree.is_empty() {
        p.section("tree", "Tree", "", &tree_tables(tree));
    }
    if !doc.sessions.is_empty() {
        p.section("sessions", "Sessions", "", &sessions(doc));
    }
    p.section("verdict", "Verdict", "", &findings::verdict(doc));
    p.section(
        "settings",
        "Settings and levels",
        "",
        &settings(doc, report, request),
    );
    p.section("provenance", "Provenance", "", &provenance.html());
    p.finish()
}

fn summary(doc: &CalibrationDoc) -> String {
    let mut s = format!("<p class=\"big\">{}</p>\n", esc(&doc.verdict.summary));
    let arrow = |a: Option<f64>, b: Option<f64>| format!("{} \u{2192} {} mm", mm(a), mm(b));
    let outliers = doc.outliers.as_ref().map_or_else(
        || "not screened".to_string(),
        |o| {
            format!(
                "{} {}",
                o.points.len(),
                if o.kept {
                    "(kept in the fit)"
                } else {
                    "left out"
                }
            )
        },
    );
    s.push_str(&tiles(&[
        (
            "calibration RMS, nominal \u{2192} final",
            arrow(Some(doc.rms_before), Some(doc.rms_after)),
        ),
        (
            "validation RMS, nominal \u{2192} final",
            arrow(doc.val_rms_before, doc.val_rms_after),
        ),
        ("noise floor (RMS)", format!("{} mm", mm(doc.noise_floor))),
        (
            "final / floor",
            doc.verdict
                .ratio
                .map_or_else(|| NA.to_string(), |r| format!("{} \u{00d7}", fixed(r, 2))),
        ),
        ("condition number", sci(doc.condition_number, 2)),
        (
            "samples",
            format!(
                "{} + {} validation, {} target(s)",
                doc.samples,
                doc.validation_samples,
                doc.targets.len()
            ),
        ),
        ("outliers", outliers),
        (
            "effects selected",
            if doc.selected_effects.is_empty() {
                "none".into()
            } else {
                doc.selected_effects.join(", ")
            },
        ),
    ]));
    s.push_str(&page::list(&doc.verdict.notes));
    s
}

fn steps(doc: &CalibrationDoc) -> String {
    let groups: Vec<(String, Vec<Option<f64>>)> = doc
        .steps
        .iter()
        .map(|st| {
            (
                st.label.clone(),
                vec![Some(st.rms * 1e3), st.val_rms.map(|v| v * 1e3)],
            )
        })
        .collect();
    let chart = Bars {
        title: "RMS distance per step",
        y_label: "RMS distance [mm]",
        series: &[("calibration", "bar-cal"), ("validation", "bar-val")],
        groups: &groups,
    }
    .render();
    let mut s = page::figure(
        &chart,
        &format!(
            "Each step's RMS 3-D distance between modelled and measured points; {}.",
            doc.validation_words()
        ),
    );
    let rows: Vec<Vec<String>> = doc
        .steps
        .iter()
        .map(|st| {
            vec![
                esc(&st.label),
                st.free.to_string(),
                st.iterations.to_string(),
                mm(st.rms_before),
                mm(st.rms),
                mm(st.mean),
                mm(st.max),
                mm(st.val_rms_before),
                mm(st.val_rms),
                mm(st.val_mean),
                mm(st.val_max),
                st.angle_rms
                    .map_or_else(|| NA.into(), |a| fixed(a.to_degrees(), 5)),
            ]
        })
        .collect();
    s.push_str(&table(
        &[
            "step",
            "#free",
            "#iterations",
            "#RMS before [mm]",
            "#RMS [mm]",
            "#mean [mm]",
            "#max [mm]",
            "#val. RMS before [mm]",
            "#val. RMS [mm]",
            "#val. mean [mm]",
            "#val. max [mm]",
            "#angle RMS [deg]",
        ],
        &rows,
    ));
    s
}

/// The outlier lines of `doc` (1-based file lines of flagged samples).
fn outlier_lines(doc: &CalibrationDoc) -> HashSet<usize> {
    doc.outliers
        .iter()
        .flat_map(|o| o.points.iter().map(|p| p.line))
        .filter(|l| *l > 0)
        .collect()
}

fn residual_plots(doc: &CalibrationDoc, inputs: &Inputs, r: &Residuals) -> String {
    let data = &inputs.data;
    let flagged = outlier_lines(doc);
    let kind = |s: &dh_calib::data::Sample| match s.split {
        Split::Validation => Kind::Validation,
        _ => Kind::Calibration,
    };
    let against = |x: &dyn Fn(usize) -> f64, values: &[f64]| -> Vec<Point> {
        data.samples
            .iter()
            .zip(values)
            .enumerate()
            .map(|(i, (s, d))| Point {
                x: x(i),
                y: d * 1e3,
                kind: kind(s),
                marked: flagged.contains(&s.line),
            })
            .collect()
    };
    let floor = doc
        .noise_floor
        .map(|f| (f * 1e3, "noise floor".to_string(), "floor"));
    let mut s = String::new();
    let last = doc.steps.last().map_or("geometric", |st| st.label.as_str());
    let pose = |i: usize| r.poses.get(i).map_or(f64::NAN, |p| *p as f64 + 1.0);
    for (title, values, rms) in [
        (
            "before: nominal model (device frame and targets fitted)".to_string(),
            &r.before,
            doc.rms_before,
        ),
        (format!("after: {last}"), &r.after, doc.rms_after),
    ] {
        let points = against(&pose, values);
        let mut lines = vec![(rms * 1e3, format!("RMS {} mm", mm(rms)), "rms")];
        lines.extend(floor.clone());
        let (svg, note) = Scatter {
            title: &format!("residual against pose order, {title}"),
            x_label: "pose (order of first appearance in the data)",
            y_label: "distance [mm]",
            points: &points,
            lines,
            y_from_zero: true,
            compact: false,
        }
        .render();
        s.push_str(&page::figure(
            &svg,
            &format!(
                "{}Distance between modelled and measured point, per sample, in the data's pose order ({} poses); dashed: the calibration RMS; dotted: the noise floor; red rings: the outliers.",
                note, r.pose_count
            ),
        ));
    }
    s.push_str(&page::muted(
        "The measurement format has no time column: the pose order (the order of the file) stands in for time; a drift in time shows as a trend from left to right.",
    ));
    let _ = write!(
        s,
        "<h3>Final residual against each joint</h3>\n<div class=\"grid2\">"
    );
    for (j, name) in data.joint_names.iter().enumerate() {
        let prismatic = inputs
            .table
            .rows
            .iter()
            .any(|row| &row.name == name && row.kind == JointKind::Prismatic);
        let (scale, unit) = if prismatic {
            (1e3, "mm")
        } else {
            (180.0 / std::f64::consts::PI, "deg")
        };
        let q = |i: usize| {
            data.samples
                .get(i)
                .and_then(|s| s.q.get(j))
                .map_or(f64::NAN, |v| v * scale)
        };
        let points = against(&q, &r.after);
        let (svg, note) = Scatter {
            title: &format!("after: {last}, against {name}"),
            x_label: &format!("{name} [{unit}]"),
            y_label: "distance [mm]",
            points: &points,
            lines: vec![(doc.rms_after * 1e3, "RMS".into(), "rms")],
            y_from_zero: true,
            compact: true,
        }
        .render();
        s.push_str(&page::figure(
            &svg,
            &format!("{note}Final residual against the commanded value of {name}."),
        ));
    }
    s.push_str("</div>\n");
    s
}

fn tree_tables(tree: &[TableDoc]) -> String {
    let rows: Vec<Vec<String>> = tree
        .iter()
        .map(|t| {
            vec![
                esc(&t.name),
                esc(&t.joints.join(", ")),
                esc(&t.targets.join(", ")),
                t.free.len().to_string(),
                t.fixed.len().to_string(),
                t.mount.as_ref().map_or_else(
                    || NA.into(),
                    |m| {
                        format!(
                            "{} {} {} mm",
                            fixed(m.xyz[0] * 1e3, 3),
                            fixed(m.xyz[1] * 1e3, 3),
                            fixed(m.xyz[2] * 1e3, 3)
                        )
                    },
                ),
            ]
        })
        .collect();
    table(
        &[
            "table",
            "joints",
            "targets",
            "#free",
            "#fixed",
            "mount (branch point frame)",
        ],
        &rows,
    )
}

fn sessions(doc: &CalibrationDoc) -> String {
    let rows: Vec<Vec<String>> = doc
        .sessions
        .iter()
        .map(|s| {
            vec![
                esc(&s.name),
                s.samples.to_string(),
                mm(s.rms),
                s.validation_samples.to_string(),
                mm(s.val_rms),
                if s.fitted_on_validation { "yes" } else { "no" }.into(),
            ]
        })
        .collect();
    table(
        &[
            "session",
            "#samples",
            "#RMS [mm]",
            "#validation samples",
            "#val. RMS [mm]",
            "frame fitted on validation",
        ],
        &rows,
    )
}

fn settings(doc: &CalibrationDoc, report: &Report, request: &CalibrationRequest) -> String {
    let effects = match &request.effects {
        EffectsChoice::None => "none".to_string(),
        EffectsChoice::Auto => format!("auto (at most {})", request.max_effects),
        EffectsChoice::List(l) => l.join(", "),
    };
    let noise = doc.noise.as_ref().map_or_else(
        || "unknown".to_string(),
        |n| format!("{} mm per axis ({})", mm(n.sigma), n.source),
    );
    let mut rows = vec![
        vec!["effects asked for".into(), esc(&effects)],
        vec!["validation".into(), esc(&doc.validation_words())],
        vec![
            "significance level (alpha) of the diagnosis and verdict".into(),
            fixed(request.alpha, 4),
        ],
        vec!["measurement noise".into(), esc(&noise)],
        vec![
            "outliers".into(),
            if request.keep_outliers {
                "kept in the fit (--keep-outliers), still named".into()
            } else {
                "left out of the fit".into()
            },
        ],
        vec![
            "units of the input files".into(),
            format!(
                "{}, {}",
                request.units.length.symbol(),
                request.units.angle.symbol()
            ),
        ],
        vec![
            "rank tolerance (relative singular value)".into(),
            sci(report.rank_tolerance, 1),
        ],
    ];
    if let Some(o) = &doc.outliers {
        rows.push(vec![
            "outlier screen".into(),
            esc(&format!(
                "family-wise level {} (Bonferroni), threshold {} x the {} scale of {} mm",
                sci(o.level, 1),
                fixed(o.threshold, 2),
                o.scale_source,
                mm(o.scale)
            )),
        ]);
    }
    if !request.targets.is_empty() {
        rows.push(vec![
            "targets kept".into(),
            esc(&request.targets.join(", ")),
        ]);
    }
    let mut s = table(&["setting", "value"], &rows);
    if !doc.notes.is_empty() {
        s.push_str("<h3>Notes</h3>\n");
        s.push_str(&page::list(&doc.notes));
    }
    s
}
