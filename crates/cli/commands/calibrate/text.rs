//! The text report of a calibration: the steps' RMS, mean and largest errors, the estimates
//! with their standard errors in the data's units, the parameters fixed with their aliases,
//! the sessions, outliers, verdict and diagnosis.

use super::*;

/// A length in the report's unit with micrometre resolution.
pub(super) fn len(v: f64, unit: LengthUnit) -> String {
    let v = v / unit.metres();
    let s = match unit {
        LengthUnit::M => format!("{v:.6}"),
        LengthUnit::Mm => format!("{v:.3}"),
    };
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        s.trim_start_matches('-').to_string()
    } else {
        s
    }
}

/// A parameter value in its unit (lengths and angles in the report's units).
/// A standard error as [`value`] prints it, or in scientific notation in the same unit when
/// that would print only zeros (a fit of millions of points pins lengths below a micrometre).
pub(super) fn std_error(e: f64, unit: &str, units: DataUnits) -> String {
    let fixed = value(e, unit, units);
    if e == 0.0 || !fixed.chars().all(|c| c == '0' || c == '.') {
        return fixed;
    }
    let shown = match (unit, units.angle) {
        ("m", _) => e / units.length.metres(),
        ("rad", AngleUnit::Deg) => e.to_degrees(),
        _ => e,
    };
    format!("{shown:.1e}")
}

pub(super) fn value(v: f64, unit: &str, units: DataUnits) -> String {
    let s = match unit {
        "m" => return len(v, units.length),
        "rad" => match units.angle {
            AngleUnit::Rad => format!("{v:.7}"),
            AngleUnit::Deg => format!("{:.5}", v.to_degrees()),
        },
        _ => format!("{v:.4e}"),
    };
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        s.trim_start_matches('-').to_string()
    } else {
        s
    }
}

/// The unit printed in brackets in the parameter table: lengths and angles in `units`, any
/// other unit as the JSON names it (`1`, `rad/(N m)`, `1/m^2`, `ln s`...).
pub(super) fn unit_label(unit: &str, units: DataUnits) -> &str {
    match unit {
        "m" => units.length.symbol(),
        "rad" => units.angle.symbol(),
        other => other,
    }
}

