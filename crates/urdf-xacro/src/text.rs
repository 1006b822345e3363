//! Text evaluation, Python xacro's `eval_text`: a text is split into plain pieces, `${expr}`
//! (up to the first `}`), `$(command args)` (up to the first `)`) and `$$`-escapes; one piece
//! keeps its type (`${1+1}` is the int 2), several are joined as `str()` gives them. Also the
//! lazy lookup of properties and the substitution commands (`arg`, `find`, `env`, `optenv`,
//! `dirname`, `cwd`, `eval`).

use crate::expand::{Expander, Slot};
use crate::expr::{self, ExprError, Names};
use crate::value::{literal, parse_float, parse_int, Value};
use crate::MAX_EVAL_DEPTH;

/// A piece of a text.
enum Piece<'a> {
    Text(&'a str),
    Expr(&'a str),
    Command(&'a str),
}

/// Splits `text` as xacro's lexer does.
fn pieces(text: &str) -> Result<Vec<Piece<'_>>, ExprError> {
    let mut out = Vec::new();
    let mut rest = text;
    while !rest.is_empty() {
        if let Some(after) = rest.strip_prefix('$') {
            let dollars = after.len() - after.trim_start_matches('$').len();
            let next = after[dollars..].chars().next();
            if dollars > 0 && matches!(next, Some('{' | '(')) {
                // `$${` / `$$(`: one `$` dropped, the rest is text.
                out.push(Piece::Text(&after[..dollars + 1]));
                rest = &after[dollars + 1..];
            } else if let Some(body) = after.strip_prefix('{') {
                let end = body.find('}').ok_or_else(|| {
                    ExprError::new(format!("expected '}}' to close '${{' in '{text}'"))
                })?;
                out.push(Piece::Expr(&body[..end]));
                rest = &body[end + 1..];
            } else if let Some(body) = after.strip_prefix('(') {
                let end = body.find(')').ok_or_else(|| {
                    ExprError::new(format!("expected ')' to close '$(' in '{text}'"))
                })?;
                out.push(Piece::Command(&body[..end]));
                rest = &body[end + 1..];
            } else if dollars > 0 {
                return Err(ExprError::new(format!("invalid expression: '{rest}'")));
            } else {
                let end = after.find(['{', '(', '$']).map_or(rest.len(), |k| k + 1);
                out.push(Piece::Text(&rest[..end]));
                rest = &rest[end..];
            }
        } else {
            let end = rest.find('$').unwrap_or(rest.len());
            out.push(Piece::Text(&rest[..end]));
            rest = &rest[end..];
        }
    }
    Ok(out)
}

impl Expander {
    /// Evaluates `text` in property table `scope`.
    ///
    /// # Errors
    /// A failing expression or substitution, with the expression quoted.
    pub fn eval_text(&mut self, text: &str, scope: usize) -> Result<Value, ExprError> {
        if !text.contains('$') {
            return Ok(Value::str(text));
        }
        let mut values = Vec::new();
        for piece in pieces(text)? {
            values.push(match piece {
                Piece::Text(t) => Value::str(t),
                Piece::Expr(src) => {
                    let src_text = self.eval_text(src, scope)?.to_text();
                    let mut names = Symbols { ex: self, scope };
                    expr::evaluate(&src_text, &mut names).map_err(|mut e| {
                        // The innermost expression is the one to quote.
                        if !e.message.contains(" in '${") {
                            e.message = format!("{} in '${{{src}}}'", e.message);
                        }
                        e
                    })?
                }
                Piece::Command(cmd) => {
                    let cmd = self.eval_text(cmd, scope)?.to_text();
                    Value::str(self.substitute(&cmd)?)
                }
            });
        }
        if values.len() == 1 {
            return Ok(values.pop().unwrap_or(Value::None));
        }
        let joined: String = values.iter().map(Value::to_text).collect();
        if joined.len() > crate::MAX_OUTPUT_BYTES {
            return Err(ExprError::new("a text exceeds the size limit"));
        }
        Ok(Value::str(joined))
    }

    /// The property `name` as seen from `scope`, evaluating a lazy one (once) in its own table.
    ///
    /// # Errors
    /// The lazy evaluation fails, or the definition is circular or too deep.
    pub fn lookup(&mut self, name: &str, scope: usize) -> Result<Option<Value>, ExprError> {
        let mut at = Some(scope);
        while let Some(k) = at {
            let Some(s) = self.scopes.get(k) else { break };
            match s.vars.get(name) {
                Some(Slot::Ready(v)) => return Ok(Some(v.clone())),
                Some(Slot::Lazy(raw, at)) => {
                    let (raw, at) = (raw.clone(), *at);
                    if let Some(first) = self
                        .resolving
                        .iter()
                        .position(|(s, n)| *s == k && n == name)
                    {
                        let chain: Vec<&str> = self.resolving[first..]
                            .iter()
                            .map(|(_, n)| n.as_str())
                            .chain(std::iter::once(name))
                            .collect();
                        return Err(ExprError::new(format!(
                            "circular property definition: {}",
                            chain.join(" -> ")
                        )));
                    }
                    if self.resolving.len() >= MAX_EVAL_DEPTH {
                        return Err(ExprError::new(format!(
                            "properties refer to one another deeper than {MAX_EVAL_DEPTH}"
                        )));
                    }
                    self.resolving.push((k, name.to_string()));
                    let value = self.eval_text(&raw, k);
                    self.resolving.pop();
                    let value = literal(value.map_err(|mut e| {
                        if !e.message.contains("(property '") {
                            let (head, _) = self.location(at);
                            e.message = format!("{} (property '{name}' of {head})", e.message);
                        }
                        e
                    })?);
                    if let Some(s) = self.scopes.get_mut(k) {
                        s.vars.insert(name.to_string(), Slot::Ready(value.clone()));
                    }
                    return Ok(Some(value));
                }
                None => at = s.parent,
            }
        }
        Ok(None)
    }

    fn arg(&self, name: &str) -> Result<String, ExprError> {
        self.args
            .get(name)
            .cloned()
            .ok_or_else(|| ExprError::new(format!("undefined argument '{name}'")))
    }

    fn find(&mut self, pkg: &str) -> Result<String, ExprError> {
        self.packages
            .find(pkg)
            .map(|p| p.to_string_lossy().into_owned())
            .map_err(ExprError::new)
    }

    fn dirname(&self) -> Result<String, ExprError> {
        let file = self.file_stack.last().and_then(|&i| self.files.get(i));
        let dir = file
            .and_then(|f| f.path.parent())
            .unwrap_or(std::path::Path::new("."));
        Ok(std::path::absolute(dir)
            .unwrap_or_else(|_| dir.to_path_buf())
            .to_string_lossy()
            .into_owned())
    }

    /// A substitution `$(cmd)`, `cmd` being the text inside the parentheses.
    fn substitute(&mut self, cmd: &str) -> Result<String, ExprError> {
        if let Some(src) = cmd.strip_prefix("eval ") {
            if src.contains("__") {
                return Err(ExprError::new("$(eval) may not contain '__'"));
            }
            let mut names = EvalArgs { ex: self };
            return Ok(expr::evaluate(src, &mut names)?.to_text());
        }
        let words: Vec<&str> = cmd.split(' ').filter(|w| !w.is_empty()).collect();
        let resolved = match words.as_slice() {
            ["cwd"] => std::env::current_dir()
                .map(|d| d.to_string_lossy().into_owned())
                .map_err(|e| ExprError::new(format!("$(cwd): {e}")))?,
            ["arg", name] => self.arg(name)?,
            ["find", pkg] => self.find(pkg)?,
            ["env", var] => std::env::var(var)
                .map_err(|_| ExprError::new(format!("environment variable {var} is not set")))?,
            ["optenv", var, default @ ..] => {
                std::env::var(var).unwrap_or_else(|_| default.join(" "))
            }
            ["dirname"] => self.dirname()?,
            ["anon", ..] => return Err(ExprError::unsupported("$(anon) substitutions")),
            [c @ ("arg" | "find" | "env" | "dirname" | "cwd"), ..] => {
                return Err(ExprError::new(format!(
                    "$({c}) takes {} argument{}, found '$({cmd})'",
                    usize::from(!matches!(*c, "dirname" | "cwd")),
                    if matches!(*c, "dirname" | "cwd") { "s" } else { "" }
                )))
            }
            _ => {
                return Err(ExprError::new(format!(
                    "unknown substitution '$({cmd})' (expected arg, find, env, optenv, dirname, cwd or eval)"
                )))
            }
        };
        // roslaunch resolves `$(find)` once more in what an argument held.
        let mut out = resolved;
        while let Some(start) = out.find("$(find ") {
            let Some(len) = out[start..].find(')') else {
                break;
            };
            let pkg = out[start + 7..start + len].trim().to_string();
            let dir = self.find(&pkg)?;
            out.replace_range(start..start + len + 1, &dir);
        }
        Ok(out)
    }
}

/// Names of `${}`: the property tables from `scope` outwards, and `xacro.load_yaml` /
/// `xacro.arg`.
struct Symbols<'a> {
    ex: &'a mut Expander,
    scope: usize,
}

