//! Reading a sheet's text: YAML or JSON into a [`SheetDoc`] (syntax, nesting, what the text
//! looks like when it is no sheet), and a document into a [`Sheet`] in SI units (metres,
//! radians).

use dh_calib::import::{too_deep_at, MAX_FLOW_DEPTH};
use dh_core::DhTable;

use super::rows::{check_mimics, coupled_of, effects_of, pose_of, row_of};
use super::{Sheet, SheetDoc};
use crate::error::{Result, SheetError};
use crate::text::escape;

/// Parses the text of a sheet (serial or tree) into its document, refusing what no sheet may
/// hold (see [`Sheet::parse`]); the numbers are checked when it is converted.
///
/// # Errors
/// Syntax errors with line and column, unknown or missing keys, nesting too deep.
pub fn parse_doc(text: &str, origin: &str) -> Result<SheetDoc> {
    // A byte-order mark is no part of the first key (URDF and JSON readers skip it too).
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    {
        if text.trim().is_empty() {
            return Err(SheetError::Empty {
                origin: origin.into(),
            });
        }
        check_nesting(text, origin)?;
        not_a_sheet(text, origin)?;
        // JSON is read by a JSON reader, which streams: the YAML reader holds every event of
        // the document at once (about 5 kB per row, 500 MB for 100 000 joints). A document it
        // refuses goes on to the YAML reader, whose messages say where and what.
        if text.trim_start().starts_with('{') {
            if let Ok(doc) = serde_json::from_str::<SheetDoc>(text) {
                return Ok(doc);
            }
        } else if text.len() >= super::parts::PARTS_MIN_BYTES {
            if let Some(doc) = super::parts::read_in_parts(text) {
                return Ok(doc);
            }
        }
        let doc: SheetDoc = serde_yaml::from_str(text).map_err(|e| {
            let mut message = shortened(&e.to_string());
            let location = match e.location() {
                Some(l) => {
                    // serde_yaml repeats the position in its message; say it once, up front.
                    let said = format!(" at line {} column {}", l.line(), l.column());
                    if let Some(k) = message.find(&said) {
                        message.replace_range(k..k + said.len(), "");
                    }
                    // For a repeated key serde_yaml points at the start of the mapping: point
                    // at the repetition instead.
                    let (line, column) = duplicate_key_at(text, &message, l.index())
                        .unwrap_or((l.line(), l.column()));
                    Some((line, column))
                }
                None => None,
            };
            SheetError::Syntax {
                origin: origin.into(),
                location,
                message,
            }
        })?;
        Ok(doc)
    }
}

/// Longest error message quoted from the YAML parser: it may quote a whole document (a CSV file
/// reads as one long string), and one line of it says enough.
const MAX_MESSAGE: usize = 200;

/// `message` cut at [`MAX_MESSAGE`] characters, saying so.
fn shortened(message: &str) -> String {
    match message.char_indices().nth(MAX_MESSAGE) {
        Some((k, _)) => format!("{}... (cut)", &message[..k]),
        None => message.to_string(),
    }
}

/// Refuses a file whose first line of content cannot start a sheet (a mapping in YAML, `{` in
/// JSON), saying what it looks like and quoting that line (at most 80 characters), instead of the
/// YAML parser's "expected struct" with the whole file quoted.
fn not_a_sheet(text: &str, origin: &str) -> Result<()> {
    let Some((k, first)) = text.lines().enumerate().find(|(_, l)| {
        let t = l.trim();
        !t.is_empty() && !t.starts_with('#') && t != "---" && !t.starts_with('%')
    }) else {
        return Ok(());
    };
    let t = first.trim();
    if t.starts_with('{') || t.contains(": ") || t.ends_with(':') {
        return Ok(());
    }
    let looks = if t.contains(',') || t.contains(';') || t.contains('\t') {
        "a CSV table (a measurement file?)"
    } else if t.starts_with('<') {
        "XML (a URDF?)"
    } else {
        "text without YAML keys"
    };
    let quoted: String = t.chars().take(80).collect();
    let cut = if t.chars().count() > 80 { "..." } else { "" };
    Err(SheetError::NotASheet {
        origin: origin.into(),
        line: k + 1,
        looks,
        found: format!("{}{cut}", escape(&quoted)),
    })
}

