//! Mimic drivers over the whole model: each must exist, move, and lead to a joint that mimics
//! none, through maps that compose to a finite one. Linear in the number of joints (each joint
//! has at most one driver, so the drivers form a functional graph, walked once).

use std::collections::HashMap;

use crate::check::MAX_MAGNITUDE;
use crate::robot::Joint;
use crate::UrdfError;

/// Longest mimic cycle whose joints are all named in its error.
const SHOWN_CYCLE: usize = 8;

/// Records in [`Joint::fault`] a mimic of an undefined joint, of a joint that does not move,
/// a mimic cycle (on every joint of the cycle), or a chain of drivers whose composed map is
/// beyond [`MAX_MAGNITUDE`] ([`composed_out_of_range`]). Joints that already have a fault keep it.
pub(crate) fn check_mimics(joints: &mut [Joint], index: &HashMap<String, usize>) {
    let n = joints.len();
    // Per joint: the index of its driver, for joints whose mimic is sound so far.
    let mut driver: Vec<Option<usize>> = vec![None; n];
    for k in 0..n {
        let Some(j) = joints.get(k) else { continue };
        let Some(m) = j.mimic.as_ref().filter(|_| j.fault.is_none()) else {
            continue;
        };
        let fault = match index.get(&m.joint).copied() {
            None => Some(UrdfError::UnknownMimicJoint {
                joint: j.name.clone(),
                driver: m.joint.clone(),
                line: j.mimic_line.or(Some(j.line)),
            }),
            Some(d) => match joints.get(d).and_then(|dj| dj.kind) {
                Some(kind) if !kind.is_moving() => Some(UrdfError::MimicOfFixed {
                    joint: j.name.clone(),
                    driver: m.joint.clone(),
                    kind: kind.label(),
                    line: j.mimic_line.or(Some(j.line)),
                }),
                _ => {
                    if let Some(slot) = driver.get_mut(k) {
                        *slot = Some(d);
                    }
                    None
                }
            },
        };
        if let (Some(f), Some(j)) = (fault, joints.get_mut(k)) {
            j.fault = Some(f);
        }
    }
    for cycle in cycles(&driver) {
        let names: Vec<String> = cycle
            .iter()
            .filter_map(|&k| joints.get(k).map(|j| j.name.clone()))
            .collect();
        let length = names.len();
        for (pos, &k) in cycle.iter().enumerate() {
            // Each joint's message starts at itself: a -> b -> c -> a, b -> c -> a -> b, ...
            // A long cycle keeps its first 6 and last 2 names (constant per joint).
            let at = |i: usize| {
                names
                    .get((pos + i) % length.max(1))
                    .cloned()
                    .unwrap_or_default()
            };
            let shown: Vec<String> = if length <= SHOWN_CYCLE {
                (0..=length).map(at).collect()
            } else {
                (0..6).chain([length - 1, length]).map(at).collect()
            };
            if let Some(j) = joints.get_mut(k) {
                j.fault = Some(UrdfError::MimicCycle {
                    joints: shown,
                    length,
                    line: j.mimic_line.or(Some(j.line)),
                });
            }
            if let Some(slot) = driver.get_mut(k) {
                *slot = None;
            }
        }
    }
    composed_out_of_range(joints, &driver);
}

/// Composes each joint's map from the joint at the end of its drivers, `q = m · q_root + o`
/// (radians or metres), and records [`UrdfError::MimicChainOutOfRange`] on a joint whose `|m|`
/// or `|o|` is beyond [`MAX_MAGNITUDE`] or not finite. `driver` holds each sound joint's driver
/// and no cycle (cut by the caller). Each joint's map is computed once: a walk stops at a joint
/// already composed, so the whole model costs O(joints).
fn composed_out_of_range(joints: &mut [Joint], driver: &[Option<usize>]) {
    let n = joints.len();
    // Per joint: (multiplier, offset, root) once composed.
    let mut map: Vec<Option<(f64, f64, usize)>> = vec![None; n];
    let mut path = Vec::new();
    for start in 0..n {
        path.clear();
        let mut k = start;
        // Walk up to a composed joint or a root (a joint with no sound driver).
        let (mut m, mut o, root) = loop {
            if let Some(done) = map.get(k).copied().flatten() {
                break done;
            }
            match driver.get(k).copied().flatten() {
                Some(d) if path.len() < n => {
                    path.push(k);
                    k = d;
                }
                _ => {
                    if let Some(slot) = map.get_mut(k) {
                        *slot = Some((1.0, 0.0, k));
                    }
                    break (1.0, 0.0, k);
                }
            }
        };
        // Compose back down: q_j = m_j · q_driver + o_j.
        for &j in path.iter().rev() {
            let Some(spec) = joints.get(j).and_then(|jt| jt.mimic.as_ref()) else {
                continue;
            };
            m *= spec.multiplier;
            o = spec.multiplier * o + spec.offset;
            if let Some(slot) = map.get_mut(j) {
                *slot = Some((m, o, root));
            }
            let bad = [("multiplier", m), ("offset", o)]
                .into_iter()
                .find(|(_, v)| !v.is_finite() || v.abs() > MAX_MAGNITUDE);
            let root_name = joints.get(root).map(|r| r.name.clone()).unwrap_or_default();
            if let (Some((what, value)), Some(jt)) = (bad, joints.get_mut(j)) {
                if jt.fault.is_none() {
                    jt.fault = Some(UrdfError::MimicChainOutOfRange {
                        joint: jt.name.clone(),
                        root: root_name,
                        what,
                        value,
                        line: jt.mimic_line.or(Some(jt.line)),
                    });
                }
            }
        }
    }
}

/// The cycles of a functional graph (`next[k]` is `k`'s successor), each once, each in
/// successor order from the first member met. Linear time.
fn cycles(next: &[Option<usize>]) -> Vec<Vec<usize>> {
    // 0: unvisited, 1: on the current walk, 2: done.
    let mut state = vec![0u8; next.len()];
    let mut out = Vec::new();
    for start in 0..next.len() {
        let mut walk = Vec::new();
        let mut k = start;
        loop {
            match state.get(k).copied() {
                Some(0) => {
                    if let Some(s) = state.get_mut(k) {
                        *s = 1;
                    }
                    walk.push(k);
                    match next.get(k).copied().flatten() {
                        Some(d) => k = d,
                        None => break,
                    }
                }
                Some(1) => {
                    let from = walk.iter().position(|&w| w == k).unwrap_or(0);
                    out.push(walk.get(from..).unwrap_or(&[]).to_vec());
                    break;
                }
                _ => break,
            }
        }
        for w in walk {
            if let Some(s) = state.get_mut(w) {
                *s = 2;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cycles_of_a_functional_graph() {
        // 0 -> 1 -> 2 -> 1, 3 -> 3 is excluded upstream, 4 -> 5 -> end.
        let next = [Some(1), Some(2), Some(1), None, Some(5), None];
        assert_eq!(cycles(&next), vec![vec![1, 2]]);
        let ring: Vec<Option<usize>> = (0..5).map(|k| Some((k + 1) % 5)).collect();
        assert_eq!(cycles(&ring), vec![vec![0, 1, 2, 3, 4]]);
        // A long chain without a cycle: linear, no stack.
        let long: Vec<Option<usize>> = (0..100_000)
            .map(|k| (k + 1 < 100_000).then_some(k + 1))
            .collect();
        assert!(cycles(&long).is_empty());
    }
}
