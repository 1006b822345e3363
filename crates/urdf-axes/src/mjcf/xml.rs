//! The MJCF document as an owned tree of elements, with every `<include>` replaced by the
//! children of the included file's `<mujoco>` root (as MuJoCo's parser does). Each element keeps
//! its line and file for messages. Parsed with `roxmltree` (no DTD, so no entity expansion).

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::rc::Rc;

use super::error::{MjcfError, Place};
use crate::MAX_URDF_BYTES;

/// Deepest element nesting accepted (bodies nest one level per link; real models stay below
/// 30). Bounds the reader's recursion for hostile input.
pub(crate) const MAX_DEPTH: usize = 256;

/// Most `<include>` elements followed in one model (MuJoCo refuses an included file twice,
/// so a finite set of files bounds them; this bounds a hostile folder of files).
const MAX_INCLUDES: usize = 1000;

/// One element: tag, attributes in document order, children, file and line.
#[derive(Clone, Debug)]
pub(crate) struct Node {
    pub name: String,
    pub attrs: Vec<(String, String)>,
    pub children: Vec<Node>,
    pub line: usize,
    /// The included file it came from; `None` for the main document.
    pub file: Option<Rc<str>>,
}

impl Node {
    /// The value of attribute `key`.
    pub fn attr(&self, key: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    /// `tag 'name'` when the element has a name, `<tag>` otherwise.
    pub fn describe(&self) -> String {
        match self.attr("name") {
            Some(n) => format!("{} '{}'", self.name, n.escape_debug()),
            None => format!("<{}>", self.name),
        }
    }

    /// Where the element is, for messages.
    pub fn place(&self) -> Place {
        Place {
            element: self.describe(),
            file: self.file.as_deref().map(str::to_owned),
            line: self.line,
        }
    }

    /// An [`MjcfError::Invalid`] about this element.
    pub fn error(&self, message: impl Into<String>) -> MjcfError {
        MjcfError::at(self.place(), message)
    }
}

/// Reads the `<mujoco>` document `text`; `dir` is the folder relative to which `<include file>`
/// is resolved (the main file's folder), `None` when the text came from standard input or a
/// string (then an `<include>` is refused).
///
/// # Errors
/// [`MjcfError::Xml`] for text that is not well-formed or whose root is not `<mujoco>`;
/// [`MjcfError::Invalid`] for an `<include>` that cannot be followed (no folder, no `file`,
/// missing or unreadable file, the same file twice, a root other than `<mujoco>`) or nesting
/// beyond [`MAX_DEPTH`].
pub(crate) fn read_document(
    text: &str,
    dir: Option<&Path>,
    files: Option<&super::MemoryFiles>,
) -> Result<Node, MjcfError> {
    let mut includes = Includes {
        dir: dir.map(Path::to_path_buf),
        files,
        seen: HashSet::new(),
        count: 0,
    };
    let doc = parse(text, None)?;
    let root = doc.root_element();
    convert(&doc, root, None, 0, &mut includes)
}

struct Includes<'f> {
    dir: Option<PathBuf>,
    /// The files to read includes from instead of the disk (see [`super::from_bytes_with`]).
    files: Option<&'f super::MemoryFiles>,
    seen: HashSet<PathBuf>,
    count: usize,
}

fn parse<'a>(text: &'a str, file: Option<&Rc<str>>) -> Result<roxmltree::Document<'a>, MjcfError> {
    let xml_error = |line: Option<usize>, message: String| MjcfError::Xml {
        file: file.map(|f| f.to_string()),
        line,
        message,
    };
    let doc = roxmltree::Document::parse(text.strip_prefix('\u{feff}').unwrap_or(text))
        .map_err(|e| xml_error(Some(e.pos().row as usize), e.to_string()))?;
    let root = doc.root_element();
    if root.tag_name().name() != "mujoco" {
        return Err(xml_error(
            Some(line_of(&doc, root)),
            format!(
                "expected a <mujoco> root element, found <{}>",
                root.tag_name().name()
            ),
        ));
    }
    Ok(doc)
}

fn line_of(doc: &roxmltree::Document, node: roxmltree::Node) -> usize {
    doc.text_pos_at(node.range().start).row as usize
}

