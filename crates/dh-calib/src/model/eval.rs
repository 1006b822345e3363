//! Evaluating a [`Model`]: op values at `x` and joint values `q`, chains of frames, points
//! and tip frames in the device frame (metres, the device scale applied), the robot's own
//! forward kinematics, and the calibrated table or tree.

use dh_core::DhTable;
use nalgebra::{Isometry3, Vector3};

use super::ops::{Frame, DEVICE_OPS};
use super::prepared::DEVICE_BLOCK;
use super::{Block, EffectField, Field, Model, SampleContext};
use crate::tree::{Branch, DhTree};

impl Model {
    pub(super) fn op_values(&self, x: &[f64], q: &[f64], ctx: &SampleContext, out: &mut Vec<f64>) {
        out.clear();
        out.extend(self.ops.iter().map(|o| {
            o.value
                + o.param.and_then(|p| x.get(p)).copied().unwrap_or(0.0)
                + o.joint.and_then(|j| q.get(j)).copied().unwrap_or(0.0)
        }));
        for slot in &self.effects {
            if let Some(op) = slot.op {
                let params = x.get(slot.params.clone()).unwrap_or(&[]);
                if params.iter().any(|p| *p != 0.0) {
                    out[op] += slot.effect.delta_in(q, ctx, params);
                }
            }
        }
    }

    /// `1 + Σ s` of the device scale effects at `x`, `q` and `ctx` (1 without one): the
    /// scale effects add (a constant `scale` and a `drift` in time together).
    pub(super) fn scale_factor(&self, x: &[f64], q: &[f64], ctx: &SampleContext) -> f64 {
        self.factor_of(EffectField::Scale, x, q, ctx)
    }

    /// `1 + Σ g` of the robot growth effects at `x`, `q` and `ctx` (1 without one): what
    /// multiplies the robot's positions about its base origin (see the module docs).
    pub(super) fn growth_factor(&self, x: &[f64], q: &[f64], ctx: &SampleContext) -> f64 {
        self.factor_of(EffectField::Growth, x, q, ctx)
    }

    /// Whether the model has a robot growth effect.
    pub(super) fn has_growth(&self) -> bool {
        !self.free_slots.growth.is_empty()
    }

    /// `1 + Σ` of the effects of `field` (the device scale or the robot growth) at `x`, `q`
    /// and `ctx`, in slot order.
    fn factor_of(&self, field: EffectField, x: &[f64], q: &[f64], ctx: &SampleContext) -> f64 {
        let slots = match field {
            EffectField::Scale => &self.free_slots.scale,
            EffectField::Growth => &self.free_slots.growth,
            _ => return 1.0,
        };
        1.0 + slots
            .iter()
            .map(|&e| {
                let slot = &self.effects[e];
                let params = x.get(slot.params.clone()).unwrap_or(&[]);
                slot.effect.delta_in(q, ctx, params)
            })
            .sum::<f64>()
    }

    /// The base link's origin in the device frame of `session` (metres), chain `chain`'s
    /// device ops at `x` (they depend on `x` alone).
    pub(super) fn base_origin(&self, x: &[f64], chain: usize, session: usize) -> Vector3<f64> {
        let mut f = Frame::IDENTITY;
        for &i in self.session_ops(chain, session).iter().take(DEVICE_OPS) {
            let o = &self.ops[i];
            let v = o.value + o.param.and_then(|p| x.get(p)).copied().unwrap_or(0.0);
            f.apply(o.kind, v, &o.fixed);
        }
        f.t
    }

    /// A position `p` of chain `chain` in `session`'s device frame, grown by the robot growth
    /// effects about the base origin (`p` itself without them).
    fn grown(
        &self,
        x: &[f64],
        q: &[f64],
        ctx: &SampleContext,
        (chain, session): (usize, usize),
        p: Vector3<f64>,
    ) -> Vector3<f64> {
        if !self.has_growth() {
            return p;
        }
        // At no growth the position is kept to the bit (`o + (p − o)` is not).
        let g = self.growth_factor(x, q, ctx);
        if g == 1.0 {
            return p;
        }
        let o = self.base_origin(x, chain, session);
        o + (p - o) * g
    }

    /// `Σ delta · direction` of the shift effects at `x`, `q` and `ctx` (metres, the robot's
    /// base link frame; zero without one): how far the tip and the targets move after the
    /// chain ([`super::EffectField::Shift`]).
    pub(super) fn shift_at(&self, x: &[f64], q: &[f64], ctx: &SampleContext) -> Vector3<f64> {
        let mut out = Vector3::zeros();
        for &e in &self.free_slots.shift {
            let slot = &self.effects[e];
            if let Some(dir) = slot.shift {
                let params = x.get(slot.params.clone()).unwrap_or(&[]);
                if params.iter().any(|p| *p != 0.0) {
                    out += dir * slot.effect.delta_in(q, ctx, params);
                }
            }
        }
        out
    }

