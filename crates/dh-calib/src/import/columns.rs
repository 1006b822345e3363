//! The user's own export, laid out by a column map: which columns hold the joint values, the
//! measured point, and optionally the target, the point's standard deviation, the pose
//! identifier, the calibration/validation split, the session and a 6-DoF device's orientation
//! ([`orientation`]); in which units; with which separator; with or without a header line.
//!
//! # Frames and units
//! Points are in the measuring device's frame, converted to metres with
//! [`ColumnMap::length_scale`]; joint values to radians with [`ColumnMap::angle_scale`] (joints
//! named in [`ColumnMap::prismatic`] to metres with the length scale). Orientations are the
//! target frame's rotation in the device frame, their angles in the angle unit (see
//! [`orientation`]). Lines starting with `#` are comments.
//!
//! # Columns
//! A [`ColumnRef`] is a 1-based column number or a header name. A decimal comma (`1,5`) is not
//! read: with `;` as separator, cells must use a decimal point.

use nalgebra::Vector3;

use crate::csv::{
    check_name, parse_split, DataError, Records, MAX_PLAUSIBLE_METRES as MAX_METRES,
    MAX_PLAUSIBLE_RADIANS as MAX_RADIANS, SIGMA_FLOOR,
};
use crate::data::{Measurements, Sample, Split};

mod copies;
pub mod orientation;
mod resolve;
pub use orientation::{OrientationMap, RotationColumns};
use resolve::{Header, Sigma};

/// Most columns a range in a column list may span (`1-65536`): far more than any export has,
/// and a bound on what a list allocates before the file's own width is known (a range
/// `1-100000000000` was 2.4 TB of column numbers). Columns beyond the file's width are refused
/// when the file is read.
pub const MAX_COLUMNS: usize = 1 << 16;

/// Smallest non-zero standard deviation (metres): a nanometre, below every device's noise, the
/// bound `calibrate --sigma` and the canonical reader hold sigmas to (`dh_calib::MIN_SIGMA`,
/// issue 30; 0 is floored at [`SIGMA_FLOOR`] instead).
const MIN_SIGMA_METRES: f64 = 1e-9;

/// Largest standard deviation in the file's length unit, as `calibrate --sigma` takes it
/// (1 m in mm, 1 km in m; `dh_workflows::ranges::MAX_SIGMA`); in metres it must also be within the
/// canonical reader's 100 m.
pub const MAX_SIGMA_IN_UNIT: f64 = 1000.0;

/// A column by 1-based number or by header name.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ColumnRef {
    /// 1-based column number.
    Number(usize),
    /// A header name (needs a header line).
    Name(String),
}

impl ColumnRef {
    /// Parses a list of columns: names or 1-based numbers and ranges (`1-6`), separated by
    /// commas (`1-6`, `q1,q2,q3`, `7,8,9`).
    ///
    /// # Errors
    /// An empty item, a column 0 or a backwards range.
    pub fn parse_list(text: &str) -> Result<Vec<ColumnRef>, String> {
        let mut out = Vec::new();
        for item in text.split(',').map(str::trim) {
            if item.is_empty() {
                return Err(format!("expected column numbers or names, found '{text}'"));
            }
            let range = item.split_once('-').and_then(|(a, b)| {
                Some((
                    a.trim().parse::<usize>().ok()?,
                    b.trim().parse::<usize>().ok()?,
                ))
            });
            match (item.parse::<usize>(), range) {
                (Ok(0), _) | (_, Some((0, _))) => {
                    return Err(format!("expected columns numbered from 1, found '{item}'"))
                }
                (Ok(n), _) => out.push(ColumnRef::Number(n)),
                (_, Some((a, b))) if b >= MAX_COLUMNS.saturating_add(a) => {
                    return Err(format!(
                        "expected a range of at most {MAX_COLUMNS} columns, found '{item}'"
                    ));
                }
                (_, Some((a, b))) if a <= b => out.extend((a..=b).map(ColumnRef::Number)),
                (_, Some(_)) => {
                    return Err(format!("expected a range low-high, found '{item}'"));
                }
                _ => out.push(ColumnRef::Name(item.to_string())),
            }
        }
        Ok(out)
    }
}

