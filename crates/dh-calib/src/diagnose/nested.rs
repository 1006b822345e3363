//! Nested rivals (module docs, step 4; issue 33 §3): when the effect a round would add and
//! another candidate refitted in the same round change the same quantity of the same joint
//! and the terms of one are a subset of the other's (`gear_harmonic:J`, once per turn, and
//! `gear_harmonic:J:2`, once and twice per turn), the bigger one explains everything the
//! smaller one does and more by construction, so BIC and the held-out RMS alone can pick it on
//! noise. The two are compared by the extra-sum-of-squares F test (N. R. Draper, H. Smith,
//! *Applied Regression Analysis*, 3rd ed., 1998, §6.1),
//!
//! `F = ((SSR_small − SSR_big) / (p_big − p_small)) / (SSR_big / (m − p_big))`,
//!
//! on `(p_big − p_small, m − p_big)` degrees of freedom (`m` residuals, `p` free parameters of
//! each fit), and the simpler is kept unless the extra terms are significant at the run's
//! `alpha`. The simpler one must itself have passed the fit's own tests (F-to-enter and BIC):
//! its held-out check may have failed by a hair where the bigger one's passed, which the
//! report says.

use super::*;

/// Whether `small`'s terms are a strict subset of `big`'s: the two are rivals
/// ([`rivals::are_rivals`]), of one kind (the label's first part, a trailing harmonic number
/// dropped: `gear_harmonic2` is `gear_harmonic`) and the names of `small`'s parameters (after
/// the label: `sin`, `cos`, `sin2`, `cos2`) are all among `big`'s, which has more.
pub(crate) fn is_nested(small: &dyn Effect, big: &dyn Effect) -> bool {
    let kind = |e: &dyn Effect| {
        let label = e.label();
        let first = label.split(':').next().unwrap_or_default().to_string();
        first
            .trim_end_matches(|c: char| c.is_ascii_digit())
            .to_string()
    };
    let terms = |e: &dyn Effect| -> Vec<String> {
        e.parameter_names()
            .iter()
            .map(|n| n.rsplit('.').next().unwrap_or_default().to_string())
            .collect()
    };
    if !rivals::are_rivals(small, big) || kind(small) != kind(big) {
        return false;
    }
    let (s, b) = (terms(small), terms(big));
    s.len() < b.len() && s.iter().all(|t| b.contains(t))
}

/// The extra-sum-of-squares F test of `big` against the `small` model nested in it (see the
/// module docs).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct ExtraTerms {
    /// The statistic.
    pub(crate) f: f64,
    /// Its degrees of freedom: the extra terms, and the residuals less the bigger fit's
    /// parameters.
    pub(crate) dof: (f64, f64),
    /// Its p-value.
    pub(crate) p: f64,
}

impl ExtraTerms {
    /// The test of `big` (the bigger fit) against `small`, both of the same `m` residuals.
    pub(crate) fn of(small: &FitOutcome, big: &FitOutcome) -> ExtraTerms {
        let m = big.residual_count as f64;
        let (ps, pb) = (small.free.len() as f64, big.free.len() as f64);
        let extra = (pb - ps).max(1.0);
        let dof = (m - pb).max(1.0);
        let f = ((small.ssr - big.ssr).max(0.0) / extra) / (big.ssr / dof).max(1e-300);
        ExtraTerms {
            f,
            dof: (extra, dof),
            p: stats::f_sf(f, extra, dof),
        }
    }

    /// `F = 1.23 on (2, 700), p = 2.90e-1`.
    pub(crate) fn summary(&self) -> String {
        format!(
            "F = {:.2} on ({}, {}), p = {:.2e}",
            self.f, self.dof.0, self.dof.1, self.p
        )
    }
}

/// A refitted candidate of the round: its effect, its trial and its fit, and whether it
/// passed every test of the rule.
pub(super) struct Refitted<'a> {
    pub(super) effect: usize,
    pub(super) trial: &'a Trial,
    pub(super) fit: &'a FitOutcome,
    pub(super) passed: bool,
}

/// Whether a trial passed the tests of the fit itself: F-to-enter and BIC (the held-out check
/// aside).
fn fits_well(t: &Trial) -> bool {
    t.f_p < t.f_threshold && t.bic.1 < t.bic.0
}

