//! MJCF (MuJoCo XML) robot models, read into the same [`UrdfModel`] as a URDF, so that chains,
//! default tips, mimics, warnings and the forward kinematics oracle work unchanged.
//!
//! # Names and values
//! Links are body names (the world body is `world`); rows are joint names; a joint's value is
//! MuJoCo's `qpos` (its `ref` is folded into the joint's origin). Hinge and slide joints are
//! revolute (continuous when not limited) and prismatic joints; `ball` and `free` joints are
//! kept, and refused on a chosen chain. A free joint at the root is fine: when the world holds
//! one body on a free joint with joints below it, chains start at that body by default. An `<equality><joint>` coupling with a linear `polycoef` is a mimic.
//!
//! # Frames
//! MuJoCo's `mj_kinematics` places a body at `F = F_parent · pose(body)` and then applies its
//! joints in document order, each on the right, in the body frame as moved so far: a hinge with
//! anchor `p` and unit axis `a` multiplies by `T(p) · R(a, q − ref) · T(−p)`, a slide by
//! `T(a (q − ref))`. A URDF joint rotates about an axis through its frame's origin, so a hinge
//! becomes the joint frame `T(p) · R(a, −ref)` (`R(a, −ref)` commutes with `R(a, q)`), and the
//! `T(−p)` after it goes into the next joint's origin, or into a fixed joint `anchor:BODY` to
//! the body's own link after the last one. A body with several joints becomes a chain of
//! zero-length links `BODY:JOINT`; a body without joints is welded to its parent by a fixed
//! joint `weld:BODY`. Rotations are stored as URDF roll-pitch-yaw
//! ([`dh_core::pose::to_xyz_rpy`], exact to 1e-15 rad at gimbal lock too: see the tests).
//!
//! # What is read
//! `<compiler angle eulerseq autolimits>`, `<default>` classes (nesting, `class`,
//! `childclass`), `<include>` (relative to the main file's folder), `<worldbody>`, `<body>`,
//! `<frame>`, `<joint>`/`<freejoint>` (`type pos axis ref range limited`), body `pos` with
//! `quat`/`axisangle`/`euler`/`xyaxes`/`zaxis`, `<inertial pos mass>` and `<equality>`. What
//! defines the kinematics is strict (an [`MjcfError`] naming the element and its line, where
//! MuJoCo's compiler would refuse the model too); unknown elements inside bodies are warnings;
//! geoms, sites, assets, actuators and the like are skipped.

mod build;
mod defaults;
mod error;
mod orient;
mod xml;

pub use error::{MjcfError, Place};
pub use xml::is_mjcf;

use std::path::Path;

use crate::{UrdfError, UrdfModel, MAX_URDF_BYTES};

/// Elements of `<mujoco>` that do not change the kinematic tree (beyond `<compiler>`,
/// `<default>`, `<worldbody>` and `<equality>`, which are read).
const SKIPPED: [&str; 13] = [
    "option",
    "size",
    "visual",
    "statistic",
    "custom",
    "extension",
    "asset",
    "contact",
    "deformable",
    "tendon",
    "actuator",
    "sensor",
    "keyframe",
];

/// Reads an MJCF document given as bytes (UTF-8); `dir` is the folder of its file, against which
/// `<include file>` is resolved (`None` for standard input or a string: then an `<include>` is
/// refused).
///
/// # Errors
/// As [`read`]; [`UrdfError::NotUtf8`] and [`UrdfError::TooLarge`] (as [`MjcfError::Model`]).
pub fn from_bytes(bytes: &[u8], dir: Option<&Path>) -> Result<UrdfModel, MjcfError> {
    from_bytes_with(bytes, dir, None)
}

/// Files by path, their contents as bytes: an in-memory folder tree (the files a person dropped
/// on the web page, where there is no disk).
pub type MemoryFiles = std::collections::BTreeMap<std::path::PathBuf, Vec<u8>>;

/// [`from_bytes`] with `<include file>` read from `files` (when given) instead of the disk:
/// the included path is `dir` joined with the file's name, `.` and `..` applied.
///
/// # Errors
/// As [`from_bytes`]; an include not among `files`.
pub fn from_bytes_with(
    bytes: &[u8],
    dir: Option<&Path>,
    files: Option<&MemoryFiles>,
) -> Result<UrdfModel, MjcfError> {
    if bytes.len() > MAX_URDF_BYTES {
        return Err(UrdfError::TooLarge {
            size: Some(bytes.len()),
            limit: MAX_URDF_BYTES,
        }
        .into());
    }
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let offset = e.valid_up_to();
        let line = bytes
            .get(..offset)
            .map_or(0, |b| b.iter().filter(|&&c| c == b'\n').count())
            + 1;
        UrdfError::NotUtf8 { offset, line }
    })?;
    read_with(text, dir, files)
}

/// Reads an MJCF document (see the module docs for what is read).
///
/// # Errors
/// - [`MjcfError::Xml`]: not well-formed XML, a root other than `<mujoco>`;
/// - [`MjcfError::Invalid`]: a malformed number or orientation, an unknown class, an
///   `<include>` that cannot be followed, a zero axis, bad limits, a free joint below the world's
///   children, repeated body or joint names, an `<equality>` naming an unknown joint, `<attach>`
///   or `<replicate>`;
/// - [`MjcfError::Model`]: a fault of the converted model's own validation.
pub fn read(text: &str, dir: Option<&Path>) -> Result<UrdfModel, MjcfError> {
    read_with(text, dir, None)
}

fn read_with(
    text: &str,
    dir: Option<&Path>,
    files: Option<&MemoryFiles>,
) -> Result<UrdfModel, MjcfError> {
    if text.len() > MAX_URDF_BYTES {
        return Err(UrdfError::TooLarge {
            size: Some(text.len()),
            limit: MAX_URDF_BYTES,
        }
        .into());
    }
    let root = xml::read_document(text, dir, files)?;
    let mut compiler = orient::Compiler::default();
    for c in root.children.iter().filter(|c| c.name == "compiler") {
        compiler.apply(c)?;
    }
    let classes = defaults::Classes::read(&root)?;
    let name = root.attr("model").unwrap_or("").to_owned();
    let mut builder = build::Builder::new(&classes, compiler, name);
    let worldbodies: Vec<&xml::Node> = root
        .children
        .iter()
        .filter(|c| c.name == "worldbody")
        .collect();
    let line = worldbodies.first().map_or(root.line, |w| w.line);
    builder.world(&worldbodies, line)?;
    for c in &root.children {
        match c.name.as_str() {
            "equality" => builder.equality(c)?,
            "compiler" | "default" | "worldbody" => {}
            name if SKIPPED.contains(&name) => {}
            other => {
                let message = format!("unknown element <{other}> in <mujoco>; ignored");
                builder.warn(c, message);
            }
        }
    }
    let free_bodies = std::mem::take(&mut builder.free_bodies);
    let mut model = UrdfModel::from_robot(builder.robot)?;
    model.format_name = "MJCF";
    if let [body] = free_bodies.as_slice() {
        model.set_default_base_if_moving_below(body);
    }
    Ok(model)
}
