//! Parsing and whole-document validation.

use std::collections::HashMap;

use crate::check::check_name;
use crate::read::{self, fault_summary};
use crate::robot::{Robot, Warning};
use crate::scan::{self, ScanError};
use crate::UrdfError;

/// Largest URDF accepted, in bytes (64 MiB). Real URDFs are at most a few megabytes (meshes
/// live in their own files); the limit bounds time and memory (about ten times the input at
/// worst) for piped or hostile input.
pub const MAX_URDF_BYTES: usize = 64 * 1024 * 1024;

/// The name of SDFormat in messages ([`UrdfModel::format_name`]).
const SDFORMAT: &str = "SDFormat";

/// A parsed and validated URDF: one tree of uniquely named links joined by joints, indexed by
/// name, with the warnings of its reading.
///
/// Build it with [`UrdfModel::parse`] or [`UrdfModel::from_bytes`], then pick a serial chain
/// with [`UrdfModel::chain`]. What defines the tree (names, parents, children) is validated
/// here. A fault in a joint's own content (type, numbers, limits, mimic) is kept with the
/// joint: [`UrdfModel::chain`] refuses a chain through that joint, and elsewhere it is a
/// warning ([`UrdfModel::warnings_for`]). Faults of visuals, collisions, materials and
/// inertials are warnings ([`UrdfModel::warnings`]), as urdfdom logs and skips them.
#[derive(Debug, Clone)]
pub struct UrdfModel {
    pub(crate) robot: Robot,
    link_index: HashMap<String, usize>,
    joint_index: HashMap<String, usize>,
    /// Per joint: index of its parent link.
    pub(crate) joint_parent: Vec<usize>,
    /// Per joint: index of its child link.
    pub(crate) joint_child: Vec<usize>,
    /// Per link: the joint whose child it is.
    pub(crate) parent_joint: Vec<Option<usize>>,
    /// Per link: joints whose parent it is.
    pub(crate) child_joints: Vec<Vec<usize>>,
    pub(crate) root: usize,
    /// The base of a chain when none is given: the root link, or (MJCF) the body of the one
    /// free joint at the root.
    pub(crate) default_base: usize,
    /// The format the model was read from (`URDF`, `MJCF`).
    pub(crate) format_name: &'static str,
}

impl UrdfModel {
    /// Parses and validates a whole URDF document, or an SDFormat one (root element `<sdf>`,
    /// converted into the same model: [`UrdfError::Sdf`], [`UrdfError::SdfJointType`]).
    ///
    /// A leading byte-order mark is ignored. Documents declaring entities (`<!ENTITY`) are
    /// refused before any XML parsing, so an entity-expansion bomb costs one linear scan.
    ///
    /// # Errors
    /// - [`UrdfError::TooLarge`] beyond [`MAX_URDF_BYTES`];
    /// - [`UrdfError::EntityDeclaration`] for an entity declaration;
    /// - [`UrdfError::Parse`] for text that is not one well-formed `<robot>` element, or a link
    ///   or joint without a name, parent or child;
    /// - [`UrdfError::NoLinks`], [`UrdfError::DuplicateLink`], [`UrdfError::DuplicateJoint`],
    ///   [`UrdfError::ControlCharacterInName`] (of a link), [`UrdfError::MissingLink`],
    ///   [`UrdfError::TwoParents`], [`UrdfError::Cycle`], [`UrdfError::NoRoot`],
    ///   [`UrdfError::SeveralRoots`] when the links are not one tree.
    pub fn parse(text: &str) -> Result<UrdfModel, UrdfError> {
        if text.len() > MAX_URDF_BYTES {
            return Err(UrdfError::TooLarge {
                size: Some(text.len()),
                limit: MAX_URDF_BYTES,
            });
        }
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        if crate::sdf::is_sdf(text) {
            let mut model = Self::validate(crate::sdf::read(text)?)?;
            model.format_name = SDFORMAT;
            return Ok(model);
        }
        let doc = scan::scan(text).map_err(|e| match e {
            ScanError::Entity { line } => UrdfError::EntityDeclaration { line },
            ScanError::Malformed { message, line } => UrdfError::Parse { message, line },
        })?;
        let robot = read::read(&doc)?;
        drop(doc);
        Self::validate(robot)
    }

