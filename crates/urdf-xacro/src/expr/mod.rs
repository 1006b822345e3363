//! The `${}` expression evaluator: Python's expression grammar as xacro files use it
//! ([`parse`]), evaluated with Python's semantics for the types of [`Value`] (true division
//! `/`, floor division `//`, `**`, short-circuit `and`/`or` that return an operand, chained
//! comparisons). Names are looked up through [`Names`] first (properties, or `$(eval)`'s args),
//! then among the built-ins ([`builtins`]): Python's `math` module, a few of Python's
//! built-in functions, `xacro.load_yaml`.

pub mod builtins;
pub mod lex;
pub mod parse;

use std::rc::Rc;

use crate::value::{equal, order, Num, Value};
use parse::Expr;

/// Strings and lists built by an expression are capped at this many bytes / items (a guard
/// against `'a' * 10**9`; the expanded document is capped at 64 MiB anyway).
pub const MAX_VALUE_LEN: usize = 64 << 20;

/// An error of an expression: its message, and whether it is a construct this evaluator does
/// not support (so that the caller may hand the file to Python's xacro instead).
#[derive(Clone, Debug, PartialEq)]
pub struct ExprError {
    /// The message, lowercase.
    pub message: String,
    /// `Some(construct)` when the expression uses a construct that is not supported.
    pub unsupported: Option<String>,
}

impl ExprError {
    /// An error with `message`.
    pub fn new(message: impl Into<String>) -> ExprError {
        ExprError {
            message: message.into(),
            unsupported: None,
        }
    }

    /// A construct this evaluator does not support.
    pub fn unsupported(construct: &str) -> ExprError {
        ExprError {
            message: format!("{construct} are not supported by the native xacro expansion"),
            unsupported: Some(construct.to_string()),
        }
    }
}

/// What an expression can reach beyond its literals and the built-ins.
pub trait Names {
    /// The value of `name` (a property, or a `$(eval)` argument), `None` when it is undefined.
    ///
    /// # Errors
    /// The value exists but its lazy evaluation fails.
    fn lookup(&mut self, name: &str) -> Result<Option<Value>, ExprError>;

    /// A host function by name: `load_yaml`, `xacro.arg`, and in `$(eval)` `arg`, `find`,
    /// `env`, `optenv`, `dirname`. `None` when the name is not a host function.
    ///
    /// # Errors
    /// The function fails (missing file, undefined argument).
    fn call(&mut self, name: &str, args: &[Value]) -> Result<Option<Value>, ExprError>;
}

/// Evaluates the expression `src`.
///
/// # Errors
/// A syntax error, an undefined name, a type error, division by zero, an unsupported construct.
pub fn evaluate(src: &str, names: &mut dyn Names) -> Result<Value, ExprError> {
    let tokens = lex::tokens(src)?;
    if tokens.is_empty() {
        return Err(ExprError::new("empty expression"));
    }
    let expr = parse::parse(&tokens)?;
    eval(&expr, names)
}

fn eval(e: &Expr, names: &mut dyn Names) -> Result<Value, ExprError> {
    Ok(match e {
        Expr::Lit(v) => v.clone(),
        Expr::Name(n) => match names.lookup(n)? {
            Some(v) => v,
            None => builtins::global(n)
                .ok_or_else(|| ExprError::new(format!("undefined name '{n}'")))?,
        },
        Expr::List(items) => Value::List(Rc::new(
            items
                .iter()
                .map(|i| eval(i, names))
                .collect::<Result<_, _>>()?,
        )),
        Expr::Dict(pairs) => {
            let mut out: Vec<(Value, Value)> = Vec::new();
            for (k, v) in pairs {
                let (k, v) = (eval(k, names)?, eval(v, names)?);
                match out.iter_mut().find(|(k2, _)| equal(&k, k2)) {
                    Some(slot) => slot.1 = v,
                    None => out.push((k, v)),
                }
            }
            Value::Dict(Rc::new(out))
        }
        Expr::Unary(op, a) => unary(op, eval(a, names)?)?,
        Expr::Bin(op, a, b) => binary(op, eval(a, names)?, eval(b, names)?)?,
        Expr::Cmp(first, rest) => {
            let mut left = eval(first, names)?;
            for (op, right) in rest {
                let right = eval(right, names)?;
                if !compare(op, &left, &right)? {
                    return Ok(Value::Bool(false));
                }
                left = right;
            }
            Value::Bool(true)
        }
        Expr::And(a, b) => {
            let a = eval(a, names)?;
            if a.truthy() {
                eval(b, names)?
            } else {
                a
            }
        }
        Expr::Or(a, b) => {
            let a = eval(a, names)?;
            if a.truthy() {
                a
            } else {
                eval(b, names)?
            }
        }
        Expr::IfElse(then, cond, other) => {
            if eval(cond, names)?.truthy() {
                eval(then, names)?
            } else {
                eval(other, names)?
            }
        }
        Expr::Call(f, args, kwargs) => {
            let f = eval(f, names)?;
            let args: Vec<Value> = args
                .iter()
                .map(|a| eval(a, names))
                .collect::<Result<_, _>>()?;
            let kwargs: Vec<(String, Value)> = kwargs
                .iter()
                .map(|(k, v)| Ok((k.clone(), eval(v, names)?)))
                .collect::<Result<_, ExprError>>()?;
            let Value::Builtin(name) = f else {
                return Err(ExprError::new(format!(
                    "a {} is not callable",
                    f.type_name()
                )));
            };
            if kwargs.is_empty() {
                if let Some(v) = names.call(name, &args)? {
                    return Ok(v);
                }
            }
            builtins::call(name, &args, &kwargs)?
        }
        Expr::Index(a, i) => index(&eval(a, names)?, &eval(i, names)?)?,
        Expr::Attr(a, name) => match eval(a, names)? {
            Value::Builtin("xacro")
                if matches!(
                    name.as_str(),
                    "message"
                        | "warning"
                        | "error"
                        | "print_location"
                        | "tokenize"
                        | "abs_filename"
                ) =>
            {
                return Err(ExprError::unsupported(
                    "xacro's message, tokenize and abs_filename functions",
                ))
            }
            Value::Builtin(ns) => builtins::member(ns, name)
                .ok_or_else(|| ExprError::new(format!("'{ns}' has no attribute '{name}'")))?,
            Value::Dict(d) => d
                .iter()
                .find(|(k, _)| matches!(k, Value::Str(s) if **s == **name))
                .map(|(_, v)| v.clone())
                .ok_or_else(|| ExprError::new(format!("the dict has no key '{name}'")))?,
            other => {
                return Err(ExprError::new(format!(
                    "a {} has no attribute '{name}'",
                    other.type_name()
                )))
            }
        },
    })
}