/// Where the key named in serde's "duplicate field `KEY`" message is given the second time at
/// or after byte `from` (the mapping's start): (line, column), both from 1. `None` for other
/// messages or when the key is not found as a key (`KEY:` after a line start, `-`, `{` or `,`).
pub(super) fn duplicate_key_at(text: &str, message: &str, from: usize) -> Option<(usize, usize)> {
    let key = message
        .split_once("duplicate field `")?
        .1
        .split_once('`')?
        .0;
    let mut seen = 0;
    let mut k = from.min(text.len());
    while let Some(found) = text.get(k..)?.find(key) {
        let at = k + found;
        let before = text[..at].trim_end_matches([' ', '\t', '"', '\'']);
        let after = text[at + key.len()..].trim_start_matches(['"', '\'', ' ', '\t']);
        let starts_key = before.is_empty() || before.ends_with(['\n', '-', '{', ',']);
        if starts_key && after.starts_with(':') {
            seen += 1;
            if seen == 2 {
                let line = text[..at].matches('\n').count() + 1;
                let column = text[..at]
                    .rsplit('\n')
                    .next()
                    .map_or(0, |l| l.chars().count())
                    + 1;
                return Some((line, column));
            }
        }
        k = at + key.len();
    }
    None
}

/// Refuses flow collections nested deeper than [`MAX_FLOW_DEPTH`] (a sheet needs three
/// levels; libyaml's scanner takes time quadratic in the depth), in one linear pass.
///
/// # Errors
/// [`SheetError::TooDeep`], naming the line.
pub fn check_nesting(text: &str, origin: &str) -> Result<()> {
    if let Some(line) = too_deep_at(text) {
        return Err(SheetError::TooDeep {
            origin: origin.into(),
            line,
            max: MAX_FLOW_DEPTH,
        });
    }
    Ok(())
}

impl SheetDoc {
    /// Converts to SI units and checks the numbers (see [`Sheet::parse`]).
    ///
    /// # Errors
    /// As [`Sheet::parse`].
    pub fn into_sheet(self, origin: &str) -> Result<Sheet> {
        if let Some(branches) = &self.branches {
            return Err(SheetError::TreeNotChain {
                origin: origin.into(),
                branches: branches.iter().map(|b| b.name.clone()).collect(),
            });
        }
        if self.inertials.is_some() {
            return Err(SheetError::InertialsNotTree {
                origin: origin.into(),
            });
        }
        if self.joints.is_empty() {
            return Err(SheetError::NoJoints {
                origin: origin.into(),
            });
        }
        check_labels(
            [
                ("robot", self.robot.as_deref()),
                ("source", self.source.as_deref()),
                ("base_link", self.base_link.as_deref()),
                ("tip_link", self.tip_link.as_deref()),
            ],
            origin,
        )?;
        let (lu, au) = (self.length_unit, self.angle_unit);
        let mut warnings = Vec::new();
        let mut rows = Vec::with_capacity(self.joints.len());
        let mut seen = std::collections::HashSet::new();
        for j in &self.joints {
            if !seen.insert(j.name.as_str()) {
                return Err(SheetError::DuplicateJoint {
                    origin: origin.into(),
                    joint: j.name.clone(),
                });
            }
            rows.push(row_of(j, lu, au, origin, &mut warnings)?);
        }
        check_mimics(&rows, origin, &mut warnings)?;
        let table = DhTable {
            convention: self.convention.into(),
            base: pose_of(self.base.as_ref(), lu, au, origin, "base")
                .map_err(|e| transform("base", e))?,
            tool: pose_of(self.tool.as_ref(), lu, au, origin, "tool")
                .map_err(|e| transform("tool", e))?,
            rows,
        };
        let coupled = coupled_of(self.coupled.as_ref(), &table.rows, origin)?;
        let effects = effects_of(self.effects, origin)?;
        Ok(Sheet {
            coupled,
            effects,
            table,
            has_base: self.base.is_some(),
            has_tool: self.tool.is_some(),
            robot: self.robot,
            source: self.source,
            length_unit: self.length_unit,
            angle_unit: self.angle_unit,
            warnings,
        })
    }
}

/// Refuses a control or bidi character in a sheet's labels (`robot`, `source`, `base_link`,
/// `tip_link`; `source` may hold line feeds and tabs), which every table printed from the sheet
/// would carry to a terminal.
///
/// # Errors
/// [`SheetError::BadLabel`] naming the key.
pub(crate) fn check_labels<'a>(
    labels: impl IntoIterator<Item = (&'static str, Option<&'a str>)>,
    origin: &str,
) -> Result<()> {
    for (key, text) in labels {
        let Some(text) = text else { continue };
        if let Some(problem) = crate::text::label_problem(text, key == "source") {
            return Err(SheetError::BadLabel {
                origin: origin.into(),
                key,
                problem,
            });
        }
    }
    Ok(())
}

/// A serial sheet's bad `base` or `tool`, said as such.
fn transform(which: &'static str, error: SheetError) -> SheetError {
    SheetError::Transform {
        which,
        error: Box::new(error),
    }
}
