//! The URDF data model, read from the scanned document ([`crate::scan`]) in one pass.
//!
//! # What is strict and what is a warning
//! ROS's urdfdom ignores unknown elements, takes the first `<material>` of a `<visual>`, logs
//! a malformed `rgba` or a `<texture>` without `filename` and goes on. Mirroring it, a fault
//! that cannot change a chain's kinematics (in a link's `<visual>`, `<collision>` or
//! `<inertial>`, or in a top-level `<material>`) is a [`Warning`] naming the element and its
//! line. What defines the tree (link and joint names, parents and children) is strict: an error
//! here. A fault in a joint's own numbers, type, limits or mimic is kept with the joint: an
//! error from [`crate::UrdfModel::chain`] when the joint is on the chosen chain, a warning
//! otherwise.
//!
//! Numbers are read like Rust's `f64::from_str` (so `nan` and `inf` read, and are refused by
//! the checks). A missing `<origin>` is the identity, a missing `<axis>` is `1 0 0`, a
//! missing `lower`/`upper` is 0 (infinite from `version="1.2"` on), a missing mimic multiplier
//! 1 and offset 0: the URDF defaults. The types it fills are in [`crate::robot`].

use crate::robot::{Inertial, Joint, JointType, Link, MimicSpec, Origin, Robot};
use crate::scan::{Doc, Element};
use crate::UrdfError;

fn parse_error(message: String, line: usize) -> UrdfError {
    UrdfError::Parse {
        message,
        line: Some(line),
    }
}

/// Reads the links and joints of a scanned document.
///
/// # Errors
/// [`UrdfError::Parse`] for a link or joint without a name, or a joint without `<parent>` or
/// `<child>` (or their `link`): what defines the tree; [`UrdfError::ControlCharacterInName`]
/// for a robot name with a control or bidi character.
pub(crate) fn read(doc: &Doc) -> Result<Robot, UrdfError> {
    let root = doc.root();
    let mut robot = Robot {
        name: root.and_then(|r| r.attr("name")).unwrap_or("").to_owned(),
        ..Robot::default()
    };
    // The robot's name heads every table and sheet written from the file: refused as link and
    // joint names are (`&#27;[2J` would clear the terminal of whoever prints the table).
    if !robot.name.is_empty() {
        crate::check::check_name("robot", &robot.name, root.map(|r| r.line))?;
    }
    let infinite_by_default = version_at_least_1_2(root.and_then(|r| r.attr("version")));
    let children = root.map(|r| r.children.as_slice()).unwrap_or(&[]);
    let count = |name: &str| {
        children
            .iter()
            .filter(|&&k| doc.get(k).is_some_and(|e| e.name == name))
            .count()
    };
    robot.links.reserve_exact(count("link"));
    robot.joints.reserve_exact(count("joint"));
    for &k in children {
        let Some(e) = doc.get(k) else { continue };
        match e.name {
            "link" => {
                let link = read_link(doc, e, &mut robot)?;
                robot.links.push(link);
            }
            "joint" => {
                let joint = read_joint(doc, e, infinite_by_default)?;
                robot.joints.push(joint);
            }
            "material" => {
                let name = e.attr("name").unwrap_or("").escape_debug().to_string();
                let what = format!("material '{name}'");
                check_material(doc, e, &what, &mut robot);
            }
            _ => {}
        }
    }
    Ok(robot)
}

/// `version="1.2"` or later: omitted limits are infinite by definition.
pub(crate) fn version_at_least_1_2(version: Option<&str>) -> bool {
    version
        .and_then(|v| {
            let (major, minor) = v.trim().split_once('.')?;
            Some((major.parse::<u32>().ok()?, minor.parse::<u32>().ok()?))
        })
        .is_some_and(|v| v >= (1, 2))
}

fn children<'d, 'a>(
    doc: &'d Doc<'a>,
    e: &'d Element<'a>,
) -> impl Iterator<Item = &'d Element<'a>> + 'd {
    e.children.iter().filter_map(move |&c| doc.get(c))
}

fn first<'d, 'a>(doc: &'d Doc<'a>, e: &'d Element<'a>, name: &str) -> Option<&'d Element<'a>> {
    children(doc, e).find(|c| c.name == name)
}