/// A number of `v` for arithmetic, or a type error naming `op`.
pub fn num(v: &Value, op: &str) -> Result<Num, ExprError> {
    v.number().ok_or_else(|| {
        ExprError::new(format!(
            "expected a number for '{op}', found a {} ({})",
            v.type_name(),
            v.repr()
        ))
    })
}

fn overflow(op: &str) -> ExprError {
    ExprError::new(format!("integer overflow in '{op}'"))
}

fn unary(op: &str, a: Value) -> Result<Value, ExprError> {
    Ok(match (op, num(&a, op)) {
        ("not", _) => Value::Bool(!a.truthy()),
        ("+", Ok(Num::Int(i))) => Value::Int(i),
        ("+", Ok(Num::Float(f))) => Value::Float(f),
        ("-", Ok(Num::Int(i))) => Value::Int(i.checked_neg().ok_or_else(|| overflow(op))?),
        ("-", Ok(Num::Float(f))) => Value::Float(-f),
        ("~", Ok(Num::Int(i))) => Value::Int(!i),
        (_, Err(e)) => return Err(e),
        _ => return Err(ExprError::new(format!("bad operand for unary '{op}'"))),
    })
}

fn capped(len: usize) -> Result<(), ExprError> {
    if len > MAX_VALUE_LEN {
        return Err(ExprError::new(format!(
            "a value of {len} bytes or items exceeds the limit of {MAX_VALUE_LEN}"
        )));
    }
    Ok(())
}

fn repeat(v: &Value, times: i64) -> Result<Value, ExprError> {
    let n = usize::try_from(times.max(0)).unwrap_or(0);
    match v {
        Value::Str(s) => {
            capped(s.len().saturating_mul(n))?;
            Ok(Value::str(s.repeat(n)))
        }
        Value::List(l) => {
            capped(l.len().saturating_mul(n))?;
            Ok(Value::List(Rc::new(
                (0..n).flat_map(|_| l.iter().cloned()).collect(),
            )))
        }
        _ => Err(ExprError::new("bad operands for '*'")),
    }
}

