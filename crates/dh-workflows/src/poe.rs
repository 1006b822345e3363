//! The product-of-exponentials form of a chain (Lynch & Park, *Modern Robotics*, 2017, §4.1.1,
//! the space form, eq. 4.14): `T(q) = exp([S_1] q_1) ··· exp([S_n] q_n) M`, written as JSON by
//! `urdf-dh extract --format poe` and proved like every written format: the text is read back and
//! its forward kinematics compared with the URDF's at sampled joint values.
//!
//! # Frames and units
//! Everything is in the base link's frame (the space frame) with every joint at zero. A revolute
//! joint's screw is `S = (ω, v)` with `ω` the unit axis direction and `v = −ω × p` for any point
//! `p` of the axis (metres); a prismatic joint's is `S = (0, v)` with `v` the unit direction of
//! travel. `M` is the tip link's pose at zero (4x4, row-major, metres). Joint values are those of
//! the rows of `--format yaml` (radians, metres); a mimic row takes its driver's value times
//! `multiplier` plus `offset`, as there.

use anyhow::{bail, ensure, Context, Result};
use dh_core::{DhTable, JointAxis, JointKind, JointSampler};
use nalgebra::{Isometry3, Matrix3, Matrix4, Vector3};
use serde::{Deserialize, Serialize};
use urdf_axes::Chain;

use crate::sheet::VerificationDoc;

/// What the `convention` key of a PoE document says.
pub const POE_CONVENTION: &str = "product of exponentials, space form (Lynch & Park, Modern Robotics, eq. 4.14): T(q) = exp([S1] q1) ... exp([Sn] qn) M, S = (omega, v)";

/// Decimals written: screws and `M` to 1e-12 (a picometre, as the sheets write lengths).
const DECIMALS: i32 = 12;

/// Deviation allowed between the written form's forward kinematics and the URDF's (metres,
/// radians): the rounding to 12 decimals moves a tip a few 1e-12 m per joint at a few metres,
/// so a nanometre keeps a margin of a hundred and still catches any real defect, as the written
/// artefacts of `calibrate` are held to ([`crate::written::WRITTEN_TOLERANCE`]).
pub const POE_BOUND: f64 = 1e-9;

/// Largest deviation of a read-back `ω` from unit length, or of `M`'s rotation from orthonormal,
/// accepted when reading a PoE document: ten times what rounding to [`DECIMALS`] causes.
const UNIT_SLACK: f64 = 1e-11;

/// One joint of a PoE document.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PoeJoint {
    /// Joint name.
    pub name: String,
    /// `revolute` or `prismatic`.
    #[serde(rename = "type")]
    pub kind: String,
    /// `[ωx, ωy, ωz, vx, vy, vz]` in the base frame.
    pub screw: [f64; 6],
    /// Lower limit (radians or metres), absent for a continuous joint.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lower: Option<f64>,
    /// Upper limit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub upper: Option<f64>,
    /// The joint it follows, with `multiplier` and `offset`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mimic: Option<crate::sheet::MimicDoc>,
}

/// A PoE document as written and read.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PoeDoc {
    /// Robot name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub robot: Option<String>,
    /// Base link (the space frame).
    pub base_link: String,
    /// Tip link (the frame `M` places).
    pub tip_link: String,
    /// [`POE_CONVENTION`].
    pub convention: String,
    /// Always `m`.
    pub length_unit: String,
    /// Always `rad`.
    pub angle_unit: String,
    /// One per row, base to tip.
    pub joints: Vec<PoeJoint>,
    /// The tip's home pose `M`, 4x4 row-major.
    pub home: [[f64; 4]; 4],
    /// The proof of the text as written.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub verification: Option<VerificationDoc>,
}

fn rounded(x: f64) -> f64 {
    let scale = 10f64.powi(DECIMALS);
    let r = (x * scale).round() / scale;
    // Beyond 1e3 the product loses digits: keep the value (rounding it gains nothing).
    let r = if x.abs() < 1e3 { r } else { x };
    if r == 0.0 {
        0.0
    } else {
        r
    }
}

