//! The calibrated model as a minimal edit of the user's own URDF: the same document text with
//! only the chain's joint `<origin>` elements (and the tool's fixed joint) rewritten, so that
//! meshes, collisions, gazebo and transmission elements stay byte for byte as they were.
//!
//! Each moving joint `i` keeps its axis. With `D_i` the DH frame in which the joint's motion is
//! `Rz(q)` (or `Tz(q)`) at the zero pose and `J_i` the URDF joint frame, the nominal
//! `K_i = D_i⁻¹ J_i` maps the URDF axis onto DH z (extraction puts DH z on the URDF axis line),
//! so `J_i · R(axis, q) = D_i · Rz(q) · K_i`. The calibrated joint frame is `J_i' = D_i' K_i`,
//! and each origin is the zero-pose transform from the previous joint frame (through the
//! unchanged fixed joints between) to the new one; the last fixed joint before the tip takes
//! the calibrated tool. Then URDF FK equals the calibrated table's at every joint value.
//! Where `D_i'` lies farther than the arm's size from the nominal joint frame (nearly parallel
//! axes of a factory calibration), it first slides along its own axis to the foot of the
//! nominal origin (`D_i' Tz(s)`, which commutes with the joint's motion).

use anyhow::{bail, Context, Result};
use dh_core::pose::{pose_error, rot_z, trans_z};
use dh_core::{Convention, DhTable};
use nalgebra::Isometry3;
use urdf_axes::UrdfModel;

use crate::urdf_writer::origin;

/// Largest pose difference (metres or radians) accepted where the edit cannot move a frame:
/// a tip link without a fixed joint of its own must already sit where the calibrated tool says.
const TIP_TOLERANCE: f64 = 1e-9;

/// Zero-pose frames `D_i` (base link frame) in which row `i`'s joint motion is `Rz(q)` or
/// `Tz(q)`: standard `frame_(i-1) · Rz(theta_i) Tz(d_i)` (the motion commutes with `Tz(d)`),
/// modified `frame_i`.
fn motion_frames(table: &DhTable) -> Result<Vec<Isometry3<f64>>> {
    let frames = table.frames(&vec![0.0; table.rows.len()])?;
    Ok(table
        .rows
        .iter()
        .enumerate()
        .map(|(i, r)| match table.convention {
            Convention::Standard => frames[i] * rot_z(r.theta) * trans_z(r.d),
            Convention::Modified => frames[i + 1],
        })
        .collect())
}

/// One joint on the path from the base link to the tip link.
struct PathJoint {
    name: String,
    moving: bool,
    origin: Isometry3<f64>,
}

