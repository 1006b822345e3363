//! SDFormat input: an `<sdf>` document (a `<model>`, nested models, or a `<world>` of models)
//! read into the same robot model a URDF fills, so that every chain, check and proof works on
//! it unchanged.
//!
//! # Conversion
//! Every frame's pose in the world is found first ([`frames::Graph::world_poses`], with the
//! rules of the document's version: [`pose::Version`]). A URDF joint's frame is its child
//! link's frame, and its axis passes through that frame's origin; an SDF joint's frame is its
//! own (`<joint><pose>`, by default the child link's). So a joint is written as a URDF joint
//! from the parent link `P` to the child `C` with origin `X_P⁻¹ X_C` and its axis in `C`'s
//! frame when its frame is `C`'s; otherwise as a joint to an added link `<joint>#frame` at the
//! joint frame (origin `X_P⁻¹ X_J`) and a fixed joint `<joint>#child` from it to `C`
//! (origin `X_J⁻¹ X_C`): the chain's forward kinematics are the SDF's exactly.
//!
//! `//axis/xyz` is expressed in the joint frame, in the model frame before 1.5 and with
//! `use_parent_model_frame` (1.5, 1.6), or in the frame `expressed_in` names (1.7+). Limits
//! of 1e16 and beyond (SDFormat's default) are no limits. Links that no joint holds (the
//! models of a world, a free link) hang from an added `world` link by a `floating` joint
//! `<link>#free` at their pose, which a chain refuses to cross; a joint whose parent is
//! `world` is a joint from that link.
//!
//! A joint of a type with no single axis (`ball`, `universal`, `revolute2`, `screw`,
//! `gearbox`) is kept with [`UrdfError::SdfJointType`]: refused on a chain, a warning
//! elsewhere. `<include>` is not expanded (a warning).

mod frames;
mod pose;

use nalgebra::{Isometry3, Vector3};
use roxmltree::Node;

use crate::robot::{Inertial, Joint, JointType, Link, Origin, Robot};
use crate::UrdfError;
use frames::{scoped, Graph, JointSpec};
use pose::{numbers, sdf_error, Version};

/// Limits at or beyond this magnitude are SDFormat's "no limit" (its default is ±1e16).
const NO_LIMIT: f64 = 1e16;

/// A joint frame within this distance (metres) and angle (radians) of its child link's frame
/// is that frame: the joint needs no added link. Far below any written precision.
const SAME_FRAME: f64 = 1e-12;

/// The newest version whose rules are implemented; later versions are read with them.
const NEWEST: Version = Version(1, 11);

/// 1-based line of a node.
pub(crate) fn line_of(node: Node) -> usize {
    node.document().text_pos_at(node.range().start).row as usize
}

/// The name of the root element of `text`, skipping the XML declaration, comments, processing
/// instructions and a doctype; `None` when no element starts the document.
pub(crate) fn root_element_name(text: &str) -> Option<&str> {
    let mut rest = text.trim_start_matches('\u{feff}');
    loop {
        rest = rest.trim_start();
        if let Some(r) = rest.strip_prefix("<?") {
            rest = r.split_once("?>")?.1;
        } else if let Some(r) = rest.strip_prefix("<!--") {
            rest = r.split_once("-->")?.1;
        } else if let Some(r) = rest.strip_prefix("<!") {
            rest = r.split_once('>')?.1;
        } else {
            let r = rest.strip_prefix('<')?;
            let end = r
                .find(|c: char| c.is_whitespace() || c == '>' || c == '/')
                .unwrap_or(r.len());
            return r.get(..end);
        }
    }
}

/// Whether `text` is an SDFormat document (its root element is `<sdf>`).
pub(crate) fn is_sdf(text: &str) -> bool {
    root_element_name(text) == Some("sdf")
}

