//! The canonical measurement CSV: reading ([`parse_measurements`]) and writing
//! ([`write_measurements`]).
//!
//! # Layout
//! One header line, then one measured point per line:
//!
//! ```text
//! # comment lines start with '#'; blank lines are skipped
//! joint_1,joint_2,x,y,z,target,config,sigma,set
//! 0.1,-0.25,1.2034,0.4411,0.9873,A,7,1e-5,train
//! ```
//!
//! - one column per joint, named exactly as the model's joints: radians for revolute joints,
//!   metres for prismatic ones (other units through [`CsvOptions`]);
//! - `x`, `y`, `z`: the measured position of a target on the tool, in the measuring device's
//!   own frame, metres;
//! - optional `target`: which reflector or marker was measured (a name; targets are numbered in
//!   order of first appearance; without the column every row measures one target called
//!   [`DEFAULT_TARGET`]);
//! - optional `config`: pose identifier, rows with the same id repeat one pose (an empty cell
//!   means none);
//! - optional `sigma` (isotropic) or `sx`, `sy`, `sz` (per axis): the point's standard deviation
//!   in the length unit (an empty cell means unknown);
//! - optional `set`: `train`/`calibration` or `test`/`validation` (an empty cell or no column
//!   means calibration);
//! - optional `socket`: a contact sample (see [`crate::socket`]): the target sat in the unknown
//!   fixed point of this name, and the row's `x`, `y`, `z` cells are empty (the columns may be
//!   absent when every row is a contact); with it, optional `partner`, `distance` and
//!   `distance_sigma`: another socket at a known centre-to-centre distance from this one and
//!   its standard deviation, in the length unit (both needed when `partner` is given);
//! - optional `session`: the measurement session (a non-empty name): the device was moved
//!   between sessions, each has its own device frame (see [`crate::sessions`]); without the
//!   column every row is in one session.
//!
//! Other columns are ignored. Cells may be double-quoted (`""` inside quotes is one quote).
//! Column names and cells are trimmed of surrounding spaces.

use std::fmt;
use std::str::FromStr;

use nalgebra::Vector3;
use thiserror::Error;

use crate::data::{Measurements, Sample, Socket, SocketDistance, Split};

/// Name of the single target of a file without a `target` column.
pub const DEFAULT_TARGET: &str = "tip";

/// A revolute joint value beyond this many radians (four turns) is taken for degrees.
pub(crate) const MAX_PLAUSIBLE_RADIANS: f64 = 8.0 * std::f64::consts::PI;
/// A point coordinate beyond this many metres is taken for millimetres: no laser tracker,
/// camera system or total station used for arm calibration measures 100 m away.
pub(crate) const MAX_PLAUSIBLE_METRES: f64 = 100.0;

/// Is `c` a character that changes how a terminal or table shows the text around it: a control
/// character (C0, DEL, C1) or a bidirectional override, embedding, isolate or mark (U+202A to
/// U+202E, U+2066 to U+2069, U+200E, U+200F, U+061C)? Names holding one are refused: printed,
/// they can hide or reorder what a report says (`t1` followed by U+202E reads backwards).
pub fn is_spoofing(c: char) -> bool {
    c.is_control()
        || matches!(
            c,
            '\u{202A}'..='\u{202E}' | '\u{2066}'..='\u{2069}' | '\u{200E}' | '\u{200F}' | '\u{061C}'
        )
}

/// A name cell (`target`, `config`, `socket`, a header column) without [`is_spoofing`]
/// characters.
pub(crate) fn check_name(text: &str, line: usize, column: &str) -> Result<(), DataError> {
    match text.chars().enumerate().find(|(_, c)| is_spoofing(*c)) {
        None => Ok(()),
        Some((k, c)) => Err(DataError::Format {
            line,
            expected: format!(
                "a name without control or bidi characters in column '{}'",
                column.escape_default()
            ),
            found: format!("U+{:04X} at character {}", u32::from(c), k + 1),
        }),
    }
}