impl PoeDoc {
    /// The PoE form of joint axes at zero in the base frame (`axes`: names, kinds, limits,
    /// mimics) and the tip's pose at zero (`home`), at full precision.
    pub fn new(
        axes: &[JointAxis],
        home: &Isometry3<f64>,
        base_link: &str,
        tip_link: &str,
        robot: Option<String>,
    ) -> PoeDoc {
        let joints = axes
            .iter()
            .map(|axis| {
                let d = axis.line.direction();
                // The moment p x d of the line is v = -omega x p for a revolute joint.
                let (omega, v) = match axis.kind {
                    JointKind::Revolute => (d, axis.line.moment()),
                    JointKind::Prismatic => (Vector3::zeros(), d),
                };
                PoeJoint {
                    name: axis.name.clone(),
                    kind: match axis.kind {
                        JointKind::Revolute => "revolute".into(),
                        JointKind::Prismatic => "prismatic".into(),
                    },
                    screw: [omega.x, omega.y, omega.z, v.x, v.y, v.z],
                    lower: axis.limits.map(|l| l.lower),
                    upper: axis.limits.map(|l| l.upper),
                    mimic: axis.mimic.as_ref().map(|m| crate::sheet::MimicDoc {
                        joint: m.joint.clone(),
                        multiplier: m.multiplier,
                        offset: m.offset,
                    }),
                }
            })
            .collect();
        let m = home.to_homogeneous();
        PoeDoc {
            robot,
            base_link: base_link.to_owned(),
            tip_link: tip_link.to_owned(),
            convention: POE_CONVENTION.into(),
            length_unit: "m".into(),
            angle_unit: "rad".into(),
            joints,
            home: std::array::from_fn(|i| std::array::from_fn(|j| m[(i, j)])),
            verification: None,
        }
    }

    /// The PoE form of `chain` (a URDF's or MJCF's), at full precision.
    pub fn of_chain(chain: &Chain, robot: Option<String>) -> PoeDoc {
        PoeDoc::new(
            chain.axes(),
            &chain.tip_pose(),
            chain.base(),
            chain.tip(),
            robot,
        )
    }

    /// The PoE form of a DH table's own kinematics (its axes and tip at zero: the same forward
    /// kinematics as [`DhTable::fk`]), at full precision.
    ///
    /// # Errors
    /// A table of non-finite values.
    pub fn of_table(table: &DhTable, base_link: &str, tip_link: &str) -> Result<PoeDoc> {
        let home = table.fk(&vec![0.0; table.rows.len()])?;
        Ok(PoeDoc::new(
            &table.axes()?,
            &home,
            base_link,
            tip_link,
            None,
        ))
    }

    /// The same form with every number rounded to 1e-12 (as written).
    fn rounded(mut self) -> PoeDoc {
        for j in &mut self.joints {
            j.screw = j.screw.map(rounded);
        }
        self.home = self.home.map(|row| row.map(rounded));
        self
    }

    /// Reads a PoE document and checks it: units, unit `ω` (or zero `ω` and unit `v` for a
    /// prismatic joint), `M` a rigid transform.
    ///
    /// # Errors
    /// Not JSON of this shape; a screw or `M` that is not what the form requires (naming the
    /// joint).
    pub fn parse(text: &str) -> Result<PoeDoc> {
        let doc: PoeDoc = serde_json::from_str(text).context("expected a poe document")?;
        ensure!(
            doc.length_unit == "m" && doc.angle_unit == "rad",
            "expected units m and rad, found {} and {}",
            doc.length_unit,
            doc.angle_unit
        );
        for j in &doc.joints {
            let [wx, wy, wz, vx, vy, vz] = j.screw;
            let (w, v) = (Vector3::new(wx, wy, wz), Vector3::new(vx, vy, vz));
            let unit = match j.kind.as_str() {
                "revolute" => w,
                "prismatic" if w == Vector3::zeros() => v,
                "prismatic" => bail!(
                    "joint '{}': expected omega = 0 for a prismatic joint, found {w:?}",
                    j.name
                ),
                other => bail!(
                    "joint '{}': expected type revolute or prismatic, found '{other}'",
                    j.name
                ),
            };
            ensure!(
                (unit.norm() - 1.0).abs() <= UNIT_SLACK,
                "joint '{}': expected a unit {} in the screw, found length {}",
                j.name,
                if j.kind == "revolute" { "omega" } else { "v" },
                unit.norm()
            );
        }
        let r = Matrix3::from_fn(|i, k| doc.home[i][k]);
        let off = (r.transpose() * r - Matrix3::identity()).amax();
        ensure!(
            off <= UNIT_SLACK && doc.home[3] == [0.0, 0.0, 0.0, 1.0],
            "home: expected a rigid transform (orthonormal rotation, last row 0 0 0 1), found one off by {off:.1e}"
        );
        Ok(doc)
    }

