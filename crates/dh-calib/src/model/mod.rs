//! The parametrised measurement model: a DH table with errors on every parameter, the
//! measuring device's frame, the measured targets, and room for non-geometric effects.
//!
//! # Frames
//! Everything is expressed in the measuring device's frame ("world"). A measured point is
//!
//! ```text
//! p = T_device_base · FK(q) · t_k,    FK(q) = base · A_1(q_1) ⋯ A_n(q_n) · tool
//! ```
//!
//! with `T_device_base` the pose of the robot's base link frame in the device frame, `FK` the
//! table's forward kinematics (its `base` and `tool` transforms included) and `t_k` target `k`'s
//! position in the tip (tool) frame. A measured pose (for comparing with another model of the
//! same robot, where the "device" is the base link frame itself) is `T_device_base · FK(q)`.
//!
//! # Parameters
//! Every parameter is an offset from a reference model (`x = 0` is the reference):
//! - `<joint>.a`, `<joint>.alpha`, `<joint>.d`, `<joint>.theta`: errors of the row's DH values
//!   (metres, radians), added to the nominal values;
//! - `<joint>.beta`: the Hayati-Mirmirani tilt of a near-parallel pair (radians, nominal 0); the
//!   pair's `d` error is then not a parameter (see [`PairParametrisation`]);
//! - `base.x|y|z|rx|ry|rz`: `base = base_nominal · Tr(x, y, z) · Rx(rx) Ry(ry) Rz(rz)`, a small
//!   motion expressed in DH frame 0 (metres, radians); `tool.*` likewise in the tip frame;
//! - `device.x|y|z|rx|ry|rz`: `T_device_base = T_ref · Tr(x, y, z) · Rx(rx) Ry(ry) Rz(rz)`, a
//!   small motion of the robot expressed in its own base link frame, so that `device.z` is a
//!   lift along the robot's base z axis and `device.rz` a turn about it;
//! - `target.<name>.x|y|z`: offset of the target's position in the tip frame (metres);
//! - `target.<name>.rx|ry|rz`: only for a target measured as a 6-DoF pose
//!   ([`Observation::TargetPose`], [`Model::add_target_orientation`]): a small rotation of its
//!   frame (radians, see `target_frame`), appended after the parameters present so far;
//! - `<branch>.base.x|y|z|rx|ry|rz`: for a tree ([`crate::tree`]), the small motion of branch
//!   `<branch>`'s mount in the trunk's branch point frame, laid out as `base.*`;
//! - effect parameters, named by their [`Effect`].
//!
//! # Trees
//! [`Model::new_tree`] models a [`DhTree`]: every target rides on one chain (the trunk for a
//! serial robot, else one branch), rows shared by several chains (the trunk's) have one set of
//! parameters, and joint values are given per row of the tree, in its joint order. A tree's
//! trunk tool and branch tools are fixed at nominal (with point measurements each is aliased
//! with its chain's targets); [`Observation::Pose`] refers to the first chain's tip.
//!
//! # Device scale
//! An [`Effect`] whose field is [`EffectField::Scale`] multiplies every modelled position in
//! the device frame by `1 + delta` (about the device's origin): a measuring device whose length
//! unit is off. Several such effects add: the factor is `1 + Σ delta` (a constant `scale` and a
//! `drift` in time together).
//!
//! # Robot growth
//! An [`Effect`] whose field is [`EffectField::Growth`] scales the robot instead: a modelled
//! position `p` (device frame) becomes `o + (1 + Σ delta) (p − o)`, `o` the base link's origin
//! in the device frame (of the sample's session), before the device scale applies. A robot whose
//! links all lengthen (a warm-up) is this; a device scale is not, unless the device sits at the
//! robot's base.
//!
//! # Sample order
//! Every [`Observed`] carries a [`SampleContext`]: the direction of each joint's last motion
//! and the pose's place in the measurement sequence. Effects of the joint values alone ignore
//! it; effects of the motion history or of time ([`crate::effects_order`]) read it through
//! [`Effect::delta_in`].
//!
//! # Hayati-Mirmirani parametrisation
//! Consecutive joint axes within [`ModelOptions::hayati_threshold`] of parallel at the nominal
//! zero pose make the DH `d` (where the common normal sits along the axis) ill conditioned: a
//! tilt of 0.01 degree moves it by metres. For such a pair the row that holds the pair's link
//! gets a rotation `Ry(beta)` and the `d` error that locates the common normal is dropped
//! (S. Hayati and M. Mirmirani, "Improving the absolute positioning accuracy of robot
//! manipulators", J. Robotic Systems 2(4), 1985, eq. 3):
//! - standard convention, joints `i`, `i+1` (rows `i`, `i+1`): row `i` becomes
//!   `A_i = Rz(theta_i + q_i) Tz(d_i) Tx(a_i) Rx(alpha_i) Ry(beta_i)` and `<joint_i>.d` is
//!   dropped;
//! - modified convention: row `i+1` becomes
//!   `A_{i+1} = Rx(alpha_i) Tx(a_i) Ry(beta_i) Rz(theta_{i+1} + q_{i+1}) Tz(d_{i+1})` and
//!   `<joint_i>.d` is dropped.
//!
//! In both, `beta` turns about the y axis of the frame that sits on the later joint's axis
//! just before that joint, at the far end of the common normal. The parameter is named after
//! the row that holds it (`<joint_i>.beta` standard, `<joint_{i+1}>.beta` modified), and it is
//! exactly [`dh_core::DhRow::beta`] of that row: a table whose rows carry tilts is modelled
//! with them as nominal values, and [`Model::table_at`] writes the estimate there.

