//! A serial chain of a URDF: its joint axis lines at `q = 0` and its forward kinematics.

use dh_core::pose::from_xyz_rpy;
use dh_core::{CoreError, JointAxis, JointKind, Limits, Line, Mimic};
use nalgebra::{Isometry3, Quaternion, Unit, UnitQuaternion, Vector3};

use crate::check::unit_axis;
use crate::model::UrdfModel;
use crate::robot::{JointType, Warning};
use crate::UrdfError;

/// A moving joint of a [`Chain`] that follows another joint (URDF `<mimic>`):
/// `q = multiplier · q_driver + offset`.
#[derive(Clone, Debug, PartialEq)]
pub struct MimicJoint {
    /// The following joint.
    pub joint: String,
    /// The joint it follows.
    pub driver: String,
    /// Gear ratio (URDF default 1).
    pub multiplier: f64,
    /// Offset in the follower's unit, radians or metres (URDF default 0).
    pub offset: f64,
    /// Whether the driver is itself a moving joint of the chain; if not, the follower's value
    /// is free as far as the chain can tell.
    pub driver_in_chain: bool,
}

/// One moving joint with every fixed transform since the previous one folded in.
#[derive(Clone, Debug)]
struct Segment {
    /// Pose of this joint's frame in the previous moving joint's child link frame (the base
    /// link frame for the first).
    origin: Isometry3<f64>,
    /// Unit axis in the joint frame.
    axis: Unit<Vector3<f64>>,
    kind: JointKind,
    /// `origin.rotation · (0, axis)` as a quaternion product: the origin's rotation followed
    /// by the turn by `q` about the axis is `cos(q/2) origin.rotation + sin(q/2) turn`, one
    /// quaternion sum where [`UnitQuaternion::from_axis_angle`] and a product were.
    turn: Quaternion<f64>,
}

impl Segment {
    fn new(origin: Isometry3<f64>, axis: Unit<Vector3<f64>>, kind: JointKind) -> Segment {
        let turn = origin.rotation.quaternion() * Quaternion::from_imag(axis.into_inner());
        Segment {
            origin,
            axis,
            kind,
            turn,
        }
    }

    /// `t · origin · motion(q)` into `t`.
    #[inline]
    fn step(&self, t: &mut Isometry3<f64>, q: f64) {
        match self.kind {
            JointKind::Revolute => {
                t.translation.vector += t.rotation * self.origin.translation.vector;
                let (s, c) = dh_core::math::sin_cos(0.5 * q);
                let local = self.origin.rotation.quaternion() * c + self.turn * s;
                t.rotation = UnitQuaternion::new_unchecked(t.rotation.quaternion() * local);
            }
            JointKind::Prismatic => {
                *t *= self.origin;
                apply_motion(t, self, q);
            }
        }
    }
}

/// A serial chain of a URDF from a base link down to a tip link.
///
/// Frames and units: every pose and line is in the base link's frame; lengths in metres,
/// angles in radians. Joint values are one per moving joint (revolute, continuous,
/// prismatic), base to tip, in the order of [`Chain::axes`]; mimic joints take their own value
/// like any other.
#[derive(Clone, Debug)]
pub struct Chain {
    base: String,
    tip: String,
    axes: Vec<JointAxis>,
    segments: Vec<Segment>,
    /// Tip link frame in the last moving joint's child link frame.
    tail: Isometry3<f64>,
    tip_pose: Isometry3<f64>,
    folded_fixed: Vec<String>,
    joints: Vec<String>,
    mimics: Vec<MimicJoint>,
}

