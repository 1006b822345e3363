//! Parsing and whole-document validation.

use std::collections::HashMap;

use urdf_rs::{JointType, Robot};

use crate::scan::{self, Doc, ScanError};
use crate::{Chain, UrdfError};

/// Where a joint and its parts sit in the source text, and what urdf-rs forgets about it.
#[derive(Clone, Debug, Default)]
pub(crate) struct JointSource {
    /// Line of `<joint`.
    pub line: Option<usize>,
    pub parent_line: Option<usize>,
    pub child_line: Option<usize>,
    pub origin_line: Option<usize>,
    pub axis_line: Option<usize>,
    pub limit_line: Option<usize>,
    pub mimic_line: Option<usize>,
    /// Whether a `<limit>` element is present (urdf-rs fills in zeros when it is not).
    pub has_limit: bool,
    /// Raw `xyz`, `rpy` of `<origin>` and `xyz` of `<axis>`: urdf-rs silently drops tokens that
    /// are not numbers.
    pub raw_vectors: Vec<(&'static str, String, Option<usize>)>,
}

impl JointSource {
    fn unknown() -> Self {
        Self {
            has_limit: true,
            ..Self::default()
        }
    }

    fn from_doc(doc: &Doc, index: usize) -> Self {
        let line_of = |name: &str| doc.child(index, name).map(|e| e.line);
        let mut raw_vectors = Vec::new();
        if let Some(o) = doc.child(index, "origin") {
            for (what, attr) in [("origin xyz", "xyz"), ("origin rpy", "rpy")] {
                if let Some(v) = o.attr(attr) {
                    raw_vectors.push((what, v.to_owned(), Some(o.line)));
                }
            }
        }
        if let Some(a) = doc.child(index, "axis") {
            if let Some(v) = a.attr("xyz") {
                raw_vectors.push(("axis xyz", v.to_owned(), Some(a.line)));
            }
        }
        Self {
            line: doc.get(index).map(|e| e.line),
            parent_line: line_of("parent"),
            child_line: line_of("child"),
            origin_line: line_of("origin"),
            axis_line: line_of("axis"),
            limit_line: line_of("limit"),
            mimic_line: line_of("mimic"),
            has_limit: doc.child(index, "limit").is_some(),
            raw_vectors,
        }
    }
}

/// A parsed and validated URDF: one tree of uniquely named links joined by joints with finite
/// numbers, indexed by name.
///
/// Build it with [`UrdfModel::parse`] or [`UrdfModel::from_bytes`], then pick a serial chain
/// with [`UrdfModel::chain`]. Validation covers the whole document (names, tree shape, numbers,
/// limits, mimic drivers); what depends on the chosen chain (floating or planar joints, at
/// least one moving joint) is checked by [`UrdfModel::chain`].
#[derive(Debug, Clone)]
pub struct UrdfModel {
    pub(crate) robot: Robot,
    link_index: HashMap<String, usize>,
    joint_index: HashMap<String, usize>,
    link_lines: Vec<Option<usize>>,
    pub(crate) joint_sources: Vec<JointSource>,
    /// Per joint: index of its parent link.
    pub(crate) joint_parent: Vec<usize>,
    /// Per joint: index of its child link.
    joint_child: Vec<usize>,
    /// Per link: the joint whose child it is.
    parent_joint: Vec<Option<usize>>,
    /// Per link: joints whose parent it is.
    child_joints: Vec<Vec<usize>>,
    root: usize,
}

impl UrdfModel {
    /// Parses and validates a whole URDF document.
    ///
    /// A leading byte-order mark is ignored. Documents declaring entities (`<!ENTITY`) are
    /// refused before any XML parsing, so an entity-expansion bomb costs one linear scan.
    ///
    /// # Errors
    /// - [`UrdfError::EntityDeclaration`] for an entity declaration;
    /// - [`UrdfError::Parse`] for text that is not one well-formed `<robot>` element, a missing
    ///   required attribute or element, or a malformed number (with the line when found);
    /// - [`UrdfError::NoLinks`], [`UrdfError::DuplicateLink`], [`UrdfError::DuplicateJoint`],
    ///   [`UrdfError::MissingLink`], [`UrdfError::TwoParents`], [`UrdfError::Cycle`],
    ///   [`UrdfError::NoRoot`], [`UrdfError::SeveralRoots`] when the links are not one tree;
    /// - [`UrdfError::UnsupportedJointType`] for a type that is not URDF (`spherical`, `ball`);
    /// - [`UrdfError::NonFinite`], [`UrdfError::ZeroAxis`], [`UrdfError::MissingLimit`],
    ///   [`UrdfError::LimitsReversed`], [`UrdfError::UnknownMimicJoint`],
    ///   [`UrdfError::MimicItself`] for a joint's numbers.
    pub fn parse(text: &str) -> Result<UrdfModel, UrdfError> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let doc = scan::scan(text).map_err(|e| match e {
            ScanError::Entity { line } => UrdfError::EntityDeclaration { line },
            ScanError::Malformed { message, line } => UrdfError::Parse { message, line },
        })?;
        let robot = urdf_rs::read_from_string(text)
            .map_err(|e| crate::locate::urdf_rs_error(&e.to_string(), &doc))?;
        Self::validate(robot, &doc)
    }

