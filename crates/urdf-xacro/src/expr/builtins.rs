//! The built-in names of xacro's expressions: Python's `math` module (directly and as
//! `math.NAME`), the Python built-ins xacro exposes (`len`, `min`, `max`, `round`, `int`, `float`,
//! `str`, `bool`, `list`, `dict`, `abs`, `sum`, `sorted`, `range`, also as `python.NAME`), and
//! the `xacro.` namespace (`xacro.load_yaml`, `xacro.arg`, `xacro.dotify`, `xacro.fatal`), the
//! host functions of which are answered by [`super::Names::call`].

use std::f64::consts;
use std::rc::Rc;

use super::{capped, num, ExprError};
use crate::value::{order, parse_float, parse_int, Num, Value};

/// Python's math functions of one float argument.
const MATH1: [&str; 25] = [
    "sin", "cos", "tan", "asin", "acos", "atan", "sinh", "cosh", "tanh", "asinh", "acosh", "atanh",
    "exp", "expm1", "log10", "log2", "log1p", "sqrt", "fabs", "radians", "degrees", "floor",
    "ceil", "trunc", "isnan",
];

/// Other callables.
const OTHER: [&str; 27] = [
    "atan2",
    "hypot",
    "pow",
    "copysign",
    "fmod",
    "log",
    "isinf",
    "isfinite",
    "abs",
    "min",
    "max",
    "round",
    "int",
    "float",
    "str",
    "bool",
    "len",
    "list",
    "dict",
    "sum",
    "sorted",
    "range",
    "load_yaml",
    "xacro.arg",
    "dotify",
    "fatal",
    "tuple",
];

/// A global name: a constant of `math`, a function, or a namespace.
pub fn global(name: &str) -> Option<Value> {
    Some(match name {
        "pi" => Value::Float(consts::PI),
        "e" => Value::Float(consts::E),
        "tau" => Value::Float(consts::TAU),
        "inf" => Value::Float(f64::INFINITY),
        "nan" => Value::Float(f64::NAN),
        "math" => Value::Builtin("math"),
        "python" => Value::Builtin("python"),
        "xacro" => Value::Builtin("xacro"),
        "true" | "True" => return None,
        _ => Value::Builtin(function(name)?),
    })
}

fn function(name: &str) -> Option<&'static str> {
    MATH1
        .iter()
        .chain(OTHER.iter())
        .find(|f| **f == name)
        .copied()
}

/// `ns.name` for the namespaces `math`, `python` and `xacro`.
pub fn member(ns: &str, name: &str) -> Option<Value> {
    match (ns, name) {
        ("math" | "python", _) => {
            global(name).filter(|v| !matches!(v, Value::Builtin("math" | "python" | "xacro")))
        }
        ("xacro", "arg") => Some(Value::Builtin("xacro.arg")),
        ("xacro", "load_yaml" | "dotify" | "fatal") => global(name),
        _ => None,
    }
}

fn arity(name: &str, args: &[Value], n: usize) -> Result<(), ExprError> {
    if args.len() != n {
        return Err(ExprError::new(format!(
            "{name}() takes {n} argument{}, found {}",
            if n == 1 { "" } else { "s" },
            args.len()
        )));
    }
    Ok(())
}

fn float_of(name: &str, v: &Value) -> Result<f64, ExprError> {
    Ok(num(v, name)?.as_f64())
}

fn domain(name: &str, x: f64) -> ExprError {
    ExprError::new(format!("math domain error: {name}({x})"))
}

fn to_int(f: f64, name: &str) -> Result<Value, ExprError> {
    if !f.is_finite() || f.abs() >= 9.2e18 {
        return Err(ExprError::new(format!(
            "{name}() of {f} is not a 64-bit integer"
        )));
    }
    Ok(Value::Int(f as i64))
}

/// The items of an iterable argument (list, string characters, dict keys).
fn items(name: &str, v: &Value) -> Result<Vec<Value>, ExprError> {
    Ok(match v {
        Value::List(l) => l.to_vec(),
        Value::Str(s) => s.chars().map(|c| Value::str(c.to_string())).collect(),
        Value::Dict(d) => d.iter().map(|(k, _)| k.clone()).collect(),
        other => {
            return Err(ExprError::new(format!(
                "{name}() needs a list, found a {}",
                other.type_name()
            )))
        }
    })
}