// A chain is taken from a model: here, so that the model knows nothing of chains.
impl UrdfModel {
    /// Chooses a serial chain from `base` down to `tip` (link names).
    ///
    /// `base` defaults to the root link (for an MJCF model whose world holds one body on a free
    /// joint with joints below it, to that body: the chain starts below the free joint). `tip` defaults to the end of the arm below the base:
    /// the leaf at the end of the longest run of moving joints, preferring a tool-like fixed
    /// link (`tool0`, `flange`...) off the last moving link, and the hand link when the
    /// longest runs are the fingers of one gripper (the rule is in the `tip` module's docs).
    /// Fixed joints between them are folded into the neighbouring transforms; every revolute,
    /// continuous and prismatic joint becomes one axis of the chain. Frames: everything the
    /// chain returns is in the base link's frame, metres and radians.
    ///
    /// # Errors
    /// - [`UrdfError::UnknownLink`] for a base or tip the URDF does not define (with close
    ///   names, or every link when there are few);
    /// - [`UrdfError::SeveralLeaves`] when no tip is given and the longest runs of moving
    ///   joints below the base end at several places (two arms, a humanoid);
    /// - the fault of a joint on the chain (its type, numbers, limits or mimic:
    ///   [`UrdfError::Parse`], [`UrdfError::UnsupportedJointType`], [`UrdfError::NonFinite`],
    ///   [`UrdfError::OutOfRange`], [`UrdfError::ZeroAxis`], [`UrdfError::MissingLimit`],
    ///   [`UrdfError::LimitsReversed`], [`UrdfError::ControlCharacterInName`],
    ///   [`UrdfError::UnknownMimicJoint`], [`UrdfError::MimicItself`],
    ///   [`UrdfError::MimicCycle`], [`UrdfError::MimicOfFixed`]);
    /// - [`UrdfError::Disconnected`] when the tip is not below the base;
    /// - [`UrdfError::JointTypeInChain`] for a floating or planar joint between them;
    /// - [`UrdfError::NoMovingJoint`] when only fixed joints (or none) join them;
    /// - [`UrdfError::Geometry`] when finite inputs overflow while composing the chain.
    pub fn chain(&self, base: Option<&str>, tip: Option<&str>) -> Result<Chain, UrdfError> {
        let base = match base {
            Some(name) => self.find_link(name, "base")?,
            None => self.default_base,
        };
        let tip = match tip {
            Some(name) => self.find_link(name, "tip")?,
            None => self.default_tip(base)?,
        };
        let path = self.path(base, tip)?;
        // A fault of a joint's own content is an error on the chain (a warning off it).
        if let Some(fault) = path
            .iter()
            .filter_map(|&k| self.robot.joints.get(k))
            .find_map(|j| j.fault.as_ref())
        {
            return Err(fault.clone());
        }
        Chain::build(self, base, tip, &path)
    }

    /// The warnings that concern `chain` (taken from this model): those of
    /// [`UrdfModel::warnings`], with the faults of joints off the chain (a joint on it has
    /// none, or the chain would have been refused).
    pub fn warnings_for(&self, chain: &Chain) -> Vec<Warning> {
        let on: std::collections::HashSet<&str> =
            chain.joints().iter().map(String::as_str).collect();
        let note = format!(
            "ignored: not on the chain from '{}' to '{}'",
            chain.base(),
            chain.tip()
        );
        self.collect_warnings(|j| !on.contains(j), &note)
    }
}

