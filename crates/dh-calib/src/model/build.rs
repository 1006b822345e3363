//! Building a [`Model`]: its ops and parameters from a DH table or tree, effects and
//! measurement sessions added later (frames and parameter layout in the parent module).

use std::ops::Range;
use std::sync::Arc;

use dh_core::{Convention, DhTable, JointKind};
use nalgebra::{Isometry3, Vector3};

use super::ops::{unit_of, Axis, EffectSlot, Frame, Op, OpKind, RowOps, DEVICE_OPS, POSE_FIELDS};
use super::options::{plan_table, RowPlan};
use super::{
    finite, prepared, Block, Effect, EffectField, Field, Model, ModelOptions, Parameter, Unit,
};
use crate::fit::CalibError;
use crate::tree::DhTree;

impl Model {
    /// Builds the model of `table` measured at the targets named `targets` (their positions
    /// start at the tip frame's origin, the device frame at the base link frame; set them with
    /// [`Model::set_device`] and [`Model::set_target`]).
    ///
    /// # Errors
    /// [`CalibError::Core`] for a non-finite table value or an empty table;
    /// [`CalibError::BadOption`] for a negative or non-finite threshold or scale.
    pub fn new(
        table: &DhTable,
        targets: &[String],
        options: &ModelOptions,
    ) -> Result<Model, CalibError> {
        let on: Vec<(String, usize)> = targets.iter().map(|t| (t.clone(), 0)).collect();
        Self::new_tree(&DhTree::serial(table), &on, options)
    }

    /// Builds the model of a tree; each target is `(name, chain)` with `chain` a branch index
    /// (0 for a serial robot). See the module docs.
    ///
    /// # Errors
    /// As [`Model::new`], and [`CalibError::BadOption`] for a chain index out of range.
    pub fn new_tree(
        tree: &DhTree,
        targets: &[(String, usize)],
        options: &ModelOptions,
    ) -> Result<Model, CalibError> {
        if tree.rows().is_empty() {
            return Err(CalibError::Core(dh_core::CoreError::NoJoints));
        }
        for r in tree.rows() {
            for (f, v) in [
                ("a", r.a),
                ("alpha", r.alpha),
                ("d", r.d),
                ("theta", r.theta),
            ] {
                finite(&format!("{}.{f}", r.name), v)?;
            }
        }
        for (name, c) in targets {
            if *c >= tree.chain_count() {
                return Err(CalibError::BadOption {
                    what: format!("target '{name}'"),
                    reason: format!(
                        "expected a chain index below {}, found {c}",
                        tree.chain_count()
                    ),
                });
            }
        }
        let t = options.hayati_threshold;
        if !(t.is_finite() && t >= 0.0) {
            return Err(CalibError::BadOption {
                what: "hayati threshold".into(),
                reason: format!("expected a finite angle >= 0, found {t}"),
            });
        }
        let length_scale = options.length_scale.unwrap_or_else(|| tree.size());
        let orientation_scale = options.orientation_scale.unwrap_or(length_scale);
        for (what, v) in [
            ("length scale", length_scale),
            ("orientation scale", orientation_scale),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(CalibError::BadOption {
                    what: what.into(),
                    reason: format!("expected a positive length, found {v}"),
                });
            }
        }
        let (mut pairs, mut plan) = plan_table(tree.trunk(), t)?;
        for b in tree.branches() {
            let (p, r) = plan_table(&b.table, t)?;
            pairs.extend(p);
            plan.extend(r);
        }
        let nominal = if tree.branches().is_empty() {
            tree.trunk().clone()
        } else {
            tree.joint_table()
        };

