//! Tree sheets: the DH sheet format (see [`crate::sheet`]) with `branches`, for robots whose
//! chains share a trunk (two arms on one torso). Only `calibrate` reads them; the other
//! commands take one chain and refuse a tree sheet.
//!
//! ```yaml
//! convention: modified            # one convention and one pair of units for the whole tree
//! length_unit: m
//! angle_unit: deg
//! base: {xyz: [0, 0, 0.5884], rpy: [0, 0, 0]}   # trunk DH frame 0 in the base link frame
//! tool: {xyz: [0, 0, 0], rpy: [0, 0, 0]}        # the branch point in the trunk's last DH frame
//! joints:                         # the trunk (may be empty: branches on a fixed base)
//!   - {name: torso_1, type: revolute, a: 0, alpha: 0, d: 0.1055, theta: 0}
//! coupled:                        # any joint of the tree; drivers are measured columns
//!   torso_4: {torso_2: -1, torso_3: -1}
//! branches:                       # at least one; each a sheet of its own rows
//!   - name: right                 # targets ride on it (see below)
//!     base: {xyz: [0.19, 0.088, -0.256], rpy: [0, 150, 0]}  # mount in the branch point frame
//!     tool: {xyz: [0, 0.118, 0], rpy: [90, 0, 180]}        # tip in the branch's last DH frame
//!     joints:
//!       - {name: right_1, type: revolute, a: 0, alpha: 0, d: 0, theta: 0}
//! inertials:                      # optional: link masses for the gravity effects
//!   com_frame: dh                 # dh (the row's DH frame) | base_at_zero (default)
//!   gravity: [0, 0, -9.80665]     # m/s² in the base link frame (optional)
//!   links: [{joint: torso_1, mass: 4.651, com: [0.0013, 0.0154, 0.0074]}]   # kg, m
//!   payloads: [{branch: right, mass: 2.0, com: [0, 0, 0.1]}]                 # branch tip frame
//! ```
//!
//! Frames are those of [`dh_calib::tree`]: a target on branch `b` is at
//! `base · A_trunk(q) · tool · b.base · A_b(q) · b.tool · t`. Joint names are unique across
//! the tree; lengths and angles are in the sheet's units, inertials always in kg and metres.
//!
//! **Targets and branches.** A measurement file's `target` rides on the branch of its own
//! name (`right`), or on the branch named before its first `/` (`right/wrist`, `right/1`):
//! `urdf-dh import --layout dlr` names the Agile Justin markers `right` and `left`, which a
//! tree with branches `right` and `left` reads as is.

use std::collections::HashSet;

use anyhow::{bail, Result};
use dh_calib::gravity::{Inertial, Inertials};
use dh_calib::tree::{Branch, DhTree};
use dh_core::{DhRow, DhTable};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::error::hinted;
use crate::measured::LoadedModel;
use crate::sheet::{
    check_mimics, coupled_of, parse_doc, pose_of, row_of, JointDoc, PoseDoc, SheetDoc,
};
use crate::units::{AngleUnit, LengthUnit};

/// One branch of a tree sheet.
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

/// Largest mass taken as a link or payload mass (kg): an overflow guard, far above any robot.
const MAX_MASS: f64 = 1e9;

/// Largest centre-of-mass coordinate or gravity component accepted (metres, m/s²).
const MAX_INERTIAL_MAGNITUDE: f64 = 1e6;

