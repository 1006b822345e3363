//! The findings of `calibrate` beyond the fit as text lines: the outliers it named and the
//! verdict on the final model (their JSON documents are the library's, see
//! `dh_workflows::fit`).

use std::fmt::Write as _;

use dh_workflows::fit::{OutliersDoc, VerdictDoc};

/// Text lines for the outliers and the verdict (millimetres).
pub fn text(outliers: Option<&OutliersDoc>, verdict: &VerdictDoc) -> String {
    let mut s = String::new();
    if let Some(o) = outliers.filter(|o| !o.points.is_empty()) {
        let _ = writeln!(
            s,
            "outliers: {} beyond {:.1} sigma (scale {:.4} mm per axis, {}; level {} over all points), {}; {} RMS {:.4} mm with them, {:.4} mm without",
            o.points.len(),
            o.threshold,
            o.scale * 1e3,
            o.scale_source,
            o.level,
            if o.kept { "kept (--keep-outliers)" } else { "left out" },
            if o.effects.is_empty() {
                "geometric".to_string()
            } else {
                format!("geometry + {}", o.effects.join(", "))
            },
            o.rms_with * 1e3,
            o.rms_without * 1e3,
        );
        for p in &o.points {
            let _ = writeln!(
                s,
                "  line {}{}, target {}{}: {:.4} mm, {:.1} sigma",
                p.line,
                p.config
                    .as_deref()
                    .map(|c| format!(", config {c}"))
                    .unwrap_or_default(),
                p.target,
                if p.split == "validation" {
                    " (validation)"
                } else {
                    ""
                },
                p.residual * 1e3,
                p.sigmas,
            );
        }
    }
    if let Some(o) = outliers {
        s.push_str(&given_back(o));
    }
    let _ = writeln!(
        s,
        "verdict: {} ({}{})",
        verdict.summary,
        verdict.test.summary,
        if verdict.test.kind == "none" {
            String::new()
        } else {
            format!(", level {}", verdict.alpha)
        }
    );
    for n in &verdict.notes {
        let _ = writeln!(s, "  {n}");
    }
    s
}

/// Text lines for the points given back, each with why (none: empty).
fn given_back(o: &OutliersDoc) -> String {
    let mut s = String::new();
    if o.given_back.is_empty() {
        return s;
    }
    let _ = writeln!(
        s,
        "outliers given back: {} point(s) an earlier judgement left out, given back by one against a model with effects (in the fit or the validation figures)",
        o.given_back.len()
    );
    for g in &o.given_back {
        let _ = writeln!(
            s,
            "  line {}{}, target {}{}: {}",
            g.line,
            g.config
                .as_deref()
                .map(|c| format!(", config {c}"))
                .unwrap_or_default(),
            g.target,
            if g.split == "validation" {
                " (validation)"
            } else {
                ""
            },
            g.reason,
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use dh_workflows::fit::{GivenBackDoc, JudgedDoc};

    fn judged(sigmas: f64, effects: &[&str]) -> JudgedDoc {
        JudgedDoc {
            residual: sigmas * 2e-5,
            sigmas,
            threshold: 4.2,
            effects: effects.iter().map(|e| e.to_string()).collect(),
        }
    }

    #[test]
    fn the_points_given_back_are_printed_with_why() {
        let outliers = OutliersDoc {
            level: 0.01,
            scale: 2e-5,
            scale_source: "known".into(),
            threshold: 4.6,
            kept: false,
            rms_with: 4e-5,
            rms_without: 4e-5,
            effects: vec!["backlash_direction:j2".into()],
            rounds: 1,
            converged: true,
            points: vec![],
            given_back: vec![GivenBackDoc {
                line: 13,
                config: Some("p11".into()),
                target: "t1".into(),
                split: "validation".into(),
                before: judged(5.2, &[]),
                after: judged(1.9, &["backlash_direction:j2"]),
                reason: "5.2 sigma against the geometric model, 1.9 sigma against the geometry \
                         and backlash_direction:j2"
                    .into(),
            }],
        };
        let s = given_back(&outliers);
        assert!(s.starts_with("outliers given back: 1 point(s)"), "{s}");
        assert!(
            s.contains(
                "  line 13, config p11, target t1 (validation): 5.2 sigma against the geometric \
                 model, 1.9 sigma against the geometry and backlash_direction:j2\n"
            ),
            "{s}"
        );
    }
}