/// What the comparison of nested rivals decided: take `effect` instead of the round's winner,
/// compared with it by `test`; `simpler` when it is the smaller of the two.
pub(super) struct NestedChoice {
    pub(super) effect: usize,
    pub(super) test: ExtraTerms,
    pub(super) simpler: bool,
}

/// Compares the round's `winner` with the candidates of `refitted` nested with it (see the
/// module docs): a smaller one that fits well is taken when the winner's extra terms are not
/// significant at `alpha` (the fewest parameters, then the lowest SSR); else a bigger one that
/// passed every test is taken when its extra terms are significant (the lowest p). `None`: the
/// winner stays.
pub(super) fn choose(
    pool: &[Arc<dyn Effect>],
    winner: &Refitted<'_>,
    refitted: &[Refitted<'_>],
    alpha: f64,
) -> Option<NestedChoice> {
    let w = pool.get(winner.effect)?;
    let smaller = refitted
        .iter()
        .filter(|r| r.effect != winner.effect && fits_well(r.trial))
        .filter(|r| {
            pool.get(r.effect)
                .is_some_and(|s| is_nested(s.as_ref(), w.as_ref()))
        })
        .map(|r| (r, ExtraTerms::of(r.fit, winner.fit)))
        .filter(|(_, t)| t.p >= alpha)
        .min_by(|(a, _), (b, _)| {
            a.fit
                .free
                .len()
                .cmp(&b.fit.free.len())
                .then(a.fit.ssr.total_cmp(&b.fit.ssr))
        });
    if let Some((r, test)) = smaller {
        return Some(NestedChoice {
            effect: r.effect,
            test,
            simpler: true,
        });
    }
    refitted
        .iter()
        .filter(|r| r.effect != winner.effect && r.passed)
        .filter(|r| {
            pool.get(r.effect)
                .is_some_and(|b| is_nested(w.as_ref(), b.as_ref()))
        })
        .map(|r| (r, ExtraTerms::of(winner.fit, r.fit)))
        .filter(|(_, t)| t.p < alpha)
        .min_by(|(_, a), (_, b)| a.p.total_cmp(&b.p))
        .map(|(r, test)| NestedChoice {
            effect: r.effect,
            test,
            simpler: false,
        })
}

/// The reasons and the note of a choice: `(the winner's new reason, the chosen one's, the
/// note)`. `kept` and `dropped` are labels.
pub(super) fn reasons(
    choice: &NestedChoice,
    kept: &str,
    dropped: &str,
    alpha: f64,
) -> (String, String, String) {
    let test = choice.test.summary();
    if choice.simpler {
        (
            format!(
                "{}{kept}, nested in it: the extra terms are not significant ({test} >= {alpha}); \
                 the simpler kept",
                rivals::RIVAL_OF
            ),
            format!("kept over {dropped}, whose extra terms are not significant ({test})"),
            format!(
                "nested rivals compared: {kept} kept over {dropped}, whose extra terms are not \
                 significant ({test} >= {alpha})"
            ),
        )
    } else {
        (
            format!(
                "{}{kept}, nested in it: its extra terms are significant ({test} < {alpha})",
                rivals::RIVAL_OF
            ),
            format!("taken over {dropped}: its extra terms are significant ({test})"),
            format!(
                "nested rivals compared: {kept} taken over {dropped}, its extra terms significant \
                 ({test} < {alpha})"
            ),
        )
    }
}

/// A refit's step with its free and held parameters (the fitted part of an [`Attempt`]).
pub(super) type Fitted = (
    crate::calibrate::StepResult,
    Vec<usize>,
    Vec<crate::fit::Fixed>,
);

/// Settles the round's winner `passed[best]` against the candidates nested with it (see
/// [`choose`]): `passed` holds `(effect, trial index, fit)` of those that passed every test,
/// `failed` those refitted this round that did not. When a nested rival is taken instead, it
/// moves into `passed` (out of `failed` and `rejected`), its trial is marked accepted with the
/// comparison, and a note says what was compared; returns the index in `passed` to add and,
/// when the winner changed, the old winner's trial and its reason (to set once the losers'
/// reasons are written).
#[allow(clippy::too_many_arguments)]
pub(super) fn settle(
    pool: &[Arc<dyn Effect>],
    trials: &mut [Trial],
    passed: &mut Vec<(usize, usize, Fitted)>,
    failed: &mut HashMap<usize, (usize, Fitted)>,
    rejected: &mut Vec<usize>,
    best: usize,
    alpha: f64,
    notes: &mut Vec<String>,
) -> (usize, Option<(usize, String)>) {
    let Some(&(w_effect, w_trial, ref w_fit)) = passed.get(best) else {
        return (best, None);
    };
    let choice = {
        let refitted: Vec<Refitted<'_>> = passed
            .iter()
            .map(|(e, t, f)| (*e, *t, f, true))
            .chain(failed.iter().map(|(e, (t, f))| (*e, *t, f, false)))
            .filter_map(|(effect, t, f, passed)| {
                Some(Refitted {
                    effect,
                    trial: trials.get(t)?,
                    fit: &f.0.outcome,
                    passed,
                })
            })
            .collect();
        let Some(trial) = trials.get(w_trial) else {
            return (best, None);
        };
        let winner = Refitted {
            effect: w_effect,
            trial,
            fit: &w_fit.0.outcome,
            passed: true,
        };
        choose(pool, &winner, &refitted, alpha)
    };
    let Some(choice) = choice else {
        return (best, None);
    };
    let at = match passed.iter().position(|p| p.0 == choice.effect) {
        Some(i) => i,
        None => {
            let Some((t, f)) = failed.remove(&choice.effect) else {
                return (best, None);
            };
            rejected.retain(|&r| r != choice.effect);
            passed.push((choice.effect, t, f));
            passed.len() - 1
        }
    };
    let kept_trial = passed[at].1;
    let (w_label, k_label) = (
        trials[w_trial].label.clone(),
        trials[kept_trial].label.clone(),
    );
    let (w_reason, k_reason, note) = reasons(&choice, &k_label, &w_label, alpha);
    let kept = &mut trials[kept_trial];
    kept.reason = if kept.accepted {
        k_reason
    } else {
        format!("{k_reason}; its own: {}", kept.reason)
    };
    kept.accepted = true;
    notes.push(note);
    (at, Some((w_trial, w_reason)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::effects::parse_label;
    use crate::test_robots::ur5;

    #[test]
    fn harmonics_nest_and_other_rivals_do_not() {
        let t = ur5();
        let e = |l: &str| parse_label(l, &t).unwrap();
        let (one, both, two) = (
            e("gear_harmonic:j1"),
            e("gear_harmonic:j1:2"),
            e("gear_harmonic2:j1"),
        );
        assert!(is_nested(one.as_ref(), both.as_ref()));
        assert!(is_nested(two.as_ref(), both.as_ref()));
        assert!(!is_nested(both.as_ref(), one.as_ref()));
        assert!(!is_nested(one.as_ref(), two.as_ref()));
        assert!(!is_nested(one.as_ref(), one.as_ref()));
        let ratio = e("gear_ratio:j1");
        assert!(!is_nested(ratio.as_ref(), both.as_ref()));
        let other = e("gear_harmonic:j3:2");
        assert!(!is_nested(one.as_ref(), other.as_ref()));
    }

    fn outcome(ssr: f64, free: usize, m: usize) -> FitOutcome {
        FitOutcome {
            x: vec![0.0; free],
            free: (0..free).collect(),
            ssr,
            residual_count: m,
            iterations: 1,
            termination: crate::fit::Termination::Converged,
            rank: free,
            singular_values: vec![],
            condition_number: 1.0,
            sigma: None,
            covariance: None,
            std_errors: vec![],
        }
    }

    #[test]
    fn the_extra_sum_of_squares_test_is_an_f_test() {
        // 2 extra terms, 100 residuals, 10 and 12 parameters: F = (1/2) / (8.8/88) = 5.
        let t = ExtraTerms::of(&outcome(9.8, 10, 100), &outcome(8.8, 12, 100));
        assert!((t.f - 5.0).abs() < 1e-12, "{t:?}");
        assert_eq!(t.dof, (2.0, 88.0));
        assert!((t.p - stats::f_sf(5.0, 2.0, 88.0)).abs() < 1e-15);
        assert!(t.p > 0.005 && t.p < 0.02, "{}", t.p);
    }
}
