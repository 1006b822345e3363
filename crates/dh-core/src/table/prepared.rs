//! The forward kinematics of a [`DhTable`] prepared for thousands of evaluations (the proofs'
//! samples): what does not depend on the joint values is computed once, and each row is
//! composed onto the running pose as turns about coordinate axes.
//!
//! A row's transform is a turn about z and a turn about x with a shift between them:
//! standard `Rz(theta) Tz(d) Tx(a) Rx(alpha)` moves the running pose `(R, p)` to
//! `(U Rx(alpha), p + U (a, 0, d))` with `U = R Rz(theta)`; modified
//! `Rx(alpha) Tx(a) Rz(theta) Tz(d)` to `(R Rx(alpha) Rz(theta), p + R (a, -sin alpha d,
//! cos alpha d))`. With rotations as unit quaternions, a turn about a coordinate axis by
//! `(c, s) = (cos, sin)` of half the angle is 8 multiplications (a general product takes 16),
//! and `theta`'s half-angle sine and cosine are the row's one trigonometric call
//! ([`crate::math::sin_cos`]). A tilted row (`beta != 0`) is composed from its elementary
//! transforms, as [`DhRow::transform`] does.

use nalgebra::{Isometry3, Quaternion, UnitQuaternion, Vector3};

use super::{Convention, DhRow, DhTable, JointKind};
use crate::math::sin_cos;
use crate::CoreError;

/// A [`DhTable`] with every row's twist turned into sines and cosines once, for verification
/// and other loops that evaluate FK at thousands of joint vectors (made by [`DhTable::prepare`]).
#[derive(Clone, Debug)]
pub struct PreparedFk<'a> {
    table: &'a DhTable,
    rows: Vec<Prepared>,
}

/// What a row's transform needs besides the joint value.
#[derive(Clone, Copy, Debug)]
struct Prepared {
    /// `(sin, cos)` of `alpha / 2`.
    half_twist: (f64, f64),
    /// `(sin, cos)` of `alpha`.
    twist: (f64, f64),
}

/// `p Rz(phi)`, given `(sin, cos)` of `phi / 2`.
#[inline]
fn turn_z(p: &Quaternion<f64>, (s, c): (f64, f64)) -> Quaternion<f64> {
    Quaternion::new(
        p.w * c - p.k * s,
        p.i * c + p.j * s,
        p.j * c - p.i * s,
        p.w * s + p.k * c,
    )
}

/// `p Rx(phi)`, given `(sin, cos)` of `phi / 2`.
#[inline]
fn turn_x(p: &Quaternion<f64>, (s, c): (f64, f64)) -> Quaternion<f64> {
    Quaternion::new(
        p.w * c - p.i * s,
        p.w * s + p.i * c,
        p.j * c + p.k * s,
        p.k * c - p.j * s,
    )
}

impl<'a> PreparedFk<'a> {
    /// `table` prepared.
    pub(crate) fn new(table: &'a DhTable) -> Self {
        let rows = table
            .rows
            .iter()
            .map(|r| Prepared {
                half_twist: sin_cos(0.5 * r.alpha),
                twist: sin_cos(r.alpha),
            })
            .collect();
        PreparedFk { table, rows }
    }

    /// Pose of the tip link frame in the base link frame at joint values `q` (radians for
    /// revolute rows, metres for prismatic ones); [`DhTable::fk`] to rounding.
    ///
    /// # Errors
    /// [`CoreError::JointCount`] when `q` has the wrong length.
    pub fn fk(&self, q: &[f64]) -> Result<Isometry3<f64>, CoreError> {
        let table = self.table;
        table.check_len(q)?;
        let mut t = table.base;
        for ((row, &qi), p) in table.rows.iter().zip(q).zip(&self.rows) {
            compose(&mut t, row, table.convention, qi, p);
        }
        Ok(t * table.tool)
    }
}

/// `t · A(q)` of `row` into `t` (see the module documentation).
#[inline]
fn compose(t: &mut Isometry3<f64>, row: &DhRow, convention: Convention, q: f64, p: &Prepared) {
    if row.beta != 0.0 {
        *t *= row.transform_with_twist(convention, q, p.half_twist);
        return;
    }
    let (theta, d) = match row.kind {
        JointKind::Revolute => (row.theta + q, row.d),
        JointKind::Prismatic => (row.theta, row.d + q),
    };
    let half_theta = sin_cos(0.5 * theta);
    let r = t.rotation.quaternion();
    match convention {
        Convention::Standard => {
            let u = UnitQuaternion::new_unchecked(turn_z(r, half_theta));
            t.translation.vector += u * Vector3::new(row.a, 0.0, d);
            t.rotation = UnitQuaternion::new_unchecked(turn_x(&u, p.half_twist));
        }
        Convention::Modified => {
            let (sin_a, cos_a) = p.twist;
            t.translation.vector += t.rotation * Vector3::new(row.a, -sin_a * d, cos_a * d);
            let v = turn_x(r, p.half_twist);
            t.rotation = UnitQuaternion::new_unchecked(turn_z(&v, half_theta));
        }
    }
}
