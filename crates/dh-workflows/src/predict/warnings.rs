//! The warnings of a prediction: joint values outside their limits, backlash whose approach
//! direction is unknown, a drift predicted at the session's start (units: radians, metres).

use dh_core::JointKind;

use super::{Frame, JointInput};
use crate::calibrated::CalibratedModel;
use crate::input::display_name;
use crate::text::escape;

/// One warning per `backlash_direction:J` of `model` whose approach direction some rows of
/// `input` do not give: they are predicted midway between the gear's flanks, `±|b|` (half the
/// backlash) in the joint added to their uncertainty.
pub fn backlash_warnings(model: &CalibratedModel, input: &JointInput) -> Vec<String> {
    model
        .calibrated
        .backlash_effects()
        .into_iter()
        .filter_map(|(label, _, row, b)| {
            let unknown = (0..input.rows.len())
                .filter(|&i| input.contexts.get(i).map_or(0.0, |c| c.direction_of(row)) == 0.0)
                .count();
            (unknown > 0).then(|| {
                format!(
                    "'{}' (b = {b:.3e}): the approach direction of the joint is not known at {unknown} of {} row(s), predicted midway between the gear's flanks with ±{:.3e} (half the backlash) added to the uncertainty; give the rows in the order the robot moves through them with --sequence to predict each on its flank",
                    escape(&label),
                    input.rows.len(),
                    b.abs()
                )
            })
        })
        .collect()
}

/// The warning for a `drift` effect of `model` when `input`'s rows have no place in a sequence
/// ([`in_sequence`](super::in_sequence)) and are predicted in the device frame: they are predicted at the session's
/// start (`t = 0`, the device scale the calibration started with), which a pose measured later
/// in the session misses by up to `|c|` times its distance from the device. `None` otherwise
/// (the base link frame does not see the device's scale).
pub fn drift_warning(model: &CalibratedModel, input: &JointInput, frame: Frame) -> Option<String> {
    let c = model.calibrated.drift()?;
    (frame == Frame::Device && input.contexts.is_empty() && !input.rows.is_empty()).then(|| {
        format!(
            "'drift' (c = {c:.3e}): the rows' place in the session is not known, predicted at the session's start (t = 0): a pose measured later is off by up to {:.1} ppm of its distance from the device, not in the uncertainty; give the rows in the order they were measured with --sequence to follow the drift",
            c.abs() * 1e6
        )
    })
}

/// One warning per joint (table row) whose value leaves its limits at some rows of `input`:
/// the joint, its limits, how many rows and the first (its line in `joints_name` and value).
/// A prediction there extrapolates the calibration to where the robot cannot go, which is
/// allowed (a model can be asked anything) but rarely meant: a value in degrees read as
/// radians, a wrong column. Radians, or metres for a prismatic joint.
pub fn limit_warnings(
    model: &CalibratedModel,
    input: &JointInput,
    joints_name: &str,
) -> Vec<String> {
    let table = &model.loaded.table;
    // Per table row: rows outside, and the first (line, value).
    let mut outside: Vec<(usize, Option<(usize, f64)>)> = vec![(0, None); table.rows.len()];
    if table.rows.iter().all(|r| r.limits.is_none()) {
        return Vec::new();
    }
    for row in &input.rows {
        let values = model.joints.rows(&row.q);
        for ((r, v), o) in table.rows.iter().zip(&values).zip(outside.iter_mut()) {
            if r.limits
                .as_ref()
                .is_some_and(|l| *v < l.lower || *v > l.upper)
            {
                o.0 += 1;
                o.1.get_or_insert((row.line, *v));
            }
        }
    }
    table
        .rows
        .iter()
        .zip(&outside)
        .filter_map(|(r, (count, first))| {
            let (l, (line, value)) = (r.limits.as_ref()?, (*first)?);
            let unit = match r.kind {
                JointKind::Prismatic => "m",
                JointKind::Revolute => "rad",
            };
            Some(format!(
                "{}: joint '{}' is outside its limits [{}, {}] {unit} in {count} row(s), the first at line {line} ({value} {unit}): the prediction extrapolates the calibration to where the robot cannot go",
                display_name(joints_name),
                escape(&r.name),
                l.lower,
                l.upper,
            ))
        })
        .collect()
}
