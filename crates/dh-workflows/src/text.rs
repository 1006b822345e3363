//! Names in text: the one escaping rule for every name a message or table quotes ([`escape`],
//! and [`json_pretty`] for JSON), the cut of long names and paths in messages ([`cut`],
//! [`shorten`]), names that differ only in Unicode normalisation ([`normalisation_note`]), and
//! the capped width of a text table's name column.

use std::borrow::Cow;

pub use dh_calib::csv::is_spoofing;

/// Widest padded column of a text table, in characters. Longer names are printed whole and
/// push the row's later cells to the right; the width itself never grows past this (a format
/// width of 65 536 or more panics in `std::fmt`).
pub const MAX_COLUMN: usize = 48;

/// The width of a text column holding `names`: the longest name's length in characters, at
/// least `min`, at most [`MAX_COLUMN`].
pub fn column_width<'a>(names: impl IntoIterator<Item = &'a str>, min: usize) -> usize {
    names
        .into_iter()
        .map(|n| escape(n).chars().count())
        .max()
        .unwrap_or(0)
        .max(min)
        .min(MAX_COLUMN)
}

/// A name as the tool prints it: every control or bidi character ([`is_spoofing`]) written as
/// `\u{XX}` (Rust's escape), everything else as it is. Names the readers accept never hold
/// such characters, so they print unchanged; this is for names that reach a message before or
/// without a reader's check (command-line arguments, the name a refusal quotes).
pub fn escape(name: &str) -> Cow<'_, str> {
    if !name.chars().any(is_spoofing) {
        return Cow::Borrowed(name);
    }
    let mut s = String::with_capacity(name.len() + 8);
    for c in name.chars() {
        if is_spoofing(c) {
            s.push_str(&format!("\\u{{{:x}}}", u32::from(c)));
        } else {
            s.push(c);
        }
    }
    Cow::Owned(s)
}

/// What is wrong with a name that a file or option gives (a joint, target, link or column), or
/// `None`: empty, or holding a control or bidi character (found at character `k`, counted
/// from 1). The URDF reader refuses the same characters.
pub fn name_problem(name: &str) -> Option<String> {
    if name.trim().is_empty() {
        return Some("expected a name, found an empty one".into());
    }
    let (k, c) = name.chars().enumerate().find(|(_, c)| is_spoofing(*c))?;
    Some(format!(
        "'{}': expected a name without control or bidi characters, found U+{:04X} at character {}",
        escape(name),
        u32::from(c),
        k + 1
    ))
}

/// Longest name or path a message quotes whole, in characters; longer ones are [`cut`].
pub const MAX_QUOTED: usize = 160;

/// `text` as a message quotes it when it may be long (a path, a `--tip`, a name from a file):
/// at most [`MAX_QUOTED`] characters, the middle replaced by `…(N characters cut)…` so that
/// both ends, which tell paths and numbered names apart, stay. Short text is returned as it is.
pub fn cut(text: &str) -> Cow<'_, str> {
    cut_to(text, MAX_QUOTED)
}

/// [`cut`] with a bound of `max` characters kept (at least 2: one at each end).
pub fn cut_to(text: &str, max: usize) -> Cow<'_, str> {
    let max = max.max(2);
    // Byte length first: most text is short, and counting characters is then not needed.
    if text.len() <= max || text.chars().count() <= max {
        return Cow::Borrowed(text);
    }
    let n = text.chars().count();
    let head = max / 2;
    let tail = max - head;
    let start: String = text.chars().take(head).collect();
    let end: String = text.chars().skip(n - tail).collect();
    Cow::Owned(format!("{start}…({} characters cut)…{end}", n - max))
}

/// A name or path as a message quotes it: [`escape`]d, then [`cut`].
pub fn quote(name: &str) -> String {
    cut(&escape(name)).into_owned()
}

