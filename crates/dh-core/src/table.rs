//! DH tables in the standard (distal) and modified (Craig, proximal) conventions, and their
//! forward kinematics.

use std::fmt;
use std::str::FromStr;

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};

use crate::pose::{rot_x, rot_y, rot_z, trans_x, trans_z};
use crate::CoreError;

mod prepared;
pub use prepared::PreparedFk;

/// Where a row's link parameters sit.
///
/// With `q` the joint value (added to `theta` for revolute joints, to `d` for prismatic ones):
/// - `Standard` (distal): `A_i = Rz(theta_i + q_i) Tz(d_i) Tx(a_i) Rx(alpha_i)`; frame `i` has
///   its z axis along joint `i + 1`, so frame 0 has z along joint 1.
/// - `Modified` (Craig, proximal): `A_i = Rx(alpha_{i-1}) Tx(a_{i-1}) Rz(theta_i + q_i) Tz(d_i)`;
///   row `i` holds `alpha_{i-1}`, `a_{i-1}` in its own `alpha`, `a` fields, and frame `i` has
///   its z axis along joint `i`.
///
/// In both, `FK(q) = base · A_1(q_1) ⋯ A_n(q_n) · tool`. A row with a Hayati-Mirmirani tilt
/// `beta` (see [`DhRow::beta`]) adds `Ry(beta)` right after its `Rx(alpha)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Convention {
    /// Standard (distal) DH.
    Standard,
    /// Modified (proximal, Craig) DH.
    Modified,
}

impl fmt::Display for Convention {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Convention::Standard => "standard",
            Convention::Modified => "modified",
        })
    }
}

impl FromStr for Convention {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "standard" => Ok(Convention::Standard),
            "modified" => Ok(Convention::Modified),
            other => Err(format!(
                "expected convention 'standard' or 'modified', found '{other}'"
            )),
        }
    }
}

/// What a joint's value moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum JointKind {
    /// The value (radians) adds to `theta`.
    Revolute,
    /// The value (metres) adds to `d`.
    Prismatic,
}

impl fmt::Display for JointKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            JointKind::Revolute => "revolute",
            JointKind::Prismatic => "prismatic",
        })
    }
}

/// Joint limits in the joint's own unit (radians or metres).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// Lowest joint value.
    pub lower: f64,
    /// Highest joint value.
    pub upper: f64,
}

/// A joint whose value follows another: `q = multiplier · q_driver + offset` (URDF `<mimic>`).
#[derive(Clone, Debug, PartialEq)]
pub struct Mimic {
    /// Name of the driving joint.
    pub joint: String,
    /// Gear ratio.
    pub multiplier: f64,
    /// Offset (radians or metres).
    pub offset: f64,
}

/// One row of a DH table: one joint and the link after it (standard) or before it (modified).
#[derive(Clone, Debug, PartialEq)]
pub struct DhRow {
    /// Joint name.
    pub name: String,
    /// Revolute or prismatic.
    pub kind: JointKind,
    /// Link length (metres).
    pub a: f64,
    /// Link twist (radians).
    pub alpha: f64,
    /// Link offset (metres); the joint value adds to it for prismatic joints.
    pub d: f64,
    /// Joint angle offset (radians); the joint value adds to it for revolute joints.
    pub theta: f64,
    /// Hayati-Mirmirani tilt about y (radians, 0 for a plain DH row), held by the row that
    /// holds the link's `a` and `alpha`: standard
    /// `A_i = Rz(theta_i + q_i) Tz(d_i) Tx(a_i) Rx(alpha_i) Ry(beta_i)`, modified
    /// `A_i = Rx(alpha_{i-1}) Tx(a_{i-1}) Ry(beta_{i-1}) Rz(theta_i + q_i) Tz(d_i)`. It turns
    /// about the y axis of the frame at the far end of the common normal, on the next joint's
    /// axis, so that a pair of nearly parallel axes is written with a small tilt instead of a
    /// common normal kilometres away (S. Hayati and M. Mirmirani, J. Robotic Systems 2(4),
    /// 1985, eq. 3). The placement is the one `dh-calib`'s model estimates.
    pub beta: f64,
    /// Joint limits, `None` for a continuous joint.
    pub limits: Option<Limits>,
    /// Set when the joint follows another one.
    pub mimic: Option<Mimic>,
}

