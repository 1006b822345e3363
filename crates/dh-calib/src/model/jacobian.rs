//! Residuals (model minus measured) of one observation and their analytic Jacobian.
//!
//! A point gives 3 residuals (metres); a pose 6: the position difference (metres) and
//! `w · log(R_model R_measuredᵀ)` (metres per radian times radians), `w` the model's
//! orientation scale for a tip pose ([`Observation::Pose`]) and the sample's own weight for a
//! target frame ([`Observation::TargetPose`]). The
//! orientation part's derivative uses SO(3)'s inverse left Jacobian (Barfoot, *State
//! Estimation for Robotics*, 2017, eq. 7.77b).

use nalgebra::{Isometry3, Matrix3, Rotation3, UnitQuaternion, Vector3};

use super::ops::{Frame, OpKind};
use super::prepared::PreparedChain;
use super::{Block, Field, Model, Observation, Observed};

impl Model {
    /// Residuals of one observation (model minus measured) into `out` (3 or 6 values).
    pub fn residuals(&self, x: &[f64], obs: &Observed, out: &mut [f64]) {
        let chain = self.observation_chain(obs);
        let f = self.with_prepared(x, chain, obs.session, |p| {
            p.frame(self, x, &obs.q, &obs.context, None)
        });
        let s = self.scale_factor(x, &obs.q, &obs.context);
        let growth = self.growth_of(x, obs, chain, false);
        self.write_residuals(x, &f, (s, growth), obs, out);
    }

    /// The robot growth of an observation on `chain`: its factor `1 + Σ g` and the base
    /// origin it scales about, in the device frame of the observation's session; `None`
    /// without a growth effect, or at a factor of exactly 1 unless `always` (a growth
    /// parameter's column needs the origin).
    fn growth_of(
        &self,
        x: &[f64],
        obs: &Observed,
        chain: usize,
        always: bool,
    ) -> Option<(f64, Vector3<f64>)> {
        if !self.has_growth() {
            return None;
        }
        let g = self.growth_factor(x, &obs.q, &obs.context);
        (always || g != 1.0).then(|| (g, self.base_origin(x, chain, obs.session)))
    }

    /// Whether `columns` hold a parameter of a robot growth effect.
    fn growth_column(&self, columns: &[usize]) -> bool {
        self.free_slots.growth.iter().any(|&e| {
            let params = &self.effects[e].params;
            columns.iter().any(|c| params.contains(c))
        })
    }

    fn observation_chain(&self, obs: &Observed) -> usize {
        match &obs.observation {
            Observation::Point { target, .. } | Observation::TargetPose { target, .. } => {
                self.target_chain(*target)
            }
            Observation::Pose(_) => 0,
        }
    }

