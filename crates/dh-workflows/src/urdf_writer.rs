//! Writing a DH table as a URDF whose kinematics equal it, and proving what was written (read
//! back and extracted again): what `urdf-dh to-urdf` and `calibrate --out X.urdf` write.
//!
//! Every row `A_i(q) = pre_i · M(q) · post_i` with `M` a rotation about (or translation along)
//! z: standard rows have `pre = Rz(theta)`, `post = Tz(d) Tx(a) Rx(alpha) Ry(beta)`; modified
//! rows `pre = Rx(alpha) Tx(a) Ry(beta) Rz(theta)`, `post = Tz(d)` (`beta` the row's
//! Hayati-Mirmirani tilt, 0 in plain DH). Joint `i`'s origin is then
//! `post_(i-1) · pre_i` (the first one `base · pre_1`), its axis `0 0 1`, and a fixed joint
//! `post_n · tool` carries the tip link. Links sit on the joint axes, as vendor URDFs place them.
//!
//! A calibrated arm's parallel axes (a UR's joints 2, 3, 4) are milliradians off parallel, so
//! their common normals, where the DH frames sit, lie metres away along them (a UR3's factory
//! deltas: d of -6.29 m and +8.57 m). A link frame may slide along its own joint axis without
//! changing the kinematics (`Tz(s)` commutes with the joint's `Rz(q)` or `Tz(q)`): joint `i`'s
//! origin becomes `Tz(-s_(i-1)) · origin_i · Tz(s_i)` and the tip's `Tz(-s_n) · post_n · tool`.
//! [`joint_origins`] slides a joint's frame to the foot of the previous joint's origin on its
//! axis when its axis is within [`PARALLEL_RUN_ANGLE`] of the previous one and its DH origin
//! lies farther from that origin than the arm's size ([`arm_size`]): the written URDF's joint
//! origins stay on the arm, and its proof (read back, extracted) is the same.

use std::fmt::Write as _;

use anyhow::Result;
use dh_core::pose::{rot_x, rot_y, rot_z, to_xyz_rpy, trans_x, trans_z};
use dh_core::{Convention, DhRow, DhTable, JointKind};
use nalgebra::Isometry3;

/// Consecutive axes within this angle (radians) form a run of parallel axes whose common normals
/// may lie far along them: 50 mrad, four times the largest calibration tilt of a UR's parallel
/// axes seen (12 mrad).
pub const PARALLEL_RUN_ANGLE: f64 = 0.05;

/// The link frames of the rows at zero (in the base link frame): `L_i = L_(i-1) · origin_i`.
fn raw_origins(table: &DhTable) -> (Vec<Isometry3<f64>>, Isometry3<f64>) {
    let mut before = table.base;
    let mut origins = Vec::with_capacity(table.rows.len());
    for row in &table.rows {
        let (pre, post) = split(row, table.convention);
        origins.push(before * pre);
        before = post;
    }
    (origins, before * table.tool)
}

/// The link frames in the base link frame: the running products of the joint `origins`.
fn frames_of(origins: &[Isometry3<f64>]) -> Vec<Isometry3<f64>> {
    origins
        .iter()
        .scan(Isometry3::identity(), |pose, o| {
            *pose *= o;
            Some(*pose)
        })
        .collect()
}

/// For each row: whether its axis is within [`PARALLEL_RUN_ANGLE`] of the previous row's.
fn parallel_to_previous(frames: &[Isometry3<f64>]) -> Vec<bool> {
    let mut out = vec![false; frames.len()];
    for (k, pair) in frames.windows(2).enumerate() {
        if let ([a, b], Some(slot)) = (pair, out.get_mut(k + 1)) {
            let angle =
                (a.rotation * nalgebra::Vector3::z()).angle(&(b.rotation * nalgebra::Vector3::z()));
            *slot = angle < PARALLEL_RUN_ANGLE;
        }
    }
    out
}

/// The arm's size for placing link frames (metres, at least 1 mm): the sum of `|a|`, of `|d|`
/// outside runs of parallel axes, of `|sum of d|` over each run (only the sum of a run's `d`
/// is defined by its axes), and the base and tool offsets.
pub fn arm_size(table: &DhTable) -> f64 {
    let (origins, _) = raw_origins(table);
    let frames = frames_of(&origins);
    let parallel = parallel_to_previous(&frames);
    let in_run = |k: usize| {
        parallel.get(k).copied().unwrap_or(false) || parallel.get(k + 1).copied().unwrap_or(false)
    };
    let mut size = table.base.translation.vector.norm() + table.tool.translation.vector.norm();
    let mut run_sum: Option<f64> = None;
    for (k, row) in table.rows.iter().enumerate() {
        size += row.a.abs();
        let continues = parallel.get(k).copied().unwrap_or(false);
        if !continues {
            if let Some(sum) = run_sum.take() {
                size += sum.abs();
            }
        }
        if in_run(k) {
            run_sum = Some(run_sum.unwrap_or(0.0) + row.d);
        } else {
            size += row.d.abs();
        }
    }
    size += run_sum.map_or(0.0, f64::abs);
    size.max(1e-3)
}