/// One number attribute: `Ok(None)` when absent.
fn number(e: &Element, attr: &str) -> Result<Option<f64>, String> {
    match e.attr(attr) {
        None => Ok(None),
        Some(v) => v
            .trim()
            .parse::<f64>()
            .map(Some)
            .map_err(|_| format!("attribute '{attr}': expected a number, found '{v}'")),
    }
}

/// A vector attribute of `n` numbers: `Ok(None)` when absent. Every token must be a number.
fn numbers<const N: usize>(e: &Element, attr: &str) -> Result<Option<[f64; N]>, String> {
    let Some(v) = e.attr(attr) else {
        return Ok(None);
    };
    let mut out = [0.0; N];
    let mut count = 0;
    for t in v.split_whitespace() {
        match (t.parse::<f64>(), out.get_mut(count)) {
            (Ok(x), Some(slot)) => *slot = x,
            (Ok(_), None) => {}
            (Err(_), _) => {
                return Err(format!(
                    "attribute '{attr}': expected {N} numbers, found '{}'",
                    v.trim()
                ))
            }
        }
        count += 1;
    }
    if count == N {
        Ok(Some(out))
    } else {
        Err(format!(
            "attribute '{attr}': expected {N} numbers, found '{}'",
            v.trim()
        ))
    }
}

fn read_origin(e: Option<&Element>) -> Result<Origin, String> {
    let Some(e) = e else {
        return Ok(Origin::default());
    };
    Ok(Origin {
        xyz: numbers::<3>(e, "xyz")?.unwrap_or_default(),
        rpy: numbers::<3>(e, "rpy")?.unwrap_or_default(),
    })
}

fn read_link(doc: &Doc, e: &Element, robot: &mut Robot) -> Result<Link, UrdfError> {
    let name = e
        .attr("name")
        .ok_or_else(|| parse_error("link: expected attribute 'name', found none".into(), e.line))?
        .to_owned();
    let owner = format!("link '{name}'");
    let inertial = match first(doc, e, "inertial") {
        None => Ok(None),
        Some(i) => read_inertial(doc, i).map(Some).map_err(|(line, m)| {
            robot.warn(
                format!("{owner}, <inertial>"),
                line,
                format!("{m}; the inertial is ignored"),
            );
            m
        }),
    };
    for part in children(doc, e).filter(|c| matches!(c.name, "visual" | "collision")) {
        check_shape(doc, part, &format!("{owner}, <{}>", part.name), robot);
    }
    Ok(Link {
        name,
        line: e.line,
        inertial,
    })
}

fn read_inertial(doc: &Doc, i: &Element) -> Result<Inertial, (usize, String)> {
    let origin = first(doc, i, "origin");
    let com = read_origin(origin)
        .map_err(|m| (origin.map_or(i.line, |o| o.line), m))?
        .xyz;
    let mass_e = first(doc, i, "mass")
        .ok_or_else(|| (i.line, "expected a <mass> element, found none".to_owned()))?;
    let mass = number(mass_e, "value")
        .and_then(|m| m.ok_or_else(|| "expected attribute 'value', found none".into()))
        .map_err(|m| (mass_e.line, format!("<mass>: {m}")))?;
    if let Some(inertia) = first(doc, i, "inertia") {
        for a in ["ixx", "ixy", "ixz", "iyy", "iyz", "izz"] {
            number(inertia, a).map_err(|m| (inertia.line, format!("<inertia>: {m}")))?;
        }
    }
    Ok(Inertial { mass, com })
}