/// The readable report: metres and radians, like the JSON (the unit options say what the
/// measurement files hold, not how to print).
pub(super) fn text(doc: &CalibrationDoc, inputs: &Inputs) -> String {
    let units = DataUnits::default();
    let lu = units.length;
    let l = |v: f64| len(v, lu);
    let o = |v: Option<f64>| v.map_or_else(|| "-".to_string(), |v| len(v, lu));
    let mut s = String::new();
    let robot = inputs
        .robot
        .as_deref()
        .map(|r| format!("{r}, "))
        .unwrap_or_default();
    let _ = writeln!(
        s,
        "calibration of {robot}{} ({} DH, {} joints) against {}",
        doc.model,
        inputs.table.convention,
        inputs.table.rows.len(),
        doc.data
    );
    let validation = doc.validation_words();
    let _ = writeln!(
        s,
        "data: {} calibration samples of {} target(s) ({}); {validation}",
        doc.samples,
        doc.targets.len(),
        doc.targets
            .iter()
            .map(|t| t.name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    );
    // 6-DoF poses: the orientation residuals beside the positions (absent for points).
    if let Some(a) = doc.steps.last().and_then(|s| s.angle_rms) {
        let floor = doc
            .angle_noise_floor
            .map(|f| format!("; noise floor {:.1} µrad RMS", f * 1e6))
            .unwrap_or_default();
        let _ = writeln!(s, "angle: RMS {:.1} µrad per axis{floor}", a * 1e6);
    }
    match (&doc.noise, doc.noise_floor) {
        (Some(n), Some(f)) => {
            let _ = writeln!(
                s,
                "noise: {} {} per axis ({}); noise floor {} {} RMS",
                l(n.sigma),
                lu.symbol(),
                match n.source.as_str() {
                    "given" => "given with --sigma",
                    "samples" => "the samples' sigma",
                    _ => "pure error of repeated poses",
                },
                l(f),
                lu.symbol()
            );
        }
        _ => {
            let _ = writeln!(
                s,
                "noise: unknown (no sigma column, no repeated poses, no --sigma)"
            );
        }
    }
    let _ = writeln!(
        s,
        "{:<12} {:>5} {:>5} {:>11} {:>11} {:>11} {:>11} {:>11} {:>11}  [{}]",
        "step",
        "free",
        "iter",
        "rms",
        "mean",
        "max",
        "val_rms",
        "val_mean",
        "val_max",
        lu.symbol()
    );
    for st in &doc.steps {
        let _ = writeln!(
            s,
            "{:<12} {:>5} {:>5} {:>11} {:>11} {:>11} {:>11} {:>11} {:>11}",
            st.label,
            st.free,
            st.iterations,
            l(st.rms),
            l(st.mean),
            l(st.max),
            o(st.val_rms),
            o(st.val_mean),
            o(st.val_max)
        );
    }
    // 6-DoF poses: each step's orientation residuals, as the positions' above.
    if doc.steps.iter().any(|st| st.angle_rms.is_some()) {
        let urad = |v: Option<f64>| v.map_or_else(|| "-".into(), |v| format!("{:.1}", v * 1e6));
        let _ = writeln!(
            s,
            "{:<12} {:>11} {:>13}  [µrad per axis]",
            "step", "angle_rms", "val_angle_rms"
        );
        for st in &doc.steps {
            let _ = writeln!(
                s,
                "{:<12} {:>11} {:>13}",
                st.label,
                urad(st.angle_rms),
                urad(st.val_angle_rms)
            );
        }
    }
    // What the nominal step could not estimate (targets seen at one tool orientation only,
    // aliased with the device frame) stayed at the closed-form start.
    if let Some(first) = doc.steps.first().filter(|st| !st.fixed.is_empty()) {
        let _ = writeln!(
            s,
            "{} step: held at the start ({}; not identifiable from this data):",
            first.label,
            first.fixed.len()
        );
        for f in &first.fixed {
            let _ = writeln!(s, "  {:<28} {}", f.name, absorbed(&f.aliases));
        }
    }
    let _ = writeln!(
        s,
        "identifiability: {} free parameters, condition number {:.3e}{}",
        doc.rank,
        doc.condition_number,
        doc.sigma_hat
            .map(|v| format!(", residual sigma {} {} per coordinate", l(v), lu.symbol()))
            .unwrap_or_default()
    );
    if doc.fixed.is_empty() {
        let _ = writeln!(s, "fixed at nominal: none");
    } else {
        let _ = writeln!(
            s,
            "fixed at nominal ({}; not identifiable from this data):",
            doc.fixed.len()
        );
        for f in &doc.fixed {
            let _ = writeln!(s, "  {:<28} {}", f.name, absorbed(&f.aliases));
        }
    }
    let _ = writeln!(
        s,
        "estimated parameters (nominal -> estimate +- standard error):"
    );
    let width = crate::guard::column_width(doc.parameters.iter().map(|p| p.name.as_str()), 4);
    let listed: Vec<_> = doc
        .parameters
        .iter()
        .filter(|p| {
            p.free
                && !p.name.starts_with("device.")
                && !p.name.starts_with("session.")
                && !p.name.starts_with("target.")
        })
        .collect();
    // The unit column as wide as its widest unit (`ln session`), at least the 3 of `rad`.
    let unit_width = listed
        .iter()
        .map(|p| unit_label(&p.unit, units).chars().count())
        .fold(3, usize::max);
    for p in listed {
        let _ = writeln!(
            s,
            "  {:<width$} [{:>unit_width$}] {:>13} -> {:>13} +- {}{}",
            crate::guard::escape(&p.name),
            unit_label(&p.unit, units),
            value(p.nominal, &p.unit, units),
            value(p.estimate, &p.unit, units),
            p.std_error
                .map_or_else(|| "-".into(), |e| std_error(e, &p.unit, units)),
            if p.identified { "" } else { "  not identified" }
        );
    }
    let unidentified = |effects: bool| -> Vec<String> {
        doc.parameters
            .iter()
            .filter(|p| p.free && !p.identified && p.is_effect() == effects)
            .map(|p| crate::guard::escape(&p.name).into_owned())
            .collect()
    };
    let effects = unidentified(true);
    if !effects.is_empty() {
        let _ = writeln!(
            s,
            "not identified by this data ({}): {}: each estimate is within {} standard errors of zero, as consistent with no effect as with the estimate; kept in the model, its uncertainty covers zero",
            effects.len(),
            effects.join(", "),
            dh_workflows::fit::IDENTIFIED_SIGMAS
        );
    }
    let geometric = unidentified(false);
    if !geometric.is_empty() {
        let _ = writeln!(
            s,
            "geometric parameters not identified by this data ({}): {}: each standard error, as a length at the measured points, exceeds {} x {} ({} {}): the poses barely tell it from the others; kept at its estimate, its uncertainty is what the data allow",
            geometric.len(),
            geometric.join(", "),
            dh_workflows::fit::GEOMETRIC_FLOOR_RATIO,
            if doc.noise_floor.is_some() {
                "the noise floor"
            } else {
                "the fit's RMS residual (the noise is not known)"
            },
            l(doc.noise_floor.unwrap_or(doc.rms_after)),
            lu.symbol()
        );
    }
    let rpy = |r: [f64; 3]| {
        r.map(|v| value(v, "rad", units))
            .into_iter()
            .collect::<Vec<_>>()
            .join(" ")
    };
    let xyz = |p: [f64; 3]| p.map(l).into_iter().collect::<Vec<_>>().join(" ");
    let _ = writeln!(
        s,
        "device frame (robot base in the device frame): xyz [{}] {}  rpy [{}] {}",
        lu.symbol(),
        xyz(doc.device.xyz),
        units.angle.symbol(),
        rpy(doc.device.rpy)
    );
    crate::commands::calibrate_sessions::text(&mut s, &doc.sessions, &xyz, &rpy, &o);
    for t in &doc.targets {
        let _ = writeln!(
            s,
            "target {} (tip frame): xyz [{}] {}{}",
            t.name,
            lu.symbol(),
            xyz(t.xyz),
            t.rpy.map_or(String::new(), |r| format!(
                "  rpy [{}] {}",
                units.angle.symbol(),
                rpy(r)
            ))
        );
    }
    if !doc.candidates.is_empty() {
        let level = doc
            .diagnosis
            .as_ref()
            .map_or(String::new(), |d| format!("tests at level {}; ", d.alpha));
        let _ = writeln!(
            s,
            "effect candidates (first round, best score first; {level}score = SSR reduction beyond the geometric fit, held-out RMS linearised):"
        );
        let _ = writeln!(
            s,
            "  {:<32} {:>12} {:>12} {:>12}  status",
            "label",
            format!("score [{}²]", lu.symbol()),
            "independence",
            format!("val_rms [{}]", lu.symbol())
        );
        let scale = lu.metres();
        for c in doc.candidates.iter().take(15) {
            let _ = writeln!(
                s,
                "  {:<32} {:>12.4e} {:>12.4} {:>12}  {}",
                c.label,
                c.score / (scale * scale),
                c.independence,
                o(c.val_rms),
                match (c.status.as_str(), &c.reason) {
                    ("rival", Some(r)) => format!("rival ({r})"),
                    (s, _) => s.to_string(),
                }
            );
        }
        if doc.candidates.len() > 15 {
            let _ = writeln!(
                s,
                "  ... {} more (see --format json)",
                doc.candidates.len() - 15
            );
        }
    }
    if !doc.selected_effects.is_empty() {
        let _ = writeln!(s, "effects: {}", doc.selected_effects.join(", "));
        for p in doc.parameters.iter().filter(|p| p.is_effect()) {
            let stiffness = (p.unit == "rad/(N m)" && p.estimate != 0.0).then(|| {
                format!(
                    "  (stiffness {:.4e}{} N m/rad)",
                    1.0 / p.estimate,
                    p.std_error
                        .map(|e| format!(" +- {:.1e}", e / (p.estimate * p.estimate)))
                        .unwrap_or_default()
                )
            });
            // A derived quantity beside it (tau of thermal_growth.ln_tau), as the stiffness.
            let derived = p.derived.as_ref().map(|d| {
                format!(
                    "  ({} {:.4e}{} {})",
                    d.name.rsplit('.').next().unwrap_or(&d.name),
                    d.estimate,
                    d.std_error
                        .map(|e| format!(" +- {e:.1e}"))
                        .unwrap_or_default(),
                    d.unit
                )
            });
            let _ = writeln!(
                s,
                "  {} = {:.6e}{} {}{}{}",
                p.name,
                p.estimate,
                p.std_error
                    .map(|e| format!(" +- {e:.1e}"))
                    .unwrap_or_default(),
                p.unit,
                stiffness.unwrap_or_default(),
                derived.unwrap_or_default()
            );
        }
    }
    for n in &doc.notes {
        let _ = writeln!(s, "note: {n}");
    }
    s.push_str(&crate::commands::calibrate_findings::text(
        doc.outliers.as_ref(),
        &doc.verdict,
    ));
    if let Some(w) = &doc.written {
        let _ = writeln!(s, "{}", dh_workflows::written::line(w));
    }
    let _ = writeln!(
        s,
        "result: RMS {} -> {} {}{}",
        l(doc.rms_before),
        l(doc.rms_after),
        lu.symbol(),
        match (doc.val_rms_before, doc.val_rms_after) {
            (Some(b), Some(a)) => format!(" (validation {} -> {} {})", l(b), l(a), lu.symbol()),
            _ => String::new(),
        } + &angle_result(doc)
    );
    s
}

/// The result line's orientation part for 6-DoF poses: `; angle RMS a -> b µrad (validation
/// c -> d µrad)`, empty for points.
fn angle_result(doc: &CalibrationDoc) -> String {
    let (Some(first), Some(last)) = (doc.steps.first(), doc.steps.last()) else {
        return String::new();
    };
    let (Some(b), Some(a)) = (first.angle_rms, last.angle_rms) else {
        return String::new();
    };
    let val = match (first.val_angle_rms, last.val_angle_rms) {
        (Some(vb), Some(va)) => format!(" (validation {:.1} -> {:.1} µrad)", vb * 1e6, va * 1e6),
        _ => String::new(),
    };
    format!(
        "; angle RMS {:.1} -> {:.1} µrad per axis{val}",
        b * 1e6,
        a * 1e6
    )
}

/// How a fixed parameter's error shows in the data: the free parameters that absorb it.
pub(super) fn absorbed(aliases: &[String]) -> String {
    if aliases.is_empty() {
        "no effect on the data".to_string()
    } else {
        format!("absorbed by {}", aliases.join(", "))
    }
}