/// The origins of the rows' joints (each in its parent link's frame) and of the tip's fixed
/// joint, link frames slid along their axes onto the arm (see the module's documentation).
pub fn joint_origins(table: &DhTable) -> (Vec<Isometry3<f64>>, Isometry3<f64>) {
    let (origins, tip) = raw_origins(table);
    let size = arm_size(table);
    let frames = frames_of(&origins);
    let parallel = parallel_to_previous(&frames);
    // Slides s_k of each link frame, and its placed origin (base link frame).
    let mut slides = vec![0.0; origins.len()];
    let mut placed_prev: Option<nalgebra::Vector3<f64>> = None;
    for (k, frame) in frames.iter().enumerate() {
        let p = frame.translation.vector;
        let z = frame.rotation * nalgebra::Vector3::z();
        let mut s = 0.0;
        if let (Some(prev), true) = (placed_prev, parallel.get(k).copied().unwrap_or(false)) {
            if (p - prev).norm() > size {
                s = -(p - prev).dot(&z);
            }
        }
        if let Some(slot) = slides.get_mut(k) {
            *slot = s;
        }
        placed_prev = Some(p + z * s);
    }
    let mut out = Vec::with_capacity(origins.len());
    let mut prev_slide = 0.0;
    for (o, &s) in origins.iter().zip(&slides) {
        out.push(trans_z(-prev_slide) * o * trans_z(s));
        prev_slide = s;
    }
    (out, trans_z(-prev_slide) * tip)
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
pub fn origin(p: &Isometry3<f64>) -> String {
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

/// Largest origin coordinate, limit or mimic number the URDF reader accepts (metres or radians;
/// `urdf-axes` refuses larger ones).
const URDF_MAX_MAGNITUDE: f64 = 1e9;

/// Refuses a table or names that would make [`urdf_of`] write a URDF its own reader refuses:
/// a robot, base or tip link name that is empty or holds a control or bidi character (a TAB
/// too); two links or two joints of one name (the links are `base_link`, `<row>_link` per row
/// and `tip_link`; the joints are the rows and `<tip_link>_joint`); an origin coordinate, limit
/// or mimic number beyond the reader's 1e9 (metres or radians); a table whose reach
/// ([`DhTable::size`]) passes that 1e9 m, whose own forward kinematics then round by more than
/// the proof's 1 mm (a base 1e27 m out and a first `a` of -1e27 m cancel in the URDF's origins,
/// not in the sheet's double-precision arithmetic).
///
/// # Errors
/// The first clash, bad name or value, naming the option or row that brings it.
pub fn check_urdf(table: &DhTable, robot: &str, base_link: &str, tip_link: &str) -> Result<()> {
    use crate::text::{escape, name_problem};
    let reach = table.size();
    if reach > URDF_MAX_MAGNITUDE || !reach.is_finite() {
        return Err(crate::error::hinted(
            format!(
                "expected a reach (the sum of |a|, |d|, prismatic travel and the base and tool offsets) within {URDF_MAX_MAGNITUDE:e} m, found {reach:e} m"
            ),
            "at that scale the sheet's own forward kinematics round by more than the 1 mm a written URDF is proved to; check the sheet's length_unit and its base and tool",
        ));
    }
    let (origins, tip) = joint_origins(table);
    for (row, joint_origin) in table.rows.iter().zip(&origins) {
        if row.kind == JointKind::Prismatic && row.limits.is_none() {
            return Err(crate::error::hinted(
                format!(
                    "joint '{}': expected lower and upper limits for a prismatic joint, found none",
                    escape(&row.name)
                ),
                "a URDF prismatic joint needs a <limit>: give the row lower and upper in the sheet",
            ));
        }
        let (xyz, _) = to_xyz_rpy(joint_origin);
        let limits = row.limits.map_or([0.0; 2], |l| [l.lower, l.upper]);
        let mimic = row
            .mimic
            .as_ref()
            .map_or([0.0; 2], |m| [m.multiplier, m.offset]);
        let worst = xyz
            .iter()
            .chain(&limits)
            .chain(&mimic)
            .fold(0.0f64, |m, v| m.max(v.abs()));
        if worst > URDF_MAX_MAGNITUDE || !worst.is_finite() {
            anyhow::bail!(
                "joint '{}': expected origin coordinates, limits and mimic numbers within {URDF_MAX_MAGNITUDE:e} m or rad (what a URDF may hold), found {worst:e}",
                escape(&row.name)
            );
        }
    }
    let (xyz, _) = to_xyz_rpy(&tip);
    if let Some(v) = xyz
        .iter()
        .find(|v| v.abs() > URDF_MAX_MAGNITUDE || !v.is_finite())
    {
        anyhow::bail!(
            "the tip link's origin: expected coordinates within {URDF_MAX_MAGNITUDE:e} m (what a URDF may hold), found {v:e}"
        );
    }
    for (what, name) in [
        ("robot name", robot),
        ("base link", base_link),
        ("tip link", tip_link),
    ] {
        if let Some(p) = name_problem(name) {
            anyhow::bail!("{what} {p}");
        }
    }
    let mut links: Vec<(String, String)> = vec![(base_link.to_string(), "the base link".into())];
    links.extend(table.rows.iter().map(|r| {
        (
            format!("{}_link", r.name),
            format!("the link of joint '{}'", escape(&r.name)),
        )
    }));
    links.push((tip_link.to_string(), "the tip link".into()));
    let mut joints: Vec<(String, String)> = table
        .rows
        .iter()
        .map(|r| (r.name.clone(), format!("joint '{}'", escape(&r.name))))
        .collect();
    joints.push((
        format!("{tip_link}_joint"),
        "the tip link's fixed joint".into(),
    ));
    for (kind, items) in [("link", &links), ("joint", &joints)] {
        for (k, (name, who)) in items.iter().enumerate() {
            if let Some((_, first)) = items[..k].iter().find(|(n, _)| n == name) {
                return Err(crate::error::hinted(
                    format!(
                        "the URDF would have two {kind}s named '{}': {first} and {who}",
                        escape(name)
                    ),
                    "choose other names with --base-link and --tip-link (the row links are <joint>_link, the tip's joint <tip>_joint)",
                ));
            }
        }
    }
    Ok(())
}

/// The URDF text of `table`.
pub fn urdf_of(table: &DhTable, name: &str, base_link: &str, tip_link: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "<?xml version=\"1.0\"?>");
    let _ = writeln!(s, "<!-- written by urdf-dh to-urdf from a {} DH sheet; the sheet has no dynamics, so effort and velocity limits are 0 -->", table.convention);
    let _ = writeln!(s, "<robot name=\"{}\">", xml(name));
    let _ = writeln!(s, "  <link name=\"{}\"/>", xml(base_link));
    let mut parent = base_link.to_string();
    let (origins, tip) = joint_origins(table);
    for (row, joint_origin) in table.rows.iter().zip(&origins) {
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
        let _ = writeln!(s, "    {}", origin(joint_origin));
        let _ = writeln!(s, "    <axis xyz=\"0 0 1\"/>");
        if let Some(l) = row.limits {
            let _ = writeln!(
                s,
                "    <limit lower=\"{}\" upper=\"{}\" effort=\"0\" velocity=\"0\"/>",
                l.lower, l.upper
            );
        }
        // A driver that is no row of the sheet (a gripper finger following its twin on another
        // branch) has no joint here to follow: the joint moves on its own (the sheet reader warns).
        if let Some(m) = row
            .mimic
            .as_ref()
            .filter(|m| table.rows.iter().any(|r| r.name == m.joint))
        {
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
    }
    let _ = writeln!(s, "  <link name=\"{}\"/>", xml(tip_link));
    let _ = writeln!(
        s,
        "  <joint name=\"{}_joint\" type=\"fixed\">",
        xml(tip_link)
    );
    let _ = writeln!(s, "    <parent link=\"{}\"/>", xml(&parent));
    let _ = writeln!(s, "    <child link=\"{}\"/>", xml(tip_link));
    let _ = writeln!(s, "    {}", origin(&tip));
    let _ = writeln!(s, "  </joint>");
    let _ = writeln!(s, "</robot>");
    s
}

/// What `urdf-dh to-urdf` writes for `sheet` (read from the file shown as `sheet_name`): the
/// URDF of its table ([`urdf_of`]), named `name` (default: the sheet's `robot`, else `robot`),
/// with the proof of what was written ([`prove_urdf`], `samples` joint-value samples drawn with
/// `seed`) appended as a comment after the root element, and that proof.
///
/// # Errors
/// Names the URDF cannot carry ([`check_urdf`]); a written URDF that does not read back.
pub fn write_proved(
    sheet: &crate::Sheet,
    sheet_name: &str,
    name: Option<&str>,
    base_link: &str,
    tip_link: &str,
    samples: usize,
    seed: u64,
) -> Result<(String, UrdfProof)> {
    let robot = name
        .map(str::to_string)
        .or(sheet.robot.clone().filter(|n| !n.trim().is_empty()))
        .unwrap_or_else(|| "robot".into());
    check_urdf(&sheet.table, &robot, base_link, tip_link)?;
    let mut text = urdf_of(&sheet.table, &robot, base_link, tip_link);
    let proof = prove_urdf(&text, &sheet.table, base_link, tip_link, samples, seed)?;
    let verdict = if proof.passed { "PASS" } else { "FAIL" };
    let _ = writeln!(
        text,
        "<!-- verification of this URDF as written (extracted again): {} joint samples (seed {seed}) against {sheet_name}: max position error {:.1e} m (bound {:.1e}), max orientation error {:.1e} rad (bound {:.1e}): {verdict} -->",
        proof.samples,
        proof.deviation.0,
        crate::units::bound_for_print(proof.bound.0),
        proof.deviation.1,
        crate::units::bound_for_print(proof.bound.1)
    );
    Ok((text, proof))
}

/// The check of a written URDF: it is read back and extracted, and that table (with the
/// written `<mimic>` couplings) is compared with the sheet by forward kinematics, within the
/// extraction's bound, the written precision (15 decimals) and the float error of the sheet's
/// own arithmetic.
#[derive(Clone, Debug, PartialEq)]
pub struct UrdfProof {
    /// Joint-value samples compared.
    pub samples: usize,
    /// Largest tip deviation (metres, radians).
    pub deviation: (f64, f64),
    /// Bound it must stay within (metres, radians).
    pub bound: (f64, f64),
    /// Whether it stayed within.
    pub passed: bool,
}

/// Proves `text` (a URDF written from `table`) by extracting it.
///
/// # Errors
/// A sample count outside [`crate::ranges::check_samples`]'s range, or a written URDF that
/// does not read back (a writer bug, or names the URDF reader refuses).
pub fn prove_urdf(
    text: &str,
    table: &DhTable,
    base_link: &str,
    tip_link: &str,
    samples: usize,
    seed: u64,
) -> Result<UrdfProof> {
    crate::ranges::check_samples(samples, table.rows.len())
        .map_err(|e| anyhow::anyhow!("samples: {e}"))?;
    let model = urdf_axes::UrdfModel::parse(text)
        .map_err(|e| anyhow::anyhow!("the written URDF does not read back: {e}"))?;
    let chain = model
        .chain(Some(base_link), Some(tip_link))
        .map_err(|e| anyhow::anyhow!("the written URDF does not read back: {e}"))?;
    let ex = dh_core::extract(
        chain.axes(),
        &chain.tip_pose(),
        dh_core::Tolerance::default(),
        table.convention,
    )
    .map_err(|e| anyhow::anyhow!("the written URDF does not extract: {e}"))?;
    let source = table.prepare();
    let dev = dh_core::compare_written(
        &ex.table,
        table,
        |q| source.fk(q).unwrap_or_else(|_| Isometry3::identity()),
        samples,
        seed,
    )
    .map_err(|e| anyhow::anyhow!("the written URDF has other joints than the sheet: {e}"))?;
    let n = table.rows.len() as f64 + 1.0;
    let rounding = dh_core::written_bound(&ex.table, dh_core::Precision::rounded(0.5e-15, 0.5e-15));
    let bound = (
        (ex.bound.position + rounding.position + 16.0 * n * f64::EPSILON * table.size())
            .min(dh_core::Bound::MAX_POSITION),
        (ex.bound.orientation + rounding.orientation + 16.0 * n * f64::EPSILON)
            .min(dh_core::Bound::MAX_ORIENTATION),
    );
    let kinds_agree = ex
        .table
        .rows
        .iter()
        .zip(&table.rows)
        .all(|(w, s)| w.kind == s.kind && w.name == s.name);
    Ok(UrdfProof {
        samples: dev.samples,
        deviation: (dev.max_position_error, dev.max_orientation_error),
        bound,
        passed: kinds_agree
            && dev.max_position_error <= bound.0
            && dev.max_orientation_error <= bound.1,
    })
}