impl InertialsDoc {
    /// The inertials of `tree` and the gravity vector, if given (metres, kg, m/s²).
    ///
    /// # Errors
    /// A non-finite, negative or huge number, a link of no joint of the tree, a payload on no
    /// branch (or without one in a tree of several branches).
    ///
    /// `text` is the file's, to name the line of a bad link.
    pub fn to_inertials(
        &self,
        tree: &DhTree,
        origin: &str,
        text: Option<&str>,
    ) -> Result<(Inertials, Option<Vector3<f64>>)> {
        let finite3 = |v: &[f64; 3], what: &str| -> Result<Vector3<f64>> {
            if v.iter()
                .any(|c| !c.is_finite() || c.abs() > MAX_INERTIAL_MAGNITUDE)
            {
                bail!(
                    "{origin}: inertials: {what}: expected finite numbers of magnitude at most {MAX_INERTIAL_MAGNITUDE:e}, found {v:?}"
                );
            }
            Ok(Vector3::new(v[0], v[1], v[2]))
        };
        let mass = |m: f64, what: &str| -> Result<f64> {
            if !(m.is_finite() && (0.0..=MAX_MASS).contains(&m)) {
                bail!("{origin}: inertials: {what}: expected a mass in kg from 0 to {MAX_MASS:e}, found {m}");
            }
            Ok(m)
        };
        let mut links = Vec::with_capacity(self.links.len());
        for l in &self.links {
            let line = text.and_then(|t| line_of(t, "joint", &l.joint, 0));
            if tree.row_index(&l.joint).is_none() {
                return Err(hinted(
                    format!(
                        "{}: inertials: link of joint '{}': expected a joint of the tree, found none of that name",
                        at(origin, line),
                        l.joint
                    ),
                    format!("the tree's joints: {}", joint_list(tree.rows())),
                ));
            }
            let what = format!("link of joint '{}'", l.joint);
            links.push((
                l.joint.clone(),
                mass(l.mass, &what)?,
                finite3(&l.com, &what)?,
            ));
        }
        let mut payloads = Vec::new();
        for p in self.payloads.iter().flatten() {
            let chain = match (&p.branch, tree.branches().len()) {
                (Some(b), _) => tree.branch_index(b).ok_or_else(|| {
                    hinted(
                        format!("{origin}: inertials: payload on branch '{b}': expected a branch of the tree, found none of that name"),
                        format!("the branches: {}", branch_list(tree)),
                    )
                })?,
                (None, 0 | 1) => 0,
                (None, _) => {
                    return Err(hinted(
                        format!("{origin}: inertials: a payload without 'branch' in a tree of several tips"),
                        format!("name the branch whose tip carries it: {}", branch_list(tree)),
                    ))
                }
            };
            payloads.push((
                chain,
                Inertial {
                    mass: mass(p.mass, "payload")?,
                    com: finite3(&p.com, "payload com")?,
                },
            ));
        }
        let inertials = match self.com_frame.unwrap_or_default() {
            ComFrame::Dh => Inertials {
                links: links
                    .into_iter()
                    .map(|(j, mass, com)| (j, Inertial { mass, com }))
                    .collect(),
                payloads,
            },
            ComFrame::BaseAtZero => Inertials::from_zero_pose(tree, &links, payloads)
                .map_err(|e| anyhow::anyhow!("{origin}: inertials: {e}"))?,
        };
        let gravity = match &self.gravity {
            Some(g) => Some(finite3(g, "gravity")?),
            None => None,
        };
        Ok((inertials, gravity))
    }

    /// Reads an inertials file (YAML or JSON; the keys of [`InertialsDoc`]).
    ///
    /// # Errors
    /// Syntax errors with line and column, unknown or missing keys.
    pub fn parse(text: &str, origin: &str) -> Result<InertialsDoc> {
        crate::sheet::check_nesting(text, origin)?;
        serde_yaml::from_str(text).map_err(|e| anyhow::anyhow!("{origin}: {e}"))
    }
}

fn joint_list(rows: &[DhRow]) -> String {
    rows.iter()
        .map(|r| r.name.as_str())
        .collect::<Vec<_>>()
        .join(", ")
}

fn branch_list(tree: &DhTree) -> String {
    tree.branches()
        .iter()
        .map(|b| b.name.as_str())
        .collect::<Vec<_>>()
        .join(", ")
}

/// A tree sheet read into SI units.
#[derive(Clone, Debug, PartialEq)]
pub struct TreeSheet {
    /// The tree (metres, radians); a missing base, tool or mount is the identity.
    pub tree: DhTree,
    /// Coupled joints (see [`SheetDoc::coupled`]), in joint order.
    pub coupled: Vec<(String, Vec<(String, f64)>)>,
    /// The sheet's `inertials`, as written (converted when calibrating).
    pub inertials: Option<InertialsDoc>,
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
}