fn convert(
    doc: &roxmltree::Document,
    node: roxmltree::Node,
    file: Option<&Rc<str>>,
    depth: usize,
    includes: &mut Includes,
) -> Result<Node, MjcfError> {
    let mut out = Node {
        name: node.tag_name().name().to_owned(),
        attrs: node
            .attributes()
            .map(|a| (a.name().to_owned(), a.value().to_owned()))
            .collect(),
        children: Vec::new(),
        line: line_of(doc, node),
        file: file.cloned(),
    };
    if depth > MAX_DEPTH {
        return Err(out.error(format!(
            "expected elements nested at most {MAX_DEPTH} deep, found deeper"
        )));
    }
    for child in node.children().filter(roxmltree::Node::is_element) {
        let c = convert(doc, child, file, depth + 1, includes)?;
        if c.name == "include" {
            out.children.extend(include(&c, depth, includes)?);
        } else {
            out.children.push(c);
        }
    }
    Ok(out)
}

/// The children of the `<mujoco>` root of the file `<include file>` names.
fn include(at: &Node, depth: usize, includes: &mut Includes) -> Result<Vec<Node>, MjcfError> {
    let Some(name) = at.attr("file") else {
        return Err(at.error("expected attribute 'file', found none"));
    };
    let Some(dir) = &includes.dir else {
        return Err(at.error(format!(
            "cannot include '{name}': the model was not read from a file, so relative paths have no folder (give the mjcf as a file)"
        )));
    };
    let path = dir.join(name);
    includes.count += 1;
    if includes.count > MAX_INCLUDES {
        return Err(at.error(format!(
            "expected at most {MAX_INCLUDES} <include> elements, found more"
        )));
    }
    let key = match includes.files {
        Some(_) => normalize(&path),
        None => path.canonicalize().unwrap_or_else(|_| path.clone()),
    };
    if !includes.seen.insert(key.clone()) {
        return Err(at.error(format!(
            "expected each file included once, found '{name}' included again"
        )));
    }
    let bytes = match includes.files {
        Some(files) => files.get(&key).cloned().ok_or_else(|| {
            at.error(format!(
                "cannot read the included file '{name}': not among the files given"
            ))
        })?,
        None => std::fs::read(&path)
            .map_err(|e| at.error(format!("cannot read the included file '{name}': {e}")))?,
    };
    if bytes.len() > MAX_URDF_BYTES {
        return Err(at.error(format!(
            "expected an included file of at most {MAX_URDF_BYTES} bytes, found {}",
            bytes.len()
        )));
    }
    let text = String::from_utf8(bytes).map_err(|_| {
        at.error(format!(
            "expected utf-8 text in '{name}', found invalid bytes"
        ))
    })?;
    let file: Rc<str> = Rc::from(name);
    let doc = parse(&text, Some(&file))?;
    let root = convert(&doc, doc.root_element(), Some(&file), depth + 1, includes)?;
    Ok(root.children)
}

/// `path` with `.` dropped and `..` applied to the component before it (in-memory files have
/// no file system to canonicalise paths).
fn normalize(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            std::path::Component::CurDir => {}
            std::path::Component::ParentDir => {
                if !out.pop() {
                    out.push("..");
                }
            }
            other => out.push(other.as_os_str()),
        }
    }
    out
}

/// Whether `bytes` hold an MJCF document: the first element (after an XML declaration, comments,
/// processing instructions and a doctype) is `<mujoco`. Looks at the prolog only, so a URDF
/// costs a few bytes of scanning.
pub fn is_mjcf(bytes: &[u8]) -> bool {
    let mut rest = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    loop {
        let start = rest
            .iter()
            .position(|b| !b.is_ascii_whitespace())
            .unwrap_or(rest.len());
        rest = rest.get(start..).unwrap_or_default();
        let skip_to = |rest: &[u8], end: &[u8]| -> Option<usize> {
            rest.windows(end.len())
                .position(|w| w == end)
                .map(|p| p + end.len())
        };
        let next = if rest.starts_with(b"<!--") {
            skip_to(rest, b"-->")
        } else if rest.starts_with(b"<?") {
            skip_to(rest, b"?>")
        } else if rest.starts_with(b"<!") {
            skip_to(rest, b">")
        } else {
            return rest.starts_with(b"<mujoco")
                && rest
                    .get(7)
                    .is_none_or(|&b| b.is_ascii_whitespace() || b == b'>' || b == b'/');
        };
        match next {
            Some(n) => rest = rest.get(n..).unwrap_or_default(),
            None => return false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_root_decides_the_format() {
        assert!(is_mjcf(b"<mujoco model=\"a\"/>"));
        assert!(is_mjcf(
            b"\xEF\xBB\xBF<?xml version=\"1.0\"?>\n<!-- a <robot> -->\n<mujoco>"
        ));
        assert!(!is_mjcf(b"<robot name=\"mujoco\"/>"));
        assert!(!is_mjcf(b"<mujocox/>"));
        assert!(!is_mjcf(b"<!-- unterminated"));
        assert!(!is_mjcf(b""));
    }
}
