//! The expansion walk, Python xacro's `eval_all`: each element's attributes are evaluated,
//! then its children in document order, where xacro's own elements act (properties, macros,
//! args, includes, conditionals, blocks, element/attribute) and every other element is copied
//! with its text evaluated.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::rc::Rc;

use crate::expr::ExprError;
use crate::files::Source;
use crate::macros::Macro;
use crate::packages::Packages;
use crate::tree::{self, Element, Node, Pos};
use crate::value::{boolean, literal, Value};
use crate::{Expansion, Options, XacroError, MAX_INCLUDE_DEPTH, MAX_MACRO_DEPTH, MAX_OUTPUT_BYTES};

/// A property's value: evaluated, or the raw text of a lazy property, evaluated at first use.
#[derive(Clone, Debug)]
pub enum Slot {
    /// The value.
    Ready(Value),
    /// The raw text, evaluated in its own scope when first used, and where it is defined.
    Lazy(Rc<str>, Pos),
}

/// A table of properties; `parent` is the enclosing table (a macro call's caller).
#[derive(Default)]
pub struct Scope {
    pub parent: Option<usize>,
    pub vars: HashMap<String, Slot>,
}

/// A file read, and the include element that read it.
pub struct File {
    pub path: PathBuf,
    pub included_from: Option<Pos>,
}

/// The state of one expansion.
pub struct Expander {
    /// Where files are read from.
    pub source: Source,
    pub packages: Packages,
    pub files: Vec<File>,
    /// Files being expanded, innermost last (relative paths are relative to the last).
    pub file_stack: Vec<usize>,
    /// Substitution arguments (`$(arg)`): the caller's, then `xacro:arg` defaults.
    pub args: HashMap<String, String>,
    /// Property tables; a macro call pushes one and drops it when it returns.
    pub scopes: Vec<Scope>,
    /// Lazy properties being evaluated (scope, name), to report circular definitions.
    pub resolving: Vec<(usize, String)>,
    /// Macro tables, innermost last; a macro call pushes one.
    pub macros: Vec<HashMap<String, Rc<Macro>>>,
    /// Macro calls being expanded: name and the call's position.
    pub calls: Vec<(String, Pos)>,
    /// Bytes of output produced so far (an estimate, for the size guard).
    pub produced: usize,
    /// The size limit of the document.
    pub limit: usize,
    pub warnings: Vec<String>,
}

impl Expander {
    /// A fresh expansion with the caller's options.
    pub fn new(opts: &Options) -> Expander {
        let source = match &opts.files {
            Some(files) => Source::Memory(files.clone()),
            None => Source::Disk,
        };
        Expander {
            packages: Packages::new(&opts.packages, source.clone()),
            source,
            files: Vec::new(),
            file_stack: Vec::new(),
            args: opts.args.iter().cloned().collect(),
            scopes: vec![Scope::default()],
            resolving: Vec::new(),
            macros: vec![HashMap::new()],
            calls: Vec::new(),
            produced: 0,
            limit: opts
                .max_bytes
                .unwrap_or(MAX_OUTPUT_BYTES)
                .min(MAX_OUTPUT_BYTES),
            warnings: Vec::new(),
        }
    }

    /// Expands the file at `path` into a document.
    pub fn run(mut self, path: &Path) -> Result<Expansion, XacroError> {
        let root = self.read(path, None)?;
        let mut out = self.element(&root, 0)?;
        out.attrs.retain(|(k, _)| k != "xmlns:xacro");
        let mut xml = String::from("<?xml version=\"1.0\" ?>\n");
        tree::write(&out, &mut xml);
        xml.push('\n');
        if xml.len() > self.limit {
            return Err(self.too_large(root.pos));
        }
        Ok(Expansion {
            xml,
            files: self.files.into_iter().map(|f| f.path).collect(),
            warnings: self.warnings,
        })
    }

