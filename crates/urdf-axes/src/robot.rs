//! The URDF data model that [`crate::read`] fills in one pass over the scanned document: the
//! robot, its links and joints with their numbers as written (metres, radians, the joint's own
//! frame), and the warnings about what does not change a chain's kinematics.
//!
//! [`crate::check`] checks these joints and [`crate::read`] builds them: both depend on this
//! module, and neither on the other's types.

use std::fmt;

use crate::UrdfError;

/// Warnings kept per document; beyond this they are counted (a hostile file of a million bad
/// visuals must not cost a million messages).
pub const MAX_WARNINGS: usize = 100;

/// A fault that does not change the chosen chain's kinematics, kept as a warning.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Warning {
    /// The element it is about, e.g. `link 'base', <visual>` or `joint 'wheel'`.
    pub element: String,
    /// 1-based line of that element.
    pub line: Option<usize>,
    /// What is wrong: lowercase, "expected X, found Y", and what was done about it.
    pub message: String,
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.element)?;
        if let Some(l) = self.line {
            write!(f, " (line {l})")?;
        }
        write!(f, ": {}", self.message)
    }
}

/// A joint type of URDF (and MJCF's `ball` and `free`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum JointType {
    Revolute,
    Continuous,
    Prismatic,
    Fixed,
    Floating,
    Planar,
    /// MJCF `ball`: three rotations about one point.
    Ball,
    /// MJCF `free`: a floating body.
    Free,
}

impl JointType {
    /// Revolute, continuous or prismatic: one axis line.
    pub fn is_moving(self) -> bool {
        matches!(self, Self::Revolute | Self::Continuous | Self::Prismatic)
    }

    /// The name of a joint type without one axis line, for messages.
    pub fn label(self) -> &'static str {
        match self {
            Self::Floating => "floating",
            Self::Planar => "planar",
            Self::Ball => "ball",
            Self::Free => "free",
            Self::Fixed => "fixed",
            Self::Revolute => "revolute",
            Self::Continuous => "continuous",
            Self::Prismatic => "prismatic",
        }
    }
}

/// `<origin xyz rpy>`: metres and radians (`R = Rz(yaw) Ry(pitch) Rx(roll)`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Origin {
    pub xyz: [f64; 3],
    pub rpy: [f64; 3],
}

impl Origin {
    /// The pose `p` as URDF `xyz`/`rpy` ([`dh_core::pose::to_xyz_rpy`], exact at gimbal lock
    /// to a few 1e-16 rad): how the MJCF and SDFormat readers write their poses.
    pub(crate) fn of(p: &nalgebra::Isometry3<f64>) -> Origin {
        let (xyz, rpy) = dh_core::pose::to_xyz_rpy(p);
        Origin { xyz, rpy }
    }
}

/// `<mimic>` with the URDF defaults filled in.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct MimicSpec {
    pub joint: String,
    pub multiplier: f64,
    pub offset: f64,
}

/// One `<joint>`.
#[derive(Clone, Debug)]
pub(crate) struct Joint {
    pub name: String,
    pub line: usize,
    /// `None` when the type is missing or not URDF (then `fault` says so).
    pub kind: Option<JointType>,
    pub parent: String,
    pub parent_line: usize,
    pub child: String,
    pub child_line: usize,
    pub origin: Origin,
    pub axis: [f64; 3],
    /// `(lower, upper)` in radians or metres; `None` without a `<limit>`.
    pub limit: Option<(f64, f64)>,
    pub mimic: Option<MimicSpec>,
    pub mimic_line: Option<usize>,
    /// The first fault of the joint's own content (an error when it is on the chosen chain).
    pub fault: Option<UrdfError>,
}

impl Joint {
    /// A fixed joint a reader adds to carry a pose (an MJCF anchor or weld, an SDFormat joint
    /// frame off its child link): written at `line` of the source, its child at `child_line`.
    pub(crate) fn fixed(
        name: String,
        line: usize,
        parent: String,
        child: String,
        child_line: usize,
        origin: Origin,
    ) -> Joint {
        Joint {
            name,
            line,
            kind: Some(JointType::Fixed),
            parent,
            parent_line: line,
            child,
            child_line,
            origin,
            axis: [1.0, 0.0, 0.0],
            limit: None,
            mimic: None,
            mimic_line: None,
            fault: None,
        }
    }
}

/// A link's `<inertial>`: mass (kg) and centre of mass (metres, in the link frame).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Inertial {
    pub mass: f64,
    pub com: [f64; 3],
}

/// One `<link>`.
#[derive(Clone, Debug)]
pub(crate) struct Link {
    pub name: String,
    pub line: usize,
    /// `Ok(None)` without `<inertial>`; `Err(message)` when it is malformed (a warning too).
    pub inertial: Result<Option<Inertial>, String>,
}

/// The document read: robot name, links and joints in document order, warnings.
#[derive(Clone, Debug, Default)]
pub(crate) struct Robot {
    pub name: String,
    pub links: Vec<Link>,
    pub joints: Vec<Joint>,
    pub warnings: Vec<Warning>,
    /// Warnings beyond [`MAX_WARNINGS`], counted only.
    pub more_warnings: usize,
}

impl Robot {
    pub(crate) fn warn(&mut self, element: String, line: usize, message: String) {
        if self.warnings.len() < MAX_WARNINGS {
            self.warnings.push(Warning {
                element,
                line: Some(line),
                message,
            });
        } else {
            self.more_warnings += 1;
        }
    }
}
