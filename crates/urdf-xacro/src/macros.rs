//! Macros: definitions (`<xacro:macro name params>`) and calls (`<xacro:NAME a="..">blocks`),
//! as Python xacro's `grab_macro` and `handle_macro_call` do them. A call's body is expanded
//! in a new property table whose parent is the caller's (xacro's scoping is dynamic), with a
//! new macro table for macros defined inside it.

use std::collections::HashMap;
use std::rc::Rc;

use crate::expand::{Expander, Scope, Slot};
use crate::tree::{Element, Node};
use crate::value::{literal, Value};
use crate::XacroError;

/// A parameter's default: forwarded from the caller's property of the same name (`^`), and/or
/// a default text.
#[derive(Clone, Debug, PartialEq)]
pub struct Default {
    /// `^` or `^|`: take the caller's property of the same name when it exists.
    pub forward: bool,
    /// The default text, evaluated in the caller's scope.
    pub text: Option<String>,
}

/// A macro definition.
#[derive(Debug)]
pub struct Macro {
    /// Parameter names in order, block parameters with their `*` / `**`.
    pub params: Vec<String>,
    /// Defaults of the parameters that have one.
    pub defaults: HashMap<String, Default>,
    /// The `<xacro:macro>` element (its content is the body).
    pub body: Element,
}

/// Splits a `params` attribute into parameters: `a`, `b:=1`, `c:=^`, `d:=^|x`, `*e`, `**f`,
/// defaults quoted (`'a b'`) or holding `${...}` / `$(...)` with spaces.
pub fn parse_params(spec: &str) -> Vec<(String, Option<Default>)> {
    let mut out = Vec::new();
    let mut rest = spec.trim_start();
    while !rest.is_empty() {
        let name_end = rest
            .find(|c: char| c.is_whitespace() || c == ':' || c == '=')
            .unwrap_or(rest.len());
        let name = &rest[..name_end];
        let after = rest[name_end..].trim_start();
        let assign = after.strip_prefix(":=").or_else(|| after.strip_prefix('='));
        match (name.is_empty(), assign) {
            (false, Some(value)) => {
                let mut value = value.trim_start();
                let forward = if let Some(v) = value.strip_prefix("^|") {
                    value = v;
                    true
                } else if let Some(v) = value.strip_prefix('^') {
                    value = v;
                    true
                } else {
                    false
                };
                let len = default_len(value);
                let text = &value[..len];
                out.push((
                    name.to_string(),
                    Some(Default {
                        forward,
                        text: (!text.is_empty()).then(|| text.to_string()),
                    }),
                ));
                rest = value[len..].trim_start();
            }
            _ => {
                let end = rest.find(char::is_whitespace).unwrap_or(rest.len());
                out.push((rest[..end].to_string(), None));
                rest = rest[end..].trim_start();
            }
        }
    }
    out
}

/// The length of the default text at the start of `s`: up to whitespace outside quotes and
/// outside `${...}` / `$(...)`.
fn default_len(s: &str) -> usize {
    let bytes = s.as_bytes();
    let mut i = 0;
    while let Some(&b) = bytes.get(i) {
        let close = match (b, bytes.get(i + 1)) {
            (b'\'', _) => Some(b'\''),
            (b'"', _) => Some(b'"'),
            (b'$', Some(b'{')) => Some(b'}'),
            (b'$', Some(b'(')) => Some(b')'),
            _ => None,
        };
        match close {
            Some(c) => {
                let from = if b == b'$' { i + 2 } else { i + 1 };
                i = bytes[from.min(bytes.len())..]
                    .iter()
                    .position(|&x| x == c)
                    .map_or(bytes.len(), |k| from + k + 1);
            }
            None if b.is_ascii_whitespace() => return i,
            None => i += 1,
        }
    }
    bytes.len()
}

impl Expander {
    /// Records a `<xacro:macro>` in the innermost macro table.
    pub fn define_macro(&mut self, e: &Element) -> Result<(), XacroError> {
        let name = self.required(e, "name")?.to_string();
        let name = name.strip_prefix("xacro:").unwrap_or(&name).to_string();
        if name == "call" || name.contains('.') {
            return Err(self.invalid(
                e.pos,
                &format!("expected a macro name without '.' other than 'call', found '{name}'"),
            ));
        }
        let mut params = Vec::new();
        let mut defaults = HashMap::new();
        for (p, d) in parse_params(e.attr("params").unwrap_or("")) {
            if let Some(d) = d {
                defaults.insert(p.clone(), d);
            }
            params.push(p);
        }
        let m = Macro {
            params,
            defaults,
            body: e.clone(),
        };
        if let Some(table) = self.macros.last_mut() {
            table.insert(name, Rc::new(m));
        }
        Ok(())
    }