/// `message` with every run of non-blank characters longer than [`MAX_QUOTED`] [`cut`]: the last
/// guard of a message that quotes a huge path or name without [`quote`] (a message made by
/// another library, an argument echoed by clap).
pub fn shorten(message: &str) -> Cow<'_, str> {
    let long = |w: &str| w.len() > MAX_QUOTED && w.chars().count() > MAX_QUOTED;
    if !message.split(char::is_whitespace).any(long) {
        return Cow::Borrowed(message);
    }
    let mut out = String::with_capacity(4 * MAX_QUOTED);
    let mut word = String::new();
    let flush = |word: &mut String, out: &mut String| {
        out.push_str(&cut(word));
        word.clear();
    };
    for c in message.chars() {
        if c.is_whitespace() {
            flush(&mut word, &mut out);
            out.push(c);
        } else {
            word.push(c);
        }
    }
    flush(&mut word, &mut out);
    Cow::Owned(out)
}

/// A path as messages name an output: `<stdout>` for `-`, else the file name (as
/// [`crate::input::display_name`] names inputs, `<stdin>` for `-`), [`quote`]d.
pub fn output_name(path: &str) -> String {
    if path == "-" {
        return "<stdout>".into();
    }
    let name = std::path::Path::new(path)
        .file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.to_string());
    quote(&name)
}

/// The code points of `name`, as `U+0063 U+0301` (at most [`MAX_QUOTED`] of them, then `…`).
pub fn code_points(name: &str) -> String {
    let mut s: Vec<String> = name
        .chars()
        .take(MAX_QUOTED)
        .map(|c| format!("U+{:04X}", u32::from(c)))
        .collect();
    if name.chars().nth(MAX_QUOTED).is_some() {
        s.push("…".into());
    }
    s.join(" ")
}

/// When `given` differs from one of `known` only in Unicode normalisation (`é` as one code point,
/// NFC, against `e` and a combining accent, NFD), a sentence saying so with both spellings' code
/// points, since the two print alike; `None` otherwise (also when `given` is among `known`).
pub fn normalisation_note<'a>(
    given: &str,
    known: impl IntoIterator<Item = &'a str>,
) -> Option<String> {
    use unicode_normalization::UnicodeNormalization;
    let nfc: String = given.nfc().collect();
    let mut twin = None;
    for k in known {
        if k == given {
            return None;
        }
        if twin.is_none() && k.len() <= 4 * given.len() + 16 && k.nfc().eq(nfc.chars()) {
            twin = Some(k);
        }
    }
    let twin = twin?;
    Some(format!(
        "'{}' and '{}' differ only in Unicode normalisation: the given name is {} ({}), the \
         file's is {} ({})",
        quote(given),
        quote(twin),
        normal_form(given),
        code_points(given),
        normal_form(twin),
        code_points(twin)
    ))
}

/// `NFC`, `NFD` or `mixed` for a name, as [`normalisation_note`] describes it.
fn normal_form(name: &str) -> &'static str {
    use unicode_normalization::{is_nfc, is_nfd};
    match (is_nfc(name), is_nfd(name)) {
        (true, _) => "NFC",
        (false, true) => "NFD",
        _ => "neither NFC nor NFD",
    }
}

/// Serialises `value` as pretty JSON (two-space indent, as `serde_json::to_string_pretty`) with
/// every control or bidi character ([`is_spoofing`]) written as a `\uXXXX` escape: the
/// document reads back to the same strings, and printing it cannot drive a terminal or reorder
/// what it shows (serde_json escapes only U+0000 to U+001F by itself).
///
/// # Errors
/// As `serde_json::to_string_pretty` (a map with non-string keys, a failing `Serialize`).
pub fn json_pretty<T: serde::Serialize + ?Sized>(value: &T) -> serde_json::Result<String> {
    json_with(value, Safe(serde_json::ser::PrettyFormatter::new()))
}

