//! The values xacro's expressions compute with: Python's `None`, `bool`, `int`, `float`, `str`,
//! `list`, `dict`, plus the XML blocks of block parameters and the built-in functions. Their
//! text forms are Python's `str()` and `repr()` (a float prints as `0.1`, `1.0`, `1e-05`), since
//! xacro writes `str(value)` into attributes and text.

use std::rc::Rc;

use crate::tree::Element;

/// A value of a `${}` expression or of a property.
#[derive(Clone, Debug)]
pub enum Value {
    /// Python's `None`.
    None,
    /// `True` / `False`.
    Bool(bool),
    /// An integer (Python's `int`, here 64-bit; overflow is an error).
    Int(i64),
    /// A float.
    Float(f64),
    /// A string.
    Str(Rc<str>),
    /// A list (or tuple).
    List(Rc<Vec<Value>>),
    /// A dict, in insertion order.
    Dict(Rc<Vec<(Value, Value)>>),
    /// An XML block: a macro's `*param` / `**param`, or a block property.
    Block(Rc<Element>),
    /// A built-in function or namespace (`radians`, `xacro.load_yaml`, `math`).
    Builtin(&'static str),
}

impl Value {
    /// A string value.
    pub fn str(s: impl Into<Rc<str>>) -> Value {
        Value::Str(s.into())
    }

    /// The Python type name, for messages.
    pub fn type_name(&self) -> &'static str {
        match self {
            Value::None => "NoneType",
            Value::Bool(_) => "bool",
            Value::Int(_) => "int",
            Value::Float(_) => "float",
            Value::Str(_) => "str",
            Value::List(_) => "list",
            Value::Dict(_) => "dict",
            Value::Block(_) => "block",
            Value::Builtin(_) => "function",
        }
    }

    /// Python's `bool(value)`.
    pub fn truthy(&self) -> bool {
        match self {
            Value::None => false,
            Value::Bool(b) => *b,
            Value::Int(i) => *i != 0,
            Value::Float(f) => *f != 0.0,
            Value::Str(s) => !s.is_empty(),
            Value::List(l) => !l.is_empty(),
            Value::Dict(d) => !d.is_empty(),
            Value::Block(_) | Value::Builtin(_) => true,
        }
    }

    /// The value as a number, when it is one (`bool` counts, as in Python).
    pub fn number(&self) -> Option<Num> {
        match self {
            Value::Bool(b) => Some(Num::Int(i64::from(*b))),
            Value::Int(i) => Some(Num::Int(*i)),
            Value::Float(f) => Some(Num::Float(*f)),
            _ => None,
        }
    }

    /// Python's `str(value)`.
    pub fn to_text(&self) -> String {
        match self {
            Value::Str(s) => s.to_string(),
            other => other.repr(),
        }
    }

    /// Python's `repr(value)`.
    pub fn repr(&self) -> String {
        match self {
            Value::None => "None".into(),
            Value::Bool(true) => "True".into(),
            Value::Bool(false) => "False".into(),
            Value::Int(i) => i.to_string(),
            Value::Float(f) => float_repr(*f),
            Value::Str(s) => str_repr(s),
            Value::List(l) => {
                let items: Vec<String> = l.iter().map(Value::repr).collect();
                format!("[{}]", items.join(", "))
            }
            Value::Dict(d) => {
                let items: Vec<String> = d
                    .iter()
                    .map(|(k, v)| format!("{}: {}", k.repr(), v.repr()))
                    .collect();
                format!("{{{}}}", items.join(", "))
            }
            Value::Block(e) => format!("<block {}>", e.name),
            Value::Builtin(name) => format!("<built-in function {name}>"),
        }
    }
}

/// A number of an arithmetic operation.
#[derive(Clone, Copy, Debug)]
pub enum Num {
    /// An integer.
    Int(i64),
    /// A float.
    Float(f64),
}

impl Num {
    /// The number as a float.
    pub fn as_f64(self) -> f64 {
        match self {
            Num::Int(i) => i as f64,
            Num::Float(f) => f,
        }
    }
}

