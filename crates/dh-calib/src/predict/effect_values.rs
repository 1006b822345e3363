//! The effects of a calibration with their values: from a report's selection, or from the
//! parameter values a calibrated sheet writes (SI units, names of [`crate::effects`]).

use super::EffectValues;
use crate::effects::{parse_label_in, EffectContext};
use crate::fit::CalibError;

/// The effects `report` selected, their labels parsed in `ctx`, at their estimates.
pub(super) fn report_effects(
    report: &crate::calibrate::Report,
    ctx: &EffectContext,
) -> Result<Vec<EffectValues>, CalibError> {
    let values: Vec<(String, f64)> = report
        .parameters
        .iter()
        .map(|p| (p.name.clone(), p.estimate))
        .collect();
    let mut effects = Vec::new();
    for label in &report.selected_effects {
        let effect = parse_label_in(label, ctx)?;
        let v = effect
            .parameter_names()
            .iter()
            .map(|n| values.iter().find(|(m, _)| m == n).map_or(0.0, |(_, v)| *v))
            .collect();
        effects.push((effect, v));
    }
    Ok(effects)
}

/// The effects of a written calibration: `values` are its effect parameters by name
/// (`gear_ratio:j2`, `gear_harmonic:j1.sin`, ...), grouped into the effects they belong to
/// (labels parsed in `ctx`), in the order first named.
///
/// # Errors
/// [`CalibError::BadOption`] for a name that belongs to no effect `ctx` can parse, or an
/// effect with some of its parameters missing; as [`parse_label_in`].
pub fn effects_from_parameters(
    values: &[(String, f64)],
    ctx: &EffectContext,
) -> Result<Vec<EffectValues>, CalibError> {
    let mut out: Vec<EffectValues> = Vec::new();
    let mut used = vec![false; values.len()];
    for (i, (name, _)) in values.iter().enumerate() {
        if used[i] {
            continue;
        }
        // The label is the name, or the name without its last `.part`s (the parameter).
        let mut label = name.as_str();
        let effect = loop {
            let parsed = parse_label_in(label, ctx);
            match parsed {
                Ok(e) if e.parameter_names().contains(name) => break e,
                Ok(_) | Err(_) => match label.rfind('.') {
                    Some(dot) => label = &label[..dot],
                    None => {
                        // The label's own error says what is wrong with the name.
                        parse_label_in(name, ctx)?;
                        return Err(CalibError::BadOption {
                            what: format!("effect parameter '{name}'"),
                            reason: "expected the name of an effect's parameter".into(),
                        });
                    }
                },
            }
        };
        let mut v = Vec::new();
        for p in effect.parameter_names() {
            let at =
                values
                    .iter()
                    .position(|(n, _)| *n == p)
                    .ok_or_else(|| CalibError::BadOption {
                        what: format!("effect '{}'", effect.label()),
                        reason: format!("expected a value of its parameter '{p}', found none"),
                    })?;
            used[at] = true;
            v.push(values[at].1);
        }
        out.push((effect, v));
    }
    Ok(out)
}
