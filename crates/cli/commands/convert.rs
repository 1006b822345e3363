//! `urdf-dh convert`: a sheet in the other convention (or other units), exactly.

use std::io::Write;

use anyhow::Result;
use dh_core::Convention;

use crate::error::Outcome;
use crate::input::{display_name, read_text};
use crate::render::{render_sheet, Format};
use crate::sheet::{Sheet, SheetDoc};
use crate::units::{AngleUnit, LengthUnit};

/// Everything `convert` needs.
#[derive(Clone, Debug)]
pub struct ConvertArgs {
    /// Sheet path or `-`.
    pub sheet: String,
    /// Target convention.
    pub to: Convention,
    /// Output format.
    pub format: Format,
    /// Length unit of the output (default: the sheet's).
    pub length_unit: Option<LengthUnit>,
    /// Angle unit of the output (default: the sheet's).
    pub angle_unit: Option<AngleUnit>,
}

/// Runs `convert`: `a`, `alpha` move one row and the base or tool takes the pair that falls
/// off the end (see `DhTable::to_convention`); `theta`, `d`, joint directions and zero pose stay.
///
/// # Errors
/// Unreadable or invalid sheet.
pub fn convert(args: &ConvertArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    let name = display_name(&args.sheet);
    let sheet = Sheet::parse(&read_text(&args.sheet)?, &name)?;
    for w in &sheet.warnings {
        writeln!(err, "urdf-dh: warning: {w}")?;
    }
    let table = sheet.table.to_convention(args.to);
    let mut doc = SheetDoc::from_table(
        &table,
        args.length_unit.unwrap_or(sheet.length_unit),
        args.angle_unit.unwrap_or(sheet.angle_unit),
    );
    doc.robot = sheet.robot.clone();
    doc.source = sheet.source.clone();
    // Effects do not depend on the convention: they pass through unchanged.
    doc.effects = (!sheet.effects.is_empty()).then(|| sheet.effects.clone());
    // A transform the sheet left free stays free: whatever the conversion moves into it (the
    // last row's a, alpha; the first row's) is absorbed by a free transform anyway.
    if !sheet.has_base {
        doc.base = None;
    }
    if !sheet.has_tool {
        doc.tool = None;
    }
    out.write_all(render_sheet(&doc, args.format)?.as_bytes())?;
    Ok(Outcome::Pass)
}
