//! Writing a DH sheet: a readable table, YAML, JSON, CSV and Markdown (lengths and angles in
//! the sheet's own units). [`crate::read_back`] reads every one of them back.
//!
//! Every name the text, CSV and Markdown tables print goes through [`escape`], and JSON through
//! [`crate::text::json_pretty`] (control and bidi characters as `\uXXXX`): the readers refuse
//! such names, so a sheet read from a file prints unchanged, and a name that slipped past a
//! reader still cannot drive the terminal the table is printed on.

use std::fmt::Write as _;

use crate::error::Result;
use crate::text::escape;

use crate::sheet::{ConventionDoc, JointDoc, JointType, SheetDoc};

/// Output format of `extract` and `convert`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
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
    /// The product-of-exponentials form, JSON: each joint's screw axis in the base frame at
    /// zero and the tip's home pose (extract only)
    Poe,
}

/// Renders `doc` in `format`.
///
/// # Errors
/// Serialisation failures (not expected for finite numbers).
pub fn render_sheet(doc: &SheetDoc, format: Format) -> Result<String> {
    render_sheet_at(doc, format, 0)
}

/// Renders `doc` in `format`, the text and Markdown tables with `extra` decimals beyond their
/// usual ones (so that a very large chain's table still proves itself as written; see
/// the written-artefact proof of `urdf-dh extract`).
///
/// # Errors
/// Serialisation failures (not expected for finite numbers).
pub fn render_sheet_at(doc: &SheetDoc, format: Format, extra: usize) -> Result<String> {
    Ok(match format {
        Format::Yaml => crate::sheet::write_in_parts(doc)?,
        Format::Json => crate::text::json_pretty(doc)? + "\n",
        Format::Text => text(doc, extra),
        Format::Csv => csv(doc),
        Format::Markdown => markdown(doc, extra),
        Format::Poe => return Err(crate::error::SheetError::NotSheetFormat { format: "poe" }),
    })
}

/// Decimals of the text and Markdown tables per unit symbol (`m`, `mm`, `deg`, `rad`).
pub fn decimals(unit: &str) -> usize {
    match unit {
        "m" => 6,
        "mm" => 3,
        "deg" => 4,
        _ => 6,
    }
}

/// Formats `v` with the decimals its unit deserves, `-0` printed as `0`.
fn num(v: f64, unit: &str) -> String {
    num_at(v, unit, 0)
}