/// Checks a `<visual>` or `<collision>`: geometry, origin, material. Faults are warnings.
fn check_shape(doc: &Doc, part: &Element, what: &str, robot: &mut Robot) {
    if let Some(o) = first(doc, part, "origin") {
        if let Err(m) = read_origin(Some(o)) {
            robot.warn(format!("{what}, <origin>"), o.line, format!("{m}; ignored"));
        }
    }
    match first(doc, part, "geometry") {
        None => robot.warn(
            what.to_owned(),
            part.line,
            "expected a <geometry> element, found none; ignored".into(),
        ),
        Some(g) => match children(doc, g).next() {
            None => robot.warn(
                format!("{what}, <geometry>"),
                g.line,
                "expected <box>, <cylinder>, <capsule>, <sphere> or <mesh>, found nothing; ignored"
                    .into(),
            ),
            Some(shape) => {
                let fault = match shape.name {
                    "box" => numbers::<3>(shape, "size").and_then(|v| {
                        v.map(|_| ())
                            .ok_or_else(|| "expected attribute 'size', found none".into())
                    }),
                    "sphere" => required_numbers(shape, &["radius"]),
                    "cylinder" | "capsule" => required_numbers(shape, &["radius", "length"]),
                    "mesh" => match shape.attr("filename") {
                        None => Err("expected attribute 'filename', found none".into()),
                        Some(_) => numbers::<3>(shape, "scale").map(|_| ()),
                    },
                    other => Err(format!(
                        "expected <box>, <cylinder>, <capsule>, <sphere> or <mesh>, found <{other}>"
                    )),
                };
                if let Err(m) = fault {
                    robot.warn(
                        format!("{what}, <{}>", shape.name),
                        shape.line,
                        format!("{m}; ignored"),
                    );
                }
            }
        },
    }
    if part.name == "visual" {
        let mut materials = children(doc, part).filter(|c| c.name == "material");
        if let Some(m) = materials.next() {
            check_material(doc, m, &format!("{what}, <material>"), robot);
        }
        let more = materials.count();
        if more > 0 {
            robot.warn(
                what.to_owned(),
                part.line,
                format!(
                    "expected one <material>, found {}; the first is used (as urdfdom does)",
                    more + 1
                ),
            );
        }
    }
}

fn required_numbers(e: &Element, attrs: &[&str]) -> Result<(), String> {
    for a in attrs {
        if number(e, a)?.is_none() {
            return Err(format!("expected attribute '{a}', found none"));
        }
    }
    Ok(())
}

/// Checks a `<material>` (top-level or in a visual): color and texture. Faults are warnings.
fn check_material(doc: &Doc, m: &Element, what: &str, robot: &mut Robot) {
    if m.attr("name").is_none() {
        robot.warn(
            what.to_owned(),
            m.line,
            "expected attribute 'name', found none; ignored".into(),
        );
    }
    if let Some(c) = first(doc, m, "color") {
        let fault = match c.attr("rgba") {
            None => Some("expected attribute 'rgba', found none".to_owned()),
            Some(_) => numbers::<4>(c, "rgba").err(),
        };
        if let Some(f) = fault {
            robot.warn(
                format!("{what}, <color>"),
                c.line,
                format!("{f}; the color is ignored"),
            );
        }
    }
    if let Some(t) = first(doc, m, "texture") {
        if t.attr("filename").is_none() {
            robot.warn(
                format!("{what}, <texture>"),
                t.line,
                "expected attribute 'filename', found none; the texture is ignored".into(),
            );
        }
    }
}

/// Reads a `<joint>`: the tree part strictly, the rest into [`Joint::fault`].
fn read_joint(doc: &Doc, e: &Element, infinite_by_default: bool) -> Result<Joint, UrdfError> {
    let name = e
        .attr("name")
        .ok_or_else(|| {
            parse_error(
                "joint: expected attribute 'name', found none".into(),
                e.line,
            )
        })?
        .to_owned();
    let end = |role: &str| -> Result<(String, usize), UrdfError> {
        let el = first(doc, e, role).ok_or_else(|| {
            parse_error(
                format!("joint '{name}': expected a <{role}> element, found none"),
                e.line,
            )
        })?;
        let link = el.attr("link").ok_or_else(|| {
            parse_error(
                format!("joint '{name}', <{role}>: expected attribute 'link', found none"),
                el.line,
            )
        })?;
        Ok((link.to_owned(), el.line))
    };
    let (parent, parent_line) = end("parent")?;
    let (child, child_line) = end("child")?;
    let mut joint = Joint {
        name,
        line: e.line,
        kind: None,
        parent,
        parent_line,
        child,
        child_line,
        origin: Origin::default(),
        axis: [1.0, 0.0, 0.0],
        limit: None,
        mimic: None,
        mimic_line: first(doc, e, "mimic").map(|m| m.line),
        fault: None,
    };
    joint.fault = read_joint_content(doc, e, &mut joint, infinite_by_default).err();
    if joint.fault.is_none() {
        joint.fault = crate::check::check_joint(&joint, doc, e, infinite_by_default).err();
    }
    Ok(joint)
}