/// Reads an SDFormat document into the robot model.
///
/// # Errors
/// [`UrdfError::EntityDeclaration`] for a document with a DTD; [`UrdfError::Parse`] for text
/// that is not well-formed XML; [`UrdfError::Sdf`] for frames that do not resolve, a joint
/// whose parent or child no link defines, or a document with no model.
pub(crate) fn read(text: &str) -> Result<Robot, UrdfError> {
    let doc = roxmltree::Document::parse(text).map_err(|e| match e {
        roxmltree::Error::DtdDetected => UrdfError::EntityDeclaration {
            line: e.pos().row as usize,
        },
        other => UrdfError::Parse {
            message: other.to_string(),
            line: Some(other.pos().row as usize),
        },
    })?;
    let sdf = doc.root_element();
    let mut robot = Robot::default();
    let version = match Version::parse(sdf.attribute("version")) {
        Some(v) if v < Version(1, 4) => {
            robot.warn(
                "<sdf>".into(),
                line_of(sdf),
                format!("version {}.{} is read with the rules of 1.4", v.0, v.1),
            );
            Version(1, 4)
        }
        Some(v) if v > NEWEST => {
            robot.warn(
                "<sdf>".into(),
                line_of(sdf),
                format!("version {}.{} is read with the rules of 1.11", v.0, v.1),
            );
            v
        }
        Some(v) => v,
        None => {
            robot.warn(
                "<sdf>".into(),
                line_of(sdf),
                format!(
                    "expected attribute 'version' (e.g. 1.9), found '{}'; read as 1.11",
                    sdf.attribute("version").unwrap_or("")
                ),
            );
            NEWEST
        }
    };
    let graph = Graph::collect(sdf, version)?;
    for (element, line, message) in &graph.warnings {
        robot.warn(element.clone(), *line, message.clone());
    }
    let top = sdf
        .children()
        .find(|c| c.has_tag_name("model") || c.has_tag_name("world"))
        .ok_or_else(|| {
            sdf_error(
                sdf,
                "<sdf>: expected a <model> or a <world>, found neither".into(),
            )
        })?;
    robot.name = top.attribute("name").unwrap_or("").to_owned();
    if graph.links.is_empty() {
        return Err(sdf_error(
            top,
            format!(
                "<{}> '{}': expected at least one <link>, found none",
                top.tag_name().name(),
                robot.name
            ),
        ));
    }
    let poses = graph.world_poses()?;
    let world_pose = |name: &str| -> Isometry3<f64> {
        graph
            .index
            .get(name)
            .and_then(|&i| poses.get(i).copied())
            .unwrap_or_else(Isometry3::identity)
    };
    for l in &graph.links {
        let inertial = read_inertial(l.node, &mut robot, &l.name);
        robot.links.push(Link {
            name: l.name.clone(),
            line: line_of(l.node),
            inertial,
        });
    }
    let mut ends = Vec::with_capacity(graph.joints.len());
    let mut world_used = false;
    for j in &graph.joints {
        let parent = if j.parent == "world" {
            world_used = true;
            "world".to_owned()
        } else {
            graph
                .attached_link(&j.parent)
                .ok_or_else(|| UrdfError::Sdf {
                    message: format!(
                    "joint '{}', <parent>: expected a link or a frame attached to one, found '{}'",
                    j.name, j.parent
                ),
                    line: Some(j.parent_line),
                })?
        };
        let child = graph
            .attached_link(&j.child)
            .ok_or_else(|| UrdfError::Sdf {
                message: format!(
                    "joint '{}', <child>: expected a link or a frame attached to one, found '{}'",
                    j.name, j.child
                ),
                line: Some(j.child_line),
            })?;
        ends.push((parent, child));
    }
    let link_order: Vec<&str> = graph.links.iter().map(|l| l.name.as_str()).collect();
    let keep = tree_joints(&ends, &link_order);
    let mut held = std::collections::HashSet::new();
    for ((j, (parent, child)), keep) in graph.joints.iter().zip(ends).zip(keep) {
        if !keep {
            robot.warn(
                format!("joint '{}'", j.name),
                line_of(j.node),
                format!("link '{child}' already has a parent joint: this joint closes a kinematic loop and is left out of the tree"),
            );
            continue;
        }
        held.insert(child.clone());
        let (x_p, x_c, x_j) = (
            world_pose(&parent),
            world_pose(&child),
            world_pose(&j.frame_key),
        );
        let (kind, fault, axis_world, limit) = joint_content(j, version, &graph, &world_pose, x_j);
        let mut joint = Joint {
            name: j.name.clone(),
            line: line_of(j.node),
            kind,
            parent: parent.clone(),
            parent_line: j.parent_line,
            child: child.clone(),
            child_line: j.child_line,
            origin: Origin::of(&(x_p.inverse() * x_c)),
            axis: [1.0, 0.0, 0.0],
            limit,
            mimic: None,
            mimic_line: None,
            fault,
        };
        let offset = x_c.inverse() * x_j;
        let same =
            offset.translation.vector.norm() <= SAME_FRAME && offset.rotation.angle() <= SAME_FRAME;
        let moving = kind.is_some_and(JointType::is_moving);
        if same || !moving {
            joint.axis = (x_c.rotation.inverse() * axis_world).into();
            robot.joints.push(joint);
        } else {
            let frame_link = format!("{}#frame", j.name);
            robot.links.push(Link {
                name: frame_link.clone(),
                line: line_of(j.node),
                inertial: Ok(None),
            });
            joint.child = frame_link.clone();
            joint.origin = Origin::of(&(x_p.inverse() * x_j));
            joint.axis = (x_j.rotation.inverse() * axis_world).into();
            robot.joints.push(joint);
            robot.joints.push(Joint::fixed(
                format!("{}#child", j.name),
                line_of(j.node),
                frame_link,
                child,
                j.child_line,
                Origin::of(&offset.inverse()),
            ));
        }
    }
    let free: Vec<String> = graph
        .links
        .iter()
        .map(|l| l.name.clone())
        .filter(|l| !held.contains(l))
        .collect();
    if world_used || free.len() > 1 {
        if robot.links.iter().any(|l| l.name == "world") {
            return Err(sdf_error(
                top,
                "expected no link named 'world' (the world frame's name), found one".into(),
            ));
        }
        robot.links.insert(
            0,
            Link {
                name: "world".into(),
                line: line_of(top),
                inertial: Ok(None),
            },
        );
        for l in free {
            let line = graph.get(&l).map_or(0, |f| f.line);
            let mut j = Joint::fixed(
                format!("{l}#free"),
                line,
                "world".into(),
                l.clone(),
                line,
                Origin::of(&world_pose(&l)),
            );
            j.kind = Some(JointType::Floating);
            robot.joints.push(j);
        }
    }
    Ok(robot)
}

