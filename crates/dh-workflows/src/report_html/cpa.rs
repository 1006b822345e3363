//! The page of a circle-point analysis ([`cpa_page`]): the sweeps, each joint's fitted circles
//! and axis, each point's distance from its target's circle and the commanded against measured
//! motion (plots per joint, the points the screen left out ringed and listed), the DH table
//! the axes make, the comparison with a nominal model, the proof against the measured axes,
//! the tolerances and the provenance.

use std::collections::HashSet;

use dh_calib::cpa::{JointCpa, TargetFit};
use dh_calib::data::Measurements;
use dh_core::JointKind;

use super::page::{self, esc, fixed, mm, sci, table, table_with, tiles, Page, NA};
use super::svg::{Kind, Point, Scatter};
use super::Provenance;
use crate::cpa_report::CpaReport;

const DEG: f64 = 180.0 / std::f64::consts::PI;
/// Arc seconds per radian.
const ARCSEC: f64 = DEG * 3600.0;

/// The report page of the circle-point analysis `r`, with `provenance`.
pub fn cpa_page(r: &CpaReport, provenance: &Provenance) -> String {
    let doc = &r.doc;
    let mut p = Page::new(
        &format!("Circle-point analysis: {}", doc.data),
        &format!(
            "{} samples of {} target(s), device frame; lengths in mm, angles in degrees",
            doc.samples,
            doc.targets.len()
        ),
    );
    let left_out: usize = doc.joints.iter().map(|j| j.screen.left_out.len()).sum();
    let unsound: Vec<&str> = doc
        .joints
        .iter()
        .filter(|j| !j.screen.sound)
        .map(|j| j.name.as_str())
        .collect();
    let worst = doc
        .joints
        .iter()
        .max_by(|a, b| a.circle_rms.total_cmp(&b.circle_rms));
    let (class, headline) = if unsound.is_empty() {
        (
            "verdict pass",
            format!(
                "{} axes measured; every sweep's screen settled",
                doc.joints.len()
            ),
        )
    } else {
        (
            "verdict fail",
            format!(
                "the fits of {} left out more than a quarter of their points: their axes are not to be trusted",
                unsound.join(", ")
            ),
        )
    };
    let mut summary = format!("<p class=\"big\">{}</p>\n", esc(&headline));
    summary.push_str(&tiles(&[
        ("joints", doc.joints.len().to_string()),
        ("sweeps found", doc.sweeps.len().to_string()),
        (
            "worst circle RMS",
            worst.map_or_else(
                || NA.into(),
                |j| format!("{} mm ({})", mm(j.circle_rms), j.name),
            ),
        ),
        ("points left out", left_out.to_string()),
        (
            "table against the measured axes",
            format!(
                "{} mm, {} deg",
                mm(doc.proof.written[0]),
                sci(doc.proof.written[1] * DEG, 2)
            ),
        ),
    ]));
    p.section("summary", "Summary", class, &summary);
    p.section("sweeps", "Sweeps", "", &sweeps(r));
    p.section("joints", "Fitted circles and axes", "", &joints(r));
    p.section("residuals", "Residuals", "", &plots(r));
    p.section("outliers", "Outliers", "", &outliers(r));
    p.section("table", "DH table", "", &dh_table(r));
    p.section("proof", "Proof and comparison", "", &proof(r));
    p.section("provenance", "Provenance", "", &provenance.html());
    p.finish()
}

fn sweeps(r: &CpaReport) -> String {
    let rows: Vec<Vec<String>> = r
        .doc
        .sweeps
        .iter()
        .map(|s| {
            let prismatic = r
                .doc
                .joints
                .iter()
                .any(|j| j.name == s.joint && j.kind == "prismatic");
            vec![
                esc(&s.joint),
                esc(&s
                    .coupled
                    .iter()
                    .map(|c| format!("{} x {}", c.joint, fixed(c.ratio, 4)))
                    .collect::<Vec<_>>()
                    .join(", ")),
                format!("{}\u{2013}{}", s.lines[0], s.lines[1]),
                s.poses.to_string(),
                s.samples.to_string(),
                if prismatic {
                    format!("{} mm", fixed(s.span * 1e3, 3))
                } else {
                    format!("{} deg", fixed(s.span * DEG, 3))
                },
                if s.used { "yes" } else { "no" }.into(),
            ]
        })
        .collect();
    table(
        &[
            "joint", "coupled", "lines", "#poses", "#samples", "#span", "used",
        ],
        &rows,
    )
}

