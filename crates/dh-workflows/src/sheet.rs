//! The DH sheet format: the output of `extract` and the input of `check`, `convert`, `to-urdf`
//! and `calibrate --model`. YAML and JSON carry the same keys.
//!
//! ```yaml
//! convention: standard          # standard | modified
//! length_unit: m                # m | mm
//! angle_unit: rad               # rad | deg
//! base: {xyz: [0, 0, 0], rpy: [0, 0, 0]}   # DH frame 0 in the base link frame (optional)
//! tool: {xyz: [0, 0, 0], rpy: [0, 0, 0]}   # tip link frame in the last DH frame (optional)
//! joints:
//!   - {name: j1, type: revolute, a: 0, alpha: 90, d: 0.089, theta: 0, lower: -360, upper: 360}
//! ```
//! `theta` is the offset added to the joint value (prismatic joints add it to `d`); `rpy` is
//! URDF roll-pitch-yaw. Lengths in `length_unit`, angles in `angle_unit` (joint limits of
//! prismatic joints in `length_unit`). Extraction adds `tolerances`, `pairs`, `warnings` and
//! `verification`, `cpa` adds `cpa`, `calibrate --out` adds `calibration` and `simulate`'s truth
//! file `truth`; a sheet may carry them and they are ignored on input.
//!
//! This module holds the document types ([`SheetDoc`] and its parts, as written, including the
//! tree keys `branches` and `inertials` that [`crate::tree_sheet`] reads) and the sheet
//! read into SI units ([`Sheet`]); reading the text is in `parse` ([`parse_doc`],
//! [`Sheet::parse`], [`SheetDoc::into_sheet`]), checking rows, poses, mimics, couplings and
//! effects in `rows`. Writing is [`crate::render`].

use dh_core::pose::to_xyz_rpy;
use dh_core::{Convention, DhTable, JointKind};
use nalgebra::Isometry3;
use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::units::{AngleUnit, LengthUnit};

mod parse;
mod parts;
pub(crate) use parts::write_in_parts;
mod rows;
#[cfg(test)]
mod tests;

pub(crate) use parse::check_labels;
pub use parse::{check_nesting, parse_doc};
pub(crate) use rows::{check_mimics, coupled_of, pose_of, row_of};
pub use rows::{Coupled, CoupledDoc};

/// A pose as URDF writes it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PoseDoc {
    /// Translation, in the sheet's length unit.
    pub xyz: [f64; 3],
    /// Roll, pitch, yaw about fixed x, y, z, in the sheet's angle unit.
    pub rpy: [f64; 3],
}

/// A mimic coupling: `q = multiplier * q_joint + offset`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MimicDoc {
    /// The driving joint.
    pub joint: String,
    /// Gear ratio.
    #[serde(default = "one")]
    pub multiplier: f64,
    /// Offset in the joint's unit.
    #[serde(default)]
    pub offset: f64,
}

fn one() -> f64 {
    1.0
}

/// Joint type as sheets spell it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum JointType {
    /// Rotates.
    Revolute,
    /// Slides.
    Prismatic,
}

/// One row of a sheet.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointDoc {
    /// Joint name (as in the URDF).
    pub name: String,
    /// Revolute or prismatic.
    #[serde(rename = "type")]
    pub kind: JointType,
    /// Link length.
    pub a: f64,
    /// Link twist.
    pub alpha: f64,
    /// Link offset.
    pub d: f64,
    /// Joint angle offset.
    pub theta: f64,
    /// Hayati-Mirmirani tilt about y (angle unit), written only where nonzero: standard rows
    /// `Rz(theta + q) Tz(d) Tx(a) Rx(alpha) Ry(beta)`, modified rows
    /// `Rx(alpha) Tx(a) Ry(beta) Rz(theta + q) Tz(d)` (see `dh_core::DhRow::beta`). A
    /// calibrated pair of nearly parallel axes carries it instead of a far common normal.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub beta: Option<f64>,
    /// Lower joint limit (absent for continuous joints).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lower: Option<f64>,
    /// Upper joint limit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub upper: Option<f64>,
    /// Coupling to another joint.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mimic: Option<MimicDoc>,
}

