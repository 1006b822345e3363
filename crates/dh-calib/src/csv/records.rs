//! The CSV lexer: records of trimmed cells with their line numbers (comments and blank lines
//! skipped, quoted cells), and number cells with the error naming line and column.

use super::*;

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
    pub(super) lines: std::iter::Peekable<std::iter::Enumerate<std::str::Split<'a, char>>>,
    pub(super) delimiter: char,
    pub(super) comments: bool,
    /// A text that is not UTF-8 lines as a CSV needs them ([`encoding_problem`]): the first
    /// record is this error.
    pub(super) refused: Option<DataError>,
}

impl<'a> Records<'a> {
    /// The records of `text` (see [`records`]).
    pub(crate) fn new(text: &'a str, delimiter: char, comments: bool) -> Self {
        let mut records = Self::lines_of(
            text.strip_prefix('\u{feff}').unwrap_or(text),
            delimiter,
            comments,
        );
        records.refused = encoding_problem(text);
        records
    }

    /// The records of `text` as lines of a longer text (a byte-order mark kept, line numbers
    /// counted from `text`'s first line as 1).
    pub(crate) fn lines_of(text: &'a str, delimiter: char, comments: bool) -> Self {
        Records {
            lines: text.split('\n').enumerate().peekable(),
            delimiter,
            comments,
            refused: None,
        }
    }
}

impl Iterator for Records<'_> {
    type Item = Result<Record, DataError>;

    fn next(&mut self) -> Option<Self::Item> {
        if let Some(e) = self.refused.take() {
            // Nothing after the refusal: the text is not read as lines at all.
            self.lines = "".split('\n').enumerate().peekable();
            self.lines.next();
            return Some(Err(e));
        }
        let delimiter = self.delimiter;
        loop {
            let (index, raw) = self.lines.next()?;
            let line = index + 1;
            let raw = raw.strip_suffix('\r').unwrap_or(raw);
            let trimmed = trim(raw);
            if trimmed.is_empty() || self.comments && trimmed.starts_with('#') {
                continue;
            }
            if !raw.contains('"') {
                // No quotes: the cells between delimiters, trimmed (as the loop below reads
                // them, without a copy of the line and a push per character).
                let fields = raw.split(delimiter).map(|c| trim(c).to_string()).collect();
                return Some(Ok(Record { line, fields }));
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

/// How many bytes at the start of a text [`encoding_problem`] looks at for the zero bytes of
/// UTF-16: such a text has one every other byte from the start, and a look at the start only
/// keeps a 2 GB file's check instant.
const ENCODING_PROBE_BYTES: usize = 4096;

/// Why `text` cannot be read as CSV lines, with how to convert it: UTF-16 text without a
/// byte-order mark (its ASCII characters are valid UTF-8, each followed or preceded by a zero
/// byte, which the reader would report as control characters U+0000), or line ends that are
/// CR alone (old Mac OS: the whole file one line). `None` for ordinary text.
pub(crate) fn encoding_problem(text: &str) -> Option<DataError> {
    let probe = &text.as_bytes()[..text.len().min(ENCODING_PROBE_BYTES)];
    let zeros = |parity: usize| {
        probe
            .iter()
            .skip(parity)
            .step_by(2)
            .filter(|b| **b == 0)
            .count()
    };
    let (even, odd) = (zeros(0), zeros(1));
    let half = probe.len() / 2;
    // Mostly ASCII UTF-16: zeros at nearly every odd (little-endian) or even (big-endian)
    // position, none at the other.
    if half >= 2 && (odd.max(even) * 4 >= half * 3) {
        let order = if odd > even { "le" } else { "be" };
        return Some(DataError::Encoding {
            found: format!(
                "UTF-16{} text without a byte-order mark (a zero byte beside every character)",
                order.to_uppercase()
            ),
            convert: format!("iconv -f utf-16{order} -t utf-8 FILE > FILE-utf8.csv"),
        });
    }
    if !text.contains('\n') && text.trim_end_matches('\r').contains('\r') {
        return Some(DataError::Encoding {
            found: "lines ending in CR alone (old Mac OS line ends), so the file is one line"
                .into(),
            convert: "tr '\\r' '\\n' < FILE > FILE-lf.csv".into(),
        });
    }
    None
}

/// A cell being read.
#[derive(Default)]
pub(super) struct Cell {
    pub(super) text: String,
    /// Inside double quotes.
    pub(super) open: bool,
    /// Length of the text when the closing quote came: what follows it is dropped.
    pub(super) closed_at: Option<usize>,
}

impl Cell {
    /// The cell's value: a quoted cell exactly as quoted, a bare one trimmed. Resets the cell.
    pub(super) fn finish(&mut self) -> String {
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
    let value: f64 = trim(text).parse().map_err(|_| DataError::NotANumber {
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

/// `text` without leading and trailing whitespace, as [`str::trim`] (Unicode's White_Space,
/// the vertical tab included), without decoding a character when the text starts and ends with
/// an ASCII character that is not whitespace, as nearly every cell of a large file does.
pub(crate) fn trim(text: &str) -> &str {
    let plain = |b: u8| b.is_ascii() && b != b' ' && !(b'\t'..=b'\r').contains(&b);
    match text.as_bytes() {
        [first, .., last] if plain(*first) && plain(*last) => text,
        [only] if plain(*only) => text,
        _ => text.trim(),
    }
}
