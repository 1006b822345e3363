//! Rival candidates of the automatic diagnosis: effects that change the same quantity of the
//! same joint (`gear_ratio:J`, `gear_harmonic:J`, `gear_harmonic2:J`, `gear_harmonic:J:2`,
//! `coupling:J:K`, `compliance:J`, `backlash_direction:J` all turn `theta_J`; `scale` and
//! `drift` both scale the device's lengths) explain much of one another's signal, so the first
//! that passes the rule's tests is not necessarily the one in the data. When one passes, the
//! diagnosis refits its eligible rivals too and adds the best of those that pass: the lowest
//! BIC on the calibration data (the likelihood with a penalty per parameter, so a harmonic
//! with four terms must explain more than one with two), the lower held-out RMS breaking a tie.
//! The others are reported as rivals with the difference (`reason`).
//!
//! A sag along gravity (`gravity_sag:J`) and the effects driven by the gravity torques
//! (`compliance`, `lateral_compliance`, `backlash`, of any joint) are rivals too: they are
//! deflections under one load, and explain much of one another on a robot with link masses.
//! Among such rivals the lower held-out RMS decides (`best`): a sag is a stand-in for the
//! compliances as much as they are for it, and the BIC of the calibration data cannot tell
//! the physical one from the stand-in (on Boby's 36 tracker poses the sag of joint 2 had the
//! lower BIC by 4.3 and the higher held-out RMS than `lateral_compliance:joint_5`).

use crate::findings::Trial;
use crate::model::{Effect, EffectField};

/// Relative margin of the round's linearised held-out RMS within which a rival of one load (a
/// sag against a gravity-torque effect, or the reverse) is refitted beside the candidate that
/// passed: the held-out RMS decides between them (`best`), and the linearised figure of the
/// candidate table is the refit's to about 1e-5 relative on Boby's tracker set (these effects
/// are linear in their parameter). A rival more than 2 % worse cannot win, and its refit was
/// most of the work the sags added to the real sets (Boby: 9 refits, 22 % more instructions).
pub const LOAD_RIVAL_MARGIN: f64 = 0.02;

/// Whether rival `r` of the candidate `e` that passed can be left without a refit: they are
/// rivals of one load (a shift against a gravity-torque effect), decided by the held-out RMS,
/// and `r`'s linearised held-out RMS `val_r` is more than [`LOAD_RIVAL_MARGIN`] above `e`'s
/// `val_e` (metres, the round's candidate table). Never without held-out figures.
pub(crate) fn cannot_win(
    e: &dyn Effect,
    r: &dyn Effect,
    val_e: Option<f64>,
    val_r: Option<f64>,
) -> bool {
    let shift = |x: &dyn Effect| x.field() == EffectField::Shift;
    let load = |x: &dyn Effect| x.gravity_model().is_some() && !shift(x);
    let one_load = (shift(e) && load(r)) || (load(e) && shift(r));
    match (val_e, val_r) {
        (Some(a), Some(b)) if one_load => b > a * (1.0 + LOAD_RIVAL_MARGIN),
        _ => false,
    }
}

/// The start of a rival's reason in its trial and candidate row.
pub const RIVAL_OF: &str = "rival of ";

/// BIC differences within this are a tie, decided by the held-out RMS. BIC is on the scale of
/// `−2 ln likelihood`, where a difference below 2 is evidence "not worth more than a bare
/// mention" (R. E. Kass, A. E. Raftery, "Bayes factors", JASA 90(430), 1995, §3.2).
pub const BIC_TIE: f64 = 2.0;

/// Whether `a` and `b` change the same quantity of the same joint (the device scale counts as
/// one quantity).
pub(crate) fn are_rivals(a: &dyn Effect, b: &dyn Effect) -> bool {
    let shift = |e: &dyn Effect| e.field() == EffectField::Shift;
    let load = |e: &dyn Effect| e.gravity_model().is_some();
    (a.joint() == b.joint() && a.field() == b.field())
        || (shift(a) && load(b))
        || (load(a) && shift(b))
}

