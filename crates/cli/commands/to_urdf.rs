//! `urdf-dh to-urdf`: a URDF whose kinematics equal a DH sheet.
//!
//! Every row `A_i(q) = pre_i · M(q) · post_i` with `M` a rotation about (or translation along)
//! z: standard rows have `pre = Rz(theta)`, `post = Tz(d) Tx(a) Rx(alpha) Ry(beta)`; modified
//! rows `pre = Rx(alpha) Tx(a) Ry(beta) Rz(theta)`, `post = Tz(d)` (`beta` the row's
//! Hayati-Mirmirani tilt, 0 in plain DH). Joint `i`'s origin is then
//! `post_(i-1) · pre_i` (the first one `base · pre_1`), its axis `0 0 1`, and a fixed joint
//! `post_n · tool` carries the tip link. Links sit on the joint axes, as vendor URDFs place them.

use std::fmt::Write as _;
use std::io::Write;

use anyhow::Result;
use dh_core::pose::{rot_x, rot_y, rot_z, to_xyz_rpy, trans_x, trans_z};
use dh_core::{Convention, DhRow, DhTable, JointKind};
use nalgebra::Isometry3;

use crate::error::Outcome;
use crate::input::{display_name, read_text};
use crate::sheet::Sheet;

/// Everything `to-urdf` needs.
#[derive(Clone, Debug)]
pub struct ToUrdfArgs {
    /// Sheet path or `-`.
    pub sheet: String,
    /// Robot name (default: the sheet's `robot`, else `robot`).
    pub name: Option<String>,
    /// Base link name.
    pub base_link: String,
    /// Tip link name.
    pub tip_link: String,
}

fn split(row: &DhRow, convention: Convention) -> (Isometry3<f64>, Isometry3<f64>) {
    match convention {
        Convention::Standard => (
            rot_z(row.theta),
            trans_z(row.d) * trans_x(row.a) * rot_x(row.alpha) * rot_y(row.beta),
        ),
        Convention::Modified => (
            rot_x(row.alpha) * trans_x(row.a) * rot_y(row.beta) * rot_z(row.theta),
            trans_z(row.d),
        ),
    }
}

/// Escapes text for an XML attribute.
fn xml(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('"', "&quot;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// A URDF `<origin>` element of `p`, values rounded to 1e-15.
pub(crate) fn origin(p: &Isometry3<f64>) -> String {
    let (xyz, rpy) = to_xyz_rpy(p);
    let n = |v: f64| {
        let v = crate::units::round_decimals(crate::units::clean(v), 15);
        if v == 0.0 {
            "0".to_string()
        } else {
            format!("{v}")
        }
    };
    format!(
        "<origin xyz=\"{} {} {}\" rpy=\"{} {} {}\"/>",
        n(xyz[0]),
        n(xyz[1]),
        n(xyz[2]),
        n(rpy[0]),
        n(rpy[1]),
        n(rpy[2])
    )
}

/// The URDF text of `table`.
pub fn urdf_of(table: &DhTable, name: &str, base_link: &str, tip_link: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "<?xml version=\"1.0\"?>");
    let _ = writeln!(s, "<!-- written by urdf-dh to-urdf from a {} DH sheet; the sheet has no dynamics, so effort and velocity limits are 0 -->", table.convention);
    let _ = writeln!(s, "<robot name=\"{}\">", xml(name));
    let _ = writeln!(s, "  <link name=\"{}\"/>", xml(base_link));
    let mut parent = base_link.to_string();
    let mut before = table.base;
    for (i, row) in table.rows.iter().enumerate() {
        let (pre, post) = split(row, table.convention);
        let child = format!("{}_link", row.name);
        let kind = match (row.kind, row.limits) {
            (JointKind::Prismatic, _) => "prismatic",
            (JointKind::Revolute, Some(_)) => "revolute",
            (JointKind::Revolute, None) => "continuous",
        };
        let _ = writeln!(s, "  <link name=\"{}\"/>", xml(&child));
        let _ = writeln!(s, "  <joint name=\"{}\" type=\"{kind}\">", xml(&row.name));
        let _ = writeln!(s, "    <parent link=\"{}\"/>", xml(&parent));
        let _ = writeln!(s, "    <child link=\"{}\"/>", xml(&child));
        let _ = writeln!(s, "    {}", origin(&(before * pre)));
        let _ = writeln!(s, "    <axis xyz=\"0 0 1\"/>");
        if let Some(l) = row.limits {
            let _ = writeln!(
                s,
                "    <limit lower=\"{}\" upper=\"{}\" effort=\"0\" velocity=\"0\"/>",
                l.lower, l.upper
            );
        }
        if let Some(m) = &row.mimic {
            let _ = writeln!(
                s,
                "    <mimic joint=\"{}\" multiplier=\"{}\" offset=\"{}\"/>",
                xml(&m.joint),
                m.multiplier,
                m.offset
            );
        }
        let _ = writeln!(s, "  </joint>");
        parent = child;
        before = post;
        let _ = i;
    }
    let _ = writeln!(s, "  <link name=\"{}\"/>", xml(tip_link));
    let _ = writeln!(
        s,
        "  <joint name=\"{}_joint\" type=\"fixed\">",
        xml(tip_link)
    );
    let _ = writeln!(s, "    <parent link=\"{}\"/>", xml(&parent));
    let _ = writeln!(s, "    <child link=\"{}\"/>", xml(tip_link));
    let _ = writeln!(s, "    {}", origin(&(before * table.tool)));
    let _ = writeln!(s, "  </joint>");
    let _ = writeln!(s, "</robot>");
    s
}

/// Runs `to-urdf`.
///
/// # Errors
/// Unreadable or invalid sheet.
pub fn to_urdf(args: &ToUrdfArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    let name = display_name(&args.sheet);
    let sheet = Sheet::parse(&read_text(&args.sheet)?, &name)?;
    for w in &sheet.warnings {
        writeln!(err, "urdf-dh: warning: {w}")?;
    }
    if let Some(w) = sheet.effects_warning(&name, "a URDF holds the DH kinematics alone") {
        writeln!(err, "urdf-dh: warning: {w}")?;
    }
    let robot = args
        .name
        .clone()
        .or(sheet.robot.clone())
        .unwrap_or_else(|| "robot".into());
    out.write_all(urdf_of(&sheet.table, &robot, &args.base_link, &args.tip_link).as_bytes())?;
    Ok(Outcome::Pass)
}