/// How the user's file is laid out (see the [module docs](self)).
#[derive(Clone, Debug, PartialEq)]
pub struct ColumnMap {
    /// The joint columns, in the model's joint order.
    pub joints: Vec<ColumnRef>,
    /// Joint names for the output, one per joint column; empty: the header's names (or
    /// `joint_1..n` without a header).
    pub joint_names: Vec<String>,
    /// The `x`, `y`, `z` columns of the measured point.
    pub point: [ColumnRef; 3],
    /// The target (reflector, marker) name column; without it every row measures target `t1`.
    pub target: Option<ColumnRef>,
    /// The isotropic standard deviation column.
    pub sigma: Option<ColumnRef>,
    /// The per-axis standard deviation columns of `x`, `y`, `z` (written as `sx`, `sy`,
    /// `sz`); not with [`ColumnMap::sigma`].
    pub sigma_axes: Option<[ColumnRef; 3]>,
    /// Rows with a joint, coordinate or sigma cell that is empty or NaN (a pose the device did
    /// not log) are left out and counted in a note, instead of refused.
    pub skip_incomplete: bool,
    /// The pose identifier column (repeats share it).
    pub config: Option<ColumnRef>,
    /// The split column (`calibration`/`train` or `validation`/`test`).
    pub set: Option<ColumnRef>,
    /// The measurement session column (a non-empty name per row; see [`crate::sessions`]):
    /// each session has its own device frame. Without it every row is in one session.
    pub session: Option<ColumnRef>,
    /// The time column (seconds, any origin; see [`crate::data::Sample::time`]): what effects
    /// of time read (`thermal_growth`). An empty cell is a row without a time.
    pub time: Option<ColumnRef>,
    /// A 6-DoF device's orientation columns ([`orientation`]); `None`: points. Needs
    /// [`ColumnMap::sigma`] (the position sigma weighs the angle against the position).
    pub orientation: Option<OrientationMap>,
    /// Separator; `None` detects `,`, `;` or tab from the first data line.
    pub delimiter: Option<char>,
    /// Whether the first non-comment line is a header.
    pub header: bool,
    /// Metres per unit of the points, sigmas and prismatic joints (1e-3 for mm).
    pub length_scale: f64,
    /// Radians per unit of the revolute joints (π/180 for degrees).
    pub angle_scale: f64,
    /// Joints (by output name) that are prismatic.
    pub prismatic: Vec<String>,
}

/// The separator of `text`: the first of `,` `;` tab that occurs most on its first non-comment
/// line.
fn detect_delimiter(text: &str) -> char {
    let line = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'))
        .unwrap_or("");
    [',', ';', '\t']
        .into_iter()
        .max_by_key(|d| (line.matches(*d).count(), usize::from(*d == ',')))
        .unwrap_or(',')
}

