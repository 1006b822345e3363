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

use anyhow::{bail, Context, Result};
use dh_calib::import::{too_deep_at, MAX_FLOW_DEPTH};
use dh_core::pose::{from_xyz_rpy, to_xyz_rpy};
use dh_core::{Convention, DhRow, DhTable, JointKind, Limits, Mimic};
use nalgebra::Isometry3;
use serde::{Deserialize, Serialize};

use crate::units::{AngleUnit, LengthUnit};

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
    pub branches: Option<Vec<crate::tree_sheet::BranchDoc>>,
    /// Link masses of a tree sheet (see [`crate::tree_sheet::InertialsDoc`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inertials: Option<crate::tree_sheet::InertialsDoc>,
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

/// `standard` or `modified` in a sheet.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
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

/// Largest magnitude of a sheet value, in its own unit: an overflow guard (found by fuzzing the
/// URDF path: a finite 1e306 m became infinite in millimetres). Far beyond anything `extract`
/// writes (an ill-conditioned common normal of URDF axes within 1e9 m stays below 1e25 m, 1e28
/// mm), and far from overflow in any unit conversion or forward kinematics.
const MAX_MAGNITUDE: f64 = 1e30;

/// Largest magnitude of a sheet value in metres or radians: a thousandth of
/// [`MAX_MAGNITUDE`], so that whatever a sheet holds can be written in any unit (mm, deg: at
/// most x1000) and read back.
const MAX_SI_MAGNITUDE: f64 = 1e27;

/// Is `v` (in a unit of `scale` metres or radians) beyond what a sheet may hold?
fn too_large(v: f64, scale: f64) -> bool {
    v.abs() > MAX_MAGNITUDE || (v * scale).abs() > MAX_SI_MAGNITUDE
}

/// Largest magnitude of a DH angle or `rpy` angle (radians): past it a double wraps the angle
/// to the circle with an error above 1e-10 rad, and 9.9e26 rad has no angle left in it at all.
/// Joint limits may be larger (they only bound the joint values drawn).
const MAX_ANGLE: f64 = 1e6;

/// Lengths beyond this in a sheet that says metres are almost surely millimetres (m).
const SUSPICIOUS_METRES: f64 = 20.0;

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

/// Parses the text of a sheet (serial or tree) into its document, refusing what no sheet may
/// hold (see [`Sheet::parse`]); the numbers are checked when it is converted.
///
/// # Errors
/// Syntax errors with line and column, unknown or missing keys, nesting too deep.
pub fn parse_doc(text: &str, origin: &str) -> Result<SheetDoc> {
    // A byte-order mark is no part of the first key (URDF and JSON readers skip it too).
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    {
        if text.trim().is_empty() {
            bail!("{origin}: the sheet is empty; expected YAML or JSON with 'convention', 'length_unit', 'angle_unit' and 'joints'");
        }
        check_nesting(text, origin)?;
        not_a_sheet(text, origin)?;
        let doc: SheetDoc = serde_yaml::from_str(text).map_err(|e| {
            let mut message = shortened(&e.to_string());
            let at = match e.location() {
                Some(l) => {
                    // serde_yaml repeats the position in its message; say it once, up front.
                    let said = format!(" at line {} column {}", l.line(), l.column());
                    if let Some(k) = message.find(&said) {
                        message.replace_range(k..k + said.len(), "");
                    }
                    // For a repeated key serde_yaml points at the start of the mapping: point
                    // at the repetition instead.
                    let (line, column) = duplicate_key_at(text, &message, l.index())
                        .unwrap_or((l.line(), l.column()));
                    format!(" (line {line}, column {column})")
                }
                None => String::new(),
            };
            anyhow::anyhow!("{origin}{at}: {message}")
        })?;
        Ok(doc)
    }
}

/// Longest error message quoted from the YAML parser: it may quote a whole document (a CSV file
/// reads as one long string), and one line of it says enough.
const MAX_MESSAGE: usize = 200;

/// `message` cut at [`MAX_MESSAGE`] characters, saying so.
fn shortened(message: &str) -> String {
    match message.char_indices().nth(MAX_MESSAGE) {
        Some((k, _)) => format!("{}... (cut)", &message[..k]),
        None => message.to_string(),
    }
}