/// Python's `repr(float)`: the shortest digits that read back the same, in fixed notation for
/// exponents -4..16 (always with a `.`), else `1e-05` / `1.5e+16`.
pub fn float_repr(f: f64) -> String {
    if f.is_nan() {
        return "nan".into();
    }
    if f.is_infinite() {
        return if f > 0.0 { "inf".into() } else { "-inf".into() };
    }
    if f == 0.0 {
        return if f.is_sign_negative() { "-0.0" } else { "0.0" }.into();
    }
    // Rust's `{:e}` gives the shortest round-trip digits, e.g. `-1.5e-5`.
    let sci = format!("{f:e}");
    let (mantissa, exp) = sci.split_once('e').unwrap_or((sci.as_str(), "0"));
    let exp: i32 = exp.parse().unwrap_or(0);
    let negative = mantissa.starts_with('-');
    let digits: String = mantissa.chars().filter(char::is_ascii_digit).collect();
    let sign = if negative { "-" } else { "" };
    if (-4..16).contains(&exp) {
        let body = if exp >= 0 {
            let point = exp as usize + 1;
            if digits.len() <= point {
                format!("{digits}{}.0", "0".repeat(point - digits.len()))
            } else {
                format!("{}.{}", &digits[..point], &digits[point..])
            }
        } else {
            format!("0.{}{digits}", "0".repeat((-exp - 1) as usize))
        };
        format!("{sign}{body}")
    } else {
        let (first, rest) = digits.split_at(1.min(digits.len()));
        let frac = if rest.is_empty() {
            String::new()
        } else {
            format!(".{rest}")
        };
        let esign = if exp < 0 { '-' } else { '+' };
        format!("{sign}{first}{frac}e{esign}{:02}", exp.abs())
    }
}

/// Python's `repr(str)`: single quotes unless the text holds one and no double quote.
fn str_repr(s: &str) -> String {
    let quote = if s.contains('\'') && !s.contains('"') {
        '"'
    } else {
        '\''
    };
    let mut out = String::with_capacity(s.len() + 2);
    out.push(quote);
    for c in s.chars() {
        match c {
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            c if c == quote => {
                out.push('\\');
                out.push(c);
            }
            c => out.push(c),
        }
    }
    out.push(quote);
    out
}

/// Python's `int(text)` for a decimal string (surrounding whitespace and a sign allowed).
pub fn parse_int(text: &str) -> Option<i64> {
    let t = text.trim();
    let digits = t.strip_prefix(['+', '-']).unwrap_or(t);
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    t.trim_start_matches('+').parse().ok()
}

/// Python's `float(text)`: decimal or exponent notation, `inf`, `nan`, surrounding whitespace.
pub fn parse_float(text: &str) -> Option<f64> {
    let t = text.trim();
    let body = t.strip_prefix(['+', '-']).unwrap_or(t);
    let lower = body.to_ascii_lowercase();
    let special = matches!(lower.as_str(), "inf" | "infinity" | "nan");
    let numeric = !body.is_empty()
        && body.bytes().any(|b| b.is_ascii_digit())
        && body
            .bytes()
            .all(|b| b.is_ascii_digit() || matches!(b, b'.' | b'e' | b'E' | b'+' | b'-'));
    if !(special || numeric) {
        return None;
    }
    t.parse().ok()
}

/// xacro's `Table._eval_literal`: a stored string becomes the number or boolean it spells
/// (`'0.1'` is 0.1, `'true'` is True), a `'quoted'` string loses its quotes, and a string with
/// `_` stays a string.
pub fn literal(value: Value) -> Value {
    let Value::Str(s) = &value else {
        return value;
    };
    if s.len() >= 2 && s.starts_with('\'') && s.ends_with('\'') {
        return Value::str(&s[1..s.len() - 1]);
    }
    if s.contains('_') {
        return value;
    }
    if let Some(i) = parse_int(s) {
        return Value::Int(i);
    }
    if let Some(f) = parse_float(s) {
        return Value::Float(f);
    }
    match &**s {
        "true" | "True" => Value::Bool(true),
        "false" | "False" => Value::Bool(false),
        _ => value,
    }
}

/// xacro's `get_boolean_value`: the value of an `xacro:if` / `xacro:unless` condition.
///
/// # Errors
/// A string that is neither `true`/`false` (any of `True`/`False`) nor an integer.
pub fn boolean(value: &Value) -> Result<bool, String> {
    match value {
        Value::Str(s) => match &**s {
            "true" | "True" => Ok(true),
            "false" | "False" => Ok(false),
            other => parse_int(other).map(|i| i != 0).ok_or_else(|| {
                format!("expected a boolean (true, false, 1 or 0), found '{other}'")
            }),
        },
        other => Ok(other.truthy()),
    }
}

