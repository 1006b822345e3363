//! Non-geometric effects: the [`Effect`] trait (a change of one row's `theta`, `d`, `alpha`
//! or tilt, or of the device's length scale) and the simplest effect, a gear ratio error.
//!
//! Units: the change is radians (angles) or metres (offsets); the device scale is
//! dimensionless.

use std::fmt;

use dh_core::DhTable;

use super::SampleContext;
use crate::fit::CalibError;

/// Which quantity an [`Effect`] changes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum EffectField {
    /// The row's joint angle (radians).
    Theta,
    /// The row's link offset (metres).
    D,
    /// The row's link twist (radians): a rotation about the `x` axis that carries `alpha`.
    Alpha,
    /// The row's Hayati-Mirmirani tilt about `y` (radians), where the row has one (see
    /// [`Model::tilt_rows`](super::Model::tilt_rows)).
    Beta,
    /// The measuring device's length scale: modelled positions are multiplied by `1 + delta`.
    /// The effect's [`Effect::joint`] is ignored.
    Scale,
    /// The robot's length scale: every position in the robot's base link frame (each `a` and
    /// `d` of the table, the base and tool offsets, the targets' offsets, prismatic travel
    /// included) is multiplied by `1 + delta`, about the base link's origin; the device frame
    /// is not scaled. The effect's [`Effect::joint`] is ignored.
    Growth,
    /// A translation of the robot in its base link frame (metres): the tip and every target
    /// move by `delta` along [`Effect::shift_direction`], after the chain (no joint turns
    /// it), before the device frame. A sag under gravity ([`crate::effects::GravitySag`]).
    Shift,
}

/// A non-geometric error source: a change of one row's `theta`, `d`, `alpha` or tilt, or of the
/// device's scale, that depends on the joint values and on the effect's own parameters (gear
/// ratio errors, joint compliance, coupling between joints). Added to a model with
/// [`Model::add_effect`](super::Model::add_effect); its parameters become extra Jacobian columns.
pub trait Effect: fmt::Debug + Send + Sync {
    /// Full names of the effect's parameters (e.g. `gear_ratio:j2`).
    fn parameter_names(&self) -> Vec<String>;
    /// The joint (row name) whose quantity the effect changes.
    fn joint(&self) -> &str;
    /// Which quantity.
    fn field(&self) -> EffectField;
    /// The unit of each parameter, for reports (e.g. `rad/(N m)`); empty when not given.
    fn units(&self) -> Vec<String> {
        Vec::new()
    }
    /// The effect's label (see [`crate::effects`]); by default its first parameter's name.
    fn label(&self) -> String {
        self.parameter_names()
            .into_iter()
            .next()
            .unwrap_or_default()
    }
    /// The change (radians or metres) at joint values `q` (one per row, in row order). It must
    /// be zero when every parameter is zero: the model skips such effects.
    fn delta(&self, q: &[f64], params: &[f64]) -> f64;
    /// `∂delta/∂params` at `q` into `out` (one per parameter).
    fn gradient(&self, q: &[f64], params: &[f64], out: &mut [f64]);
    /// The change at joint values `q` in the sample's place in the measurement sequence
    /// `context` ([`SampleContext`]). The model calls this one; by default it is
    /// [`Effect::delta`] (an effect of the joint values only ignores the context). An effect
    /// that depends on the sequence (direction of the last motion, time) overrides it and
    /// makes `delta` its value in the neutral context ([`SampleContext::default`]).
    fn delta_in(&self, q: &[f64], context: &SampleContext, params: &[f64]) -> f64 {
        let _ = context;
        self.delta(q, params)
    }
    /// Whether the effect reads the sample's [`SampleContext`] (false by default): such an
    /// effect needs data in a sequence and is neutral elsewhere.
    fn uses_sequence(&self) -> bool {
        false
    }
    /// Whether the effect reads the samples' time ([`SampleContext::time`], the pose order
    /// without one; false by default): such an effect is evaluated at a given time, or at the
    /// sequence's start ([`crate::effects_thermal`]).
    fn uses_time(&self) -> bool {
        false
    }
    /// `∂delta_in/∂params` (see [`Effect::delta_in`]); by default [`Effect::gradient`].
    fn gradient_in(&self, q: &[f64], context: &SampleContext, params: &[f64], out: &mut [f64]) {
        let _ = context;
        self.gradient(q, params, out)
    }
    /// Column scales: the tip motion (metres) that a unit change of each parameter causes,
    /// roughly, in a robot of characteristic length `length`.
    fn scales(&self, length: f64) -> Vec<f64>;
    /// The gravity model whose torques drive the effect (compliance, backlash under load);
    /// `None` by default. A calibrated model file must carry it for the effect to be evaluated
    /// again from joint values alone.
    fn gravity_model(&self) -> Option<&std::sync::Arc<crate::gravity::GravityModel>> {
        None
    }
    /// For an effect whose later parameters act only through its first (an amplitude times a
    /// shape with a time constant, so that at amplitude 0 the shape is not identifiable):
    /// the values of the second parameter to try, in its own unit, before a fit starts from
    /// amplitude 0 ([`crate::calibrate`] fits the amplitude at each, linearly, and starts the
    /// joint fit from the best). `span` is the sequence's extent in the unit the effect reads
    /// (seconds of [`SampleContext::time`], or 1 for the pose order). Empty (the default): the
    /// effect is linear in its parameters and starts at 0.
    fn shape_grid(&self, span: f64) -> Vec<f64> {
        let _ = span;
        Vec::new()
    }
    /// For an [`EffectField::Shift`] effect, the unit direction of its translation in the
    /// robot's base link frame; zero for every other effect (the default).
    fn shift_direction(&self) -> nalgebra::Vector3<f64> {
        nalgebra::Vector3::zeros()
    }
}

/// A gear ratio error: `theta_J += eps · q_J` (radians per radian), named `gear_ratio:<J>`.
#[derive(Clone, Debug, PartialEq)]
pub struct GearRatio {
    joint: String,
    row: usize,
}

impl GearRatio {
    /// A gear ratio error of `joint` (a row of `table`).
    ///
    /// # Errors
    /// [`CalibError::MissingJoint`] when the table has no such row.
    pub fn new(table: &DhTable, joint: &str) -> Result<Self, CalibError> {
        let row = table
            .rows
            .iter()
            .position(|r| r.name == joint)
            .ok_or_else(|| CalibError::MissingJoint {
                joint: joint.into(),
            })?;
        Ok(Self {
            joint: joint.into(),
            row,
        })
    }
}

impl Effect for GearRatio {
    fn parameter_names(&self) -> Vec<String> {
        vec![format!("gear_ratio:{}", self.joint)]
    }
    fn joint(&self) -> &str {
        &self.joint
    }
    fn field(&self) -> EffectField {
        EffectField::Theta
    }
    fn delta(&self, q: &[f64], params: &[f64]) -> f64 {
        params.first().copied().unwrap_or(0.0) * q.get(self.row).copied().unwrap_or(0.0)
    }
    fn gradient(&self, q: &[f64], _params: &[f64], out: &mut [f64]) {
        if let Some(o) = out.first_mut() {
            *o = q.get(self.row).copied().unwrap_or(0.0);
        }
    }
    fn scales(&self, length: f64) -> Vec<f64> {
        vec![length]
    }
    fn units(&self) -> Vec<String> {
        vec!["rad/rad".into()]
    }
}
