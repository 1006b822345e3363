//! Identical copies of a record: some exports repeat a pose's record once per line of another
//! sensor's data (the CTU Motoman Leica set writes each tracker reading once per camera
//! detection, 5 to 16 times, identical to the last digit). Read as they are, the copies would
//! be repeated measurements with no scatter: a pure error of zero. They are counted once.

use std::collections::HashMap;

use crate::data::{Sample, Split};

/// Everything a sample says except its line, bit for bit.
#[derive(PartialEq, Eq, Hash)]
struct Key {
    numbers: Vec<u64>,
    target: usize,
    session: usize,
    config: Option<String>,
    validation: bool,
}

fn key(s: &Sample) -> Key {
    let mut numbers: Vec<u64> = s.q.iter().map(|v| v.to_bits()).collect();
    numbers.extend(s.point.iter().map(|v| v.to_bits()));
    if let Some(sigma) = &s.sigma {
        numbers.push(1);
        numbers.extend(sigma.iter().map(|v| v.to_bits()));
    }
    if let Some(t) = s.time {
        numbers.push(3);
        numbers.push(t.to_bits());
    }
    if let Some(o) = &s.orientation {
        numbers.push(2);
        numbers.extend(o.rotation.coords.iter().map(|v| v.to_bits()));
        numbers.push(o.sigma.to_bits());
    }
    Key {
        numbers,
        target: s.target,
        session: s.session,
        config: s.config.as_ref().map(|c| c.to_string()),
        validation: s.split == Split::Validation,
    }
}

/// Drops the samples that repeat an earlier one exactly (all but the line), keeping the first;
/// returns the dropped ones' (line, line of the sample they copy), in order.
pub(super) fn drop_copies(samples: &mut Vec<Sample>) -> Vec<(usize, usize)> {
    let mut first: HashMap<Key, usize> = HashMap::with_capacity(samples.len());
    let mut dropped = Vec::new();
    samples.retain(|s| match first.entry(key(s)) {
        std::collections::hash_map::Entry::Occupied(e) => {
            dropped.push((s.line, *e.get()));
            false
        }
        std::collections::hash_map::Entry::Vacant(e) => {
            e.insert(s.line);
            true
        }
    });
    dropped
}
