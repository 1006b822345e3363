//! `urdf-dh check`: does a URDF match a vendor's DH sheet? If not, which joint and which
//! parameter differ?
//!
//! Two independent answers are combined:
//! 1. the row-by-row equivalence walk of `dh_core::equivalence`, which sees through the
//!    representation freedoms (x signs, common-normal placement, convention, units) and names
//!    every difference;
//! 2. the sheet taken literally, with its free base and tool fitted by least squares from a
//!    closed-form registration of the joint axes (`dh_core::literal`), against the URDF's own
//!    forward kinematics: the largest position and orientation deviation over many joint
//!    values, the number a CI job can put a bound on.
//!
//! Both live in `dh_core::check`, which also holds the invariant: no MATCH while the literal
//! comparison exceeds the tolerances.

use std::io::Write;

use anyhow::{Context, Result};
use dh_core::{check_sheet, Convention, Freedom, Parameter, Tolerance};
use serde::Serialize;
use urdf_axes::Chain;

use crate::commands::extract::load_chain;
use crate::error::Outcome;
use crate::input::{display_name, read_text};
use crate::sheet::Sheet;

/// Default length tolerance of `check`: 0.1 mm.
///
/// Far above URDF rounding (micrometres) and the cost of `rpy="1.5708"` (3.7e-6 rad, a few
/// micrometres over a metre), and five times below the 0.5 mm a real drift must show.
pub const CHECK_LINEAR: f64 = 1e-4;
/// Default angle tolerance of `check`: 2e-4 rad (0.011°).
///
/// Accepts four-decimal angles (≤ 5e-5 rad) and `1.5708` with margin; four times below the
/// 0.05° (8.7e-4 rad) a real drift must show.
pub const CHECK_ANGULAR: f64 = 2e-4;

/// Output format of `check`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Default)]
pub enum CheckFormat {
    /// A readable report.
    #[default]
    Text,
    /// The JSON contract of the README.
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

/// One difference, as the JSON contract spells it (SI units).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DifferenceDoc {
    /// Joint name (`null` for base, tool and joint count).
    pub joint: Option<String>,
    /// `a|alpha|d|theta|direction|base|tool|type|fk_position|fk_orientation|joint_count`.
    pub parameter: String,
    /// What the URDF has (the value the sheet would need).
    pub urdf: f64,
    /// What the sheet says.
    pub sheet: f64,
    /// `urdf − sheet`.
    pub difference: f64,
    /// Joints whose same parameter the data cannot tell apart from this one.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub aliases: Vec<String>,
    /// A sentence for people.
    pub note: String,
}

/// Tolerances echoed in the report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CheckTolerances {
    /// Metres.
    pub linear: f64,
    /// Radians.
    pub angular: f64,
}

/// The report of `check`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CheckReport {
    /// No difference found.
    pub matches: bool,
    /// Every difference.
    pub differences: Vec<DifferenceDoc>,
    /// Largest tip position deviation of the sheet taken literally (same joint values), with
    /// its free base and tool fitted (metres); `null` when the joint counts differ.
    pub max_position_error: Option<f64>,
    /// Largest orientation deviation likewise (radians).
    pub max_orientation_error: Option<f64>,
    /// What `max_position_error` may reach in a match (metres): `linear + angular × size` of
    /// the chain; `null` when the joint counts differ.
    pub position_bound: Option<f64>,
    /// What `max_orientation_error` may reach in a match (radians): `angular`.
    pub orientation_bound: Option<f64>,
    /// Tolerances used.
    pub tolerances: CheckTolerances,
    /// The sheet's base and tool: given (compared) or free (fitted).
    pub base_given: bool,
    /// See `base_given`.
    pub tool_given: bool,
    /// Joint-value samples of the literal comparison.
    pub samples: usize,
    /// Remarks (joint names that differ, suspicious units).
    pub warnings: Vec<String>,
}

