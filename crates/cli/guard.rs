//! Guards against hostile input at the command line's edges: one escaping rule for every name
//! the tool prints, one test for names the readers refuse, capped column widths for text
//! tables, and the value parsers (with their ranges) of the numeric options, which are the
//! `dh-sheet` library's ([`dh_sheet::ranges`]) so that library and Python callers get the same
//! checks.
//!
//! The ranges are documented in README.md ("Bad input"); each parser's error names the range,
//! and clap prefixes it with the option, so `--sigma 1e200` reads
//! `invalid value '1e200' for '--sigma <SIGMA>': expected a length in (0, 1000], found 1e200`.

use std::borrow::Cow;
use std::io::Write;

pub use dh_sheet::ranges::*;
pub use dh_sheet::text::{column_width, escape, is_spoofing, name_problem, MAX_COLUMN};

/// A writer that passes text on with every [`is_spoofing`] character but the line feed
/// [`escape`]d: standard error goes through it, so no message, warning or usage text can put a
/// raw escape sequence or bidi override on the user's terminal, whatever it quotes.
pub struct Escaping<'a>(pub &'a mut dyn Write);

impl Write for Escaping<'_> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        // `write!` hands over whole `str` pieces; other bytes pass as they are.
        match std::str::from_utf8(buf) {
            Ok(s) if s.chars().any(|c| c != '\n' && is_spoofing(c)) => {
                let escaped: Vec<Cow<'_, str>> = s.split('\n').map(escape).collect();
                self.0.write_all(escaped.join("\n").as_bytes())?;
                Ok(buf.len())
            }
            _ => self.0.write(buf),
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.0.flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_control_and_bidi_only() {
        assert_eq!(escape("joint_1"), "joint_1");
        assert_eq!(escape("gelenk_ä"), "gelenk_ä");
        assert_eq!(escape("a\u{1b}[31mb"), "a\\u{1b}[31mb");
        assert_eq!(escape("x\u{202e}y\0"), "x\\u{202e}y\\u{0}");
        assert!(matches!(escape("plain"), Cow::Borrowed(_)));
    }

    #[test]
    fn the_escaping_writer_keeps_lines_and_escapes_the_rest() {
        let mut buf = Vec::new();
        {
            let mut w = Escaping(&mut buf);
            let tip = "a\u{1b}[2Jb";
            writeln!(w, "tip '{tip}' not found").unwrap();
            writeln!(w, "plain").unwrap();
        }
        assert_eq!(
            String::from_utf8(buf).unwrap(),
            "tip 'a\\u{1b}[2Jb' not found\nplain\n"
        );
    }

    #[test]
    fn names_with_spoofing_characters_are_refused() {
        assert_eq!(name_problem("t1"), None);
        let p = name_problem("t\u{202e}1").unwrap();
        assert!(p.contains("U+202E at character 2"), "{p}");
        assert!(name_problem(" ").is_some());
        assert!(name_problem("a\tb").unwrap().contains("U+0009"));
    }

    #[test]
    fn widths_are_capped() {
        let long = "j".repeat(70_000);
        assert_eq!(column_width([long.as_str()], 5), MAX_COLUMN);
        assert_eq!(column_width(["ab"], 5), 5);
        assert_eq!(column_width(["joint_12"], 5), 8);
        // Formatting with the capped width does not panic and keeps the whole name.
        let w = column_width([long.as_str()], 5);
        assert_eq!(format!("{long:<w$}|").len(), 70_001);
    }
}
