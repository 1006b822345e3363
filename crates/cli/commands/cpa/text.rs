//! The text report of `cpa`.

use dh_workflows::sheet::SheetDoc;
use dh_workflows::units::{AngleUnit, LengthUnit};
use std::fmt::Write as _;

use super::*;

/// `v` with `decimals`, `-0` as `0`.
pub(super) fn fixed(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        s.trim_start_matches('-').to_string()
    } else {
        s
    }
}

pub(super) fn text(doc: &CpaDoc, sheet: &SheetDoc) -> String {
    let (lu, au) = (LengthUnit::M, AngleUnit::Rad);
    let l = |v: f64| match lu {
        LengthUnit::M => fixed(v, 6),
        LengthUnit::Mm => fixed(v * 1e3, 3),
    };
    // Joint-motion residuals are small angles: a tenth of a microradian resolves them.
    let a = |v: f64| match au {
        AngleUnit::Rad => fixed(v, 7),
        AngleUnit::Deg => fixed(v.to_degrees(), 5),
    };
    let span = |v: f64, kind: &str| {
        if kind == "prismatic" {
            format!("{} {}", l(v), lu.symbol())
        } else {
            format!("{} {}", a(v), au.symbol())
        }
    };
    let mut s = String::new();
    let _ = writeln!(
        s,
        "circle-point analysis of {}: {} samples of {} target(s) ({}), device frame",
        doc.data,
        doc.samples,
        doc.targets.len(),
        doc.targets.join(", ")
    );
    let _ = writeln!(s, "sweeps:");
    for sw in &doc.sweeps {
        let coupled: String = sw
            .coupled
            .iter()
            .map(|c| format!(" with {} x {}", c.joint, fixed(c.ratio, 4)))
            .collect();
        let kind = doc
            .joints
            .iter()
            .find(|j| j.name == sw.joint)
            .map_or("revolute", |j| j.kind);
        let _ = writeln!(
            s,
            "  {}{coupled}: lines {}-{}, {} poses, span {}{}",
            sw.joint,
            sw.lines[0],
            sw.lines[1],
            sw.poses,
            span(sw.span, kind),
            if sw.used { "" } else { " (not used)" }
        );
    }
    let _ = writeln!(
        s,
        "joints (lengths in {}, angles in {}):",
        lu.symbol(),
        au.symbol()
    );
    let w = crate::guard::column_width(doc.joints.iter().map(|j| j.name.as_str()), 5);
    let _ = writeln!(
        s,
        "  {:<w$} {:>5} {:>6} {:>12} {:>11} {:>11} {:>11} {:>12}",
        "joint",
        "poses",
        "points",
        "radius",
        "circle_rms",
        "plane_rms",
        "motion_rms",
        "motion_slope"
    );
    for j in &doc.joints {
        let motion = |v: f64| {
            if j.kind == "prismatic" {
                l(v)
            } else {
                a(v)
            }
        };
        let _ = writeln!(
            s,
            "  {:<w$} {:>5} {:>6} {:>12} {:>11} {:>11} {:>11} {:>12}",
            crate::guard::escape(&j.name),
            j.poses,
            j.points,
            j.radius.map_or_else(|| "-".into(), l),
            l(j.circle_rms),
            j.plane_rms.map_or_else(|| "-".into(), l),
            motion(j.motion.rms),
            j.motion
                .slope
                .map_or_else(|| "-".into(), |v| format!("{v:.3e}"))
        );
    }
    let _ = writeln!(
        s,
        "  (motion: measured minus commanded joint motion, mean removed; slope: measured = (1 + slope) x commanded)"
    );
    for j in &doc.joints {
        let sc = &j.screen;
        if sc.left_out.is_empty() && sc.sound {
            continue;
        }
        let _ = writeln!(
            s,
            "{}: {} point(s) left out of the fits (farther than {:.1} x {} {} from their circles){}",
            crate::guard::escape(&j.name),
            sc.left_out.len(),
            sc.threshold,
            l(sc.scale),
            lu.symbol(),
            if sc.sound { "" } else { "; too many to trust the fit: the sweep is not a circle" }
        );
        for o in &sc.left_out {
            let _ = writeln!(
                s,
                "  line {}, target {}: {} {} off ({:.1} x the scale)",
                o.line,
                crate::guard::escape(&o.target),
                l(o.distance),
                lu.symbol(),
                o.sigmas
            );
        }
    }
    if !doc.pairs.is_empty() {
        let _ = writeln!(s, "axis pairs, nominal -> measured:");
        for p in &doc.pairs {
            let _ = writeln!(
                s,
                "  {} -> {}: angle {} -> {} {}, distance {} -> {} {}",
                p.joints[0],
                p.joints[1],
                a(p.nominal_angle),
                a(p.measured_angle),
                au.symbol(),
                l(p.nominal_distance),
                l(p.measured_distance),
                lu.symbol()
            );
        }
    }
    let _ = writeln!(
        s,
        "table against the measured axes (FK at the {} measured joint vectors): max {:.3e} m, {:.3e} rad (snapping near-parallel pairs would give {:.3e} m, {:.3e} rad)",
        doc.proof.poses, doc.proof.written[0], doc.proof.written[1], doc.proof.snapped[0], doc.proof.snapped[1]
    );
    let _ = writeln!(s, "extracted DH table (base: DH frame 0 in the device frame; tool: the tip frame at the last joint's circle centre):");
    s.push_str(&render_sheet(sheet, Format::Text).unwrap_or_default());
    s
}