/// Everything that can be wrong with a measurement file: the message names the line, the column
/// and the text found.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum DataError {
    /// Nothing but comments and blank lines, or a header without data rows.
    #[error("expected a header line and at least one data row, found {found}")]
    Empty {
        /// What was there instead ("an empty file", "only a header").
        found: &'static str,
    },
    /// The header lacks a column for some of the model's joints.
    #[error(
        "line {line}: missing joint column(s) {}; the header has {}",
        list(.missing),
        list(.found)
    )]
    MissingJoints {
        /// Header line.
        line: usize,
        /// Joint names without a column.
        missing: Vec<String>,
        /// The columns the header has.
        found: Vec<String>,
    },
    /// The header lacks `x`, `y` or `z`.
    #[error("line {line}: missing point column '{column}'; the header has {}", list(.found))]
    MissingCoordinate {
        /// Header line.
        line: usize,
        /// `x`, `y` or `z`.
        column: &'static str,
        /// The columns the header has.
        found: Vec<String>,
    },
    /// A joint of the model has the name of a column the format reserves (`x`, `socket`, ...):
    /// its column could not be told from that one.
    #[error(
        "line {line}: joint '{joint}' has the name of a reserved column ({}); rename the joint in the model",
        RESERVED_COLUMNS.join(", ")
    )]
    ReservedJointName {
        /// Header line.
        line: usize,
        /// The joint.
        joint: String,
    },
    /// Two header columns share a name.
    #[error("line {line}: duplicate column '{column}'")]
    DuplicateColumn {
        /// Header line.
        line: usize,
        /// The repeated name.
        column: String,
    },
    /// Two columns that say the same thing in different ways (`sigma` and `sx`).
    #[error("line {line}: columns '{first}' and '{second}' conflict; give one of them")]
    ConflictingColumns {
        /// Header line.
        line: usize,
        /// One column.
        first: String,
        /// The other.
        second: String,
    },
    /// A row with more or fewer cells than the header.
    #[error("line {line}: expected {expected} fields, found {found}")]
    FieldCount {
        /// The row's line.
        line: usize,
        /// Fields in the header.
        expected: usize,
        /// Fields in the row.
        found: usize,
    },
    /// A cell that should be a number is not one.
    #[error("line {line}, column '{column}': expected a number, found '{text}'")]
    NotANumber {
        /// The row's line.
        line: usize,
        /// Column name.
        column: String,
        /// The cell's text.
        text: String,
    },
    /// A cell holds NaN or infinity.
    #[error("line {line}, column '{column}': expected a finite number, found '{text}'")]
    NonFinite {
        /// The row's line.
        line: usize,
        /// Column name.
        column: String,
        /// The cell's text.
        text: String,
    },
    /// A standard deviation that is zero or negative.
    #[error("line {line}, column '{column}': expected a standard deviation > 0, found '{text}'")]
    BadSigma {
        /// The row's line.
        line: usize,
        /// Column name.
        column: String,
        /// The cell's text.
        text: String,
    },
    /// A `set` cell that names no known split.
    #[error(
        "line {line}, column 'set': expected train, calibration, test or validation, found '{text}'"
    )]
    UnknownSet {
        /// The row's line.
        line: usize,
        /// The cell's text.
        text: String,
    },
    /// A value far outside the range of the declared unit.
    #[error("line {line}, column '{column}': {value} {unit} {hint}")]
    SuspiciousUnit {
        /// The row's line.
        line: usize,
        /// Column name.
        column: String,
        /// The value in the declared unit.
        value: f64,
        /// The declared unit (`rad`, `m`).
        unit: &'static str,
        /// What it looks like and what to do.
        hint: &'static str,
    },
    /// A quoted cell without its closing quote.
    #[error("line {line}: unterminated quoted field")]
    UnterminatedQuote {
        /// The line where the quote opened.
        line: usize,
    },
    /// A dataset layout found something other than it expects.
    #[error("line {line}: expected {expected}, found {found}")]
    Format {
        /// The line (1-based) in the file.
        line: usize,
        /// What the layout needs there.
        expected: String,
        /// What is there.
        found: String,
    },
    /// The content does not fit the layout where no single line is to blame: files of one
    /// dataset that disagree in row counts, a structured document missing a field.
    #[error("expected {expected}, found {found}")]
    Content {
        /// What should hold.
        expected: String,
        /// What does.
        found: String,
    },
    /// A file a dataset layout needs was not given.
    #[error("layout '{layout}' needs file '{file}', which was not given; given: {}", list(.given))]
    MissingFile {
        /// Layout name.
        layout: &'static str,
        /// The missing file.
        file: &'static str,
        /// The names of the files given.
        given: Vec<String>,
    },
    /// An error inside one file of a multi-file dataset.
    #[error("{file}: {source}")]
    InFile {
        /// File name.
        file: String,
        /// The error.
        source: Box<DataError>,
    },
}

/// `'a', 'b', 'c'`, or `none`.
fn list(items: &[String]) -> String {
    if items.is_empty() {
        return "none".into();
    }
    items
        .iter()
        .map(|s| format!("'{s}'"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Unit of lengths in a file: point coordinates, standard deviations and prismatic joints.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum LengthUnit {
    /// Metres (the canonical unit).
    #[default]
    Metre,
    /// Millimetres.
    Millimetre,
}

impl LengthUnit {
    /// `value` (in this unit) in metres; millimetres are divided by 1000, which rounds
    /// correctly (`7 mm` is the double nearest `0.007 m`).
    pub fn to_metres(self, value: f64) -> f64 {
        match self {
            LengthUnit::Metre => value,
            LengthUnit::Millimetre => value / 1000.0,
        }
    }
}

impl fmt::Display for LengthUnit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            LengthUnit::Metre => "m",
            LengthUnit::Millimetre => "mm",
        })
    }
}

impl FromStr for LengthUnit {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "m" => Ok(LengthUnit::Metre),
            "mm" => Ok(LengthUnit::Millimetre),
            other => Err(format!("expected length unit 'm' or 'mm', found '{other}'")),
        }
    }
}

/// Unit of revolute joint values in a file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum AngleUnit {
    /// Radians (the canonical unit).
    #[default]
    Radian,
    /// Degrees.
    Degree,
}

impl AngleUnit {
    /// `value` (in this unit) in radians.
    pub fn to_radians(self, value: f64) -> f64 {
        match self {
            AngleUnit::Radian => value,
            AngleUnit::Degree => value.to_radians(),
        }
    }
}

impl fmt::Display for AngleUnit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            AngleUnit::Radian => "rad",
            AngleUnit::Degree => "deg",
        })
    }
}

impl FromStr for AngleUnit {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "rad" => Ok(AngleUnit::Radian),
            "deg" => Ok(AngleUnit::Degree),
            other => Err(format!(
                "expected angle unit 'rad' or 'deg', found '{other}'"
            )),
        }
    }
}

/// Units of a measurement file; values are converted to metres and radians on reading.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct CsvOptions {
    /// Unit of `x`, `y`, `z`, of `sigma`/`sx`/`sy`/`sz` and of prismatic joint columns.
    pub length_unit: LengthUnit,
    /// Unit of revolute joint columns.
    pub angle_unit: AngleUnit,
    /// Names of the prismatic joints (their columns are lengths, not angles); every other joint
    /// column is an angle.
    pub prismatic: Vec<String>,
}

/// One CSV record: its first line (1-based) and its cells, unquoted and trimmed.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Record {
    pub line: usize,
    pub fields: Vec<String>,
}