impl Chain {
    /// Builds the chain along `path` (joint indices from `base` down to `tip`).
    pub(crate) fn build(
        model: &UrdfModel,
        base: usize,
        tip: usize,
        path: &[usize],
    ) -> Result<Chain, UrdfError> {
        let base_name = model.link_name(base).to_owned();
        let tip_name = model.link_name(tip).to_owned();
        let mut pose = Isometry3::identity();
        let mut pending = Isometry3::identity();
        let mut axes = Vec::new();
        let mut segments = Vec::new();
        let mut folded_fixed = Vec::new();
        let mut joints = Vec::with_capacity(path.len());
        let mut mimics = Vec::new();
        let mut on_path = vec![false; model.robot.joints.len()];
        for &k in path {
            if let Some(slot) = on_path.get_mut(k) {
                *slot = true;
            }
        }
        let in_path = |driver: &str| {
            model.joint_index_of(driver).is_some_and(|d| {
                on_path.get(d).copied().unwrap_or(false)
                    && model
                        .robot
                        .joints
                        .get(d)
                        .and_then(|j| j.kind)
                        .is_some_and(JointType::is_moving)
            })
        };
        for &k in path {
            let Some(joint) = model.robot.joints.get(k) else {
                continue;
            };
            let line = Some(joint.line);
            joints.push(joint.name.clone());
            let origin = from_xyz_rpy(joint.origin.xyz, joint.origin.rpy);
            let Some(joint_type) = joint.kind else {
                // A joint without a known type carries a fault, refused before building.
                return Err(joint
                    .fault
                    .clone()
                    .unwrap_or(UrdfError::UnsupportedJointType {
                        joint: joint.name.clone(),
                        found: String::new(),
                        line,
                    }));
            };
            let kind = match joint_type {
                JointType::Fixed => {
                    pending *= origin;
                    pose *= origin;
                    folded_fixed.push(joint.name.clone());
                    continue;
                }
                JointType::Revolute | JointType::Continuous => JointKind::Revolute,
                JointType::Prismatic => JointKind::Prismatic,
                JointType::Floating | JointType::Planar | JointType::Ball | JointType::Free => {
                    return Err(UrdfError::JointTypeInChain {
                        joint: joint.name.clone(),
                        found: joint_type.label(),
                        base: base_name,
                        tip: tip_name,
                        line,
                    });
                }
            };
            let axis = unit_axis(joint.axis).ok_or_else(|| UrdfError::ZeroAxis {
                joint: joint.name.clone(),
                axis: joint.axis,
                line,
            })?;
            let frame = pose * origin;
            let line_in_base = Line::through(frame.translation.vector, frame.rotation * *axis)
                .map_err(|cause| UrdfError::Geometry {
                    joint: joint.name.clone(),
                    cause,
                })?;
            let limits = match (joint_type, joint.limit) {
                (JointType::Continuous, _) | (_, None) => None,
                // Only URDF 1.2 lets infinities through validation: "no limit".
                (_, Some((lower, upper))) => {
                    (lower.is_finite() && upper.is_finite()).then_some(Limits { lower, upper })
                }
            };
            let mimic = joint.mimic.as_ref().map(|m| Mimic {
                joint: m.joint.clone(),
                multiplier: m.multiplier,
                offset: m.offset,
            });
            if let Some(m) = &mimic {
                mimics.push(MimicJoint {
                    joint: joint.name.clone(),
                    driver: m.joint.clone(),
                    multiplier: m.multiplier,
                    offset: m.offset,
                    driver_in_chain: in_path(&m.joint),
                });
            }
            axes.push(JointAxis {
                name: joint.name.clone(),
                kind,
                line: line_in_base,
                limits,
                mimic,
            });
            segments.push(Segment::new(pending * origin, axis, kind));
            pending = Isometry3::identity();
            pose = frame;
        }
        if axes.is_empty() {
            return Err(UrdfError::NoMovingJoint {
                base: base_name,
                tip: tip_name,
            });
        }
        let finite = pose.translation.vector.iter().all(|v| v.is_finite())
            && pose.rotation.coords.iter().all(|v| v.is_finite());
        if !finite {
            return Err(UrdfError::Geometry {
                joint: joints.last().cloned().unwrap_or_default(),
                cause: CoreError::NonFinite {
                    what: format!("pose of tip link '{tip_name}'"),
                    value: f64::INFINITY,
                },
            });
        }
        Ok(Chain {
            base: base_name,
            tip: tip_name,
            axes,
            segments,
            tail: pending,
            tip_pose: pose,
            folded_fixed,
            joints,
            mimics,
        })
    }

    /// The base link: the frame of every pose and line of the chain.
    pub fn base(&self) -> &str {
        &self.base
    }

    /// The tip link.
    pub fn tip(&self) -> &str {
        &self.tip
    }

    /// The moving joints (revolute, continuous, prismatic) in chain order, as axis lines in the
    /// base link frame at `q = 0` (metres).
    ///
    /// The line of a joint passes through the origin of its joint frame (parent link pose times
    /// joint origin) along the joint frame's rotation applied to the normalised URDF axis, so
    /// its direction is the joint's positive sense. Revolute joints carry their limits
    /// (radians), continuous ones none, prismatic ones theirs (metres); under URDF 1.2 an
    /// omitted (infinite) limit gives `None`. Mimic joints carry their `<mimic>` with the URDF
    /// defaults (multiplier 1, offset 0) filled in.
    pub fn axes(&self) -> &[JointAxis] {
        &self.axes
    }

    /// The tip link's pose in the base link frame at `q = 0` (metres, unit quaternion).
    pub fn tip_pose(&self) -> Isometry3<f64> {
        self.tip_pose
    }

    /// URDF forward kinematics, the oracle: the tip link's pose in the base link frame.
    ///
    /// `q` holds one value per moving joint in the order of [`Chain::axes`] (radians for
    /// revolute and continuous joints, metres for prismatic ones); mimic joints take the value
    /// given, not one computed from their driver. Each joint contributes
    /// `origin(xyz, rpy) · motion(q)`, with `motion` the rotation by `q` about the normalised
    /// axis or the translation `q · axis` (ROS URDF joint specification); fixed joints are
    /// precomputed into their neighbours, a revolute joint's origin rotation and its turn are one
    /// quaternion sum (half-angle sine and cosine from [`dh_core::math::sin_cos`]), and the call
    /// allocates nothing.
    ///
    /// A missing value reads as 0 and extra values are ignored; [`Chain::try_fk`] refuses both.
    pub fn fk(&self, q: &[f64]) -> Isometry3<f64> {
        let mut t = Isometry3::identity();
        for (i, seg) in self.segments.iter().enumerate() {
            seg.step(&mut t, q.get(i).copied().unwrap_or(0.0));
        }
        t * self.tail
    }