fn joints(r: &CpaReport) -> String {
    let rows: Vec<Vec<String>> = r
        .doc
        .joints
        .iter()
        .map(|j| {
            let motion = if j.kind == "prismatic" {
                format!("{} mm", mm(j.motion.rms))
            } else {
                format!("{} arcsec", fixed(j.motion.rms * ARCSEC, 2))
            };
            vec![
                esc(&j.name),
                j.kind.into(),
                j.poses.to_string(),
                j.points.to_string(),
                mm(j.radius),
                mm(j.circle_rms),
                mm(j.plane_rms),
                motion,
                sci(j.motion.slope, 3),
            ]
        })
        .collect();
    let mut s = table(
        &[
            "joint",
            "kind",
            "#poses",
            "#points",
            "#radius [mm]",
            "#circle RMS [mm]",
            "#plane RMS [mm]",
            "#motion RMS",
            "#motion slope",
        ],
        &rows,
    );
    s.push_str(&page::muted(
        "motion: measured minus commanded joint motion, mean removed; slope: measured = (1 + slope) x commanded.",
    ));
    let axes: Vec<Vec<String>> = r
        .doc
        .joints
        .iter()
        .map(|j| {
            let mut row = vec![esc(&j.name)];
            row.extend(j.axis.direction.iter().map(|v| fixed(*v, 6)));
            row.extend(j.axis.point.iter().map(|v| fixed(v * 1e3, 3)));
            row
        })
        .collect();
    s.push_str("<h3>Axes (device frame, at each sweep's configuration)</h3>\n");
    s.push_str(&table(
        &[
            "joint",
            "#direction x",
            "#direction y",
            "#direction z",
            "#point x [mm]",
            "#point y [mm]",
            "#point z [mm]",
        ],
        &axes,
    ));
    let rows: Vec<Vec<String>> = r
        .doc
        .joints
        .iter()
        .flat_map(|j| {
            j.targets.iter().map(move |t| {
                vec![
                    esc(&j.name),
                    esc(&t.name),
                    t.points.to_string(),
                    mm(t.radius),
                    mm(t.path_rms),
                    mm(t.plane_rms),
                    mm(t.axis_offset),
                    fixed(t.axis_tilt * DEG, 4),
                ]
            })
        })
        .collect();
    s.push_str("<h3>Each target's own circle</h3>\n");
    s.push_str(&table(
        &[
            "joint",
            "target",
            "#points",
            "#radius [mm]",
            "#path RMS [mm]",
            "#plane RMS [mm]",
            "#centre off the axis [mm]",
            "#tilt from the axis [deg]",
        ],
        &rows,
    ));
    s
}

/// Distance of `p` from the target's own circle (revolute: in-plane and out-of-plane parts
/// together) or line (prismatic), metres.
fn off_path(fit: &TargetFit, p: &nalgebra::Vector3<f64>, kind: JointKind) -> f64 {
    let v = p - fit.centre;
    let along = v.dot(&fit.direction);
    let across = v - fit.direction * along;
    match (kind, fit.radius) {
        (JointKind::Revolute, Some(radius)) => {
            let radial = across.norm() - radius;
            (radial * radial + along * along).sqrt()
        }
        _ => across.norm(),
    }
}

fn joint_points(j: &JointCpa, r: &CpaReport, data: &Measurements) -> (Vec<Point>, &'static str) {
    let Some(sweep) = r.result.sweeps.get(j.sweep) else {
        return (Vec::new(), "deg");
    };
    let flagged: HashSet<usize> = j.screen.left_out.iter().map(|o| o.sample).collect();
    let (scale, unit) = match j.kind {
        JointKind::Prismatic => (1e3, "mm"),
        JointKind::Revolute => (DEG, "deg"),
    };
    let points = sweep
        .samples
        .iter()
        .filter_map(|&i| {
            let s = data.samples.get(i)?;
            let fit = j.targets.iter().find(|t| t.target == s.target)?;
            Some(Point {
                x: s.q.get(sweep.joint).map_or(f64::NAN, |q| q * scale),
                y: off_path(fit, &s.point, j.kind) * 1e3,
                kind: Kind::Calibration,
                marked: flagged.contains(&i),
            })
        })
        .collect();
    (points, unit)
}

fn plots(r: &CpaReport) -> String {
    let mut s = String::from("<div class=\"grid2\">");
    for (j, jd) in r.result.joints.iter().zip(&r.doc.joints) {
        let (points, unit) = joint_points(j, r, &r.data);
        let (svg, note) = Scatter {
            title: &format!("{}: distance from the target's circle", j.name),
            x_label: &format!("{} [{unit}]", j.name),
            y_label: "distance [mm]",
            points: &points,
            lines: vec![(
                j.circle_rms * 1e3,
                format!("circle RMS {} mm", mm(j.circle_rms)),
                "rms",
            )],
            y_from_zero: true,
            compact: true,
        }
        .render();
        s.push_str(&page::figure(
            &svg,
            &format!("{note}Each point of {}'s sweep: its distance from its target's fitted circle, against the commanded value; red rings: left out by the screen.", j.name),
        ));
        let prismatic = j.kind == JointKind::Prismatic;
        let (xs, ys, yu) = if prismatic {
            (1e3, 1e3, "mm")
        } else {
            (DEG, ARCSEC, "arcsec")
        };
        let motion: Vec<Point> = jd
            .motion
            .poses
            .iter()
            .map(|[q, e]| Point {
                x: q * xs,
                y: e * ys,
                kind: Kind::Calibration,
                marked: false,
            })
            .collect();
        let (svg, note) = Scatter {
            title: &format!("{}: measured minus commanded motion", j.name),
            x_label: &format!("{} commanded [{unit}]", j.name),
            y_label: &format!("residual [{yu}]"),
            points: &motion,
            lines: vec![(0.0, String::new(), "rms")],
            y_from_zero: false,
            compact: true,
        }
        .render();
        s.push_str(&page::figure(
            &svg,
            &format!("{note}Per pose: the measured change of {} minus the commanded one, mean removed (slope {}).", j.name, sci(jd.motion.slope, 3)),
        ));
    }
    s.push_str("</div>\n");
    s.push_str(&page::muted(
        "The measurement format has no time column: the sweeps' pose order stands in for time.",
    ));
    s
}