/// Splits `text` into CSV records with `delimiter`. Double-quoted cells may hold delimiters,
/// `""` and line breaks. With `comments`, lines starting with `#` (after spaces) are skipped;
/// blank lines are always skipped. A leading byte-order mark is dropped.
///
/// # Errors
/// [`DataError::UnterminatedQuote`] for a quote that never closes.
pub(crate) fn records(
    text: &str,
    delimiter: char,
    comments: bool,
) -> Result<Vec<Record>, DataError> {
    Records::new(text, delimiter, comments).collect()
}

/// The records of [`records`], one at a time: a reader of millions of rows keeps one row's
/// cells at a time, not all of them (2 000 000 rows: about 0.8 GB less).
pub(crate) struct Records<'a> {
    lines: std::iter::Peekable<std::iter::Enumerate<std::str::Split<'a, char>>>,
    delimiter: char,
    comments: bool,
}

impl<'a> Records<'a> {
    /// The records of `text` (see [`records`]).
    pub(crate) fn new(text: &'a str, delimiter: char, comments: bool) -> Self {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        Records {
            lines: text.split('\n').enumerate().peekable(),
            delimiter,
            comments,
        }
    }
}

impl Iterator for Records<'_> {
    type Item = Result<Record, DataError>;

    fn next(&mut self) -> Option<Self::Item> {
        let delimiter = self.delimiter;
        loop {
            let (index, raw) = self.lines.next()?;
            let line = index + 1;
            let raw = raw.strip_suffix('\r').unwrap_or(raw);
            let trimmed = raw.trim();
            if trimmed.is_empty() || self.comments && trimmed.starts_with('#') {
                continue;
            }
            let mut fields = Vec::new();
            let mut cell = Cell::default();
            let mut current = raw.to_string();
            loop {
                let mut chars = current.chars().peekable();
                while let Some(c) = chars.next() {
                    if cell.open {
                        if c == '"' {
                            if chars.peek() == Some(&'"') {
                                chars.next();
                                cell.text.push('"');
                            } else {
                                cell.open = false;
                                cell.closed_at = Some(cell.text.len());
                            }
                        } else {
                            cell.text.push(c);
                        }
                    } else if c == '"' && cell.closed_at.is_none() && cell.text.trim().is_empty() {
                        cell.text.clear();
                        cell.open = true;
                    } else if c == delimiter {
                        fields.push(cell.finish());
                    } else {
                        cell.text.push(c);
                    }
                }
                if !cell.open {
                    break;
                }
                // A quoted cell runs on over the line break.
                match self.lines.next() {
                    Some((_, next)) => {
                        cell.text.push('\n');
                        current = next.strip_suffix('\r').unwrap_or(next).to_string();
                    }
                    None => return Some(Err(DataError::UnterminatedQuote { line })),
                }
            }
            fields.push(cell.finish());
            return Some(Ok(Record { line, fields }));
        }
    }
}

/// A cell being read.
#[derive(Default)]
struct Cell {
    text: String,
    /// Inside double quotes.
    open: bool,
    /// Length of the text when the closing quote came: what follows it is dropped.
    closed_at: Option<usize>,
}

impl Cell {
    /// The cell's value: a quoted cell exactly as quoted, a bare one trimmed. Resets the cell.
    fn finish(&mut self) -> String {
        let value = match self.closed_at {
            Some(len) => self.text[..len].to_string(),
            None => self.text.trim().to_string(),
        };
        *self = Cell::default();
        value
    }
}

/// Parses a finite number from a cell.
///
/// # Errors
/// [`DataError::NotANumber`] or [`DataError::NonFinite`], naming `line` and `column`.
pub(crate) fn number(text: &str, line: usize, column: &str) -> Result<f64, DataError> {
    let value: f64 = text.trim().parse().map_err(|_| DataError::NotANumber {
        line,
        column: column.into(),
        text: text.into(),
    })?;
    if !value.is_finite() {
        return Err(DataError::NonFinite {
            line,
            column: column.into(),
            text: text.into(),
        });
    }
    Ok(value)
}

/// Columns of the canonical CSV that are not joints: a model's joint may not take these names.
pub const RESERVED_COLUMNS: [&str; 15] = [
    "x",
    "y",
    "z",
    "target",
    "config",
    "sigma",
    "sx",
    "sy",
    "sz",
    "set",
    "socket",
    "partner",
    "distance",
    "distance_sigma",
    "session",
];

/// What is wrong with a list of joint names that a dataset gives itself, as the columns of the
/// canonical CSV would have them: an empty name, a repeated one, a reserved column's name
/// ([`RESERVED_COLUMNS`]) or a control character. `None` when the list is fine.
pub fn joint_name_problem(names: &[String]) -> Option<String> {
    for (i, name) in names.iter().enumerate() {
        if name.trim().is_empty() {
            return Some(format!("an empty name at position {}", i + 1));
        }
        if names[..i].contains(name) {
            return Some(format!("'{name}' twice"));
        }
        if RESERVED_COLUMNS.contains(&name.as_str()) {
            return Some(format!("'{name}', the name of a reserved column"));
        }
        if let Some(c) = name.chars().find(|c| is_spoofing(*c)) {
            return Some(format!(
                "'{}' with the control or bidi character U+{:04X}",
                name.escape_debug(),
                u32::from(c)
            ));
        }
    }
    None
}

/// Column indices of the canonical header.
struct Columns {
    joints: Vec<usize>,
    /// Absent only when there is a `socket` column.
    xyz: Option<[usize; 3]>,
    socket: Option<usize>,
    partner: Option<[usize; 3]>,
    target: Option<usize>,
    config: Option<usize>,
    sigma: Sigma,
    set: Option<usize>,
    session: Option<usize>,
}

