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

use std::fmt;
use std::ops::Range;
use std::sync::Arc;

use dh_core::{Convention, DhTable, JointKind};
use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3, Vector6};

use crate::fit::{CalibError, Problem};
use crate::tree::{Branch, DhTree};

/// Physical kind of a parameter, which decides its column scale.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Unit {
    /// Metres.
    Length,
    /// Radians.
    Angle,
    /// Defined by the effect that owns the parameter.
    Other,
}

/// Which part of the model a parameter belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Block {
    /// The device frame (`T_device_base`).
    Device,
    /// The device frame of measurement session `s` (index into
    /// [`crate::data::Measurements::sessions`]) when it is not the first calibration session,
    /// which uses [`Block::Device`] (see [`crate::sessions`]).
    Session(usize),
    /// The table's base transform.
    Base,
    /// A row of the table (index into its rows).
    Joint(usize),
    /// The table's tool transform.
    Tool,
    /// A tree branch's mount (index into the tree's branches).
    Mount(usize),
    /// A target (index into the target list).
    Target(usize),
    /// An effect (index in the order added).
    Effect(usize),
}

/// Which quantity of its block a parameter is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Field {
    /// Translation along x (metres).
    X,
    /// Translation along y (metres).
    Y,
    /// Translation along z (metres).
    Z,
    /// Rotation about x (radians).
    Rx,
    /// Rotation about y (radians).
    Ry,
    /// Rotation about z (radians).
    Rz,
    /// DH link length error (metres).
    A,
    /// DH link twist error (radians).
    Alpha,
    /// DH link offset error (metres).
    D,
    /// DH joint angle offset error (radians).
    Theta,
    /// Hayati-Mirmirani tilt about y (radians).
    Beta,
    /// The effect's `k`-th parameter.
    Effect(usize),
}

/// One estimable quantity of a [`Model`].
#[derive(Clone, Debug, PartialEq)]
pub struct Parameter {
    /// Name, part of the report's contract (see the module docs).
    pub name: String,
    /// What it belongs to.
    pub block: Block,
    /// Which quantity.
    pub field: Field,
    /// Its unit.
    pub unit: Unit,
}

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
    /// [`Model::tilt_rows`]).
    Beta,
    /// The measuring device's length scale: modelled positions are multiplied by `1 + delta`.
    /// The effect's [`Effect::joint`] is ignored.
    Scale,
}

/// A non-geometric error source: a change of one row's `theta`, `d`, `alpha` or tilt, or of the
/// device's scale, that depends on the joint values and on the effect's own parameters (gear
/// ratio errors, joint compliance, coupling between joints). Added to a model with
/// [`Model::add_effect`]; its parameters become extra Jacobian columns.
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
    /// `∂delta_in/∂params` (see [`Effect::delta_in`]); by default [`Effect::gradient`].
    fn gradient_in(&self, q: &[f64], context: &SampleContext, params: &[f64], out: &mut [f64]) {
        let _ = context;
        self.gradient(q, params, out)
    }
    /// Column scales: the tip motion (metres) that a unit change of each parameter causes,
    /// roughly, in a robot of characteristic length `length`.
    fn scales(&self, length: f64) -> Vec<f64>;
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

/// How one pair of consecutive joints is parametrised.
#[derive(Clone, Debug, PartialEq)]
pub struct PairParametrisation {
    /// The earlier joint.
    pub first: String,
    /// The later joint.
    pub second: String,
    /// Angle between the two axes at the nominal zero pose, folded to `[0, pi/2]` (radians).
    pub angle: f64,
    /// `true` when the pair uses Hayati-Mirmirani (`beta` instead of a `d` error).
    pub hayati: bool,
    /// The row whose `beta` parameter the pair adds (when `hayati`).
    pub beta_row: Option<String>,
    /// The row whose `d` error the pair drops (when `hayati`).
    pub dropped_d: Option<String>,
}

/// Options of [`Model::new`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelOptions {
    /// Pairs of consecutive axes within this angle of parallel (radians) at the nominal zero
    /// pose use Hayati-Mirmirani. Default 1 degree.
    pub hayati_threshold: f64,
    /// Characteristic length (metres) that scales angle columns; `None` uses
    /// [`DhTable::size`].
    pub length_scale: Option<f64>,
    /// Metres per radian of orientation residual for pose measurements; `None` uses the
    /// length scale.
    pub orientation_scale: Option<f64>,
}