impl DhRow {
    /// A revolute row without limits or mimic.
    pub fn revolute(name: &str, a: f64, alpha: f64, d: f64, theta: f64) -> Self {
        Self {
            name: name.into(),
            kind: JointKind::Revolute,
            a,
            alpha,
            d,
            theta,
            beta: 0.0,
            limits: None,
            mimic: None,
        }
    }

    /// A prismatic row without limits or mimic.
    pub fn prismatic(name: &str, a: f64, alpha: f64, d: f64, theta: f64) -> Self {
        Self {
            kind: JointKind::Prismatic,
            ..Self::revolute(name, a, alpha, d, theta)
        }
    }

    /// `theta` and `d` with the joint value `q` applied.
    pub(crate) fn moved(&self, q: f64) -> (f64, f64) {
        match self.kind {
            JointKind::Revolute => (self.theta + q, self.d),
            JointKind::Prismatic => (self.theta, self.d + q),
        }
    }

    /// The row's transform at joint value `q` in `convention` (see [`Convention`]), its tilt
    /// `beta` included.
    ///
    /// Closed form from half-angle quaternions: `Rz(theta) Rx(alpha)` is the quaternion
    /// `(c_t c_a, c_t s_a, s_t s_a, s_t c_a)` with `c_t = cos(theta/2)` etc., and
    /// `Rx(alpha) Rz(theta)` is `(c_a c_t, s_a c_t, −s_a s_t, c_a s_t)`. A row without a tilt
    /// takes exactly that path (bit for bit as before tilts existed); a tilted row composes
    /// its elementary transforms.
    pub fn transform(&self, convention: Convention, q: f64) -> Isometry3<f64> {
        self.transform_with_twist(convention, q, (0.5 * self.alpha).sin_cos())
    }

    /// [`DhRow::transform`] given `(sin, cos)` of `alpha / 2`, which does not depend on `q`
    /// (see [`PreparedFk`]).
    pub(crate) fn transform_with_twist(
        &self,
        convention: Convention,
        q: f64,
        (sa, ca): (f64, f64),
    ) -> Isometry3<f64> {
        let (theta, d) = self.moved(q);
        if self.beta != 0.0 {
            let tilt = rot_y(self.beta);
            return match convention {
                Convention::Standard => {
                    rot_z(theta) * trans_z(d) * trans_x(self.a) * rot_x(self.alpha) * tilt
                }
                Convention::Modified => {
                    rot_x(self.alpha) * trans_x(self.a) * tilt * rot_z(theta) * trans_z(d)
                }
            };
        }
        let (st, ct) = (0.5 * theta).sin_cos();
        match convention {
            Convention::Standard => standard_from_halves(self.a, d, (st, ct), (sa, ca)),
            Convention::Modified => {
                let (cos_a, sin_a) = (ca * ca - sa * sa, 2.0 * sa * ca);
                let rot = Quaternion::new(ca * ct, sa * ct, -sa * st, ca * st);
                Isometry3::from_parts(
                    Translation3::new(self.a, -sin_a * d, cos_a * d),
                    UnitQuaternion::new_unchecked(rot),
                )
            }
        }
    }
}

/// The untilted standard row transform `Rz(theta) Tz(d) Tx(a) Rx(alpha)` from `(sin, cos)` of
/// `theta / 2` and of `alpha / 2` (the closed form of [`DhRow::transform`]); the extraction
/// gets those halves from its unit vectors without trigonometry.
pub(crate) fn standard_from_halves(
    a: f64,
    d: f64,
    (st, ct): (f64, f64),
    (sa, ca): (f64, f64),
) -> Isometry3<f64> {
    let (cos_t, sin_t) = (ct * ct - st * st, 2.0 * st * ct);
    let rot = Quaternion::new(ct * ca, ct * sa, st * sa, st * ca);
    Isometry3::from_parts(
        Translation3::new(a * cos_t, a * sin_t, d),
        UnitQuaternion::new_unchecked(rot),
    )
}

