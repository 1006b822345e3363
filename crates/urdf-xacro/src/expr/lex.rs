//! Tokens of the Python expression subset that `${}` and `$(eval)` hold.

use super::ExprError;
use crate::value::{parse_float, parse_int, Value};

/// A token.
#[derive(Clone, Debug)]
pub enum Token {
    /// A number literal.
    Num(Value),
    /// A string literal (adjacent literals are joined by the parser).
    Str(String),
    /// A name or keyword.
    Name(String),
    /// An operator or bracket.
    Op(&'static str),
}

/// Operators, longest first so that `**` wins over `*`.
const OPS: [&str; 25] = [
    "**", "//", "==", "!=", "<=", ">=", "+", "-", "*", "/", "%", "<", ">", "(", ")", "[", "]", "{",
    "}", ",", ":", ".", "=", "~", "|",
];

/// Splits `src` into tokens.
///
/// # Errors
/// An unterminated string, a malformed number, a character Python does not allow here.
pub fn tokens(src: &str) -> Result<Vec<Token>, ExprError> {
    let bytes = src.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while let Some(&b) = bytes.get(i) {
        if b.is_ascii_whitespace() {
            i += 1;
        } else if b.is_ascii_digit()
            || (b == b'.' && bytes.get(i + 1).is_some_and(u8::is_ascii_digit))
        {
            let start = i;
            while let Some(&c) = bytes.get(i) {
                let exp_sign = matches!(c, b'+' | b'-')
                    && matches!(bytes.get(i.wrapping_sub(1)), Some(b'e' | b'E'))
                    && !src[start..i].starts_with("0x");
                if c.is_ascii_alphanumeric() || c == b'.' || c == b'_' || exp_sign {
                    i += 1;
                } else {
                    break;
                }
            }
            let text = src[start..i].replace('_', "");
            let value = parse_int(&text)
                .map(Value::Int)
                .or_else(|| {
                    text.bytes()
                        .all(|c| {
                            c.is_ascii_digit() || matches!(c, b'.' | b'e' | b'E' | b'+' | b'-')
                        })
                        .then(|| parse_float(&text).map(Value::Float))
                        .flatten()
                })
                .ok_or_else(|| ExprError::new(format!("invalid number '{}'", &src[start..i])))?;
            out.push(Token::Num(value));
        } else if b.is_ascii_alphabetic() || b == b'_' {
            let start = i;
            while bytes
                .get(i)
                .is_some_and(|c| c.is_ascii_alphanumeric() || *c == b'_')
            {
                i += 1;
            }
            out.push(Token::Name(src[start..i].to_string()));
        } else if b == b'\'' || b == b'"' {
            let (text, next) = string(src, i)?;
            out.push(Token::Str(text));
            i = next;
        } else if let Some(op) = OPS.iter().find(|op| src[i..].starts_with(*op)) {
            out.push(Token::Op(op));
            i += op.len();
        } else {
            let c = src[i..].chars().next().unwrap_or('?');
            return Err(ExprError::new(format!("unexpected character '{c}'")));
        }
    }
    Ok(out)
}

/// The string literal starting at byte `start` (a quote) and the index after it.
fn string(src: &str, start: usize) -> Result<(String, usize), ExprError> {
    let quote = src[start..].chars().next().unwrap_or('\'');
    let mut out = String::new();
    let mut chars = src[start + 1..].char_indices();
    while let Some((k, c)) = chars.next() {
        if c == quote {
            return Ok((out, start + 1 + k + 1));
        }
        if c == '\\' {
            match chars.next() {
                Some((_, 'n')) => out.push('\n'),
                Some((_, 't')) => out.push('\t'),
                Some((_, e)) => out.push(e),
                None => break,
            }
        } else {
            out.push(c);
        }
    }
    Err(ExprError::new(format!(
        "unterminated string starting at {}",
        &src[start..]
    )))
}