    /// Decodes `bytes` as UTF-8, then parses and validates them like [`UrdfModel::parse`].
    ///
    /// # Errors
    /// [`UrdfError::NotUtf8`] with the offset and line of the first invalid byte; otherwise as
    /// [`UrdfModel::parse`].
    pub fn from_bytes(bytes: &[u8]) -> Result<UrdfModel, UrdfError> {
        match std::str::from_utf8(bytes) {
            Ok(text) => Self::parse(text),
            Err(e) => {
                let offset = e.valid_up_to();
                let line = scan::Lines::new(bytes).line_of(offset);
                Err(UrdfError::NotUtf8 { offset, line })
            }
        }
    }

    fn validate(robot: Robot, doc: &Doc) -> Result<UrdfModel, UrdfError> {
        let link_elems = doc.top_level("link");
        let joint_elems = doc.top_level("joint");
        let link_lines: Vec<Option<usize>> = if link_elems.len() == robot.links.len() {
            link_elems
                .iter()
                .map(|&i| doc.get(i).map(|e| e.line))
                .collect()
        } else {
            vec![None; robot.links.len()]
        };
        let joint_sources: Vec<JointSource> = if joint_elems.len() == robot.joints.len() {
            joint_elems
                .iter()
                .map(|&i| JointSource::from_doc(doc, i))
                .collect()
        } else {
            vec![JointSource::unknown(); robot.joints.len()]
        };
        let infinite_limits_allowed = version_at_least_1_2(robot.version.as_deref());

        if robot.links.is_empty() {
            return Err(UrdfError::NoLinks {
                robot: robot.name.clone(),
            });
        }
        let mut link_index: HashMap<String, usize> = HashMap::with_capacity(robot.links.len());
        for (i, link) in robot.links.iter().enumerate() {
            check_name("link", &link.name, line_at(&link_lines, i))?;
            if let Some(&first) = link_index.get(&link.name) {
                return Err(UrdfError::DuplicateLink {
                    link: link.name.clone(),
                    line: line_at(&link_lines, i),
                    first_line: line_at(&link_lines, first),
                });
            }
            link_index.insert(link.name.clone(), i);
        }
        let mut joint_index: HashMap<String, usize> = HashMap::with_capacity(robot.joints.len());
        for (k, joint) in robot.joints.iter().enumerate() {
            check_name(
                "joint",
                &joint.name,
                joint_sources.get(k).and_then(|s| s.line),
            )?;
            if let Some(&first) = joint_index.get(&joint.name) {
                return Err(UrdfError::DuplicateJoint {
                    joint: joint.name.clone(),
                    line: joint_sources.get(k).and_then(|s| s.line),
                    first_line: joint_sources.get(first).and_then(|s| s.line),
                });
            }
            joint_index.insert(joint.name.clone(), k);
        }

        let unknown = JointSource::unknown();
        let mut joint_parent = Vec::with_capacity(robot.joints.len());
        let mut joint_child = Vec::with_capacity(robot.joints.len());
        for (k, joint) in robot.joints.iter().enumerate() {
            let src = joint_sources.get(k).unwrap_or(&unknown);
            let find = |role: &'static str, name: &str, line: Option<usize>| {
                link_index
                    .get(name)
                    .copied()
                    .ok_or_else(|| UrdfError::MissingLink {
                        joint: joint.name.clone(),
                        role,
                        link: name.to_owned(),
                        line: line.or(src.line),
                    })
            };
            joint_parent.push(find("parent", &joint.parent.link, src.parent_line)?);
            joint_child.push(find("child", &joint.child.link, src.child_line)?);
            check_joint(joint, src, infinite_limits_allowed, &joint_index)?;
        }

