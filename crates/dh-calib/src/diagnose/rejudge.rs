//! The outliers judged again (module docs of [`diagnose_tree`]): the diagnosis's entry point
//! for trees, which reruns the selection when a judgement against the effects selected gives
//! points back, and the judgements themselves ([`rejudge()`]) with the notes on the points given
//! back.

use crate::calibrate::{confirmed_at, Confirmation};
use crate::outliers::{GivenBack, OutlierReport};

use super::selection::diagnose_judged;
use super::*;

/// Calibrates `tree` against `data` as [`crate::calibrate::calibrate_tree`] does, then
/// diagnoses and adds the effects the geometric model lacks (see the module docs). The report
/// has the steps `nominal`, `geometric` and one `+<label>` per effect added, the candidate
/// table of the first round, the selected effects and the [`Diagnosis`], whose notes (and the
/// residual test's summary) are also appended to the report's notes.
/// `options.effects` is ignored: [`DiagnoseOptions::effects`] says which effects.
///
/// The outlier screen first judges the points against the geometric fit, before any effect is
/// known; a pose that only an unmodelled effect puts far off (the most gravity-loaded poses
/// before a compliance is added) is then left out, and with it the evidence for that effect.
/// So when points were left out (calibration or validation), they are judged again against
/// the geometry and the effects selected so far once the selection has added 1, 2, 4, 8...
/// effects, and at its end (a second judgement only gives points back: the tighter scale of a
/// better model never takes more); as soon as it gives some back, the selection stops and
/// runs again from the start with them (in the fit, or in the held-out figures), judged
/// against those effects (at most [`MAX_REJUDGE`] times), and a note says so; the points given
/// back are then judged against the final model too, in a second note, and the report's
/// [`OutlierReport::given_back`] gives each one's figures against the model that left it out
/// and against the final model.
/// Declared labels are judged with from the start.
///
/// A left-out point can be the very evidence for an effect (every pose a direction backlash
/// reverses), so the candidates are judged with the left-out points too: a candidate's
/// held-out test (with a validation split) counts the left-out validation points that its fit
/// or the fit before it explains, for both fits; and at the end of a run, the calibration
/// points still left out are judged against each remaining candidate (linearised, the kept
/// points agreeing, then exactly): when one gives back points of two poses or more, the
/// selection runs again with them, judged against it.
///
/// # Errors
/// Those of [`crate::calibrate::calibrate_tree`]; [`CalibError::BadOption`] /
/// [`CalibError::MissingJoint`] for a bad label, bad inertials or a bad `alpha`.
pub fn diagnose_tree(
    tree: &DhTree,
    data: &Measurements,
    options: &CalibrationOptions,
    diag: &DiagnoseOptions,
) -> Result<Report, CalibError> {
    let mut judged: Option<Rejudged> = None;
    let mut first_left = 0;
    let mut passes = 0;
    loop {
        match diagnose_judged(
            tree,
            data,
            options,
            diag,
            judged.take(),
            passes < MAX_REJUDGE,
        )? {
            Judgement::Again(again) => {
                if passes == 0 {
                    first_left = again.1.left_out().len();
                }
                judged = Some(*again);
                passes += 1;
            }
            Judgement::Final(mut report, confirmed, effects) => {
                let count = report.outliers.as_ref().map_or(0, |s| s.left_out().len());
                // The judgement against the final model, when one was made at the end of the
                // run, carries the figures of the points given back against that model.
                let final_judgement = match &confirmed {
                    Some((_, again)) => Some(again.clone()),
                    None if passes > 0 => given_back_check(tree, data, options, &report, &effects)?
                        .as_ref()
                        .map(Confirmation::of),
                    None => None,
                };
                let judged_with = report
                    .outliers
                    .as_ref()
                    .map(|s| s.effects.clone())
                    .unwrap_or_default();
                if let (Some(scan), Some(check)) = (report.outliers.as_mut(), &final_judgement) {
                    scan.given_back = check.given_back.clone();
                }
                if passes > 0 {
                    report.notes.push(format!(
                        "outliers judged again against the geometry and {}: {count} \
                         point(s) left out instead of the {first_left} of the geometric fit; \
                         the selection ran again with the points given back ({passes} time(s))",
                        judged_with.join(", ")
                    ));
                    if let Some(check) = final_judgement
                        .as_ref()
                        .filter(|_| judged_with != report.selected_effects)
                    {
                        report.notes.push(given_back_note(
                            &check.given_back,
                            effects.len(),
                            check.threshold,
                        ));
                    }
                } else if let Some((with, _)) = confirmed {
                    report.notes.push(format!(
                        "the {count} point(s) left out are outliers of the final model too \
                         (judged again against the geometry and {with})"
                    ));
                }
                return Ok(*report);
            }
        }
    }
}