/// The 1-based line of the `nth` (0-based) line of `text` that holds the key `name` (or
/// `joint`) with the value `value` (`name: right_1`, `{name: "right_1", ...}`, JSON
/// `"name": "right_1"`): where a tree sheet's error points. `None` when not found (the
/// message then names the branch and joint only).
fn line_of(text: &str, key: &str, value: &str, nth: usize) -> Option<usize> {
    let is_word = |c: char| c.is_alphanumeric() || c == '_' || c == '-' || c == '.';
    text.lines()
        .enumerate()
        .filter(|(_, line)| {
            let mut rest = *line;
            while let Some(k) = rest.find(key) {
                let after = rest[k + key.len()..].trim_start_matches(['"', '\'']);
                if let Some(v) = after.trim_start().strip_prefix(':') {
                    let v = v.trim_start().trim_start_matches(['"', '\'']);
                    if v.starts_with(value)
                        && !v[value.len()..].starts_with(is_word)
                        && !v.is_empty()
                    {
                        return true;
                    }
                }
                rest = &rest[k + key.len()..];
            }
            false
        })
        .nth(nth)
        .map(|(i, _)| i + 1)
}

/// The 1-based line of the first mapping key `key` (`key:` or `"key":` after a space, `{`,
/// `,` or the line's start) after the line `coupled:`, where a coupled joint is given.
fn line_of_key(text: &str, key: &str) -> Option<usize> {
    let start = text
        .lines()
        .position(|l| l.trim_start().starts_with("coupled"))?;
    text.lines()
        .enumerate()
        .skip(start)
        .find(|(_, l)| {
            l.match_indices(key).any(|(k, _)| {
                let before = l[..k].trim_end_matches(['"', '\'']).chars().next_back();
                let after = l[k + key.len()..].trim_start_matches(['"', '\'']);
                matches!(before, None | Some(' ' | '{' | ',')) && after.starts_with(':')
            })
        })
        .map(|(i, _)| i + 1)
}

/// `origin (line N)` when the line is known.
fn at(origin: &str, line: Option<usize>) -> String {
    match line {
        Some(l) => format!("{origin} (line {l})"),
        None => origin.to_string(),
    }
}

impl TreeSheet {
    /// Parses a tree sheet (YAML or JSON). `origin` names the file in errors.
    ///
    /// # Errors
    /// Those of [`crate::sheet::Sheet::parse`] for every row and pose, each naming the file,
    /// line, branch and joint; a sheet without `branches`; an empty branch or one without a
    /// name; a branch or joint name given twice across the tree; coupled joints or drivers that
    /// are no joint of the tree; bad inertials.
    pub fn parse(text: &str, origin: &str) -> Result<TreeSheet> {
        let doc = parse_doc(text, origin)?;
        Self::from_doc(doc, text, origin)
    }

