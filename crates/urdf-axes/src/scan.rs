//! A small XML scanner for what urdf-rs does not keep.
//!
//! urdf-rs deserialises into plain structs: it forgets source lines, cannot tell a missing
//! `<limit>` from `<limit lower="0" upper="0">`, reads only the first of several root elements,
//! accepts any root element name, and its XML backend recurses once per nesting level (a deeply
//! nested document overflows the stack). This scanner runs first, in one linear pass without
//! recursion and without expanding anything: it refuses entity declarations and excessive
//! nesting, checks the document's shape, and records every element with its line.

/// Deepest element nesting accepted. A URDF needs about six levels (robot, link, visual,
/// geometry, mesh); vendor extensions (`<gazebo>` plugins) a few more.
pub(crate) const MAX_DEPTH: usize = 100;

/// One element of the document.
#[derive(Debug)]
pub(crate) struct Element {
    /// Tag name, with any namespace prefix.
    pub name: String,
    /// Attributes in source order, values with the predefined and numeric character
    /// references decoded.
    pub attrs: Vec<(String, String)>,
    /// 1-based line of the `<`.
    pub line: usize,
    /// Child elements (indices into [`Doc::elements`]).
    pub children: Vec<usize>,
}

impl Element {
    /// The value of attribute `name`.
    pub fn attr(&self, name: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.as_str())
    }
}

/// The scanned document: every element, the root first.
#[derive(Debug)]
pub(crate) struct Doc {
    /// Elements in document order; index 0 is the root.
    pub elements: Vec<Element>,
}

impl Doc {
    /// The element at `index`.
    pub fn get(&self, index: usize) -> Option<&Element> {
        self.elements.get(index)
    }

    /// The root element.
    #[cfg(test)]
    pub fn root(&self) -> Option<&Element> {
        self.elements.first()
    }

    /// Indices of the root's children named `name`, in document order.
    pub fn top_level(&self, name: &str) -> Vec<usize> {
        self.children_named(0, name)
    }

    /// Indices of the children of `parent` named `name`, in document order.
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
    pub fn child(&self, parent: usize, name: &str) -> Option<&Element> {
        self.children_named(parent, name)
            .first()
            .and_then(|&c| self.get(c))
    }
}

/// Why a document was refused before urdf-rs saw it.
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

/// Byte offsets of line starts, for offset -> line lookups.
pub(crate) struct Lines {
    starts: Vec<usize>,
}

impl Lines {
    /// Indexes the line starts of `bytes`.
    pub fn new(bytes: &[u8]) -> Self {
        let mut starts = vec![0];
        starts.extend(
            bytes
                .iter()
                .enumerate()
                .filter(|(_, &b)| b == b'\n')
                .map(|(i, _)| i + 1),
        );
        Self { starts }
    }

    /// 1-based line of byte `offset`.
    pub fn line_of(&self, offset: usize) -> usize {
        self.starts.partition_point(|&s| s <= offset).max(1)
    }
}

fn malformed(message: String, line: usize) -> ScanError {
    ScanError::Malformed {
        message,
        line: Some(line),
    }
}

