//! Planting effects in simulated data: what a true robot with effects (a gear ratio, a
//! compliance, a harmonic, a drift, …) measures, given what [`super::simulate`] drew for the
//! same robot without them.
//!
//! # Frames and units
//! Positions are in the device frame (metres), as [`crate::data::Sample::point`] holds them;
//! orientations are the rotation of the target frame in the device frame
//! ([`crate::data::Orientation`]), the same quantity the fit compares in
//! [`crate::model::Observation::TargetPose`] (`R_model = R_device_tip · R_tip_target`). Each
//! sample is moved by exactly what the effects change in the noise-free model at its joint
//! values and place in the sequence ([`crate::effects_order`]):
//!
//! ```text
//! p'  = p + (p_with − p_without)                 (metres, device frame)
//! R'  = R · R_withoutᵀ · R_with                  (rotation of the target in the device frame)
//! ```
//!
//! The simulator's position noise is additive and its orientation noise a left factor
//! `exp(n) · R_without`, so both noises are kept unchanged: `R' = exp(n) · R_with`. The
//! target frames in the tip frame are not changed (the effects move joints and the device
//! scale, not the targets on the tool), so [`Truth::target_rotations`] stays the truth.

use std::sync::Arc;

use dh_core::DhTable;

use super::Truth;
use crate::data::Measurements;
use crate::fit::CalibError;
use crate::model::{Effect, Model, ModelOptions};

/// Seconds between two simulated poses when a planted effect reads time
/// ([`Effect::uses_time`]: `thermal_growth`) and the samples carry none: the samples get a
/// `time`, pose `k` (of the sequence, repeats and targets sharing it) at `k · 30 s`, so 240
/// poses take two hours, a warm-up's length.
pub const POSE_INTERVAL: f64 = 30.0;

/// One effect of the true robot and its parameter values (in the effect's own units, one per
/// name of [`Effect::parameter_names`]).
pub type PlantedEffect = (Arc<dyn Effect>, Vec<f64>);

/// Adds `effects` to the simulated samples of `data` (see the module docs for the frames):
/// `data` and `truth` come from [`super::simulate`] of `nominal` with the parametrisation
/// `options`, without effects. Returns every effect parameter planted, by name, with its
/// value, in the order given (for the truth file).
///
/// The true model is rebuilt from `truth`: its device frame (each session's own), its target
/// positions and, for data with orientations, its target rotations; its parameter errors are
/// [`Truth::errors`] by name. An effect of time gives samples without times their times
/// ([`POSE_INTERVAL`] apart).
///
/// # Errors
/// [`CalibError::BadOption`] when an effect is given a number of values other than its
/// parameter count or a value that is not finite; any error of [`Model::new`] or
/// [`Model::add_effect`] (an effect the model refuses).
pub fn plant_effects(
    nominal: &DhTable,
    data: &mut Measurements,
    truth: &Truth,
    effects: &[PlantedEffect],
    options: &ModelOptions,
) -> Result<Vec<(String, f64)>, CalibError> {
    if effects.is_empty() {
        return Ok(Vec::new());
    }
    let mut model = Model::new(nominal, &data.targets, options)?;
    model.set_device(&truth.device);
    for (k, (_, t)) in truth.targets.iter().enumerate() {
        model.set_target(k, *t);
    }
    // The orientation parameters come before the effects', as in the simulator's model
    // (their values are looked up by name, so only their presence matters).
    let six_dof = data.samples.iter().any(|s| s.orientation.is_some());
    if six_dof {
        for (k, r) in truth.target_rotations.iter().enumerate() {
            model.add_target_orientation(k);
            model.set_target_rotation(k, r);
        }
    }
    let mut ranges = Vec::with_capacity(effects.len());
    for (e, v) in effects {
        let r = model.add_effect(e.clone())?;
        let names = e.parameter_names().join(", ");
        if r.len() != v.len() {
            return Err(CalibError::BadOption {
                what: format!("effect {names}"),
                reason: format!("expected {} value(s), found {}", r.len(), v.len()),
            });
        }
        if let Some(bad) = v.iter().find(|v| !v.is_finite()) {
            return Err(CalibError::BadOption {
                what: format!("effect {names}"),
                reason: format!("expected finite values, found {bad}"),
            });
        }
        ranges.push(r);
    }
    let mut x = vec![0.0; model.parameter_count()];
    for (name, v) in &truth.errors {
        if let Some(i) = model.index_of(name) {
            x[i] = *v;
        }
    }
    let plain = x.clone();
    let mut applied = Vec::new();
    for ((e, v), r) in effects.iter().zip(ranges) {
        for ((i, val), name) in r.zip(v).zip(e.parameter_names()) {
            x[i] = *val;
            applied.push((name, *val));
        }
    }
    // An effect of time needs times: poses `POSE_INTERVAL` apart, as the file will say.
    if effects.iter().any(|(e, _)| e.uses_time()) && !crate::effects_order::has_times(data) {
        let (pose, _) = crate::effects_order::sequence_orders(
            data.samples.iter().map(|s| (&*s.q, s.config.as_deref())),
        );
        for (s, k) in data.samples.iter_mut().zip(pose) {
            s.time = Some(k as f64 * POSE_INTERVAL);
        }
    }
    // The effects of the sample order see each sample's place in the file's sequence.
    let contexts = crate::effects_order::measurement_contexts(data);
    for (s, c) in data.samples.iter_mut().zip(&contexts) {
        // Each session's own device frame (the differences are in that frame).
        model.set_device(truth.sessions.get(s.session).unwrap_or(&truth.device));
        match &mut s.orientation {
            None => {
                s.point += model.point_in(&x, &s.q, c, s.target)
                    - model.point_in(&plain, &s.q, c, s.target);
            }
            Some(o) => {
                let with = model.target_pose_in(&x, &s.q, c, s.target, 0);
                let without = model.target_pose_in(&plain, &s.q, c, s.target, 0);
                s.point += with.translation.vector - without.translation.vector;
                o.rotation = o.rotation * without.rotation.inverse() * with.rotation;
            }
        }
    }
    Ok(applied)
}
