//! The wording shared by [`super::UrdfError`]'s messages: an optional line (` (line N)`), a
//! first definition, lists of names cut at [`SHOWN`], candidate tips with their moving joints,
//! and cycles of links or mimic joints shortened to their ends.

use std::fmt;

/// Formats an optional line as ` (line N)`.
pub(super) struct At(Option<usize>);

impl fmt::Display for At {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some(n) => write!(f, " (line {n})"),
            None => Ok(()),
        }
    }
}

pub(super) fn at(line: &Option<usize>) -> At {
    At(*line)
}

/// Formats an optional first definition as ` at line N`.
pub(super) struct First(Option<usize>);

impl fmt::Display for First {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some(n) => write!(f, " (first defined at line {n})"),
            None => Ok(()),
        }
    }
}

pub(super) fn first(line: &Option<usize>) -> First {
    First(*line)
}

/// Names shown in one message at most; a URDF with thousands of leaves or stray links must not
/// produce a message of thousands of names.
const SHOWN: usize = 8;

/// Formats names as `'a', 'b', 'c'`, the first [`SHOWN`] and how many more.
pub(crate) fn list(names: &[String]) -> String {
    let mut s = names
        .iter()
        .take(SHOWN)
        .map(|n| format!("'{n}'"))
        .collect::<Vec<_>>()
        .join(", ");
    if names.len() > SHOWN {
        s.push_str(&format!(" and {} more", names.len() - SHOWN));
    }
    s
}

/// Formats candidate tips as `'a' (6 moving joints), 'b' (6 moving joints)`, the first [`SHOWN`]
/// and how many more.
pub(super) fn counted(names: &[String], moving: &[usize]) -> String {
    let mut s = names
        .iter()
        .zip(moving)
        .take(SHOWN)
        .map(|(n, m)| format!("'{n}' ({m} moving joint{})", if *m == 1 { "" } else { "s" }))
        .collect::<Vec<_>>()
        .join(", ");
    if names.len() > SHOWN {
        s.push_str(&format!(" and {} more", names.len() - SHOWN));
    }
    s
}

/// Formats a mimic cycle as `a -> b -> a`, a long one (shortened, see
/// [`super::UrdfError::MimicCycle`]) as its start, `...`, its end and its length.
pub(super) fn joint_cycle(joints: &[String], length: usize) -> String {
    if joints.len() > length {
        return joints.join(" -> ");
    }
    let head = joints.get(..SHOWN - 2).unwrap_or(joints).join(" -> ");
    let tail = joints.get(SHOWN - 2..).unwrap_or(&[]).join(" -> ");
    format!("{head} -> ... -> {tail} ({length} joints)")
}

/// Formats a cycle as `a -> b -> a`; a long one as its start, `...`, its end and its length.
pub(super) fn cycle(links: &[String]) -> String {
    if links.len() <= SHOWN + 1 {
        return links.join(" -> ");
    }
    let head = links.get(..SHOWN - 2).unwrap_or(&[]).join(" -> ");
    let tail = links.get(links.len() - 2..).unwrap_or(&[]).join(" -> ");
    format!("{head} -> ... -> {tail} ({} links)", links.len() - 1)
}

pub(super) fn suggest(candidates: &[String]) -> String {
    if candidates.is_empty() {
        String::new()
    } else {
        format!("; candidates: {}", list(candidates))
    }
}