impl Names for Symbols<'_> {
    fn lookup(&mut self, name: &str) -> Result<Option<Value>, ExprError> {
        self.ex.lookup(name, self.scope)
    }

    fn call(&mut self, name: &str, args: &[Value]) -> Result<Option<Value>, ExprError> {
        match (name, args) {
            ("load_yaml", [file]) => {
                let path = self.ex.relative(&file.to_text());
                self.ex.files.push(crate::expand::File {
                    path: path.clone(),
                    included_from: None,
                });
                crate::yaml::load(&self.ex.source, &path).map(Some)
            }
            ("xacro.arg", [n]) => Ok(Some(Value::str(self.ex.arg(&n.to_text())?))),
            _ => Ok(None),
        }
    }
}

/// Names of `$(eval)`: roslaunch's — the arguments (as numbers or booleans where they read as
/// such), `arg()`, `find()`, `env()`, `optenv()`, `dirname()`, `true`/`false`, and `math`.
struct EvalArgs<'a> {
    ex: &'a mut Expander,
}

/// roslaunch's `convert_value(value, 'auto')`.
fn auto(value: &str) -> Value {
    let number = if value.contains('.') {
        parse_float(value).map(Value::Float)
    } else {
        parse_int(value).map(Value::Int)
    };
    number.unwrap_or_else(|| match value.to_ascii_lowercase().as_str() {
        "true" => Value::Bool(true),
        "false" => Value::Bool(false),
        _ => Value::str(value),
    })
}