enum Sigma {
    None,
    Isotropic(usize),
    PerAxis([usize; 3]),
}

fn header_columns(header: &Record, joint_names: &[String]) -> Result<Columns, DataError> {
    let line = header.line;
    let names = &header.fields;
    if let Some(joint) = joint_names
        .iter()
        .find(|j| RESERVED_COLUMNS.contains(&j.as_str()))
    {
        return Err(DataError::ReservedJointName {
            line,
            joint: joint.clone(),
        });
    }
    for (i, name) in names.iter().enumerate() {
        if names[..i].contains(name) {
            return Err(DataError::DuplicateColumn {
                line,
                column: name.clone(),
            });
        }
    }
    let find = |name: &str| names.iter().position(|n| n == name);
    let missing: Vec<String> = joint_names
        .iter()
        .filter(|j| find(j).is_none())
        .cloned()
        .collect();
    if !missing.is_empty() {
        return Err(DataError::MissingJoints {
            line,
            missing,
            found: names.clone(),
        });
    }
    let joints = joint_names.iter().filter_map(|j| find(j)).collect();
    let socket = find("socket");
    // A file of contacts only may leave out the point columns.
    let any_xyz = ["x", "y", "z"].iter().any(|c| find(c).is_some());
    let xyz = if socket.is_none() || any_xyz {
        let mut xyz = [0; 3];
        for (slot, column) in xyz.iter_mut().zip(["x", "y", "z"]) {
            *slot = find(column).ok_or_else(|| DataError::MissingCoordinate {
                line,
                column,
                found: names.clone(),
            })?;
        }
        Some(xyz)
    } else {
        None
    };
    let partner = match (socket, find("partner")) {
        (Some(_), Some(p)) => {
            let mut cols = [p, 0, 0];
            for (slot, column) in cols[1..].iter_mut().zip(["distance", "distance_sigma"]) {
                *slot = find(column).ok_or_else(|| DataError::MissingCoordinate {
                    line,
                    column,
                    found: names.clone(),
                })?;
            }
            Some(cols)
        }
        _ => None,
    };
    let per_axis = [find("sx"), find("sy"), find("sz")];
    let sigma = match (find("sigma"), per_axis) {
        (None, [None, None, None]) => Sigma::None,
        (Some(i), [None, None, None]) => Sigma::Isotropic(i),
        (None, [Some(a), Some(b), Some(c)]) => Sigma::PerAxis([a, b, c]),
        (Some(_), _) => {
            let other = ["sx", "sy", "sz"]
                .into_iter()
                .zip(per_axis)
                .find_map(|(n, i)| i.map(|_| n))
                .unwrap_or("sx");
            return Err(DataError::ConflictingColumns {
                line,
                first: "sigma".into(),
                second: other.into(),
            });
        }
        (None, _) => {
            let missing = ["sx", "sy", "sz"]
                .into_iter()
                .zip(per_axis)
                .find_map(|(n, i)| i.is_none().then_some(n))
                .unwrap_or("sx");
            return Err(DataError::MissingCoordinate {
                line,
                column: missing,
                found: names.clone(),
            });
        }
    };
    Ok(Columns {
        joints,
        xyz,
        socket,
        partner,
        target: find("target"),
        config: find("config"),
        sigma,
        set: find("set"),
        session: find("session"),
    })
}

/// Reads a measurement set in the canonical CSV layout (see the [module docs](self)).
///
/// `joint_names` are the model's joints: each needs a column, and every sample's `q` follows
/// their order. Values are converted to metres and radians with `opts`. Frames: points are in
/// the measuring device's frame. `Sample::line` is the row's 1-based line in `text`.
///
/// # Errors
/// A [`DataError`] naming the line and column for: no header or no data rows, a missing joint
/// or point column, duplicate or conflicting columns, a row with the wrong number of fields, a
/// cell that is not a finite number, a standard deviation < 0 (0 is floored at [`SIGMA_FLOOR`]), an unknown `set` value, and
/// values that look like another unit (a revolute joint beyond 8π rad, a coordinate beyond
/// 100 m).
pub fn parse_measurements(
    text: &str,
    joint_names: &[String],
    opts: &CsvOptions,
) -> Result<Measurements, DataError> {
    parse_measurements_noting(text, joint_names, opts).map(|(m, _)| m)
}

/// Standard deviation (metres) given to a point whose `sigma` cell is 0: trackers export
/// coordinates rounded to 1 µm, and some write a 0 for "exact". A zero would weight the point
/// infinitely; 1 µm is the rounding step, a conservative bound on the rounding error (whose
/// standard deviation is the step over √12).
pub const SIGMA_FLOOR: f64 = 1e-6;