/// Runs `check`.
///
/// # Errors
/// Unreadable or invalid URDF or sheet.
pub fn check(args: &CheckArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    let (model, chain) = load_chain(&args.robot, args.base.as_deref(), args.tip.as_deref())?;
    for w in crate::commands::extract::urdf_warnings(&display_name(&args.robot), &model, &chain) {
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
        CheckFormat::Json => writeln!(out, "{}", serde_json::to_string_pretty(&report)?)?,
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

/// Compares a URDF chain with a sheet.
///
/// # Errors
/// Extraction or fitting failures (not expected for a valid chain).
pub fn compare(chain: &Chain, sheet: &Sheet, tol: Tolerance) -> Result<CheckReport> {
    let mut warnings = sheet.warnings.clone();
    let urdf_names: Vec<&str> = chain.axes().iter().map(|a| a.name.as_str()).collect();
    let sheet_names: Vec<&str> = sheet.table.rows.iter().map(|r| r.name.as_str()).collect();
    let tolerances = CheckTolerances {
        linear: tol.linear,
        angular: tol.angular,
    };
    if urdf_names.len() != sheet_names.len() {
        let mut differences = vec![DifferenceDoc {
            joint: None,
            parameter: "joint_count".into(),
            urdf: urdf_names.len() as f64,
            sheet: sheet_names.len() as f64,
            difference: urdf_names.len() as f64 - sheet_names.len() as f64,
            aliases: vec![],
            note: format!(
                "the URDF chain has {} moving joints, the sheet {}",
                urdf_names.len(),
                sheet_names.len()
            ),
        }];
        for name in urdf_names.iter().filter(|n| !sheet_names.contains(n)) {
            differences.push(missing(name, "missing from the sheet"));
        }
        for name in sheet_names.iter().filter(|n| !urdf_names.contains(n)) {
            differences.push(missing(name, "not a moving joint of the URDF chain"));
        }
        return Ok(CheckReport {
            matches: false,
            differences,
            max_position_error: None,
            max_orientation_error: None,
            position_bound: None,
            orientation_bound: None,
            tolerances,
            base_given: sheet.has_base,
            tool_given: sheet.has_tool,
            samples: 0,
            warnings,
        });
    }
    for (u, s) in urdf_names.iter().zip(&sheet_names) {
        if u != s {
            warnings.push(format!(
                "joint names differ: the URDF's '{u}' is compared with the sheet's '{s}' (same position in the chain)"
            ));
        }
    }
    let reference = dh_core::extract(
        chain.axes(),
        &chain.tip_pose(),
        Tolerance::default(),
        Convention::Standard,
    )
    .context("extracting the URDF's own table")?;
    let freedom = Freedom {
        base_free: !sheet.has_base,
        tool_free: !sheet.has_tool,
    };
    // Row by row, a tilted sheet is compared as the plain DH table of its own kinematics.
    let plain = if sheet.table.has_tilts() {
        warnings.push(
            "the sheet's beta tilts are compared row by row as the plain DH values they stand for (exact; a common normal may lie far away)"
                .into(),
        );
        let zero = vec![0.0; sheet.table.rows.len()];
        let exact = Tolerance::new(1e-12, 1e-12).map_err(|e| anyhow::anyhow!("{e}"))?;
        dh_core::extract(
            &sheet.table.axes()?,
            &sheet.table.fk(&zero)?,
            exact,
            sheet.table.convention,
        )
        .context("folding the sheet's beta tilts into plain DH")?
        .table
    } else {
        sheet.table.clone()
    };
    let verdict = check_sheet(&reference.table, &plain, freedom, tol, |q| chain.fk(q))
        .context("comparing the sheet with the URDF")?;
    let name = |row: Option<usize>| {
        row.and_then(|r| sheet.table.rows.get(r))
            .map(|r| r.name.clone())
    };
    let differences: Vec<DifferenceDoc> = verdict
        .differences()
        .iter()
        .map(|d| {
            let joint = name(d.row);
            let note = match d.parameter {
                Parameter::Direction => "the joint turns the other way: the same joint value moves it in the opposite sense".to_string(),
                Parameter::Theta => "a different zero pose: theta differs".to_string(),
                Parameter::D if !d.aliases.is_empty() => "d differs; along a run of parallel axes the data cannot tell which joint's d".to_string(),
                Parameter::D => "d differs".to_string(),
                Parameter::A => "link length a differs".to_string(),
                Parameter::Alpha => "twist alpha differs".to_string(),
                Parameter::Base => "the sheet's base puts joint 1's axis elsewhere (urdf: distance in metres)".to_string(),
                Parameter::Tool => "the sheet's tool puts the tip elsewhere (urdf: distance in metres)".to_string(),
                Parameter::Type => format!(
                    "the URDF's joint is {}, the sheet's {} (urdf, sheet: 0 revolute, 1 prismatic)",
                    kind_name(d.reference),
                    kind_name(d.sheet)
                ),
                Parameter::FkPosition => "no parameter differs, yet the sheet taken literally puts the tip this far (metres) from the URDF's".to_string(),
                Parameter::FkOrientation => "no parameter differs, yet the sheet taken literally turns the tip this far (radians) from the URDF's".to_string(),
            };
            DifferenceDoc {
                joint,
                parameter: d.parameter.as_str().into(),
                urdf: d.reference,
                sheet: d.sheet,
                difference: d.reference - d.sheet,
                aliases: d.aliases.iter().filter_map(|&r| name(Some(r))).collect(),
                note,
            }
        })
        .collect();
    let dev = &verdict.literal().deviation;
    Ok(CheckReport {
        matches: verdict.matches(),
        differences,
        max_position_error: Some(dev.max_position_error),
        max_orientation_error: Some(dev.max_orientation_error),
        position_bound: Some(verdict.bound().position),
        orientation_bound: Some(verdict.bound().orientation),
        tolerances,
        base_given: sheet.has_base,
        tool_given: sheet.has_tool,
        samples: dev.samples,
        warnings,
    })
}

fn missing(name: &str, note: &str) -> DifferenceDoc {
    DifferenceDoc {
        joint: Some(name.to_string()),
        parameter: "joint_count".into(),
        urdf: 0.0,
        sheet: 0.0,
        difference: 0.0,
        aliases: vec![],
        note: note.to_string(),
    }
}

/// The joint kind a `type` difference's number stands for (`dh_core::kind_code`).
fn kind_name(code: f64) -> &'static str {
    if code == 0.0 {
        "revolute"
    } else {
        "prismatic"
    }
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