    /// Decodes `bytes` as UTF-8, then parses and validates them like [`UrdfModel::parse`].
    ///
    /// # Errors
    /// [`UrdfError::NotUtf8`] with the offset and line of the first invalid byte; otherwise as
    /// [`UrdfModel::parse`].
    pub fn from_bytes(bytes: &[u8]) -> Result<UrdfModel, UrdfError> {
        if bytes.len() > MAX_URDF_BYTES {
            return Err(UrdfError::TooLarge {
                size: Some(bytes.len()),
                limit: MAX_URDF_BYTES,
            });
        }
        match std::str::from_utf8(bytes) {
            Ok(text) => Self::parse(text),
            Err(e) => {
                let offset = e.valid_up_to();
                let line = scan::Lines::new(bytes).line_of(offset);
                Err(UrdfError::NotUtf8 { offset, line })
            }
        }
    }

    /// Validates a robot read from another format (MJCF) as [`UrdfModel::parse`] validates a
    /// URDF's.
    pub(crate) fn from_robot(robot: Robot) -> Result<UrdfModel, UrdfError> {
        Self::validate(robot)
    }

    fn validate(mut robot: Robot) -> Result<UrdfModel, UrdfError> {
        if robot.links.is_empty() {
            return Err(UrdfError::NoLinks {
                robot: robot.name.clone(),
            });
        }
        let mut link_index: HashMap<String, usize> = HashMap::with_capacity(robot.links.len());
        for (i, link) in robot.links.iter().enumerate() {
            check_name("link", &link.name, Some(link.line))?;
            if let Some(&first) = link_index.get(&link.name) {
                return Err(UrdfError::DuplicateLink {
                    link: link.name.clone(),
                    line: Some(link.line),
                    first_line: robot.links.get(first).map(|l| l.line),
                });
            }
            link_index.insert(link.name.clone(), i);
        }
        let mut joint_index: HashMap<String, usize> = HashMap::with_capacity(robot.joints.len());
        for (k, joint) in robot.joints.iter().enumerate() {
            if let Some(&first) = joint_index.get(&joint.name) {
                return Err(UrdfError::DuplicateJoint {
                    joint: joint.name.clone(),
                    line: Some(joint.line),
                    first_line: robot.joints.get(first).map(|j| j.line),
                });
            }
            joint_index.insert(joint.name.clone(), k);
        }

        let mut joint_parent = Vec::with_capacity(robot.joints.len());
        let mut joint_child = Vec::with_capacity(robot.joints.len());
        for joint in &robot.joints {
            let find = |role: &'static str, name: &str, line: usize| {
                link_index
                    .get(name)
                    .copied()
                    .ok_or_else(|| UrdfError::MissingLink {
                        joint: joint.name.clone(),
                        role,
                        link: name.to_owned(),
                        line: Some(line),
                    })
            };
            joint_parent.push(find("parent", &joint.parent, joint.parent_line)?);
            joint_child.push(find("child", &joint.child, joint.child_line)?);
        }
        crate::mimic::check_mimics(&mut robot.joints, &joint_index);