/// Python's binary arithmetic `a op b`.
///
/// # Errors
/// Type errors, division by zero, integer overflow.
pub fn binary(op: &str, a: Value, b: Value) -> Result<Value, ExprError> {
    match (op, &a, &b) {
        ("+", Value::Str(x), Value::Str(y)) => {
            capped(x.len() + y.len())?;
            return Ok(Value::str(format!("{x}{y}")));
        }
        ("+", Value::List(x), Value::List(y)) => {
            capped(x.len() + y.len())?;
            return Ok(Value::List(Rc::new(
                x.iter().chain(y.iter()).cloned().collect(),
            )));
        }
        ("*", Value::Str(_) | Value::List(_), Value::Int(n))
        | ("*", Value::Int(n), Value::Str(_) | Value::List(_)) => {
            let seq = if matches!(a, Value::Int(_)) { &b } else { &a };
            return repeat(seq, *n);
        }
        ("%", Value::Str(_), _) => return Err(ExprError::unsupported("string formatting with %")),
        _ => {}
    }
    let (x, y) = (num(&a, op)?, num(&b, op)?);
    let zero = || ExprError::new(format!("division by zero: {} {op} {}", a.repr(), b.repr()));
    if let (Num::Int(i), Num::Int(j)) = (x, y) {
        return Ok(match op {
            "+" => Value::Int(i.checked_add(j).ok_or_else(|| overflow(op))?),
            "-" => Value::Int(i.checked_sub(j).ok_or_else(|| overflow(op))?),
            "*" => Value::Int(i.checked_mul(j).ok_or_else(|| overflow(op))?),
            "/" if j == 0 => return Err(zero()),
            "/" => Value::Float(i as f64 / j as f64),
            "//" | "%" if j == 0 => return Err(zero()),
            "//" => Value::Int(
                i.checked_div_euclid(j).ok_or_else(|| overflow(op))?
                    - i64::from(j < 0 && i.rem_euclid(j) != 0),
            ),
            "%" => {
                let r = i.checked_rem_euclid(j).ok_or_else(|| overflow(op))?;
                Value::Int(if j < 0 && r != 0 { r + j } else { r })
            }
            "**" if j >= 0 => Value::Int(
                u32::try_from(j)
                    .ok()
                    .and_then(|e| i.checked_pow(e))
                    .ok_or_else(|| overflow(op))?,
            ),
            "**" if i == 0 => return Err(zero()),
            "**" => Value::Float((i as f64).powf(j as f64)),
            _ => return Err(ExprError::new(format!("unknown operator '{op}'"))),
        });
    }
    let (f, g) = (x.as_f64(), y.as_f64());
    Ok(Value::Float(match op {
        "+" => f + g,
        "-" => f - g,
        "*" => f * g,
        "/" | "//" | "%" if g == 0.0 => return Err(zero()),
        "/" => f / g,
        "//" => (f / g).floor(),
        "%" => f - g * (f / g).floor(),
        "**" if f == 0.0 && g < 0.0 => return Err(zero()),
        "**" => f.powf(g),
        _ => return Err(ExprError::new(format!("unknown operator '{op}'"))),
    }))
}

fn contains(container: &Value, item: &Value) -> Result<bool, ExprError> {
    Ok(match (container, item) {
        (Value::Str(s), Value::Str(i)) => s.contains(&**i),
        (Value::List(l), _) => l.iter().any(|v| equal(v, item)),
        (Value::Dict(d), _) => d.iter().any(|(k, _)| equal(k, item)),
        _ => {
            return Err(ExprError::new(format!(
                "'in' needs a str, list or dict, found a {}",
                container.type_name()
            )))
        }
    })
}

fn compare(op: &str, a: &Value, b: &Value) -> Result<bool, ExprError> {
    use std::cmp::Ordering::*;
    let ord = || order(a, b).map_err(ExprError::new);
    Ok(match op {
        "==" => equal(a, b),
        "!=" => !equal(a, b),
        "<" => ord()? == Less,
        ">" => ord()? == Greater,
        "<=" => ord()? != Greater,
        ">=" => ord()? != Less,
        "in" => contains(b, a)?,
        "not in" => !contains(b, a)?,
        "is" => std::mem::discriminant(a) == std::mem::discriminant(b) && equal(a, b),
        "is not" => !(std::mem::discriminant(a) == std::mem::discriminant(b) && equal(a, b)),
        _ => return Err(ExprError::new(format!("unknown comparison '{op}'"))),
    })
}

fn index(a: &Value, i: &Value) -> Result<Value, ExprError> {
    let position = |len: usize| -> Result<usize, ExprError> {
        let Some(Num::Int(k)) = i.number() else {
            return Err(ExprError::new(format!(
                "expected an integer index, found a {}",
                i.type_name()
            )));
        };
        let len = i64::try_from(len).unwrap_or(i64::MAX);
        let at = if k < 0 { k + len } else { k };
        if !(0..len).contains(&at) {
            return Err(ExprError::new(format!(
                "index {k} out of range (length {len})"
            )));
        }
        Ok(usize::try_from(at).unwrap_or(0))
    };
    match a {
        Value::List(l) => Ok(l.get(position(l.len())?).cloned().unwrap_or(Value::None)),
        Value::Str(s) => {
            let chars: Vec<char> = s.chars().collect();
            Ok(Value::str(
                chars
                    .get(position(chars.len())?)
                    .map(char::to_string)
                    .unwrap_or_default(),
            ))
        }
        Value::Dict(d) => d
            .iter()
            .find(|(k, _)| equal(k, i))
            .map(|(_, v)| v.clone())
            .ok_or_else(|| ExprError::new(format!("key {} not found", i.repr()))),
        other => Err(ExprError::new(format!(
            "a {} cannot be indexed",
            other.type_name()
        ))),
    }
}