    /// Reads and parses a file, registering it; it becomes the current file.
    fn read(&mut self, path: &Path, from: Option<Pos>) -> Result<Element, XacroError> {
        let index = self.files.len();
        self.files.push(File {
            path: path.to_path_buf(),
            included_from: from,
        });
        let here = Pos {
            file: index,
            line: 0,
        };
        let text = read_capped(&self.source, path).map_err(|e| match from {
            Some(at) => self.invalid(at, &format!("cannot read '{}': {e}", path.display())),
            None => XacroError::Invalid(format!("{}: cannot read the file: {e}", path.display())),
        })?;
        let root = tree::parse(&text, index).map_err(|e| match e {
            tree::ParseError::Malformed(m) => self.invalid(here, &format!("invalid XML: {m}")),
            tree::ParseError::Unsupported(construct, m) => {
                let (head, tail) = self.location(here);
                XacroError::Unsupported {
                    construct: construct.to_string(),
                    message: format!(
                        "{head}: {construct} are not supported by the native xacro expansion ({m}){tail}"
                    ),
                }
            }
        })?;
        self.file_stack.push(index);
        Ok(root)
    }

    /// `file: line N` of `pos`, and the context after the message: the include chain and the
    /// macro being expanded.
    pub fn location(&self, pos: Pos) -> (String, String) {
        let name = |i: usize| {
            self.files
                .get(i)
                .map(|f| display(&f.path))
                .unwrap_or_default()
        };
        let mut head = name(pos.file);
        if pos.line > 0 {
            head.push_str(&format!(": line {}", pos.line));
        }
        let mut tail = String::new();
        let mut from = self.files.get(pos.file).and_then(|f| f.included_from);
        while let Some(at) = from {
            tail.push_str(&format!(
                " (included from {}: line {})",
                name(at.file),
                at.line
            ));
            from = self.files.get(at.file).and_then(|f| f.included_from);
        }
        if let Some((m, at)) = self.calls.last() {
            tail.push_str(&format!(
                " (in macro '{m}' called at {}: line {})",
                name(at.file),
                at.line
            ));
        }
        (head, tail)
    }

    /// An error at `pos`.
    pub fn invalid(&self, pos: Pos, message: &str) -> XacroError {
        let (head, tail) = self.location(pos);
        XacroError::Invalid(format!("{head}: {message}{tail}"))
    }

    /// An expression error at `pos` (unsupported constructs stay distinguishable).
    pub fn fail(&self, pos: Pos, e: ExprError) -> XacroError {
        let (head, tail) = self.location(pos);
        let message = format!("{head}: {}{tail}", e.message);
        match e.unsupported {
            Some(construct) => XacroError::Unsupported { construct, message },
            None => XacroError::Invalid(message),
        }
    }

    /// An unsupported construct at `pos`.
    pub fn unsupported(&self, pos: Pos, construct: &str) -> XacroError {
        self.fail(pos, ExprError::unsupported(construct))
    }

    fn too_large(&self, pos: Pos) -> XacroError {
        self.invalid(
            pos,
            &format!("the expanded document exceeds {} bytes", self.limit),
        )
    }

    /// The text of `text` evaluated in `scope`, as `str()` gives it.
    pub fn text_at(&mut self, text: &str, scope: usize, pos: Pos) -> Result<String, XacroError> {
        self.eval_text(text, scope)
            .map(|v| v.to_text())
            .map_err(|e| self.fail(pos, e))
    }

