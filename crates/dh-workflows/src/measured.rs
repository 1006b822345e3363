//! What the measured-data commands (`import`, `calibrate`, `cpa`, `simulate`) share: the model
//! (`--model`: a URDF chain or a DH sheet), measurement files in the canonical CSV layout, and
//! effect labels.

use std::sync::Arc;

use anyhow::{Context, Result};
use dh_calib::csv::CsvOptions;
use dh_calib::data::Measurements;
use dh_calib::model::Effect;
use dh_core::{DhTable, JointKind};

use crate::error::hinted;
use crate::input::{display_name, read_data_text};
use crate::units::{AngleUnit, LengthUnit};

/// Measurements and joint values handed over as arrays instead of a file.
pub use dh_calib::csv::SampleArrays;
/// Columns of the canonical CSV that are not joints (the format's own list).
pub use dh_calib::csv::RESERVED_COLUMNS;

/// Units of a measurement file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct DataUnits {
    /// Unit of `x`, `y`, `z`, `sigma` and prismatic joints.
    pub length: LengthUnit,
    /// Unit of revolute joints.
    pub angle: AngleUnit,
}

impl DataUnits {
    /// The CSV reader's options in these units, `prismatic` naming the prismatic joint
    /// columns (read in the length unit).
    pub fn csv_options(self, prismatic: &[String]) -> CsvOptions {
        CsvOptions {
            length_unit: match self.length {
                LengthUnit::M => dh_calib::csv::LengthUnit::Metre,
                LengthUnit::Mm => dh_calib::csv::LengthUnit::Millimetre,
            },
            angle_unit: match self.angle {
                AngleUnit::Rad => dh_calib::csv::AngleUnit::Radian,
                AngleUnit::Deg => dh_calib::csv::AngleUnit::Degree,
            },
            prismatic: prismatic.to_vec(),
        }
    }
}

/// A measurement file's text, read once (standard input cannot be read twice).
#[derive(Clone, Debug)]
pub struct DataFile {
    /// The file name (no directories; `<stdin>` for `-`).
    pub name: String,
    /// Its text.
    pub text: String,
}

impl DataFile {
    /// Reads `path`, or standard input for `-`.
    ///
    /// # Errors
    /// Unreadable file or not UTF-8.
    pub fn read(path: &str) -> Result<DataFile> {
        Ok(DataFile {
            name: display_name(path),
            text: read_data_text(path)?,
        })
    }
}

/// Parses a measurement file in the canonical CSV layout with columns for `joints`.
///
/// # Errors
/// Any [`dh_calib::csv::DataError`], prefixed with the file name (the error names the line and
/// column).
pub fn read_measurements(
    file: &DataFile,
    joints: &[String],
    prismatic: &[String],
    units: DataUnits,
    err: &mut dyn std::io::Write,
) -> Result<Measurements> {
    let name = &file.name;
    let (data, notes) = dh_calib::csv::parse_measurements_noting(
        &file.text,
        joints,
        &units.csv_options(prismatic),
    )
    .map_err(|e| {
        let hint = match &e {
            dh_calib::csv::DataError::MissingJoints { .. } => Some(
                "the joint columns must be named as the model's joints (see docs/guide/measurements.md)",
            ),
            _ => None,
        };
        match hint {
            Some(h) => hinted(format!("{name}: {e}"), h),
            None => anyhow::anyhow!("{name}: {e}"),
        }
    })?;
    for n in notes {
        writeln!(err, "urdf-dh: warning: {name}: {n}")?;
    }
    Ok(data)
}

/// Where measurements come from: a file, or a caller's arrays (named in messages).
pub enum DataSource<'a> {
    /// A measurement file, read.
    File(DataFile),
    /// Arrays handed over instead of a file, and their name.
    Arrays(&'a dh_calib::csv::SampleArrays, String),
}

