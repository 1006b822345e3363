//! Targets as full frames: the orientation of a 6-DoF probe (a tracker's probe, an optical
//! marker body) on the tool, for [`Observation::TargetPose`](super::Observation::TargetPose).
//!
//! # Frames and parameters
//! Target `k`'s frame in the tip (tool) frame is `(t_k, R_k)` with
//!
//! ```text
//! R_k = R_ref,k · Rx(rx) · Ry(ry) · Rz(rz)
//! ```
//!
//! (radians, a small rotation expressed in the target's own reference frame, as the `base.*`
//! and `tool.*` blocks are), its parameters `target.<name>.rx|ry|rz` in [`Block::Target`].
//! They exist only for targets given an orientation with [`Model::add_target_orientation`]:
//! a model of point data has none, so its parameter list is unchanged by this module.

use std::ops::Range;

use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};

use super::ops::{Axis, Frame, OpKind};
use super::{Block, Field, Model, SampleContext, Unit};

/// A target's orientation: its first parameter (`rx`, then `ry`, `rz`) and its reference
/// rotation in the tip frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct TargetFrame {
    pub(super) first: usize,
    pub(super) reference: Matrix3<f64>,
}

impl Model {
    /// Makes target `k` a full frame: appends its orientation parameters
    /// `target.<name>.rx|ry|rz` (radians, see the module docs) and returns their range; the
    /// reference rotation starts at identity (set it with [`Model::set_target_rotation`]).
    /// `None` when `k` is out of range; a target that already has them returns its range.
    pub fn add_target_orientation(&mut self, k: usize) -> Option<Range<usize>> {
        self.revision = super::prepared::next_revision();
        let name = self.targets.get(k)?.0.clone();
        if let Some(range) = self.target_orientation(k) {
            return Some(range);
        }
        let first = self.parameters.len();
        for (f, s) in [(Field::Rx, "rx"), (Field::Ry, "ry"), (Field::Rz, "rz")] {
            self.push_param(
                format!("target.{name}.{s}"),
                Block::Target(k),
                f,
                Unit::Angle,
            );
        }
        self.target_frames[k] = Some(TargetFrame {
            first,
            reference: Matrix3::identity(),
        });
        Some(first..first + 3)
    }

    /// The range of target `k`'s orientation parameters, `None` when it is a point.
    pub fn target_orientation(&self, k: usize) -> Option<Range<usize>> {
        self.target_frames
            .get(k)
            .copied()
            .flatten()
            .map(|f| f.first..f.first + 3)
    }

    /// Sets target `k`'s reference rotation in the tip frame; ignored when the target has no
    /// orientation.
    pub fn set_target_rotation(&mut self, k: usize, rotation: &UnitQuaternion<f64>) {
        self.revision = super::prepared::next_revision();
        if let Some(Some(f)) = self.target_frames.get_mut(k) {
            f.reference = *rotation.to_rotation_matrix().matrix();
        }
    }

    /// Target `k`'s rotation in the tip frame at `x` (identity for a point target).
    pub fn target_rotation_at(&self, x: &[f64], k: usize) -> UnitQuaternion<f64> {
        let (r, _) = self.target_rotation_axes(x, k);
        UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r))
    }

    /// Target `k`'s rotation in the tip frame at `x` and the axes (tip frame, unit vectors)
    /// about which its `rx`, `ry` and `rz` turn it: `∂R_k/∂rx = [a_0]× R_k` and so on, the
    /// exact derivatives of the module docs' product.
    pub(super) fn target_rotation_axes(
        &self,
        x: &[f64],
        k: usize,
    ) -> (Matrix3<f64>, [Vector3<f64>; 3]) {
        let Some(Some(tf)) = self.target_frames.get(k) else {
            return (Matrix3::identity(), [Vector3::zeros(); 3]);
        };
        let mut f = Frame {
            r: tf.reference,
            t: Vector3::zeros(),
        };
        let mut axes = [Vector3::zeros(); 3];
        for (i, a) in [Axis::X, Axis::Y, Axis::Z].into_iter().enumerate() {
            axes[i] = f.r.column(i).into_owned();
            let v = x.get(tf.first + i).copied().unwrap_or(0.0);
            f.apply(OpKind::Rot(a), v, &Frame::IDENTITY);
        }
        (f.r, axes)
    }

    /// Target `k`'s frame in session `session`'s device frame at `x`, joint values `q` and
    /// place in the sequence `ctx`: its position as [`Model::point_in`] gives it (metres, the
    /// device scale applied), its rotation the tip's times [`Model::target_rotation_at`] (the
    /// scale does not turn it).
    pub fn target_pose_in(
        &self,
        x: &[f64],
        q: &[f64],
        ctx: &SampleContext,
        target: usize,
        session: usize,
    ) -> Isometry3<f64> {
        let mut v = Vec::with_capacity(self.ops.len());
        self.op_values(x, q, ctx, &mut v);
        let f = self.shifted_chain(
            x,
            q,
            ctx,
            &v,
            self.session_ops(self.target_chain(target), session),
        );
        let p = (f.t + f.r * self.target_at(x, target)) * self.scale_factor(x, q, ctx);
        let (rk, _) = self.target_rotation_axes(x, target);
        Isometry3::from_parts(
            Translation3::from(p),
            UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(f.r * rk)),
        )
    }

    /// Moves target `k`'s orientation offsets of `x` into its reference (the caller zeroes
    /// them, see [`Model::rebase`]).
    pub(super) fn rebase_target_rotation(&mut self, x: &[f64], k: usize) {
        self.revision = super::prepared::next_revision();
        let (r, _) = self.target_rotation_axes(x, k);
        if let Some(Some(f)) = self.target_frames.get_mut(k) {
            f.reference = r;
        }
    }
}
