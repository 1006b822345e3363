//! Turns urdf-rs's errors into [`UrdfError`]s with a line and the joint or link named.
//!
//! urdf-rs parses twice: RustyXML reads the text (its errors carry `Line: N, Column: M`), then
//! serde-xml-rs deserialises a re-serialised copy (its errors carry no position at all, e.g.
//! "missing field `velocity`"). For the latter the scanned document is searched for the first
//! element that shows the same fault, in the order urdf-rs deserialises (links, joints,
//! materials).

use crate::scan::{Doc, Element};
use crate::UrdfError;

/// Maps the text of a urdf-rs error.
pub(crate) fn urdf_rs_error(raw: &str, doc: &Doc) -> UrdfError {
    let msg = raw.trim();
    let msg = msg.strip_prefix("custom: ").unwrap_or(msg);
    if let Some(e) = rusty_xml(msg) {
        return e;
    }
    if let Some(variant) = between(msg, "unknown variant `", "`") {
        if let Some(e) = unknown_variant(variant, doc) {
            return e;
        }
    }
    if let Some(field) = between(msg, "missing field `", "`") {
        if let Some((line, ctx)) = find(doc, |e| missing(e, doc, field)) {
            let what = if ELEMENT_FIELDS.contains(&field) {
                format!("a <{field}> element")
            } else {
                format!("attribute '{field}'")
            };
            return parse(format!("{ctx}: expected {what}, found none"), Some(line));
        }
    }
    if msg.contains("invalid float literal") {
        if let Some((line, ctx)) = find(doc, bad_float) {
            return parse(ctx, Some(line));
        }
    }
    if msg.starts_with("Wrong vector element count") {
        if let Some((line, ctx)) = find(doc, bad_vector) {
            return parse(ctx, Some(line));
        }
    }
    if let Some(field) = between(msg, "duplicate field `", "`") {
        if let Some((line, ctx)) = find(doc, |e| {
            (doc_children_named(doc, e, field) > 1)
                .then(|| format!("expected one <{field}>, found several"))
        }) {
            return parse(ctx, Some(line));
        }
    }
    // urdf-rs's own checks of URDF 1.1/1.2 documents name the joint as "joint [name]: ...".
    if let Some(joint) = between(msg, "joint [", "]") {
        let line = joint_line(doc, joint);
        if msg.contains("cannot be smaller than") {
            let upper = between(msg, "limit (", ")").and_then(|v| v.parse().ok());
            let lower = msg
                .rsplit_once("limit (")
                .and_then(|(_, r)| r.split_once(')'))
                .and_then(|(v, _)| v.parse().ok());
            if let (Some(lower), Some(upper)) = (lower, upper) {
                return UrdfError::LimitsReversed {
                    joint: joint.to_owned(),
                    lower,
                    upper,
                    line,
                };
            }
        }
        return parse(lowercase_first(msg), line);
    }
    parse(lowercase_first(msg), None)
}

/// Fields that are child elements rather than attributes.
const ELEMENT_FIELDS: [&str; 5] = ["parent", "child", "mass", "inertia", "geometry"];

fn parse(message: String, line: Option<usize>) -> UrdfError {
    UrdfError::Parse { message, line }
}

/// "Parse error; Line: 4, Column: 4, Reason: Malformed XML".
fn rusty_xml(msg: &str) -> Option<UrdfError> {
    let rest = msg.strip_prefix("Parse error; ")?;
    let line = between(rest, "Line: ", ",").and_then(|v| v.trim().parse().ok());
    let column = between(rest, "Column: ", ",").map(str::trim);
    let reason = rest.split_once("Reason: ").map_or(rest, |(_, r)| r).trim();
    let message = match column {
        Some(c) => format!("{} (column {c})", lowercase_first(reason)),
        None => lowercase_first(reason),
    };
    Some(parse(message, line))
}

fn unknown_variant(variant: &str, doc: &Doc) -> Option<UrdfError> {
    for k in doc.top_level("joint") {
        let Some(j) = doc.get(k) else { continue };
        if j.attr("type") == Some(variant) {
            return Some(UrdfError::UnsupportedJointType {
                joint: j.attr("name").unwrap_or("").to_owned(),
                found: variant.to_owned(),
                line: Some(j.line),
            });
        }
    }
    let (line, ctx) = find(doc, |e| {
        (e.name == "geometry" && doc_children_named(doc, e, variant) > 0).then(|| {
            format!("expected <box>, <cylinder>, <capsule>, <sphere> or <mesh>, found <{variant}>")
        })
    })?;
    Some(parse(ctx, Some(line)))
}

fn joint_line(doc: &Doc, joint: &str) -> Option<usize> {
    doc.top_level("joint")
        .into_iter()
        .filter_map(|k| doc.get(k))
        .find(|j| j.attr("name") == Some(joint))
        .map(|j| j.line)
}

/// Required fields (attribute or child element) of what urdf-rs deserialises.
fn required(element: &str) -> &'static [&'static str] {
    match element {
        "link" | "material" => &["name"],
        "joint" => &["name", "type", "parent", "child"],
        "parent" | "child" => &["link"],
        "limit" => &["velocity"],
        "mimic" => &["joint"],
        "inertial" => &["mass", "inertia"],
        "mass" => &["value"],
        "inertia" => &["ixx", "ixy", "ixz", "iyy", "iyz", "izz"],
        "visual" | "collision" => &["geometry"],
        "color" => &["rgba"],
        "texture" | "mesh" => &["filename"],
        "box" => &["size"],
        "cylinder" | "capsule" => &["radius", "length"],
        "sphere" => &["radius"],
        "safety_controller" => &["k_velocity"],
        "axis" => &["xyz"],
        _ => &[],
    }
}

