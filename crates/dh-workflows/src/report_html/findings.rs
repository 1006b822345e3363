//! The findings of a calibration from points, serial or tree: the outliers named by the screen,
//! the diagnosis's candidates and refits (why each was taken or rejected), and the verdict with
//! its test and the structure left in the residual.

use std::fmt::Write as _;

use dh_calib::pipeline::{CalibrationDoc, CandidateDoc, OutliersDoc, StructureDoc, TestDoc};

use super::page::{self, esc, fixed, mm, sci, table_with, NA};

/// The outlier section: the screen's figures and every flagged point.
pub(super) fn outliers(doc: &CalibrationDoc) -> String {
    let Some(o) = &doc.outliers else {
        return page::muted("The outlier screen did not run (too few samples for it).");
    };
    let mut s = page::para(&format!(
        "{} point(s) beyond {} x the {} scale of {} mm per axis (Bonferroni family-wise level {}); {}. RMS of the screen's fit with them {} mm, without them {} mm ({} round(s){}{}).",
        o.points.len(),
        fixed(o.threshold, 2),
        o.scale_source,
        mm(o.scale),
        sci(o.level, 1),
        if o.kept { "kept in the fit (--keep-outliers)" } else { "left out of the fit" },
        mm(o.rms_with),
        mm(o.rms_without),
        o.rounds,
        if o.converged { "" } else { ", not settled" },
        if o.effects.is_empty() {
            String::new()
        } else {
            format!("; screened with {}", o.effects.join(", "))
        }
    ));
    if o.points.is_empty() {
        s.push_str(&given_back(o));
        return s;
    }
    let rows: Vec<Vec<String>> = o
        .points
        .iter()
        .map(|p| {
            vec![
                p.line.to_string(),
                p.config.as_deref().map_or_else(|| NA.into(), esc),
                esc(&p.target),
                esc(&p.split),
                mm(p.residual),
                fixed(p.sigmas, 1),
            ]
        })
        .collect();
    let classes = vec!["flag"; rows.len()];
    s.push_str(&table_with(
        &[
            "#line",
            "pose",
            "target",
            "split",
            "#residual [mm]",
            "#size [sigma]",
        ],
        &rows,
        &classes,
    ));
    s.push_str(&given_back(o));
    s
}

/// The points given back: left out by an earlier judgement, not outliers of the final model.
fn given_back(o: &OutliersDoc) -> String {
    if o.given_back.is_empty() {
        return String::new();
    }
    let mut s = page::para(&format!(
        "{} point(s) given back: left out by an earlier judgement, given back by one against a model with effects; they are in the fit (calibration) or the held-out figures (validation). Their size against the model that left them out and against the final model:",
        o.given_back.len()
    ));
    let rows: Vec<Vec<String>> = o
        .given_back
        .iter()
        .map(|g| {
            vec![
                g.line.to_string(),
                g.config.as_deref().map_or_else(|| NA.into(), esc),
                esc(&g.target),
                esc(&g.split),
                fixed(g.before.sigmas, 1),
                fixed(g.after.sigmas, 1),
                esc(&g.reason),
            ]
        })
        .collect();
    s.push_str(&page::table(
        &[
            "#line",
            "pose",
            "target",
            "split",
            "#before [sigma]",
            "#final [sigma]",
            "why",
        ],
        &rows,
    ));
    s
}

fn status_tag(status: &str) -> String {
    let class = match status {
        "selected" => "tag taken",
        "rejected" | "aliased" | "rival" => "tag rejected",
        _ => "tag",
    };
    format!("<span class=\"{class}\">{}</span>", esc(status))
}

fn candidate_rows(candidates: &[CandidateDoc]) -> (Vec<Vec<String>>, Vec<&'static str>) {
    let rows = candidates
        .iter()
        .map(|c| {
            vec![
                esc(&c.label),
                sci(c.score * 1e6, 3),
                mm(c.val_rms),
                fixed(c.independence, 4),
                status_tag(&c.status),
                c.reason.as_deref().map_or_else(String::new, esc),
            ]
        })
        .collect();
    let classes = candidates
        .iter()
        .map(|c| if c.status == "selected" { "taken" } else { "" })
        .collect();
    (rows, classes)
}

