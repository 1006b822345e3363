//! The XML scanner: the one parse of a URDF.
//!
//! One linear pass without recursion and without expanding anything: it refuses entity
//! declarations, excessive nesting, characters XML forbids, unknown entity references and raw
//! `<` in attribute values, checks the document's shape, and records with its line every
//! element a URDF reader needs: the root, its `<link>`, `<joint>` and `<material>` children and
//! everything inside them. Other elements (`<gazebo>`, `<transmission>`, vendor extensions)
//! are checked for well-formedness and dropped at once, so memory stays proportional to the
//! kept part of the document. Names and attribute values borrow from the text.

use std::borrow::Cow;

pub(crate) use crate::text::Lines;
use crate::text::{bad_reference, column_of, decode, excerpt, forbidden_character, LineCounter};

/// Deepest element nesting accepted. A URDF needs about six levels (robot, link, visual,
/// geometry, mesh); vendor extensions (`<gazebo>` plugins) a few more.
pub(crate) const MAX_DEPTH: usize = 100;

/// Most attributes accepted on one element: a URDF element has at most a dozen, and the
/// duplicate check must not turn quadratic on a hostile file.
pub(crate) const MAX_ATTRIBUTES: usize = 256;

/// Top-level elements kept for the model; the others are checked and dropped.
const KEPT: [&str; 3] = ["link", "joint", "material"];

/// One element of the document.
#[derive(Debug)]
pub(crate) struct Element<'a> {
    /// Tag name, with any namespace prefix.
    pub name: &'a str,
    /// Attributes in source order, values with the predefined and numeric character
    /// references decoded.
    pub attrs: Vec<(&'a str, Cow<'a, str>)>,
    /// 1-based line of the `<`.
    pub line: usize,
    /// Child elements (indices into [`Doc::elements`]).
    pub children: Vec<usize>,
}

impl Element<'_> {
    /// The value of attribute `name`.
    pub fn attr(&self, name: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| *k == name)
            .map(|(_, v)| v.as_ref())
    }
}

/// The scanned document: the kept elements, the root first.
#[derive(Debug)]
pub(crate) struct Doc<'a> {
    /// Kept elements in document order; index 0 is the root.
    pub elements: Vec<Element<'a>>,
}

impl<'a> Doc<'a> {
    /// The element at `index`.
    pub fn get(&self, index: usize) -> Option<&Element<'a>> {
        self.elements.get(index)
    }

    /// The root element.
    pub fn root(&self) -> Option<&Element<'a>> {
        self.elements.first()
    }

    /// Indices of the root's children named `name`, in document order.
    #[cfg(test)]
    pub fn top_level(&self, name: &str) -> Vec<usize> {
        self.children_named(0, name)
    }

    /// Indices of the children of `parent` named `name`, in document order.
    #[cfg(test)]
    pub fn children_named(&self, parent: usize, name: &str) -> Vec<usize> {
        self.get(parent)
            .map(|p| {
                p.children
                    .iter()
                    .copied()
                    .filter(|&c| self.get(c).is_some_and(|e| e.name == name))
                    .collect()
            })
            .unwrap_or_default()
    }

    /// The first child of `parent` named `name`.
    #[cfg(test)]
    pub fn child(&self, parent: usize, name: &str) -> Option<&Element<'a>> {
        self.children_named(parent, name)
            .first()
            .and_then(|&c| self.get(c))
    }
}

/// Why a document was refused by the scan.
#[derive(Debug, PartialEq)]
pub(crate) enum ScanError {
    /// A `<!ENTITY` declaration (refused: entity expansion can exhaust memory).
    Entity {
        /// 1-based line.
        line: usize,
    },
    /// Not a well-formed single-root XML document, or not a `<robot>`.
    Malformed {
        /// Lowercase, "expected X, found Y".
        message: String,
        /// 1-based line, when there is one.
        line: Option<usize>,
    },
}

fn malformed(message: String, line: usize) -> ScanError {
    ScanError::Malformed {
        message,
        line: Some(line),
    }
}