/// Which joints make the tree (per joint, in order): from each link that is no joint's child
/// (`world` first, then in document order, the canonical link first), the whole tree below it
/// breadth first along parent to child; a joint whose child already has a parent closes a loop
/// (PR2's gripper and screw linkages) and is left out. Joints no such link reaches are then
/// taken in document order.
fn tree_joints(ends: &[(String, String)], links: &[&str]) -> Vec<bool> {
    use std::collections::{HashMap, HashSet, VecDeque};
    let children: HashSet<&str> = ends.iter().map(|(_, c)| c.as_str()).collect();
    let mut by_parent: HashMap<&str, Vec<usize>> = HashMap::new();
    for (k, (p, _)) in ends.iter().enumerate() {
        by_parent.entry(p.as_str()).or_default().push(k);
    }
    let mut keep = vec![false; ends.len()];
    let mut reached = vec![false; ends.len()];
    let mut held: HashSet<&str> = HashSet::new();
    let roots = std::iter::once("world")
        .chain(links.iter().copied())
        .filter(|l| !children.contains(l));
    for root in roots {
        let mut queue = VecDeque::from([root]);
        while let Some(link) = queue.pop_front() {
            for &k in by_parent.get(link).map(Vec::as_slice).unwrap_or(&[]) {
                let Some((_, child)) = ends.get(k) else {
                    continue;
                };
                if let Some(r) = reached.get_mut(k) {
                    *r = true;
                }
                if held.insert(child.as_str()) {
                    if let Some(slot) = keep.get_mut(k) {
                        *slot = true;
                    }
                    queue.push_back(child.as_str());
                }
            }
        }
    }
    for (k, (_, child)) in ends.iter().enumerate() {
        if !reached.get(k).copied().unwrap_or(true) && held.insert(child.as_str()) {
            if let Some(slot) = keep.get_mut(k) {
                *slot = true;
            }
        }
    }
    keep
}

type Content = (
    Option<JointType>,
    Option<UrdfError>,
    Vector3<f64>,
    Option<(f64, f64)>,
);

