//! Output formats of a DH sheet: a readable table, YAML, JSON, CSV and Markdown.

use std::fmt::Write as _;

use anyhow::Result;

use crate::sheet::{ConventionDoc, JointDoc, JointType, SheetDoc};

/// Output format of `extract` and `convert`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Default)]
pub enum Format {
    /// An aligned table with units, pairs, warnings and the verification line.
    #[default]
    Text,
    /// The sheet format, YAML.
    Yaml,
    /// The sheet format, JSON (same keys as YAML).
    Json,
    /// One row per joint, with `#` comment lines for units, base and tool.
    Csv,
    /// A Markdown table for documents.
    Markdown,
}

/// Renders `doc` in `format`.
///
/// # Errors
/// Serialisation failures (not expected for finite numbers).
pub fn render_sheet(doc: &SheetDoc, format: Format) -> Result<String> {
    Ok(match format {
        Format::Yaml => serde_yaml::to_string(doc)?,
        Format::Json => serde_json::to_string_pretty(doc)? + "\n",
        Format::Text => text(doc),
        Format::Csv => csv(doc),
        Format::Markdown => markdown(doc),
    })
}

fn decimals(unit: &str) -> usize {
    match unit {
        "m" => 6,
        "mm" => 3,
        "deg" => 4,
        _ => 6,
    }
}

/// Formats `v` with the decimals its unit deserves, `-0` printed as `0`.
fn num(v: f64, unit: &str) -> String {
    let s = format!("{:.*}", decimals(unit), v);
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        s.trim_start_matches('-').to_string()
    } else {
        s
    }
}

fn limit_unit<'a>(doc: &'a SheetDoc, j: &JointDoc) -> &'a str {
    match j.kind {
        JointType::Revolute => doc.angle_unit.symbol(),
        JointType::Prismatic => doc.length_unit.symbol(),
    }
}

fn coupling(doc: &SheetDoc, j: &JointDoc) -> String {
    j.mimic
        .as_ref()
        .map(|m| {
            format!(
                "= {} * {} {} {}",
                m.multiplier,
                m.joint,
                if m.offset < 0.0 { "-" } else { "+" },
                num(m.offset.abs(), limit_unit(doc, j))
            )
        })
        .unwrap_or_default()
}

fn header_line(doc: &SheetDoc) -> String {
    let conv = match doc.convention {
        ConventionDoc::Standard => {
            "standard DH: A_i = Rz(theta_i + q_i) Tz(d_i) Tx(a_i) Rx(alpha_i)"
        }
        ConventionDoc::Modified => {
            "modified DH (Craig): A_i = Rx(alpha_{i-1}) Tx(a_{i-1}) Rz(theta_i + q_i) Tz(d_i)"
        }
    };
    let chain = match (&doc.base_link, &doc.tip_link) {
        (Some(b), Some(t)) => format!(" ({b} -> {t})"),
        _ => String::new(),
    };
    format!("{}{chain}, {conv}", doc.robot.as_deref().unwrap_or("robot"))
}