    /// Expands the call `call` of macro `name` into `out`.
    pub fn call_macro(
        &mut self,
        call: &Element,
        name: &str,
        scope: usize,
        out: &mut Vec<Node>,
    ) -> Result<(), XacroError> {
        let Some(m) = self.macros.iter().rev().find_map(|t| t.get(name)).cloned() else {
            return Err(self.invalid(call.pos, &format!("unknown macro name: xacro:{name}")));
        };
        self.check_depth(call.pos)?;
        // Every call counts against the size budget, so that calls which write nothing cannot
        // run without end either.
        self.charge(name.len() + 16, call.pos)?;
        let inner = self.scopes.len();
        self.scopes.push(Scope {
            parent: Some(scope),
            vars: HashMap::new(),
        });
        let result = self.bind_and_expand(call, name, &m, scope, inner, out);
        self.scopes.truncate(inner);
        result
    }

    fn bind_and_expand(
        &mut self,
        call: &Element,
        name: &str,
        m: &Macro,
        scope: usize,
        inner: usize,
        out: &mut Vec<Node>,
    ) -> Result<(), XacroError> {
        let mut params = m.params.clone();
        for (k, v) in &call.attrs {
            if k.starts_with("xmlns") {
                continue;
            }
            let Some(at) = params.iter().position(|p| p == k) else {
                return Err(self.invalid(
                    call.pos,
                    &format!(
                        "macro '{name}' has no parameter '{k}' (its parameters: {})",
                        m.params.join(" ")
                    ),
                ));
            };
            params.remove(at);
            let value = self
                .eval_text(v, scope)
                .map_err(|e| self.fail(call.pos, e))?;
            self.scopes[inner]
                .vars
                .insert(k.clone(), Slot::Ready(literal(value)));
        }
        // Block parameters: the call's content, expanded in the caller's scope.
        let mut content = Vec::new();
        self.content(
            &call.children,
            scope,
            &mut content,
            &mut Vec::new(),
            call.pos,
        )?;
        let mut blocks = content.into_iter().filter_map(|n| match n {
            Node::Element(e) => Some(e),
            _ => None,
        });
        for p in params.clone() {
            if p.starts_with('*') {
                let Some(block) = blocks.next() else {
                    return Err(self.invalid(
                        call.pos,
                        &format!("macro '{name}': not enough blocks (parameter '{p}' has none)"),
                    ));
                };
                self.scopes[inner]
                    .vars
                    .insert(p.clone(), Slot::Ready(Value::Block(Rc::new(block))));
                params.retain(|q| *q != p);
            }
        }
        if let Some(extra) = blocks.next() {
            return Err(self.invalid(
                call.pos,
                &format!("macro '{name}': unused block <{}>", extra.name),
            ));
        }
        for p in params.clone() {
            let Some(d) = m.defaults.get(&p) else {
                continue;
            };
            let forwarded = if d.forward {
                self.lookup_at(&p, scope, call.pos)?
            } else {
                None
            };
            let value = match (forwarded, &d.text) {
                (Some(v), _) => v,
                (None, Some(text)) => self
                    .eval_text(text, scope)
                    .map_err(|e| self.fail(call.pos, e))?,
                (None, None) if d.forward => {
                    return Err(self.invalid(
                        call.pos,
                        &format!("macro '{name}': undefined property to forward: '{p}'"),
                    ))
                }
                (None, None) => continue,
            };
            self.scopes[inner]
                .vars
                .insert(p.clone(), Slot::Ready(literal(value)));
            params.retain(|q| *q != p);
        }
        if !params.is_empty() {
            return Err(self.invalid(
                call.pos,
                &format!("macro '{name}': parameters not set: {}", params.join(", ")),
            ));
        }
        self.calls.push((name.to_string(), call.pos));
        self.macros.push(HashMap::new());
        let result = self.content(&m.body.children, inner, out, &mut Vec::new(), m.body.pos);
        self.macros.pop();
        self.calls.pop();
        result
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn d(forward: bool, text: Option<&str>) -> Option<Default> {
        Some(Default {
            forward,
            text: text.map(str::to_string),
        })
    }

    #[test]
    fn parameters_split_as_xacro_does() {
        let got = parse_params("name *origin **body a:=1 b=${x * 2} c:=^ d:=^|'a b' e:=$(arg f)");
        let want = vec![
            ("name".to_string(), None),
            ("*origin".to_string(), None),
            ("**body".to_string(), None),
            ("a".to_string(), d(false, Some("1"))),
            ("b".to_string(), d(false, Some("${x * 2}"))),
            ("c".to_string(), d(true, None)),
            ("d".to_string(), d(true, Some("'a b'"))),
            ("e".to_string(), d(false, Some("$(arg f)"))),
        ];
        assert_eq!(got, want);
    }
}
