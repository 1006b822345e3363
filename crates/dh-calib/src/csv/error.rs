//! Names and errors of the measurement CSV: the default target name, the reserved column names
//! ([`RESERVED_COLUMNS`]), plausibility limits of joint values (radians, metres), the check
//! that a name has no spoofing characters, and [`DataError`] with its messages.

use super::*;

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
    // Printable ASCII has no such character: most names are checked without decoding one.
    if text.bytes().all(|b| (b' '..=b'~').contains(&b)) {
        return Ok(());
    }
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
    /// A bad value in measurements given as arrays ([`Measurements::from_arrays`]).
    #[error("row {row}, column '{column}': expected {expected}, found {found}")]
    Array {
        /// The 1-based row.
        row: usize,
        /// Column name.
        column: String,
        /// What the column needs.
        expected: String,
        /// What is there.
        found: String,
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
    /// A text that is not UTF-8 lines: UTF-16 without a byte-order mark, CR-only line ends.
    #[error("expected UTF-8 text with LF or CRLF line ends, found {found}; convert it: {convert}")]
    Encoding {
        /// What the text is.
        found: String,
        /// The command that converts it (`FILE` standing for the file).
        convert: String,
    },
    /// A header that is one column holding another separator: an export for another reader
    /// (`;`-separated, tab-separated).
    #[error(
        "line {line}: expected columns separated by ',', found {} (the header is one column); \
         an export with its own separator, units and column names reads with \
         urdf-dh import --layout columns",
        separator_name(*.found)
    )]
    Separator {
        /// Header line.
        line: usize,
        /// The separator the header holds.
        found: char,
    },
    /// A cell with no value where a number is needed: empty or NaN (a value the device did
    /// not log).
    #[error("line {line}, column '{column}': expected a number, found {} (a value not logged)", if .text.is_empty() { "an empty cell".to_string() } else { format!("'{}'", .text) })]
    Incomplete {
        /// The row's line.
        line: usize,
        /// Column name.
        column: String,
        /// The cell's text.
        text: String,
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

/// A separator as a message names it.
fn separator_name(c: char) -> &'static str {
    match c {
        ';' => "';'",
        '\t' => "tabs",
        _ => "another separator",
    }
}

/// `'a', 'b', 'c'`, or `none`.
pub(super) fn list(items: &[String]) -> String {
    if items.is_empty() {
        return "none".into();
    }
    items
        .iter()
        .map(|s| format!("'{s}'"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Columns of the canonical CSV that are not joints: a model's joint may not take these names.
pub const RESERVED_COLUMNS: [&str; 21] = [
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
    "qw",
    "qx",
    "qy",
    "qz",
    "sigma_rot",
    "time",
];
