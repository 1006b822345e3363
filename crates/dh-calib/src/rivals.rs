//! Rival candidates of the automatic diagnosis: effects that change the same quantity of the
//! same joint (`gear_ratio:J`, `gear_harmonic:J`, `gear_harmonic2:J`, `gear_harmonic:J:2`,
//! `coupling:J:K`, `compliance:J`, `backlash_direction:J` all turn `theta_J`; `scale` and
//! `drift` both scale the device's lengths) explain much of one another's signal, so the first
//! that passes the rule's tests is not necessarily the one in the data. When one passes, the
//! diagnosis refits its eligible rivals too and adds the best of those that pass: the lowest
//! BIC on the calibration data (the likelihood with a penalty per parameter, so a harmonic
//! with four terms must explain more than one with two), the lower held-out RMS breaking a tie.
//! The others are reported as rivals with the difference (`reason`).

use crate::findings::Trial;
use crate::model::Effect;

/// The start of a rival's reason in its trial and candidate row.
pub const RIVAL_OF: &str = "rival of ";

/// BIC differences within this are a tie, decided by the held-out RMS. BIC is on the scale of
/// `−2 ln likelihood`, where a difference below 2 is evidence "not worth more than a bare
/// mention" (R. E. Kass, A. E. Raftery, "Bayes factors", JASA 90(430), 1995, §3.2).
pub const BIC_TIE: f64 = 2.0;

/// Whether `a` and `b` change the same quantity of the same joint (the device scale counts as
/// one quantity).
pub(crate) fn are_rivals(a: &dyn Effect, b: &dyn Effect) -> bool {
    a.joint() == b.joint() && a.field() == b.field()
}

/// Relative difference within which two figures of trials are the same number: exact aliases
/// (two effects that span the same columns with the ones already in, such as couplings of a
/// passive joint with either of its drivers once its gear ratio is in) fit identically, and
/// their figures differ by rounding alone.
const SAME: f64 = 1e-6;

/// The index of the best of `trials` (all passed): lowest BIC after the refit, the lower
/// held-out RMS among those within [`BIC_TIE`] of it (when every one has one); among trials
/// with the same figures (exact aliases, [`SAME`]) the first label in byte order, so that
/// rounding never decides. `0` for an empty list.
pub(crate) fn best(trials: &[&Trial]) -> usize {
    let first = best_by_figures(trials);
    let Some(w) = trials.get(first) else {
        return first;
    };
    let same = |a: f64, b: f64| (a - b).abs() <= SAME * a.abs().max(b.abs()).max(1e-300);
    (0..trials.len())
        .filter(|&i| {
            let t = trials[i];
            same(t.bic.1, w.bic.1)
                && match (t.val_rms, w.val_rms) {
                    (Some(a), Some(b)) => same(a, b),
                    (None, None) => true,
                    _ => false,
                }
        })
        .min_by(|&i, &j| trials[i].label.cmp(&trials[j].label))
        .unwrap_or(first)
}

/// [`best`] before the tie between exact aliases is broken.
fn best_by_figures(trials: &[&Trial]) -> usize {
    let lowest = trials
        .iter()
        .map(|t| t.bic.1)
        .filter(|b| b.is_finite())
        .fold(f64::INFINITY, f64::min);
    let close: Vec<usize> = (0..trials.len())
        .filter(|&i| trials[i].bic.1 <= lowest + BIC_TIE)
        .collect();
    let by_bic = |i: &usize, j: &usize| trials[*i].bic.1.total_cmp(&trials[*j].bic.1);
    if close.iter().all(|&i| trials[i].val_rms.is_some()) {
        close
            .iter()
            .copied()
            .min_by(|i, j| {
                let (a, b) = (trials[*i].val_rms, trials[*j].val_rms);
                a.unwrap_or(f64::INFINITY)
                    .total_cmp(&b.unwrap_or(f64::INFINITY))
                    .then_with(|| by_bic(i, j))
            })
            .unwrap_or(0)
    } else {
        close.iter().copied().min_by(by_bic).unwrap_or(0)
    }
}

/// Why `other` (which passed) was not added in favour of `winner`: `rival of X: BIC worse by
/// N (held-out RMS a mm against b mm)`.
pub(crate) fn reason(winner: &Trial, other: &Trial) -> String {
    let held = match (other.val_rms, winner.val_rms) {
        (Some(a), Some(b)) => format!(
            " (held-out RMS {:.4} mm against {:.4} mm)",
            a * 1e3,
            b * 1e3
        ),
        _ => String::new(),
    };
    let diff = other.bic.1 - winner.bic.1;
    let bic = if diff >= 0.0 {
        format!("BIC worse by {diff:.1}")
    } else {
        format!("BIC better by {:.1} but within {BIC_TIE} of it", -diff)
    };
    format!("{RIVAL_OF}{}: {bic}{held}", winner.label)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn trial(label: &str, bic: f64, val: Option<f64>) -> Trial {
        Trial {
            label: label.into(),
            rms: 0.0,
            val_rms: val,
            f: 0.0,
            f_p: 0.0,
            f_threshold: 0.0,
            bic: (0.0, bic),
            held_out: None,
            accepted: true,
            reason: String::new(),
        }
    }

    #[test]
    fn the_lowest_bic_wins_and_a_tie_goes_to_the_held_out_rms() {
        let a = trial("gear_ratio:j1", -100.0, Some(2e-5));
        let b = trial("gear_harmonic:j1", -140.0, Some(3e-5));
        assert_eq!(best(&[&a, &b]), 1);
        let r = reason(&b, &a);
        assert!(
            r.starts_with("rival of gear_harmonic:j1: BIC worse by 40.0"),
            "{r}"
        );
        assert!(r.contains("0.0200 mm against 0.0300 mm"), "{r}");
        let c = trial("gear_harmonic2:j1", -139.0, Some(1e-5));
        assert_eq!(best(&[&a, &b, &c]), 2);
        assert!(reason(&c, &b).contains("BIC better by 1.0 but within"));
        // Without held-out RMS, BIC alone.
        let d = trial("x", -139.0, None);
        assert_eq!(best(&[&b, &d]), 0);
        assert_eq!(best(&[]), 0);
        // Exact aliases (the same figures to rounding): the first label, whichever order or
        // rounding.
        let e = trial(
            "coupling:j4:j3",
            -140.0 * (1.0 + 1e-12),
            Some(3e-5 * (1.0 - 1e-11)),
        );
        let f = trial("coupling:j4:j2", -140.0, Some(3e-5));
        assert_eq!(best(&[&e, &f]), 1);
        assert_eq!(best(&[&f, &e]), 0);
    }
}
