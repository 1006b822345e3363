//! `urdf-dh check`: does a URDF match a vendor's DH sheet? If not, which joint and which
//! parameter differ? Reads the files, runs `dh_workflows::check::compare` and renders its report
//! (text, or the JSON contract of docs/guide/check.md).
//!
//! Two independent answers are combined (see `dh_workflows::check`):
//! 1. the row-by-row equivalence walk of `dh_core::equivalence`, which sees through the
//!    representation freedoms (x signs, common-normal placement, convention, units) and names
//!    every difference;
//! 2. the sheet taken literally, with its free base and tool fitted by least squares from a
//!    closed-form registration of the joint axes (`dh_core::literal`), against the URDF's own
//!    forward kinematics: the largest position and orientation deviation over many joint
//!    values, the number a CI job can put a bound on.

use std::io::Write;

use anyhow::Result;
use dh_workflows::check::kind_name;
pub use dh_workflows::check::{
    compare, CheckReport, CheckTolerances, DifferenceDoc, CHECK_ANGULAR, CHECK_LINEAR,
};
use dh_workflows::geometry::Tolerance;
use dh_workflows::input::load_chain;
use dh_workflows::input::{display_name, read_text};
use dh_workflows::sheet::Sheet;

use crate::error::Outcome;

/// Output format of `check`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Default)]
pub enum CheckFormat {
    /// A readable report.
    #[default]
    Text,
    /// The JSON contract of docs/guide/check.md.
    Json,
}

/// Everything `check` needs.
#[derive(Clone, Debug)]
pub struct CheckArgs {
    /// URDF path (or `-`).
    pub robot: String,
    /// Sheet path.
    pub sheet: String,
    /// Base link.
    pub base: Option<String>,
    /// Tip link.
    pub tip: Option<String>,
    /// Comparison tolerances.
    pub tolerance: Tolerance,
    /// Output format.
    pub format: CheckFormat,
}

/// Runs `check`.
///
/// # Errors
/// Unreadable or invalid URDF or sheet.
pub fn check(args: &CheckArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    let (model, chain) = load_chain(&args.robot, args.base.as_deref(), args.tip.as_deref())?;
    for w in dh_workflows::input::urdf_warnings(&display_name(&args.robot), &model, &chain) {
        writeln!(err, "urdf-dh: warning: {w}")?;
    }
    let sheet_name = display_name(&args.sheet);
    let sheet = Sheet::parse(&read_text(&args.sheet)?, &sheet_name)?;
    if let Some(w) = sheet.effects_warning(&sheet_name, "check compares the DH kinematics alone") {
        writeln!(err, "urdf-dh: warning: {w}")?;
    }
    let report = compare(&chain, &sheet, args.tolerance)?;
    for w in &report.warnings {
        writeln!(err, "urdf-dh: warning: {w}")?;
    }
    match args.format {
        CheckFormat::Json => writeln!(out, "{}", crate::guard::json_pretty(&report)?)?,
        CheckFormat::Text => {
            let title = format!(
                "{} ({} -> {}) against {sheet_name}",
                display_name(&args.robot),
                chain.base(),
                chain.tip()
            );
            out.write_all(text(&title, &report, &sheet).as_bytes())?
        }
    }
    Ok(if report.matches {
        Outcome::Pass
    } else {
        Outcome::Differs
    })
}

fn text(title: &str, r: &CheckReport, sheet: &Sheet) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let free = |given: bool| if given { "given" } else { "free" };
    let _ = writeln!(s, "check: {title}");
    let _ = writeln!(
        s,
        "sheet: {} convention, base {}, tool {}; tolerances: linear {:e} m, angular {:e} rad",
        sheet.table.convention,
        free(r.base_given),
        free(r.tool_given),
        r.tolerances.linear,
        r.tolerances.angular
    );
    if r.matches {
        let _ = writeln!(
            s,
            "MATCH: the URDF and the sheet describe the same kinematics"
        );
    } else {
        let _ = writeln!(s, "MISMATCH: {} difference(s)", r.differences.len());
        let w = crate::guard::column_width(
            r.differences
                .iter()
                .map(|d| d.joint.as_deref().unwrap_or("-")),
            5,
        );
        let _ = writeln!(
            s,
            "  {:<w$}  {:<11}  {:>14}  {:>14}  {:>14}  note",
            "joint", "parameter", "urdf", "sheet", "difference"
        );
        for d in &r.differences {
            let fmt = |v: f64| match d.parameter.as_str() {
                "alpha" | "theta" | "fk_orientation" => format!("{:.4} deg", v.to_degrees()),
                "a" | "d" | "base" | "tool" | "fk_position" => format!("{:.6} m", v),
                "type" => kind_name(v).to_string(),
                _ => format!("{v}"),
            };
            let mut note = d.note.clone();
            if !d.aliases.is_empty() {
                note += &format!(" (or: {})", d.aliases.join(", "));
            }
            let _ = writeln!(
                s,
                "  {:<w$}  {:<11}  {:>14}  {:>14}  {:>14}  {note}",
                crate::guard::escape(d.joint.as_deref().unwrap_or("-")),
                d.parameter,
                fmt(d.urdf),
                fmt(d.sheet),
                if d.parameter == "type" {
                    "-".to_string()
                } else {
                    fmt(d.difference)
                }
            );
        }
    }
    if let (Some(p), Some(o), Some(bp), Some(bo)) = (
        r.max_position_error,
        r.max_orientation_error,
        r.position_bound,
        r.orientation_bound,
    ) {
        let _ = writeln!(
            s,
            "sheet taken literally (same joint values, free base/tool fitted), {} samples: max position error {:.3e} m, max orientation error {:.3e} rad (bound {:.1e} m, {:.1e} rad)",
            r.samples, p, o, bp, bo
        );
    }
    s
}