impl DataSource<'_> {
    /// The joint columns to read for `model`: its measured joints, or without a model every
    /// joint column of the data (the file's header, the arrays' names).
    ///
    /// # Errors
    /// A file header without joint columns.
    pub fn joints(&self, model: Option<&crate::model::LoadedModel>) -> Result<Vec<String>> {
        match (model, self) {
            (Some(m), _) => Ok(m.measured_joints()),
            (None, DataSource::File(file)) => header_joints(file),
            (None, DataSource::Arrays(a, _)) => Ok(a.joint_names.clone()),
        }
    }

    /// The measurements with the joint columns `joints` (`prismatic` naming the prismatic
    /// ones), in `units`; warnings on `err`.
    ///
    /// # Errors
    /// As [`read_measurements`] and [`read_arrays`].
    pub fn read(
        &self,
        joints: &[String],
        prismatic: &[String],
        units: DataUnits,
        err: &mut dyn std::io::Write,
    ) -> Result<Measurements> {
        match self {
            DataSource::File(file) => read_measurements(file, joints, prismatic, units, err),
            DataSource::Arrays(a, name) => read_arrays(a, name, joints, prismatic, units, err),
        }
    }
}

/// The measurements of `arrays` (a caller's arrays instead of a file, named `name` in messages)
/// with the joint columns `joints`, read as [`read_measurements`] reads a file with the same
/// columns; its notes (standard deviations of 0 floored) go to `err` as warnings.
///
/// # Errors
/// Missing joint columns, columns of different lengths, a bad value (naming the row and the
/// column).
pub fn read_arrays(
    arrays: &dh_calib::csv::SampleArrays,
    name: &str,
    joints: &[String],
    prismatic: &[String],
    units: DataUnits,
    err: &mut dyn std::io::Write,
) -> Result<Measurements> {
    let (data, notes) = arrays
        .with_joints(joints)
        .and_then(|a| Measurements::from_arrays(&a, &units.csv_options(prismatic)))
        .map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
    for n in notes {
        writeln!(err, "urdf-dh: warning: {name}: {n}")?;
    }
    Ok(data)
}

/// The joint columns of a measurement file without a model: every header column that is not
/// one of [`RESERVED_COLUMNS`], in order.
///
/// # Errors
/// No header line, no joint column.
pub fn header_joints(file: &DataFile) -> Result<Vec<String>> {
    let name = &file.name;
    let (line, header) = file
        .text
        .trim_start_matches('\u{feff}')
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .find(|(_, l)| !l.is_empty() && !l.starts_with('#'))
        .with_context(|| format!("{name}: expected a header line, found an empty file"))?;
    let joints: Vec<String> = split_header(header)
        .into_iter()
        .filter(|c| !RESERVED_COLUMNS.contains(&c.as_str()))
        .collect();
    if joints.is_empty() {
        return Err(hinted(
            format!("{name}: line {line}: expected joint columns besides x, y, z, found none"),
            "a measurement file has one column per joint, named as the model's joints",
        ));
    }
    Ok(joints)
}

/// Header cells: comma separated, trimmed, double quotes removed.
fn split_header(line: &str) -> Vec<String> {
    let mut cells = vec![String::new()];
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '"' if quoted && chars.peek() == Some(&'"') => {
                chars.next();
                if let Some(s) = cells.last_mut() {
                    s.push('"');
                }
            }
            '"' => quoted = !quoted,
            ',' if !quoted => cells.push(String::new()),
            c => {
                if let Some(s) = cells.last_mut() {
                    s.push(c);
                }
            }
        }
    }
    cells.into_iter().map(|s| s.trim().to_string()).collect()
}

/// The effect a label names, for the rows of `table` (`dh_calib::effects::parse_label`). The
/// gravity effects (`compliance`, `lateral_compliance`, `backlash`) need link inertials, which
/// a DH table does not carry.
///
/// # Errors
/// An unknown kind, a wrong number of joints, a joint the table does not have.
pub fn parse_effect(label: &str, table: &DhTable) -> Result<Arc<dyn Effect>> {
    parse_effect_in(label, &dh_calib::effects::EffectContext::serial(table))
}

