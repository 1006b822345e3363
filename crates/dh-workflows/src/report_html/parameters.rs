//! The parameters of a calibration on its page: estimates in the page's units (mm, degrees)
//! with their standard errors, the parameters held at nominal with what absorbs them, and the
//! identifiability figures: the condition number and the most correlated pairs of the
//! covariance.

use dh_calib::calibrate::Report;
use dh_calib::pipeline::CalibrationDoc;

use super::page::{self, esc, fixed, mm, sci, table, tiles};

/// A parameter's value in the page's units: lengths in mm, angles in degrees, others as they
/// are; and the unit's symbol (any other unit as the JSON names it: `rad/(N m)`, `ln s`...).
pub(super) fn shown(v: f64, unit: &str) -> (String, &str) {
    match unit {
        "m" => (fixed(v * 1e3, 4), "mm"),
        "rad" => (fixed(v.to_degrees(), 5), "deg"),
        other => (sci(v, 4), other),
    }
}

/// A standard error in the page's units (scientific: a fit of many points pins them far below
/// the value's last printed digit).
pub(super) fn shown_error(e: Option<f64>, unit: &str) -> String {
    let scale = match unit {
        "m" => 1e3,
        "rad" => 180.0 / std::f64::consts::PI,
        _ => 1.0,
    };
    sci(e.map(|e| e * scale), 2)
}

pub(super) fn parameters(doc: &CalibrationDoc) -> String {
    let free: Vec<&dh_calib::pipeline::ParameterDoc> =
        doc.parameters.iter().filter(|p| p.free).collect();
    let rows: Vec<Vec<String>> = free
        .iter()
        .map(|p| {
            let (nominal, unit) = shown(p.nominal, &p.unit);
            let (estimate, _) = shown(p.estimate, &p.unit);
            let (change, _) = shown(p.estimate - p.nominal, &p.unit);
            vec![
                if p.identified {
                    esc(&p.name)
                } else {
                    format!("{} (not identified)", esc(&p.name))
                },
                unit.into(),
                nominal,
                estimate,
                change,
                shown_error(p.std_error, &p.unit),
            ]
        })
        .collect();
    let mut s = page::muted(&format!(
        "{} estimated parameters (of {}); lengths in mm, angles in degrees; standard errors from the covariance of the last step (residual sigma {} mm per coordinate).",
        free.len(),
        doc.parameters.len(),
        mm(doc.sigma_hat)
    ));
    s.push_str(&table(
        &[
            "parameter",
            "unit",
            "#nominal",
            "#estimate",
            "#change",
            "#standard error",
        ],
        &rows,
    ));
    s.push_str(&derived(&free));
    s.push_str(&unidentified(doc));
    if !doc.fixed.is_empty() {
        let rows: Vec<Vec<String>> = doc
            .fixed
            .iter()
            .map(|f| {
                vec![
                    esc(&f.name),
                    if f.aliases.is_empty() {
                        "no effect on the data".into()
                    } else {
                        esc(&f.aliases.join(", "))
                    },
                ]
            })
            .collect();
        s.push_str("<h3>Held at nominal (not identifiable from the data)</h3>\n");
        s.push_str(&table(&["parameter", "absorbed by"], &rows));
    }
    s
}

/// A paragraph per quantity derived from a free parameter
/// ([`dh_calib::pipeline::ParameterDoc::derived`]: the time constant `tau` of
/// `thermal_growth.ln_tau`), with its standard error by the delta method; empty without one.
fn derived(free: &[&dh_calib::pipeline::ParameterDoc]) -> String {
    free.iter()
        .filter_map(|p| p.derived.as_ref().map(|d| (p, d)))
        .map(|(p, d)| {
            page::muted(&format!(
                "{} = exp({}) = {} {} (standard error {} {}, delta method).",
                esc(&d.name),
                esc(&p.name),
                sci(d.estimate, 4),
                esc(&d.unit),
                sci(d.std_error, 2),
                esc(&d.unit)
            ))
        })
        .collect()
}

/// The paragraphs naming the free parameters the data did not identify
/// ([`dh_calib::pipeline::ParameterDoc::identified`]): effect parameters within
/// [`dh_calib::pipeline::IDENTIFIED_SIGMAS`] standard errors of zero, geometric ones whose
/// standard error at the measured points exceeds [`dh_calib::pipeline::GEOMETRIC_FLOOR_RATIO`] times the
/// noise floor; empty when every one is identified.
fn unidentified(doc: &CalibrationDoc) -> String {
    let names = |effects: bool| -> Vec<String> {
        doc.parameters
            .iter()
            .filter(|p| p.free && !p.identified && p.is_effect() == effects)
            .map(|p| esc(&p.name))
            .collect()
    };
    let mut s = String::new();
    let effects = names(true);
    if !effects.is_empty() {
        s.push_str(&page::muted(&format!(
            "Not identified by this data ({}): {}: each estimate is within {} standard errors of zero, as consistent with no effect as with the estimate.",
            effects.len(),
            effects.join(", "),
            dh_calib::pipeline::IDENTIFIED_SIGMAS
        )));
    }
    let geometric = names(false);
    if !geometric.is_empty() {
        s.push_str(&page::muted(&format!(
            "Geometric parameters not identified by this data ({}): {}: each standard error, as a length at the measured points, exceeds {} x {} ({} mm): the poses barely tell it from the others.",
            geometric.len(),
            geometric.join(", "),
            dh_calib::pipeline::GEOMETRIC_FLOOR_RATIO,
            if doc.noise_floor.is_some() {
                "the noise floor"
            } else {
                "the fit's RMS residual (the noise is not known)"
            },
            mm(doc.noise_floor.unwrap_or(doc.rms_after))
        )));
    }
    s
}