/// Candidates listed in each round after the first (best scores first), besides those refitted.
const LATER_ROUND_CANDIDATES: usize = 15;

const CANDIDATE_HEADER: [&str; 6] = [
    "effect",
    "#score [mm\u{b2}]",
    "#held-out RMS [mm]",
    "#independence",
    "status",
    "why",
];

/// A test's one-line figures.
fn test_line(t: &TestDoc) -> String {
    if t.kind == "none" {
        return t.summary.clone();
    }
    format!(
        "{}: statistic {} on ({}, {}) degrees of freedom, p = {}; noise {} mm RMS; {}",
        t.kind,
        t.statistic.map_or_else(|| NA.into(), |v| fixed(v, 3)),
        fixed(t.dof.0, 0),
        fixed(t.dof.1, 0),
        sci(t.p_value, 2),
        mm(t.noise_rms),
        if t.significant {
            "something significant is left"
        } else {
            "nothing significant is left"
        }
    )
}

/// The structure checks of the final residual.
fn structure(checks: &[StructureDoc]) -> String {
    if checks.is_empty() {
        return String::new();
    }
    let rows: Vec<Vec<String>> = checks
        .iter()
        .map(|c| {
            vec![
                esc(&c.variable),
                fixed(c.statistic, 3),
                sci(c.p_value, 2),
                if c.significant { "yes" } else { "no" }.into(),
            ]
        })
        .collect();
    let classes: Vec<&str> = checks
        .iter()
        .map(|c| if c.significant { "flag" } else { "" })
        .collect();
    let mut s = String::from("<h3>Structure of the final residual</h3>\n");
    s.push_str(&table_with(
        &["against", "#statistic", "#p-value", "significant"],
        &rows,
        &classes,
    ));
    s
}

/// The diagnosis section: the rule, the geometric test, every round's candidates and refits.
pub(super) fn diagnosis(doc: &CalibrationDoc) -> String {
    let Some(d) = &doc.diagnosis else {
        let mut s = page::muted(&if doc.selected_effects.is_empty() {
            "No effect search ran (--effects auto runs one): the model is the geometry.".to_string()
        } else {
            format!(
                "The effects were named on the command line ({}); no search ran.",
                doc.selected_effects.join(", ")
            )
        });
        if !doc.candidates.is_empty() {
            let (rows, classes) = candidate_rows(&doc.candidates);
            s.push_str(&table_with(&CANDIDATE_HEADER, &rows, &classes));
        }
        return s;
    };
    let mut s = page::para(&format!("Rule: {} (level {}).", d.rule, fixed(d.alpha, 4)));
    s.push_str(&page::muted(
        "score: first-order reduction of the calibration sum of squares beyond the fit; independence: sine between the effect's columns and the geometric ones (below 1e-3: aliased).",
    ));
    s.push_str(&page::para(&format!(
        "After the geometric step: {}.",
        test_line(&d.geometric_test)
    )));
    for (k, r) in d.rounds.iter().enumerate() {
        let _ = writeln!(
            s,
            "<h3>Round {}: from RMS {} mm (held-out {} mm)</h3>",
            k + 1,
            mm(r.rms),
            mm(r.val_rms)
        );
        // The first round lists every candidate; later ones the best and those refitted.
        let shown: Vec<CandidateDoc> = r
            .candidates
            .iter()
            .enumerate()
            .filter(|(i, c)| {
                k == 0
                    || *i < LATER_ROUND_CANDIDATES
                    || c.status == "selected"
                    || r.trials.iter().any(|t| t.label == c.label)
            })
            .map(|(_, c)| c.clone())
            .collect();
        let (rows, classes) = candidate_rows(&shown);
        s.push_str(&table_with(&CANDIDATE_HEADER, &rows, &classes));
        if shown.len() < r.candidates.len() {
            s.push_str(&page::muted(&format!(
                "{} more candidates with lower scores, none refitted (the first round lists them all; --format json has every round whole).",
                r.candidates.len() - shown.len()
            )));
        }
        if !r.trials.is_empty() {
            let rows: Vec<Vec<String>> = r
                .trials
                .iter()
                .map(|t| {
                    vec![
                        esc(&t.label),
                        mm(t.rms),
                        mm(t.val_rms),
                        sci(t.f_p, 2),
                        sci(t.f_threshold, 2),
                        t.held_out.map_or_else(|| NA.into(), |h| sci(h.1, 2)),
                        if t.accepted {
                            status_tag("selected")
                        } else {
                            status_tag("rejected")
                        },
                        esc(&t.reason),
                    ]
                })
                .collect();
            let classes: Vec<&str> = r
                .trials
                .iter()
                .map(|t| if t.accepted { "taken" } else { "" })
                .collect();
            s.push_str("<p>Refits (full fits with the candidate added):</p>\n");
            s.push_str(&table_with(
                &[
                    "effect",
                    "#RMS [mm]",
                    "#held-out RMS [mm]",
                    "#F-test p",
                    "#must beat",
                    "#held-out p",
                    "result",
                    "why",
                ],
                &rows,
                &classes,
            ));
        }
    }
    s
}

