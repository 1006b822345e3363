//! A small owned XML tree: what the expansion reads from each file and writes out. Element and
//! attribute names keep the prefix written in the file (`xacro:macro`), as Python's xacro
//! matches them, and every element keeps its file and line for messages.

use std::fmt::Write;

/// Where an element starts: the index of its file in the expansion's file list, and its line.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Pos {
    /// Index into the list of files read.
    pub file: usize,
    /// 1-based line.
    pub line: u32,
}

/// An element.
#[derive(Clone, Debug)]
pub struct Element {
    /// The qualified name, e.g. `xacro:property` or `joint`.
    pub name: String,
    /// Attributes in document order, names qualified.
    pub attrs: Vec<(String, String)>,
    /// Child nodes.
    pub children: Vec<Node>,
    /// Where the element starts.
    pub pos: Pos,
}

/// A node of an element's content.
#[derive(Clone, Debug)]
pub enum Node {
    /// A child element.
    Element(Element),
    /// Text (entities already resolved).
    Text(String),
    /// A comment.
    Comment(String),
}

impl Element {
    /// The value of attribute `name`.
    pub fn attr(&self, name: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.as_str())
    }

    /// Sets attribute `name` (in place when present, else appended).
    pub fn set_attr(attrs: &mut Vec<(String, String)>, name: &str, value: String) {
        match attrs.iter_mut().find(|(k, _)| k == name) {
            Some(slot) => slot.1 = value,
            None => attrs.push((name.to_string(), value)),
        }
    }
}

/// Why a file does not parse.
#[derive(Debug)]
pub enum ParseError {
    /// Not well-formed XML: roxmltree's message, which names the line and column.
    Malformed(String),
    /// Well-formed for Python's (namespace-unaware) parser, but not read here: a DOCTYPE, or a
    /// prefix without its `xmlns:` declaration. The construct, and the message.
    Unsupported(&'static str, String),
}

/// Parses `text` (the file number `file`) into its root element.
///
/// # Errors
/// [`ParseError`].
pub fn parse(text: &str, file: usize) -> Result<Element, ParseError> {
    let opts = roxmltree::ParsingOptions {
        allow_dtd: false,
        ..roxmltree::ParsingOptions::default()
    };
    let doc = roxmltree::Document::parse_with_options(text, opts).map_err(|e| match e {
        roxmltree::Error::DtdDetected => {
            ParseError::Unsupported("document type declarations", e.to_string())
        }
        roxmltree::Error::UnknownNamespace(..) => {
            ParseError::Unsupported("undeclared namespace prefixes", e.to_string())
        }
        other => ParseError::Malformed(other.to_string()),
    })?;
    Ok(element(&doc, doc.root_element(), file, true))
}

fn qualified(node: roxmltree::Node, ns: Option<&str>, local: &str) -> String {
    match ns.and_then(|uri| node.lookup_prefix(uri)) {
        Some(prefix) if !prefix.is_empty() => format!("{prefix}:{local}"),
        _ => local.to_string(),
    }
}

fn element(doc: &roxmltree::Document, node: roxmltree::Node, file: usize, root: bool) -> Element {
    let tag = node.tag_name();
    let mut attrs: Vec<(String, String)> = Vec::new();
    // Namespace declarations of this element (all in scope, for a root): kept as attributes,
    // as a DOM keeps them, so that the output declares what it uses.
    let parent_ns: Vec<_> = node
        .parent_element()
        .map(|p| p.namespaces().collect())
        .unwrap_or_default();
    for ns in node.namespaces() {
        let declared_here = root || !parent_ns.contains(&ns);
        if declared_here && ns.uri() != "http://www.w3.org/XML/1998/namespace" {
            let key = match ns.name() {
                Some(p) => format!("xmlns:{p}"),
                None => "xmlns".to_string(),
            };
            attrs.push((key, ns.uri().to_string()));
        }
    }
    for a in node.attributes() {
        attrs.push((
            qualified(node, a.namespace(), a.name()),
            a.value().to_string(),
        ));
    }
    let children = node
        .children()
        .filter_map(|c| {
            if c.is_element() {
                Some(Node::Element(element(doc, c, file, false)))
            } else if c.is_text() {
                c.text().map(|t| Node::Text(t.to_string()))
            } else if c.is_comment() {
                c.text().map(|t| Node::Comment(t.to_string()))
            } else {
                None
            }
        })
        .collect();
    Element {
        name: qualified(node, tag.namespace(), tag.name()),
        attrs,
        children,
        pos: Pos {
            file,
            line: doc.text_pos_at(node.range().start).row,
        },
    }
}

/// Writes `e` as XML text into `out`.
pub fn write(e: &Element, out: &mut String) {
    out.push('<');
    out.push_str(&e.name);
    for (k, v) in &e.attrs {
        let _ = write!(out, " {k}=\"");
        escape(v, true, out);
        out.push('"');
    }
    if e.children.is_empty() {
        out.push_str("/>");
        return;
    }
    out.push('>');
    for c in &e.children {
        match c {
            Node::Element(child) => write(child, out),
            Node::Text(t) => escape(t, false, out),
            Node::Comment(t) => {
                out.push_str("<!--");
                out.push_str(&t.replace("--", "- -"));
                out.push_str("-->");
            }
        }
    }
    out.push_str("</");
    out.push_str(&e.name);
    out.push('>');
}

fn escape(text: &str, attr: bool, out: &mut String) {
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' if attr => out.push_str("&quot;"),
            '\n' if attr => out.push_str("&#10;"),
            c => out.push(c),
        }
    }
}

/// An estimate of the bytes `e` takes when written (for the size guard).
pub fn size(e: &Element) -> usize {
    let attrs: usize = e.attrs.iter().map(|(k, v)| k.len() + v.len() + 4).sum();
    let children: usize = e
        .children
        .iter()
        .map(|c| match c {
            Node::Element(child) => size(child),
            Node::Text(t) | Node::Comment(t) => t.len(),
        })
        .sum();
    2 * e.name.len() + 5 + attrs + children
}