/// [`json_pretty`] on one line (as `serde_json::to_string`), for JSON Lines.
///
/// # Errors
/// As [`json_pretty`].
pub fn json_line<T: serde::Serialize + ?Sized>(value: &T) -> serde_json::Result<String> {
    json_with(value, Safe(serde_json::ser::CompactFormatter))
}

fn json_with<T: serde::Serialize + ?Sized, F: serde_json::ser::Formatter>(
    value: &T,
    formatter: F,
) -> serde_json::Result<String> {
    let mut buf = Vec::with_capacity(128);
    let mut ser = serde_json::Serializer::with_formatter(&mut buf, formatter);
    value.serialize(&mut ser)?;
    // serde_json writes UTF-8 only; a failure here would be its bug, said as an error.
    String::from_utf8(buf).map_err(|e| serde::ser::Error::custom(e.to_string()))
}

/// A JSON formatter that escapes [`is_spoofing`] characters inside strings and delegates the
/// rest (the layout of arrays and objects) to the formatter it wraps; numbers, booleans and
/// null keep serde_json's stateless defaults.
struct Safe<F>(F);

impl<F: serde_json::ser::Formatter> serde_json::ser::Formatter for Safe<F> {
    fn write_string_fragment<W: ?Sized + std::io::Write>(
        &mut self,
        writer: &mut W,
        fragment: &str,
    ) -> std::io::Result<()> {
        let mut rest = fragment;
        while let Some((at, c)) = rest.char_indices().find(|(_, c)| is_spoofing(*c)) {
            writer.write_all(&rest.as_bytes()[..at])?;
            // Every spoofing character lies in the Basic Multilingual Plane: one \u escape.
            write!(writer, "\\u{:04x}", u32::from(c))?;
            rest = &rest[at + c.len_utf8()..];
        }
        writer.write_all(rest.as_bytes())
    }
    fn begin_array<W: ?Sized + std::io::Write>(&mut self, w: &mut W) -> std::io::Result<()> {
        self.0.begin_array(w)
    }
    fn end_array<W: ?Sized + std::io::Write>(&mut self, w: &mut W) -> std::io::Result<()> {
        self.0.end_array(w)
    }
    fn begin_array_value<W: ?Sized + std::io::Write>(
        &mut self,
        w: &mut W,
        first: bool,
    ) -> std::io::Result<()> {
        self.0.begin_array_value(w, first)
    }
    fn end_array_value<W: ?Sized + std::io::Write>(&mut self, w: &mut W) -> std::io::Result<()> {
        self.0.end_array_value(w)
    }
    fn begin_object<W: ?Sized + std::io::Write>(&mut self, w: &mut W) -> std::io::Result<()> {
        self.0.begin_object(w)
    }
    fn end_object<W: ?Sized + std::io::Write>(&mut self, w: &mut W) -> std::io::Result<()> {
        self.0.end_object(w)
    }
    fn begin_object_key<W: ?Sized + std::io::Write>(
        &mut self,
        w: &mut W,
        first: bool,
    ) -> std::io::Result<()> {
        self.0.begin_object_key(w, first)
    }
    fn end_object_key<W: ?Sized + std::io::Write>(&mut self, w: &mut W) -> std::io::Result<()> {
        self.0.end_object_key(w)
    }
    fn begin_object_value<W: ?Sized + std::io::Write>(&mut self, w: &mut W) -> std::io::Result<()> {
        self.0.begin_object_value(w)
    }
    fn end_object_value<W: ?Sized + std::io::Write>(&mut self, w: &mut W) -> std::io::Result<()> {
        self.0.end_object_value(w)
    }
}