    /// [`Chain::fk`], refusing a `q` of the wrong length.
    ///
    /// # Errors
    /// [`UrdfError::JointCount`] when `q.len()` differs from the number of moving joints.
    pub fn try_fk(&self, q: &[f64]) -> Result<Isometry3<f64>, UrdfError> {
        self.check_len(q)?;
        Ok(self.fk(q))
    }

    /// Axis lines of the moving joints in the base link frame at joint values `q` (same order
    /// and units as [`Chain::fk`]); at `q = 0` these are the lines of [`Chain::axes`].
    ///
    /// # Errors
    /// [`UrdfError::JointCount`] when `q` has the wrong length; [`UrdfError::Geometry`] when a
    /// value is NaN or infinite.
    pub fn axis_lines(&self, q: &[f64]) -> Result<Vec<Line>, UrdfError> {
        self.check_len(q)?;
        let mut t = Isometry3::identity();
        let mut lines = Vec::with_capacity(self.segments.len());
        for ((seg, &qi), ax) in self.segments.iter().zip(q).zip(&self.axes) {
            t *= seg.origin;
            let line =
                Line::through(t.translation.vector, t.rotation * *seg.axis).map_err(|cause| {
                    UrdfError::Geometry {
                        joint: ax.name.clone(),
                        cause,
                    }
                })?;
            lines.push(line);
            apply_motion(&mut t, seg, qi);
        }
        Ok(lines)
    }

    /// The URDF's own frames along the chain at joint values `q` (same order and units as
    /// [`Chain::fk`]), in the base link frame: the child link frame of each moving joint after
    /// its motion (fixed joints folded in, as in [`Chain::fk`]), then the tip link frame, which
    /// is `fk(q)`. For drawing the links as the URDF places them.
    ///
    /// # Errors
    /// [`UrdfError::JointCount`] when `q` has the wrong length.
    pub fn link_poses(&self, q: &[f64]) -> Result<Vec<Isometry3<f64>>, UrdfError> {
        self.check_len(q)?;
        let mut t = Isometry3::identity();
        let mut poses = Vec::with_capacity(self.segments.len() + 1);
        for (seg, &qi) in self.segments.iter().zip(q) {
            seg.step(&mut t, qi);
            poses.push(t);
        }
        poses.push(t * self.tail);
        Ok(poses)
    }

    /// Names of the fixed joints between base and tip, folded into their neighbours, in chain
    /// order.
    pub fn folded_fixed(&self) -> &[String] {
        &self.folded_fixed
    }

    /// Names of every joint between base and tip (fixed ones included), in chain order.
    pub fn joints(&self) -> &[String] {
        &self.joints
    }

    /// The moving joints of the chain that follow another joint, in chain order.
    pub fn mimics(&self) -> &[MimicJoint] {
        &self.mimics
    }

    fn check_len(&self, q: &[f64]) -> Result<(), UrdfError> {
        if q.len() == self.segments.len() {
            Ok(())
        } else {
            Err(UrdfError::JointCount {
                expected: self.segments.len(),
                found: q.len(),
            })
        }
    }
}

