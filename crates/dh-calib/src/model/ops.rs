//! The elementary transforms ("ops") a model's chains are made of: a translation or rotation
//! along one axis of the current frame (metres, radians) or a fixed frame, and the frame
//! type they compose (rotation matrix and translation, in the device frame).

use std::ops::Range;
use std::sync::Arc;

use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};

use super::{Effect, Field, Unit};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Axis {
    X = 0,
    Y = 1,
    Z = 2,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum OpKind {
    Trans(Axis),
    Rot(Axis),
    Fixed,
}

/// A rotation matrix and translation: cheaper to compose than quaternions in the hot loop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Frame {
    pub(super) r: Matrix3<f64>,
    pub(super) t: Vector3<f64>,
}

impl Frame {
    pub(super) const IDENTITY: Frame = Frame {
        r: Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
        t: Vector3::new(0.0, 0.0, 0.0),
    };

    pub(super) fn from_iso(iso: &Isometry3<f64>) -> Self {
        Self {
            r: *iso.rotation.to_rotation_matrix().matrix(),
            t: iso.translation.vector,
        }
    }

    pub(super) fn to_iso(self) -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::from(self.t),
            UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(self.r)),
        )
    }

    pub(super) fn apply(&mut self, kind: OpKind, v: f64, fixed: &Frame) {
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
pub(super) struct Op {
    pub(super) kind: OpKind,
    pub(super) value: f64,
    pub(super) fixed: Frame,
    pub(super) joint: Option<usize>,
    pub(super) param: Option<usize>,
}

#[derive(Clone, Debug)]
pub(super) struct EffectSlot {
    pub(super) effect: Arc<dyn Effect>,
    pub(super) params: Range<usize>,
    /// The op the effect changes; `None` for the device scale and a shift.
    pub(super) op: Option<usize>,
    /// A shift's unit direction in the base link frame ([`super::EffectField::Shift`]);
    /// `None` for every other effect.
    pub(super) shift: Option<Vector3<f64>>,
}

/// Op indices of one row.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct RowOps {
    pub(super) theta: usize,
    pub(super) d: usize,
    pub(super) alpha: usize,
    pub(super) beta: Option<usize>,
}

pub(super) const POSE_FIELDS: [(Field, &str, OpKind); 6] = [
    (Field::X, "x", OpKind::Trans(Axis::X)),
    (Field::Y, "y", OpKind::Trans(Axis::Y)),
    (Field::Z, "z", OpKind::Trans(Axis::Z)),
    (Field::Rx, "rx", OpKind::Rot(Axis::X)),
    (Field::Ry, "ry", OpKind::Rot(Axis::Y)),
    (Field::Rz, "rz", OpKind::Rot(Axis::Z)),
];

/// Ops 0..7 are the device block.
pub(super) const DEVICE_OPS: usize = 7;

pub(super) fn unit_of(kind: OpKind) -> Unit {
    match kind {
        OpKind::Rot(_) => Unit::Angle,
        _ => Unit::Length,
    }
}