    /// The tip pose at joint values `q` (one per joint): `exp([S_1] q_1) ··· exp([S_n] q_n) M`.
    ///
    /// # Errors
    /// `q` has not one value per joint.
    pub fn fk(&self, q: &[f64]) -> Result<Matrix4<f64>> {
        ensure!(
            q.len() == self.joints.len(),
            "expected {} joint values, found {}",
            self.joints.len(),
            q.len()
        );
        let mut t = Matrix4::<f64>::identity();
        for (j, &theta) in self.joints.iter().zip(q) {
            t *= screw_exp(&j.screw, theta);
        }
        Ok(t * Matrix4::from_fn(|i, k| self.home[i][k]))
    }
}

/// `exp([S] θ)` (Modern Robotics, Proposition 3.25, eq. 3.88; Rodrigues for the rotation):
/// `R = I + sin θ [ω] + (1 − cos θ) [ω]²`, `p = (I θ + (1 − cos θ) [ω] + (θ − sin θ) [ω]²) v`;
/// `R = I`, `p = v θ` when `ω = 0`.
pub fn screw_exp(screw: &[f64; 6], theta: f64) -> Matrix4<f64> {
    let [wx, wy, wz, vx, vy, vz] = *screw;
    let v = Vector3::new(vx, vy, vz);
    let mut t = Matrix4::identity();
    if [wx, wy, wz] == [0.0; 3] {
        t.fixed_view_mut::<3, 1>(0, 3).copy_from(&(v * theta));
        return t;
    }
    let w = Vector3::new(wx, wy, wz).cross_matrix();
    let w2 = w * w;
    let (s, c) = theta.sin_cos();
    let r = Matrix3::identity() + w * s + w2 * (1.0 - c);
    let g = Matrix3::identity() * theta + w * (1.0 - c) + w2 * (theta - s);
    t.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
    t.fixed_view_mut::<3, 1>(0, 3).copy_from(&(g * v));
    t
}

/// `doc` as pretty JSON with every list of numbers on one line (a screw, a row of `M`), so that
/// the text reads as the form is printed in books.
fn to_json(doc: &PoeDoc) -> Result<String> {
    let pretty = serde_json::to_string_pretty(doc)?;
    let mut out = String::with_capacity(pretty.len());
    let mut lines = pretty.lines().peekable();
    while let Some(line) = lines.next() {
        if line.trim_end().ends_with('[') {
            let mut items = Vec::new();
            let probe = lines.clone();
            let mut close = None;
            for next in probe {
                let t = next.trim();
                if t.starts_with(']') {
                    close = Some(t);
                    break;
                }
                let number = t.trim_end_matches(',');
                if number.parse::<f64>().is_err() {
                    break;
                }
                items.push(number);
            }
            if let (Some(close), false) = (close, items.is_empty()) {
                out.push_str(line.trim_end());
                out.push_str(&items.join(", "));
                out.push_str(close);
                out.push('\n');
                for _ in 0..=items.len() {
                    lines.next();
                }
                continue;
            }
        }
        out.push_str(line);
        out.push('\n');
    }
    Ok(out)
}