mod access;
mod build;
mod effect;
mod eval;
mod jacobian;
mod observation;
mod ops;
mod options;
mod params;
mod prepared;
mod problem;
mod target_frame;

use nalgebra::{Isometry3, Vector3, Vector6};

pub use effect::{Effect, EffectField, GearRatio};
pub use observation::{Observation, Observed, SampleContext};
pub use options::{ModelOptions, PairParametrisation, NEAR_PARALLEL};
pub use params::{Block, Field, Parameter, Unit};
pub use problem::{ModelProblem, SubsetProblem};

use crate::fit::CalibError;
use crate::tree::DhTree;
use dh_core::DhTable;
use ops::{EffectSlot, Op, RowOps};

/// Indices into [`Model`]'s effect slots of the effects that change no op.
#[derive(Clone, Debug, Default)]
struct FreeSlots {
    /// [`EffectField::Scale`] effects (the device scale).
    scale: Vec<usize>,
    /// [`EffectField::Growth`] effects (the robot growth).
    growth: Vec<usize>,
    /// [`EffectField::Shift`] effects.
    shift: Vec<usize>,
}

/// The parametrised measurement model (see the module docs for frames and parameters).
#[derive(Clone, Debug)]
pub struct Model {
    nominal: DhTable,
    tree: DhTree,
    length_scale: f64,
    orientation_scale: f64,
    ops: Vec<Op>,
    rows: Vec<RowOps>,
    /// Op indices of each chain, device block first.
    chains: Vec<Vec<usize>>,
    parameters: Vec<Parameter>,
    param_op: Vec<Option<usize>>,
    targets: Vec<(String, Vector3<f64>)>,
    target_chain: Vec<usize>,
    target_params: usize,
    effects: Vec<EffectSlot>,
    /// The effect slots without an op, by field, in slot order: what every evaluation scans
    /// for the device scale, the robot growth and the shifts (kept by [`Model::add_effect`],
    /// so that a model with many candidate effects does not ask each for its field per sample).
    free_slots: FreeSlots,
    pairs: Vec<PairParametrisation>,
    /// Per session with its own device block: the session index and its op indices of each
    /// chain (its block instead of the device block).
    session_chains: Vec<(usize, Vec<Vec<usize>>)>,
    /// Per target: its orientation parameters when it is a full frame (see
    /// [`Model::add_target_orientation`]).
    target_frames: Vec<Option<target_frame::TargetFrame>>,
    /// Renewed by every change of the model (see `prepared`): what the per-thread cache of
    /// prepared chains is keyed by, with the parameter vector.
    revision: u64,
}

pub(super) fn finite(what: &str, v: f64) -> Result<f64, CalibError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(CalibError::Core(dh_core::CoreError::NonFinite {
            what: what.into(),
            value: v,
        }))
    }
}

/// The pose `xyz`, `rpy` of an isometry as a 6-vector (URDF convention, see
/// [`dh_core::pose::to_xyz_rpy`]).
pub fn xyz_rpy(pose: &Isometry3<f64>) -> Vector6<f64> {
    let (t, r) = dh_core::pose::to_xyz_rpy(pose);
    Vector6::new(t[0], t[1], t[2], r[0], r[1], r[2])
}