/// The first offset from `j` on whose byte fails `pred` (or the end).
fn skip(b: &[u8], mut j: usize, pred: impl Fn(u8) -> bool) -> usize {
    while b.get(j).is_some_and(|&c| pred(c)) {
        j += 1;
    }
    j
}

fn is_name_end(b: u8) -> bool {
    b.is_ascii_whitespace() || b == b'/' || b == b'>' || b == b'='
}

/// An open element: its name, line and index among the kept elements (if kept).
struct Open<'a> {
    name: &'a str,
    line: usize,
    kept: Option<usize>,
}

/// Scans `text` as a URDF document.
///
/// # Errors
/// [`ScanError::Entity`] for an entity declaration; [`ScanError::Malformed`] for anything that
/// is not one well-formed `<robot>` element (unclosed or mismatched tags, text or a second
/// element outside the root, nesting deeper than [`MAX_DEPTH`], a character XML forbids, an
/// unknown entity reference, a raw `<` in an attribute value, more than [`MAX_ATTRIBUTES`]
/// attributes on one element, a double dash inside a comment).
pub(crate) fn scan(text: &str) -> Result<Doc<'_>, ScanError> {
    let b = text.as_bytes();
    let mut lines = LineCounter {
        bytes: b,
        offset: 0,
        line: 1,
    };
    if let Some((at, c)) = forbidden_character(b) {
        return Err(malformed(
            format!(
                "expected xml text, found the control character U+{c:04X} (column {}), which xml forbids",
                column_of(text, at)
            ),
            lines.line_of(at),
        ));
    }
    let find =
        |from: usize, pat: &str| text.get(from..).and_then(|s| s.find(pat)).map(|i| i + from);

    let mut elements: Vec<Element> = Vec::new();
    let mut stack: Vec<Open> = Vec::new();
    // The attributes of the tag being read (one list for every tag).
    let mut attrs: Vec<(&str, &str)> = Vec::new();
    let mut root_closed = false;
    let mut i = 0;
    while i < b.len() {
        let lt = find(i, "<").unwrap_or(b.len());
        // Text outside the root element must be blank.
        if stack.is_empty() {
            if let Some(gap) = text.get(i..lt) {
                if let Some(off) = gap.find(|c: char| !c.is_whitespace()) {
                    let what = if root_closed {
                        "the end of the document after </robot>"
                    } else {
                        "a <robot> element"
                    };
                    return Err(malformed(
                        format!("expected {what}, found text '{}'", excerpt(gap)),
                        lines.line_of(i + off),
                    ));
                }
            }
        }
        if lt >= b.len() {
            break;
        }
        let line = lines.line_of(lt);
        let rest = text.get(lt..).unwrap_or("");
        if rest.starts_with("<!--") {
            let end = find(lt + 4, "-->").ok_or_else(|| {
                malformed(
                    "expected '-->' closing a comment, found end of file".into(),
                    line,
                )
            })?;
            // XML forbids "--" inside a comment (and a comment ending in "--->").
            if let Some(k) = text.get(lt + 4..end).and_then(|c| {
                c.find("--")
                    .or_else(|| c.ends_with('-').then(|| c.len() - 1))
            }) {
                let at = lt + 4 + k;
                return Err(malformed(
                    format!(
                        "no more than one adjacent '-' allowed in a comment (column {})",
                        column_of(text, at + 2)
                    ),
                    lines.line_of(at),
                ));
            }
            i = end + 3;
        } else if rest.starts_with("<![CDATA[") {
            let end = find(lt + 9, "]]>").ok_or_else(|| {
                malformed(
                    "expected ']]>' closing a cdata section, found end of file".into(),
                    line,
                )
            })?;
            if stack.is_empty() {
                return Err(malformed(
                    "expected a <robot> element, found a cdata section".into(),
                    line,
                ));
            }
            i = end + 3;
        } else if rest.starts_with("<?") {
            let end = find(lt + 2, "?>").ok_or_else(|| {
                malformed(
                    "expected '?>' closing a processing instruction, found end of file".into(),
                    line,
                )
            })?;
            i = end + 2;
        } else if rest.starts_with("<!") {
            i = declaration(text, lt, &mut lines)?;
        } else if rest.starts_with("</") {
            let start = lt + 2;
            let mut j = start;
            j = skip(b, j, |c| !is_name_end(c));
            let name = text.get(start..j).unwrap_or("");
            j = skip(b, j, |c| c.is_ascii_whitespace());
            if b.get(j) != Some(&b'>') {
                return Err(malformed(
                    format!("expected '>' ending </{name}, found {}", found_at(text, j)),
                    line,
                ));
            }
            match stack.pop() {
                None => {
                    return Err(malformed(
                        format!("expected an opening tag, found </{name}> with no open element"),
                        line,
                    ))
                }
                Some(e) if e.name != name => {
                    return Err(malformed(
                        format!(
                            "expected </{}> closing the <{}> of line {}, found </{name}>",
                            e.name, e.name, e.line
                        ),
                        line,
                    ))
                }
                Some(_) => {}
            }
            if stack.is_empty() {
                root_closed = true;
            }
            i = j + 1;
        } else {
            // Kept: the root, its link/joint/material children, and everything inside those.
            let parent = stack.last();
            let (name, end, self_closing) = start_tag(text, lt, line, &mut attrs)?;
            let kept = match parent {
                Some(p) => {
                    let keep = p.kept.is_some_and(|k| k != 0 || KEPT.contains(&name));
                    match (keep, p.kept) {
                        (true, Some(pk)) => {
                            let index = elements.len();
                            if let Some(pe) = elements.get_mut(pk) {
                                pe.children.push(index);
                            }
                            Some(index)
                        }
                        _ => None,
                    }
                }
                None if root_closed || !elements.is_empty() => {
                    return Err(malformed(
                        format!("expected one root element, found a second one <{name}>"),
                        line,
                    ))
                }
                None if name != "robot" => {
                    return Err(malformed(
                        format!("expected a <robot> root element, found <{name}>"),
                        line,
                    ))
                }
                None => Some(0),
            };
            if kept.is_some() {
                elements.push(Element {
                    name,
                    attrs: attrs.iter().map(|&(k, v)| (k, decode(v))).collect(),
                    line,
                    children: Vec::new(),
                });
            }
            if self_closing {
                if stack.is_empty() {
                    root_closed = true;
                }
            } else {
                stack.push(Open { name, line, kept });
                if stack.len() > MAX_DEPTH {
                    return Err(malformed(
                        format!("expected elements nested at most {MAX_DEPTH} deep, found deeper"),
                        line,
                    ));
                }
            }
            i = end;
        }
    }
    if let Some(e) = stack.last() {
        return Err(malformed(
            format!(
                "expected </{}> closing the <{}> of line {}, found end of file",
                e.name, e.name, e.line
            ),
            lines.line_of(b.len().saturating_sub(1)),
        ));
    }
    if elements.is_empty() {
        let found = if text.trim().is_empty() {
            "an empty document"
        } else {
            "no element"
        };
        return Err(ScanError::Malformed {
            message: format!("expected a <robot> element, found {found}"),
            line: None,
        });
    }
    Ok(Doc { elements })
}