fn text(doc: &SheetDoc) -> String {
    let (l, a) = (doc.length_unit.symbol(), doc.angle_unit.symbol());
    let mut s = String::new();
    let _ = writeln!(s, "{}", header_line(doc));
    let name_w = doc
        .joints
        .iter()
        .map(|j| j.name.len())
        .max()
        .unwrap_or(5)
        .max(5);
    let headers = [
        format!("theta [{a}]"),
        format!("d [{l}]"),
        format!("a [{l}]"),
        format!("alpha [{a}]"),
        "lower".to_string(),
        "upper".to_string(),
    ];
    let _ = write!(s, "{:>3}  {:<name_w$}  {:<9}", "#", "joint", "type");
    for h in &headers {
        let _ = write!(s, "  {h:>13}");
    }
    let _ = writeln!(s, "  coupling");
    for (i, j) in doc.joints.iter().enumerate() {
        let lu = limit_unit(doc, j);
        let kind = match j.kind {
            JointType::Revolute => "revolute",
            JointType::Prismatic => "prismatic",
        };
        let lim =
            |v: Option<f64>| v.map_or_else(|| "-".to_string(), |v| format!("{} {lu}", num(v, lu)));
        let cells = [
            num(j.theta, a),
            num(j.d, l),
            num(j.a, l),
            num(j.alpha, a),
            lim(j.lower),
            lim(j.upper),
        ];
        let _ = write!(s, "{:>3}  {:<name_w$}  {:<9}", i + 1, j.name, kind);
        for c in &cells {
            let _ = write!(s, "  {c:>13}");
        }
        let _ = writeln!(s, "  {}", coupling(doc, j)).map(|_| ());
    }
    // Trailing spaces from an empty coupling column would make diffs noisy.
    s = s.lines().map(str::trim_end).collect::<Vec<_>>().join("\n") + "\n";
    let pose = |name: &str, what: &str, p: &Option<crate::sheet::PoseDoc>| match p {
        Some(p) => format!(
            "{name:<5} {what}: xyz [{l}] {} {} {}   rpy [{a}] {} {} {}\n",
            num(p.xyz[0], l),
            num(p.xyz[1], l),
            num(p.xyz[2], l),
            num(p.rpy[0], a),
            num(p.rpy[1], a),
            num(p.rpy[2], a)
        ),
        None => format!("{name:<5} {what}: not given\n"),
    };
    s += &tilts_and_effects(doc, "");
    let n = doc.joints.len();
    let base_link = doc.base_link.as_deref().unwrap_or("base link");
    let tip_link = doc.tip_link.as_deref().unwrap_or("tip link");
    s += &pose("base", &format!("DH frame 0 in {base_link}"), &doc.base);
    s += &pose("tool", &format!("{tip_link} in DH frame {n}"), &doc.tool);
    if let Some(pairs) = &doc.pairs {
        let _ = writeln!(s, "axis pairs:");
        let w = pairs
            .iter()
            .map(|p| p.joints[0].len() + p.joints[1].len() + 4)
            .max()
            .unwrap_or(0);
        for p in pairs {
            let names = format!("{} -> {}", p.joints[0], p.joints[1]);
            let _ = writeln!(
                s,
                "  {names:<w$}  {:<21} angle {:>10} {a}  distance {:>10} {l}",
                p.relation,
                num(p.angle, a),
                num(p.distance, l)
            );
        }
    }
    if let Some(warnings) = &doc.warnings {
        if warnings.is_empty() {
            let _ = writeln!(s, "warnings: none");
        } else {
            let _ = writeln!(s, "warnings:");
            for w in warnings {
                let _ = writeln!(s, "  - {w}");
            }
        }
    }
    if let Some(t) = &doc.tolerances {
        let _ = writeln!(
            s,
            "tolerances: linear {:e} m, angular {:e} rad",
            t.linear, t.angular
        );
    }
    if let Some(v) = &doc.verification {
        let _ = writeln!(
            s,
            "verification: {} joint samples (seed {}) against the URDF: max position error {:.1e} m (bound {:.1e}), max orientation error {:.1e} rad (bound {:.1e}): {}",
            v.samples,
            v.seed,
            v.max_position_error,
            v.position_bound,
            v.max_orientation_error,
            v.orientation_bound,
            if v.passed { "PASS" } else { "FAIL" }
        );
    }
    s
}

/// The rows' Hayati-Mirmirani tilts and the sheet's effects, one line each with `prefix`
/// (empty when the sheet has neither).
fn tilts_and_effects(doc: &SheetDoc, prefix: &str) -> String {
    let a = doc.angle_unit.symbol();
    let mut s = String::new();
    let tilts: Vec<String> = doc
        .joints
        .iter()
        .filter_map(|j| j.beta.map(|b| format!("{} {} {a}", j.name, num(b, a))))
        .collect();
    if !tilts.is_empty() {
        let _ = writeln!(
            s,
            "{prefix}beta (Hayati-Mirmirani tilt, Ry(beta) right after the row's Rx(alpha)): {}",
            tilts.join(", ")
        );
    }
    for e in doc.effects.iter().flatten() {
        let _ = writeln!(
            s,
            "{prefix}effect {} = {:e} {}{}",
            e.name,
            e.value,
            e.unit,
            e.std_error
                .map(|u| format!(" +- {u:.1e}"))
                .unwrap_or_default()
        );
    }
    s
}