impl ModelOptions {
    /// Default Hayati threshold: 1 degree.
    pub const DEFAULT_HAYATI_THRESHOLD: f64 = std::f64::consts::PI / 180.0;
}

impl Default for ModelOptions {
    fn default() -> Self {
        Self {
            hayati_threshold: Self::DEFAULT_HAYATI_THRESHOLD,
            length_scale: None,
            orientation_scale: None,
        }
    }
}

/// What is measured in one sample.
#[derive(Clone, Debug, PartialEq)]
pub enum Observation {
    /// A target's position in the device frame (3 residuals: model minus measured, metres).
    Point {
        /// Target index.
        target: usize,
        /// Measured position (metres).
        point: Vector3<f64>,
    },
    /// The tip frame's pose in the device frame (6 residuals: position difference in metres,
    /// then `orientation_scale · log(R_model R_measuredᵀ)` as a rotation vector).
    Pose(Isometry3<f64>),
}

/// Where a sample sits in the measurement sequence (the file's sample order): what effects
/// of the motion history and of time see besides the joint values
/// ([`Effect::delta_in`]). Built by [`crate::effects_order::sequence_contexts`]; the default
/// (no direction, order 0) is the neutral context of a pose outside any sequence (a
/// prediction, a synthetic sample).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct SampleContext {
    /// Per row (tree joint order): the sign of the joint's last motion before this pose,
    /// `-1`, `0` (not moved yet) or `+1`; empty means 0 for every row.
    pub direction: Vec<f64>,
    /// The pose's place in the sequence, normalised to `[0, 1]` (0 the first pose, 1 the
    /// last; repeats of one pose share it). Dimensionless.
    pub order: f64,
}

impl SampleContext {
    /// The direction of row `row` (0 when not given).
    pub fn direction_of(&self, row: usize) -> f64 {
        self.direction.get(row).copied().unwrap_or(0.0)
    }
}

/// One sample: joint values in row order, its place in the sequence and what was measured
/// there.
#[derive(Clone, Debug, PartialEq)]
pub struct Observed {
    /// One value per table row (radians or metres).
    pub q: Vec<f64>,
    /// The measurement.
    pub observation: Observation,
    /// Measurement session (index into [`crate::data::Measurements::sessions`]): which device
    /// frame measured it. Sessions without their own block ([`Model::add_session`]) use the
    /// `device` block.
    pub session: usize,
    /// Its place in the measurement sequence (neutral by default).
    pub context: SampleContext,
}

impl Observed {
    /// A sample in the neutral context.
    pub fn new(q: Vec<f64>, observation: Observation) -> Self {
        Self {
            q,
            observation,
            session: 0,
            context: SampleContext::default(),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Axis {
    X = 0,
    Y = 1,
    Z = 2,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum OpKind {
    Trans(Axis),
    Rot(Axis),
    Fixed,
}

/// A rotation matrix and translation: cheaper to compose than quaternions in the hot loop.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Frame {
    r: Matrix3<f64>,
    t: Vector3<f64>,
}

impl Frame {
    const IDENTITY: Frame = Frame {
        r: Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
        t: Vector3::new(0.0, 0.0, 0.0),
    };

    fn from_iso(iso: &Isometry3<f64>) -> Self {
        Self {
            r: *iso.rotation.to_rotation_matrix().matrix(),
            t: iso.translation.vector,
        }
    }

    fn to_iso(self) -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::from(self.t),
            UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(self.r)),
        )
    }