    /// [`TreeSheet::parse`] of a parsed document; `text` locates lines for errors.
    ///
    /// # Errors
    /// As [`TreeSheet::parse`].
    pub fn from_doc(doc: SheetDoc, text: &str, origin: &str) -> Result<TreeSheet> {
        let Some(branch_docs) = &doc.branches else {
            return Err(hinted(
                format!("{origin}: expected a tree sheet with 'branches', found a serial sheet"),
                "a serial sheet is read as the model itself; a tree sheet adds 'branches: [{name, base, tool, joints}]'",
            ));
        };
        if branch_docs.is_empty() {
            return Err(hinted(
                format!("{origin}: 'branches' is empty; expected at least one branch"),
                "drop 'branches' for a serial robot",
            ));
        }
        let (lu, au) = (doc.length_unit, doc.angle_unit);
        let mut warnings = Vec::new();
        // Joint names seen so far, with how often, for the line of a repeat.
        let mut seen: Vec<(String, String)> = Vec::new();
        let mut rows_of = |joints: &[JointDoc],
                           table: &str,
                           warnings: &mut Vec<String>|
         -> Result<Vec<DhRow>> {
            let mut rows = Vec::with_capacity(joints.len());
            for j in joints {
                let count = seen.iter().filter(|(n, _)| n == &j.name).count();
                let line = line_of(text, "name", &j.name, count);
                if let Some((_, first)) = seen.iter().find(|(n, _)| n == &j.name) {
                    bail!(
                        "{}: {table}: joint '{}' appears twice in the tree (first in {first}); expected unique joint names",
                        at(origin, line),
                        j.name
                    );
                }
                seen.push((j.name.clone(), table.to_string()));
                rows.push(row_of(
                    j,
                    lu,
                    au,
                    &format!("{}: {table}", at(origin, line)),
                    warnings,
                )?);
            }
            Ok(rows)
        };
        let trunk_rows = rows_of(&doc.joints, "trunk", &mut warnings)?;
        let trunk = DhTable {
            convention: doc.convention.into(),
            base: pose_of(doc.base.as_ref(), lu, au, origin, "trunk: base")?,
            tool: pose_of(doc.tool.as_ref(), lu, au, origin, "trunk: tool")?,
            rows: trunk_rows,
        };
        let mut branches = Vec::with_capacity(branch_docs.len());
        let mut names = HashSet::new();
        for (k, b) in branch_docs.iter().enumerate() {
            let count = branch_docs[..k].iter().filter(|o| o.name == b.name).count();
            let here = at(origin, line_of(text, "name", &b.name, count));
            if b.name.trim().is_empty() || b.name.chars().any(crate::guard::is_spoofing) {
                bail!(
                    "{here}: branch {}: expected a name of printable characters, found '{}'",
                    k + 1,
                    crate::guard::escape(&b.name)
                );
            }
            if b.name.contains('/') {
                return Err(hinted(
                    format!("{here}: branch '{}': expected a name without '/', found one", b.name),
                    "a target 'BRANCH/NAME' rides on branch BRANCH, so a branch name cannot hold '/'",
                ));
            }
            if !names.insert(b.name.as_str()) {
                bail!(
                    "{here}: branch '{}' appears twice; expected unique branch names",
                    b.name
                );
            }
            if b.joints.is_empty() {
                return Err(hinted(
                    format!(
                        "{here}: branch '{}': 'joints' is empty; expected at least one joint",
                        b.name
                    ),
                    "a branch is a chain of its own rows; a fixed tool on the trunk is its 'tool'",
                ));
            }
            let table = format!("branch '{}'", b.name);
            let rows = rows_of(&b.joints, &table, &mut warnings)?;
            branches.push(Branch {
                name: b.name.clone(),
                table: DhTable {
                    convention: doc.convention.into(),
                    base: pose_of(b.base.as_ref(), lu, au, &here, &format!("{table}: base"))?,
                    tool: pose_of(b.tool.as_ref(), lu, au, &here, &format!("{table}: tool"))?,
                    rows,
                },
            });
        }
        let tree =
            DhTree::new(trunk, branches).map_err(|e| anyhow::anyhow!("{origin}: tree: {e}"))?;
        check_mimics(tree.rows(), origin, &mut warnings)?;
        // One coupled joint at a time, so that its error names its line.
        let mut coupled = Vec::new();
        for (joint, terms) in doc.coupled.iter().flatten() {
            let one = std::collections::BTreeMap::from([(joint.clone(), terms.clone())]);
            let here = at(origin, line_of_key(text, joint));
            coupled.extend(coupled_of(Some(&one), tree.rows(), &here)?);
        }
        let order = |j: &str| tree.row_index(j);
        coupled.sort_by_key(|(j, _)| order(j));
        if let Some(i) = &doc.inertials {
            // Checked now, so that a bad mass is an error of the model, not of the run.
            i.to_inertials(&tree, origin, Some(text))?;
        }
        Ok(TreeSheet {
            tree,
            coupled,
            inertials: doc.inertials,
            robot: doc.robot,
            source: doc.source,
            length_unit: lu,
            angle_unit: au,
            warnings,
        })
    }

    /// The model as the measured-data code takes it: every row of the tree in joint order
    /// (trunk, then each branch), for the columns a measurement file needs and the coupling
    /// of its values ([`LoadedModel::measured_joints`], [`LoadedModel::couple`]).
    pub fn loaded(&self, origin: &str) -> LoadedModel {
        LoadedModel {
            table: self.tree.joint_table(),
            origin: origin.to_string(),
            robot: self.robot.clone(),
            units: (self.length_unit, self.angle_unit),
            warnings: self.warnings.clone(),
            links: ("base_link".into(), "tool0".into()),
            coupled: self.coupled.clone(),
        }
    }