/// `text` (the URDF the nominal table was extracted from, chain `base` -> `tip`) with the joint
/// origins that make its kinematics `calibrated`'s.
///
/// # Errors
/// The URDF does not parse, its chain's moving joints are not the table's rows, or the tool
/// changed while the tip link has no fixed joint to carry it.
pub fn minimal_edit(
    text: &str,
    nominal: &DhTable,
    calibrated: &DhTable,
    base: &str,
    tip: &str,
) -> Result<String> {
    let model = UrdfModel::parse(text).context("re-reading the model URDF")?;
    let mut path = Vec::new();
    let mut link = tip.to_string();
    while link != base {
        let Some((name, parent, origin)) = model.parent_joint(&link) else {
            bail!("link '{link}' has no parent joint on the way to '{base}'");
        };
        path.push(PathJoint {
            name: name.to_string(),
            // The chain's moving joints are the table's rows (mimic joints included).
            moving: nominal.rows.iter().any(|r| r.name == name),
            origin,
        });
        link = parent.to_string();
    }
    path.reverse();
    let moving: Vec<&str> = path
        .iter()
        .filter(|p| p.moving)
        .map(|p| p.name.as_str())
        .collect();
    let rows: Vec<&str> = nominal.rows.iter().map(|r| r.name.as_str()).collect();
    if moving != rows || calibrated.rows.len() != rows.len() {
        bail!(
            "the URDF chain's moving joints ({}) are not the model's rows ({})",
            moving.join(", "),
            rows.join(", ")
        );
    }
    let (d_nominal, d_calibrated) = (motion_frames(nominal)?, motion_frames(calibrated)?);
    // Nominal URDF joint frames at the zero pose, and the new ones.
    // A calibrated frame far from the nominal one (the common normal of nearly parallel axes,
    // metres out: see `urdf_writer`) slides along its own axis to the foot of the nominal joint
    // origin on it; `Tz(s)` commutes with the joint's motion, so the kinematics stay.
    let far = crate::urdf_writer::arm_size(nominal);
    let mut t = Isometry3::identity();
    let mut new_frames = Vec::new();
    let mut k = 0;
    for p in &path {
        t *= p.origin;
        if p.moving {
            let fixed = d_nominal[k].inverse() * t;
            let placed = d_calibrated[k] * fixed;
            let gap = t.translation.vector - placed.translation.vector;
            let slide = if gap.norm() > far {
                gap.dot(&(d_calibrated[k].rotation * nalgebra::Vector3::z()))
            } else {
                0.0
            };
            new_frames.push(d_calibrated[k] * trans_z(slide) * fixed);
            k += 1;
        }
    }
    let tool = calibrated.fk(&vec![0.0; rows.len()])?;
    let last_moving = path.iter().rposition(|p| p.moving).unwrap_or(0);
    let mut edits: Vec<(String, Isometry3<f64>)> = Vec::new();
    let mut t = Isometry3::identity();
    let mut k = 0;
    for (i, p) in path.iter().enumerate() {
        if p.moving {
            edits.push((p.name.clone(), t.inverse() * new_frames[k]));
            t = new_frames[k];
            k += 1;
        } else if i + 1 == path.len() && i > last_moving {
            edits.push((p.name.clone(), t.inverse() * tool));
            t = tool;
        } else {
            t *= p.origin;
        }
    }
    let (dp, dr) = pose_error(&t, &tool);
    if dp > TIP_TOLERANCE || dr > TIP_TOLERANCE {
        bail!(
            "the calibrated tool moves the tip link by {dp:.1e} m, {dr:.1e} rad, and '{tip}' has no fixed joint after the last moving joint to carry it"
        );
    }
    let mut out = text.to_string();
    for (name, pose) in &edits {
        out = replace_origin(&out, name, &origin(pose))
            .with_context(|| format!("joint '{name}': rewriting its <origin>"))?;
    }
    Ok(out)
}

/// `text` with the `<origin .../>` of joint `name` replaced by `element` (inserted after the
/// joint's opening tag when it has none).
fn replace_origin(text: &str, name: &str, element: &str) -> Result<String> {
    let mut from = 0;
    while let Some(k) = text[from..].find("<joint") {
        let start = from + k;
        let Some(open_len) = text[start..].find('>') else {
            break;
        };
        let open_end = start + open_len + 1;
        let tag = &text[start..open_end];
        let named =
            tag.contains(&format!("name=\"{name}\"")) || tag.contains(&format!("name='{name}'"));
        if !named {
            from = open_end;
            continue;
        }
        let close = text[open_end..]
            .find("</joint>")
            .map(|c| open_end + c)
            .context("expected a </joint>")?;
        let body = &text[open_end..close];
        return Ok(match body.find("<origin") {
            Some(o) => {
                let o = open_end + o;
                let end = text[o..]
                    .find("/>")
                    .map(|e| o + e + 2)
                    .context("expected a self-closing <origin .../>")?;
                format!("{}{element}{}", &text[..o], &text[end..])
            }
            None => format!("{}\n    {element}{}", &text[..open_end], &text[open_end..]),
        });
    }
    bail!("no <joint name=\"{name}\"> in the text")
}