/// What is wrong with a free-text label of a file (a sheet's `robot` or `source`, a URDF's robot
/// name), or `None`: a control or bidi character ([`is_spoofing`]) other than a line feed or
/// tab where `multiline`. A label may be empty; a name may not (see [`name_problem`]).
pub fn label_problem(label: &str, multiline: bool) -> Option<String> {
    let (k, c) = label
        .chars()
        .enumerate()
        .find(|&(_, c)| is_spoofing(c) && !(multiline && matches!(c, '\n' | '\t')))?;
    Some(format!(
        "'{}': expected text without control or bidi characters, found U+{:04X} at character {}",
        quote(label),
        u32::from(c),
        k + 1
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_text_is_cut_in_the_middle_with_the_count() {
        let long = format!("/a{}/robot.urdf", "x".repeat(100_000));
        let c = cut(&long);
        assert!(c.chars().count() < MAX_QUOTED + 40, "{}", c.len());
        assert!(
            c.starts_with("/axxx") && c.ends_with("xx/robot.urdf"),
            "{c}"
        );
        let n = long.chars().count() - MAX_QUOTED;
        assert!(c.contains(&format!("…({n} characters cut)…")), "{c}");
        assert!(matches!(cut("short"), Cow::Borrowed("short")));
        // Characters, not bytes: a cut never splits a code point.
        let wide = "é".repeat(1000);
        assert_eq!(
            cut_to(&wide, 10),
            format!("ééééé…(990 characters cut)…ééééé")
        );
    }

    #[test]
    fn only_long_words_of_a_message_are_shortened() {
        let m = format!("tip link '{}': not found", "t".repeat(5000));
        let s = shorten(&m);
        assert!(s.len() < 300 && s.starts_with("tip link 'ttt") && s.ends_with("tt': not found"));
        assert!(matches!(shorten("a short message"), Cow::Borrowed(_)));
    }

    #[test]
    fn outputs_are_named_stdout() {
        assert_eq!(output_name("-"), "<stdout>");
        assert_eq!(output_name("dir/x.csv"), "x.csv");
    }

    #[test]
    fn names_differing_in_normalisation_are_told_apart() {
        let (nfc, nfd) = ("caf\u{e9}", "cafe\u{301}");
        let note = normalisation_note(nfc, ["base", nfd]).unwrap();
        assert!(
            note.contains("differ only in Unicode normalisation"),
            "{note}"
        );
        assert!(note.contains("NFC (U+0063 U+0061 U+0066 U+00E9)"), "{note}");
        assert!(
            note.contains("NFD (U+0063 U+0061 U+0066 U+0065 U+0301)"),
            "{note}"
        );
        assert_eq!(normalisation_note(nfc, [nfc, nfd]), None);
        assert_eq!(normalisation_note("cafe", [nfd]), None);
    }

    #[test]
    fn json_escapes_spoofing_characters_and_reads_back() {
        let names = vec!["a\u{1b}[2J", "b\u{202e}c", "d\u{85}\u{7f}", "plain é"];
        let pretty = json_pretty(&names).unwrap();
        assert_eq!(
            pretty,
            serde_json::to_string_pretty(&names)
                .unwrap()
                .replace('\u{202e}', "\\u202e")
                .replace('\u{85}', "\\u0085")
                .replace('\u{7f}', "\\u007f")
        );
        assert!(
            !pretty.chars().any(|c| c != '\n' && is_spoofing(c)),
            "{pretty}"
        );
        let back: Vec<String> = serde_json::from_str(&pretty).unwrap();
        assert_eq!(back, names);
        let line = json_line(&names).unwrap();
        assert!(!line.contains('\n') && line.contains("b\\u202ec"), "{line}");
        let back: Vec<String> = serde_json::from_str(&line).unwrap();
        assert_eq!(back, names);
    }

    #[test]
    fn labels_allow_line_feeds_only_where_multiline() {
        assert_eq!(label_problem("UR5 (CB3)", false), None);
        assert_eq!(label_problem("", false), None);
        assert!(label_problem("a\u{202e}b", false)
            .unwrap()
            .contains("U+202E at character 2"));
        assert_eq!(label_problem("line\nnext", true), None);
        assert!(label_problem("line\nnext", false).is_some());
        assert!(label_problem("\u{1b}[2J", true).unwrap().contains("U+001B"));
    }
}