    /// The branch a target rides on: the branch of the target's own name, else the one named
    /// before its first `/` (see the module docs).
    pub fn branch_of<'a>(tree: &'a DhTree, target: &str) -> Option<&'a str> {
        let name = match tree.branch_index(target) {
            Some(_) => target,
            None => target.split_once('/')?.0,
        };
        tree.branch_index(name)
            .and_then(|b| tree.branches().get(b))
            .map(|b| b.name.as_str())
    }

    /// Names of the prismatic rows of the tree.
    pub fn prismatic(&self) -> Vec<String> {
        self.loaded("").prismatic()
    }

    /// The sheet of `tree` in the given units, with `coupled` and `inertials` as given:
    /// readable by [`TreeSheet::parse`].
    pub fn to_doc(
        tree: &DhTree,
        coupled: &[(String, Vec<(String, f64)>)],
        inertials: Option<InertialsDoc>,
        length: LengthUnit,
        angle: AngleUnit,
    ) -> SheetDoc {
        let mut doc = SheetDoc::from_table(tree.trunk(), length, angle);
        doc.branches = Some(
            tree.branches()
                .iter()
                .map(|b| {
                    let d = SheetDoc::from_table(&b.table, length, angle);
                    BranchDoc {
                        name: b.name.clone(),
                        base: d.base,
                        tool: d.tool,
                        joints: d.joints,
                    }
                })
                .collect(),
        );
        if !coupled.is_empty() {
            doc.coupled = Some(
                coupled
                    .iter()
                    .map(|(j, t)| (j.clone(), t.iter().cloned().collect()))
                    .collect(),
            );
        }
        doc.inertials = inertials;
        doc
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A two-branch tree: trunk `t1`, branches `r` and `l` of two joints each.
    const TREE: &str = "\
convention: modified
length_unit: m
angle_unit: deg
base: {xyz: [0, 0, 0.5], rpy: [0, 0, 0]}
tool: {xyz: [0, 0, 0.1], rpy: [0, 0, 0]}
joints:
  - {name: t1, type: revolute, a: 0, alpha: 0, d: 0.2, theta: 0}
  - {name: t2, type: revolute, a: 0.3, alpha: 90, d: 0, theta: 0}
branches:
  - name: r
    base: {xyz: [0, -0.2, 0], rpy: [90, 0, 0]}
    tool: {xyz: [0, 0, 0.05], rpy: [0, 0, 0]}
    joints:
      - {name: r1, type: revolute, a: 0, alpha: 0, d: 0, theta: 0}
      - {name: r2, type: revolute, a: 0.25, alpha: -90, d: 0, theta: 0}
  - name: l
    base: {xyz: [0, 0.2, 0], rpy: [-90, 0, 0]}
    joints:
      - {name: l1, type: revolute, a: 0, alpha: 0, d: 0, theta: 0}
      - {name: l2, type: revolute, a: 0.25, alpha: 90, d: 0, theta: 0}
";

    fn err(text: &str) -> String {
        format!("{:#}", TreeSheet::parse(text, "tree.yaml").unwrap_err())
    }

    #[test]
    fn a_tree_sheet_reads_into_a_tree() {
        let s = TreeSheet::parse(TREE, "tree.yaml").unwrap();
        assert_eq!(s.tree.rows().len(), 6);
        assert_eq!(s.tree.branches().len(), 2);
        assert_eq!(s.tree.branch_start(1), 4);
        let r = &s.tree.branches()[0].table;
        assert!((r.rows[1].a - 0.25).abs() < 1e-15);
        assert!((r.rows[1].alpha + std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        assert!((r.base.translation.vector.y + 0.2).abs() < 1e-15);
        assert_eq!(
            s.tree.branches()[1].table.tool,
            nalgebra::Isometry3::identity()
        );
        assert_eq!(
            s.loaded("tree.yaml").measured_joints(),
            ["t1", "t2", "r1", "r2", "l1", "l2"]
        );
        // Targets: by their own name, or the branch before '/'.
        assert_eq!(TreeSheet::branch_of(&s.tree, "r"), Some("r"));
        assert_eq!(TreeSheet::branch_of(&s.tree, "l/wrist"), Some("l"));
        assert_eq!(TreeSheet::branch_of(&s.tree, "x/wrist"), None);
        assert_eq!(TreeSheet::branch_of(&s.tree, "right"), None);
        // Written back and read again: the same tree.
        let doc = TreeSheet::to_doc(&s.tree, &s.coupled, None, LengthUnit::Mm, AngleUnit::Rad);
        let text = serde_yaml::to_string(&doc).unwrap();
        let back = TreeSheet::parse(&text, "back.yaml").unwrap();
        for (a, b) in back.tree.rows().iter().zip(s.tree.rows()) {
            assert!((a.a - b.a).abs() < 1e-12 && (a.alpha - b.alpha).abs() < 1e-12);
        }
        let (dp, dr) = dh_core::pose::pose_error(
            &back.tree.branches()[0].table.base,
            &s.tree.branches()[0].table.base,
        );
        assert!(dp < 1e-12 && dr < 1e-12);
    }

    #[test]
    fn an_unknown_key_in_a_branch_names_it_and_the_line() {
        let text = TREE.replace(
            "  - name: l\n",
            "  - name: l\n    mount: {xyz: [0, 0, 0], rpy: [0, 0, 0]}\n",
        );
        let e = err(&text);
        assert!(e.contains("tree.yaml (line 17, column 5)"), "{e}");
        assert!(e.contains("unknown field `mount`"), "{e}");
    }

    #[test]
    fn a_joint_in_two_branches_is_refused_with_both_places() {
        let text = TREE.replace("{name: l2,", "{name: r2,");
        let e = err(&text);
        assert!(
            e.contains("tree.yaml (line 20): branch 'l': joint 'r2' appears twice in the tree (first in branch 'r')"),
            "{e}"
        );
        let text = TREE.replace("{name: l1,", "{name: t1,");
        assert!(err(&text).contains("(first in trunk)"), "{}", err(&text));
    }

    #[test]
    fn an_empty_branch_and_empty_branches_are_refused() {
        let text = TREE.replace(
            "    joints:\n      - {name: l1, type: revolute, a: 0, alpha: 0, d: 0, theta: 0}\n      - {name: l2, type: revolute, a: 0.25, alpha: 90, d: 0, theta: 0}\n",
            "    joints: []\n",
        );
        let e = err(&text);
        assert!(
            e.contains("tree.yaml (line 16): branch 'l': 'joints' is empty"),
            "{e}"
        );
        let serial = TREE.split("branches:").next().unwrap().to_string() + "branches: []\n";
        assert!(
            err(&serial).contains("'branches' is empty"),
            "{}",
            err(&serial)
        );
        let twice = TREE.replace("name: l\n", "name: r\n");
        assert!(
            err(&twice).contains("branch 'r' appears twice"),
            "{}",
            err(&twice)
        );
    }

    #[test]
    fn a_branch_joint_may_be_coupled_to_a_trunk_driver() {
        // The coupled joint's value is a sum over measured columns, wherever they sit.
        let text = format!("{TREE}coupled:\n  l2: {{t2: -1, r2: 0.5}}\n");
        let s = TreeSheet::parse(&text, "tree.yaml").unwrap();
        assert_eq!(
            s.coupled,
            [(
                "l2".to_string(),
                vec![("r2".into(), 0.5), ("t2".into(), -1.0)]
            )]
        );
        assert_eq!(
            s.loaded("tree.yaml").measured_joints(),
            ["t1", "t2", "r1", "r2", "l1"]
        );
        let mut data = dh_calib::data::Measurements {
            sessions: Vec::new(),
            joint_names: vec![
                "t1".into(),
                "t2".into(),
                "r1".into(),
                "r2".into(),
                "l1".into(),
            ],
            targets: vec!["l".into()],
            samples: vec![dh_calib::data::Sample {
                session: 0,
                q: vec![0.1, 0.2, 0.3, 0.4, 0.5],
                target: 0,
                point: Vector3::zeros(),
                sigma: None,
                config: None,
                split: dh_calib::data::Split::Calibration,
                line: 2,
                socket: None,
            }],
        };
        s.loaded("tree.yaml").couple(&mut data).unwrap();
        assert_eq!(data.joint_names.last().map(String::as_str), Some("l2"));
        assert!((data.samples[0].q[5] - (-0.2 + 0.5 * 0.4)).abs() < 1e-15);
        // A driver that is no joint of the tree is refused.
        let text = format!("{TREE}coupled:\n  l2: {{torso_9: 1}}\n");
        assert!(
            err(&text).contains("driver 'torso_9' is no joint of the sheet"),
            "{}",
            err(&text)
        );
    }

    #[test]
    fn inertials_need_joints_and_branches_of_the_tree() {
        let with = |i: &str| format!("{TREE}inertials:\n{i}");
        let ok = with("  com_frame: dh\n  links: [{joint: r2, mass: 1.5, com: [0.1, 0, 0]}]\n  payloads: [{branch: l, mass: 2, com: [0, 0, 0.1]}]\n");
        let s = TreeSheet::parse(&ok, "tree.yaml").unwrap();
        let (i, g) = s
            .inertials
            .as_ref()
            .unwrap()
            .to_inertials(&s.tree, "tree.yaml", None)
            .unwrap();
        assert_eq!(i.payloads[0].0, 1);
        assert!(g.is_none());
        let e = err(&with("  links: [{joint: r9, mass: 1, com: [0, 0, 0]}]\n"));
        assert!(
            e.contains("link of joint 'r9': expected a joint of the tree"),
            "{e}"
        );
        let e = err(&with(
            "  links: []\n  payloads: [{mass: 1, com: [0, 0, 0]}]\n",
        ));
        assert!(
            e.contains("a payload without 'branch' in a tree of several tips"),
            "{e}"
        );
        let e = err(&with("  links: [{joint: r1, mass: -1, com: [0, 0, 0]}]\n"));
        assert!(e.contains("expected a mass in kg"), "{e}");
        let e = err(&with("  links: []\n  density: 3\n"));
        assert!(e.contains("unknown field `density`"), "{e}");
    }

    #[test]
    fn serial_commands_refuse_a_tree_sheet() {
        let e = crate::sheet::Sheet::parse(TREE, "tree.yaml").unwrap_err();
        assert!(
            e.to_string().contains(
                "tree.yaml: 'branches': a tree sheet (a trunk and 2 branch(es): 'r', 'l')"
            ),
            "{e}"
        );
    }

    #[test]
    fn every_prefix_and_mangling_of_a_tree_is_an_answer_not_a_panic() {
        // Truncated files and swapped keys: each parses or is an error naming the file.
        let mut cut = 0;
        while cut <= TREE.len() {
            if let Err(e) = TreeSheet::parse(&TREE[..cut], "tree.yaml") {
                assert!(format!("{e:#}").starts_with("tree.yaml"), "{e:#}");
            }
            cut += 7;
        }
        for (from, to) in [
            ("name: r\n", "name: ''\n"),
            ("name: r\n", "name: 'r/x'\n"),
            ("name: l\n", "name: r\n"),
            ("t2", "t1"),
            ("branches:", "branches: []\nx:"),
            ("a: 0.25", "a: .nan"),
            ("rpy: [90, 0, 0]", "rpy: [90, 0]"),
        ] {
            let e = err(&TREE.replacen(from, to, 1));
            assert!(e.starts_with("tree.yaml"), "{from} -> {to}: {e}");
        }
    }

    #[test]
    fn lines_are_found_for_every_spelling() {
        let t = "a:\n  - {name: j1}\n  - name: \"j1\"\n  - {\"name\": \"j10\"}\n  - {\"name\": \"j1\"}\n";
        assert_eq!(line_of(t, "name", "j1", 0), Some(2));
        assert_eq!(line_of(t, "name", "j1", 1), Some(3));
        assert_eq!(line_of(t, "name", "j1", 2), Some(5));
        assert_eq!(line_of(t, "name", "j1", 3), None);
    }
}