/// Describes what sits at byte `at` for a message.
fn found_at(text: &str, at: usize) -> String {
    match text.get(at..).and_then(|s| s.chars().next()) {
        Some(c) => format!("'{c}'"),
        None => "end of file".into(),
    }
}

/// Skips a `<!DOCTYPE ...>` (or other `<!...>`) declaration starting at `lt`, refusing entity
/// declarations; returns the offset after it.
fn declaration(text: &str, lt: usize, lines: &mut LineCounter) -> Result<usize, ScanError> {
    let b = text.as_bytes();
    let mut depth = 0usize;
    let mut quote: Option<u8> = None;
    let mut j = lt + 2;
    while let Some(&c) = b.get(j) {
        match quote {
            Some(q) if c == q => quote = None,
            Some(_) => {}
            None => match c {
                b'"' | b'\'' => quote = Some(c),
                b'[' => depth += 1,
                b']' => depth = depth.saturating_sub(1),
                b'<' if text.get(j..).is_some_and(|s| s.starts_with("<!ENTITY")) => {
                    return Err(ScanError::Entity {
                        line: lines.line_of(j),
                    })
                }
                b'<' if text.get(j..).is_some_and(|s| s.starts_with("<!--")) => {
                    match text.get(j + 4..).and_then(|s| s.find("-->")) {
                        Some(k) => j += 4 + k + 2,
                        None => break,
                    }
                }
                b'>' if depth == 0 => return Ok(j + 1),
                _ => {}
            },
        }
        j += 1;
    }
    Err(malformed(
        "expected '>' closing a <! declaration, found end of file".into(),
        lines.line_of(lt),
    ))
}

