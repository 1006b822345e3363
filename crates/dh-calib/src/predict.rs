//! Using a calibration: the calibrated robot's positions and poses at given joint values, with
//! each prediction's standard uncertainty.
//!
//! # Frames
//! With `T_device_base` the estimated device frame, `FK` the calibrated table's forward
//! kinematics with its effects (base and tool included, see [`crate::model`]) and `t_k` target
//! `k` in the tip frame:
//!
//! ```text
//! Frame::Device:  p = s(q) · T_device_base · FK(q) · t_k    (s: the device scale effect, 1 without)
//! Frame::Base:    p = FK(q) · t_k,        tool pose FK(q)   (the robot's base link frame)
//! ```
//!
//! A prediction is a pose outside the measured sequence: the effects of the sample order
//! ([`crate::effects_order`]) are in their neutral context, a `backlash_direction` midway
//! between its flanks (`s = 0`) and a `drift` at the session's start (`t = 0`).
//!
//! # Uncertainty
//! `u = sqrt(diag(G C Gᵀ))`, first order: `C` is the covariance of the calibration's free
//! parameters ([`Covariance`], `σ̂² (JᵀJ)⁺` of [`crate::fit`]) and `G` the prediction's
//! derivative by those parameters, analytic: the screw motion each parameter gives the chain
//! ([`Model::frame_jacobian`], the calibration's own Jacobian), moved to the base link frame by
//! the device frame's rotation and scale. Parameters the data could not identify were held at nominal and add
//! nothing: the uncertainty is that of what was identified, in the frame it was identified in
//! (a base frame error aliased with the device frame is in neither figure). Rotational
//! uncertainties are about the axes of the prediction frame (radians), not roll-pitch-yaw.
//! A `backlash_direction:J` whose approach direction the prediction does not know (`s_J = 0`)
//! adds its own spread, `|b| · ∂p/∂theta_J` per axis (half the backlash, see
//! `Calibrated::backlash_variance`), to the variance.

use std::ops::Range;
use std::sync::Arc;

use dh_core::DhTable;
use nalgebra::{DMatrix, DVectorView, Isometry3, UnitQuaternion, Vector3, Vector6};

use crate::effects::EffectContext;
use crate::fit::CalibError;
use crate::model::{
    Block, Effect, EffectField, Model, ModelOptions, Observation, Observed, SampleContext,
};

pub use crate::covariance::Covariance;

/// Which frame predictions are expressed in (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Frame {
    /// The measuring device's frame, where the calibration data were measured.
    Device,
    /// The robot's base link frame.
    Base,
}

/// An effect with its parameter values (in the order of [`Effect::parameter_names`]).
pub type EffectValues = (Arc<dyn Effect>, Vec<f64>);

/// A calibrated robot that predicts (see the module docs).
#[derive(Clone, Debug)]
pub struct Calibrated {
    model: Model,
    x: Vec<f64>,
    /// Where the predicted poses sit in a sequence of motions (neutral by default: see the
    /// module docs and [`Calibrated::set_context`]).
    context: SampleContext,
    /// The covariance and the parameters it is of.
    covariance: Option<Propagation>,
    /// How many of the model's targets are the calibration's (the rest are the tips of a
    /// tree's chains, see `predict::tree`).
    real_targets: usize,
    /// Per chain of a tree: the model's target at its tip (empty for a serial robot, whose
    /// tool is the model's own tip).
    tools: Vec<usize>,
}

impl Calibrated {
    /// The calibrated `table` with its `effects` at their values, the device frame
    /// `T_device_base` and the targets (name, position in the tip frame), all metres and
    /// radians.
    ///
    /// # Errors
    /// As [`Model::new`] and [`Model::add_effect`]; [`CalibError::BadOption`] for an effect
    /// given the wrong number of values.
    pub fn new(
        table: &DhTable,
        effects: &[EffectValues],
        device: &Isometry3<f64>,
        targets: &[(String, Vector3<f64>)],
    ) -> Result<Self, CalibError> {
        let names: Vec<String> = targets.iter().map(|(n, _)| n.clone()).collect();
        let model = Model::new(table, &names, &ModelOptions::default())?;
        let positions: Vec<Vector3<f64>> = targets.iter().map(|(_, t)| *t).collect();
        Self::build(model, effects, device, &positions)
    }