/// Attributes urdf-rs reads as one number.
fn float_attributes(element: &str) -> &'static [&'static str] {
    match element {
        "limit" => &[
            "lower",
            "upper",
            "effort",
            "velocity",
            "acceleration",
            "deceleration",
            "jerk",
        ],
        "mimic" => &["multiplier", "offset"],
        "mass" => &["value"],
        "inertia" => &["ixx", "ixy", "ixz", "iyy", "iyz", "izz"],
        "dynamics" => &["damping", "friction"],
        "safety_controller" => &[
            "soft_lower_limit",
            "soft_upper_limit",
            "k_position",
            "k_velocity",
        ],
        "calibration" => &["rising", "falling"],
        "cylinder" | "capsule" => &["radius", "length"],
        "sphere" => &["radius"],
        _ => &[],
    }
}

/// Attributes urdf-rs reads as a fixed number of numbers.
fn vector_attributes(element: &str) -> &'static [(&'static str, usize)] {
    match element {
        "origin" => &[("xyz", 3), ("rpy", 3)],
        "axis" => &[("xyz", 3)],
        "box" => &[("size", 3)],
        "mesh" => &[("scale", 3)],
        "color" => &[("rgba", 4)],
        _ => &[],
    }
}

fn doc_children_named(doc: &Doc, e: &Element, name: &str) -> usize {
    e.children
        .iter()
        .filter(|&&c| doc.get(c).is_some_and(|c| c.name == name))
        .count()
}

fn missing(e: &Element, doc: &Doc, field: &str) -> Option<String> {
    let lacks = required(&e.name).contains(&field)
        && e.attr(field).is_none()
        && doc_children_named(doc, e, field) == 0;
    lacks.then(String::new)
}

fn bad_float(e: &Element) -> Option<String> {
    float_attributes(&e.name).iter().find_map(|&a| {
        let v = e.attr(a)?;
        v.trim()
            .parse::<f64>()
            .is_err()
            .then(|| format!("attribute '{a}': expected a number, found '{v}'"))
    })
}

fn bad_vector(e: &Element) -> Option<String> {
    vector_attributes(&e.name).iter().find_map(|&(a, n)| {
        let v = e.attr(a)?;
        let numbers = v
            .split_whitespace()
            .filter(|t| t.parse::<f64>().is_ok())
            .count();
        (numbers != n).then(|| {
            format!(
                "attribute '{a}': expected {n} numbers, found '{}'",
                v.trim()
            )
        })
    })
}

/// The first element (links, then joints, then materials, each depth first) for which `fault`
/// says something; returns its line and "owner: <element>: fault".
fn find(doc: &Doc, fault: impl Fn(&Element) -> Option<String>) -> Option<(usize, String)> {
    for kind in ["link", "joint", "material"] {
        for top in doc.top_level(kind) {
            let Some(owner) = doc.get(top) else { continue };
            let owner_name = format!("{kind} '{}'", owner.attr("name").unwrap_or(""));
            let mut stack = vec![top];
            while let Some(i) = stack.pop() {
                let Some(e) = doc.get(i) else { continue };
                if let Some(what) = fault(e) {
                    let ctx = if i == top {
                        owner_name
                    } else {
                        format!("{owner_name}, <{}>", e.name)
                    };
                    let ctx = if what.is_empty() {
                        ctx
                    } else {
                        format!("{ctx}: {what}")
                    };
                    return Some((e.line, ctx));
                }
                // urdf-rs keeps only these children of a link.
                let children = e.children.iter().rev().copied().filter(|&c| {
                    i != top
                        || kind != "link"
                        || doc.get(c).is_some_and(|c| {
                            matches!(c.name.as_str(), "inertial" | "visual" | "collision")
                        })
                });
                stack.extend(children);
            }
        }
    }
    None
}

/// The text between the first `start` and the next `end` after it.
fn between<'a>(s: &'a str, start: &str, end: &str) -> Option<&'a str> {
    let (_, rest) = s.split_once(start)?;
    rest.split_once(end).map(|(v, _)| v)
}

fn lowercase_first(s: &str) -> String {
    let mut chars = s.chars();
    match chars.next() {
        Some(c) => c.to_lowercase().chain(chars).collect(),
        None => String::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scan::scan;

    #[test]
    fn rusty_xml_positions_are_kept() {
        let doc = scan("<robot/>").unwrap();
        let e = urdf_rs_error(
            "Parse error; Line: 4, Column: 7, Reason: Found invalid entity",
            &doc,
        );
        assert_eq!(
            e,
            UrdfError::Parse {
                message: "found invalid entity (column 7)".into(),
                line: Some(4)
            }
        );
    }

    #[test]
    fn version_checks_become_reversed_limits() {
        let doc = scan("<robot>\n<joint name=\"j\"/>\n</robot>").unwrap();
        let e = urdf_rs_error(
            "joint [j]: upper position limit (1) cannot be smaller than lower position limit (2)",
            &doc,
        );
        assert_eq!(
            e,
            UrdfError::LimitsReversed {
                joint: "j".into(),
                lower: 2.0,
                upper: 1.0,
                line: Some(2)
            }
        );
    }

    #[test]
    fn unknown_messages_pass_through_lowercased() {
        let doc = scan("<robot/>").unwrap();
        assert_eq!(
            urdf_rs_error("Something odd", &doc),
            UrdfError::Parse {
                message: "something odd".into(),
                line: None
            }
        );
    }
}