fn csv(doc: &SheetDoc) -> String {
    let (l, a) = (doc.length_unit.symbol(), doc.angle_unit.symbol());
    let mut s = String::new();
    let _ = writeln!(s, "# {}", header_line(doc));
    let _ = writeln!(s, "# length_unit {l}, angle_unit {a}");
    for (name, p) in [("base", &doc.base), ("tool", &doc.tool)] {
        if let Some(p) = p {
            let _ = writeln!(
                s,
                "# {name} xyz {} {} {} rpy {} {} {}",
                p.xyz[0], p.xyz[1], p.xyz[2], p.rpy[0], p.rpy[1], p.rpy[2]
            );
        }
    }
    s += &tilts_and_effects(doc, "# ");
    let _ = writeln!(
        s,
        "joint,type,a,alpha,d,theta,lower,upper,mimic_joint,mimic_multiplier,mimic_offset"
    );
    for j in &doc.joints {
        let opt = |v: Option<f64>| v.map(|v| v.to_string()).unwrap_or_default();
        let kind = match j.kind {
            JointType::Revolute => "revolute",
            JointType::Prismatic => "prismatic",
        };
        let (mj, mm, mo) = match &j.mimic {
            Some(m) => (
                m.joint.clone(),
                m.multiplier.to_string(),
                m.offset.to_string(),
            ),
            None => Default::default(),
        };
        let _ = writeln!(
            s,
            "{},{kind},{},{},{},{},{},{},{mj},{mm},{mo}",
            j.name,
            j.a,
            j.alpha,
            j.d,
            j.theta,
            opt(j.lower),
            opt(j.upper)
        );
    }
    s
}

fn markdown(doc: &SheetDoc) -> String {
    let (l, a) = (doc.length_unit.symbol(), doc.angle_unit.symbol());
    let mut s = String::new();
    let _ = writeln!(s, "**{}**\n", header_line(doc));
    let _ = writeln!(
        s,
        "| # | joint | type | theta [{a}] | d [{l}] | a [{l}] | alpha [{a}] | lower | upper |"
    );
    let _ = writeln!(s, "|---|---|---|---:|---:|---:|---:|---:|---:|");
    for (i, j) in doc.joints.iter().enumerate() {
        let lu = limit_unit(doc, j);
        let lim =
            |v: Option<f64>| v.map_or_else(|| "-".to_string(), |v| format!("{} {lu}", num(v, lu)));
        let kind = match j.kind {
            JointType::Revolute => "revolute",
            JointType::Prismatic => "prismatic",
        };
        let _ = writeln!(
            s,
            "| {} | {} | {kind} | {} | {} | {} | {} | {} | {} |",
            i + 1,
            j.name,
            num(j.theta, a),
            num(j.d, l),
            num(j.a, l),
            num(j.alpha, a),
            lim(j.lower),
            lim(j.upper)
        );
    }
    for (name, p) in [("base", &doc.base), ("tool", &doc.tool)] {
        if let Some(p) = p {
            let _ = writeln!(
                s,
                "\n{name}: xyz [{l}] {} {} {}, rpy [{a}] {} {} {}",
                num(p.xyz[0], l),
                num(p.xyz[1], l),
                num(p.xyz[2], l),
                num(p.rpy[0], a),
                num(p.rpy[1], a),
                num(p.rpy[2], a)
            );
        }
    }
    for line in tilts_and_effects(doc, "").lines() {
        let _ = writeln!(s, "\n{line}");
    }
    if let Some(v) = &doc.verification {
        let _ = writeln!(
            s,
            "\nverification: {} samples, max position error {:.1e} m, max orientation error {:.1e} rad: {}",
            v.samples,
            v.max_position_error,
            v.max_orientation_error,
            if v.passed { "PASS" } else { "FAIL" }
        );
    }
    s
}