        // Tree shape: one parent per link, no cycle, one root.
        let n = robot.links.len();
        let mut parent_joint: Vec<Option<usize>> = vec![None; n];
        for (k, &child) in joint_child.iter().enumerate() {
            let Some(slot) = parent_joint.get_mut(child) else {
                continue;
            };
            if let Some(first) = *slot {
                return Err(UrdfError::TwoParents {
                    link: name_of(&robot.links, child, |l| &l.name),
                    first: name_of(&robot.joints, first, |j| &j.name),
                    second: name_of(&robot.joints, k, |j| &j.name),
                    line: joint_sources.get(k).and_then(|s| s.line),
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
            idx.iter()
                .map(|&i| name_of(&robot.links, i, |l| &l.name))
                .collect()
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
                joint: name_of(&robot.joints, joint, |j| &j.name),
                line: joint_sources.get(joint).and_then(|s| s.line),
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
            link_lines,
            joint_sources,
            joint_parent,
            joint_child,
            parent_joint,
            child_joints,
            root,
        })
    }

    /// The `name` attribute of `<robot>` (empty when absent).
    pub fn robot_name(&self) -> &str {
        &self.robot.name
    }

    /// The robot as urdf-rs parsed it (with urdf-rs's defaults filled in: a missing `<origin>`
    /// is the identity, a missing `<axis>` is `1 0 0`, a missing `<limit>` is all zeros).
    pub fn robot(&self) -> &Robot {
        &self.robot
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
        line_at(&self.link_lines, i)
    }

    /// The 1-based source line of `<joint name="joint"`, when the joint exists and its line is
    /// known.
    pub fn joint_line(&self, joint: &str) -> Option<usize> {
        let &k = self.joint_index.get(joint)?;
        self.joint_sources.get(k).and_then(|s| s.line)
    }

    /// Chooses a serial chain from `base` down to `tip` (link names).
    ///
    /// `base` defaults to the root link. `tip` defaults to the only leaf link below the base.
    /// Fixed joints between them are folded into the neighbouring transforms; every revolute,
    /// continuous and prismatic joint becomes one axis of the chain. Frames: everything the
    /// chain returns is in the base link's frame, metres and radians.
    ///
    /// # Errors
    /// - [`UrdfError::UnknownLink`] for a base or tip the URDF does not define (with close
    ///   names, or every link when there are few);
    /// - [`UrdfError::SeveralLeaves`] when no tip is given and several leaves lie below the base;
    /// - [`UrdfError::Disconnected`] when the tip is not below the base;
    /// - [`UrdfError::JointTypeInChain`] for a floating or planar joint between them;
    /// - [`UrdfError::NoMovingJoint`] when only fixed joints (or none) join them;
    /// - [`UrdfError::Geometry`] when finite inputs overflow while composing the chain.
    pub fn chain(&self, base: Option<&str>, tip: Option<&str>) -> Result<Chain, UrdfError> {
        let base = match base {
            Some(name) => self.find_link(name, "base")?,
            None => self.root,
        };
        let tip = match tip {
            Some(name) => self.find_link(name, "tip")?,
            None => self.only_leaf_below(base)?,
        };
        let path = self.path(base, tip)?;
        Chain::build(self, base, tip, &path)
    }

    pub(crate) fn link_name(&self, link: usize) -> &str {
        self.robot
            .links
            .get(link)
            .map(|l| l.name.as_str())
            .unwrap_or("")
    }

    pub(crate) fn joint_index_of(&self, joint: &str) -> Option<usize> {
        self.joint_index.get(joint).copied()
    }

    fn find_link(&self, name: &str, role: &'static str) -> Result<usize, UrdfError> {
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

    fn only_leaf_below(&self, base: usize) -> Result<usize, UrdfError> {
        let mut leaves = Vec::new();
        let mut stack = vec![base];
        while let Some(link) = stack.pop() {
            let children = self
                .child_joints
                .get(link)
                .map(Vec::as_slice)
                .unwrap_or(&[]);
            if children.is_empty() {
                leaves.push(link);
            }
            stack.extend(children.iter().filter_map(|&j| self.joint_child.get(j)));
        }
        leaves.sort_unstable();
        match leaves.as_slice() {
            [leaf] => Ok(*leaf),
            _ => Err(UrdfError::SeveralLeaves {
                base: self.link_name(base).to_owned(),
                leaves: leaves
                    .iter()
                    .map(|&l| self.link_name(l).to_owned())
                    .collect(),
            }),
        }
    }

    /// Whether `below` lies in the subtree of `above` (or is it).
    fn is_below(&self, below: usize, above: usize) -> bool {
        self.ancestors(below).any(|l| l == above)
    }

    /// `link`, its parent, its grandparent, ..., the root.
    fn ancestors(&self, link: usize) -> impl Iterator<Item = usize> + '_ {
        std::iter::successors(Some(link), move |&l| {
            let j = self.parent_joint.get(l).copied().flatten()?;
            self.joint_parent.get(j).copied()
        })
        // The tree is validated acyclic; the bound only guards against a broken invariant.
        .take(self.robot.links.len() + 1)
    }

    /// Joint indices from `base` down to `tip`.
    fn path(&self, base: usize, tip: usize) -> Result<Vec<usize>, UrdfError> {
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

/// Refuses a link or joint name holding a control character (see
/// [`UrdfError::ControlCharacterInName`]).
fn check_name(kind: &'static str, name: &str, line: Option<usize>) -> Result<(), UrdfError> {
    match name.chars().enumerate().find(|(_, c)| c.is_control()) {
        Some((k, c)) => Err(UrdfError::ControlCharacterInName {
            kind,
            name: format!("{name:?}").trim_matches('"').to_owned(),
            code: format!("U+{:04X}", u32::from(c)),
            position: k + 1,
            line,
        }),
        None => Ok(()),
    }
}

fn line_at(lines: &[Option<usize>], i: usize) -> Option<usize> {
    lines.get(i).copied().flatten()
}

fn name_of<T>(items: &[T], i: usize, name: impl Fn(&T) -> &String) -> String {
    items.get(i).map(|t| name(t).clone()).unwrap_or_default()
}

/// `version="1.2"` or later: omitted limits are infinite by definition (urdf-rs follows it).
fn version_at_least_1_2(version: Option<&str>) -> bool {
    version
        .and_then(|v| {
            let (major, minor) = v.trim().split_once('.')?;
            Some((major.parse::<u32>().ok()?, minor.parse::<u32>().ok()?))
        })
        .is_some_and(|v| v >= (1, 2))
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

/// Largest magnitude of an origin coordinate (metres), a limit (radians or metres) or a mimic
/// number: far beyond any robot, and far enough from overflow that every unit conversion and
/// composition stays finite.
pub(crate) const MAX_MAGNITUDE: f64 = 1e9;

/// Checks one joint's type, numbers, limits and mimic.
fn check_joint(
    joint: &urdf_rs::Joint,
    src: &JointSource,
    infinite_limits_allowed: bool,
    joint_index: &HashMap<String, usize>,
) -> Result<(), UrdfError> {
    let name = || joint.name.clone();
    let (moving, limited) = match joint.joint_type {
        JointType::Revolute => (true, Some("revolute")),
        JointType::Prismatic => (true, Some("prismatic")),
        JointType::Continuous => (true, None),
        JointType::Fixed | JointType::Floating | JointType::Planar => (false, None),
        JointType::Spherical => {
            return Err(UrdfError::UnsupportedJointType {
                joint: name(),
                found: "spherical".into(),
                line: src.line,
            })
        }
    };
    let finite = |what: &'static str, value: f64, line: Option<usize>| {
        if value.is_finite() {
            Ok(())
        } else {
            Err(UrdfError::NonFinite {
                joint: name(),
                what,
                value,
                line: line.or(src.line),
            })
        }
    };
    for (what, v, line) in [
        ("origin xyz", joint.origin.xyz.0, src.origin_line),
        ("origin rpy", joint.origin.rpy.0, src.origin_line),
        ("axis xyz", joint.axis.xyz.0, src.axis_line),
    ] {
        for x in v {
            finite(what, x, line)?;
        }
    }
    // Found by fuzzing: an origin of 1e306 m is finite, but its table printed in millimetres is
    // not. No robot needs lengths or limits beyond MAX_MAGNITUDE.
    let limits = [
        ("limit lower", joint.limit.lower),
        ("limit upper", joint.limit.upper),
    ];
    let mimic = joint.mimic.as_ref().map_or([None, None], |m| {
        [
            m.multiplier.map(|v| ("mimic multiplier", v)),
            m.offset.map(|v| ("mimic offset", v)),
        ]
    });
    for (what, v, line) in joint
        .origin
        .xyz
        .0
        .iter()
        .map(|&v| ("origin xyz", v, src.origin_line))
        .chain(limits.into_iter().map(|(w, v)| (w, v, src.limit_line)))
        .chain(
            mimic
                .into_iter()
                .flatten()
                .map(|(w, v)| (w, v, src.mimic_line)),
        )
    {
        if v.is_finite() && v.abs() > MAX_MAGNITUDE {
            return Err(UrdfError::OutOfRange {
                joint: name(),
                what,
                value: v,
                line: line.or(src.line),
            });
        }
    }
    for (what, raw, line) in &src.raw_vectors {
        if raw.split_whitespace().any(|t| t.parse::<f64>().is_err()) {
            return Err(UrdfError::Parse {
                message: format!(
                    "joint '{}': {what}: expected 3 numbers, found '{}'",
                    joint.name,
                    raw.trim()
                ),
                line: line.or(src.line),
            });
        }
    }
    let axis = joint.axis.xyz.0;
    if moving && crate::chain::unit_axis(axis).is_none() {
        return Err(UrdfError::ZeroAxis {
            joint: name(),
            axis,
            line: src.axis_line.or(src.line),
        });
    }
    if let Some(kind) = limited {
        if !src.has_limit {
            return Err(UrdfError::MissingLimit {
                joint: name(),
                kind,
                line: src.line,
            });
        }
        let (lower, upper) = (joint.limit.lower, joint.limit.upper);
        for (what, v) in [("limit lower", lower), ("limit upper", upper)] {
            if v.is_nan() || v.is_infinite() && !infinite_limits_allowed {
                finite(what, v, src.limit_line)?;
            }
        }
        if lower > upper {
            return Err(UrdfError::LimitsReversed {
                joint: name(),
                lower,
                upper,
                line: src.limit_line.or(src.line),
            });
        }
    }
    if let Some(m) = &joint.mimic {
        for (what, v) in [
            ("mimic multiplier", m.multiplier),
            ("mimic offset", m.offset),
        ] {
            if let Some(v) = v {
                finite(what, v, src.mimic_line)?;
            }
        }
        if m.joint == joint.name {
            return Err(UrdfError::MimicItself {
                joint: name(),
                line: src.mimic_line.or(src.line),
            });
        }
        if !joint_index.contains_key(&m.joint) {
            return Err(UrdfError::UnknownMimicJoint {
                joint: name(),
                driver: m.joint.clone(),
                line: src.mimic_line.or(src.line),
            });
        }
    }
    Ok(())
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
    fn versions() {
        assert!(!version_at_least_1_2(None));
        assert!(!version_at_least_1_2(Some("1.1")));
        assert!(version_at_least_1_2(Some("1.2")));
        assert!(version_at_least_1_2(Some(" 2.0")));
        assert!(!version_at_least_1_2(Some("garbage")));
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