    fn write_residuals(
        &self,
        x: &[f64],
        f: &Frame,
        (scale, growth): (f64, Option<(f64, Vector3<f64>)>),
        obs: &Observed,
        out: &mut [f64],
    ) -> Vector3<f64> {
        let grow = |p: Vector3<f64>| match growth {
            Some((g, o)) if g != 1.0 => o + (p - o) * g,
            _ => p,
        };
        match &obs.observation {
            Observation::Point { target, point } => {
                let p = grow(f.t + f.r * self.target_at(x, *target)) * scale;
                let r = p - point;
                out[..3].copy_from_slice(r.as_slice());
                Vector3::zeros()
            }
            Observation::Pose(m) => {
                let r = grow(f.t) * scale - m.translation.vector;
                out[..3].copy_from_slice(r.as_slice());
                orientation_residual(&f.r, m, self.orientation_scale, out)
            }
            Observation::TargetPose {
                target,
                pose,
                weight,
            } => {
                let p = grow(f.t + f.r * self.target_at(x, *target)) * scale;
                let r = p - pose.translation.vector;
                out[..3].copy_from_slice(r.as_slice());
                let (rk, _) = self.target_rotation_axes(x, *target);
                orientation_residual(&(f.r * rk), pose, *weight, out)
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
        let chain = self.observation_chain(obs);
        self.with_prepared(x, chain, obs.session, |prepared| {
            SCRATCH.with(|scratch| {
                let mut scratch = scratch.borrow_mut();
                let Scratch { starts, grad } = &mut *scratch;
                let work = (starts, grad);
                self.jacobian_with(x, obs, columns, residuals, jacobian, prepared, work, false);
            })
        });
    }

    /// The derivative of an observation's frame by the parameters `columns` (row-major,
    /// `6 × columns.len()`): rows 0-2 the position in the device frame (metres per unit of
    /// the parameter, the device scale applied), rows 3-5 the small rotation about the device
    /// frame's axes (radians per unit), unweighted. `obs` is a [`Observation::TargetPose`] (a
    /// target's frame; a point target's is the tip's orientation) or an
    /// [`Observation::Pose`] (the tip frame); its measured pose is not used. What a
    /// prediction's uncertainty propagates ([`crate::predict`]); the same screw motions as
    /// [`Model::jacobian`]. A [`Observation::Point`]'s rotation rows are the tip's.
    pub fn frame_jacobian(&self, x: &[f64], obs: &Observed, columns: &[usize], out: &mut [f64]) {
        let chain = self.observation_chain(obs);
        let mut residuals = [0.0; 6];
        out.fill(0.0);
        self.with_prepared(x, chain, obs.session, |prepared| {
            SCRATCH.with(|scratch| {
                let mut scratch = scratch.borrow_mut();
                let Scratch { starts, grad } = &mut *scratch;
                let work = (starts, grad);
                self.jacobian_with(x, obs, columns, &mut residuals, out, prepared, work, true);
            })
        });
    }

    /// [`Model::jacobian`] on a prepared chain, with its work space (frames at the steps'
    /// starts and an effect's gradient, reused between calls on one thread); `raw`: the
    /// rotation rows are the plain rotation derivative ([`Model::frame_jacobian`]).
    #[allow(clippy::too_many_arguments)]
    fn jacobian_with(
        &self,
        x: &[f64],
        obs: &Observed,
        columns: &[usize],
        residuals: &mut [f64],
        jacobian: &mut [f64],
        prepared: &PreparedChain,
        (starts, grad): (&mut Vec<Frame>, &mut Vec<f64>),
        raw: bool,
    ) {
        let f = prepared.frame(self, x, &obs.q, &obs.context, Some(starts));
        let scale = self.scale_factor(x, &obs.q, &obs.context);
        let chain = self.observation_chain(obs);
        let growth = self.growth_of(x, obs, chain, self.growth_column(columns));
        let phi = self.write_residuals(x, &f, (scale, growth), obs, residuals);
        let (point, target, weight) = match &obs.observation {
            Observation::Point { target, .. } => {
                (f.t + f.r * self.target_at(x, *target), Some(*target), None)
            }
            Observation::Pose(_) => (f.t, None, Some(self.orientation_scale)),
            Observation::TargetPose { target, weight, .. } => (
                f.t + f.r * self.target_at(x, *target),
                Some(*target),
                Some(*weight),
            ),
        };
        let jl_inv = match weight {
            _ if raw => Matrix3::identity(),
            Some(w) => left_jacobian_inverse(&phi) * w,
            None => Matrix3::zeros(),
        };
        // The shift effects' translation in the device frame: ops after the device block do
        // not turn it (it is along gravity in the base link frame whatever the joints).
        let shifted = if self.has_shift() {
            prepared.device_rotation() * self.shift_at(x, &obs.q, &obs.context)
        } else {
            Vector3::zeros()
        };
        // The target's orientation axes in the device frame (zero for a point target).
        let target_axes = target.map(|t| self.target_rotation_axes(x, t).1.map(|a| f.r * a));
        // With a robot growth `G` about the base origin `o`: the grown point, the factor, and
        // the device ops (which move the grown robot rigidly; every other op moves a point of
        // the robot, so its motion grows by `G`).
        let (g_factor, origin) = growth.unwrap_or((1.0, Vector3::zeros()));
        let grown = match growth {
            Some((g, o)) if g != 1.0 => o + (point - o) * g,
            _ => point,
        };
        let nc = columns.len();
        let rows = obs.observation.residual_count();
        for (k, &c) in columns.iter().enumerate() {
            let mut dp = Vector3::zeros();
            let mut dw = Vector3::zeros();
            let op_motion = |o: usize, g: f64, dp: &mut Vector3<f64>, dw: &mut Vector3<f64>| {
                // `None`: not on this observation's chain (the other arm of a tree).
                let Some(place) = prepared.place(o) else {
                    return;
                };
                // The frame before op `o`: the start of its step times its place in the step.
                let start = &starts[place.step];
                // A device op moves the grown robot rigidly, its shift included; any other op
                // moves a point of the robot (not the shift, which is after the chain in the
                // base link frame), and its motion grows by `G`.
                let (moved, grows) = if place.device {
                    (grown, 1.0)
                } else {
                    (point - shifted, g_factor)
                };
                match self.ops[o].kind {
                    OpKind::Trans(_) => *dp += (start.r * place.axis) * (g * grows),
                    OpKind::Rot(_) => {
                        let w = start.r * place.axis;
                        let origin = start.t + start.r * place.origin;
                        *dp += w.cross(&(moved - origin)) * (g * grows);
                        *dw += w * g;
                    }
                    OpKind::Fixed => {}
                }
            };
            match self.parameters.get(c).map(|p| p.block) {
                Some(Block::Target(t)) if target == Some(t) => match self.parameters[c].field {
                    Field::X => dp = f.r.column(0) * g_factor,
                    Field::Y => dp = f.r.column(1) * g_factor,
                    Field::Z => dp = f.r.column(2) * g_factor,
                    // An orientation turns the target's frame about its origin: the position
                    // stays, the orientation moves about the axis.
                    field => {
                        let i = match field {
                            Field::Rx => 0,
                            Field::Ry => 1,
                            _ => 2,
                        };
                        if let Some(axes) = &target_axes {
                            dw = axes[i];
                        }
                    }
                },
                Some(Block::Target(_)) => {}
                Some(Block::Effect(e)) => {
                    let slot = &self.effects[e];
                    grad.resize(slot.params.len(), 0.0);
                    let params = x.get(slot.params.clone()).unwrap_or(&[]);
                    slot.effect.gradient_in(&obs.q, &obs.context, params, grad);
                    let g = grad.get(c - slot.params.start).copied().unwrap_or(0.0);
                    match (slot.op, slot.shift) {
                        (Some(op), _) => op_motion(op, g, &mut dp, &mut dw),
                        // A shift: along its direction in the device frame, grown with the robot.
                        (None, Some(dir)) => dp = prepared.device_rotation() * dir * (g * g_factor),
                        // Robot growth: the position from the base origin, ungrown (the shift in).
                        (None, None) if self.free_slots.growth.contains(&e) => {
                            dp = (point - origin) * g;
                        }
                        // Device scale: the unscaled position, undoing the factor below.
                        (None, None) if scale != 0.0 => dp = grown * (g / scale),
                        (None, None) => {}
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
            if rows == 6 || raw {
                let dr = jl_inv * dw;
                for i in 0..3 {
                    jacobian[(3 + i) * nc + k] = dr[i];
                }
            }
        }
    }
}

/// Writes `weight · log(R_model R_measuredᵀ)` into `out[3..6]` and returns the rotation
/// vector `log(R_model R_measuredᵀ)` (device frame, radians).
fn orientation_residual(
    model: &Matrix3<f64>,
    measured: &Isometry3<f64>,
    weight: f64,
    out: &mut [f64],
) -> Vector3<f64> {
    let rel = Rotation3::from_matrix_unchecked(
        model * measured.rotation.to_rotation_matrix().matrix().transpose(),
    );
    let phi = UnitQuaternion::from_rotation_matrix(&rel).scaled_axis();
    for k in 0..3 {
        out[3 + k] = weight * phi[k];
    }
    phi
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

/// Work space of [`Model::residuals`] and [`Model::jacobian`], one per thread, so that the
/// millions of calls of a large fit allocate nothing.
#[derive(Default)]
struct Scratch {
    /// The frame at the start of each step of the prepared chain.
    starts: Vec<Frame>,
    grad: Vec<f64>,
}

thread_local! {
    static SCRATCH: std::cell::RefCell<Scratch> = std::cell::RefCell::new(Scratch::default());
}