/// A joint's type, fault, axis direction in the world and limits.
fn joint_content(
    j: &JointSpec,
    version: Version,
    graph: &Graph,
    world_pose: &dyn Fn(&str) -> Isometry3<f64>,
    x_j: Isometry3<f64>,
) -> Content {
    let line = Some(line_of(j.node));
    let found = j.node.attribute("type").unwrap_or("").trim();
    let kind = match found {
        "revolute" => JointType::Revolute,
        "continuous" => JointType::Continuous,
        "prismatic" => JointType::Prismatic,
        "fixed" => JointType::Fixed,
        _ => {
            let fault = UrdfError::SdfJointType {
                joint: j.name.clone(),
                found: found.to_owned(),
                line,
            };
            return (None, Some(fault), Vector3::x(), None);
        }
    };
    let fail = |e: UrdfError| (Some(kind), Some(e), Vector3::x(), None);
    let Some(axis) = j.node.children().find(|c| c.has_tag_name("axis")) else {
        if kind.is_moving() {
            let e = sdf_error(
                j.node,
                format!("joint '{}': expected an <axis>, found none", j.name),
            );
            return fail(e);
        }
        return (Some(kind), None, Vector3::x(), None);
    };
    let Some(xyz_node) = axis.children().find(|c| c.has_tag_name("xyz")) else {
        // SDFormat's default axis is 0 0 1.
        return (
            Some(kind),
            None,
            x_j.rotation * Vector3::z(),
            limits(axis, kind),
        );
    };
    let xyz = match numbers(xyz_node, "<axis><xyz>") {
        Ok(v) if v.len() == 3 => Vector3::from_iterator(v),
        Ok(v) => {
            return fail(sdf_error(
                xyz_node,
                format!(
                    "joint '{}', <axis><xyz>: expected 3 numbers, found {}",
                    j.name,
                    v.len()
                ),
            ))
        }
        Err(e) => return fail(e),
    };
    if kind.is_moving() && xyz.amax() == 0.0 {
        return fail(UrdfError::ZeroAxis {
            joint: j.name.clone(),
            axis: xyz.into(),
            line: Some(line_of(xyz_node)),
        });
    }
    let parent_model_frame = axis
        .children()
        .find(|c| c.has_tag_name("use_parent_model_frame"))
        .and_then(|u| u.text())
        .is_some_and(|t| matches!(t.trim(), "true" | "1"));
    let expressed = xyz_node
        .attribute("expressed_in")
        .map(str::trim)
        .filter(|e| !e.is_empty() && version.has_frame_semantics());
    let rotation = if let Some(e) = expressed {
        let name = scoped(&j.prefix, &j.model_frame, e);
        if graph.get(&name).is_none() {
            return fail(sdf_error(
                xyz_node,
                format!("joint '{}', <axis><xyz>: expected expressed_in to name a frame of the model, found '{e}'", j.name),
            ));
        }
        world_pose(&name).rotation
    } else if version.axis_in_model_frame() || parent_model_frame {
        world_pose(&j.model_frame).rotation
    } else {
        x_j.rotation
    };
    (Some(kind), None, rotation * xyz, limits(axis, kind))
}

/// `<axis><limit>`'s lower and upper, when both are below [`NO_LIMIT`].
fn limits(axis: Node, kind: JointType) -> Option<(f64, f64)> {
    if !matches!(kind, JointType::Revolute | JointType::Prismatic) {
        return None;
    }
    let l = axis.children().find(|c| c.has_tag_name("limit"))?;
    let value = |tag: &str| -> Option<f64> {
        l.children()
            .find(|c| c.has_tag_name(tag))
            .and_then(|n| n.text())
            .and_then(|t| t.trim().parse::<f64>().ok())
            .filter(|v| v.is_finite() && v.abs() < NO_LIMIT)
    };
    let (lo, hi) = (value("lower")?, value("upper")?);
    (lo <= hi).then_some((lo, hi))
}

/// A link's `<inertial>`: mass and centre of mass (`<inertial><pose>`, in the link frame).
fn read_inertial(link: Node, robot: &mut Robot, name: &str) -> Result<Option<Inertial>, String> {
    let Some(i) = link.children().find(|c| c.has_tag_name("inertial")) else {
        return Ok(None);
    };
    let result = (|| -> Result<Inertial, (usize, String)> {
        let com = match i.children().find(|c| c.has_tag_name("pose")) {
            None => [0.0; 3],
            Some(p) => {
                let v = numbers(p, "<pose>").map_err(|e| (line_of(p), e.to_string()))?;
                match v.as_slice() {
                    [] => [0.0; 3],
                    [x, y, z, ..] => [*x, *y, *z],
                    _ => return Err((line_of(p), "<pose>: expected 6 numbers".into())),
                }
            }
        };
        let mass = match i.children().find(|c| c.has_tag_name("mass")) {
            None => 1.0,
            Some(m) => match numbers(m, "<mass>")
                .map_err(|e| (line_of(m), e.to_string()))?
                .as_slice()
            {
                [v] => *v,
                _ => return Err((line_of(m), "<mass>: expected one number".into())),
            },
        };
        Ok(Inertial { mass, com })
    })();
    result.map(Some).map_err(|(line, m)| {
        robot.warn(
            format!("link '{name}', <inertial>"),
            line,
            format!("{m}; the inertial is ignored"),
        );
        m
    })
}

#[cfg(test)]
mod tests;