/// Whether `name` is a measurement-setup parameter (the device frame, a session's frame, a
/// target) rather than the robot's.
fn is_setup(name: &str) -> bool {
    ["device.", "session.", "target."]
        .iter()
        .any(|p| name.starts_with(p))
}

/// The `n` most correlated pairs of free parameters of `report`'s covariance: (first, second,
/// correlation), largest |correlation| first; `robot`: only pairs with a parameter of the robot
/// (not both of the setup, [`is_setup`]).
pub(super) fn most_correlated(
    report: &Report,
    n: usize,
    robot: bool,
) -> Vec<(String, String, f64)> {
    let Some(c) = &report.covariance else {
        return Vec::new();
    };
    let k = c.parameters.len();
    let sd: Vec<f64> = (0..k).map(|i| c.matrix[(i, i)].max(0.0).sqrt()).collect();
    let mut pairs = Vec::new();
    for i in 0..k {
        for j in 0..i {
            if robot && is_setup(&c.parameters[i]) && is_setup(&c.parameters[j]) {
                continue;
            }
            let denom = sd[i] * sd[j];
            if denom > 0.0 && denom.is_finite() {
                let r = (c.matrix[(i, j)] / denom).clamp(-1.0, 1.0);
                if r.is_finite() {
                    pairs.push((c.parameters[j].clone(), c.parameters[i].clone(), r));
                }
            }
        }
    }
    pairs.sort_by(|a, b| b.2.abs().total_cmp(&a.2.abs()));
    pairs.truncate(n);
    pairs
}

pub(super) fn correlations(doc: &CalibrationDoc, report: &Report) -> String {
    let mut s = tiles(&[
        (
            "condition number (scaled Jacobian)",
            sci(doc.condition_number, 3),
        ),
        ("free parameters (rank)", doc.rank.to_string()),
        (
            "angle columns scaled by",
            format!("{} mm", fixed(report.length_scale * 1e3, 1)),
        ),
        ("rank tolerance (relative)", sci(report.rank_tolerance, 1)),
    ]);
    let pairs = most_correlated(report, 12, true);
    if pairs.is_empty() {
        s.push_str(&page::muted(
            "No covariance: the residual's sigma is unknown (no more coordinates than parameters).",
        ));
        return s;
    }
    let rows: Vec<Vec<String>> = pairs
        .iter()
        .map(|(a, b, r)| vec![esc(a), esc(b), fixed(*r, 4)])
        .collect();
    s.push_str("<h3>Most correlated pairs</h3>\n");
    s.push_str(&page::muted(
        "Correlation of the estimates (from the covariance of the last step), largest first; pairs of two setup parameters (device frame, targets) left out. Near \u{b1}1: the data hardly tell the two apart.",
    ));
    s.push_str(&table(&["parameter", "parameter", "#correlation"], &rows));
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn setup_parameters_are_told_from_the_robots() {
        assert!(is_setup("device.rx") && is_setup("target.t1.x") && is_setup("session.s2.z"));
        assert!(!is_setup("elbow_joint.a") && !is_setup("base.x") && !is_setup("gear_ratio:j2"));
    }

    /// The parameter table's unit column names an effect's unit as the JSON does: `ln s` (or
    /// `ln session` without times) for `thermal_growth.ln_tau`, not `1`.
    #[test]
    fn the_unit_column_names_each_effects_own_unit() {
        assert_eq!(shown(7.09, "ln s"), ("7.0900e0".into(), "ln s"));
        assert_eq!(shown(-1.0, "ln session").1, "ln session");
        assert_eq!(shown(6e-4, "1/m^2").1, "1/m^2");
        assert_eq!(shown(6e-5, "1").1, "1");
        assert_eq!(shown(0.1, "m"), ("100.0000".into(), "mm"));
    }

    /// The page gives tau = exp(ln_tau) in seconds beside `thermal_growth.ln_tau`, with its
    /// delta-method standard error: ln 1200 +- 0.25 is 1.2e3 +- 3.0e2 s.
    #[test]
    fn thermal_growth_tau_is_shown_in_seconds() {
        use dh_calib::pipeline::{DerivedDoc, ParameterDoc};
        let param = |name: &str, estimate: f64, se: f64| ParameterDoc {
            name: name.into(),
            unit: dh_calib::pipeline::unit_of(name).into(),
            nominal: 0.0,
            estimate,
            std_error: Some(se),
            free: true,
            identified: true,
            derived: DerivedDoc::of(name, estimate, Some(se), true),
        };
        let ln_tau = param("thermal_growth.ln_tau", 1200f64.ln(), 0.25);
        let k = param("thermal_growth.k", 6e-5, 6e-6);
        assert_eq!(
            derived(&[&k, &ln_tau]),
            page::muted("thermal_growth.tau = exp(thermal_growth.ln_tau) = 1.2000e3 s (standard error 3.00e2 s, delta method).")
        );
        assert_eq!(derived(&[&k]), "");
    }
}