impl Names for EvalArgs<'_> {
    fn lookup(&mut self, name: &str) -> Result<Option<Value>, ExprError> {
        Ok(match name {
            "true" | "True" => Some(Value::Bool(true)),
            "false" | "False" => Some(Value::Bool(false)),
            "arg" => Some(Value::Builtin("arg")),
            "find" => Some(Value::Builtin("find")),
            "env" => Some(Value::Builtin("env")),
            "optenv" => Some(Value::Builtin("optenv")),
            "dirname" => Some(Value::Builtin("dirname")),
            n if expr::builtins::global(n).is_some() => None,
            n => self.ex.args.get(n).map(|v| auto(v)),
        })
    }

    fn call(&mut self, name: &str, args: &[Value]) -> Result<Option<Value>, ExprError> {
        let text: Vec<String> = args.iter().map(Value::to_text).collect();
        Ok(Some(match (name, text.as_slice()) {
            ("arg", [n]) => auto(&self.ex.arg(n)?),
            ("find", [p]) => Value::str(self.ex.find(p)?),
            ("env", [v]) => Value::str(
                std::env::var(v)
                    .map_err(|_| ExprError::new(format!("environment variable {v} is not set")))?,
            ),
            ("optenv", [v]) => Value::str(std::env::var(v).unwrap_or_default()),
            ("optenv", [v, d]) => Value::str(std::env::var(v).unwrap_or_else(|_| d.clone())),
            ("dirname", []) => Value::str(self.ex.dirname()?),
            ("arg" | "find" | "env" | "optenv" | "dirname", _) => {
                return Err(ExprError::new(format!(
                    "{name}() called with wrong arguments"
                )))
            }
            _ => return Ok(None),
        }))
    }
}