    fn apply(&mut self, kind: OpKind, v: f64, fixed: &Frame) {
        match kind {
            // A zero motion is the identity (bit for bit: `sin 0 = 0`, `cos 0 = 1`): most ops
            // of a model (tilts, device and tool angles, untouched offsets) sit at zero.
            OpKind::Trans(_) | OpKind::Rot(_) if v == 0.0 => {}
            OpKind::Trans(a) => self.t += self.r.column(a as usize) * v,
            OpKind::Rot(a) => {
                let (i, j) = match a {
                    Axis::X => (1, 2),
                    Axis::Y => (2, 0),
                    Axis::Z => (0, 1),
                };
                let (s, c) = v.sin_cos();
                let ci = self.r.column(i).into_owned();
                let cj = self.r.column(j).into_owned();
                self.r.set_column(i, &(ci * c + cj * s));
                self.r.set_column(j, &(cj * c - ci * s));
            }
            OpKind::Fixed => {
                self.t += self.r * fixed.t;
                self.r *= fixed.r;
            }
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
struct Op {
    kind: OpKind,
    value: f64,
    fixed: Frame,
    joint: Option<usize>,
    param: Option<usize>,
}

#[derive(Clone, Debug)]
struct EffectSlot {
    effect: Arc<dyn Effect>,
    params: Range<usize>,
    /// The op the effect changes; `None` for the device scale.
    op: Option<usize>,
}

/// Op indices of one row.
#[derive(Clone, Copy, Debug, PartialEq)]
struct RowOps {
    theta: usize,
    d: usize,
    alpha: usize,
    beta: Option<usize>,
}

const POSE_FIELDS: [(Field, &str, OpKind); 6] = [
    (Field::X, "x", OpKind::Trans(Axis::X)),
    (Field::Y, "y", OpKind::Trans(Axis::Y)),
    (Field::Z, "z", OpKind::Trans(Axis::Z)),
    (Field::Rx, "rx", OpKind::Rot(Axis::X)),
    (Field::Ry, "ry", OpKind::Rot(Axis::Y)),
    (Field::Rz, "rz", OpKind::Rot(Axis::Z)),
];

/// Consecutive axes within this angle of parallel (radians, 5 degrees) that do not use
/// Hayati-Mirmirani get a tilt about `y` held at zero, which an [`EffectField::Beta`] effect
/// (the `parallel_tilt` candidate) can free.
pub const NEAR_PARALLEL: f64 = 5.0 * std::f64::consts::PI / 180.0;

/// Ops 0..7 are the device block.
const DEVICE_OPS: usize = 7;

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
    pairs: Vec<PairParametrisation>,
    /// Per session with its own device block: the session index and its op indices of each
    /// chain (its block instead of the device block).
    session_chains: Vec<(usize, Vec<Vec<usize>>)>,
}

fn finite(what: &str, v: f64) -> Result<f64, CalibError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(CalibError::Core(dh_core::CoreError::NonFinite {
            what: what.into(),
            value: v,
        }))
    }
}

/// Per table row: does it carry a Hayati `beta` parameter, a zero tilt placeholder, and is
/// its `d` error dropped.
#[derive(Clone, Copy, Debug, Default)]
struct RowPlan {
    beta: bool,
    placeholder: bool,
    drop_d: bool,
}