/// Reads `text` laid out as `map` says (see the [module docs](self)), with the warnings a
/// reader should see: standard deviations of 0 floored at [`SIGMA_FLOOR`], as the canonical
/// reader floors them; rows left out as incomplete ([`ColumnMap::skip_incomplete`]); rows that
/// are identical copies of an earlier row, counted once (an export that repeats a record
/// would otherwise show repeated measurements without scatter).
///
/// # Errors
/// A [`DataError`] naming the line and column: no data rows, a column that is not there (by
/// number or name) or that two header columns name, a column in two roles, joint names the
/// measurement CSV cannot hold, a prismatic joint that is not a joint, a cell that is not a
/// finite number ([`DataError::Incomplete`] for an empty or NaN one), a standard deviation
/// that is negative or outside its range, values that look like another unit, an unknown
/// split, a name with control or bidi characters.
pub fn parse(text: &str, map: &ColumnMap) -> Result<(Measurements, Vec<String>), DataError> {
    let delimiter = map.delimiter.unwrap_or_else(|| detect_delimiter(text));
    let mut rows = Records::new(text, delimiter, true).peekable();
    let header = if map.header {
        let h = rows.next().ok_or(DataError::Empty {
            found: "an empty file",
        })??;
        for (k, field) in h.fields.iter().enumerate() {
            check_name(field, h.line, &format!("{}", k + 1))?;
        }
        Some(h)
    } else {
        if let Some(Err(_)) = rows.peek() {
            if let Some(Err(e)) = rows.next() {
                return Err(e);
            }
        }
        None
    };
    let width = match (&header, rows.peek()) {
        (Some(h), _) => h.fields.len(),
        (None, Some(Ok(r))) => r.fields.len(),
        _ => 0,
    };
    let header = Header {
        record: header.as_ref(),
        width,
        line: header.as_ref().map_or(1, |h| h.line),
    };
    let cols = map.resolve(&header)?;
    let column_name = |c: usize| header.name(c);
    let mut m = Measurements {
        sessions: Vec::new(),
        joint_names: cols.joint_names.clone(),
        targets: Vec::new(),
        samples: Vec::new(),
    };
    let (mut zero_sigmas, mut skipped) = (Vec::new(), Vec::new());
    for row in rows {
        let row = row?;
        let line = row.line;
        if row.fields.len() != width {
            return Err(DataError::Format {
                line,
                expected: format!("{width} fields"),
                found: format!("{}", row.fields.len()),
            });
        }
        let cell = |c: usize| row.fields[c].as_str();
        // A pose the device did not log: an empty or NaN number cell.
        let numeric = cols.joints.iter().chain(&cols.point).copied().chain(
            cols.sigma
                .columns()
                .into_iter()
                .filter(|_| !matches!(cols.sigma, Sigma::Isotropic(c) if cell(c).is_empty())),
        );
        if let Some(c) = numeric.into_iter().find(|&c| missing(cell(c))) {
            if map.skip_incomplete {
                skipped.push((line, column_name(c)));
                continue;
            }
            return Err(DataError::Incomplete {
                line,
                column: column_name(c),
                text: cell(c).to_string(),
            });
        }
        let mut q = Vec::with_capacity(cols.joints.len());
        for (&c, &prismatic) in cols.joints.iter().zip(&cols.prismatic) {
            let v = number(cell(c), line, &column_name(c))?;
            let (value, limit, unit) = if prismatic {
                (v * map.length_scale, MAX_METRES, "m")
            } else {
                (v * map.angle_scale, MAX_RADIANS, "rad")
            };
            if value.abs() > limit {
                return Err(DataError::Format {
                    line,
                    expected: format!(
                        "a joint value within {limit:.1} {unit} in column '{}' (is the angle unit right?)",
                        column_name(c)
                    ),
                    found: format!("'{}'", cell(c)),
                });
            }
            q.push(value);
        }
        let mut p = Vector3::zeros();
        for (k, &c) in cols.point.iter().enumerate() {
            p[k] = number(cell(c), line, &column_name(c))? * map.length_scale;
            if p[k].abs() > MAX_METRES {
                return Err(DataError::Format {
                    line,
                    expected: format!(
                        "a coordinate within {MAX_METRES} m in column '{}' (is the length unit right?)",
                        column_name(c)
                    ),
                    found: format!("'{}'", cell(c)),
                });
            }
        }
        let target_name = match cols.target {
            Some(c) => {
                check_name(cell(c), line, &column_name(c))?;
                cell(c).to_string()
            }
            None => "t1".to_string(),
        };
        let target = match m.targets.iter().position(|t| *t == target_name) {
            Some(k) => k,
            None => {
                m.targets.push(target_name);
                m.targets.len() - 1
            }
        };
        let mut sigma_of = |c: usize| -> Result<f64, DataError> {
            let s = sigma_value(cell(c), line, &column_name(c), map.length_scale)?;
            if s == 0.0 {
                if zero_sigmas.last() != Some(&line) {
                    zero_sigmas.push(line);
                }
                return Ok(SIGMA_FLOOR);
            }
            Ok(s)
        };
        let sigma = match cols.sigma {
            Sigma::Isotropic(c) if !cell(c).is_empty() => Some(Vector3::repeat(sigma_of(c)?)),
            Sigma::PerAxis([a, b, c]) => {
                Some(Vector3::new(sigma_of(a)?, sigma_of(b)?, sigma_of(c)?))
            }
            _ => None,
        };
        let config = match cols.config {
            Some(c) if !cell(c).is_empty() => {
                check_name(cell(c), line, &column_name(c))?;
                Some(cell(c).into())
            }
            _ => None,
        };
        let split = match cols.set {
            Some(c) if !cell(c).is_empty() => {
                parse_split(cell(c)).ok_or_else(|| DataError::Format {
                    line,
                    expected: format!(
                        "calibration, train, validation or test in column '{}'",
                        column_name(c)
                    ),
                    found: format!("'{}'", cell(c)),
                })?
            }
            _ => Split::Calibration,
        };
        let session = match cols.session {
            None => 0,
            Some(c) if cell(c).is_empty() => {
                return Err(DataError::Format {
                    line,
                    expected: format!("a session name in column '{}'", column_name(c)),
                    found: "an empty cell".into(),
                })
            }
            Some(c) => {
                check_name(cell(c), line, &column_name(c))?;
                match m.sessions.iter().position(|s| s == cell(c)) {
                    Some(k) => k,
                    None => {
                        m.sessions.push(cell(c).to_string());
                        m.sessions.len() - 1
                    }
                }
            }
        };
        let orientation = match &cols.orientation {
            Some(o) => o.cells(line, &cell, &column_name, map.angle_scale)?,
            None => None,
        };
        if let (Some(_), None) = (&orientation, sigma) {
            return Err(DataError::Format {
                line,
                expected: format!(
                    "a standard deviation in column {} for a row with an orientation",
                    cols.sigma
                        .columns()
                        .iter()
                        .map(|&c| format!("'{}'", column_name(c)))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
                found: "an empty cell".into(),
            });
        }
        let time = match cols.time {
            Some(c) if !cell(c).is_empty() => {
                let text = cell(c);
                let t: f64 = text.trim().parse().map_err(|_| DataError::Format {
                    line,
                    expected: format!("a time in seconds in column '{}'", column_name(c)),
                    found: format!("'{text}'"),
                })?;
                if !t.is_finite() {
                    return Err(DataError::Format {
                        line,
                        expected: format!("a finite time in column '{}'", column_name(c)),
                        found: format!("'{text}'"),
                    });
                }
                Some(t)
            }
            _ => None,
        };
        m.samples.push(Sample {
            time,
            orientation: orientation.map(Box::new),
            session,
            q: q.into(),
            target,
            point: p,
            sigma,
            config,
            split,
            line,
            socket: None,
        });
    }
    let copies = copies::drop_copies(&mut m.samples);
    if m.samples.is_empty() {
        return Err(DataError::Empty {
            found: match (skipped.first(), map.header) {
                (Some(_), _) => "only incomplete rows",
                (None, true) => "only a header",
                (None, false) => "an empty file",
            },
        });
    }
    let mut notes = Vec::new();
    if let Some(first) = zero_sigmas.first() {
        notes.push(format!(
            "{} sample(s) give a standard deviation of 0 (first at line {first}; a rounded export?): floored at {SIGMA_FLOOR:e} m",
            zero_sigmas.len()
        ));
    }
    if let Some((line, column)) = skipped.first() {
        notes.push(format!(
            "{} incomplete row(s) left out (an empty or NaN number: a pose the device did not log; the first at line {line}, column '{column}')",
            skipped.len()
        ));
    }
    if let Some((line, of)) = copies.first() {
        notes.push(format!(
            "{} row(s) are identical copies of an earlier row, each record counted once (the first: line {line}, a copy of line {of}; an export that repeats a record, not repeated measurements)",
            copies.len()
        ));
    }
    Ok((m, notes))
}

/// Whether a number cell holds no value: empty, or NaN as exports write it.
fn missing(cell: &str) -> bool {
    cell.is_empty() || cell.eq_ignore_ascii_case("nan") || cell.eq_ignore_ascii_case("-nan")
}

/// A finite number from a cell, the error naming the line and column.
fn number(text: &str, line: usize, column: &str) -> Result<f64, DataError> {
    crate::csv::number(text, line, column)
}

/// A standard deviation cell in metres: 0 (the caller floors it), or within
/// [`MIN_SIGMA_METRES`] m and [`MAX_SIGMA_IN_UNIT`] in the file's unit and at most 100 m.
///
/// # Errors
/// [`DataError::Format`] naming the range, or a cell that is not a finite number.
fn sigma_value(text: &str, line: usize, column: &str, scale: f64) -> Result<f64, DataError> {
    let s = number(text, line, column)?;
    if s == 0.0 {
        return Ok(0.0);
    }
    let metres = s * scale;
    if !(0.0..=MAX_SIGMA_IN_UNIT).contains(&s) || !(MIN_SIGMA_METRES..=MAX_METRES).contains(&metres)
    {
        return Err(DataError::Format {
            line,
            expected: format!(
                "a standard deviation of 0 (floored) or in [{:e} m, {MAX_SIGMA_IN_UNIT}] in the length unit (at most {MAX_METRES} m) in column '{column}'",
                MIN_SIGMA_METRES
            ),
            found: format!("'{text}'"),
        });
    }
    Ok(metres)
}

#[cfg(test)]
mod tests;
