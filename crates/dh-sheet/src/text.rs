//! Names in text: the one escaping rule for every name a message or table quotes, and the
//! capped width of a text table's name column.

use std::borrow::Cow;

pub use dh_calib::csv::is_spoofing;

/// Widest padded column of a text table, in characters. Longer names are printed whole and
/// push the row's later cells to the right; the width itself never grows past this (a format
/// width of 65 536 or more panics in `std::fmt`).
pub const MAX_COLUMN: usize = 48;

/// The width of a text column holding `names`: the longest name's length in characters, at
/// least `min`, at most [`MAX_COLUMN`].
pub fn column_width<'a>(names: impl IntoIterator<Item = &'a str>, min: usize) -> usize {
    names
        .into_iter()
        .map(|n| escape(n).chars().count())
        .max()
        .unwrap_or(0)
        .max(min)
        .min(MAX_COLUMN)
}

/// A name as the tool prints it: every control or bidi character ([`is_spoofing`]) written as
/// `\u{XX}` (Rust's escape), everything else as it is. Names the readers accept never hold
/// such characters, so they print unchanged; this is for names that reach a message before or
/// without a reader's check (command-line arguments, the name a refusal quotes).
pub fn escape(name: &str) -> Cow<'_, str> {
    if !name.chars().any(is_spoofing) {
        return Cow::Borrowed(name);
    }
    let mut s = String::with_capacity(name.len() + 8);
    for c in name.chars() {
        if is_spoofing(c) {
            s.push_str(&format!("\\u{{{:x}}}", u32::from(c)));
        } else {
            s.push(c);
        }
    }
    Cow::Owned(s)
}

/// What is wrong with a name that a file or option gives (a joint, target, link or column), or
/// `None`: empty, or holding a control or bidi character (found at character `k`, counted
/// from 1). The URDF reader refuses the same characters.
pub fn name_problem(name: &str) -> Option<String> {
    if name.trim().is_empty() {
        return Some("expected a name, found an empty one".into());
    }
    let (k, c) = name.chars().enumerate().find(|(_, c)| is_spoofing(*c))?;
    Some(format!(
        "'{}': expected a name without control or bidi characters, found U+{:04X} at character {}",
        escape(name),
        u32::from(c),
        k + 1
    ))
}