/// [`parse_effect`] in `ctx` (a context with link masses parses the gravity effects).
///
/// # Errors
/// As [`parse_effect`].
pub fn parse_effect_in(
    label: &str,
    ctx: &dh_calib::effects::EffectContext,
) -> Result<Arc<dyn Effect>> {
    let table = ctx.tree.trunk();
    dh_calib::effects::parse_label_in(label, ctx).map_err(|e| {
        hinted(
            format!("{e}"),
            format!(
                "effects are named <kind>:<joint> (coupling:<joint>:<driver>; scale alone); the model's joints: {}",
                table
                    .rows
                    .iter()
                    .map(|r| r.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        )
    })
}

/// Slack beyond a joint's limits before a measured value counts as outside them (radians, or
/// metres for a prismatic joint): controllers report a hair past a soft limit.
pub const LIMIT_SLACK: f64 = 1e-3;

/// One warning per joint whose measured values (SI, after coupling) leave the model's limits,
/// naming the column, the first such row's line, the value and the limits: values past the
/// limits are what degrees read as radians (or millimetres as metres) look like when they stay
/// below the reader's four-turn guard.
pub fn beyond_limits(table: &DhTable, data: &Measurements, data_name: &str) -> Vec<String> {
    let mut warnings = Vec::new();
    // Per column with limits: its row, (how many samples are outside, the first of them).
    let limited: Vec<(usize, &dh_core::DhRow, dh_core::Limits)> = data
        .joint_names
        .iter()
        .enumerate()
        .filter_map(|(i, joint)| {
            let row = table.rows.iter().find(|r| &r.name == joint)?;
            Some((i, row, row.limits?))
        })
        .collect();
    let mut found: Vec<(usize, Option<&dh_calib::data::Sample>)> = vec![(0, None); limited.len()];
    // One pass over the samples for every joint (millions of samples).
    for s in &data.samples {
        for (&(i, _, l), (count, first)) in limited.iter().zip(found.iter_mut()) {
            if s.q
                .get(i)
                .is_some_and(|&v| v < l.lower - LIMIT_SLACK || v > l.upper + LIMIT_SLACK)
            {
                *count += 1;
                first.get_or_insert(s);
            }
        }
    }
    for (&(i, row, l), &(count, first)) in limited.iter().zip(&found) {
        let joint = &data.joint_names[i];
        let Some(first) = first else {
            continue;
        };
        // Past a full turn (or a metre beyond the stroke) the unit is the likely fault; else
        // the joint's zero, its direction, or the model's limits.
        let v = first.q[i];
        let far = match row.kind {
            JointKind::Revolute => v.abs() > std::f64::consts::TAU,
            JointKind::Prismatic => (v - v.clamp(l.lower, l.upper)).abs() > 1.0,
        };
        let (unit, hint) = match (row.kind, far) {
            (JointKind::Revolute, true) => {
                ("rad", "degrees labelled as radians? pass --angle-unit deg")
            }
            (JointKind::Prismatic, true) => {
                ("m", "millimetres labelled as metres? pass --length-unit mm")
            }
            (JointKind::Revolute, false) => (
                "rad",
                "check the joint's zero and direction, or the model's limits",
            ),
            (JointKind::Prismatic, false) => (
                "m",
                "check the joint's zero and direction, or the model's limits",
            ),
        };
        warnings.push(format!(
            "{data_name}: line {}, column '{}': {:.4} {unit} is beyond the joint's limits [{:.4}, {:.4}] {unit} ({count} of {} samples are); {hint}",
            first.line,
            crate::text::escape(joint),
            first.q[i],
            l.lower,
            l.upper,
            data.samples.len()
        ));
    }
    warnings
}

#[cfg(test)]
mod tests;
