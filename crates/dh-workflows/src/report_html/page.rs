//! The page's skeleton: a self-contained XHTML-compatible HTML5 document (inline CSS, no script,
//! no external resource), the escaping of every string it quotes ([`esc`]), numbers that never
//! print NaN or infinity ([`mm`], [`sci`], [`fixed`]), and small builders for sections, cards
//! and tables.
//!
//! The markup is well-formed XML (every element closed, attributes quoted, only the five XML
//! entities and numeric references), so an XML parser reads it as well as a browser does.

use std::fmt::Write as _;

/// The page's styles: system fonts, a summary card, tables, figures; print-friendly (no
/// shadows or backgrounds in print, figures not split across pages).
const CSS: &str = r#"
:root { --ink: #1d2430; --muted: #5b6575; --line: #d8dde6; --bg: #f6f7f9; --card: #ffffff;
  --cal: #2563eb; --val: #d97706; --bad: #dc2626; --good: #15803d; --warn: #b45309; }
* { box-sizing: border-box; }
body { margin: 0; background: var(--bg); color: var(--ink);
  font: 15px/1.45 system-ui, -apple-system, "Segoe UI", Roboto, "Helvetica Neue", Arial, sans-serif; }
main { max-width: 1100px; margin: 0 auto; padding: 24px 20px 48px; }
h1 { font-size: 1.6em; margin: 0 0 4px; }
h2 { font-size: 1.25em; margin: 0 0 10px; border-bottom: 2px solid var(--line); padding-bottom: 4px; }
h3 { font-size: 1.02em; margin: 14px 0 6px; }
p.sub { color: var(--muted); margin: 0 0 18px; }
section { background: var(--card); border: 1px solid var(--line); border-radius: 8px;
  padding: 16px 18px; margin: 0 0 18px; box-shadow: 0 1px 2px rgba(0,0,0,.04); }
nav { margin: 0 0 18px; font-size: .92em; }
nav a { color: var(--cal); text-decoration: none; margin-right: 14px; white-space: nowrap; }
.verdict { border-left: 6px solid var(--muted); }
.verdict.pass { border-left-color: var(--good); }
.verdict.fail { border-left-color: var(--bad); }
.verdict.warn { border-left-color: var(--warn); }
.big { font-size: 1.35em; font-weight: 600; margin: 2px 0 8px; }
.tiles { display: flex; flex-wrap: wrap; gap: 12px; margin: 10px 0 4px; }
.tile { flex: 1 1 150px; border: 1px solid var(--line); border-radius: 6px; padding: 8px 10px; }
.tile .k { color: var(--muted); font-size: .82em; }
.tile .v { font-size: 1.2em; font-weight: 600; font-variant-numeric: tabular-nums; }
table { border-collapse: collapse; width: 100%; font-size: .9em; margin: 6px 0 10px; }
th, td { border-bottom: 1px solid var(--line); padding: 4px 8px; text-align: left; vertical-align: top; }
th { background: #eef1f5; font-weight: 600; }
td.n, th.n { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
tr:nth-child(even) td { background: #fafbfc; }
tr.taken td { background: #ecfdf3; }
tr.flag td { background: #fef2f2; }
.tag { display: inline-block; white-space: nowrap; padding: 0 6px; border-radius: 4px; font-size: .85em; background: #eef1f5; }
.tag.taken { background: #dcfce7; color: var(--good); }
.tag.rejected { background: #fee2e2; color: var(--bad); }
.muted { color: var(--muted); }
code { font-family: ui-monospace, "SFMono-Regular", Menlo, Consolas, monospace; font-size: .88em;
  word-break: break-all; }
figure { margin: 8px 0 14px; break-inside: avoid; page-break-inside: avoid; }
figcaption { color: var(--muted); font-size: .85em; margin-top: 2px; }
svg { width: 100%; height: auto; max-width: 760px; display: block; }
svg text { font: 11px system-ui, -apple-system, "Segoe UI", Roboto, Arial, sans-serif; fill: #1d2430; }
svg .grid { stroke: #e5e8ee; }
svg .axis { stroke: #5b6575; }
svg path.cal, svg path.val { fill: none; stroke-width: 4; stroke-linecap: round; }
svg path.cal { stroke: #2563eb; stroke-opacity: .6; }
svg path.val { stroke: #d97706; stroke-opacity: .75; }
svg .out { fill: none; stroke: #dc2626; stroke-width: 1.6; }
svg .rms { stroke: #1d2430; stroke-dasharray: 6 4; }
svg .floor { stroke: #15803d; stroke-dasharray: 2 3; }
svg text.outv { fill: #dc2626; stroke: none; font-weight: 600; }
.scroll { overflow-x: auto; }
svg .bar-cal { fill: #2563eb; }
svg .bar-val { fill: #d97706; }
.grid2 { display: grid; grid-template-columns: repeat(auto-fill, minmax(340px, 1fr)); gap: 4px 18px; }
ul.notes { margin: 4px 0; padding-left: 20px; }
@media print {
  body { background: #fff; font-size: 11pt; }
  main { max-width: none; padding: 0; }
  nav { display: none; }
  section { box-shadow: none; border: none; border-top: 1px solid #999; border-radius: 0;
    padding: 8px 0; break-inside: auto; }
  tr { break-inside: avoid; }
}
"#;

/// `s` escaped for HTML text and attribute values (and XML): `& < > " '`; control characters
/// other than tab and newline, which XML 1.0 does not allow, as U+FFFD.
pub fn esc(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 8);
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            '\t' | '\n' => out.push(c),
            c if c.is_control() => out.push('\u{FFFD}'),
            c => out.push(c),
        }
    }
    out
}

/// What a page shows for a number that is missing or not finite.
pub const NA: &str = "n/a";

/// `v` with `decimals` decimals, `-0` as `0`, [`NA`] when not finite.
pub fn fixed(v: f64, decimals: usize) -> String {
    if !v.is_finite() {
        return NA.into();
    }
    let s = format!("{v:.decimals$}");
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        s.trim_start_matches('-').to_string()
    } else {
        s
    }
}

/// A length in metres shown in millimetres with micrometre resolution (as the text report
/// prints its steps), [`NA`] when missing or not finite.
pub fn mm(v: impl Into<Option<f64>>) -> String {
    v.into().map_or_else(|| NA.into(), |v| fixed(v * 1e3, 3))
}

/// `v` in scientific notation with `digits` after the point, [`NA`] when missing or not
/// finite.
pub fn sci(v: impl Into<Option<f64>>, digits: usize) -> String {
    match v.into() {
        Some(v) if v.is_finite() => format!("{v:.digits$e}"),
        _ => NA.into(),
    }
}

/// A page being written: sections in order, each with an id for the navigation bar.
pub struct Page {
    title: String,
    subtitle: String,
    nav: Vec<(String, String)>,
    body: String,
}

impl Page {
    /// A page titled `title` (escaped here), `subtitle` under it (escaped here).
    pub fn new(title: &str, subtitle: &str) -> Self {
        Page {
            title: title.into(),
            subtitle: subtitle.into(),
            nav: Vec::new(),
            body: String::new(),
        }
    }

    /// Adds a section with the id and `data-testid` `id`, heading `heading` (escaped here), the
    /// extra class `class` (empty for none) and the markup `inner` (already escaped).
    pub fn section(&mut self, id: &str, heading: &str, class: &str, inner: &str) {
        self.nav.push((id.into(), heading.into()));
        let class = if class.is_empty() {
            String::new()
        } else {
            format!(" class=\"{}\"", esc(class))
        };
        let _ = write!(
            self.body,
            "<section id=\"{id}\" data-testid=\"{id}\"{class}>\n<h2>{}</h2>\n{inner}</section>\n",
            esc(heading)
        );
    }

    /// The whole document.
    pub fn finish(self) -> String {
        let mut s = String::with_capacity(self.body.len() + CSS.len() + 1024);
        s.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\"/>\n");
        s.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"/>\n");
        s.push_str(
            "<meta name=\"generator\" content=\"urdf-dh\"/>\n<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; style-src 'unsafe-inline'; img-src data:\"/>\n",
        );
        let _ = writeln!(s, "<title>{}</title>", esc(&self.title));
        let _ = writeln!(s, "<style>{CSS}</style>\n</head>\n<body>\n<main>");
        let _ = writeln!(s, "<h1>{}</h1>", esc(&self.title));
        let _ = writeln!(s, "<p class=\"sub\">{}</p>", esc(&self.subtitle));
        s.push_str("<nav>");
        for (id, heading) in &self.nav {
            let _ = write!(s, "<a href=\"#{id}\">{}</a>", esc(heading));
        }
        s.push_str("</nav>\n");
        s.push_str(&self.body);
        s.push_str("</main>\n</body>\n</html>\n");
        s
    }
}

/// A table: a header row and body rows of cells already escaped; a header cell starting with
/// `#` is numeric (right-aligned, the `#` dropped), and so is its column.
pub fn table(header: &[&str], rows: &[Vec<String>]) -> String {
    table_with(header, rows, &[])
}

/// [`table`] with a class per row (`taken`, `flag` or empty; missing entries: none).
pub fn table_with(header: &[&str], rows: &[Vec<String>], classes: &[&str]) -> String {
    let numeric: Vec<bool> = header.iter().map(|h| h.starts_with('#')).collect();
    let mut s = String::from("<div class=\"scroll\"><table>\n<thead><tr>");
    for h in header {
        match h.strip_prefix('#') {
            Some(h) => {
                let _ = write!(s, "<th class=\"n\">{}</th>", esc(h));
            }
            None => {
                let _ = write!(s, "<th>{}</th>", esc(h));
            }
        }
    }
    s.push_str("</tr></thead>\n<tbody>\n");
    for (i, row) in rows.iter().enumerate() {
        match classes.get(i).filter(|c| !c.is_empty()) {
            Some(c) => {
                let _ = write!(s, "<tr class=\"{c}\">");
            }
            None => s.push_str("<tr>"),
        }
        for (k, cell) in row.iter().enumerate() {
            if numeric.get(k).copied().unwrap_or(false) {
                let _ = write!(s, "<td class=\"n\">{cell}</td>");
            } else {
                let _ = write!(s, "<td>{cell}</td>");
            }
        }
        s.push_str("</tr>\n");
    }
    s.push_str("</tbody>\n</table></div>\n");
    s
}

/// A row of key figures: (label, value), both escaped here.
pub fn tiles(items: &[(&str, String)]) -> String {
    let mut s = String::from("<div class=\"tiles\">");
    for (k, v) in items {
        let _ = write!(
            s,
            "<div class=\"tile\"><div class=\"k\">{}</div><div class=\"v\">{}</div></div>",
            esc(k),
            esc(v)
        );
    }
    s.push_str("</div>\n");
    s
}

/// A paragraph of `text`, escaped here.
pub fn para(text: &str) -> String {
    format!("<p>{}</p>\n", esc(text))
}

/// A muted paragraph of `text`, escaped here.
pub fn muted(text: &str) -> String {
    format!("<p class=\"muted\">{}</p>\n", esc(text))
}

/// A bulleted list of `items`, each escaped here; nothing for none.
pub fn list(items: &[String]) -> String {
    if items.is_empty() {
        return String::new();
    }
    let mut s = String::from("<ul class=\"notes\">");
    for i in items {
        let _ = write!(s, "<li>{}</li>", esc(i));
    }
    s.push_str("</ul>\n");
    s
}

/// A figure: the SVG `svg` (markup) and its caption (escaped here).
pub fn figure(svg: &str, caption: &str) -> String {
    format!(
        "<figure>{svg}<figcaption>{}</figcaption></figure>\n",
        esc(caption)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_markup_and_controls() {
        assert_eq!(
            esc("<script>\"a\" & 'b'\u{7}</script>"),
            "&lt;script&gt;&quot;a&quot; &amp; &#39;b&#39;\u{FFFD}&lt;/script&gt;"
        );
    }

    #[test]
    fn numbers_never_print_nan() {
        assert_eq!(mm(f64::NAN), "n/a");
        assert_eq!(mm(None), "n/a");
        assert_eq!(mm(0.0012345), "1.234");
        assert_eq!(mm(-0.0000001), "0.000");
        assert_eq!(sci(f64::INFINITY, 2), "n/a");
        assert_eq!(sci(0.000123, 2), "1.23e-4");
        assert_eq!(fixed(f64::NEG_INFINITY, 1), "n/a");
    }
}