/// `t ← t · motion(q)` without building the motion as an isometry.
fn apply_motion(t: &mut Isometry3<f64>, seg: &Segment, q: f64) {
    match seg.kind {
        JointKind::Revolute => t.rotation *= UnitQuaternion::from_axis_angle(&seg.axis, q),
        JointKind::Prismatic => t.translation.vector += t.rotation * (seg.axis.into_inner() * q),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn unit_axis_survives_huge_and_refuses_zero() {
        assert!(unit_axis([0.0; 3]).is_none());
        let u = unit_axis([1e300, 1e300, 0.0]).unwrap();
        assert_relative_eq!(u.x, std::f64::consts::FRAC_1_SQRT_2, epsilon = 1e-15);
        let u = unit_axis([0.0, 0.0, -3.0]).unwrap();
        assert_relative_eq!(*u, -Vector3::z(), epsilon = 1e-15);
    }

    /// The child link frames sit on their joints' axes at any `q` (a joint frame's origin is
    /// its child link's), the last pose is `fk(q)`, a fixed joint mid-chain is folded in.
    #[test]
    fn link_poses_follow_the_axes_and_end_at_the_tip() {
        let urdf = r#"<robot name="r"><link name="b"/><link name="l1"/><link name="f"/>
          <link name="l2"/><link name="t"/>
          <joint name="j1" type="revolute"><parent link="b"/><child link="l1"/>
            <origin xyz="0 0 0.3" rpy="0.2 0 0"/><axis xyz="0 0 1"/>
            <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
          <joint name="fx" type="fixed"><parent link="l1"/><child link="f"/>
            <origin xyz="0.1 0 0" rpy="0 0.3 0"/></joint>
          <joint name="j2" type="prismatic"><parent link="f"/><child link="l2"/>
            <origin xyz="0 0.2 0"/><axis xyz="1 0 0"/>
            <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
          <joint name="tt" type="fixed"><parent link="l2"/><child link="t"/>
            <origin xyz="0 0 0.05"/></joint></robot>"#;
        let model = UrdfModel::parse(urdf).unwrap();
        let chain = model.chain(Some("b"), Some("t")).unwrap();
        let q = [0.7, 0.25];
        let poses = chain.link_poses(&q).unwrap();
        assert_eq!(poses.len(), 3);
        assert_relative_eq!(poses[2], chain.fk(&q), epsilon = 1e-15);
        let lines = chain.axis_lines(&q).unwrap();
        // j1's child frame: on j1's axis, at the joint origin (a rotation leaves it there).
        assert!(lines[0].distance_to_point(&poses[0].translation.vector) < 1e-14);
        assert_relative_eq!(poses[0].translation.vector, Vector3::new(0.0, 0.0, 0.3));
        // j2 slides its child frame 0.25 m along its own axis from where the joint frame is.
        let slid = poses[1].translation.vector - lines[1].direction() * 0.25;
        assert!(lines[1].distance_to_point(&slid) < 1e-14);
        assert!(lines[1].distance_to_point(&poses[1].translation.vector) < 1e-14);
        assert!(chain.link_poses(&[0.0]).is_err());
    }

    #[test]
    fn motion_matches_the_isometry_product() {
        let t0 = Isometry3::new(Vector3::new(0.1, 0.2, 0.3), Vector3::new(0.4, -0.5, 0.6));
        let axis = Unit::new_normalize(Vector3::new(1.0, 2.0, -1.0));
        for kind in [JointKind::Revolute, JointKind::Prismatic] {
            let seg = Segment::new(Isometry3::identity(), axis, kind);
            let mut t = t0;
            apply_motion(&mut t, &seg, 0.7);
            let motion = match kind {
                JointKind::Revolute => Isometry3::rotation(*axis * 0.7),
                JointKind::Prismatic => {
                    Isometry3::translation(axis.x * 0.7, axis.y * 0.7, axis.z * 0.7)
                }
            };
            assert_relative_eq!(t, t0 * motion, epsilon = 1e-14);
        }
    }

    /// A step (origin, then the motion) is the isometry product `t · origin · motion(q)`,
    /// for an origin with a turn in it, both kinds, several joint values.
    #[test]
    fn step_is_origin_then_motion() {
        let t0 = Isometry3::new(Vector3::new(0.1, 0.2, 0.3), Vector3::new(0.4, -0.5, 0.6));
        let origin = Isometry3::new(Vector3::new(-0.2, 0.05, 0.4), Vector3::new(1.2, 0.3, -2.1));
        let axis = Unit::new_normalize(Vector3::new(1.0, 2.0, -1.0));
        for kind in [JointKind::Revolute, JointKind::Prismatic] {
            let seg = Segment::new(origin, axis, kind);
            for q in [-3.0, -0.7, 0.0, 0.2, 2.9] {
                let mut t = t0;
                seg.step(&mut t, q);
                let motion = match kind {
                    JointKind::Revolute => Isometry3::rotation(*axis * q),
                    JointKind::Prismatic => {
                        Isometry3::translation(axis.x * q, axis.y * q, axis.z * q)
                    }
                };
                assert_relative_eq!(t, t0 * origin * motion, epsilon = 1e-14);
            }
        }
    }
}