    /// [`Model::chain`] of the op values `v` (at `x`, `q`, `ctx`) along the chain `ops` (device
    /// block first), the shift effects' translation added: in the base link frame, turned into
    /// the device frame by the device block's rotation.
    pub(super) fn shifted_chain(
        &self,
        x: &[f64],
        q: &[f64],
        ctx: &SampleContext,
        v: &[f64],
        ops: &[usize],
    ) -> Frame {
        let mut f = self.chain(v, None, ops);
        if self.has_shift() {
            let device = self.chain(v, None, ops.get(..DEVICE_OPS).unwrap_or(ops));
            f.t += device.r * self.shift_at(x, q, ctx);
        }
        f
    }

    /// Whether the model has a shift effect (see [`Model::shift_at`]).
    pub(super) fn has_shift(&self) -> bool {
        !self.free_slots.shift.is_empty()
    }

    /// Frame at the end of `ops` (op indices in order); `before[i]` receives the frame before
    /// op `i` for the ops visited, and `on[i]` whether op `i` was visited.
    pub(super) fn chain(
        &self,
        values: &[f64],
        mut before: Option<(&mut Vec<Frame>, &mut Vec<bool>)>,
        ops: &[usize],
    ) -> Frame {
        let mut f = Frame::IDENTITY;
        if let Some((b, on)) = before.as_mut() {
            b.clear();
            b.resize(self.ops.len(), Frame::IDENTITY);
            on.clear();
            on.resize(self.ops.len(), false);
        }
        for &i in ops {
            let o = &self.ops[i];
            if let Some((b, on)) = before.as_mut() {
                b[i] = f;
                on[i] = true;
            }
            f.apply(o.kind, values[i], &o.fixed);
        }
        f
    }

    pub(super) fn chain_ops(&self, chain: usize) -> &[usize] {
        self.chains
            .get(chain)
            .or_else(|| self.chains.first())
            .map_or(&[], |c| c.as_slice())
    }

    /// [`Model::chain_ops`] of `chain` as measured in `session`.
    pub(super) fn session_ops(&self, chain: usize, session: usize) -> &[usize] {
        match self.session_chains.iter().find(|(s, _)| *s == session) {
            Some((_, chains)) => chains
                .get(chain)
                .or_else(|| chains.first())
                .map_or(&[], |c| c.as_slice()),
            None => self.chain_ops(chain),
        }
    }

    /// Chain `chain`'s tip frame in session `session`'s device frame at `x` and `q` (its
    /// position scaled by the device scale), in the neutral context (see [`Model::point_in`]).
    pub fn tip_in(&self, x: &[f64], q: &[f64], chain: usize, session: usize) -> Isometry3<f64> {
        let ctx = SampleContext::default();
        let mut f = self.with_prepared(x, chain, session, |p| p.frame(self, x, q, &ctx, None));
        f.t = self.grown(x, q, &ctx, (chain, session), f.t) * self.scale_factor(x, q, &ctx);
        f.to_iso()
    }

    /// Where target `k` is in the device frame at parameters `x` and joint values `q` (one per
    /// row), metres (the device scale applied), in the neutral context (no motion history,
    /// order 0: see [`Model::point_in`]).
    pub fn point(&self, x: &[f64], q: &[f64], target: usize) -> Vector3<f64> {
        self.point_in(x, q, &SampleContext::default(), target)
    }

    /// [`Model::point`] for a sample at `ctx` in the measurement sequence (what the
    /// effects of motion history and time see).
    pub fn point_in(
        &self,
        x: &[f64],
        q: &[f64],
        ctx: &SampleContext,
        target: usize,
    ) -> Vector3<f64> {
        // The device block's chain, whatever the session (see `prepared::DEVICE_BLOCK`).
        let chain = self.target_chain(target);
        let f = self.with_prepared(x, chain, DEVICE_BLOCK, |p| p.frame(self, x, q, ctx, None));
        let p = f.t + f.r * self.target_at(x, target);
        self.grown(x, q, ctx, (chain, DEVICE_BLOCK), p) * self.scale_factor(x, q, ctx)
    }

    /// `1 + s` of the device scale effects at `x` and `q` in the neutral context (1 without
    /// one): what multiplies a modelled position in the device frame.
    pub fn scale_at(&self, x: &[f64], q: &[f64]) -> f64 {
        self.scale_factor(x, q, &SampleContext::default())
    }

    /// `1 + g` of the robot growth effects at `x`, `q` and `ctx` (1 without one): what
    /// multiplies every position in the robot's base link frame.
    pub fn growth_at(&self, x: &[f64], q: &[f64], ctx: &SampleContext) -> f64 {
        self.growth_factor(x, q, ctx)
    }

