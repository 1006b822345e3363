//! Tree sheets: the DH sheet format (see [`crate::sheet`]) with `branches`, for robots whose
//! chains share a trunk (two arms on one torso). `calibrate` reads them, and `predict` and
//! `compensate` read the calibrated tree sheet it writes (`crate::calibrated`); the other
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

use dh_calib::gravity::{Inertial, Inertials};
use dh_calib::tree::{Branch, DhTree};
use dh_core::{DhRow, DhTable, JointKind};
use nalgebra::Vector3;

use crate::error::{Result, SheetError};
use crate::sheet::{
    check_mimics, check_nesting, coupled_of, parse_doc, pose_of, row_of, JointDoc, SheetDoc,
};
use crate::text::{escape, is_spoofing};
use crate::units::{AngleUnit, LengthUnit};

// The document types of the tree keys are the sheet's (a `SheetDoc` holds them).
pub use crate::sheet::{BranchDoc, ComFrame, InertialsDoc, LinkDoc, PayloadDoc};

#[cfg(test)]
mod tests;

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
        let bad = |origin: &str, problem: String, hint: Option<String>| SheetError::BadInertials {
            origin: origin.into(),
            problem,
            hint,
        };
        let finite3 = |v: &[f64; 3], what: &str| -> Result<Vector3<f64>> {
            if v.iter()
                .any(|c| !c.is_finite() || c.abs() > MAX_INERTIAL_MAGNITUDE)
            {
                return Err(bad(
                    origin,
                    format!(
                        "{what}: expected finite numbers of magnitude at most \
                         {MAX_INERTIAL_MAGNITUDE:e}, found {v:?}"
                    ),
                    None,
                ));
            }
            Ok(Vector3::new(v[0], v[1], v[2]))
        };
        let mass = |m: f64, what: &str| -> Result<f64> {
            if !(m.is_finite() && (0.0..=MAX_MASS).contains(&m)) {
                return Err(bad(
                    origin,
                    format!("{what}: expected a mass in kg from 0 to {MAX_MASS:e}, found {m}"),
                    None,
                ));
            }
            Ok(m)
        };
        let mut links = Vec::with_capacity(self.links.len());
        for l in &self.links {
            let line = text.and_then(|t| line_of(t, "joint", &l.joint, 0));
            if tree.row_index(&l.joint).is_none() {
                return Err(bad(
                    &at(origin, line),
                    format!(
                        "link of joint '{}': expected a joint of the tree, found none of that name",
                        l.joint
                    ),
                    Some(format!("the tree's joints: {}", joint_list(tree.rows()))),
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
                    bad(
                        origin,
                        format!(
                            "payload on branch '{b}': expected a branch of the tree, found none \
                             of that name"
                        ),
                        Some(format!("the branches: {}", branch_list(tree))),
                    )
                })?,
                (None, 0 | 1) => 0,
                (None, _) => {
                    return Err(bad(
                        origin,
                        "a payload without 'branch' in a tree of several tips".into(),
                        Some(format!(
                            "name the branch whose tip carries it: {}",
                            branch_list(tree)
                        )),
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
                .map_err(|e| bad(origin, e.to_string(), None))?,
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
        check_nesting(text, origin)?;
        serde_yaml::from_str(text).map_err(|e| SheetError::Syntax {
            origin: origin.into(),
            location: None,
            message: e.to_string(),
        })
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
            return Err(SheetError::NotATree {
                origin: origin.into(),
            });
        };
        if branch_docs.is_empty() {
            return Err(SheetError::NoBranches {
                origin: origin.into(),
            });
        }
        crate::sheet::check_labels(
            [
                ("robot", doc.robot.as_deref()),
                ("source", doc.source.as_deref()),
            ],
            origin,
        )?;
        let (lu, au) = (doc.length_unit, doc.angle_unit);
        let mut warnings = Vec::new();
        // Joint names seen so far, with how often, for the line of a repeat.
        let mut seen: Vec<(String, String)> = Vec::new();
        let mut rows_of =
            |joints: &[JointDoc], table: &str, warnings: &mut Vec<String>| -> Result<Vec<DhRow>> {
                let mut rows = Vec::with_capacity(joints.len());
                for j in joints {
                    let count = seen.iter().filter(|(n, _)| n == &j.name).count();
                    let line = line_of(text, "name", &j.name, count);
                    if let Some((_, first)) = seen.iter().find(|(n, _)| n == &j.name) {
                        return Err(SheetError::DuplicateTreeJoint {
                            origin: at(origin, line),
                            table: table.into(),
                            joint: j.name.clone(),
                            first: first.clone(),
                        });
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
            let bad =
                |branch: String, problem: &str, hint: Option<&'static str>| SheetError::BadBranch {
                    origin: here.clone(),
                    branch,
                    problem: problem.into(),
                    hint,
                };
            if b.name.trim().is_empty() || b.name.chars().any(is_spoofing) {
                return Err(bad(
                    format!("branch {}", k + 1),
                    &format!(
                        "expected a name of printable characters, found '{}'",
                        escape(&b.name)
                    ),
                    None,
                ));
            }
            if b.name.contains('/') {
                return Err(bad(
                    format!("branch '{}'", b.name),
                    "expected a name without '/', found one",
                    Some(
                        "a target 'BRANCH/NAME' rides on branch BRANCH, so a branch name cannot \
                         hold '/'",
                    ),
                ));
            }
            if !names.insert(b.name.as_str()) {
                return Err(SheetError::DuplicateBranch {
                    origin: here,
                    branch: b.name.clone(),
                });
            }
            if b.joints.is_empty() {
                return Err(bad(
                    format!("branch '{}'", b.name),
                    "'joints' is empty; expected at least one joint",
                    Some(
                        "a branch is a chain of its own rows; a fixed tool on the trunk is its \
                         'tool'",
                    ),
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
        let tree = DhTree::new(trunk, branches).map_err(|e| SheetError::BadTree {
            origin: origin.into(),
            problem: e.to_string(),
        })?;
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

    /// Names of the prismatic rows of the tree and the drivers of prismatic mimic rows.
    pub fn prismatic(&self) -> Vec<String> {
        let prismatic = || {
            self.tree
                .rows()
                .iter()
                .filter(|r| r.kind == JointKind::Prismatic)
        };
        let mut p: Vec<String> = prismatic().map(|r| r.name.clone()).collect();
        for m in prismatic().filter_map(|r| r.mimic.as_ref()) {
            if !p.contains(&m.joint) {
                p.push(m.joint.clone());
            }
        }
        p
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