/// Whether the labels of `trials` are rivals of one load with a sag among them (see the module
/// docs): the held-out RMS decides between them.
fn one_load(trials: &[&Trial]) -> bool {
    let kind = |t: &Trial| t.label.split(':').next().unwrap_or("").to_string();
    trials.iter().any(|t| kind(t) == "gravity_sag")
        && trials.iter().all(|t| {
            matches!(
                kind(t).as_str(),
                "gravity_sag" | "compliance" | "lateral_compliance" | "backlash"
            )
        })
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
    // Rivals of one load: every one that passed is close, the held-out RMS decides.
    let close: Vec<usize> = if one_load(trials) && trials.iter().all(|t| t.val_rms.is_some()) {
        (0..trials.len()).collect()
    } else {
        close
    };
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
    } else if -diff > BIC_TIE {
        format!(
            "BIC better by {:.1}, but rivals of one load are decided by the held-out RMS",
            -diff
        )
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

    /// Boby's round: the sag had the lower BIC by 4.3, the lateral compliance the lower
    /// held-out RMS; rivals of one load are decided held out, and the reason says so.
    #[test]
    fn rivals_of_one_load_are_decided_by_the_held_out_rms() {
        let sag = trial("gravity_sag:joint_2", -104.3, Some(1.656e-4));
        let lateral = trial("lateral_compliance:joint_5", -100.0, Some(1.640e-4));
        assert_eq!(best(&[&sag, &lateral]), 1);
        assert_eq!(best(&[&lateral, &sag]), 0);
        assert!(reason(&lateral, &sag)
            .contains("BIC better by 4.3, but rivals of one load are decided by the held-out RMS"));
        // Without a sag among them, compliances keep the BIC rule.
        let c2 = trial("compliance:joint_2", -104.3, Some(1.656e-4));
        assert_eq!(best(&[&c2, &lateral]), 0);
        // The effects: a sag is a rival of a compliance of any joint, and of another sag.
        let t = crate::test_robots::ur5();
        let inertials = crate::gravity::Inertials {
            links: vec![(
                "j3".into(),
                crate::gravity::Inertial {
                    mass: 5.0,
                    com: nalgebra::Vector3::new(0.2, 0.0, 0.0),
                },
            )],
            payloads: vec![],
        };
        let g = crate::gravity::GravityModel::serial(
            &t,
            &inertials,
            crate::gravity::GravityModel::default_gravity(),
        )
        .unwrap();
        let ctx = crate::effects::EffectContext {
            gravity: Some(std::sync::Arc::new(g)),
            ..crate::effects::EffectContext::serial(&t)
        };
        let e = |l: &str| crate::effects::parse_label_in(l, &ctx).unwrap();
        assert!(are_rivals(
            e("gravity_sag:j2").as_ref(),
            e("compliance:j3").as_ref()
        ));
        assert!(are_rivals(
            e("lateral_compliance:j2").as_ref(),
            e("gravity_sag:j3").as_ref()
        ));
        assert!(are_rivals(
            e("gravity_sag:j2").as_ref(),
            e("gravity_sag:j3").as_ref()
        ));
        assert!(!are_rivals(
            e("compliance:j2").as_ref(),
            e("compliance:j3").as_ref()
        ));
        assert!(!are_rivals(
            e("gravity_sag:j2").as_ref(),
            e("gear_ratio:j2").as_ref()
        ));
        // A rival of one load more than LOAD_RIVAL_MARGIN worse in the round's linearised
        // held-out RMS is not refitted; within it, or without held-out figures, or outside one
        // load (two compliances of a joint decide by BIC), it is.
        let (sag, c3) = (e("gravity_sag:j2"), e("compliance:j3"));
        assert!(cannot_win(
            c3.as_ref(),
            sag.as_ref(),
            Some(1.0e-4),
            Some(1.03e-4)
        ));
        assert!(cannot_win(
            sag.as_ref(),
            c3.as_ref(),
            Some(1.0e-4),
            Some(1.03e-4)
        ));
        assert!(!cannot_win(
            c3.as_ref(),
            sag.as_ref(),
            Some(1.0e-4),
            Some(1.01e-4)
        ));
        assert!(!cannot_win(c3.as_ref(), sag.as_ref(), None, Some(2.0e-4)));
        let b3 = e("backlash:j3");
        assert!(!cannot_win(
            c3.as_ref(),
            b3.as_ref(),
            Some(1.0e-4),
            Some(2.0e-4)
        ));
    }
}