        // Tree shape: one parent per link, no cycle, one root.
        let n = robot.links.len();
        let mut parent_joint: Vec<Option<usize>> = vec![None; n];
        for (k, &child) in joint_child.iter().enumerate() {
            let Some(slot) = parent_joint.get_mut(child) else {
                continue;
            };
            if let Some(first) = *slot {
                return Err(UrdfError::TwoParents {
                    link: link_name_of(&robot, child),
                    first: joint_name_of(&robot, first),
                    second: joint_name_of(&robot, k),
                    line: robot.joints.get(k).map(|j| j.line),
                });
            }
            *slot = Some(k);
        }
        let parent_link = |link: usize| -> Option<usize> {
            parent_joint
                .get(link)
                .copied()
                .flatten()
                .and_then(|j| joint_parent.get(j).copied())
        };
        let cycle = find_cycle(n, parent_link);
        let roots: Vec<usize> = (0..n)
            .filter(|&i| parent_joint.get(i).is_some_and(|p| p.is_none()))
            .collect();
        let link_names = |idx: &[usize]| -> Vec<String> {
            idx.iter().map(|&i| link_name_of(&robot, i)).collect()
        };
        if let Some(cycle) = cycle {
            let links = link_names(&cycle);
            if roots.is_empty() {
                return Err(UrdfError::NoRoot { links });
            }
            // The joint into the second link of the cycle (from the first).
            let joint = cycle
                .get(1)
                .and_then(|&l| parent_joint.get(l).copied().flatten())
                .unwrap_or(0);
            return Err(UrdfError::Cycle {
                links,
                joint: joint_name_of(&robot, joint),
                line: robot.joints.get(joint).map(|j| j.line),
            });
        }
        let root = match roots.as_slice() {
            [root] => *root,
            _ => {
                return Err(UrdfError::SeveralRoots {
                    roots: link_names(&roots),
                })
            }
        };
        let mut child_joints = vec![Vec::new(); n];
        for (k, &parent) in joint_parent.iter().enumerate() {
            if let Some(c) = child_joints.get_mut(parent) {
                c.push(k);
            }
        }
        Ok(UrdfModel {
            robot,
            link_index,
            joint_index,
            joint_parent,
            joint_child,
            parent_joint,
            child_joints,
            root,
            default_base: root,
            format_name: "URDF",
        })
    }

    /// Makes `link` the default base of chains (an MJCF body floating on a free joint: the chain
    /// starts below it) when a revolute, continuous or prismatic joint lies below it.
    pub(crate) fn set_default_base_if_moving_below(&mut self, link: &str) {
        let Some(l) = self.link_index_of(link) else {
            return;
        };
        let moving_below = self.robot.joints.iter().enumerate().any(|(k, j)| {
            j.kind.is_some_and(crate::robot::JointType::is_moving)
                && self
                    .joint_child
                    .get(k)
                    .is_some_and(|&c| self.is_below(c, l))
        });
        if moving_below {
            self.default_base = l;
        }
    }

    /// Warnings of the reading: faults of visuals, collisions, materials and inertials (each
    /// ignored, as urdfdom ignores them), and the fault of every joint that has one (an error
    /// from [`UrdfModel::chain`] for a chain through that joint). At most
    /// [`MAX_WARNINGS`](crate::MAX_WARNINGS) are listed, then one saying how many more.
    pub fn warnings(&self) -> Vec<Warning> {
        self.collect_warnings(|_| true, "an error on a chain through it")
    }

    pub(crate) fn collect_warnings(
        &self,
        include: impl Fn(&str) -> bool,
        note: &str,
    ) -> Vec<Warning> {
        let mut out = self.robot.warnings.clone();
        let mut more = self.robot.more_warnings;
        for j in &self.robot.joints {
            let Some(fault) = &j.fault else { continue };
            if !include(&j.name) {
                continue;
            }
            if out.len() < crate::robot::MAX_WARNINGS {
                out.push(Warning {
                    // Escaped: an off-chain joint's name may hold the very control or
                    // bidirectional character its fault is about.
                    element: format!("joint '{}'", j.name.escape_debug()),
                    line: Some(j.line),
                    message: format!("{} ({note})", fault_summary(j, fault)),
                });
            } else {
                more += 1;
            }
        }
        if more > 0 {
            out.push(Warning {
                element: format!("robot '{}'", self.robot.name),
                line: None,
                message: format!("{more} more warnings not shown"),
            });
        }
        out
    }

    /// The format the model was read from: `URDF`, `SDFormat` (a document whose root element
    /// is `<sdf>`), or `MJCF` for [`crate::mjcf::read`].
    pub fn format_name(&self) -> &'static str {
        self.format_name
    }

    /// The format a robot file's `bytes` are read as, by their root element (only the prolog is
    /// looked at): `MJCF` for `<mujoco>`, `SDFormat` for `<sdf>`, else `URDF`; what an error of
    /// reading them names.
    pub fn format_name_of(bytes: &[u8]) -> &'static str {
        if crate::mjcf::is_mjcf(bytes) {
            return "MJCF";
        }
        // The root element is in the valid UTF-8 prefix when there is one.
        let valid = match std::str::from_utf8(bytes) {
            Ok(text) => text,
            Err(e) => std::str::from_utf8(bytes.get(..e.valid_up_to()).unwrap_or_default())
                .unwrap_or_default(),
        };
        if crate::sdf::is_sdf(valid) {
            SDFORMAT
        } else {
            "URDF"
        }
    }

    /// The `name` attribute of `<robot>` (empty when absent).
    pub fn robot_name(&self) -> &str {
        &self.robot.name
    }

    /// The root link: the one link that is no joint's child.
    pub fn root_link(&self) -> &str {
        self.link_name(self.root)
    }

    /// Links that are no joint's parent, in document order.
    pub fn leaves(&self) -> Vec<&str> {
        self.child_joints
            .iter()
            .enumerate()
            .filter(|(_, c)| c.is_empty())
            .map(|(i, _)| self.link_name(i))
            .collect()
    }

    /// All link names, in document order.
    pub fn links(&self) -> Vec<&str> {
        self.robot.links.iter().map(|l| l.name.as_str()).collect()
    }

    /// All joint names, in document order.
    pub fn joints(&self) -> Vec<&str> {
        self.robot.joints.iter().map(|j| j.name.as_str()).collect()
    }

    /// The 1-based source line of `<link name="link"`, when the link exists and its line is
    /// known.
    pub fn link_line(&self, link: &str) -> Option<usize> {
        let &i = self.link_index.get(link)?;
        self.robot.links.get(i).map(|l| l.line)
    }

    /// The 1-based source line of `<joint name="joint"`, when the joint exists and its line is
    /// known.
    pub fn joint_line(&self, joint: &str) -> Option<usize> {
        let &k = self.joint_index.get(joint)?;
        self.robot.joints.get(k).map(|j| j.line)
    }

    /// The joint whose child is `link`: its name, its parent link and its `<origin>` (the pose
    /// of the joint frame in the parent link's frame; metres, radians), or `None` for the root
    /// link or an unknown one. For callers that walk or edit the document's own joints (a
    /// calibrated URDF written as a minimal edit of the user's file).
    pub fn parent_joint(&self, link: &str) -> Option<(&str, &str, nalgebra::Isometry3<f64>)> {
        let &i = self.link_index.get(link)?;
        let j = self.robot.joints.get((*self.parent_joint.get(i)?)?)?;
        let origin = dh_core::pose::from_xyz_rpy(j.origin.xyz, j.origin.rpy);
        Some((j.name.as_str(), j.parent.as_str(), origin))
    }

    pub(crate) fn link_name(&self, link: usize) -> &str {
        self.robot
            .links
            .get(link)
            .map(|l| l.name.as_str())
            .unwrap_or("")
    }

    pub(crate) fn link_index_of(&self, link: &str) -> Option<usize> {
        self.link_index.get(link).copied()
    }

    pub(crate) fn joint_index_of(&self, joint: &str) -> Option<usize> {
        self.joint_index.get(joint).copied()
    }

    pub(crate) fn find_link(&self, name: &str, role: &'static str) -> Result<usize, UrdfError> {
        self.link_index.get(name).copied().ok_or_else(|| {
            let mut candidates = candidates(name, &self.links());
            // No close name among many links: offer what the role usually is, the leaves
            // for a tip, the root for a base, rather than nothing.
            if candidates.is_empty() {
                candidates = match role {
                    "tip" => self
                        .leaves()
                        .into_iter()
                        .take(8)
                        .map(str::to_owned)
                        .collect(),
                    _ => vec![self.root_link().to_owned()],
                };
            }
            UrdfError::UnknownLink {
                role,
                link: name.to_owned(),
                candidates,
            }
        })
    }

    /// Whether `below` lies in the subtree of `above` (or is it).
    fn is_below(&self, below: usize, above: usize) -> bool {
        self.ancestors(below).any(|l| l == above)
    }

    /// `link`, its parent, its grandparent, ..., the root.
    pub(crate) fn ancestors(&self, link: usize) -> impl Iterator<Item = usize> + '_ {
        std::iter::successors(Some(link), move |&l| {
            let j = self.parent_joint.get(l).copied().flatten()?;
            self.joint_parent.get(j).copied()
        })
        // The tree is validated acyclic; the bound only guards against a broken invariant.
        .take(self.robot.links.len() + 1)
    }

    /// Joint indices from `base` down to `tip`.
    pub(crate) fn path(&self, base: usize, tip: usize) -> Result<Vec<usize>, UrdfError> {
        let mut path = Vec::new();
        let mut link = tip;
        while link != base {
            match self.parent_joint.get(link).copied().flatten() {
                Some(j) => {
                    path.push(j);
                    link = self.joint_parent.get(j).copied().unwrap_or(base);
                }
                None => {
                    return Err(UrdfError::Disconnected {
                        base: self.link_name(base).to_owned(),
                        tip: self.link_name(tip).to_owned(),
                        reversed: self.is_below(base, tip),
                    })
                }
            }
            if path.len() > self.robot.joints.len() {
                break;
            }
        }
        path.reverse();
        Ok(path)
    }
}