fn outliers(r: &CpaReport) -> String {
    let mut rows = Vec::new();
    for j in &r.doc.joints {
        for o in &j.screen.left_out {
            rows.push(vec![
                esc(&j.name),
                o.line.to_string(),
                esc(&o.target),
                mm(o.distance),
                fixed(o.sigmas, 1),
                format!(
                    "{} x {} mm",
                    fixed(j.screen.threshold, 1),
                    mm(j.screen.scale)
                ),
            ]);
        }
    }
    let mut s = page::muted(
        "Each sweep's screen leaves out the points farther from their circle than the threshold (in units of the known noise or the robust scale, the larger); a sweep that leaves out more than a quarter of its points, or does not settle, is not trusted.",
    );
    if rows.is_empty() {
        s.push_str(&page::para("No point was left out."));
        return s;
    }
    let classes = vec!["flag"; rows.len()];
    s.push_str(&table_with(
        &[
            "joint",
            "#line",
            "target",
            "#distance [mm]",
            "#size [sigma]",
            "threshold",
        ],
        &rows,
        &classes,
    ));
    s
}

fn dh_table(r: &CpaReport) -> String {
    let sheet = &r.sheet;
    let rows: Vec<Vec<String>> = sheet
        .joints
        .iter()
        .map(|j| {
            vec![
                esc(&j.name),
                fixed(j.a * 1e3, 4),
                fixed(j.alpha * DEG, 5),
                fixed(j.d * 1e3, 4),
                fixed(j.theta * DEG, 5),
            ]
        })
        .collect();
    let mut s = page::muted(&format!(
        "{} DH, base in the measuring device's frame (the sheet `cpa --format yaml` writes, in metres and radians there).",
        match sheet.convention {
            crate::sheet::ConventionDoc::Standard => "standard",
            crate::sheet::ConventionDoc::Modified => "modified",
        }
    ));
    s.push_str(&table(
        &[
            "joint",
            "#a [mm]",
            "#alpha [deg]",
            "#d [mm]",
            "#theta [deg]",
        ],
        &rows,
    ));
    if let Some(pairs) = &sheet.pairs {
        let rows: Vec<Vec<String>> = pairs
            .iter()
            .map(|p| {
                vec![
                    esc(&format!("{} \u{2013} {}", p.joints[0], p.joints[1])),
                    esc(&p.relation),
                    fixed(p.angle * DEG, 4),
                    fixed(p.distance * 1e3, 3),
                ]
            })
            .collect();
        s.push_str("<h3>Axis pairs</h3>\n");
        s.push_str(&table(
            &["joints", "relation", "#angle [deg]", "#distance [mm]"],
            &rows,
        ));
    }
    if let Some(t) = &sheet.tolerances {
        s.push_str(&page::para(&format!(
            "Tolerances: axes whose common normal is shorter than {} mm intersect; within {} deg they are parallel.",
            fixed(t.linear * 1e3, 4),
            sci(t.angular * DEG, 2)
        )));
    }
    if let Some(w) = sheet.warnings.as_ref().filter(|w| !w.is_empty()) {
        s.push_str("<h3>Warnings</h3>\n");
        s.push_str(&page::list(w));
    }
    s
}

fn proof(r: &CpaReport) -> String {
    let d = &r.doc;
    let mut s = page::para(&format!(
        "Forward kinematics of the written table against the measured axes' own, at {} measured joint vectors: largest tip difference {} mm and {} deg (the table snapped to parallel within the tolerance: {} mm, {} deg).",
        d.proof.poses,
        mm(d.proof.written[0]),
        sci(d.proof.written[1] * DEG, 2),
        mm(d.proof.snapped[0]),
        sci(d.proof.snapped[1] * DEG, 2)
    ));
    if d.pairs.is_empty() {
        s.push_str(&page::muted(
            "No nominal model given (--model): no comparison.",
        ));
        return s;
    }
    let rows: Vec<Vec<String>> = d
        .pairs
        .iter()
        .map(|p| {
            vec![
                esc(&format!("{} \u{2013} {}", p.joints[0], p.joints[1])),
                fixed(p.nominal_angle * DEG, 4),
                fixed(p.measured_angle * DEG, 4),
                fixed(p.nominal_distance * 1e3, 3),
                fixed(p.measured_distance * 1e3, 3),
            ]
        })
        .collect();
    s.push_str("<h3>Nominal against measured axes</h3>\n");
    s.push_str(&table(
        &[
            "joints",
            "#nominal angle [deg]",
            "#measured angle [deg]",
            "#nominal distance [mm]",
            "#measured distance [mm]",
        ],
        &rows,
    ));
    s
}