/// Reads type, origin, axis, limit and mimic into `joint`; the first fault is returned.
fn read_joint_content(
    doc: &Doc,
    e: &Element,
    joint: &mut Joint,
    infinite_by_default: bool,
) -> Result<(), UrdfError> {
    let name = joint.name.clone();
    let at = |el: &Element, m: String| {
        parse_error(format!("joint '{name}', <{}>: {m}", el.name), el.line)
    };
    joint.kind = Some(match e.attr("type") {
        Some("revolute") => JointType::Revolute,
        Some("continuous") => JointType::Continuous,
        Some("prismatic") => JointType::Prismatic,
        Some("fixed") => JointType::Fixed,
        Some("floating") => JointType::Floating,
        Some("planar") => JointType::Planar,
        Some(other) => {
            return Err(UrdfError::UnsupportedJointType {
                joint: name,
                found: other.to_owned(),
                line: Some(e.line),
            })
        }
        None => {
            return Err(parse_error(
                format!("joint '{name}': expected attribute 'type', found none"),
                e.line,
            ))
        }
    });
    if let Some(o) = first(doc, e, "origin") {
        joint.origin = read_origin(Some(o)).map_err(|m| at(o, m))?;
    }
    if let Some(a) = first(doc, e, "axis") {
        joint.axis = numbers::<3>(a, "xyz")
            .and_then(|v| v.ok_or_else(|| "expected attribute 'xyz', found none".into()))
            .map_err(|m| at(a, m))?;
    }
    if let Some(l) = first(doc, e, "limit") {
        let (inf_lo, inf_hi) = if infinite_by_default {
            (f64::NEG_INFINITY, f64::INFINITY)
        } else {
            (0.0, 0.0)
        };
        let lower = number(l, "lower").map_err(|m| at(l, m))?;
        let upper = number(l, "upper").map_err(|m| at(l, m))?;
        for a in ["effort", "velocity"] {
            number(l, a).map_err(|m| at(l, m))?;
        }
        if l.attr("velocity").is_none() {
            return Err(at(l, "expected attribute 'velocity', found none".into()));
        }
        joint.limit = Some((lower.unwrap_or(inf_lo), upper.unwrap_or(inf_hi)));
    }
    if let Some(m) = first(doc, e, "mimic") {
        let driver = m
            .attr("joint")
            .ok_or_else(|| at(m, "expected attribute 'joint', found none".into()))?;
        joint.mimic = Some(MimicSpec {
            joint: driver.to_owned(),
            multiplier: number(m, "multiplier")
                .map_err(|x| at(m, x))?
                .unwrap_or(1.0),
            offset: number(m, "offset").map_err(|x| at(m, x))?.unwrap_or(0.0),
        });
    }
    // Numbers that do not move the chain are still read strictly on it (as urdfdom does).
    for (el, attrs) in [
        ("dynamics", &["damping", "friction"][..]),
        (
            "safety_controller",
            &[
                "soft_lower_limit",
                "soft_upper_limit",
                "k_position",
                "k_velocity",
            ][..],
        ),
        (
            "calibration",
            &["rising", "falling", "reference_position"][..],
        ),
    ] {
        if let Some(x) = first(doc, e, el) {
            for a in attrs {
                number(x, a).map_err(|m| at(x, m))?;
            }
        }
    }
    Ok(())
}

/// A one-line summary of a joint fault for a warning: its message without the leading
/// "joint 'name' (line N): " the warning's element and line already say.
pub(crate) fn fault_summary(joint: &Joint, fault: &UrdfError) -> String {
    let text = match fault {
        UrdfError::Parse { message, .. } => message.clone(),
        other => other.to_string(),
    };
    let prefix = format!("joint '{}'", joint.name);
    let rest = text.strip_prefix(&prefix).unwrap_or(&text);
    let rest = rest
        .strip_prefix(&format!(" (line {})", joint.line))
        .or_else(|| {
            let (_, after) = rest.strip_prefix(" (line ")?.split_once(')')?;
            Some(after)
        })
        .unwrap_or(rest);
    rest.trim_start_matches([':', ',', ' ']).to_owned()
}