fn link_name_of(robot: &Robot, i: usize) -> String {
    robot
        .links
        .get(i)
        .map(|l| l.name.clone())
        .unwrap_or_default()
}

fn joint_name_of(robot: &Robot, k: usize) -> String {
    robot
        .joints
        .get(k)
        .map(|j| j.name.clone())
        .unwrap_or_default()
}

/// A cycle of links (each the parent of the next, the first repeated at the end), found by
/// walking up from every link once: linear in the number of links.
fn find_cycle(n: usize, parent: impl Fn(usize) -> Option<usize>) -> Option<Vec<usize>> {
    // 0: unvisited, 1: on the current walk, 2: known to reach a root or a reported cycle.
    let mut state = vec![0u8; n];
    for start in 0..n {
        let mut walk = Vec::new();
        let mut link = start;
        loop {
            match state.get(link).copied() {
                Some(0) => {
                    if let Some(s) = state.get_mut(link) {
                        *s = 1;
                    }
                    walk.push(link);
                    match parent(link) {
                        Some(p) => link = p,
                        None => break,
                    }
                }
                Some(1) => {
                    let from = walk.iter().position(|&l| l == link).unwrap_or(0);
                    // The walk goes child -> parent; report parent -> child.
                    let mut cycle: Vec<usize> = walk.get(from..).unwrap_or(&[]).to_vec();
                    cycle.reverse();
                    cycle.push(cycle.first().copied().unwrap_or(link));
                    return Some(cycle);
                }
                _ => break,
            }
        }
        for l in walk {
            if let Some(s) = state.get_mut(l) {
                *s = 2;
            }
        }
    }
    None
}