/// [`parse_measurements`], with the warnings a reader should see: standard deviations of 0
/// floored at [`SIGMA_FLOOR`] (how many, and the first line).
///
/// # Errors
/// As [`parse_measurements`].
pub fn parse_measurements_noting(
    text: &str,
    joint_names: &[String],
    opts: &CsvOptions,
) -> Result<(Measurements, Vec<String>), DataError> {
    let mut zero_sigmas: Vec<usize> = Vec::new();
    // Row by row: the rows' cells are never all held at once.
    let mut rows = Records::new(text, ',', true).peekable();
    let header = rows.next().ok_or(DataError::Empty {
        found: "an empty file",
    })??;
    let header = &header;
    if rows.peek().is_none() {
        return Err(DataError::Empty {
            found: "only a header",
        });
    }
    for (k, field) in header.fields.iter().enumerate() {
        check_name(field, header.line, &format!("{}", k + 1))?;
    }
    let cols = header_columns(header, joint_names)?;
    let length = |v: f64| opts.length_unit.to_metres(v);
    let revolute: Vec<bool> = joint_names
        .iter()
        .map(|j| !opts.prismatic.contains(j))
        .collect();

    let mut m = Measurements {
        sessions: Vec::new(),
        joint_names: joint_names.to_vec(),
        targets: Vec::new(),
        samples: Vec::new(),
    };
    let expected = header.fields.len();
    // Largest magnitude accepted so far per column: a value far beyond it that is also beyond
    // the unit's plausible range means the file mixes units (an earlier row in the other one).
    let mut largest = vec![0.0f64; expected];
    let mixed = |largest: &[f64], col: usize, value: f64, ratio: f64| {
        largest
            .get(col)
            .is_some_and(|&m| m > 0.0 && value.abs() > ratio * m)
    };
    for row in rows {
        let row = row?;
        let line = row.line;
        if row.fields.len() != expected {
            return Err(DataError::FieldCount {
                line,
                expected,
                found: row.fields.len(),
            });
        }
        let cell = |i: usize| row.fields[i].as_str();
        let name = |i: usize| header.fields[i].as_str();

        let mut q = Vec::with_capacity(joint_names.len());
        for (&col, &revolute) in cols.joints.iter().zip(&revolute) {
            let value = number(cell(col), line, name(col))?;
            if revolute
                && opts.angle_unit == AngleUnit::Radian
                && value.abs() > MAX_PLAUSIBLE_RADIANS
            {
                return Err(DataError::SuspiciousUnit {
                    line,
                    column: name(col).into(),
                    value,
                    unit: "rad",
                    // Degrees are 57 times radians.
                    hint: if mixed(&largest, col, value, 20.0) {
                        "looks like degrees, but the rows above look like radians: the file \
                         mixes units"
                    } else {
                        "looks like degrees; pass --angle-unit deg"
                    },
                });
            }
            if let Some(m) = largest.get_mut(col) {
                *m = m.max(value.abs());
            }
            let si = if revolute {
                opts.angle_unit.to_radians(value)
            } else {
                length(value)
            };
            // Whatever the unit: a joint value past four turns or 100 m is no pose (and a
            // huge one would lose every digit in the trigonometry).
            let cap = if revolute {
                MAX_PLAUSIBLE_RADIANS
            } else {
                MAX_PLAUSIBLE_METRES
            };
            if si.abs() > cap {
                return Err(DataError::Format {
                    line,
                    expected: format!(
                        "a joint value within {cap:.1} {} in column '{}'",
                        if revolute { "rad" } else { "m" },
                        name(col)
                    ),
                    found: format!("'{}'", cell(col)),
                });
            }
            q.push(si);
        }

        let socket = match cols.socket.map(cell).filter(|c| !c.is_empty()) {
            None => None,
            Some(socket) => {
                let partner = match cols.partner {
                    Some([p, d, ds]) if !cell(p).is_empty() => {
                        let distance = length(number(cell(d), line, name(d))?);
                        let sigma = length(number(cell(ds), line, name(ds))?);
                        if !(distance > 0.0 && sigma > 0.0) {
                            return Err(DataError::Format {
                                line,
                                expected: "a distance and its standard deviation > 0".into(),
                                found: format!("{} and {}", cell(d), cell(ds)),
                            });
                        }
                        Some(SocketDistance {
                            socket: cell(p).to_string(),
                            distance,
                            sigma,
                        })
                    }
                    _ => None,
                };
                Some(Socket {
                    name: socket.to_string(),
                    partner,
                })
            }
        };
        let mut point = Vector3::zeros();
        let xyz_cols = match (cols.xyz, &socket) {
            (Some(c), None) => c.to_vec(),
            (Some(c), Some(_)) => {
                if let Some(&col) = c.iter().find(|&&col| !cell(col).is_empty()) {
                    return Err(DataError::Format {
                        line,
                        expected: format!(
                            "an empty '{}' in a contact row (socket given)",
                            name(col)
                        ),
                        found: format!("'{}'", cell(col)),
                    });
                }
                Vec::new()
            }
            (None, None) => {
                return Err(DataError::Format {
                    line,
                    expected: "a socket name (the file has no x, y, z columns)".into(),
                    found: "an empty 'socket' cell".into(),
                })
            }
            (None, Some(_)) => Vec::new(),
        };
        for (k, &col) in xyz_cols.iter().enumerate() {
            let value = number(cell(col), line, name(col))?;
            if opts.length_unit == LengthUnit::Metre && value.abs() > MAX_PLAUSIBLE_METRES {
                return Err(DataError::SuspiciousUnit {
                    line,
                    column: name(col).into(),
                    value,
                    unit: "m",
                    hint: if mixed(&largest, col, value, 100.0) {
                        "looks like millimetres, but the rows above look like metres: the file \
                         mixes units"
                    } else {
                        "looks like millimetres; pass --length-unit mm"
                    },
                });
            }
            if let Some(m) = largest.get_mut(col) {
                *m = m.max(value.abs());
            }
            point[k] = length(value);
            if point[k].abs() > MAX_PLAUSIBLE_METRES {
                return Err(DataError::Format {
                    line,
                    expected: format!(
                        "a coordinate within {MAX_PLAUSIBLE_METRES} m in column '{}'",
                        name(col)
                    ),
                    found: format!("'{}'", cell(col)),
                });
            }
        }

        let mut sigma_cell = |col: usize| -> Result<Option<f64>, DataError> {
            let text = cell(col);
            if text.is_empty() {
                return Ok(None);
            }
            let value = number(text, line, name(col))?;
            if value == 0.0 {
                if zero_sigmas.last() != Some(&line) {
                    zero_sigmas.push(line);
                }
                return Ok(Some(SIGMA_FLOOR));
            }
            if value < 0.0 {
                return Err(DataError::BadSigma {
                    line,
                    column: name(col).into(),
                    text: text.into(),
                });
            }
            if length(value) > MAX_PLAUSIBLE_METRES {
                return Err(DataError::Format {
                    line,
                    expected: format!(
                        "a standard deviation within {MAX_PLAUSIBLE_METRES} m in column '{}'",
                        name(col)
                    ),
                    found: format!("'{text}'"),
                });
            }
            Ok(Some(length(value)))
        };
        let sigma = match cols.sigma {
            Sigma::None => None,
            Sigma::Isotropic(col) => sigma_cell(col)?.map(|s| Vector3::new(s, s, s)),
            Sigma::PerAxis(c) => match (sigma_cell(c[0])?, sigma_cell(c[1])?, sigma_cell(c[2])?) {
                (Some(a), Some(b), Some(c)) => Some(Vector3::new(a, b, c)),
                (None, None, None) => None,
                _ => {
                    return Err(DataError::Format {
                        line,
                        expected: "all of sx, sy, sz or none".into(),
                        found: "some of them empty".into(),
                    })
                }
            },
        };

        for col in [cols.target, cols.config, cols.socket, cols.session]
            .into_iter()
            .flatten()
        {
            check_name(cell(col), line, name(col))?;
        }
        if let Some([p, _, _]) = cols.partner {
            check_name(cell(p), line, name(p))?;
        }
        let target_name = cols.target.map_or(DEFAULT_TARGET, cell);
        let target = match m.targets.iter().position(|t| t == target_name) {
            Some(i) => i,
            None => {
                m.targets.push(target_name.to_string());
                m.targets.len() - 1
            }
        };
        let config = cols
            .config
            .map(cell)
            .filter(|c| !c.is_empty())
            .map(str::to_string);
        let split = match cols.set.map(cell) {
            None | Some("") => Split::Calibration,
            Some(text) => parse_split(text).ok_or_else(|| DataError::UnknownSet {
                line,
                text: text.into(),
            })?,
        };
        let session = match cols.session {
            None => 0,
            Some(col) if cell(col).is_empty() => {
                return Err(DataError::Format {
                    line,
                    expected: "a session name in column 'session'".into(),
                    found: "an empty cell".into(),
                })
            }
            Some(col) => match m.sessions.iter().position(|t| t == cell(col)) {
                Some(i) => i,
                None => {
                    m.sessions.push(cell(col).to_string());
                    m.sessions.len() - 1
                }
            },
        };
        m.samples.push(Sample {
            session,
            q,
            target,
            point,
            sigma,
            config,
            split,
            line,
            socket,
        });
    }
    let mut notes = Vec::new();
    if let Some(first) = zero_sigmas.first() {
        notes.push(format!(
            "{} sample(s) give a standard deviation of 0 (first at line {first}; a rounded export?): floored at {SIGMA_FLOOR:e} m",
            zero_sigmas.len()
        ));
    }
    Ok((m, notes))
}