/// Calls the built-in function `name`.
///
/// # Errors
/// Wrong arguments, a math domain error, a host function called where there is no host
/// (`load_yaml` outside a document).
pub fn call(name: &str, args: &[Value], kwargs: &[(String, Value)]) -> Result<Value, ExprError> {
    if !kwargs.is_empty() && name != "dict" {
        return Err(ExprError::new(format!(
            "{name}() takes no keyword arguments"
        )));
    }
    if MATH1.contains(&name) {
        arity(name, args, 1)?;
        let x = float_of(name, &args[0])?;
        return Ok(match name {
            "floor" => to_int(x.floor(), name)?,
            "ceil" => to_int(x.ceil(), name)?,
            "trunc" => to_int(x.trunc(), name)?,
            "isnan" => Value::Bool(x.is_nan()),
            _ => Value::Float(math1(name, x)?),
        });
    }
    let f2 = |args: &[Value]| -> Result<(f64, f64), ExprError> {
        arity(name, args, 2)?;
        Ok((float_of(name, &args[0])?, float_of(name, &args[1])?))
    };
    Ok(match name {
        "atan2" => f2(args).map(|(y, x)| Value::Float(y.atan2(x)))?,
        "pow" => f2(args).map(|(x, y)| Value::Float(x.powf(y)))?,
        "copysign" => f2(args).map(|(x, y)| Value::Float(x.copysign(y)))?,
        "fmod" => {
            let (x, y) = f2(args)?;
            if y == 0.0 {
                return Err(domain(name, x));
            }
            Value::Float(x % y)
        }
        "hypot" => Value::Float(
            args.iter()
                .map(|a| float_of(name, a))
                .collect::<Result<Vec<_>, _>>()?
                .iter()
                .map(|x| x * x)
                .sum::<f64>()
                .sqrt(),
        ),
        "log" => {
            let x = float_of(name, args.first().unwrap_or(&Value::None))?;
            let ln = math1("log", x)?;
            match args.get(1) {
                None => Value::Float(ln),
                Some(b) => Value::Float(ln / math1("log", float_of(name, b)?)?),
            }
        }
        "isinf" => {
            arity(name, args, 1)?;
            Value::Bool(float_of(name, &args[0])?.is_infinite())
        }
        "isfinite" => {
            arity(name, args, 1)?;
            Value::Bool(float_of(name, &args[0])?.is_finite())
        }
        "abs" => {
            arity(name, args, 1)?;
            match num(&args[0], name)? {
                Num::Int(i) => Value::Int(
                    i.checked_abs()
                        .ok_or_else(|| ExprError::new("integer overflow in abs()"))?,
                ),
                Num::Float(f) => Value::Float(f.abs()),
            }
        }
        "min" | "max" => {
            let list = if args.len() == 1 {
                items(name, &args[0])?
            } else {
                args.to_vec()
            };
            let mut best: Option<Value> = None;
            for v in list {
                best = Some(match best {
                    None => v,
                    Some(b) => {
                        let o = order(&v, &b).map_err(ExprError::new)?;
                        let better = if name == "min" { o.is_lt() } else { o.is_gt() };
                        if better {
                            v
                        } else {
                            b
                        }
                    }
                });
            }
            best.ok_or_else(|| ExprError::new(format!("{name}() of an empty list")))?
        }
        "round" => round(args)?,
        "int" => {
            arity(name, args, 1)?;
            match &args[0] {
                Value::Str(s) => Value::Int(parse_int(s).ok_or_else(|| {
                    ExprError::new(format!("int() of '{s}': expected an integer"))
                })?),
                v => match num(v, name)? {
                    Num::Int(i) => Value::Int(i),
                    Num::Float(f) => to_int(f.trunc(), name)?,
                },
            }
        }
        "float" => {
            arity(name, args, 1)?;
            match &args[0] {
                Value::Str(s) => Value::Float(parse_float(s).ok_or_else(|| {
                    ExprError::new(format!("float() of '{s}': expected a number"))
                })?),
                v => Value::Float(float_of(name, v)?),
            }
        }
        "str" => Value::str(args.first().map(Value::to_text).unwrap_or_default()),
        "bool" => Value::Bool(args.first().is_some_and(Value::truthy)),
        "len" => {
            arity(name, args, 1)?;
            let n = match &args[0] {
                Value::Str(s) => s.chars().count(),
                Value::List(l) => l.len(),
                Value::Dict(d) => d.len(),
                other => return Err(ExprError::new(format!("len() of a {}", other.type_name()))),
            };
            Value::Int(i64::try_from(n).unwrap_or(i64::MAX))
        }
        "list" | "tuple" => Value::List(Rc::new(match args.first() {
            None => Vec::new(),
            Some(v) => items(name, v)?,
        })),
        "sorted" => {
            arity(name, args, 1)?;
            let mut list = items(name, &args[0])?;
            let mut failure = None;
            list.sort_by(|a, b| {
                order(a, b).unwrap_or_else(|e| {
                    failure = Some(e);
                    std::cmp::Ordering::Equal
                })
            });
            if let Some(e) = failure {
                return Err(ExprError::new(e));
            }
            Value::List(Rc::new(list))
        }
        "sum" => {
            let mut total = Value::Int(0);
            for v in items(name, args.first().unwrap_or(&Value::None))? {
                total = super::binary("+", total, v)?;
            }
            total
        }
        "range" => range(args)?,
        "dict" => dict(args, kwargs)?,
        "dotify" => args.first().cloned().unwrap_or(Value::None),
        "fatal" => {
            let words: Vec<String> = args.iter().map(Value::to_text).collect();
            return Err(ExprError::new(format!("xacro.fatal: {}", words.join(" "))));
        }
        "load_yaml" | "xacro.arg" => {
            return Err(ExprError::new(format!(
                "{name}() needs a document being expanded"
            )))
        }
        _ => return Err(ExprError::new(format!("undefined function '{name}'"))),
    })
}

