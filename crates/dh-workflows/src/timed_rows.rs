//! The rows of a prediction or compensation at their times: what an effect of time
//! (`thermal_growth`, `dh_calib::effects_thermal`) reads from a joint file's `time` column
//! (seconds), or from the rows' order.

use anyhow::Result;
use dh_calib::effects_thermal::TimeUnit;
use dh_calib::model::SampleContext;

use crate::calibrated::CalibratedModel;
use crate::error::hinted;
use crate::predict::JointInput;

/// The labels of `model`'s effects of time (`thermal_growth`, see
/// `dh_calib::effects_thermal`).
fn time_effects(model: &CalibratedModel) -> Vec<String> {
    model
        .calibrated
        .model()
        .effects()
        .iter()
        .filter(|(e, _)| e.uses_time())
        .map(|(e, _)| e.label())
        .collect()
}

/// The context of each row of `input` for `model`'s effects: its place in the sequence
/// ([`crate::predict::in_sequence`], when given) and, when `model` has an effect of time, its time since the
/// first row (seconds, from the rows' `time` column), as `calibrate` reads a measurement
/// file's (`t = 0` at the first: the robot as at the calibration's first sample). Without a
/// `time` column the rows' order ([`crate::predict::in_sequence`]) is `t`, in `[0, 1]`: right for a
/// calibration whose data had no times (its `tau` is then a fraction of the session).
///
/// The model's [`CalibratedModel::time_unit`] says which the calibration had: rows given in
/// the other unit are refused. A model that does not say (a sheet written before it was kept)
/// takes the rows as given: a `time` column as seconds, else the pose order of `--sequence`.
///
/// # Errors
/// An effect of time with neither a `time` column nor the rows in sequence (naming the
/// effect, the missing column and the file); a row without a time where others have one; a
/// model fitted on seconds given rows without times, or fitted on the pose order given rows
/// with times (naming both files and the column).
pub fn timed_contexts<'a>(
    model: &CalibratedModel,
    input: &'a JointInput,
) -> Result<std::borrow::Cow<'a, [SampleContext]>> {
    use std::borrow::Cow;
    let effects = time_effects(model);
    if effects.is_empty() {
        return Ok(Cow::Borrowed(&input.contexts));
    }
    let effects = effects.join(", ");
    let origin = &model.loaded.origin;
    let Some(first) = input.rows.iter().find_map(|r| r.time) else {
        if model.time_unit == Some(TimeUnit::Seconds) {
            return Err(hinted(
                format!(
                    "{}: the calibration's {effects} needs each row's time: expected a 'time' column (seconds), found none ({origin} was fitted on times in seconds, `time_unit: s`)",
                    input.name
                ),
                format!(
                    "add each row's time in seconds, the first row at the robot's start (as the calibration's first sample){}",
                    if input.contexts.is_empty() {
                        ""
                    } else {
                        "; the rows' order given with --sequence is no time in seconds"
                    }
                ),
            ));
        }
        if !input.contexts.is_empty() {
            return Ok(Cow::Borrowed(&input.contexts));
        }
        return Err(hinted(
            format!(
                "{}: the calibration's {effects} needs each row's time: expected a 'time' column (seconds), found none",
                input.name
            ),
            "add each row's time in seconds (the first row at the robot's start, as the calibration's first sample), or, for a calibration whose data had no times, give the rows in the order of its session with --sequence",
        ));
    };
    if model.time_unit == Some(TimeUnit::PoseOrder) {
        return Err(hinted(
            format!(
                "{}: column 'time': the calibration's {effects} was fitted on the pose order in [0, 1] ({origin}: `time_unit: pose_order`, its data had no times): expected no 'time' column, found one (seconds)",
                input.name
            ),
            "drop the 'time' column and give the rows in the order of the calibration's session with --sequence, or calibrate again on data with a 'time' column",
        ));
    }
    let mut contexts = if input.contexts.is_empty() {
        vec![SampleContext::default(); input.rows.len()]
    } else {
        input.contexts.clone()
    };
    for (c, r) in contexts.iter_mut().zip(&input.rows) {
        let t = r.time.ok_or_else(|| {
            anyhow::anyhow!(
                "{}: line {}, column 'time': expected the row's time (seconds) for {effects}, found an empty cell",
                input.name,
                r.line
            )
        })?;
        c.time = Some(t - first);
    }
    Ok(Cow::Owned(contexts))
}