pub(crate) fn parse_split(text: &str) -> Option<Split> {
    match text.to_ascii_lowercase().as_str() {
        "train" | "calibration" => Some(Split::Calibration),
        "test" | "validation" => Some(Split::Validation),
        _ => None,
    }
}

/// Writes a measurement set in the canonical CSV layout: metres, radians, points in the device
/// frame, numbers in Rust's shortest round-trip form, so that [`parse_measurements`] with the
/// same joint names and default options gives back the same set (except `Sample::line`, which
/// becomes the line in the written text).
///
/// Columns: the joints, `x,y,z`, `target`; `config` when any sample has one; `sigma` when every
/// known standard deviation is isotropic, else `sx,sy,sz`; `set` when any sample is for
/// validation; `socket` when any sample is a contact, with `partner,distance,distance_sigma`
/// when any socket has a partner (contact rows leave `x,y,z` empty); `session` when the set
/// names sessions. Targets are written by name, so a target that no sample uses is not kept, and the
/// targets come back numbered in order of first use.
pub fn write_measurements(m: &Measurements) -> String {
    let any_config = m.samples.iter().any(|s| s.config.is_some());
    let sigmas: Vec<&Vector3<f64>> = m.samples.iter().filter_map(|s| s.sigma.as_ref()).collect();
    let any_sigma = !sigmas.is_empty();
    let isotropic = sigmas.iter().all(|s| s.x == s.y && s.y == s.z);
    let any_validation = m.samples.iter().any(|s| s.split == Split::Validation);
    let any_socket = m.samples.iter().any(|s| s.socket.is_some());
    let any_partner = m
        .samples
        .iter()
        .any(|s| s.socket.as_ref().is_some_and(|c| c.partner.is_some()));

    let mut out = String::from(
        "# urdf-dh measurements: joints in rad (m for prismatic), x,y,z in m in the device frame\n",
    );
    let mut header: Vec<String> = m.joint_names.iter().map(|n| quote(n)).collect();
    header.extend(["x", "y", "z", "target"].map(String::from));
    if any_config {
        header.push("config".into());
    }
    if any_sigma {
        if isotropic {
            header.push("sigma".into());
        } else {
            header.extend(["sx", "sy", "sz"].map(String::from));
        }
    }
    if any_validation {
        header.push("set".into());
    }
    if any_socket {
        header.push("socket".into());
    }
    if any_partner {
        header.extend(["partner", "distance", "distance_sigma"].map(String::from));
    }
    let any_session = !m.sessions.is_empty();
    if any_session {
        header.push("session".into());
    }
    out.push_str(&header.join(","));
    out.push('\n');

    for s in &m.samples {
        let mut cells: Vec<String> = s.q.iter().map(|v| format!("{v:?}")).collect();
        match s.socket {
            Some(_) => cells.extend([String::new(), String::new(), String::new()]),
            None => cells.extend(s.point.iter().map(|v| format!("{v:?}"))),
        }
        let target = m
            .targets
            .get(s.target)
            .map_or(DEFAULT_TARGET, String::as_str);
        cells.push(quote(target));
        if any_config {
            cells.push(s.config.as_deref().map(quote).unwrap_or_default());
        }
        if any_sigma {
            match (&s.sigma, isotropic) {
                (Some(v), true) => cells.push(format!("{:?}", v.x)),
                (Some(v), false) => cells.extend(v.iter().map(|c| format!("{c:?}"))),
                (None, true) => cells.push(String::new()),
                (None, false) => cells.extend([String::new(), String::new(), String::new()]),
            }
        }
        if any_validation {
            cells.push(
                match s.split {
                    Split::Calibration => "calibration",
                    Split::Validation => "validation",
                }
                .into(),
            );
        }
        if any_socket {
            cells.push(
                s.socket
                    .as_ref()
                    .map(|c| quote(&c.name))
                    .unwrap_or_default(),
            );
        }
        if any_partner {
            match s.socket.as_ref().and_then(|c| c.partner.as_ref()) {
                Some(p) => cells.extend([
                    quote(&p.socket),
                    format!("{:?}", p.distance),
                    format!("{:?}", p.sigma),
                ]),
                None => cells.extend([String::new(), String::new(), String::new()]),
            }
        }
        if any_session {
            cells.push(quote(&m.session_name(s.session)));
        }
        out.push_str(&cells.join(","));
        out.push('\n');
    }
    out
}