/// Refuses a file whose first line of content cannot start a sheet (a mapping in YAML, `{` in
/// JSON), saying what it looks like and quoting that line (at most 80 characters), instead of the
/// YAML parser's "expected struct" with the whole file quoted.
fn not_a_sheet(text: &str, origin: &str) -> Result<()> {
    let Some((k, first)) = text.lines().enumerate().find(|(_, l)| {
        let t = l.trim();
        !t.is_empty() && !t.starts_with('#') && t != "---" && !t.starts_with('%')
    }) else {
        return Ok(());
    };
    let t = first.trim();
    if t.starts_with('{') || t.contains(": ") || t.ends_with(':') {
        return Ok(());
    }
    let looks = if t.contains(',') || t.contains(';') || t.contains('\t') {
        "a CSV table (a measurement file?)"
    } else if t.starts_with('<') {
        "XML (a URDF?)"
    } else {
        "text without YAML keys"
    };
    let quoted: String = t.chars().take(80).collect();
    let cut = if t.chars().count() > 80 { "..." } else { "" };
    Err(crate::error::hinted(
        format!(
            "{origin} (line {}): expected a DH sheet (YAML or JSON with 'convention', 'length_unit', 'angle_unit' and 'joints'), found what looks like {looks}: '{}{cut}'",
            k + 1,
            crate::guard::escape(&quoted)
        ),
        "measurements go to calibrate --data; a URDF goes to extract or check as the robot",
    ))
}

/// Where the key named in serde's "duplicate field `KEY`" message is given the second time at
/// or after byte `from` (the mapping's start): (line, column), both from 1. `None` for other
/// messages or when the key is not found as a key (`KEY:` after a line start, `-`, `{` or `,`).
fn duplicate_key_at(text: &str, message: &str, from: usize) -> Option<(usize, usize)> {
    let key = message
        .split_once("duplicate field `")?
        .1
        .split_once('`')?
        .0;
    let mut seen = 0;
    let mut k = from.min(text.len());
    while let Some(found) = text.get(k..)?.find(key) {
        let at = k + found;
        let before = text[..at].trim_end_matches([' ', '\t', '"', '\'']);
        let after = text[at + key.len()..].trim_start_matches(['"', '\'', ' ', '\t']);
        let starts_key = before.is_empty() || before.ends_with(['\n', '-', '{', ',']);
        if starts_key && after.starts_with(':') {
            seen += 1;
            if seen == 2 {
                let line = text[..at].matches('\n').count() + 1;
                let column = text[..at]
                    .rsplit('\n')
                    .next()
                    .map_or(0, |l| l.chars().count())
                    + 1;
                return Some((line, column));
            }
        }
        k = at + key.len();
    }
    None
}

/// Refuses flow collections nested deeper than [`MAX_FLOW_DEPTH`] (a sheet needs three
/// levels; libyaml's scanner takes time quadratic in the depth), in one linear pass.
pub(crate) fn check_nesting(text: &str, origin: &str) -> Result<()> {
    if let Some(line) = too_deep_at(text) {
        bail!(
            "{origin} (line {line}): expected lists and maps nested at most \
             {MAX_FLOW_DEPTH} deep, found deeper"
        );
    }
    Ok(())
}

