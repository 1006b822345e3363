//! Checks of one joint's numbers and of names.

use nalgebra::{Unit, Vector3};

use crate::robot::{Joint, JointType};
use crate::scan::{Doc, Element};
use crate::UrdfError;

/// The unit direction of a URDF axis, `None` for a zero vector. Divides by the largest
/// component first so that huge finite components cannot overflow the norm.
pub(crate) fn unit_axis(xyz: [f64; 3]) -> Option<Unit<Vector3<f64>>> {
    let v = Vector3::from(xyz);
    let scale = v.amax();
    if scale > 0.0 && scale.is_finite() {
        Some(Unit::new_normalize(v / scale))
    } else {
        None
    }
}

/// Largest magnitude of an origin coordinate (metres), a limit (radians or metres) or a mimic
/// number: far beyond any robot, and far enough from overflow that every unit conversion and
/// composition stays finite.
pub(crate) const MAX_MAGNITUDE: f64 = 1e9;

/// Whether `c` may not appear in a name: a control character (C0, DEL, C1), or a bidirectional
/// formatting character (U+061C, U+200E, U+200F, U+202A..U+202E, U+2066..U+2069), which makes
/// a name display differently from what it is ("Trojan Source", CVE-2021-42574).
fn forbidden_in_name(c: char) -> bool {
    c.is_control()
        || matches!(c, '\u{061C}' | '\u{200E}' | '\u{200F}' | '\u{202A}'..='\u{202E}' | '\u{2066}'..='\u{2069}')
}

/// Refuses a link or joint name holding a control or bidirectional formatting character (see
/// [`UrdfError::ControlCharacterInName`]).
pub(crate) fn check_name(
    kind: &'static str,
    name: &str,
    line: Option<usize>,
) -> Result<(), UrdfError> {
    match name
        .chars()
        .enumerate()
        .find(|&(_, c)| forbidden_in_name(c))
    {
        Some((k, c)) => Err(UrdfError::ControlCharacterInName {
            kind,
            name: name.escape_debug().to_string(),
            code: format!("U+{:04X}", u32::from(c)),
            position: k + 1,
            line,
        }),
        None => Ok(()),
    }
}

/// Checks one joint's name, numbers, limits and mimic (its type and syntax were read by
/// [`crate::read`]); the mimic driver's existence and cycles are checked over the whole model.
pub(crate) fn check_joint(
    joint: &Joint,
    doc: &Doc,
    e: &Element,
    infinite_limits_allowed: bool,
) -> Result<(), UrdfError> {
    let line_of = |name: &str| {
        e.children
            .iter()
            .filter_map(|&c| doc.get(c))
            .find(|c| c.name == name)
            .map(|c| c.line)
            .or(Some(joint.line))
    };
    let (origin_line, axis_line, limit_line, mimic_line) = (
        line_of("origin"),
        line_of("axis"),
        line_of("limit"),
        line_of("mimic"),
    );
    check_name("joint", &joint.name, Some(joint.line))?;
    let name = || joint.name.clone();
    let kind = joint.kind.unwrap_or(JointType::Fixed);
    let finite = |what: &'static str, value: f64, line: Option<usize>| {
        if value.is_finite() {
            Ok(())
        } else {
            Err(UrdfError::NonFinite {
                joint: name(),
                what,
                value,
                line,
            })
        }
    };
    for (what, v, line) in [
        ("origin xyz", joint.origin.xyz, origin_line),
        ("origin rpy", joint.origin.rpy, origin_line),
        ("axis xyz", joint.axis, axis_line),
    ] {
        for x in v {
            finite(what, x, line)?;
        }
    }
    // Found by fuzzing: an origin of 1e306 m is finite, but its table printed in millimetres is
    // not. No robot needs lengths or limits beyond MAX_MAGNITUDE.
    let limits = joint.limit.map_or([None, None], |(lo, hi)| {
        [Some(("limit lower", lo)), Some(("limit upper", hi))]
    });
    let mimic = joint.mimic.as_ref().map_or([None, None], |m| {
        [
            Some(("mimic multiplier", m.multiplier)),
            Some(("mimic offset", m.offset)),
        ]
    });
    let magnitudes = joint
        .origin
        .xyz
        .iter()
        .map(|&v| ("origin xyz", v, origin_line))
        .chain(
            limits
                .into_iter()
                .flatten()
                .map(|(w, v)| (w, v, limit_line)),
        )
        .chain(mimic.into_iter().flatten().map(|(w, v)| (w, v, mimic_line)));
    for (what, v, line) in magnitudes {
        if v.is_finite() && v.abs() > MAX_MAGNITUDE {
            return Err(UrdfError::OutOfRange {
                joint: name(),
                what,
                value: v,
                line,
            });
        }
    }
    if kind.is_moving() && unit_axis(joint.axis).is_none() {
        return Err(UrdfError::ZeroAxis {
            joint: name(),
            axis: joint.axis,
            line: axis_line,
        });
    }
    let limited = match kind {
        JointType::Revolute => Some("revolute"),
        JointType::Prismatic => Some("prismatic"),
        _ => None,
    };
    if let Some(kind) = limited {
        let Some((lower, upper)) = joint.limit else {
            return Err(UrdfError::MissingLimit {
                joint: name(),
                kind,
                line: Some(joint.line),
            });
        };
        for (what, v) in [("limit lower", lower), ("limit upper", upper)] {
            if v.is_nan() || v.is_infinite() && !infinite_limits_allowed {
                finite(what, v, limit_line)?;
            }
        }
        if lower > upper {
            return Err(UrdfError::LimitsReversed {
                joint: name(),
                lower,
                upper,
                line: limit_line,
            });
        }
    }
    if let Some(m) = &joint.mimic {
        finite("mimic multiplier", m.multiplier, mimic_line)?;
        finite("mimic offset", m.offset, mimic_line)?;
        if m.joint == joint.name {
            return Err(UrdfError::MimicItself {
                joint: name(),
                line: mimic_line,
            });
        }
    }
    Ok(())
}