/// One estimated effect parameter (see `dh_calib::effects` for the names).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EffectDoc {
    /// Parameter name, e.g. `gear_ratio:joint_2`, `compliance:joint_3`, `scale`.
    pub name: String,
    /// Estimate, in `unit` (SI: effect units do not follow the sheet's length and angle unit).
    pub value: f64,
    /// Unit of the value, e.g. `rad/rad`, `rad/(N m)`.
    pub unit: String,
    /// Standard uncertainty of the estimate, in `unit`, where the fit gave one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub std_error: Option<f64>,
}

/// Tolerances echoed in outputs (metres, radians, whatever the sheet's units).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TolerancesDoc {
    /// Linear tolerance (metres).
    pub linear: f64,
    /// Angular tolerance (radians).
    pub angular: f64,
}

/// Classification of one consecutive pair of axes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PairDoc {
    /// The two joints.
    pub joints: [String; 2],
    /// intersecting | parallel | antiparallel | coincident | coincident (opposite) | skew.
    pub relation: String,
    /// Angle between the axes (angle unit).
    pub angle: f64,
    /// Common normal length (length unit).
    pub distance: f64,
}

/// The result of the self-check.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VerificationDoc {
    /// Joint-value samples compared.
    pub samples: usize,
    /// Seed of the sampler.
    pub seed: u64,
    /// Largest tip position deviation (metres).
    pub max_position_error: f64,
    /// Largest tip orientation deviation (radians).
    pub max_orientation_error: f64,
    /// Position bound it must stay within (metres).
    pub position_bound: f64,
    /// Orientation bound (radians).
    pub orientation_bound: f64,
    /// Whether both stayed within their bounds.
    pub passed: bool,
    /// What the written table was compared with, when not the URDF (e.g. "the input sheet").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub against: Option<String>,
}

/// A DH sheet as written to and read from YAML or JSON.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SheetDoc {
    /// Robot name (free text).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub robot: Option<String>,
    /// Where the numbers come from (free text).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
    /// URDF base link of the chain (extraction output).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub base_link: Option<String>,
    /// URDF tip link of the chain (extraction output).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tip_link: Option<String>,
    /// standard | modified.
    pub convention: ConventionDoc,
    /// m | mm.
    pub length_unit: LengthUnit,
    /// rad | deg.
    pub angle_unit: AngleUnit,
    /// DH frame 0 in the base link frame.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub base: Option<PoseDoc>,
    /// Tip link frame in the last DH frame.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tool: Option<PoseDoc>,
    /// Rows, base to tip.
    pub joints: Vec<JointDoc>,
    /// Joints whose DH value is a sum over measured joint values: `{joint: {driver: coefficient,
    /// ...}}`, value = Σ coefficient × driver (the driver may be the joint's own column). For
    /// controllers that report other joint variables than the serial chain's, e.g. FANUC's J3
    /// measured from the horizontal: `joint_3: {joint_3: 1, joint_2: 1}`. Used when measurement
    /// files are read; a joint without its own term needs no column.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coupled:
        Option<std::collections::BTreeMap<String, std::collections::BTreeMap<String, f64>>>,
    /// Estimated non-geometric effects (`calibrate --out`): what the fit used besides the DH
    /// values. No DH table can hold them; every command reads them, and one that cannot use
    /// them says so naming each.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub effects: Option<Vec<EffectDoc>>,
    /// Branches of a kinematic tree: the sheet's own `joints` are then the trunk and its
    /// `tool` the branch point (see [`crate::tree_sheet`]). Only `calibrate` reads trees.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub branches: Option<Vec<BranchDoc>>,
    /// Link masses of a tree sheet (see [`InertialsDoc`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inertials: Option<InertialsDoc>,
    /// Consecutive axis pairs (extraction output).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pairs: Option<Vec<PairDoc>>,
    /// Tolerances used (extraction output; metres and radians).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tolerances: Option<TolerancesDoc>,
    /// Warnings (extraction output).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub warnings: Option<Vec<String>>,
    /// Self-check (extraction output).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub verification: Option<VerificationDoc>,
    /// What circle-point analysis found (`cpa` output; ignored on input).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cpa: Option<serde_yaml::Value>,
    /// How a calibrated sheet was fitted (`calibrate --out`; ignored on input).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub calibration: Option<serde_yaml::Value>,
    /// What simulated data was generated from (`simulate`'s truth file; ignored on input).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub truth: Option<serde_yaml::Value>,
}