impl SheetDoc {
    /// Converts to SI units and checks the numbers (see [`Sheet::parse`]).
    ///
    /// # Errors
    /// As [`Sheet::parse`].
    pub fn into_sheet(self, origin: &str) -> Result<Sheet> {
        if let Some(branches) = &self.branches {
            return Err(crate::error::hinted(
                format!(
                    "{origin}: 'branches': a tree sheet (a trunk and {} branch(es): {}) describes no single chain; only 'calibrate' reads trees",
                    branches.len(),
                    branches
                        .iter()
                        .map(|b| format!("'{}'", b.name))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
                "calibrate the whole tree with: urdf-dh calibrate --model SHEET --data D.csv (from a file, not standard input); for other commands give one chain as a serial sheet (the trunk's joints followed by one branch's)",
            ));
        }
        if self.inertials.is_some() {
            return Err(crate::error::hinted(
                format!("{origin}: 'inertials': only a tree sheet (with 'branches') carries its link masses"),
                "give a serial robot's link masses to calibrate with --inertials FILE",
            ));
        }
        if self.joints.is_empty() {
            bail!("{origin}: 'joints' is empty; expected at least one joint");
        }
        let (lu, au) = (self.length_unit, self.angle_unit);
        let mut warnings = Vec::new();
        let mut rows = Vec::with_capacity(self.joints.len());
        let mut seen = std::collections::HashSet::new();
        for j in &self.joints {
            if !seen.insert(j.name.as_str()) {
                bail!("{origin}: joint '{}' appears twice", j.name);
            }
            rows.push(row_of(j, lu, au, origin, &mut warnings)?);
        }
        check_mimics(&rows, origin, &mut warnings)?;
        let table = DhTable {
            convention: self.convention.into(),
            base: pose_of(self.base.as_ref(), lu, au, origin, "base")
                .context("reading the base transform")?,
            tool: pose_of(self.tool.as_ref(), lu, au, origin, "tool")
                .context("reading the tool transform")?,
            rows,
        };
        let coupled = coupled_of(self.coupled.as_ref(), &table.rows, origin)?;
        let effects = effects_of(self.effects, origin)?;
        Ok(Sheet {
            coupled,
            effects,
            table,
            has_base: self.base.is_some(),
            has_tool: self.tool.is_some(),
            robot: self.robot,
            source: self.source,
            length_unit: self.length_unit,
            angle_unit: self.angle_unit,
            warnings,
        })
    }

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

/// Row `j` of a sheet in SI units; suspicious units add to `warnings`. `origin` prefixes
/// every message (the file, and for a tree sheet the line and branch).
///
/// # Errors
/// A control character in the name, a non-finite or huge value, limits out of order or
/// half given, a bad mimic multiplier or offset.
pub(crate) fn row_of(
    j: &JointDoc,
    length_unit: LengthUnit,
    angle_unit: AngleUnit,
    origin: &str,
    warnings: &mut Vec<String>,
) -> Result<DhRow> {
    let (lu, au) = (length_unit.metres(), angle_unit.radians());
    if j.name.trim().is_empty() {
        bail!(
            "{origin}: joint '{}': expected a name, found a blank one",
            j.name
        );
    }
    if let Some((k, c)) = j
        .name
        .chars()
        .enumerate()
        .find(|(_, c)| crate::guard::is_spoofing(*c))
    {
        // As the URDF reader: such a name corrupts tables, CSV and terminals (and a bidi
        // override reorders what they show).
        bail!(
            "{origin}: joint '{}': expected a name without control or bidi characters, found \
             U+{:04X} at character {}",
            crate::guard::escape(&j.name),
            u32::from(c),
            k + 1
        );
    }
    let limit_scale = if j.kind == JointType::Prismatic {
        lu
    } else {
        au
    };
    for (field, v, scale) in [
        ("a", j.a, lu),
        ("alpha", j.alpha, au),
        ("d", j.d, lu),
        ("theta", j.theta, au),
    ]
    .into_iter()
    .chain(j.beta.map(|v| ("beta", v, au)))
    .chain(j.lower.map(|v| ("lower", v, limit_scale)))
    .chain(j.upper.map(|v| ("upper", v, limit_scale)))
    {
        if !v.is_finite() {
            bail!(
                "{origin}: joint '{}': {field} must be a finite number, found {v}",
                j.name
            );
        }
        if too_large(v, scale) {
            bail!(
                "{origin}: joint '{}': {field}: expected a magnitude of at most 1e30 (1e27 m or rad), found {v:e}",
                j.name
            );
        }
        if matches!(field, "alpha" | "theta") && (v * scale).abs() > MAX_ANGLE {
            bail!(
                "{origin}: joint '{}': {field}: expected an angle of at most {MAX_ANGLE:e} rad, found {v:e} {} (a double holds no angle that large)",
                j.name,
                angle_unit.symbol()
            );
        }
    }
    if let Some(b) = j.beta {
        if (b * au).abs() > MAX_TILT {
            bail!(
                "{origin}: joint '{}': beta: expected a tilt of at most 90 degrees, found {b} {}",
                j.name,
                angle_unit.symbol()
            );
        }
    }
    let kind = match j.kind {
        JointType::Revolute => JointKind::Revolute,
        JointType::Prismatic => JointKind::Prismatic,
    };
    let limit_unit = if kind == JointKind::Prismatic { lu } else { au };
    let limits = match (j.lower, j.upper) {
        (Some(l), Some(u)) if l > u => {
            bail!(
                "{origin}: joint '{}': lower limit {l} is above upper limit {u}",
                j.name
            )
        }
        (Some(l), Some(u)) => Some(Limits {
            lower: l * limit_unit,
            upper: u * limit_unit,
        }),
        (None, None) => None,
        _ => bail!(
            "{origin}: joint '{}': give both 'lower' and 'upper', or neither",
            j.name
        ),
    };
    if length_unit == LengthUnit::M
        && (j.a.abs() > SUSPICIOUS_METRES || j.d.abs() > SUSPICIOUS_METRES)
    {
        warnings.push(format!(
            "{origin}: joint '{}': a = {}, d = {} with length_unit m looks like millimetres; set length_unit: mm if so",
            j.name, j.a, j.d
        ));
    }
    if angle_unit == AngleUnit::Rad
        && (j.alpha.abs() > 2.0 * std::f64::consts::PI + 1e-9
            || j.theta.abs() > 2.0 * std::f64::consts::PI + 1e-9)
    {
        warnings.push(format!(
            "{origin}: joint '{}': alpha = {}, theta = {} with angle_unit rad looks like degrees; set angle_unit: deg if so",
            j.name, j.alpha, j.theta
        ));
    }
    let mimic = match &j.mimic {
        Some(m) => {
            if !m.multiplier.is_finite()
                || !m.offset.is_finite()
                || m.multiplier.abs() > MAX_MAGNITUDE
                || m.offset.abs() > MAX_MAGNITUDE
            {
                bail!(
                    "{origin}: joint '{}': mimic multiplier and offset must be finite, of magnitude at most 1e30",
                    j.name
                );
            }
            Some(Mimic {
                joint: m.joint.clone(),
                multiplier: m.multiplier,
                offset: m.offset * limit_unit,
            })
        }
        None => None,
    };
    Ok(DhRow {
        name: j.name.clone(),
        kind,
        a: j.a * lu,
        alpha: j.alpha * au,
        d: j.d * lu,
        theta: j.theta * au,
        beta: j.beta.map_or(0.0, |b| b * au),
        limits,
        mimic,
    })
}

/// The largest tilt a row may carry (radians): a Hayati tilt is a small correction of a
/// nearly parallel pair, and beyond a right angle the pair is no such pair.
const MAX_TILT: f64 = std::f64::consts::FRAC_PI_2;

/// Checks a sheet's `effects` (finite values and uncertainties, distinct non-empty names).
///
/// # Errors
/// A bad value, uncertainty or name, naming the effect.
pub(crate) fn effects_of(given: Option<Vec<EffectDoc>>, origin: &str) -> Result<Vec<EffectDoc>> {
    let effects = given.unwrap_or_default();
    let mut seen = std::collections::HashSet::new();
    for e in &effects {
        if e.name.is_empty() || e.name.chars().any(char::is_control) {
            bail!(
                "{origin}: effects: expected a printable effect name, found '{}'",
                e.name.escape_debug()
            );
        }
        if !seen.insert(e.name.as_str()) {
            bail!("{origin}: effects: '{}' appears twice", e.name);
        }
        if !(e.value.is_finite() && e.value.abs() <= MAX_MAGNITUDE) {
            bail!(
                "{origin}: effects: '{}': expected a finite value, found {}",
                e.name,
                e.value
            );
        }
        if let Some(s) = e.std_error {
            if !(s.is_finite() && s >= 0.0) {
                bail!(
                    "{origin}: effects: '{}': expected a finite std_error >= 0, found {s}",
                    e.name
                );
            }
        }
    }
    Ok(effects)
}

/// A sheet's pose in SI units (identity when absent); `what` names it in errors.
///
/// # Errors
/// Non-finite or huge numbers.
pub(crate) fn pose_of(
    p: Option<&PoseDoc>,
    length_unit: LengthUnit,
    angle_unit: AngleUnit,
    origin: &str,
    what: &str,
) -> Result<Isometry3<f64>> {
    let (lu, au) = (length_unit.metres(), angle_unit.radians());
    match p {
        None => Ok(Isometry3::identity()),
        Some(p) => {
            if p.xyz.iter().chain(&p.rpy).any(|v| !v.is_finite()) {
                bail!("{origin}: {what}: xyz and rpy must be finite numbers");
            }
            if let Some(v) = p.xyz.iter().find(|v| too_large(**v, lu)) {
                bail!("{origin}: {what}: xyz: expected a magnitude of at most 1e30 (1e27 m), found {v:e}");
            }
            if let Some(v) = p.rpy.iter().find(|v| (**v * au).abs() > MAX_ANGLE) {
                bail!(
                    "{origin}: {what}: rpy: expected an angle of at most {MAX_ANGLE:e} rad, found {v:e} {} (a double holds no angle that large)",
                    angle_unit.symbol()
                );
            }
            Ok(from_xyz_rpy(p.xyz.map(|v| v * lu), p.rpy.map(|v| v * au)))
        }
    }
}

/// Refuses a row that mimics itself; warns of a mimic whose driver is no row of `rows`.
///
/// # Errors
/// A row that mimics itself.
pub(crate) fn check_mimics(rows: &[DhRow], origin: &str, warnings: &mut Vec<String>) -> Result<()> {
    for r in rows {
        let Some(m) = &r.mimic else { continue };
        if m.joint == r.name {
            bail!(
                "{origin}: joint '{}': mimic: expected another joint to follow, found itself",
                r.name
            );
        }
        if !rows.iter().any(|d| d.name == m.joint) {
            warnings.push(format!(
                "{origin}: joint '{}': mimic: follows '{}', which is no joint of the sheet (joints: {}); it moves on its own here",
                r.name,
                m.joint,
                rows.iter().map(|d| format!("'{}'", d.name)).collect::<Vec<_>>().join(", ")
            ));
        }
    }
    Ok(())
}

/// The `coupled` key of a sheet: `{joint: {driver: coefficient}}`.
pub type CoupledDoc = std::collections::BTreeMap<String, std::collections::BTreeMap<String, f64>>;

/// A coupled joint and its `(driver, coefficient)` terms.
pub type Coupled = (String, Vec<(String, f64)>);

/// Coupled joints (see [`SheetDoc::coupled`]) checked against `rows`, in row order.
///
/// # Errors
/// A coupled joint or driver that is no row, a coupled joint with a mimic, no driver, a
/// non-finite coefficient.
pub(crate) fn coupled_of(
    given: Option<&CoupledDoc>,
    rows: &[DhRow],
    origin: &str,
) -> Result<Vec<Coupled>> {
    let mut coupled = Vec::new();
    for (joint, terms) in given.into_iter().flatten() {
        let row = rows.iter().find(|r| &r.name == joint);
        match row {
            None => bail!("{origin}: coupled: '{joint}' is no joint of the sheet"),
            Some(r) if r.mimic.is_some() => {
                bail!("{origin}: coupled: joint '{joint}' also has a mimic; give one of them")
            }
            Some(_) => {}
        }
        if terms.is_empty() {
            bail!("{origin}: coupled: joint '{joint}': expected at least one driver");
        }
        for (driver, c) in terms {
            if !c.is_finite() {
                bail!("{origin}: coupled: joint '{joint}': coefficient of '{driver}' must be finite, found {c}");
            }
            if driver != joint && !rows.iter().any(|r| &r.name == driver) {
                bail!("{origin}: coupled: joint '{joint}': driver '{driver}' is no joint of the sheet");
            }
        }
        coupled.push((
            joint.clone(),
            terms.iter().map(|(d, c)| (d.clone(), *c)).collect(),
        ));
    }
    let order = |j: &str| rows.iter().position(|r| r.name == j);
    coupled.sort_by_key(|(j, _)| order(j));
    Ok(coupled)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_convert_on_read_and_write() {
        let text = "convention: standard\nlength_unit: mm\nangle_unit: deg\njoints:\n  - {name: j1, type: revolute, a: 180, alpha: -90, d: 400, theta: 0, lower: -155, upper: 155}\n";
        let s = Sheet::parse(text, "t.yaml").unwrap();
        let r = &s.table.rows[0];
        assert!(
            (r.a - 0.18).abs() < 1e-15 && (r.alpha + std::f64::consts::FRAC_PI_2).abs() < 1e-15
        );
        assert!(!s.has_base && !s.has_tool);
        let back = SheetDoc::from_table(&s.table, LengthUnit::Mm, AngleUnit::Deg);
        assert!((back.joints[0].a - 180.0).abs() < 1e-12);
        assert!((back.joints[0].upper.unwrap() - 155.0).abs() < 1e-12);
    }

    #[test]
    fn mimics_of_no_row_warn_and_of_themselves_fail() {
        let sheet = |driver: &str| {
            format!("convention: standard\nlength_unit: m\nangle_unit: rad\njoints:\n  - {{name: a, type: revolute, a: 0, alpha: 0, d: 0, theta: 0}}\n  - {{name: b, type: revolute, a: 0, alpha: 0, d: 0, theta: 0, mimic: {{joint: {driver}}}}}\n")
        };
        assert!(Sheet::parse(&sheet("a"), "s.yaml")
            .unwrap()
            .warnings
            .is_empty());
        let s = Sheet::parse(&sheet("finger_1"), "s.yaml").unwrap();
        assert_eq!(s.warnings.len(), 1);
        assert!(
            s.warnings[0]
                .contains("follows 'finger_1', which is no joint of the sheet (joints: 'a', 'b')"),
            "{:?}",
            s.warnings
        );
        let e = Sheet::parse(&sheet("b"), "s.yaml").unwrap_err();
        assert!(
            e.to_string()
                .contains("joint 'b': mimic: expected another joint to follow, found itself"),
            "{e}"
        );
    }

    #[test]
    fn magnitudes_beyond_any_robot_are_refused() {
        let e = Sheet::parse(
            "convention: standard\nlength_unit: m\nangle_unit: rad\njoints:\n  - {name: a, type: revolute, a: 0, alpha: 0, d: 1e306, theta: 0}\n",
            "s.yaml",
        )
        .unwrap_err();
        assert!(
            e.to_string().contains(
                "joint 'a': d: expected a magnitude of at most 1e30 (1e27 m or rad), found 1e306"
            ),
            "{e}"
        );
        // Found by fuzzing: extract writes ill-conditioned rows kilometres long, and they
        // must read back (here 7.9e9 mm, from a mutated KUKA URDF).
        assert!(Sheet::parse(
            "convention: standard\nlength_unit: mm\nangle_unit: deg\njoints:\n  - {name: a, type: revolute, a: 7.948966e9, alpha: 0, d: 0, theta: 0}\n",
            "s.yaml",
        )
        .is_ok());
    }

    #[test]
    fn deep_nesting_is_refused_at_once() {
        // Found by fuzzing: libyaml scans unclosed flow collections in quadratic time.
        let text = format!("convention: standard\njoints: {}", "[".repeat(8000));
        let start = std::time::Instant::now();
        let e = Sheet::parse(&text, "s.yaml").unwrap_err();
        assert!(start.elapsed() < std::time::Duration::from_secs(1));
        assert!(
            e.to_string()
                .contains("s.yaml (line 2): expected lists and maps nested at most 64 deep"),
            "{e}"
        );
        // Brackets in quotes and comments do not count.
        let text = format!(
            "# {}\nconvention: standard\nlength_unit: m\nangle_unit: rad\nrobot: '{}'\njoints: [{{name: a, type: revolute, a: 0, alpha: 0, d: 0, theta: 0}}]\n",
            "[".repeat(100),
            "{".repeat(100)
        );
        assert!(Sheet::parse(&text, "s.yaml").is_ok());
    }

    #[test]
    fn unknown_keys_and_bad_values_are_errors() {
        let e = Sheet::parse(
            "convention: standard\nlength_unit: m\nangle_unit: rad\njoints: []\nfoo: 1\n",
            "s.yaml",
        )
        .unwrap_err();
        assert!(e.to_string().contains("unknown field `foo`"), "{e}");
        let e = Sheet::parse(
            "convention: sideways\nlength_unit: m\nangle_unit: rad\njoints: []\n",
            "s.yaml",
        )
        .unwrap_err();
        assert!(e.to_string().contains("line 1"), "{e}");
    }

    #[test]
    fn a_repeated_key_is_located_where_it_repeats() {
        let text =
            "convention: standard\nlength_unit: m\nangle_unit: deg\nangle_unit: rad\njoints: []\n";
        let e = parse_doc(text, "s.yaml").unwrap_err().to_string();
        assert!(e.contains("(line 4, column 1)"), "{e}");
        let flow = "joints:\n  - {name: j, d: 0, a: 0, d: 1}\n";
        assert_eq!(
            duplicate_key_at(flow, "joints[0]: duplicate field `d`", 10),
            Some((2, 27))
        );
        assert_eq!(duplicate_key_at(flow, "some other message", 0), None);
    }
}