        let mut m = Model {
            nominal,
            tree: tree.clone(),
            length_scale,
            orientation_scale,
            ops: Vec::new(),
            rows: Vec::new(),
            chains: Vec::new(),
            parameters: Vec::new(),
            param_op: Vec::new(),
            targets: targets
                .iter()
                .map(|(name, _)| (name.clone(), Vector3::zeros()))
                .collect(),
            target_chain: targets.iter().map(|(_, c)| *c).collect(),
            target_params: 0,
            effects: Vec::new(),
            free_slots: Default::default(),
            pairs,
            session_chains: Vec::new(),
            target_frames: vec![None; targets.len()],
            revision: prepared::next_revision(),
        };
        m.push_pose_block("device", Block::Device, &Isometry3::identity());
        m.push_pose_block("base", Block::Base, &tree.trunk().base);
        let trunk_n = tree.trunk().rows.len();
        for (i, p) in plan.iter().enumerate().take(trunk_n) {
            m.push_row(tree.trunk(), i, i, *p);
        }
        if tree.branches().is_empty() {
            m.push_pose_block("tool", Block::Tool, &tree.trunk().tool);
            m.chains.push((0..m.ops.len()).collect());
        } else {
            let f = m.push_op(OpKind::Fixed, 0.0, None, None);
            m.ops[f].fixed = Frame::from_iso(&tree.trunk().tool);
            let trunk_ops: Vec<usize> = (0..m.ops.len()).collect();
            let mut g = trunk_n;
            for (b, br) in tree.branches().iter().enumerate() {
                let start = m.ops.len();
                m.push_pose_block(
                    &format!("{}.base", br.name),
                    Block::Mount(b),
                    &br.table.base,
                );
                for i in 0..br.table.rows.len() {
                    m.push_row(&br.table, i, g, plan[g]);
                    g += 1;
                }
                let f = m.push_op(OpKind::Fixed, 0.0, None, None);
                m.ops[f].fixed = Frame::from_iso(&br.table.tool);
                let mut chain = trunk_ops.clone();
                chain.extend(start..m.ops.len());
                m.chains.push(chain);
            }
        }
        m.target_params = m.parameters.len();
        let names: Vec<String> = m.targets.iter().map(|(n, _)| n.clone()).collect();
        for (k, name) in names.iter().enumerate() {
            for (f, s) in [(Field::X, "x"), (Field::Y, "y"), (Field::Z, "z")] {
                m.push_param(
                    format!("target.{name}.{s}"),
                    Block::Target(k),
                    f,
                    Unit::Length,
                );
            }
        }
        Ok(m)
    }

    /// Pushes the ops and parameters of row `i` of `table` (global row `g`).
    pub(super) fn push_row(&mut self, table: &DhTable, i: usize, g: usize, plan: RowPlan) {
        self.revision = super::prepared::next_revision();
        let row = &table.rows[i];
        let revolute = (row.kind == JointKind::Revolute).then_some(g);
        let prismatic = (row.kind == JointKind::Prismatic).then_some(g);
        let blk = Block::Joint(g);
        let alpha = (OpKind::Rot(Axis::X), row.alpha, None, Some(Field::Alpha));
        let a = (OpKind::Trans(Axis::X), row.a, None, Some(Field::A));
        let beta_field = plan.beta.then_some(Field::Beta);
        // A tilt the table already carries is the nominal value its `beta` error adds to.
        let beta = (OpKind::Rot(Axis::Y), row.beta, None, beta_field);
        let with_beta = plan.beta || plan.placeholder || row.beta != 0.0;
        let theta = (
            OpKind::Rot(Axis::Z),
            row.theta,
            revolute,
            Some(Field::Theta),
        );
        let d_field = (!plan.drop_d).then_some(Field::D);
        let d = (OpKind::Trans(Axis::Z), row.d, prismatic, d_field);
        let mut seq = Vec::with_capacity(5);
        match table.convention {
            Convention::Standard => {
                seq.extend([theta, d, a, alpha]);
                if with_beta {
                    seq.push(beta);
                }
            }
            Convention::Modified => {
                seq.extend([alpha, a]);
                if with_beta {
                    seq.push(beta);
                }
                seq.extend([theta, d]);
            }
        }
        let mut ops = RowOps {
            theta: 0,
            d: 0,
            alpha: 0,
            beta: None,
        };
        for (kind, value, joint, field) in seq {
            let param = field.map(|f| {
                let fname = match f {
                    Field::A => "a",
                    Field::Alpha => "alpha",
                    Field::D => "d",
                    Field::Theta => "theta",
                    _ => "beta",
                };
                self.push_param(format!("{}.{fname}", row.name), blk, f, unit_of(kind))
            });
            let idx = self.push_op(kind, value, joint, param);
            match kind {
                OpKind::Rot(Axis::Z) => ops.theta = idx,
                OpKind::Trans(Axis::Z) => ops.d = idx,
                OpKind::Rot(Axis::X) => ops.alpha = idx,
                OpKind::Rot(Axis::Y) => ops.beta = Some(idx),
                _ => {}
            }
        }
        self.rows.push(ops);
    }

    pub(super) fn push_param(
        &mut self,
        name: String,
        block: Block,
        field: Field,
        unit: Unit,
    ) -> usize {
        self.revision = super::prepared::next_revision();
        self.parameters.push(Parameter {
            name,
            block,
            field,
            unit,
        });
        self.param_op.push(None);
        self.parameters.len() - 1
    }

    pub(super) fn push_op(
        &mut self,
        kind: OpKind,
        value: f64,
        joint: Option<usize>,
        param: Option<usize>,
    ) -> usize {
        self.revision = super::prepared::next_revision();
        let idx = self.ops.len();
        self.ops.push(Op {
            kind,
            value,
            fixed: Frame::IDENTITY,
            joint,
            param,
        });
        if let Some(p) = param {
            self.param_op[p] = Some(idx);
        }
        idx
    }

    pub(super) fn push_pose_block(
        &mut self,
        prefix: &str,
        block: Block,
        reference: &Isometry3<f64>,
    ) {
        self.revision = super::prepared::next_revision();
        let f = self.push_op(OpKind::Fixed, 0.0, None, None);
        self.ops[f].fixed = Frame::from_iso(reference);
        for (field, s, kind) in POSE_FIELDS {
            let p = self.push_param(format!("{prefix}.{s}"), block, field, unit_of(kind));
            self.push_op(kind, 0.0, None, Some(p));
        }
    }

    /// Adds an effect; its parameters are appended to the parameter list.
    ///
    /// # Errors
    /// [`CalibError::MissingJoint`] when the effect names no row of the model;
    /// [`CalibError::BadOption`] for a tilt effect on a row without a tilt (see
    /// [`Model::tilt_rows`]) or one that already estimates it, and for a second device scale.
    pub fn add_effect(&mut self, effect: Arc<dyn Effect>) -> Result<Range<usize>, CalibError> {
        self.revision = super::prepared::next_revision();
        let label = effect.label();
        if self.effects.iter().any(|s| s.effect.label() == label) {
            return Err(CalibError::BadOption {
                what: format!("effect '{label}'"),
                reason: "expected each effect once, found it twice".into(),
            });
        }
        let op = if matches!(
            effect.field(),
            EffectField::Scale | EffectField::Growth | EffectField::Shift
        ) {
            None
        } else {
            let row =
                self.tree
                    .row_index(effect.joint())
                    .ok_or_else(|| CalibError::MissingJoint {
                        joint: effect.joint().into(),
                    })?;
            let ops = self.rows[row];
            Some(match effect.field() {
                EffectField::Theta => ops.theta,
                EffectField::D => ops.d,
                EffectField::Alpha => ops.alpha,
                EffectField::Beta => match ops.beta {
                    Some(o) if self.ops[o].param.is_none() => o,
                    Some(_) => {
                        return Err(CalibError::BadOption {
                            what: format!("effect on '{}'", effect.joint()),
                            reason: "expected a row whose tilt is not estimated already, found \
                                     a Hayati-Mirmirani row"
                                .into(),
                        })
                    }
                    None => {
                        return Err(CalibError::BadOption {
                            what: format!("effect on '{}'", effect.joint()),
                            reason: "expected a row of a near-parallel pair, found none".into(),
                        })
                    }
                },
                EffectField::Scale | EffectField::Growth | EffectField::Shift => ops.theta,
            })
        };
        let e = self.effects.len();
        let start = self.parameters.len();
        for (k, name) in effect.parameter_names().into_iter().enumerate() {
            self.push_param(name, Block::Effect(e), Field::Effect(k), Unit::Other);
        }
        let params = start..self.parameters.len();
        let shift = (effect.field() == EffectField::Shift).then(|| effect.shift_direction());
        let slots = &mut self.free_slots;
        match effect.field() {
            EffectField::Scale => slots.scale.push(e),
            EffectField::Growth => slots.growth.push(e),
            EffectField::Shift => slots.shift.push(e),
            _ => {}
        }
        self.effects.push(EffectSlot {
            effect,
            params: params.clone(),
            op,
            shift,
        });
        Ok(params)
    }

    /// Gives measurement session `session` its own device frame `T_device_base` (reference
    /// `frame`, plus six parameters `session.<name>.x|y|z|rx|ry|rz` laid out as `device.*`),
    /// appended to the parameters. Observations of other sessions keep the `device` block.
    /// Adding a session twice is a no-op.
    pub fn add_session(&mut self, session: usize, name: &str, frame: &Isometry3<f64>) {
        self.revision = super::prepared::next_revision();
        if self.session_chains.iter().any(|(s, _)| *s == session) {
            return;
        }
        let start = self.ops.len();
        self.push_pose_block(&format!("session.{name}"), Block::Session(session), frame);
        let block: Vec<usize> = (start..self.ops.len()).collect();
        let chains = self
            .chains
            .iter()
            .map(|c| {
                let mut ops = block.clone();
                ops.extend_from_slice(c.get(DEVICE_OPS..).unwrap_or(&[]));
                ops
            })
            .collect();
        self.session_chains.push((session, chains));
    }
}