    /// The calibrated robot of `model` (built with every target, the calibration's first):
    /// `effects` added at their values, the device frame and the first `positions.len()`
    /// targets set (tip frame, metres).
    fn build(
        mut model: Model,
        effects: &[EffectValues],
        device: &Isometry3<f64>,
        positions: &[Vector3<f64>],
    ) -> Result<Self, CalibError> {
        let mut values = Vec::new();
        for (effect, v) in effects {
            let range = model.add_effect(effect.clone())?;
            if range.len() != v.len() {
                return Err(CalibError::BadOption {
                    what: format!("effect '{}'", effect.label()),
                    reason: format!("expected {} values, found {}", range.len(), v.len()),
                });
            }
            values.push((range, v.clone()));
        }
        model.set_device(device);
        for (k, t) in positions.iter().enumerate() {
            model.set_target(k, *t);
        }
        let mut x = vec![0.0; model.parameter_count()];
        for (range, v) in values {
            for (i, value) in range.zip(v) {
                x[i] = value;
            }
        }
        Ok(Calibrated {
            model,
            x,
            context: SampleContext::default(),
            covariance: None,
            real_targets: positions.len(),
            tools: Vec::new(),
        })
    }

    /// The calibrated robot of a [`crate::calibrate::Report`]: its table, the effects it
    /// selected (their labels parsed in `ctx`, which gives the masses of gravity effects), its
    /// device frame and targets, and its covariance.
    ///
    /// # Errors
    /// As [`Calibrated::new`]; a selected effect whose label does not parse in `ctx`.
    pub fn from_report(
        report: &crate::calibrate::Report,
        ctx: &EffectContext,
    ) -> Result<Self, CalibError> {
        let effects = report_effects(report, ctx)?;
        let c = Self::new(
            &report.calibrated,
            &effects,
            &report.device,
            &report.targets,
        )?
        .with_target_rotations(&report.target_rotations);
        match &report.covariance {
            Some(cov) => c.with_covariance(cov),
            None => Ok(c),
        }
    }

    /// The same robot with target `k` a full frame of rotation `rotations[k]` in the tip frame
    /// (a 6-DoF probe's; `None`: a point target), so that a covariance over the targets'
    /// orientation parameters (`target.<name>.rx|ry|rz`) fits it.
    pub fn with_target_rotations(mut self, rotations: &[Option<UnitQuaternion<f64>>]) -> Self {
        for (k, r) in rotations.iter().enumerate() {
            if let Some(r) = r {
                if self.model.add_target_orientation(k).is_some() {
                    self.model.set_target_rotation(k, r);
                }
            }
        }
        self.x.resize(self.model.parameter_count(), 0.0);
        self
    }

    /// Target `k`'s rotation in the tip frame (identity for a point target).
    pub fn target_rotation(&self, k: usize) -> UnitQuaternion<f64> {
        self.model.target_rotation_at(&self.x, k)
    }

    /// The same robot measured from another device frame `T_device_base` (another
    /// measurement session's, see [`Covariance::in_session`]).
    pub fn with_device(mut self, device: &Isometry3<f64>) -> Self {
        self.model.set_device(device);
        self
    }