/// Formats `v` with `extra` decimals more than its unit deserves, `-0` printed as `0`.
fn num_at(v: f64, unit: &str, extra: usize) -> String {
    let s = crate::units::format_fixed(v, decimals(unit) + extra);
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

fn coupling(doc: &SheetDoc, j: &JointDoc, extra: usize) -> String {
    j.mimic
        .as_ref()
        .map(|m| {
            format!(
                "= {} * {} {} {}",
                m.multiplier,
                escape(&m.joint),
                if m.offset < 0.0 { "-" } else { "+" },
                num_at(m.offset.abs(), limit_unit(doc, j), extra)
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
        (Some(b), Some(t)) => format!(" ({} -> {})", escape(b), escape(t)),
        _ => String::new(),
    };
    format!(
        "{}{chain}, {conv}",
        escape(doc.robot.as_deref().unwrap_or("robot"))
    )
}

fn text(doc: &SheetDoc, extra: usize) -> String {
    let (l, a) = (doc.length_unit.symbol(), doc.angle_unit.symbol());
    let mut s = String::new();
    let _ = writeln!(s, "{}", header_line(doc));
    let name_w = crate::text::column_width(doc.joints.iter().map(|j| j.name.as_str()), 5);
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
    // Trailing spaces from an empty coupling column would make diffs noisy.
    s = s.lines().map(str::trim_end).collect::<Vec<_>>().join("\n") + "\n";
    // The rows in parts on the machine's cores (one part, on this thread, for a usual table),
    // joined in order.
    let parts: Vec<&[JointDoc]> = doc.joints.chunks(ROWS_PER_PART).collect();
    let part = |k: usize| {
        let mut rows = String::new();
        for (i, j) in parts[k].iter().enumerate() {
            let line = row_line(doc, k * ROWS_PER_PART + i, j, name_w, extra);
            let _ = writeln!(rows, "{}", line.trim_end());
        }
        rows
    };
    match dh_core::parallel::map(parts.len(), part) {
        Some(rows) => rows.iter().for_each(|r| s += r),
        None => (0..parts.len()).for_each(|k| s += &part(k)),
    }
    let pose = |name: &str, what: &str, p: &Option<crate::sheet::PoseDoc>| match p {
        Some(p) => format!(
            "{name:<5} {what}: xyz [{l}] {} {} {}   rpy [{a}] {} {} {}\n",
            num_at(p.xyz[0], l, extra),
            num_at(p.xyz[1], l, extra),
            num_at(p.xyz[2], l, extra),
            num_at(p.rpy[0], a, extra),
            num_at(p.rpy[1], a, extra),
            num_at(p.rpy[2], a, extra)
        ),
        None => format!("{name:<5} {what}: not given\n"),
    };
    s += &tilts_and_effects(doc, "", Some(extra));
    let base_link = escape(doc.base_link.as_deref().unwrap_or("base link"));
    let tip_link = escape(doc.tip_link.as_deref().unwrap_or("tip link"));
    s += &pose("base", &format!("DH frame 0 in {base_link}"), &doc.base);
    s += &pose(
        "tool",
        &format!("{tip_link} in DH frame {}", doc.joints.len()),
        &doc.tool,
    );
    if let Some(pairs) = &doc.pairs {
        let _ = writeln!(s, "axis pairs:");
        let names: Vec<String> = pairs
            .iter()
            .map(|p| {
                let [a, b] = &p.joints;
                format!("{} -> {}", escape(a), escape(b))
            })
            .collect();
        let w = crate::text::column_width(names.iter().map(String::as_str), 0);
        for (p, names) in pairs.iter().zip(&names) {
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
                let _ = writeln!(s, "  - {}", escape(w));
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
        s += &verification_line(v);
    }
    s
}

/// Rows of the text table rendered in one part (of a long table's parts on the cores).
const ROWS_PER_PART: usize = 2000;

/// Row `i` (0-based) of the text table, its name column `name_w` wide (trailing spaces kept).
fn row_line(doc: &SheetDoc, i: usize, j: &JointDoc, name_w: usize, extra: usize) -> String {
    let (kind, cells) = row_cells(doc, j, extra);
    let name = escape(&j.name);
    let mut s = format!("{:>3}  {:<name_w$}  {:<9}", i + 1, name, kind);
    for c in &cells {
        let _ = write!(s, "  {c:>13}");
    }
    let _ = write!(s, "  {}", coupling(doc, j, extra));
    s
}

/// A row's type and its theta, d, a, alpha, lower and upper cells, as the text and Markdown
/// tables print them.
fn row_cells(doc: &SheetDoc, j: &JointDoc, extra: usize) -> (&'static str, [String; 6]) {
    let (l, a) = (doc.length_unit.symbol(), doc.angle_unit.symbol());
    let lu = limit_unit(doc, j);
    let kind = match j.kind {
        JointType::Revolute => "revolute",
        JointType::Prismatic => "prismatic",
    };
    let lim =
        |v: Option<f64>| v.map_or_else(|| "-".to_string(), |v| format!("{} {lu}", num(v, lu)));
    let cells = [
        num_at(j.theta, a, extra),
        num_at(j.d, l, extra),
        num_at(j.a, l, extra),
        num_at(j.alpha, a, extra),
        lim(j.lower),
        lim(j.upper),
    ];
    (kind, cells)
}

/// The text table's last line: the verification of the table as written. [`text`] ends with
/// it, so that a proof appends it to the text it proved instead of writing the table again.
pub(crate) fn verification_line(v: &crate::sheet::VerificationDoc) -> String {
    format!(
        "verification of this table as written: {} joint samples (seed {}) against {}: max position error {:.1e} m (bound {:.1e}), max orientation error {:.1e} rad (bound {:.1e}): {}\n",
        v.samples,
        v.seed,
        v.against.as_deref().unwrap_or("the URDF"),
        v.max_position_error,
        v.position_bound,
        v.max_orientation_error,
        v.orientation_bound,
        if v.passed { "PASS" } else { "FAIL" }
    )
}

/// How the line of the rows' tilts starts (after the CSV's `# `); [`crate::read_back`] reads it.
pub(crate) const TILTS_LINE: &str =
    "beta (Hayati-Mirmirani tilt, Ry(beta) right after the row's Rx(alpha)): ";

/// The rows' Hayati-Mirmirani tilts and the sheet's effects, one line each with `prefix`
/// (empty when the sheet has neither).
/// Tilts are written with the table's decimals (`Some(extra)` more than the unit's) or in full
/// (`None`, the CSV).
fn tilts_and_effects(doc: &SheetDoc, prefix: &str, extra: Option<usize>) -> String {
    let a = doc.angle_unit.symbol();
    let mut s = String::new();
    let tilts: Vec<String> = doc
        .joints
        .iter()
        .filter_map(|j| {
            j.beta.map(|b| {
                let v = extra.map_or_else(|| b.to_string(), |k| num_at(b, a, k));
                format!("{} {v} {a}", escape(&j.name))
            })
        })
        .collect();
    if !tilts.is_empty() {
        let _ = writeln!(s, "{prefix}{TILTS_LINE}{}", tilts.join(", "));
    }
    for e in doc.effects.iter().flatten() {
        let _ = writeln!(
            s,
            "{prefix}effect {} = {:e} {}{}",
            escape(&e.name),
            e.value,
            escape(&e.unit),
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
    s += &tilts_and_effects(doc, "# ", None);
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
                escape(&m.joint).into_owned(),
                m.multiplier.to_string(),
                m.offset.to_string(),
            ),
            None => Default::default(),
        };
        let _ = writeln!(
            s,
            "{},{kind},{},{},{},{},{},{},{},{mm},{mo}",
            csv_field(&escape(&j.name)),
            j.a,
            j.alpha,
            j.d,
            j.theta,
            opt(j.lower),
            opt(j.upper),
            csv_field(&mj)
        );
    }
    s
}

/// A CSV field, quoted (RFC 4180) when it holds a separator, a quote or a line break.
fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// A Markdown table cell: `|` escaped so that it does not end the cell.
fn md_cell(s: &str) -> String {
    s.replace('|', "\\|")
}

fn markdown(doc: &SheetDoc, extra: usize) -> String {
    let (l, a) = (doc.length_unit.symbol(), doc.angle_unit.symbol());
    let mut s = String::new();
    let _ = writeln!(s, "**{}**\n", header_line(doc));
    let _ = writeln!(
        s,
        "| # | joint | type | theta [{a}] | d [{l}] | a [{l}] | alpha [{a}] | lower | upper | coupling |"
    );
    let _ = writeln!(s, "|---|---|---|---:|---:|---:|---:|---:|---:|---|");
    for (i, j) in doc.joints.iter().enumerate() {
        let (kind, [theta, d, a, alpha, lower, upper]) = row_cells(doc, j, extra);
        let _ = writeln!(
            s,
            "| {} | {} | {kind} | {theta} | {d} | {a} | {alpha} | {lower} | {upper} | {} |",
            i + 1,
            md_cell(&escape(&j.name)),
            md_cell(&coupling(doc, j, extra))
        );
    }
    for (name, p) in [("base", &doc.base), ("tool", &doc.tool)] {
        if let Some(p) = p {
            let _ = writeln!(
                s,
                "\n{name}: xyz [{l}] {} {} {}, rpy [{a}] {} {} {}",
                num_at(p.xyz[0], l, extra),
                num_at(p.xyz[1], l, extra),
                num_at(p.xyz[2], l, extra),
                num_at(p.rpy[0], a, extra),
                num_at(p.rpy[1], a, extra),
                num_at(p.rpy[2], a, extra)
            );
        }
    }
    for line in tilts_and_effects(doc, "", Some(extra)).lines() {
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