/// One branch of a tree sheet (see [`crate::tree_sheet`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BranchDoc {
    /// Name: the targets that ride on the branch are named by it.
    pub name: String,
    /// The branch's DH frame 0 in the trunk's branch point frame (the mount); identity when
    /// absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub base: Option<PoseDoc>,
    /// The branch's tip in its last DH frame; identity when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tool: Option<PoseDoc>,
    /// Rows, mount to tip (at least one).
    pub joints: Vec<JointDoc>,
}

/// The frame link centres of mass are given in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ComFrame {
    /// The base link frame with every joint at zero.
    #[default]
    BaseAtZero,
    /// The DH frame of the link's row (the frame its joint moves).
    Dh,
}

/// One link's mass (`inertials.links`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinkDoc {
    /// The joint that moves the link.
    pub joint: String,
    /// Mass, kg.
    pub mass: f64,
    /// Centre of mass, metres, in the `com_frame`.
    pub com: [f64; 3],
}

/// A payload at a tip (`inertials.payloads`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PayloadDoc {
    /// The branch whose tip carries it (required in a tree; absent for a serial robot).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub branch: Option<String>,
    /// Mass, kg.
    pub mass: f64,
    /// Centre of mass in the tip frame, metres.
    pub com: [f64; 3],
}

/// Link masses for the gravity effects (compliance, lateral compliance, backlash): the
/// `inertials` key of a tree sheet, or a `calibrate --inertials` file given with a tree.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InertialsDoc {
    /// The frame of `links[].com` (default `base_at_zero`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub com_frame: Option<ComFrame>,
    /// Gravity in the base link frame, m/s² [default: 0, 0, −9.80665].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gravity: Option<[f64; 3]>,
    /// Link masses.
    pub links: Vec<LinkDoc>,
    /// Payloads at the tips.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub payloads: Option<Vec<PayloadDoc>>,
}

/// `standard` or `modified` in a sheet.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum ConventionDoc {
    /// Standard (distal) DH.
    Standard,
    /// Modified (Craig) DH.
    Modified,
}

impl From<ConventionDoc> for Convention {
    fn from(c: ConventionDoc) -> Self {
        match c {
            ConventionDoc::Standard => Convention::Standard,
            ConventionDoc::Modified => Convention::Modified,
        }
    }
}

impl From<Convention> for ConventionDoc {
    fn from(c: Convention) -> Self {
        match c {
            Convention::Standard => ConventionDoc::Standard,
            Convention::Modified => ConventionDoc::Modified,
        }
    }
}

/// A sheet read into SI units, remembering which transforms it gave.
#[derive(Clone, Debug, PartialEq)]
pub struct Sheet {
    /// The table in metres and radians; a missing base or tool is the identity.
    pub table: DhTable,
    /// The sheet gave `base`.
    pub has_base: bool,
    /// The sheet gave `tool`.
    pub has_tool: bool,
    /// Free-text robot name.
    pub robot: Option<String>,
    /// Free-text source.
    pub source: Option<String>,
    /// The sheet's length unit.
    pub length_unit: LengthUnit,
    /// The sheet's angle unit.
    pub angle_unit: AngleUnit,
    /// Warnings about suspicious values (not errors).
    pub warnings: Vec<String>,
    /// Coupled joints (see [`SheetDoc::coupled`]): `(joint, [(driver, coefficient)])`, in row
    /// order.
    pub coupled: Vec<(String, Vec<(String, f64)>)>,
    /// Estimated effects the sheet carries (see [`SheetDoc::effects`]).
    pub effects: Vec<EffectDoc>,
}