/// Links to suggest for an unknown name: all of them when there are few, else the closest.
fn candidates(name: &str, links: &[&str]) -> Vec<String> {
    const ALL_BELOW: usize = 8;
    const SHOWN: usize = 5;
    if links.len() <= ALL_BELOW {
        return links.iter().map(|l| (*l).to_owned()).collect();
    }
    let lower = name.to_lowercase();
    let mut scored: Vec<(usize, &str)> = links
        .iter()
        .filter_map(|&l| {
            let ll = l.to_lowercase();
            let d = edit_distance(&lower, &ll);
            let close = d <= (lower.chars().count() / 3).max(2)
                || (!lower.is_empty() && (ll.contains(&lower) || lower.contains(&ll)));
            close.then_some((d, l))
        })
        .collect();
    scored.sort_unstable();
    scored
        .into_iter()
        .take(SHOWN)
        .map(|(_, l)| l.to_owned())
        .collect()
}

/// Levenshtein distance in characters.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diag = i;
        if let Some(first) = row.first_mut() {
            *first = i + 1;
        }
        for (j, &cb) in b.iter().enumerate() {
            let up = row.get(j + 1).copied().unwrap_or(0);
            let left = row.get(j).copied().unwrap_or(0);
            let cost = usize::from(ca != cb);
            let v = (diag + cost).min(up + 1).min(left + 1);
            diag = up;
            if let Some(cell) = row.get_mut(j + 1) {
                *cell = v;
            }
        }
    }
    row.last().copied().unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each reader names its own format, so that a message says which was read.
    #[test]
    fn the_format_is_named_after_the_root_element() {
        let urdf = r#"<robot name="r"><link name="a"/><link name="b"/>
            <joint name="j" type="revolute"><parent link="a"/><child link="b"/>
            <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>"#;
        let sdf = r#"<?xml version="1.0"?><sdf version="1.6"><model name="m"><link name="a"/><link name="b"/>
            <joint name="j" type="revolute"><parent>a</parent><child>b</child>
            <axis><xyz>0 0 1</xyz></axis></joint></model></sdf>"#;
        let mjcf = r#"<mujoco model="m"><worldbody><body name="b"><joint name="j" axis="0 0 1"/></body></worldbody></mujoco>"#;
        assert_eq!(UrdfModel::parse(urdf).unwrap().format_name(), "URDF");
        assert_eq!(UrdfModel::parse(sdf).unwrap().format_name(), "SDFormat");
        assert_eq!(UrdfModel::format_name_of(urdf.as_bytes()), "URDF");
        assert_eq!(UrdfModel::format_name_of(sdf.as_bytes()), "SDFormat");
        assert_eq!(UrdfModel::format_name_of(mjcf.as_bytes()), "MJCF");
        // Not UTF-8 after the root element: still told by its prolog.
        let mut bytes = b"<sdf version='1.6'><model name='m'>".to_vec();
        bytes.push(0xff);
        assert_eq!(UrdfModel::format_name_of(&bytes), "SDFormat");
        assert_eq!(UrdfModel::format_name_of(b"not xml"), "URDF");
    }

    #[test]
    fn edit_distance_counts_edits() {
        assert_eq!(edit_distance("tool0", "tool0"), 0);
        assert_eq!(edit_distance("tool", "tool0"), 1);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert_eq!(edit_distance("", "abc"), 3);
    }

    #[test]
    fn candidates_are_all_links_when_few_else_close_ones() {
        let few = ["a", "b"];
        assert_eq!(candidates("x", &few), vec!["a", "b"]);
        let many: Vec<String> = (0..20).map(|i| format!("link_{i}")).collect();
        let refs: Vec<&str> = many.iter().map(String::as_str).collect();
        let c = candidates("link_3x", &refs);
        assert_eq!(c.first().map(String::as_str), Some("link_3"));
        assert!(c.len() <= 5);
        assert!(candidates("zzzzzzzzzz", &refs).is_empty());
    }

    #[test]
    fn cycles_are_reported_parent_to_child() {
        // 0 <- 1 <- 2 <- 1 ... : links 1 and 2 are each other's parent; 0 is a root.
        let parents = [None, Some(2), Some(1)];
        let c = find_cycle(3, |l| parents.get(l).copied().flatten()).unwrap();
        assert_eq!(c.len(), 3);
        assert_eq!(c.first(), c.last());
        assert!(find_cycle(3, |l| [None, Some(0), Some(1)].get(l).copied().flatten()).is_none());
    }
}
