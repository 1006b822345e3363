//! `urdf-dh convert`: a sheet in the other convention (or other units), exactly.

use std::io::Write;

use anyhow::Result;
use dh_workflows::geometry::{Bound, Convention};
use dh_workflows::input::{display_name, read_text};
use dh_workflows::prove::{failure_line, prove, Isometry3Pair, Source};
use dh_workflows::render::{render_sheet, Format};
use dh_workflows::sheet::{Sheet, SheetDoc};
use dh_workflows::units::{AngleUnit, LengthUnit};
use dh_workflows::ur;
use nalgebra::Isometry3;

use crate::error::Outcome;

/// Everything `convert` needs.
#[derive(Clone, Debug)]
pub struct ConvertArgs {
    /// Sheet path, `-`, or the name of a shipped nominal table ([`dh_workflows::ur::nominal`]).
    pub sheet: String,
    /// A UR controller's `calibration.conf`, whose deltas calibrate the sheet.
    pub deltas: Option<String>,
    /// Target convention.
    pub to: Convention,
    /// Output format.
    pub format: Format,
    /// Length unit of the output (default: the sheet's).
    pub length_unit: Option<LengthUnit>,
    /// Angle unit of the output (default: the sheet's).
    pub angle_unit: Option<AngleUnit>,
    /// Joint-value samples of the check of the written table against the input.
    pub samples: usize,
    /// Seed of the sampler.
    pub seed: u64,
}

/// Runs `convert`: `a`, `alpha` move one row and the base or tool takes the pair that falls
/// off the end (see `DhTable::to_convention`); `theta`, `d`, joint directions and zero pose stay.
/// What is written is read back and compared with the input sheet by forward kinematics
/// ([`dh_workflows::prove::prove`]); exit 1 if it strays beyond the written precision's bound.
///
/// # Errors
/// Unreadable or invalid sheet.
pub fn convert(args: &ConvertArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    let (name, text) = sheet_text(&args.sheet)?;
    let mut sheet = Sheet::parse(&text, &name)?;
    for w in &sheet.warnings {
        writeln!(err, "urdf-dh: warning: {w}")?;
    }
    // With deltas, the source the written table is proved against is the nominal numbers plus
    // the deltas, composed directly (`ur::calibrated_fk`), not the calibrated table itself.
    let calibration = match &args.deltas {
        None => None,
        Some(path) => {
            let conf_name = display_name(path);
            let conf = ur::CalibrationConf::parse(&read_text(path)?, &conf_name)?;
            let nominal = sheet.table.clone();
            sheet.table = ur::calibrated(&nominal, &conf.deltas)
                .map_err(|e| anyhow::anyhow!("{name} with {conf_name}: {e:#}"))?;
            sheet.source = Some(format!(
                "{} + the factory calibration deltas of {conf_name} ([mounting] delta_theta, delta_a, delta_d, delta_alpha)",
                sheet.source.as_deref().unwrap_or(name.as_str())
            ));
            Some((nominal, conf.deltas, conf_name))
        }
    };
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
    // What convert writes, a sheet reader reads: refuse a result beyond a sheet's limits
    // (the conversion moves a row's a and alpha into the base or tool, where they add up).
    if let Err(e) = Sheet::parse(&render_sheet(&doc, Format::Yaml)?, &name) {
        anyhow::bail!("{name}: cannot convert: the result would not be a valid sheet: {e:#}");
    }
    let source = sheet.table.prepare();
    let free = Isometry3Pair {
        base: table.base,
        tool: table.tool,
    };
    // Unit conversion and the change of convention are exact up to float rounding: a few ulps per
    // row, relative to the chain's size (as extraction's own arithmetic bound).
    let n = sheet.table.rows.len() as f64 + 1.0;
    let bound = Bound {
        position: 16.0 * n * f64::EPSILON * sheet.table.size(),
        orientation: 16.0 * n * f64::EPSILON,
    };
    let against = match &calibration {
        None => "the input sheet".to_owned(),
        Some((_, _, conf)) => format!("{name} + the deltas of {conf}"),
    };
    let (text, passed) = prove(
        &mut doc,
        args.format,
        &free,
        Source {
            table: &sheet.table,
            bound,
            oracle: |q: &[f64]| match &calibration {
                Some((nominal, deltas, _)) => ur::calibrated_fk(nominal, deltas, q),
                None => source.fk(q).unwrap_or_else(|_| Isometry3::identity()),
            },
            against: Some(against),
            samples: args.samples,
            seed: args.seed,
        },
    )?;
    out.write_all(text.as_bytes())?;
    if passed {
        return Ok(Outcome::Pass);
    }
    writeln!(
        err,
        "{}",
        failure_line("the converted table", &name, doc.verification.as_ref())
    )?;
    Ok(Outcome::Differs)
}

/// The sheet's display name and text: the file (or `-`), else a shipped nominal table of that
/// name (`ur5e` reads as `ur5e.yaml`).
///
/// # Errors
/// No such file and no such nominal table (the hint lists the names); an unreadable file.
fn sheet_text(path: &str) -> Result<(String, String)> {
    if path != "-" && !std::path::Path::new(path).exists() {
        if let Some(n) = ur::nominal(path) {
            return Ok((format!("{}.yaml", n.name), n.text.to_owned()));
        }
        let names: Vec<&str> = ur::NOMINAL.iter().map(|n| n.name).collect();
        return Err(dh_workflows::error::hinted(
            format!("{path}: cannot read the file: no such file, and no shipped nominal table of that name"),
            format!("the shipped nominal tables: {}", names.join(", ")),
        ));
    }
    Ok((display_name(path), read_text(path)?))
}