/// Position (metres) and orientation (radians) deviation of two poses.
fn deviation(a: &Matrix4<f64>, b: &Isometry3<f64>) -> (f64, f64) {
    let b = b.to_homogeneous();
    let dp = (a.fixed_view::<3, 1>(0, 3) - b.fixed_view::<3, 1>(0, 3)).norm();
    let r = a.fixed_view::<3, 3>(0, 0).transpose() * b.fixed_view::<3, 3>(0, 0);
    let s = 0.5
        * Vector3::new(
            r[(2, 1)] - r[(1, 2)],
            r[(0, 2)] - r[(2, 0)],
            r[(1, 0)] - r[(0, 1)],
        )
        .norm();
    let c = 0.5 * (r.trace() - 1.0);
    (dp, s.atan2(c))
}

/// Writes the PoE form of `chain` (`table` is its extracted table, whose rows the sampler
/// follows: limits, mimics), reads the text back and compares its
/// forward kinematics with `oracle` (the URDF's) at `samples` joint values drawn with `seed`
/// (the zero pose first; mimic rows follow their drivers). `robot` is the robot's name and what
/// the verification names as the source when it is not the URDF (`the MJCF`). Returns the JSON
/// text with its verification, the verification, and whether it passed.
///
/// # Errors
/// The written text does not read back (a writer bug).
pub fn prove_poe<F>(
    chain: &Chain,
    table: &DhTable,
    robot: (Option<String>, Option<String>),
    samples: usize,
    seed: u64,
    mut oracle: F,
) -> Result<(String, VerificationDoc, bool)>
where
    F: FnMut(&[f64]) -> Isometry3<f64>,
{
    let (robot, against) = robot;
    let mut doc = PoeDoc::of_chain(chain, robot).rounded();
    let first = to_json(&doc)?;
    let back = PoeDoc::parse(&first).context("internal error: the poe text does not read back")?;
    let mut sampler = JointSampler::new(&table.rows, table.size(), seed);
    let mut q = Vec::with_capacity(table.rows.len());
    let mut worst: (f64, f64) = (0.0, 0.0);
    let count = samples.max(1);
    for _ in 0..count {
        sampler.next_into(&mut q);
        let (dp, dr) = deviation(&back.fk(&q)?, &oracle(&q));
        // NaN must fail, not pass.
        worst.0 = if dp.is_nan() {
            f64::INFINITY
        } else {
            worst.0.max(dp)
        };
        worst.1 = if dr.is_nan() {
            f64::INFINITY
        } else {
            worst.1.max(dr)
        };
    }
    let passed = worst.0 <= POE_BOUND && worst.1 <= POE_BOUND;
    let v = VerificationDoc {
        samples: count,
        seed,
        max_position_error: worst.0,
        max_orientation_error: worst.1,
        position_bound: POE_BOUND,
        orientation_bound: POE_BOUND,
        passed,
        against,
    };
    doc.verification = Some(v.clone());
    let text = to_json(&doc)?;
    ensure!(
        PoeDoc::parse(&text)?.joints == back.joints,
        "internal error: the poe text reads back differently once verified"
    );
    Ok((text, v, passed))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    /// A planar 2R arm with unit links and a prismatic joint along z, whose tip is known in
    /// closed form; then the text reads back, and a screw of non-unit omega is refused.
    #[test]
    fn the_product_of_exponentials_of_a_planar_arm() {
        let doc = PoeDoc {
            robot: None,
            base_link: "b".into(),
            tip_link: "t".into(),
            convention: POE_CONVENTION.into(),
            length_unit: "m".into(),
            angle_unit: "rad".into(),
            joints: vec![
                PoeJoint {
                    name: "j1".into(),
                    kind: "revolute".into(),
                    screw: [0.0, 0.0, 1.0, 0.0, 0.0, 0.0],
                    lower: None,
                    upper: None,
                    mimic: None,
                },
                // Axis z through (1, 0, 0): v = -w x p = (0, -1, 0).
                PoeJoint {
                    name: "j2".into(),
                    kind: "revolute".into(),
                    screw: [0.0, 0.0, 1.0, 0.0, -1.0, 0.0],
                    lower: None,
                    upper: None,
                    mimic: None,
                },
                PoeJoint {
                    name: "s".into(),
                    kind: "prismatic".into(),
                    screw: [0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
                    lower: None,
                    upper: None,
                    mimic: None,
                },
            ],
            home: [
                [1.0, 0.0, 0.0, 2.0],
                [0.0, 1.0, 0.0, 0.0],
                [0.0, 0.0, 1.0, 0.0],
                [0.0, 0.0, 0.0, 1.0],
            ],
            verification: None,
        };
        let (a, b) = (0.3_f64, FRAC_PI_2);
        let t = doc.fk(&[a, b, 0.25]).unwrap();
        let want_x = a.cos() + (a + b).cos();
        let want_y = a.sin() + (a + b).sin();
        assert!((t[(0, 3)] - want_x).abs() < 1e-15, "{t}");
        assert!((t[(1, 3)] - want_y).abs() < 1e-15, "{t}");
        assert!((t[(2, 3)] - 0.25).abs() < 1e-15, "{t}");
        assert!((t[(0, 0)] - (a + b).cos()).abs() < 1e-15);
        let text = serde_json::to_string(&doc).unwrap();
        assert_eq!(PoeDoc::parse(&text).unwrap(), doc);
        let bad = text.replace("[0.0,0.0,1.0,0.0,-1.0,0.0]", "[0.0,0.0,2.0,0.0,-1.0,0.0]");
        let e = PoeDoc::parse(&bad).unwrap_err().to_string();
        assert!(e.contains("joint 'j2': expected a unit omega"), "{e}");
    }

    /// The proof compares with the URDF: right on a spatial arm, and failing when the oracle is
    /// a micrometre off.
    #[test]
    fn the_proof_holds_on_a_urdf_and_fails_off_it() {
        let urdf = r#"<robot name="r">
  <link name="a"/><link name="b"/><link name="c"/><link name="d"/>
  <joint name="j1" type="revolute"><parent link="a"/><child link="b"/>
    <origin xyz="0.1 0.2 0.3" rpy="0.3 -0.2 0.1"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="j2" type="prismatic"><parent link="b"/><child link="c"/>
    <origin xyz="0.4 0 0" rpy="1.5707963267948966 0 0"/><axis xyz="0 1 0"/>
    <limit lower="0" upper="0.5" effort="1" velocity="1"/></joint>
  <joint name="j3" type="continuous"><parent link="c"/><child link="d"/>
    <origin xyz="0 0.1 0.2" rpy="0 0.7 0"/><axis xyz="1 0 0"/></joint>
</robot>"#;
        let model = urdf_axes::UrdfModel::parse(urdf).unwrap();
        let chain = model.chain(None, None).unwrap();
        let table = dh_core::extract(
            chain.axes(),
            &chain.tip_pose(),
            dh_core::Tolerance::default(),
            dh_core::Convention::Standard,
        )
        .unwrap()
        .table;
        let (text, v, passed) =
            prove_poe(&chain, &table, (None, None), 200, 3, |q| chain.fk(q)).unwrap();
        // Written to 1e-12: a few 1e-12 m at most on an arm of half a metre.
        assert!(passed && v.max_position_error < 1e-11, "{v:?}");
        assert_eq!(PoeDoc::parse(&text).unwrap().joints.len(), 3);
        // The table's own form gives the table's own forward kinematics.
        let own = PoeDoc::of_table(&table, "a", "d").unwrap();
        for q in [[0.0, 0.0, 0.0], [0.5, 0.3, -2.0], [-0.9, 0.45, 3.0]] {
            let (dp, dr) = deviation(&own.fk(&q).unwrap(), &table.fk(&q).unwrap());
            assert!(dp < 1e-15 && dr < 1e-15, "{q:?}: {dp:e} m, {dr:e} rad");
        }
        let off = Isometry3::translation(1e-6, 0.0, 0.0);
        let (_, v, passed) =
            prove_poe(&chain, &table, (None, None), 200, 3, |q| off * chain.fk(q)).unwrap();
        assert!(
            !passed && (v.max_position_error - 1e-6).abs() < 1e-11,
            "{v:?}"
        );
    }
}