impl Sheet {
    /// The warning a command that cannot use the sheet's effects gives (`what` says what it
    /// does instead), naming each; `None` without effects.
    pub fn effects_warning(&self, origin: &str, what: &str) -> Option<String> {
        (!self.effects.is_empty()).then(|| {
            format!(
                "{origin}: effects: {} cannot be represented here and are ignored: {what}",
                self.effects
                    .iter()
                    .map(|e| format!("'{}' = {:e} {}", e.name, e.value, e.unit))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })
    }
}

impl Sheet {
    /// Parses a sheet from YAML or JSON text (JSON is YAML). `origin` names the file in errors.
    ///
    /// # Errors
    /// Syntax errors with line and column, unknown or missing keys, non-finite numbers,
    /// duplicate joint names, control characters in a name, a row without joints, limits out of order, a joint that mimics
    /// itself. A mimic naming no row is a warning, not an error: a URDF chain's joint may follow
    /// one on another branch (a gripper's fingers), and `extract` writes that driver's name.
    pub fn parse(text: &str, origin: &str) -> Result<Sheet> {
        parse_doc(text, origin)?.into_sheet(origin)
    }
}

impl SheetDoc {
    /// A sheet of just these: convention, units, base, tool and rows (no facts attached).
    pub fn new(
        convention: ConventionDoc,
        length_unit: LengthUnit,
        angle_unit: AngleUnit,
        base: Option<PoseDoc>,
        tool: Option<PoseDoc>,
        joints: Vec<JointDoc>,
    ) -> SheetDoc {
        SheetDoc {
            robot: None,
            source: None,
            base_link: None,
            tip_link: None,
            convention,
            length_unit,
            angle_unit,
            base,
            tool,
            joints,
            coupled: None,
            effects: None,
            branches: None,
            inertials: None,
            pairs: None,
            tolerances: None,
            warnings: None,
            verification: None,
            cpa: None,
            calibration: None,
            truth: None,
        }
    }

    /// A sheet of `table` in the given units (no extraction facts attached).
    pub fn from_table(table: &DhTable, length: LengthUnit, angle: AngleUnit) -> SheetDoc {
        let pose = |p: &Isometry3<f64>| {
            let (xyz, rpy) = to_xyz_rpy(p);
            PoseDoc {
                xyz: xyz.map(|v| length.from_si(v)),
                rpy: rpy.map(|v| angle.from_si(v)),
            }
        };
        let joints = table
            .rows
            .iter()
            .map(|r| {
                let limit = |v: f64| match r.kind {
                    JointKind::Prismatic => length.from_si(v),
                    JointKind::Revolute => angle.from_si_unwrapped(v),
                };
                JointDoc {
                    name: r.name.clone(),
                    kind: match r.kind {
                        JointKind::Revolute => JointType::Revolute,
                        JointKind::Prismatic => JointType::Prismatic,
                    },
                    a: length.from_si(r.a),
                    alpha: angle.from_si(r.alpha),
                    d: length.from_si(r.d),
                    theta: angle.from_si(r.theta),
                    beta: (r.beta != 0.0).then(|| angle.from_si_unwrapped(r.beta)),
                    lower: r.limits.map(|l| limit(l.lower)),
                    upper: r.limits.map(|l| limit(l.upper)),
                    mimic: r.mimic.as_ref().map(|m| MimicDoc {
                        joint: m.joint.clone(),
                        multiplier: m.multiplier,
                        offset: limit(m.offset),
                    }),
                }
            })
            .collect();
        SheetDoc::new(
            table.convention.into(),
            length,
            angle,
            Some(pose(&table.base)),
            Some(pose(&table.tool)),
            joints,
        )
    }
}