/// A DH table with the base and tool transforms that make it exact.
///
/// `base` is the pose of DH frame 0 in the robot's base link frame; `tool` is the pose of the
/// tip link frame in the last DH frame (frame `n`). Lengths in metres, angles in radians.
#[derive(Clone, Debug, PartialEq)]
pub struct DhTable {
    /// Where `a` and `alpha` sit in each row.
    pub convention: Convention,
    /// DH frame 0 in the base link frame.
    pub base: Isometry3<f64>,
    /// Tip link frame in DH frame `n`.
    pub tool: Isometry3<f64>,
    /// One row per moving joint, base to tip.
    pub rows: Vec<DhRow>,
}

impl DhTable {
    /// Forward kinematics: the tip link's pose in the base link frame at joint values `q`
    /// (one per row, mimic rows included).
    ///
    /// # Errors
    /// [`CoreError::JointCount`] when `q` has the wrong length.
    pub fn fk(&self, q: &[f64]) -> Result<Isometry3<f64>, CoreError> {
        self.check_len(q)?;
        let mut t = self.base;
        for (row, &qi) in self.rows.iter().zip(q) {
            t *= row.transform(self.convention, qi);
        }
        Ok(t * self.tool)
    }

    /// The table prepared for many FK evaluations ([`PreparedFk`]: one `sin_cos` per joint
    /// instead of two, each row composed as two quaternion turns about coordinate axes); its
    /// [`PreparedFk::fk`] equals [`DhTable::fk`] to rounding.
    pub fn prepare(&self) -> PreparedFk<'_> {
        PreparedFk::new(self)
    }

    /// Poses of DH frames `0..=n` in the base link frame at joint values `q`. For the modified
    /// convention frame `i` (`i ≥ 1`) sits on joint `i`; for the standard one on joint `i + 1`.
    ///
    /// # Errors
    /// [`CoreError::JointCount`] when `q` has the wrong length.
    pub fn frames(&self, q: &[f64]) -> Result<Vec<Isometry3<f64>>, CoreError> {
        self.check_len(q)?;
        let mut out = Vec::with_capacity(self.rows.len() + 1);
        let mut t = self.base;
        out.push(t);
        for (row, &qi) in self.rows.iter().zip(q) {
            t *= row.transform(self.convention, qi);
            out.push(t);
        }
        Ok(out)
    }

    /// The common normals of the table at joint values `q`: for each row, the segment
    /// `[start, end]` (base link frame, metres) between the axis of DH frame `i - 1` and that of
    /// frame `i` (frames as [`DhTable::frames`]) along which the row's `a` is measured. Standard
    /// convention: from the foot of frame `i`'s origin on `z(i-1)` to that origin; modified:
    /// from frame `i - 1`'s origin to its foot on `z(i)`. A zero `a` gives a point.
    ///
    /// # Errors
    /// [`CoreError::JointCount`] when `q` has the wrong length.
    pub fn common_normals(&self, q: &[f64]) -> Result<Vec<[Vector3<f64>; 2]>, CoreError> {
        let frames = self.frames(q)?;
        // The foot of `p` on the z axis of `frame`.
        let foot = |frame: &Isometry3<f64>, p: Vector3<f64>| {
            let (o, z) = (frame.translation.vector, frame.rotation * Vector3::z());
            o + z * (p - o).dot(&z)
        };
        Ok(frames
            .windows(2)
            .map(|w| {
                let (from, to) = (&w[0], &w[1]);
                match self.convention {
                    Convention::Standard => {
                        let end = to.translation.vector;
                        [foot(from, end), end]
                    }
                    Convention::Modified => {
                        let start = from.translation.vector;
                        [start, foot(to, start)]
                    }
                }
            })
            .collect())
    }

    pub(crate) fn check_len(&self, q: &[f64]) -> Result<(), CoreError> {
        if q.len() == self.rows.len() {
            Ok(())
        } else {
            Err(CoreError::JointCount {
                expected: self.rows.len(),
                found: q.len(),
            })
        }
    }

    /// The same kinematics in the other convention, exactly: `a`, `alpha` and the tilt `beta`
    /// move one row along (standard row `i` holds what modified row `i + 1` holds: `Tx(a)` and
    /// `Rx(alpha)` commute, and `Ry(beta)` follows both in either convention) and the base or
    /// tool takes the triple that falls off the end. `theta`, `d`, joint directions and zero
    /// pose stay as they are.
    pub fn to_convention(&self, convention: Convention) -> DhTable {
        self.clone().into_convention(convention)
    }

    /// [`DhTable::to_convention`] on a table the caller no longer needs: the rows are shifted
    /// in place, with no copy of their names.
    pub fn into_convention(mut self, convention: Convention) -> DhTable {
        if convention == self.convention || self.rows.is_empty() {
            self.convention = convention;
            return self;
        }
        let n = self.rows.len();
        let rows = &mut self.rows;
        match convention {
            Convention::Modified => {
                // Standard: ... Rz Tz Tx(a_i) Rx(alpha_i) Rz Tz ...; Tx and Rx commute.
                let last = &rows[n - 1];
                self.tool = tilted(trans_x(last.a) * rot_x(last.alpha), last.beta) * self.tool;
                // From the last row back, so that row i - 1 still holds its own values.
                for i in (0..n).rev() {
                    let (a, alpha, beta) = if i == 0 {
                        (0.0, 0.0, 0.0)
                    } else {
                        let r = &rows[i - 1];
                        (r.a, r.alpha, r.beta)
                    };
                    rows[i].a = a;
                    rows[i].alpha = alpha;
                    rows[i].beta = beta;
                }
            }
            Convention::Standard => {
                let first = &rows[0];
                self.base = tilted(
                    self.base * rot_x(first.alpha) * trans_x(first.a),
                    first.beta,
                );
                // From the first row on, so that row i + 1 still holds its own values.
                for i in 0..n {
                    let (a, alpha, beta) = rows
                        .get(i + 1)
                        .map_or((0.0, 0.0, 0.0), |next| (next.a, next.alpha, next.beta));
                    rows[i].a = a;
                    rows[i].alpha = alpha;
                    rows[i].beta = beta;
                }
            }
        }
        self.convention = convention;
        self
    }

    /// The joint axis lines at the zero pose, in the base link frame, with each row's name,
    /// kind, limits and mimic: what [`crate::extract()`] takes, so that
    /// `extract(&t.axes()?, &t.fk(&zeros)?, ..)` gives the plain DH table of `t`'s kinematics
    /// (its tilts, if any, folded into `theta`, `d`, `a`, `alpha`: exact, but a small tilt puts
    /// the common normal far away).
    ///
    /// # Errors
    /// [`CoreError::NonFinite`] for non-finite frames (a table of non-finite values).
    pub fn axes(&self) -> Result<Vec<crate::JointAxis>, CoreError> {
        let frames = self.frames(&vec![0.0; self.rows.len()])?;
        let shift = usize::from(self.convention == Convention::Modified);
        self.rows
            .iter()
            .enumerate()
            .map(|(i, r)| {
                let f = frames[i + shift];
                Ok(crate::JointAxis {
                    name: r.name.clone(),
                    kind: r.kind,
                    line: crate::Line::through(
                        f.translation.vector,
                        f.rotation * nalgebra::Vector3::z(),
                    )?,
                    limits: r.limits,
                    mimic: r.mimic.clone(),
                })
            })
            .collect()
    }

    /// The same kinematics with every pair of consecutive revolute or prismatic axes within
    /// `max_angle` (radians) of parallel or antiparallel written in the Hayati-Mirmirani form
    /// of [`DhRow::beta`]: standard row `i` becomes `Rz(theta) Tx(a) Rx(alpha) Ry(beta)` with
    /// `d_i = 0`, `x` from the origin of frame `i - 1` to where axis `i + 1` crosses that
    /// frame's `xy` plane, and the screw between the old and new frame `i` (both on axis
    /// `i + 1`) absorbed by row `i + 1`'s `theta`, `d` (or the tool). Plain DH puts the common
    /// normal of a pair `beta` off parallel about `a / beta` away; this form keeps every length
    /// near the link's. A modified table is converted to standard and back (both exact).
    /// Exact up to rounding of the lengths it replaces (a kilometre `d` loses ~1e-13 m).
    pub fn hayati_form(&self, max_angle: f64) -> DhTable {
        if self.convention == Convention::Modified {
            return self
                .to_convention(Convention::Standard)
                .hayati_form(max_angle)
                .to_convention(Convention::Modified);
        }
        let mut t = self.clone();
        let n = t.rows.len();
        for i in 0..n.saturating_sub(1) {
            if t.rows[i].kind == JointKind::Prismatic {
                // Its joint value moves d, which the form sets to zero.
                continue;
            }
            let zero = vec![0.0; n];
            let Ok(frames) = t.frames(&zero) else {
                return self.clone();
            };
            // Frame i - 1 (z along joint i) and the old frame i (z along joint i + 1).
            let (before, old) = (frames[i], frames[i + 1]);
            let local = before.inverse() * old;
            let u = local.rotation * nalgebra::Vector3::z();
            let angle = u.z.abs().min(1.0).acos();
            // A NaN angle (a table of non-finite values) and a perpendicular pair stay as they are.
            if angle.is_nan() || angle > max_angle || u.z == 0.0 {
                continue;
            }
            // Where axis i + 1 crosses the plane z = 0 of frame i - 1.
            let o = local.translation.vector;
            let p = o - u * (o.z / u.z);
            let (theta, a) = if p.x.hypot(p.y) > 0.0 {
                (p.y.atan2(p.x), p.x.hypot(p.y))
            } else {
                (0.0, 0.0)
            };
            let w = rot_z(-theta).rotation * u;
            let beta = w.x.clamp(-1.0, 1.0).asin();
            let alpha = (-w.y).atan2(w.z);
            let row = &mut t.rows[i];
            // The joint value adds to theta: keep the row's zero offset relative to it.
            row.theta = theta;
            row.d = 0.0;
            row.a = a;
            row.alpha = alpha;
            row.beta = beta;
            let new = before * row.transform(Convention::Standard, 0.0);
            let screw = new.inverse() * old;
            let x = screw.rotation * nalgebra::Vector3::x();
            let (phi, s) = (x.y.atan2(x.x), screw.translation.vector.z);
            t.rows[i + 1].theta += phi;
            t.rows[i + 1].d += s;
        }
        t
    }

    /// `true` when a row carries a Hayati-Mirmirani tilt (see [`DhRow::beta`]).
    pub fn has_tilts(&self) -> bool {
        self.rows.iter().any(|r| r.beta != 0.0)
    }

    /// A length that bounds the chain's size (metres, at least 1 mm): the sum of `|a|`, `|d|`,
    /// prismatic travel and the base and tool offsets. Tolerances relative to the chain's size
    /// use it.
    pub fn size(&self) -> f64 {
        let travel = |r: &DhRow| match (r.kind, r.limits) {
            (JointKind::Prismatic, Some(l)) => l.lower.abs().max(l.upper.abs()),
            _ => 0.0,
        };
        let links: f64 = self
            .rows
            .iter()
            .map(|r| r.a.abs() + r.d.abs() + travel(r))
            .sum();
        (links + self.base.translation.vector.norm() + self.tool.translation.vector.norm())
            .max(1e-3)
    }
}

/// `pose · Ry(beta)`, and `pose` untouched for no tilt (so untilted tables convert bit for bit
/// as before tilts existed).
fn tilted(pose: Isometry3<f64>, beta: f64) -> Isometry3<f64> {
    if beta == 0.0 {
        pose
    } else {
        pose * rot_y(beta)
    }
}

#[cfg(test)]
mod tests;