fn plan_table(
    table: &DhTable,
    threshold: f64,
) -> Result<(Vec<PairParametrisation>, Vec<RowPlan>), CalibError> {
    let n = table.rows.len();
    let pairs = classify_pairs(table, threshold)?;
    let mut plan = vec![RowPlan::default(); n];
    for (i, p) in pairs.iter().enumerate() {
        let beta_row = match table.convention {
            Convention::Standard => i,
            Convention::Modified => i + 1,
        };
        if p.hayati {
            plan[i].drop_d = true;
            plan[beta_row].beta = true;
        } else if p.angle <= NEAR_PARALLEL {
            plan[beta_row].placeholder = true;
        }
    }
    Ok((pairs, plan))
}

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
            pairs,
            session_chains: Vec::new(),
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
    fn push_row(&mut self, table: &DhTable, i: usize, g: usize, plan: RowPlan) {
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

    fn push_param(&mut self, name: String, block: Block, field: Field, unit: Unit) -> usize {
        self.parameters.push(Parameter {
            name,
            block,
            field,
            unit,
        });
        self.param_op.push(None);
        self.parameters.len() - 1
    }

    fn push_op(
        &mut self,
        kind: OpKind,
        value: f64,
        joint: Option<usize>,
        param: Option<usize>,
    ) -> usize {
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

    fn push_pose_block(&mut self, prefix: &str, block: Block, reference: &Isometry3<f64>) {
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
        let label = effect.label();
        if self.effects.iter().any(|s| s.effect.label() == label) {
            return Err(CalibError::BadOption {
                what: format!("effect '{label}'"),
                reason: "expected each effect once, found it twice".into(),
            });
        }
        let op = if effect.field() == EffectField::Scale {
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
                EffectField::Scale => ops.theta,
            })
        };
        let e = self.effects.len();
        let start = self.parameters.len();
        for (k, name) in effect.parameter_names().into_iter().enumerate() {
            self.push_param(name, Block::Effect(e), Field::Effect(k), Unit::Other);
        }
        let params = start..self.parameters.len();
        self.effects.push(EffectSlot {
            effect,
            params: params.clone(),
            op,
        });
        Ok(params)
    }

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

    /// Rows (tree joint order) with a zero tilt about `y` that an [`EffectField::Beta`] effect
    /// can free: the rows that would carry `beta` of a pair within [`NEAR_PARALLEL`] of
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

    /// The reference device frame `T_device_base` (at `x = 0`).
    pub fn device(&self) -> Isometry3<f64> {
        self.ops[0].fixed.to_iso()
    }

    /// Sets the reference device frame `T_device_base`.
    pub fn set_device(&mut self, device: &Isometry3<f64>) {
        self.ops[0].fixed = Frame::from_iso(device);
    }

    /// Sets target `k`'s reference position in the tip frame (metres); ignored when out of
    /// range.
    pub fn set_target(&mut self, k: usize, position: Vector3<f64>) {
        if let Some(t) = self.targets.get_mut(k) {
            t.1 = position;
        }
    }

    /// Moves the device and target offsets of `x` into the reference and zeroes them.
    pub fn rebase(&mut self, x: &mut [f64]) {
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

    fn op_values(&self, x: &[f64], q: &[f64], ctx: &SampleContext, out: &mut Vec<f64>) {
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
    fn scale_factor(&self, x: &[f64], q: &[f64], ctx: &SampleContext) -> f64 {
        1.0 + self
            .effects
            .iter()
            .filter(|s| s.op.is_none())
            .map(|slot| {
                let params = x.get(slot.params.clone()).unwrap_or(&[]);
                slot.effect.delta_in(q, ctx, params)
            })
            .sum::<f64>()
    }

    /// Frame at the end of `ops` (op indices in order); `before[i]` receives the frame before
    /// op `i` for the ops visited, and `on[i]` whether op `i` was visited.
    fn chain(
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

    fn chain_ops(&self, chain: usize) -> &[usize] {
        self.chains
            .get(chain)
            .or_else(|| self.chains.first())
            .map_or(&[], |c| c.as_slice())
    }

    /// [`Model::chain_ops`] of `chain` as measured in `session`.
    fn session_ops(&self, chain: usize, session: usize) -> &[usize] {
        match self.session_chains.iter().find(|(s, _)| *s == session) {
            Some((_, chains)) => chains
                .get(chain)
                .or_else(|| chains.first())
                .map_or(&[], |c| c.as_slice()),
            None => self.chain_ops(chain),
        }
    }

    /// Gives measurement session `session` its own device frame `T_device_base` (reference
    /// `frame`, plus six parameters `session.<name>.x|y|z|rx|ry|rz` laid out as `device.*`),
    /// appended to the parameters. Observations of other sessions keep the `device` block.
    /// Adding a session twice is a no-op.
    pub fn add_session(&mut self, session: usize, name: &str, frame: &Isometry3<f64>) {
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

    /// Chain `chain`'s tip frame in session `session`'s device frame at `x` and `q` (its
    /// position scaled by the device scale), in the neutral context (see [`Model::point_in`]).
    pub fn tip_in(&self, x: &[f64], q: &[f64], chain: usize, session: usize) -> Isometry3<f64> {
        let mut v = Vec::with_capacity(self.ops.len());
        let ctx = SampleContext::default();
        self.op_values(x, q, &ctx, &mut v);
        let mut f = self.chain(&v, None, self.session_ops(chain, session));
        f.t *= self.scale_factor(x, q, &ctx);
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
        let mut v = Vec::with_capacity(self.ops.len());
        self.op_values(x, q, ctx, &mut v);
        let f = self.chain(&v, None, self.chain_ops(self.target_chain(target)));
        (f.t + f.r * self.target_at(x, target)) * self.scale_factor(x, q, ctx)
    }

    /// `1 + s` of the device scale effects at `x` and `q` in the neutral context (1 without
    /// one): what multiplies a modelled position in the device frame.
    pub fn scale_at(&self, x: &[f64], q: &[f64]) -> f64 {
        self.scale_factor(x, q, &SampleContext::default())
    }

    /// The first chain's tip frame in the device frame at `x` and `q` (its position scaled by
    /// the device scale).
    pub fn tip(&self, x: &[f64], q: &[f64]) -> Isometry3<f64> {
        self.tip_of(x, q, 0)
    }

    /// Chain `chain`'s tip frame in the device frame at `x` and `q` (its position scaled by the
    /// device scale).
    pub fn tip_of(&self, x: &[f64], q: &[f64], chain: usize) -> Isometry3<f64> {
        let ctx = SampleContext::default();
        let mut v = Vec::with_capacity(self.ops.len());
        self.op_values(x, q, &ctx, &mut v);
        let mut f = self.chain(&v, None, self.chain_ops(chain));
        f.t *= self.scale_factor(x, q, &ctx);
        f.to_iso()
    }

    /// The robot's own forward kinematics at `x` and `q` (the first chain's tip in the base
    /// link frame, without the device frame).
    pub fn robot_fk(&self, x: &[f64], q: &[f64]) -> Isometry3<f64> {
        self.robot_fk_of(x, q, 0)
    }

    /// Chain `chain`'s tip in the base link frame at `x` and `q` (without the device frame).
    pub fn robot_fk_of(&self, x: &[f64], q: &[f64], chain: usize) -> Isometry3<f64> {
        let mut v = Vec::with_capacity(self.ops.len());
        self.op_values(x, q, &SampleContext::default(), &mut v);
        let ops = self.chain_ops(chain);
        self.chain(&v, None, ops.get(DEVICE_OPS..).unwrap_or(&[]))
            .to_iso()
    }

    /// Residuals of one observation (model minus measured) into `out` (3 or 6 values).
    pub fn residuals(&self, x: &[f64], obs: &Observed, out: &mut [f64]) {
        SCRATCH.with(|scratch| {
            let mut scratch = scratch.borrow_mut();
            let v = &mut scratch.values;
            self.op_values(x, &obs.q, &obs.context, v);
            let f = self.chain(
                v,
                None,
                self.session_ops(self.observation_chain(obs), obs.session),
            );
            let s = self.scale_factor(x, &obs.q, &obs.context);
            self.write_residuals(x, &f, s, obs, out);
        });
    }

    fn observation_chain(&self, obs: &Observed) -> usize {
        match &obs.observation {
            Observation::Point { target, .. } => self.target_chain(*target),
            Observation::Pose(_) => 0,
        }
    }

    fn write_residuals(
        &self,
        x: &[f64],
        f: &Frame,
        scale: f64,
        obs: &Observed,
        out: &mut [f64],
    ) -> Vector3<f64> {
        match &obs.observation {
            Observation::Point { target, point } => {
                let p = (f.t + f.r * self.target_at(x, *target)) * scale;
                let r = p - point;
                out[..3].copy_from_slice(r.as_slice());
                Vector3::zeros()
            }
            Observation::Pose(m) => {
                let r = f.t * scale - m.translation.vector;
                out[..3].copy_from_slice(r.as_slice());
                let rel = Rotation3::from_matrix_unchecked(
                    f.r * m.rotation.to_rotation_matrix().matrix().transpose(),
                );
                let phi = UnitQuaternion::from_rotation_matrix(&rel).scaled_axis();
                for k in 0..3 {
                    out[3 + k] = self.orientation_scale * phi[k];
                }
                phi
            }
        }
    }

    /// Residuals and the analytic Jacobian of one observation for the parameters `columns`
    /// (row-major, `residual count × columns.len()`).
    ///
    /// Each parameter moves one elementary transform of the chain; with `F` the frame before
    /// it, `w` = `F`'s axis (rotation) or `t` = `F`'s axis (translation), and `P` the measured
    /// point in the device frame, `∂P = w × (P − F.origin)` or `∂P = t` (screw motion), and
    /// the orientation moves by `w` or not at all. Orientation residuals use the exact
    /// derivative of the logarithm map, `J_l⁻¹(φ) w`.
    pub fn jacobian(
        &self,
        x: &[f64],
        obs: &Observed,
        columns: &[usize],
        residuals: &mut [f64],
        jacobian: &mut [f64],
    ) {
        SCRATCH.with(|scratch| {
            let mut scratch = scratch.borrow_mut();
            let Scratch {
                values,
                before,
                on,
                grad,
            } = &mut *scratch;
            self.jacobian_with(
                x, obs, columns, residuals, jacobian, values, before, on, grad,
            );
        });
    }

    /// [`Model::jacobian`] with its work space (reused between calls on one thread).
    #[allow(clippy::too_many_arguments)]
    fn jacobian_with(
        &self,
        x: &[f64],
        obs: &Observed,
        columns: &[usize],
        residuals: &mut [f64],
        jacobian: &mut [f64],
        v: &mut Vec<f64>,
        before: &mut Vec<Frame>,
        on: &mut Vec<bool>,
        grad: &mut Vec<f64>,
    ) {
        self.op_values(x, &obs.q, &obs.context, v);
        let ops = self.session_ops(self.observation_chain(obs), obs.session);
        let f = self.chain(v, Some((before, on)), ops);
        let scale = self.scale_factor(x, &obs.q, &obs.context);
        let phi = self.write_residuals(x, &f, scale, obs, residuals);
        let (point, target, pose) = match &obs.observation {
            Observation::Point { target, .. } => {
                (f.t + f.r * self.target_at(x, *target), Some(*target), false)
            }
            Observation::Pose(_) => (f.t, None, true),
        };
        let jl_inv = if pose {
            left_jacobian_inverse(&phi) * self.orientation_scale
        } else {
            Matrix3::zeros()
        };
        let nc = columns.len();
        let rows = if pose { 6 } else { 3 };
        for (k, &c) in columns.iter().enumerate() {
            let mut dp = Vector3::zeros();
            let mut dw = Vector3::zeros();
            let op_motion = |o: usize, g: f64, dp: &mut Vector3<f64>, dw: &mut Vector3<f64>| {
                if !on[o] {
                    // Not on this observation's chain (the other arm of a tree).
                    return;
                }
                let fr = &before[o];
                match self.ops[o].kind {
                    OpKind::Trans(a) => *dp += fr.r.column(a as usize) * g,
                    OpKind::Rot(a) => {
                        let w = fr.r.column(a as usize).into_owned();
                        *dp += w.cross(&(point - fr.t)) * g;
                        *dw += w * g;
                    }
                    OpKind::Fixed => {}
                }
            };
            match self.parameters.get(c).map(|p| p.block) {
                Some(Block::Target(t)) if target == Some(t) => {
                    let axis = (c - self.target_params) % 3;
                    dp = f.r.column(axis).into_owned();
                }
                Some(Block::Target(_)) => {}
                Some(Block::Effect(e)) => {
                    let slot = &self.effects[e];
                    grad.resize(slot.params.len(), 0.0);
                    let params = x.get(slot.params.clone()).unwrap_or(&[]);
                    slot.effect.gradient_in(&obs.q, &obs.context, params, grad);
                    let g = grad.get(c - slot.params.start).copied().unwrap_or(0.0);
                    match slot.op {
                        Some(op) => op_motion(op, g, &mut dp, &mut dw),
                        // Device scale: the unscaled position, undoing the factor below.
                        None if scale != 0.0 => dp = point * (g / scale),
                        None => {}
                    }
                }
                Some(_) => {
                    if let Some(o) = self.param_op[c] {
                        op_motion(o, 1.0, &mut dp, &mut dw);
                    }
                }
                None => {}
            }
            for i in 0..3 {
                jacobian[i * nc + k] = dp[i] * scale;
            }
            if rows == 6 {
                let dr = jl_inv * dw;
                for i in 0..3 {
                    jacobian[(3 + i) * nc + k] = dr[i];
                }
            }
        }
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

fn unit_of(kind: OpKind) -> Unit {
    match kind {
        OpKind::Rot(_) => Unit::Angle,
        _ => Unit::Length,
    }
}

/// Inverse of SO(3)'s left Jacobian at rotation vector `phi` (Barfoot, *State Estimation for
/// Robotics*, 2017, eq. 7.77b in its left form).
fn left_jacobian_inverse(phi: &Vector3<f64>) -> Matrix3<f64> {
    let th = phi.norm();
    let k = phi.cross_matrix();
    let c = if th < 1e-4 {
        1.0 / 12.0 + th * th / 720.0
    } else {
        1.0 / (th * th) - (1.0 + th.cos()) / (2.0 * th * th.sin())
    };
    Matrix3::identity() - k * 0.5 + k * k * c
}

fn classify_pairs(table: &DhTable, threshold: f64) -> Result<Vec<PairParametrisation>, CalibError> {
    let n = table.rows.len();
    let frames = table.frames(&vec![0.0; n])?;
    let shift = usize::from(table.convention == Convention::Modified);
    let axis = |i: usize| frames[i + shift].rotation * Vector3::z();
    let mut out = Vec::new();
    for i in 0..n.saturating_sub(1) {
        let (u, w) = (axis(i), axis(i + 1));
        let angle = u.cross(&w).norm().atan2(u.dot(&w).abs());
        let hayati = angle <= threshold;
        let beta_row = match table.convention {
            Convention::Standard => i,
            Convention::Modified => i + 1,
        };
        out.push(PairParametrisation {
            first: table.rows[i].name.clone(),
            second: table.rows[i + 1].name.clone(),
            angle,
            hayati,
            beta_row: hayati.then(|| table.rows[beta_row].name.clone()),
            dropped_d: hayati.then(|| table.rows[i].name.clone()),
        });
    }
    Ok(out)
}

/// A model with observations: the [`Problem`] that [`crate::fit::solve`] minimises.
#[derive(Clone, Copy, Debug)]
pub struct ModelProblem<'a> {
    /// The model.
    pub model: &'a Model,
    /// The samples.
    pub observations: &'a [Observed],
}

/// A model with samples reachable by block: [`ModelProblem`] (all of them) and
/// [`SubsetProblem`] (some, by index) share one [`Problem`] implementation through it.
trait Samples: Sync {
    fn model(&self) -> &Model;
    fn count(&self) -> usize;
    fn sample(&self, block: usize) -> Option<&Observed>;
}

impl Samples for ModelProblem<'_> {
    fn model(&self) -> &Model {
        self.model
    }
    fn count(&self) -> usize {
        self.observations.len()
    }
    fn sample(&self, block: usize) -> Option<&Observed> {
        self.observations.get(block)
    }
}

impl<S: Samples> Problem for S {
    fn parameter_count(&self) -> usize {
        self.model().parameter_count()
    }
    fn block_count(&self) -> usize {
        self.count()
    }
    fn block_size(&self, block: usize) -> usize {
        match self.sample(block).map(|o| &o.observation) {
            Some(Observation::Pose(_)) => 6,
            _ => 3,
        }
    }
    fn residuals(&self, x: &[f64], block: usize, out: &mut [f64]) {
        if let Some(o) = self.sample(block) {
            self.model().residuals(x, o, out);
        }
    }
    fn jacobian(
        &self,
        x: &[f64],
        block: usize,
        columns: &[usize],
        residuals: &mut [f64],
        jacobian: &mut [f64],
    ) {
        if let Some(o) = self.sample(block) {
            self.model().jacobian(x, o, columns, residuals, jacobian);
        }
    }
}

/// Work space of [`Model::residuals`] and [`Model::jacobian`], one per thread, so that the
/// millions of calls of a large fit allocate nothing.
#[derive(Default)]
struct Scratch {
    values: Vec<f64>,
    before: Vec<Frame>,
    on: Vec<bool>,
    grad: Vec<f64>,
}

thread_local! {
    static SCRATCH: std::cell::RefCell<Scratch> = std::cell::RefCell::new(Scratch::default());
}

/// Some of a model's observations, by index (a cross-validation fold's training samples): the
/// [`Problem`] of [`ModelProblem`] over `observations[i]` for `i` in `subset`, without copies.
#[derive(Clone, Copy, Debug)]
pub struct SubsetProblem<'a> {
    /// The model.
    pub model: &'a Model,
    /// All samples.
    pub observations: &'a [Observed],
    /// Indices into `observations` of the samples in the problem, one block each.
    pub subset: &'a [usize],
}

impl Samples for SubsetProblem<'_> {
    fn model(&self) -> &Model {
        self.model
    }
    fn count(&self) -> usize {
        self.subset.len()
    }
    fn sample(&self, block: usize) -> Option<&Observed> {
        self.subset
            .get(block)
            .and_then(|&i| self.observations.get(i))
    }
}

/// The pose `xyz`, `rpy` of an isometry as a 6-vector (URDF convention, see
/// [`dh_core::pose::to_xyz_rpy`]).
pub fn xyz_rpy(pose: &Isometry3<f64>) -> Vector6<f64> {
    let (t, r) = dh_core::pose::to_xyz_rpy(pose);
    Vector6::new(t[0], t[1], t[2], r[0], r[1], r[2])
}