    /// The same robot with the covariance of its parameters.
    ///
    /// # Errors
    /// [`CalibError::BadOption`] naming a covariance parameter the model does not have.
    pub fn with_covariance(mut self, covariance: &Covariance) -> Result<Self, CalibError> {
        let index = covariance
            .parameters
            .iter()
            .map(|p| {
                self.model.index_of(p).ok_or_else(|| CalibError::BadOption {
                    what: "covariance".into(),
                    reason: format!("parameter '{p}' is no parameter of this model"),
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let scale_effects: Vec<Range<usize>> = self
            .model
            .effects()
            .into_iter()
            .filter(|(e, _)| e.field() == EffectField::Scale)
            .map(|(_, r)| r)
            .collect();
        let moves_device = index
            .iter()
            .map(|&i| {
                matches!(
                    self.model.parameters().get(i).map(|p| p.block),
                    Some(Block::Device | Block::Session(_))
                ) || scale_effects.iter().any(|r| r.contains(&i))
            })
            .collect();
        self.covariance = Some(Propagation {
            index,
            matrix: covariance.matrix.clone(),
            moves_device,
        });
        Ok(self)
    }

    /// Predicts the next poses at `context` in a sequence of motions: each joint's approach
    /// direction (`context.direction`, per table row, -1, 0 or +1; see
    /// [`crate::effects_order::sequence_contexts`]) for `backlash_direction`, the place in
    /// time for `drift`. A joint whose direction is 0 is predicted midway between its flanks,
    /// the backlash added to the uncertainty.
    pub fn set_context(&mut self, context: SampleContext) {
        self.context = context;
    }

    /// Whether predictions come with an uncertainty.
    pub fn has_covariance(&self) -> bool {
        self.covariance.is_some()
    }

    /// The underlying model (its parameters at [`Calibrated::parameters`]).
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The parameter vector of the calibrated state (zero but for the effects' values).
    pub fn parameters(&self) -> &[f64] {
        &self.x
    }

    /// The calibrated table (the model's, tilts in their rows).
    pub fn table(&self) -> &DhTable {
        self.model.nominal()
    }

    /// Target names and positions in the tip frame (metres); a tree's target is in the tip
    /// frame of its branch ([`Calibrated::target_branch`]).
    pub fn targets(&self) -> &[(String, Vector3<f64>)] {
        let all = self.model.targets();
        &all[..self.real_targets.min(all.len())]
    }

    /// Where target `k` is at row values `q` (one per table row), metres.
    pub fn point(&self, q: &[f64], target: usize, frame: Frame) -> Vector3<f64> {
        self.point_at(&self.x, q, target, frame)
    }

    /// The tip (tool) frame at row values `q`; in [`Frame::Device`] its position carries the
    /// device scale.
    pub fn tool(&self, q: &[f64], frame: Frame) -> Isometry3<f64> {
        self.tool_at(&self.x, q, 0, frame)
    }

    /// The tip frame of chain `chain` (a tree's branch index, see [`Calibrated::chains`]; 0
    /// for a serial robot) at row values `q`, as [`Calibrated::tool`].
    pub fn tool_of(&self, q: &[f64], chain: usize, frame: Frame) -> Isometry3<f64> {
        self.tool_at(&self.x, q, chain, frame)
    }

    /// A 6-DoF target's orientation at row values `q`: the tip's rotation in `frame` times the
    /// target's rotation in the tip frame; `None` for a point target.
    pub fn target_orientation(
        &self,
        q: &[f64],
        target: usize,
        frame: Frame,
    ) -> Option<UnitQuaternion<f64>> {
        self.model.target_orientation(target)?;
        Some(self.orientation_at(&self.x, q, target, frame))
    }

    /// Standard uncertainty of [`Calibrated::target_orientation`]: the rotation about each axis
    /// of `frame` (radians); `None` for a point target or without a covariance.
    pub fn target_orientation_uncertainty(
        &self,
        q: &[f64],
        target: usize,
        frame: Frame,
    ) -> Option<Vector3<f64>> {
        self.model.target_orientation(target)?;
        let u = self.propagate(q, Of::TargetFrame(target), frame, 3..6)?;
        Some(Vector3::new(u[3], u[4], u[5]))
    }

    fn orientation_at(
        &self,
        x: &[f64],
        q: &[f64],
        target: usize,
        frame: Frame,
    ) -> UnitQuaternion<f64> {
        self.tool_at(x, q, self.model.target_chain(target), frame)
            .rotation
            * self.model.target_rotation_at(x, target)
    }

    fn point_at(&self, x: &[f64], q: &[f64], target: usize, frame: Frame) -> Vector3<f64> {
        let ctx = &self.context;
        match frame {
            Frame::Device => self.model.point_in(x, q, ctx, target),
            Frame::Base => {
                // The tip's position is grown already, the target's offset on it not yet.
                let chain = self.model.target_chain(target);
                let tip = self.model.robot_fk_in(x, q, ctx, chain);
                let growth = self.model.growth_at(x, q, ctx);
                tip.translation.vector + tip.rotation * self.model.target_at(x, target) * growth
            }
        }
    }

    fn tool_at(&self, x: &[f64], q: &[f64], chain: usize, frame: Frame) -> Isometry3<f64> {
        match frame {
            Frame::Device => self.model.tip_of_in(x, q, &self.context, chain),
            Frame::Base => self.model.robot_fk_in(x, q, &self.context, chain),
        }
    }

    /// Standard uncertainty of [`Calibrated::point`] per axis of `frame` (metres); `None`
    /// without a covariance.
    pub fn point_uncertainty(
        &self,
        q: &[f64],
        target: usize,
        frame: Frame,
    ) -> Option<Vector3<f64>> {
        let u = self.propagate(q, Of::Point(target), frame, 0..3)?;
        Some(Vector3::new(u[0], u[1], u[2]))
    }

    /// Standard uncertainty of [`Calibrated::tool`]: position per axis (metres), then rotation
    /// about each axis of `frame` (radians); `None` without a covariance.
    pub fn tool_uncertainty(&self, q: &[f64], frame: Frame) -> Option<Vector6<f64>> {
        self.tool_uncertainty_of(q, 0, frame)
    }

    /// Standard uncertainty of [`Calibrated::tool_of`], as [`Calibrated::tool_uncertainty`]:
    /// a tree's tip is propagated as the frame of a target at its origin, which no parameter
    /// of the covariance moves but through the chain.
    pub fn tool_uncertainty_of(
        &self,
        q: &[f64],
        chain: usize,
        frame: Frame,
    ) -> Option<Vector6<f64>> {
        let of = match self.tools.get(chain) {
            Some(&k) => Of::TargetFrame(k),
            None => Of::Tool,
        };
        let u = self.propagate(q, of, frame, 0..6)?;
        Some(Vector6::from_column_slice(&u))
    }

    /// `sqrt(diag(G C Gᵀ))` for the rows `rows` of the derivative `G` (6 rows: position, then
    /// rotation) of what `of` names, in `frame`; the rows not asked are zero.
    fn propagate(&self, q: &[f64], of: Of, frame: Frame, rows: Range<usize>) -> Option<[f64; 6]> {
        let p = self.covariance.as_ref()?;
        let m = p.index.len();
        let observation = match of {
            Of::Point(target) => Observation::Point {
                target,
                point: Vector3::zeros(),
            },
            Of::TargetFrame(target) => Observation::TargetPose {
                target,
                pose: Box::new(Isometry3::identity()),
                weight: 1.0,
            },
            Of::Tool => Observation::Pose(Box::new(Isometry3::identity())),
        };
        let mut obs = Observed::new(q.to_vec(), observation);
        obs.context = self.context.clone();
        let backlash = self.backlash_variance(&obs, frame);
        JACOBIAN.with(|g| {
            let mut g = g.borrow_mut();
            g.clear();
            g.resize(6 * m, 0.0);
            self.model.frame_jacobian(&self.x, &obs, &p.index, &mut g);
            if frame == Frame::Base {
                // p_base = R_deviceᵀ (p_device / s − t_device): the robot's parameters move the
                // base-frame prediction by R_deviceᵀ ∂p / s (rotations by R_deviceᵀ ∂w), the
                // device frame and its scale not at all.
                let r = self.model.device_at(&self.x).rotation.inverse();
                let s = self.model.scale_at(&self.x, q);
                let s = if s == 0.0 { 1.0 } else { s };
                for col in 0..m {
                    for (first, divide) in [(0, s), (3, 1.0)] {
                        let v = if p.moves_device[col] {
                            Vector3::zeros()
                        } else {
                            r * Vector3::from_fn(|i, _| g[(first + i) * m + col]) / divide
                        };
                        for i in 0..3 {
                            g[(first + i) * m + col] = v[i];
                        }
                    }
                }
            }
            let mut u = [0.0; 6];
            for row in rows {
                let gr = &g[row * m..(row + 1) * m];
                // g C gᵀ over the upper triangle of the symmetric C: Σ_j g_j (C_jj g_j +
                // 2 Σ_{k>j} C_jk g_k), each column's tail contiguous; parameters that do not
                // move this prediction (the other targets') skipped.
                let mut sum = 0.0;
                for (j, gj) in gr.iter().enumerate() {
                    if *gj == 0.0 {
                        continue;
                    }
                    let column = p.matrix.column(j);
                    let tail = column.rows_range(j + 1..m);
                    let cross = tail.dot(&DVectorView::from_slice(&gr[j + 1..], m - j - 1));
                    sum += gj * (column[j] * gj + 2.0 * cross);
                }
                u[row] = (sum.max(0.0) + backlash[row]).sqrt();
            }
            Some(u)
        })
    }

    /// The value `c` of the model's `drift` effect (the device scale `1 + c · t` over the
    /// session, `t` in `[0, 1]`; dimensionless), `None` without one.
    pub fn drift(&self) -> Option<f64> {
        self.model
            .effects()
            .into_iter()
            .find(|(e, _)| e.label() == "drift")
            .and_then(|(_, r)| self.x.get(r.start).copied())
    }

    /// The `backlash_direction` effects of the model: (label, parameter index, row, `b`).
    pub fn backlash_effects(&self) -> Vec<(String, usize, usize, f64)> {
        self.model
            .effects()
            .into_iter()
            .filter(|(e, _)| e.label().starts_with("backlash_direction:"))
            .filter_map(|(e, r)| {
                let row = self
                    .model
                    .nominal()
                    .rows
                    .iter()
                    .position(|x| x.name == e.joint())?;
                Some((e.label(), r.start, row, self.x[r.start]))
            })
            .collect()
    }

    /// The variance (per row of a frame derivative: position m², rotation rad²) that the
    /// unknown approach direction of each `backlash_direction:J` adds where `obs`'s context
    /// gives joint `J` no direction (`s_J = 0`, midway between the flanks): the gear rests on
    /// one flank or the other, `theta_J ± b`, a two-point spread of standard deviation `|b|`
    /// (half the backlash `2|b|`), moved to the prediction by `∂p/∂theta_J`. Joints are taken
    /// as independent.
    fn backlash_variance(&self, obs: &Observed, frame: Frame) -> [f64; 6] {
        let mut var = [0.0; 6];
        let effects = self.backlash_effects();
        if effects.is_empty() {
            return var;
        }
        // With every direction +1 the derivative by `b` is the derivative by theta_J.
        let mut flank = obs.clone();
        flank.context.direction = vec![1.0; self.model.nominal().rows.len()];
        let mut g = [0.0; 6];
        for (_, index, row, b) in effects {
            if obs.context.direction_of(row) != 0.0 {
                continue;
            }
            g.fill(0.0);
            self.model.frame_jacobian(&self.x, &flank, &[index], &mut g);
            let (mut p, mut w) = (
                Vector3::new(g[0], g[1], g[2]),
                Vector3::new(g[3], g[4], g[5]),
            );
            if frame == Frame::Base {
                let r = self.model.device_at(&self.x).rotation.inverse();
                let s = self.model.scale_at(&self.x, &obs.q);
                p = r * p / if s == 0.0 { 1.0 } else { s };
                w = r * w;
            }
            for i in 0..3 {
                var[i] += (p[i] * b).powi(2);
                var[3 + i] += (w[i] * b).powi(2);
            }
        }
        var
    }
}

/// What a derivative is of.
#[derive(Clone, Copy, Debug)]
enum Of {
    /// A target's position (its rotation rows are the tip's).
    Point(usize),
    /// A target's frame.
    TargetFrame(usize),
    /// The tip frame.
    Tool,
}

thread_local! {
    /// The derivative of [`Calibrated::propagate`], reused between calls on one thread.
    static JACOBIAN: std::cell::RefCell<Vec<f64>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// The covariance as the model's parameters see it.
#[derive(Clone, Debug)]
struct Propagation {
    /// Model parameter index per covariance row.
    index: Vec<usize>,
    /// The covariance.
    matrix: DMatrix<f64>,
    /// Per covariance row: the parameter moves the device frame or scales it (it moves no
    /// base-frame prediction).
    moves_device: Vec<bool>,
}

#[cfg(test)]
mod tests;

mod effect_values;
mod tree;

pub use effect_values::effects_from_parameters;
use effect_values::report_effects;