/// The verdict section: the summary, the test, the noise floor and what it means.
pub(super) fn verdict(doc: &CalibrationDoc) -> String {
    let v = &doc.verdict;
    let mut s = format!("<p class=\"big\">{}</p>\n", esc(&v.summary));
    s.push_str(&page::para(&format!(
        "Test at level {}: {}.",
        fixed(v.alpha, 4),
        test_line(&v.test)
    )));
    s.push_str(&page::para(&format!(
        "Noise floor: {} mm RMS 3-D ({}); final calibration RMS {} mm, {} the floor.",
        mm(doc.noise_floor),
        doc.noise.as_ref().map_or_else(
            || "the noise is unknown: give --sigma or repeat poses".to_string(),
            |n| format!("{} mm per axis from {}", mm(n.sigma), n.source)
        ),
        mm(doc.rms_after),
        v.ratio
            .map_or_else(|| "n/a x".to_string(), |r| format!("{} x", fixed(r, 2)))
    )));
    if let Some(a) = doc.angle_noise_floor {
        s.push_str(&page::para(&format!(
            "Orientation noise floor: {} deg per axis.",
            fixed(a.to_degrees(), 5)
        )));
    }
    s.push_str(&page::list(&v.notes));
    s.push_str(&structure(&v.structure));
    if let Some(w) = &doc.written {
        s.push_str(&page::para(&format!(
            "Written model {}: {} predicted points compared, largest deviation {} mm (bound {} mm): {}.",
            w.path,
            w.points,
            mm(w.max_deviation),
            mm(w.bound),
            if w.passed { "proved as written" } else { "FAILED, not written" }
        )));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use dh_calib::pipeline::{GivenBackDoc, JudgedDoc};

    fn judged(sigmas: f64, effects: &[&str]) -> JudgedDoc {
        JudgedDoc {
            residual: sigmas * 2e-5,
            sigmas,
            threshold: 4.2,
            effects: effects.iter().map(|e| e.to_string()).collect(),
        }
    }

    #[test]
    fn the_points_given_back_are_listed_with_both_sizes_and_why() {
        let mut o = OutliersDoc {
            level: 0.01,
            scale: 2e-5,
            scale_source: "known".into(),
            threshold: 4.6,
            kept: false,
            rms_with: 4e-5,
            rms_without: 3e-5,
            effects: vec!["backlash_direction:j2".into()],
            rounds: 1,
            converged: true,
            points: vec![],
            given_back: vec![],
        };
        assert_eq!(given_back(&o), "");
        o.given_back.push(GivenBackDoc {
            line: 13,
            config: Some("p11".into()),
            target: "t1".into(),
            split: "validation".into(),
            before: judged(5.2, &[]),
            after: judged(1.9, &["backlash_direction:j2"]),
            reason: "5.2 sigma against the geometric model, 1.9 sigma against the geometry and \
                     backlash_direction:j2"
                .into(),
        });
        let html = given_back(&o);
        assert!(html.contains("1 point(s) given back"), "{html}");
        for cell in [
            "<td>p11</td>",
            "<td>validation</td>",
            "5.2 sigma against the geometric model, 1.9 sigma against the geometry and backlash_direction:j2",
        ] {
            assert!(html.contains(cell), "{cell} in {html}");
        }
        for n in ["13", "5.2", "1.9"] {
            assert!(html.contains(&format!(">{n}</td>")), "{n} in {html}");
        }
    }
}
