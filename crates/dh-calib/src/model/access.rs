//! A [`Model`]'s parameters, scales, reference frames and targets, and the poses of its
//! blocks at a parameter vector `x` (metres, radians; frames as in the parent module).

use std::ops::Range;
use std::sync::Arc;

use dh_core::DhTable;
use nalgebra::{Isometry3, Vector3};

use super::ops::Frame;
use super::{Block, Effect, Model, PairParametrisation, Parameter, Unit};
use crate::tree::DhTree;

impl Model {
    /// The effects added, in order, with their parameter ranges.
    pub fn effects(&self) -> Vec<(Arc<dyn Effect>, Range<usize>)> {
        self.effects
            .iter()
            .map(|s| (s.effect.clone(), s.params.clone()))
            .collect()
    }

    /// The tree the model was built from (a trunk only for a serial robot).
    pub fn tree(&self) -> &DhTree {
        &self.tree
    }

    /// Rows (tree joint order) with a zero tilt about `y` that an [`EffectField::Beta`](super::EffectField::Beta) effect
    /// can free: the rows that would carry `beta` of a pair within [`NEAR_PARALLEL`](super::NEAR_PARALLEL) of
    /// parallel that does not use Hayati-Mirmirani.
    pub fn tilt_rows(&self) -> Vec<usize> {
        self.rows
            .iter()
            .enumerate()
            .filter(|(_, r)| r.beta.is_some_and(|o| self.ops[o].param.is_none()))
            .map(|(i, _)| i)
            .collect()
    }

    /// The chain target `k` rides on.
    pub fn target_chain(&self, k: usize) -> usize {
        self.target_chain.get(k).copied().unwrap_or(0)
    }

    /// The parameters, in the order of `x`: device (6), base (6), per row in chain order
    /// (standard: `theta`, `d`, `a`, `alpha`, `beta`; modified: `alpha`, `a`, `beta`, `theta`,
    /// `d`; `d` absent when dropped, `beta` only for Hayati rows), tool (6), targets (3 each),
    /// effects. For a tree: device, base, the trunk's rows, then per branch its mount (6) and
    /// rows, then targets and effects.
    pub fn parameters(&self) -> &[Parameter] {
        &self.parameters
    }

    /// Number of parameters.
    pub fn parameter_count(&self) -> usize {
        self.parameters.len()
    }

    /// Index of the parameter named `name`.
    pub fn index_of(&self, name: &str) -> Option<usize> {
        self.parameters.iter().position(|p| p.name == name)
    }

    /// Indices of the parameters of blocks for which `keep` is true.
    pub fn indices(&self, keep: impl Fn(Block) -> bool) -> Vec<usize> {
        (0..self.parameters.len())
            .filter(|&i| keep(self.parameters[i].block))
            .collect()
    }

    /// The nominal table the model was built from; for a tree, [`DhTree::joint_table`] (every
    /// row in joint order, the trunk's base and tool), which is not a kinematic chain.
    pub fn nominal(&self) -> &DhTable {
        &self.nominal
    }

    /// Characteristic length (metres) used to scale angle columns.
    pub fn length_scale(&self) -> f64 {
        self.length_scale
    }

    /// Column scales for [`crate::fit`]: 1 for lengths, the length scale for angles (so a
    /// column is the tip motion in metres per metre or per radian times the robot's size), and
    /// the effect's own scales for effect parameters.
    pub fn scales(&self) -> Vec<f64> {
        let mut s: Vec<f64> = self
            .parameters
            .iter()
            .map(|p| match p.unit {
                Unit::Length => 1.0,
                Unit::Angle | Unit::Other => self.length_scale,
            })
            .collect();
        for slot in &self.effects {
            for (k, v) in slot
                .effect
                .scales(self.length_scale)
                .into_iter()
                .enumerate()
            {
                if let Some(x) = s.get_mut(slot.params.start + k) {
                    if v.is_finite() && v > 0.0 {
                        *x = v;
                    }
                }
            }
        }
        s
    }

    /// Priorities for [`crate::fit::identifiability`] (lower is fixed first): base, tool and
    /// mounts (always aliased with the device frame, the targets or the rows next to them) 0, effects 1, DH rows 2, targets
    /// 3, device 4 (the device frame and the targets are what every step estimates).
    pub fn priorities(&self) -> Vec<u32> {
        self.parameters
            .iter()
            .map(|p| match p.block {
                Block::Base | Block::Tool | Block::Mount(_) => 0,
                Block::Effect(_) => 1,
                Block::Joint(_) => 2,
                Block::Target(_) => 3,
                Block::Device | Block::Session(_) => 4,
            })
            .collect()
    }