    /// The first chain's tip frame in the device frame at `x` and `q` (its position scaled by
    /// the device scale).
    pub fn tip(&self, x: &[f64], q: &[f64]) -> Isometry3<f64> {
        self.tip_of(x, q, 0)
    }

    /// Chain `chain`'s tip frame in the device frame at `x` and `q` (its position scaled by the
    /// device scale).
    pub fn tip_of(&self, x: &[f64], q: &[f64], chain: usize) -> Isometry3<f64> {
        self.tip_of_in(x, q, &SampleContext::default(), chain)
    }

    /// [`Model::tip_of`] for a sample at `ctx` in the measurement sequence.
    pub fn tip_of_in(
        &self,
        x: &[f64],
        q: &[f64],
        ctx: &SampleContext,
        chain: usize,
    ) -> Isometry3<f64> {
        let mut v = Vec::with_capacity(self.ops.len());
        self.op_values(x, q, ctx, &mut v);
        let mut f = self.shifted_chain(x, q, ctx, &v, self.chain_ops(chain));
        f.t = self.grown(x, q, ctx, (chain, DEVICE_BLOCK), f.t) * self.scale_factor(x, q, ctx);
        f.to_iso()
    }

    /// The robot's own forward kinematics at `x` and `q` (the first chain's tip in the base
    /// link frame, without the device frame).
    pub fn robot_fk(&self, x: &[f64], q: &[f64]) -> Isometry3<f64> {
        self.robot_fk_of(x, q, 0)
    }

    /// Chain `chain`'s tip in the base link frame at `x` and `q` (without the device frame).
    pub fn robot_fk_of(&self, x: &[f64], q: &[f64], chain: usize) -> Isometry3<f64> {
        self.robot_fk_in(x, q, &SampleContext::default(), chain)
    }

    /// [`Model::robot_fk_of`] for a sample at `ctx` in the measurement sequence.
    pub fn robot_fk_in(
        &self,
        x: &[f64],
        q: &[f64],
        ctx: &SampleContext,
        chain: usize,
    ) -> Isometry3<f64> {
        let mut v = Vec::with_capacity(self.ops.len());
        self.op_values(x, q, ctx, &mut v);
        let ops = self.chain_ops(chain);
        let mut f = self.chain(&v, None, ops.get(DEVICE_OPS..).unwrap_or(&[]));
        // The shift in the base link frame, then the growth about its origin (the frame's own),
        // as in the device frame.
        f.t += self.shift_at(x, q, ctx);
        f.t *= self.growth_factor(x, q, ctx);
        f.to_iso()
    }

    /// The calibrated table at `x`: nominal values plus errors, base and tool with their small
    /// motions, and every Hayati tilt in its row's [`dh_core::DhRow::beta`] (the placement
    /// this model uses, so the table's FK is the model's exactly). Effects cannot be expressed
    /// in DH and are never in the table.
    ///
    /// Tilts are not folded into plain DH values: that is exact too, but a tilt `beta` at link
    /// length `a` puts the common normal about `a / beta` away (kilometres for a tenth of a
    /// milliradian), the ill conditioning Hayati avoids.
    ///
    /// For a tree this is the trunk (its tool the nominal branch point); see
    /// [`Model::tree_at`] for the whole tree.
    pub fn table_at(&self, x: &[f64]) -> DhTable {
        self.tree_at(x).trunk().clone()
    }

    /// The calibrated tree at `x`, as [`Model::table_at`] describes. Branch mounts carry their
    /// small motions.
    pub fn tree_at(&self, x: &[f64]) -> DhTree {
        let mut trunk = self.tree.trunk().clone();
        trunk.base = self.pose_at(x, Block::Base);
        if self.tree.branches().is_empty() {
            trunk.tool = self.pose_at(x, Block::Tool);
        }
        let mut branches: Vec<Branch> = self.tree.branches().to_vec();
        for (b, br) in branches.iter_mut().enumerate() {
            br.table.base = self.pose_at(x, Block::Mount(b));
        }
        for (c, p) in self.parameters.iter().enumerate() {
            let v = x.get(c).copied().unwrap_or(0.0);
            if let Block::Joint(g) = p.block {
                let (t, i) = self.tree.place(g);
                let table = match t {
                    None => &mut trunk,
                    Some(b) => &mut branches[b].table,
                };
                let row = &mut table.rows[i];
                match p.field {
                    Field::A => row.a += v,
                    Field::Alpha => row.alpha += v,
                    Field::D => row.d += v,
                    Field::Theta => row.theta += v,
                    Field::Beta => row.beta += v,
                    _ => {}
                }
            }
        }
        if branches.is_empty() {
            DhTree::serial(&trunk)
        } else {
            // The rows and names are the nominal tree's, which was valid.
            DhTree::new(trunk, branches).unwrap_or_else(|_| self.tree.clone())
        }
    }
}