/// Shortens text quoted in a message.
fn excerpt(s: &str) -> String {
    let t = s.trim();
    // One line of a message: stop at the first line break.
    let first = t.lines().next().unwrap_or("");
    let short: String = first.chars().take(24).collect();
    if short.len() < t.len() {
        format!("{short}...")
    } else {
        short
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

/// Scans `text` as a URDF document.
///
/// # Errors
/// [`ScanError::Entity`] for an entity declaration; [`ScanError::Malformed`] for anything that
/// is not one well-formed `<robot>` element (unclosed or mismatched tags, text or a second
/// element outside the root, nesting deeper than [`MAX_DEPTH`]).
pub(crate) fn scan(text: &str) -> Result<Doc, ScanError> {
    let b = text.as_bytes();
    let lines = Lines::new(b);
    let find =
        |from: usize, pat: &str| text.get(from..).and_then(|s| s.find(pat)).map(|i| i + from);

    let mut elements: Vec<Element> = Vec::new();
    let mut stack: Vec<usize> = Vec::new();
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
            i = declaration(text, lt, &lines)?;
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
            let open = stack.pop().and_then(|k| elements.get(k));
            match open {
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
            let (element, end, self_closing) = start_tag(text, lt, line)?;
            let index = elements.len();
            match stack.last() {
                Some(&parent) => {
                    if let Some(p) = elements.get_mut(parent) {
                        p.children.push(index);
                    }
                }
                None if root_closed || !elements.is_empty() => {
                    return Err(malformed(
                        format!(
                            "expected one root element, found a second one <{}>",
                            element.name
                        ),
                        line,
                    ))
                }
                None if element.name != "robot" => {
                    return Err(malformed(
                        format!("expected a <robot> root element, found <{}>", element.name),
                        line,
                    ))
                }
                None => {}
            }
            elements.push(element);
            if self_closing {
                if stack.is_empty() {
                    root_closed = true;
                }
            } else {
                stack.push(index);
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
    if let Some(e) = stack.last().and_then(|&k| elements.get(k)) {
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
fn declaration(text: &str, lt: usize, lines: &Lines) -> Result<usize, ScanError> {
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

/// Parses the start tag at `lt`; returns the element, the offset after the tag and whether it
/// closes itself.
fn start_tag(text: &str, lt: usize, line: usize) -> Result<(Element, usize, bool), ScanError> {
    let b = text.as_bytes();
    let mut j = lt + 1;
    j = skip(b, j, |c| !is_name_end(c));
    let name = text.get(lt + 1..j).unwrap_or("").to_owned();
    if name.is_empty() {
        return Err(malformed(
            format!(
                "expected an element name after '<', found {}",
                found_at(text, j)
            ),
            line,
        ));
    }
    let mut attrs = Vec::new();
    loop {
        j = skip(b, j, |c| c.is_ascii_whitespace());
        match b.get(j) {
            None => {
                return Err(malformed(
                    format!("expected '>' ending <{name}, found end of file"),
                    line,
                ))
            }
            Some(b'>') => return Ok((element(name, attrs, line), j + 1, false)),
            Some(b'/') => {
                if b.get(j + 1) == Some(&b'>') {
                    return Ok((element(name, attrs, line), j + 2, true));
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
        let key = text.get(start..j).unwrap_or("").to_owned();
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
        if attrs.iter().any(|(k, _)| *k == key) {
            return Err(malformed(
                format!("expected attribute '{key}' once in <{name}>, found it twice"),
                line,
            ));
        }
        attrs.push((key, decode(text.get(vstart..vend).unwrap_or(""))));
        j = vend + 1;
    }
}

fn element(name: String, attrs: Vec<(String, String)>, line: usize) -> Element {
    Element {
        name,
        attrs,
        line,
        children: Vec::new(),
    }
}

/// Decodes the predefined entities and numeric character references; anything else is kept.
fn decode(raw: &str) -> String {
    if !raw.contains('&') {
        return raw.to_owned();
    }
    let mut out = String::with_capacity(raw.len());
    let mut rest = raw;
    while let Some(amp) = rest.find('&') {
        out.push_str(rest.get(..amp).unwrap_or(""));
        let tail = rest.get(amp..).unwrap_or("");
        let semi = tail.find(';');
        let decoded = semi.and_then(|s| {
            let name = tail.get(1..s)?;
            let c = match name {
                "lt" => '<',
                "gt" => '>',
                "amp" => '&',
                "quot" => '"',
                "apos" => '\'',
                _ => {
                    let code = if let Some(hex) = name.strip_prefix("#x") {
                        u32::from_str_radix(hex, 16).ok()?
                    } else {
                        name.strip_prefix('#')?.parse().ok()?
                    };
                    char::from_u32(code)?
                }
            };
            Some((c, s))
        });
        match decoded {
            Some((c, s)) => {
                out.push(c);
                rest = tail.get(s + 1..).unwrap_or("");
            }
            None => {
                out.push('&');
                rest = tail.get(1..).unwrap_or("");
            }
        }
    }
    out.push_str(rest);
    out
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