/// Quotes a cell when it holds a delimiter, a quote, a line break, surrounding spaces, a
/// leading `#` or nothing at all would be mistaken for something else.
fn quote(s: &str) -> String {
    let needs =
        s.contains([',', '"', '\n', '\r']) || s.trim() != s || s.starts_with('#') || s.is_empty();
    if needs {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(n: &[&str]) -> Vec<String> {
        n.iter().map(|s| s.to_string()).collect()
    }

    /// Fuzzing find: a model joint named `socket` was read from the socket column and the file
    /// written back had that column twice.
    #[test]
    fn a_joint_named_like_a_reserved_column_is_refused() {
        for joint in RESERVED_COLUMNS {
            let text = format!("{joint},x,y,z\n0.0,1,2,3\n");
            let err = parse_measurements(&text, &names(&[joint]), &CsvOptions::default())
                .expect_err(joint);
            assert!(
                matches!(&err, DataError::ReservedJointName { line: 1, joint: j } if j == joint),
                "{err}"
            );
            assert!(err.to_string().contains("rename the joint"), "{err}");
        }
    }

    #[test]
    fn reads_all_optional_columns() {
        let text = "\
# a comment
j1, j2 ,x,y,z,target,config,sigma,set

0.1,0.2,1,2,3,A,c1,1e-5,train
0.1,0.2,1.5,2,3,B,c1,,test
  # indented comment
0.3,0.4,1,2,3.5,A,,2e-5,
";
        let m = parse_measurements(text, &names(&["j1", "j2"]), &CsvOptions::default()).unwrap();
        assert_eq!(m.targets, names(&["A", "B"]));
        assert_eq!(m.samples.len(), 3);
        let s = &m.samples;
        assert_eq!(s[0].q, vec![0.1, 0.2]);
        assert_eq!(s[0].point, Vector3::new(1.0, 2.0, 3.0));
        assert_eq!(s[0].sigma, Some(Vector3::new(1e-5, 1e-5, 1e-5)));
        assert_eq!(s[0].config.as_deref(), Some("c1"));
        assert_eq!(s[0].line, 4);
        assert_eq!(
            (s[1].target, s[1].split, s[1].sigma),
            (1, Split::Validation, None)
        );
        assert_eq!(
            (s[2].config.clone(), s[2].split, s[2].line),
            (None, Split::Calibration, 7)
        );
    }

    #[test]
    fn joint_columns_follow_the_models_order_not_the_files() {
        let text = "z,y,x,b,a\n3,2,1,20,10\n";
        let m = parse_measurements(text, &names(&["a", "b"]), &CsvOptions::default()).unwrap();
        assert_eq!(m.samples[0].q, vec![10.0, 20.0]);
        assert_eq!(m.samples[0].point, Vector3::new(1.0, 2.0, 3.0));
        assert_eq!(m.targets, vec![DEFAULT_TARGET.to_string()]);
    }

    #[test]
    fn converts_units_and_keeps_prismatic_joints_as_lengths() {
        let text = "rot,slide,x,y,z,sx,sy,sz\n90,250,1000,-2000,500,0.01,0.02,0.03\n";
        let opts = CsvOptions {
            length_unit: LengthUnit::Millimetre,
            angle_unit: AngleUnit::Degree,
            prismatic: names(&["slide"]),
        };
        let m = parse_measurements(text, &names(&["rot", "slide"]), &opts).unwrap();
        let s = &m.samples[0];
        assert!((s.q[0] - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        assert!((s.q[1] - 0.25).abs() < 1e-15);
        assert!((s.point - Vector3::new(1.0, -2.0, 0.5)).norm() < 1e-15);
        assert!((s.sigma.unwrap() - Vector3::new(1e-5, 2e-5, 3e-5)).norm() < 1e-18);
    }

    #[test]
    fn quoted_cells_keep_commas() {
        let text = "j,x,y,z,target\n0,1,2,3,\"left, upper\"\n";
        let m = parse_measurements(text, &names(&["j"]), &CsvOptions::default()).unwrap();
        assert_eq!(m.targets, names(&["left, upper"]));
    }

    fn err(text: &str, joints: &[&str]) -> String {
        parse_measurements(text, &names(joints), &CsvOptions::default())
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn error_messages_name_line_column_and_text() {
        assert_eq!(
            err("", &["j"]),
            "expected a header line and at least one data row, found an empty file"
        );
        assert_eq!(
            err("# only comments\n\nj,x,y,z\n", &["j"]),
            "expected a header line and at least one data row, found only a header"
        );
        assert_eq!(
            err("j1,x,y,z\n0,0,0,0\n", &["j1", "j2", "j3"]),
            "line 1: missing joint column(s) 'j2', 'j3'; the header has 'j1', 'x', 'y', 'z'"
        );
        assert_eq!(
            err("j,x,z\n0,0,0\n", &["j"]),
            "line 1: missing point column 'y'; the header has 'j', 'x', 'z'"
        );
        assert_eq!(
            err("j,x,y,z,x\n0,0,0,0,0\n", &["j"]),
            "line 1: duplicate column 'x'"
        );
        assert_eq!(
            err("j,x,y,z\n0,0,0,0\n0,0,0\n", &["j"]),
            "line 3: expected 4 fields, found 3"
        );
        assert_eq!(
            err("j,x,y,z\n0,0,abc,0\n", &["j"]),
            "line 2, column 'y': expected a number, found 'abc'"
        );
        assert_eq!(
            err("j,x,y,z\nNaN,0,0,0\n", &["j"]),
            "line 2, column 'j': expected a finite number, found 'NaN'"
        );
        assert_eq!(
            err("j,x,y,z\n0,inf,0,0\n", &["j"]),
            "line 2, column 'x': expected a finite number, found 'inf'"
        );
        assert_eq!(
            err("j,x,y,z,set\n0,0,0,0,holdout\n", &["j"]),
            "line 2, column 'set': expected train, calibration, test or validation, found 'holdout'"
        );
        assert_eq!(
            err("j,x,y,z,sigma,sy\n0,0,0,0,1,1\n", &["j"]),
            "line 1: columns 'sigma' and 'sy' conflict; give one of them"
        );
        assert_eq!(
            err("j,x,y,z,sigma\n0,0,0,0,-1\n", &["j"]),
            "line 2, column 'sigma': expected a standard deviation > 0, found '-1'"
        );
        assert_eq!(
            err("j,x,y,z,target\n0,0,0,0,\"open\n", &["j"]),
            "line 2: unterminated quoted field"
        );
    }

    #[test]
    fn suspicious_units_say_what_to_pass() {
        assert_eq!(
            err("j,x,y,z\n90,0,0,0\n", &["j"]),
            "line 2, column 'j': 90 rad looks like degrees; pass --angle-unit deg"
        );
        assert_eq!(
            err("j,x,y,z\n0,0,1250.5,0\n", &["j"]),
            "line 2, column 'y': 1250.5 m looks like millimetres; pass --length-unit mm"
        );
        // Prismatic columns are lengths: 90 (m!) is not an angle, and is not checked as one.
        let opts = CsvOptions {
            prismatic: names(&["j"]),
            ..CsvOptions::default()
        };
        assert!(parse_measurements("j,x,y,z\n90,0,0,0\n", &names(&["j"]), &opts).is_ok());
        // Rows in one unit, then rows in the other: the file mixes units.
        assert_eq!(
            err("j,x,y,z\n0,0,0.8,0\n0,0,1.2,0\n0,0,1250.5,0\n", &["j"]),
            "line 4, column 'y': 1250.5 m looks like millimetres, but the rows above look like \
             metres: the file mixes units"
        );
        assert_eq!(
            err("j,x,y,z\n1.5,0,0,0\n90,0,0,0\n", &["j"]),
            "line 3, column 'j': 90 rad looks like degrees, but the rows above look like \
             radians: the file mixes units"
        );
        // A home pose of zeros first says nothing about the unit.
        assert_eq!(
            err("j,x,y,z\n0,0,0,0\n90,0,0,0\n", &["j"]),
            "line 3, column 'j': 90 rad looks like degrees; pass --angle-unit deg"
        );
    }

    #[test]
    fn writing_round_trips_exactly() {
        let mk = |q: Vec<f64>, target, point, sigma, config: Option<&str>, split| Sample {
            session: 0,
            q,
            target,
            point,
            sigma,
            config: config.map(String::from),
            split,
            line: 0,
            socket: None,
        };
        let m = Measurements {
            sessions: Vec::new(),
            joint_names: names(&["joint 1", "a,b"]),
            targets: names(&["SMR1", "with \"quote\""]),
            samples: vec![
                mk(
                    vec![0.1 + 0.2, -1e-300],
                    0,
                    Vector3::new(1.0 / 3.0, -2.5e-7, 12.345_678_901_234_568),
                    Some(Vector3::new(1e-5, 2e-5, 3e-5)),
                    Some("pose 1"),
                    Split::Calibration,
                ),
                mk(
                    vec![std::f64::consts::PI, 0.0],
                    1,
                    Vector3::new(-0.0, 5e-324, 99.999_999_999_999_99),
                    None,
                    None,
                    Split::Validation,
                ),
            ],
        };
        let text = write_measurements(&m);
        let back = parse_measurements(&text, &m.joint_names, &CsvOptions::default()).unwrap();
        let strip = |m: &Measurements| {
            let mut m = m.clone();
            m.samples.iter_mut().for_each(|s| s.line = 0);
            m
        };
        assert_eq!(strip(&back), m);
        for (a, b) in back.samples.iter().zip(&m.samples) {
            for (x, y) in a.point.iter().zip(b.point.iter()) {
                assert_eq!(x.to_bits(), y.to_bits());
            }
        }
        assert_eq!(back.samples[1].line, 4);
    }
}
