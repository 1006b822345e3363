//! `check`'s comparison: does a URDF chain match a vendor's DH sheet? If not, which joint and
//! which parameter differ? [`compare`] returns a [`CheckReport`], plain data in SI units (metres,
//! radians) that serialises to the JSON contract of `urdf-dh check --format json`.
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

use dh_core::{check_sheet, Convention, Freedom, Parameter, Tolerance};
use serde::Serialize;
use urdf_axes::Chain;

use crate::error::{Result, SheetError};
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

/// Compares a URDF chain with a sheet: the sheet's rows with the table extracted from the
/// chain, and the sheet taken literally with the chain's own forward kinematics, within `tol`.
///
/// The report names each difference's joint and parameter; its `warnings` are the sheet's own
/// plus those of the comparison (joint names that differ, tilts compared as plain DH).
///
/// # Errors
/// [`SheetError::Compare`] or [`SheetError::Geometry`]: extraction or fitting failures (not
/// expected for a valid chain).
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
    .map_err(|error| SheetError::Compare {
        step: "extracting the URDF's own table",
        error,
    })?;
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
        let exact = Tolerance::new(1e-12, 1e-12)?;
        dh_core::extract(
            &sheet.table.axes()?,
            &sheet.table.fk(&zero)?,
            exact,
            sheet.table.convention,
        )
        .map_err(|error| SheetError::Compare {
            step: "folding the sheet's beta tilts into plain DH",
            error,
        })?
        .table
    } else {
        sheet.table.clone()
    };
    let verdict =
        check_sheet(&reference.table, &plain, freedom, tol, |q| chain.fk(q)).map_err(|error| {
            SheetError::Compare {
                step: "comparing the sheet with the URDF",
                error,
            }
        })?;
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

/// The joint kind a `type` difference's number stands for (`dh_core::kind_code`): `revolute`
/// or `prismatic`.
pub fn kind_name(code: f64) -> &'static str {
    if code == 0.0 {
        "revolute"
    } else {
        "prismatic"
    }
}