/// Python's `==` between two values (numbers compare across int/float/bool).
pub fn equal(a: &Value, b: &Value) -> bool {
    if let (Some(x), Some(y)) = (a.number(), b.number()) {
        return match (x, y) {
            (Num::Int(i), Num::Int(j)) => i == j,
            _ => x.as_f64() == y.as_f64(),
        };
    }
    match (a, b) {
        (Value::None, Value::None) => true,
        (Value::Str(x), Value::Str(y)) => x == y,
        (Value::List(x), Value::List(y)) => {
            x.len() == y.len() && x.iter().zip(y.iter()).all(|(p, q)| equal(p, q))
        }
        (Value::Dict(x), Value::Dict(y)) => {
            x.len() == y.len()
                && x.iter().all(|(k, v)| {
                    y.iter()
                        .find(|(k2, _)| equal(k, k2))
                        .is_some_and(|(_, v2)| equal(v, v2))
                })
        }
        (Value::Builtin(x), Value::Builtin(y)) => x == y,
        _ => false,
    }
}

/// Python's ordering `a < b` (`Less`), for numbers, strings and lists.
///
/// # Errors
/// Values Python does not order (`'<' not supported between 'str' and 'int'`).
pub fn order(a: &Value, b: &Value) -> Result<std::cmp::Ordering, String> {
    use std::cmp::Ordering;
    if let (Some(x), Some(y)) = (a.number(), b.number()) {
        return Ok(match (x, y) {
            (Num::Int(i), Num::Int(j)) => i.cmp(&j),
            _ => x
                .as_f64()
                .partial_cmp(&y.as_f64())
                .unwrap_or(Ordering::Equal),
        });
    }
    match (a, b) {
        (Value::Str(x), Value::Str(y)) => Ok(x.cmp(y)),
        (Value::List(x), Value::List(y)) => {
            for (p, q) in x.iter().zip(y.iter()) {
                if !equal(p, q) {
                    return order(p, q);
                }
            }
            Ok(x.len().cmp(&y.len()))
        }
        _ => Err(format!(
            "cannot order a {} and a {}",
            a.type_name(),
            b.type_name()
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floats_print_as_python_does() {
        let cases = [
            (0.1, "0.1"),
            (1.0, "1.0"),
            (-2.5, "-2.5"),
            (1e-5, "1e-05"),
            (0.0001, "0.0001"),
            (1e16, "1e+16"),
            (123456789012345.0, "123456789012345.0"),
            (std::f64::consts::FRAC_PI_2, "1.5707963267948966"),
            (1.5e-7, "1.5e-07"),
            (-0.0, "-0.0"),
        ];
        for (f, want) in cases {
            assert_eq!(float_repr(f), want, "{f}");
        }
    }

    proptest::proptest! {
        /// Python's float text reads back as the same float, and always looks like a float.
        #[test]
        fn float_text_reads_back(bits in proptest::prelude::any::<u64>()) {
            let f = f64::from_bits(bits);
            proptest::prop_assume!(f.is_finite());
            let text = float_repr(f);
            proptest::prop_assert_eq!(text.parse::<f64>().ok(), Some(f));
            proptest::prop_assert!(text.contains('.') || text.contains('e'), "{}", text);
            proptest::prop_assert!(matches!(literal(Value::str(text.as_str())), Value::Float(g) if g == f));
        }
    }

    #[test]
    fn literals_follow_xacro() {
        assert!(matches!(literal(Value::str("12")), Value::Int(12)));
        assert!(matches!(literal(Value::str(" 0.5 ")), Value::Float(f) if f == 0.5));
        assert!(matches!(literal(Value::str("true")), Value::Bool(true)));
        assert!(matches!(literal(Value::str("1_0")), Value::Str(s) if &*s == "1_0"));
        assert!(matches!(literal(Value::str("'abc'")), Value::Str(s) if &*s == "abc"));
        assert!(matches!(literal(Value::str("0 0 1")), Value::Str(_)));
        assert!(matches!(literal(Value::str("e5")), Value::Str(_)));
    }

    #[test]
    fn booleans_follow_xacro() {
        assert_eq!(boolean(&Value::str("True")), Ok(true));
        assert_eq!(boolean(&Value::str("0")), Ok(false));
        assert_eq!(boolean(&Value::Float(0.5)), Ok(true));
        assert!(boolean(&Value::str("1.0")).is_err());
        assert!(boolean(&Value::str("yes")).is_err());
    }
}