/// The points given back judged against the final model when no judgement was made against
/// it at the end of the run (its screen judged against fewer effects and gave back all it
/// left out, or the run could not judge again): that judgement's model was looser, so a point
/// it gave back may still be far off the final one. Nothing is left out by it (a second
/// judgement only gives points back): it gives the figures of the points given back.
fn given_back_check(
    tree: &DhTree,
    data: &Measurements,
    options: &CalibrationOptions,
    report: &Report,
    effects: &[Arc<dyn Effect>],
) -> Result<Option<OutlierReport>, CalibError> {
    let Some(scan) = report
        .outliers
        .as_ref()
        .filter(|s| !s.given_back.is_empty() && s.effects != report.selected_effects)
    else {
        return Ok(None);
    };
    let only_given_back = OutlierReport {
        outliers: Vec::new(),
        ..scan.clone()
    };
    crate::calibrate::screen_from(tree, data, options, None, effects, Some(&only_given_back))
        .map(Some)
}

/// The note on the points given back, judged against the final model of `count` effects
/// (calibration threshold `threshold`): none beyond its threshold, or those that are (they stay
/// in: a second judgement only gives points back).
fn given_back_note(given_back: &[GivenBack], count: usize, threshold: f64) -> String {
    let beyond: Vec<String> = given_back
        .iter()
        .filter(|g| g.after.sigmas > g.after.threshold)
        .map(|g| format!("line {} ({:.1} sigma)", g.line, g.after.sigmas))
        .collect();
    let n = given_back.len();
    let model = format!(
        "the final model (the geometry and {count} effect(s), threshold {threshold:.1} sigma)"
    );
    if beyond.is_empty() {
        format!("none of the {n} point(s) given back is an outlier of {model}")
    } else {
        format!(
            "{} of the {n} point(s) given back are beyond the threshold of {model}: {}; they \
             stay in the fit",
            beyond.len(),
            beyond.join(", ")
        )
    }
}

/// Most times [`diagnose_tree`] judges the outliers again and reruns the selection.
pub const MAX_REJUDGE: usize = 3;

/// The effects a second outlier judgement used, the judgement before it (whose left-out
/// samples it could flag), and its findings (the screen of the next run: the same judgement,
/// made once).
pub(super) type Rejudged = (Vec<Arc<dyn Effect>>, OutlierReport, OutlierReport);

/// The fit a judgement again may read instead of fitting (see [`confirmed_at`]): the run's
/// session, the point of its latest fit and the number of its free parameters.
pub(super) type FitAt<'a, 's> = (&'a crate::calibrate::Session<'s>, &'a [f64], usize);

/// What one selection run leads to: its report (with the effects the points left out were
/// judged against again and confirmed as outliers, and that judgement, if so, and the effects
/// it selected), or another run with the effects selected so far, giving back the points left
/// out that are not outliers of them.
pub(super) enum Judgement {
    Final(
        Box<Report>,
        Option<(String, Confirmation)>,
        Vec<Arc<dyn Effect>>,
    ),
    Again(Box<Rejudged>),
}

/// What [`rejudge()`] found.
pub(super) enum Rejudgement {
    /// Nothing to judge again.
    Nothing,
    /// The points left out are outliers of the effects (their labels) too: that judgement's
    /// figures.
    Confirmed(String, Confirmation),
    /// Not all: the judgement before, and the new one (boxed: two reports beside a label).
    Changed(Box<(OutlierReport, OutlierReport)>),
}

/// Whether the selection must run again (see [`diagnose_tree`]): the points `scan` left out
/// (calibration and validation), judged against the geometry and the `effects` selected,
/// unless none were left out, no effect was selected or the screen already judged with them.
/// When they are all outliers of the run's fit `at` of those effects (the points `scan` kept),
/// that is the judgement, made without a fit ([`confirmed_at`]); else the screen judges them
/// again, fitting from all points in.
pub(super) fn rejudge(
    tree: &DhTree,
    data: &Measurements,
    options: &CalibrationOptions,
    scan: Option<&OutlierReport>,
    effects: &[Arc<dyn Effect>],
    at: FitAt<'_, '_>,
) -> Result<Rejudgement, CalibError> {
    let labels: Vec<String> = effects
        .iter()
        .map(|e| crate::effects::label_of(e.as_ref()))
        .collect();
    let Some(scan) = scan.filter(|s| !s.left_out().is_empty()) else {
        return Ok(Rejudgement::Nothing);
    };
    if effects.is_empty() || scan.effects == labels {
        return Ok(Rejudgement::Nothing);
    }
    if let Some(c) = confirmed_at(tree, data, options, at, effects, scan)? {
        return Ok(Rejudgement::Confirmed(labels.join(", "), c));
    }
    let again = crate::calibrate::screen_from(tree, data, options, None, effects, Some(scan))?;
    if again.left_out() == scan.left_out() {
        return Ok(Rejudgement::Confirmed(
            labels.join(", "),
            Confirmation::of(&again),
        ));
    }
    Ok(Rejudgement::Changed(Box::new((scan.clone(), again))))
}
