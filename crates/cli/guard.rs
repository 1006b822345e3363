//! Guards against hostile input at the command line's edges: one escaping rule for every name
//! the tool prints, one test for names the readers refuse, capped column widths for text
//! tables, and the value parsers (with their ranges) of the numeric options, which are the
//! `dh-workflows` library's ([`dh_workflows::ranges`]) so that library and Python callers get the same
//! checks.
//!
//! The ranges are documented in README.md ("Bad input"); each parser's error names the range,
//! and clap prefixes it with the option, so `--sigma 1e200` reads
//! `invalid value '1e200' for '--sigma <SIGMA>': expected a length in [1e-9, 1000], found 1e200`.

use std::borrow::Cow;
use std::io::Write;

pub use dh_workflows::ranges::*;
pub use dh_workflows::text::{
    column_width, cut, escape, is_spoofing, json_line, json_pretty, name_problem, output_name,
    quote, shorten, MAX_COLUMN,
};

/// A writer that passes text on with every [`is_spoofing`] character but the line feed
/// [`escape`]d and every word longer than [`dh_workflows::text::MAX_QUOTED`] characters [`cut`]
/// ([`shorten`]): standard error goes through it, so no message, warning or usage text can put
/// a raw escape sequence or bidi override on the user's terminal, or fill it with a 100 000
/// character path, whatever it quotes.
pub struct Escaping<'a>(pub &'a mut dyn Write);

impl Write for Escaping<'_> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        // `write!` hands over whole `str` pieces (each argument's text whole); other bytes pass
        // as they are.
        let Ok(s) = std::str::from_utf8(buf) else {
            return self.0.write(buf);
        };
        let spoofing = s.chars().any(|c| c != '\n' && is_spoofing(c));
        let long = matches!(shorten(s), Cow::Owned(_));
        if !spoofing && !long {
            return self.0.write(buf);
        }
        let escaped: Vec<Cow<'_, str>> = s.split('\n').map(escape).collect();
        self.0.write_all(shorten(&escaped.join("\n")).as_bytes())?;
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.0.flush()
    }
}

/// File name extensions of formats a user may mean, each with what it names: an output option
/// whose file name ends in one of these but writes another format is refused
/// ([`svg_output`] and its siblings); an extension not listed here is the user's choice.
pub const KNOWN_EXTENSIONS: &[(&str, &str)] = &[
    ("svg", "an SVG drawing"),
    ("png", "a PNG image"),
    ("jpg", "a JPEG image"),
    ("jpeg", "a JPEG image"),
    ("pdf", "a PDF document"),
    ("eps", "a PostScript drawing"),
    ("html", "a web page"),
    ("yaml", "a YAML document"),
    ("yml", "a YAML document"),
    ("json", "a JSON document"),
    ("urdf", "a URDF"),
    ("xacro", "a xacro file"),
    ("xml", "an XML document"),
    ("csv", "a CSV table"),
    ("tsv", "a tab-separated table"),
    ("txt", "plain text"),
    ("md", "a Markdown document"),
    ("html", "an HTML page"),
    ("htm", "an HTML page"),
    ("mat", "a MATLAB file"),
    ("xlsx", "a spreadsheet"),
];

/// Accepts `path` for an output option that writes `what` when its extension is one of
/// `accepted`, is none, or names no format of [`KNOWN_EXTENSIONS`]; refuses an extension that
/// names another format (`--plot chart.png` would get an SVG under a PNG's name), naming the
/// file name it expects.
fn output_named(path: &str, what: &str, accepted: &[&str]) -> Result<String, String> {
    if path == "-" {
        return Ok(path.into());
    }
    let p = std::path::Path::new(path);
    let Some(ext) = p
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
    else {
        return Ok(path.into());
    };
    if accepted.contains(&ext.as_str()) {
        return Ok(path.into());
    }
    let Some((_, names)) = KNOWN_EXTENSIONS.iter().find(|(e, _)| *e == ext) else {
        return Ok(path.into());
    };
    let stem = p
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ends: Vec<String> = accepted.iter().map(|e| format!(".{e}")).collect();
    Err(format!(
        "expected a file name ending in {} (this option writes {what}), found '.{ext}', which \
         names {names}: name it e.g. {}.{}",
        ends.join(" or "),
        quote(&stem),
        accepted[0]
    ))
}