    /// How each consecutive pair of joints is parametrised.
    pub fn pairs(&self) -> &[PairParametrisation] {
        &self.pairs
    }

    /// Target names and reference positions (tip frame, metres).
    pub fn targets(&self) -> &[(String, Vector3<f64>)] {
        &self.targets
    }

    /// A number renewed by every change of the model (every `&mut self` method): results
    /// computed from the model at one revision hold while it is the same.
    pub(crate) fn revision(&self) -> u64 {
        self.revision
    }

    /// The reference device frame `T_device_base` (at `x = 0`).
    pub fn device(&self) -> Isometry3<f64> {
        self.ops[0].fixed.to_iso()
    }

    /// Sets the reference device frame `T_device_base`.
    pub fn set_device(&mut self, device: &Isometry3<f64>) {
        self.revision = super::prepared::next_revision();
        self.ops[0].fixed = Frame::from_iso(device);
    }

    /// Sets target `k`'s reference position in the tip frame (metres); ignored when out of
    /// range.
    pub fn set_target(&mut self, k: usize, position: Vector3<f64>) {
        self.revision = super::prepared::next_revision();
        if let Some(t) = self.targets.get_mut(k) {
            t.1 = position;
        }
    }

    /// Moves the device and target offsets of `x` into the reference and zeroes them.
    pub fn rebase(&mut self, x: &mut [f64]) {
        self.revision = super::prepared::next_revision();
        let device = self.device_at(x);
        self.set_device(&device);
        let sessions: Vec<usize> = self.session_chains.iter().map(|(s, _)| *s).collect();
        for s in sessions {
            let frame = self.session_device_at(x, s);
            self.set_session_device(s, &frame);
        }
        for k in 0..self.targets.len() {
            let t = self.target_at(x, k);
            self.targets[k].1 = t;
            self.rebase_target_rotation(x, k);
        }
        for (i, p) in self.parameters.iter().enumerate() {
            if matches!(
                p.block,
                Block::Device | Block::Session(_) | Block::Target(_)
            ) {
                if let Some(v) = x.get_mut(i) {
                    *v = 0.0;
                }
            }
        }
    }

    /// The pose of a pose block (`Device`, `Base` or `Tool`) at `x`; identity for other blocks.
    pub fn pose_at(&self, x: &[f64], block: Block) -> Isometry3<f64> {
        let Some(first) = self.parameters.iter().position(|p| p.block == block) else {
            return Isometry3::identity();
        };
        let Some(op) = self.param_op[first] else {
            return Isometry3::identity();
        };
        // The block's Fixed op precedes its six parameter ops.
        let mut f = Frame::IDENTITY;
        for o in &self.ops[op - 1..op + 6] {
            let v = o.value + o.param.and_then(|p| x.get(p)).copied().unwrap_or(0.0);
            f.apply(o.kind, v, &o.fixed);
        }
        f.to_iso()
    }

    /// `T_device_base` at `x`.
    pub fn device_at(&self, x: &[f64]) -> Isometry3<f64> {
        self.pose_at(x, Block::Device)
    }

    /// Target `k`'s position in the tip frame at `x` (metres).
    pub fn target_at(&self, x: &[f64], k: usize) -> Vector3<f64> {
        let Some((_, r)) = self.targets.get(k) else {
            return Vector3::zeros();
        };
        let s = self.target_params + 3 * k;
        r + Vector3::new(
            x.get(s).copied().unwrap_or(0.0),
            x.get(s + 1).copied().unwrap_or(0.0),
            x.get(s + 2).copied().unwrap_or(0.0),
        )
    }

    /// The sessions with their own device block, in the order added.
    pub fn sessions(&self) -> Vec<usize> {
        self.session_chains.iter().map(|(s, _)| *s).collect()
    }

    /// `T_device_base` of measurement session `session` at `x` (the `device` block's for a
    /// session without its own).
    pub fn session_device_at(&self, x: &[f64], session: usize) -> Isometry3<f64> {
        if self.session_chains.iter().any(|(s, _)| *s == session) {
            self.pose_at(x, Block::Session(session))
        } else {
            self.device_at(x)
        }
    }

    /// Sets the reference device frame of `session` ([`Model::set_device`] for a session
    /// without its own block).
    pub fn set_session_device(&mut self, session: usize, device: &Isometry3<f64>) {
        self.revision = super::prepared::next_revision();
        let op = self
            .parameters
            .iter()
            .position(|p| p.block == Block::Session(session))
            .and_then(|p| self.param_op[p]);
        match op {
            // The block's Fixed op precedes its six parameter ops.
            Some(o) if o > 0 => self.ops[o - 1].fixed = Frame::from_iso(device),
            _ => self.set_device(device),
        }
    }
}