fn math1(name: &str, x: f64) -> Result<f64, ExprError> {
    let y = match name {
        "sin" => x.sin(),
        "cos" => x.cos(),
        "tan" => x.tan(),
        "asin" if x.abs() <= 1.0 => x.asin(),
        "acos" if x.abs() <= 1.0 => x.acos(),
        "atan" => x.atan(),
        "sinh" => x.sinh(),
        "cosh" => x.cosh(),
        "tanh" => x.tanh(),
        "asinh" => x.asinh(),
        "acosh" if x >= 1.0 => x.acosh(),
        "atanh" if x.abs() < 1.0 => x.atanh(),
        "exp" => x.exp(),
        "expm1" => x.exp_m1(),
        "log" | "log10" | "log2" if x > 0.0 => match name {
            "log" => x.ln(),
            "log10" => x.log10(),
            _ => x.log2(),
        },
        "log1p" if x > -1.0 => x.ln_1p(),
        "sqrt" if x >= 0.0 => x.sqrt(),
        "fabs" => x.abs(),
        "radians" => x.to_radians(),
        "degrees" => x.to_degrees(),
        _ => return Err(domain(name, x)),
    };
    Ok(y)
}

/// Python's `round(x)` (to an int, half to even) and `round(x, n)` (to a float).
fn round(args: &[Value]) -> Result<Value, ExprError> {
    let x = num(args.first().unwrap_or(&Value::None), "round")?;
    match (x, args.get(1)) {
        (Num::Int(i), None) => Ok(Value::Int(i)),
        (Num::Float(f), None) => to_int(f.round_ties_even(), "round"),
        (_, Some(n)) => {
            let Some(Num::Int(n)) = n.number() else {
                return Err(ExprError::new("round() needs an integer number of digits"));
            };
            Ok(match (x, usize::try_from(n)) {
                (Num::Int(i), Ok(_)) => Value::Int(i),
                // Correctly rounded, half to even on the exact value, as Python's round does
                // (round(2.675, 2) is 2.67: 2.675 is 2.67499... in binary).
                (_, Ok(digits)) => Value::Float(
                    format!("{:.*}", digits.min(340), x.as_f64())
                        .parse()
                        .unwrap_or(f64::NAN),
                ),
                (_, Err(_)) => {
                    let scale = 10f64.powi(i32::try_from(n.clamp(-300, 0)).unwrap_or(0));
                    Value::Float((x.as_f64() * scale).round_ties_even() / scale)
                }
            })
        }
    }
}

fn range(args: &[Value]) -> Result<Value, ExprError> {
    let ints: Vec<i64> = args
        .iter()
        .map(|a| match a.number() {
            Some(Num::Int(i)) => Ok(i),
            _ => Err(ExprError::new("range() needs integers")),
        })
        .collect::<Result<_, _>>()?;
    let (start, stop, step) = match ints.as_slice() {
        [stop] => (0, *stop, 1),
        [start, stop] => (*start, *stop, 1),
        [start, stop, step] if *step != 0 => (*start, *stop, *step),
        _ => {
            return Err(ExprError::new(
                "range() takes 1 to 3 integers, the step not 0",
            ))
        }
    };
    let count = if step > 0 {
        (stop - start).max(0) / step
    } else {
        (start - stop).max(0) / -step
    };
    capped(usize::try_from(count).unwrap_or(usize::MAX))?;
    let mut out = Vec::new();
    let mut k = start;
    while (step > 0 && k < stop) || (step < 0 && k > stop) {
        out.push(Value::Int(k));
        k += step;
    }
    Ok(Value::List(Rc::new(out)))
}

fn dict(args: &[Value], kwargs: &[(String, Value)]) -> Result<Value, ExprError> {
    let mut out: Vec<(Value, Value)> = match args.first() {
        None => Vec::new(),
        Some(Value::Dict(d)) => d.to_vec(),
        Some(Value::List(pairs)) => pairs
            .iter()
            .map(|p| match p {
                Value::List(kv) if kv.len() == 2 => Ok((kv[0].clone(), kv[1].clone())),
                _ => Err(ExprError::new("dict() needs pairs")),
            })
            .collect::<Result<_, _>>()?,
        Some(other) => return Err(ExprError::new(format!("dict() of a {}", other.type_name()))),
    };
    for (k, v) in kwargs {
        let key = Value::str(k.as_str());
        match out.iter_mut().find(|(k2, _)| crate::value::equal(&key, k2)) {
            Some(slot) => slot.1 = v.clone(),
            None => out.push((key, v.clone())),
        }
    }
    Ok(Value::Dict(Rc::new(out)))
}