/// A start tag's name and raw attributes, the offset after it and whether it closes itself.
/// A start tag's name, the offset after it and whether it closes itself.
type StartTag<'a> = (&'a str, usize, bool);

/// Parses the start tag at `lt`, its attributes (raw values) into `attrs`.
fn start_tag<'a>(
    text: &'a str,
    lt: usize,
    line: usize,
    attrs: &mut Vec<(&'a str, &'a str)>,
) -> Result<StartTag<'a>, ScanError> {
    let b = text.as_bytes();
    let mut j = lt + 1;
    j = skip(b, j, |c| !is_name_end(c));
    let name = text.get(lt + 1..j).unwrap_or("");
    if name.is_empty() {
        return Err(malformed(
            format!(
                "expected an element name after '<', found {}",
                found_at(text, j)
            ),
            line,
        ));
    }
    attrs.clear();
    loop {
        j = skip(b, j, |c| c.is_ascii_whitespace());
        match b.get(j) {
            None => {
                return Err(malformed(
                    format!("expected '>' ending <{name}, found end of file"),
                    line,
                ))
            }
            Some(b'>') => return Ok((name, j + 1, false)),
            Some(b'/') => {
                if b.get(j + 1) == Some(&b'>') {
                    return Ok((name, j + 2, true));
                }
                return Err(malformed(
                    format!(
                        "expected '/>' ending <{name}, found {}",
                        found_at(text, j + 1)
                    ),
                    line,
                ));
            }
            Some(_) => {}
        }
        let start = j;
        j = skip(b, j, |c| !is_name_end(c));
        let key = text.get(start..j).unwrap_or("");
        j = skip(b, j, |c| c.is_ascii_whitespace());
        if key.is_empty() || b.get(j) != Some(&b'=') {
            return Err(malformed(
                format!(
                    "expected an attribute name=\"value\" in <{name}, found {}",
                    found_at(text, if key.is_empty() { j } else { start })
                ),
                line,
            ));
        }
        j += 1;
        j = skip(b, j, |c| c.is_ascii_whitespace());
        let quote = match b.get(j) {
            Some(&q @ (b'"' | b'\'')) => q,
            _ => {
                return Err(malformed(
                    format!(
                        "expected a quoted value for attribute '{key}' of <{name}>, found {}",
                        found_at(text, j)
                    ),
                    line,
                ))
            }
        };
        let vstart = j + 1;
        let vend = b
            .get(vstart..)
            .and_then(|rest| rest.iter().position(|&c| c == quote))
            .map(|k| vstart + k)
            .ok_or_else(|| {
                malformed(
                    format!(
                        "expected a closing quote for attribute '{key}' of <{name}>, found end of file"
                    ),
                    line,
                )
            })?;
        let value = text.get(vstart..vend).unwrap_or("");
        if value.contains('<') {
            return Err(malformed(
                format!(
                    "attribute '{key}' of <{name}>: expected '&lt;' for a '<' in a value, found a raw '<'"
                ),
                line,
            ));
        }
        if let Some(bad) = bad_reference(value) {
            return Err(malformed(
                format!("attribute '{key}' of <{name}>: expected a known entity reference, found '{bad}'"),
                line,
            ));
        }
        if attrs.len() >= MAX_ATTRIBUTES {
            return Err(malformed(
                format!("expected at most {MAX_ATTRIBUTES} attributes in <{name}>, found more"),
                line,
            ));
        }
        if attrs.iter().any(|(k, _)| *k == key) {
            return Err(malformed(
                format!("expected attribute '{key}' once in <{name}>, found it twice"),
                line,
            ));
        }
        attrs.push((key, value));
        j = vend + 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn malformed_line(text: &str) -> (String, Option<usize>) {
        match scan(text) {
            Err(ScanError::Malformed { message, line }) => (message, line),
            other => panic!("expected a malformed document, got {other:?}"),
        }
    }

    #[test]
    fn records_lines_attributes_and_children() {
        let doc = scan(
            "<?xml version=\"1.0\"?>\n<!-- c <joint> -->\n<robot name='r&amp;s'>\n  <link name=\"a\"/>\n  <joint name=\"j&#65;\" type=\"fixed\">\n<parent link=\"a\" />\n  </joint>\n</robot>\n",
        )
        .unwrap();
        let root = doc.root().unwrap();
        assert_eq!(root.attr("name"), Some("r&s"));
        assert_eq!(root.line, 3);
        let joints = doc.top_level("joint");
        assert_eq!(joints.len(), 1);
        let j = doc.get(joints[0]).unwrap();
        assert_eq!((j.attr("name"), j.line), (Some("jA"), 5));
        assert_eq!(doc.child(joints[0], "parent").unwrap().line, 6);
        assert_eq!(doc.get(doc.top_level("link")[0]).unwrap().line, 4);
    }

    #[test]
    fn refuses_entity_declarations_with_their_line() {
        let bomb = "<?xml version=\"1.0\"?>\n<!DOCTYPE r [\n <!ENTITY a \"aaaaaaaa\">\n]>\n<robot name=\"&a;\"/>";
        assert_eq!(scan(bomb).unwrap_err(), ScanError::Entity { line: 3 });
        // A doctype without declarations is harmless.
        assert!(scan("<!DOCTYPE robot>\n<robot name=\"r\"/>").is_ok());
    }

    #[test]
    fn refuses_documents_of_the_wrong_shape() {
        assert_eq!(
            malformed_line("<robot>\n<link name=\"a\">\n</robot>").1,
            Some(3)
        );
        let (m, line) = malformed_line("<robot name=\"r\">\n  <link name=\"a\"/>\n");
        assert!(m.contains("found end of file"), "{m}");
        assert!(m.contains("line 1"), "{m}");
        assert_eq!(line, Some(2));
        let (m, _) = malformed_line("<foo/>");
        assert!(m.contains("found <foo>"), "{m}");
        let (m, line) = malformed_line("<robot/>\n<robot/>");
        assert!(m.contains("second"), "{m}");
        assert_eq!(line, Some(2));
        let (m, line) = malformed_line("hello");
        assert!(m.contains("'hello'"), "{m}");
        assert_eq!(line, Some(1));
        let (m, _) = malformed_line("joint_1: revolute\njoint_2: prismatic\n");
        assert!(m.ends_with("'joint_1: revolute...'"), "{m}");
        assert!(malformed_line("").0.contains("empty document"));
        assert!(malformed_line("<robot a=1/>").0.contains("quoted value"));
        assert!(malformed_line("<robot a=\"1\" a=\"2\"/>")
            .0
            .contains("twice"));
        let deep = format!("<robot>{}{}</robot>", "<x>".repeat(200), "</x>".repeat(200));
        assert!(malformed_line(&deep).0.contains("nested at most"));
    }

    #[test]
    fn line_index_is_one_based() {
        let l = Lines::new(b"a\nb\n\nc");
        assert_eq!([0, 1, 2, 3, 4, 5].map(|o| l.line_of(o)), [1, 1, 2, 2, 3, 4]);
    }
}