/// An output option that writes an SVG drawing (`--svg`, `--plot`): refused when its
/// extension names another format of [`KNOWN_EXTENSIONS`] (`--plot chart.png`), accepted
/// when it has none or an unknown one.
///
/// # Errors
/// A file name whose extension names another format.
pub fn svg_output(path: &str) -> Result<String, String> {
    output_named(path, "an SVG drawing", &["svg"])
}

/// An output option that writes an HTML page (`--report`), accepted as [`svg_output`] accepts
/// an SVG.
///
/// # Errors
/// A file name whose extension names another format.
pub fn html_output(path: &str) -> Result<String, String> {
    output_named(path, "an HTML page", &["html", "htm"])
}

/// An output option that writes a measurement or joint CSV (`--out` of `predict`,
/// `compensate`, `simulate`, `import`), accepted as [`svg_output`] accepts an SVG.
///
/// # Errors
/// A file name whose extension names another format.
pub fn csv_output(path: &str) -> Result<String, String> {
    output_named(path, "a CSV table", &["csv", "txt"])
}

/// An output option that writes a YAML sheet (`simulate --truth`), accepted as
/// [`svg_output`] accepts an SVG.
///
/// # Errors
/// A file name whose extension names another format.
pub fn yaml_output(path: &str) -> Result<String, String> {
    output_named(path, "a YAML sheet", &["yaml", "yml"])
}

/// `calibrate --out`: the calibrated model, whose format its extension chooses (`.urdf` a URDF,
/// `.json` a JSON sheet, else a YAML sheet), accepted as [`svg_output`] accepts an SVG.
///
/// # Errors
/// A file name whose extension names another format.
pub fn model_output(path: &str) -> Result<String, String> {
    output_named(
        path,
        "the calibrated model: a YAML or JSON sheet, or a URDF",
        &["yaml", "yml", "json", "urdf"],
    )
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
    fn the_escaping_writer_cuts_huge_words() {
        let mut buf = Vec::new();
        {
            let mut w = Escaping(&mut buf);
            let tip = "t".repeat(100_000);
            writeln!(w, "tip '{tip}' not found").unwrap();
        }
        let text = String::from_utf8(buf).unwrap();
        assert!(text.len() < 400, "{}", text.len());
        assert!(
            text.starts_with("tip 'ttt") && text.ends_with("tt' not found\n"),
            "{text}"
        );
        assert!(text.contains("characters cut"), "{text}");
    }

    #[test]
    fn output_extensions_of_other_formats_are_refused() {
        assert_eq!(svg_output("a/chart.svg").unwrap(), "a/chart.svg");
        assert_eq!(svg_output("-").unwrap(), "-");
        assert_eq!(svg_output("chart").unwrap(), "chart");
        assert_eq!(svg_output("chart.v2.SVG").unwrap(), "chart.v2.SVG");
        let e = svg_output("chart.png").unwrap_err();
        assert!(
            e.contains("ending in .svg") && e.contains("found '.png', which names a PNG image"),
            "{e}"
        );
        assert!(e.ends_with("name it e.g. chart.svg"), "{e}");
        assert!(csv_output("p.txt").is_ok() && csv_output("p.dat").is_ok());
        assert!(csv_output("p.yaml")
            .unwrap_err()
            .contains("writes a CSV table"));
        assert!(model_output("m.urdf").is_ok() && model_output("m.json").is_ok());
        assert!(model_output("m.txt")
            .unwrap_err()
            .contains("found '.txt', which names plain text"));
        assert!(yaml_output("t.json").is_err());
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