    /// A required attribute of a xacro element.
    pub fn required<'e>(&self, e: &'e Element, name: &str) -> Result<&'e str, XacroError> {
        e.attr(name).ok_or_else(|| {
            self.invalid(e.pos, &format!("<{}> needs the attribute '{name}'", e.name))
        })
    }

    /// An ordinary element: attributes evaluated, then its content.
    pub fn element(&mut self, e: &Element, scope: usize) -> Result<Element, XacroError> {
        let mut attrs = Vec::with_capacity(e.attrs.len());
        for (k, v) in &e.attrs {
            if k.starts_with("xacro:") || k == "xmlns:xacro" {
                continue;
            }
            attrs.push((k.clone(), self.text_at(v, scope, e.pos)?));
        }
        self.produced += 2 * e.name.len()
            + 5
            + attrs
                .iter()
                .map(|(k, v)| k.len() + v.len() + 4)
                .sum::<usize>();
        if self.produced > self.limit {
            return Err(self.too_large(e.pos));
        }
        let mut children = Vec::new();
        self.content(&e.children, scope, &mut children, &mut attrs, e.pos)?;
        Ok(Element {
            name: e.name.clone(),
            attrs,
            children,
            pos: e.pos,
        })
    }

    /// Expands `nodes` (the content of an element at `pos`) into `out`; `xacro:attribute` sets
    /// attributes of `attrs`.
    pub fn content(
        &mut self,
        nodes: &[Node],
        scope: usize,
        out: &mut Vec<Node>,
        attrs: &mut Vec<(String, String)>,
        pos: Pos,
    ) -> Result<(), XacroError> {
        for node in nodes {
            match node {
                Node::Element(e) => self.node(e, scope, out, attrs)?,
                Node::Text(t) => {
                    let t = self.text_at(t, scope, pos)?;
                    self.charge(t.len(), pos)?;
                    out.push(Node::Text(t));
                }
                Node::Comment(c) => out.push(Node::Comment(c.clone())),
            }
        }
        Ok(())
    }

    fn node(
        &mut self,
        e: &Element,
        scope: usize,
        out: &mut Vec<Node>,
        attrs: &mut Vec<(String, String)>,
    ) -> Result<(), XacroError> {
        let Some(kind) = e.name.strip_prefix("xacro:") else {
            let done = self.element(e, scope)?;
            out.push(Node::Element(done));
            return Ok(());
        };
        match kind {
            "property" => self.property(e, scope),
            "macro" => self.define_macro(e),
            "arg" => {
                let name = self.required(e, "name")?.to_string();
                let default = self.required(e, "default")?.to_string();
                if !self.args.contains_key(&name) {
                    let value = self.text_at(&default, scope, e.pos)?;
                    self.args.insert(name, value);
                }
                Ok(())
            }
            "include" => self.include(e, scope, out, attrs),
            "if" | "unless" => {
                let cond = self.required(e, "value")?;
                let value = self
                    .eval_text(cond, scope)
                    .map_err(|x| self.fail(e.pos, x))?;
                let keep = boolean(&value).map_err(|m| {
                    self.invalid(e.pos, &format!("<{}> condition '{cond}': {m}", e.name))
                })?;
                if keep == (kind == "if") {
                    self.content(&e.children, scope, out, &mut Vec::new(), e.pos)?;
                }
                Ok(())
            }
            "insert_block" => {
                let name = self.required(e, "name")?;
                let (block, inner) = match self.lookup_at(&format!("**{name}"), scope, e.pos)? {
                    Some(v) => (v, true),
                    None => match self.lookup_at(&format!("*{name}"), scope, e.pos)? {
                        Some(v) => (v, false),
                        None => {
                            return Err(self.invalid(e.pos, &format!("undefined block '{name}'")))
                        }
                    },
                };
                let Value::Block(block) = block else {
                    return Err(self.invalid(
                        e.pos,
                        &format!("'{name}' is a {}, not a block", block.type_name()),
                    ));
                };
                let done = self.element(&block, scope)?;
                if inner {
                    out.extend(done.children);
                } else {
                    out.push(Node::Element(done));
                }
                Ok(())
            }
            "element" => {
                let raw = self.required(e, "xacro:name")?;
                let name = self.text_at(raw, scope, e.pos)?;
                if name.is_empty() {
                    return Err(self.invalid(e.pos, "xacro:element: empty name"));
                }
                let mut renamed = e.clone();
                renamed.name = name;
                renamed.attrs.retain(|(k, _)| k != "xacro:name");
                self.node(&renamed, scope, out, attrs)
            }
            "attribute" => {
                let name = self.text_at(self.required(e, "name")?, scope, e.pos)?;
                let value = self.text_at(self.required(e, "value")?, scope, e.pos)?;
                if name.is_empty() {
                    return Err(self.invalid(e.pos, "xacro:attribute: empty name"));
                }
                Element::set_attr(attrs, &name, value);
                Ok(())
            }
            "call" => {
                let raw = self.required(e, "macro")?;
                let name = self.text_at(raw, scope, e.pos)?;
                let mut call = e.clone();
                call.name = format!("xacro:{name}");
                call.attrs.retain(|(k, _)| k != "macro");
                self.call_macro(&call, &name, scope, out)
            }
            name => self.call_macro(e, name, scope, out),
        }
    }

    /// A property lookup whose failure is reported at `pos`.
    pub fn lookup_at(
        &mut self,
        name: &str,
        scope: usize,
        pos: Pos,
    ) -> Result<Option<Value>, XacroError> {
        self.lookup(name, scope).map_err(|x| self.fail(pos, x))
    }

    /// Python xacro's `grab_property`.
    fn property(&mut self, e: &Element, scope: usize) -> Result<(), XacroError> {
        let name = self.text_at(self.required(e, "name")?, scope, e.pos)?;
        if !is_identifier(&name) || name.starts_with("__") {
            return Err(self.invalid(
                e.pos,
                &format!("expected a property name that is a Python identifier, found '{name}'"),
            ));
        }
        let remove = match e.attr("remove") {
            Some(r) => {
                let v = self.eval_text(r, scope).map_err(|x| self.fail(e.pos, x))?;
                boolean(&v).map_err(|m| self.invalid(e.pos, &m))?
            }
            None => false,
        };
        let (value, default) = (e.attr("value"), e.attr("default"));
        if usize::from(value.is_some()) + usize::from(default.is_some()) + usize::from(remove) > 1 {
            return Err(self.invalid(
                e.pos,
                &format!("property '{name}': value, default and remove exclude one another"),
            ));
        }
        if remove {
            let mut s = Some(scope);
            while let Some(k) = s {
                self.scopes[k].vars.remove(&name);
                s = self.scopes[k].parent;
            }
            return Ok(());
        }
        let mut value = value.map(Value::str);
        let mut name = name;
        if let Some(d) = default {
            if self.lookup_at(&name, scope, e.pos)?.is_some()
                || crate::expr::builtins::global(&name).is_some()
            {
                return Ok(());
            }
            value = Some(Value::str(d));
        }
        let value = match value {
            Some(v) => v,
            None => {
                name = format!("**{name}");
                Value::Block(Rc::new(e.clone()))
            }
        };
        let mut lazy = match e.attr("lazy_eval") {
            Some(l) => {
                let v = self.eval_text(l, scope).map_err(|x| self.fail(e.pos, x))?;
                boolean(&v).map_err(|m| self.invalid(e.pos, &m))?
            }
            None => true,
        };
        let target = match e.attr("scope") {
            Some("global") => {
                lazy = false;
                0
            }
            Some("parent") => match self.scopes[scope].parent {
                Some(p) => {
                    lazy = false;
                    p
                }
                None => {
                    let (head, tail) = self.location(e.pos);
                    self.warnings.push(format!(
                        "{head}: property '{name}': no parent scope at global scope{tail}"
                    ));
                    return Ok(());
                }
            },
            _ => scope,
        };
        let value = match value {
            Value::Str(s) if !lazy => self.eval_text(&s, scope).map_err(|x| self.fail(e.pos, x))?,
            v => v,
        };
        let slot = match literal(value) {
            Value::Str(s) if lazy => Slot::Lazy(s, e.pos),
            v => Slot::Ready(v),
        };
        self.scopes[target].vars.insert(name, slot);
        Ok(())
    }

    /// `xacro:include`: the included file's content replaces the element.
    fn include(
        &mut self,
        e: &Element,
        scope: usize,
        out: &mut Vec<Node>,
        _attrs: &mut [(String, String)],
    ) -> Result<(), XacroError> {
        if e.attr("ns").is_some() {
            return Err(self.unsupported(e.pos, "namespaced includes (ns=)"));
        }
        let spec = self.text_at(self.required(e, "filename")?, scope, e.pos)?;
        if spec.contains(['*', '?', '[']) {
            return Err(self.unsupported(e.pos, "includes with a glob pattern"));
        }
        let optional = match e.attr("optional") {
            Some(o) => boolean(&Value::str(o)).map_err(|m| self.invalid(e.pos, &m))?,
            None => false,
        };
        let path = self.relative(&spec);
        if self.file_stack.len() >= MAX_INCLUDE_DEPTH {
            return Err(self.invalid(
                e.pos,
                &format!("includes nested deeper than {MAX_INCLUDE_DEPTH}"),
            ));
        }
        let key = self.source.canonical(&path);
        let open: Vec<PathBuf> = self
            .file_stack
            .iter()
            .filter_map(|&i| self.files.get(i))
            .map(|f| self.source.canonical(&f.path))
            .collect();
        if let Some(first) = open.iter().position(|p| *p == key) {
            let chain: Vec<String> = open[first..]
                .iter()
                .chain(std::iter::once(&key))
                .map(|p| display(p))
                .collect();
            return Err(self.invalid(e.pos, &format!("include cycle: {}", chain.join(" -> "))));
        }
        if optional && !self.source.is_file(&path) {
            return Ok(());
        }
        let root = self.read(&path, Some(e.pos))?;
        // Python's xacro evaluates the included root's attributes too (and fails as it does).
        for (k, v) in &root.attrs {
            if !k.starts_with("xmlns") && !k.starts_with("xacro:") {
                self.text_at(v, scope, root.pos)?;
            }
        }
        let result = self.content(&root.children, scope, out, &mut Vec::new(), root.pos);
        self.file_stack.pop();
        result
    }

    /// `spec` relative to the folder of the file being expanded.
    pub fn relative(&self, spec: &str) -> PathBuf {
        let p = PathBuf::from(spec);
        if p.is_absolute() {
            return p;
        }
        let dir = self
            .file_stack
            .last()
            .and_then(|&i| self.files.get(i))
            .and_then(|f| f.path.parent().map(Path::to_path_buf))
            .unwrap_or_default();
        dir.join(p)
    }

    /// Counts `bytes` of output against the size limit.
    pub fn charge(&mut self, bytes: usize, pos: Pos) -> Result<(), XacroError> {
        self.produced = self.produced.saturating_add(bytes);
        if self.produced > self.limit {
            return Err(self.too_large(pos));
        }
        Ok(())
    }

    /// The depth guard of macro calls.
    pub fn check_depth(&self, pos: Pos) -> Result<(), XacroError> {
        if self.calls.len() >= MAX_MACRO_DEPTH {
            let name = self.calls.last().map_or("", |(n, _)| n.as_str());
            return Err(self.invalid(
                pos,
                &format!(
                    "macro calls nested deeper than {MAX_MACRO_DEPTH} (does '{name}' call itself without end?)"
                ),
            ));
        }
        Ok(())
    }
}

/// Reads a file of at most [`MAX_OUTPUT_BYTES`] as UTF-8 text.
pub fn read_capped(source: &Source, path: &Path) -> Result<String, String> {
    let mut bytes = source.read(path, MAX_OUTPUT_BYTES)?;
    if bytes.len() > MAX_OUTPUT_BYTES {
        return Err(format!("the file exceeds {MAX_OUTPUT_BYTES} bytes"));
    }
    if bytes.starts_with(b"\xEF\xBB\xBF") {
        bytes.drain(..3);
    }
    String::from_utf8(bytes).map_err(|_| "expected UTF-8 text".to_string())
}

/// The file name of `path`, for messages (outputs stay the same wherever files live).
pub fn display(path: &Path) -> String {
    path.file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string())
}

fn is_identifier(name: &str) -> bool {
    let mut chars = name.chars();
    chars.next().is_some_and(|c| c.is_alphabetic() || c == '_')
        && chars.all(|c| c.is_alphanumeric() || c == '_')
        && !matches!(
            name,
            "and"
                | "or"
                | "not"
                | "if"
                | "else"
                | "in"
                | "is"
                | "lambda"
                | "for"
                | "None"
                | "True"
                | "False"
        )
}
