//! The default tip: the end of the arm, as a user expects it.
//!
//! # The rule
//! Below the base, take the leaves whose path from the base holds the most moving joints
//! (revolute, continuous, prismatic). Group them by the link their last moving joint moves
//! (the arm's last link): the leaves of one group differ only in fixed links hanging off it.
//! - One group: its only leaf, else its leaf named like a tool frame (`tool0`, `flange`,
//!   `ee`, `tcp`...), else the last link itself.
//! - Several groups that split at most [`MAX_HAND_JOINTS`] moving joints before their ends,
//!   below a longer arm, are the fingers of one hand (a gripper): the tip is the link where
//!   they split, or its fixed link named like a tool frame.
//! - Otherwise (two arms of one length, a humanoid) there is no tip to guess: refused with
//!   the candidates and their moving-joint counts.
//!
//! Then a gripper is taken off the end: while the last moving joint of the chosen chain is
//! named like a gripper (`gripper`, `jaw`, `finger`, `claw`, `rh`: a
//! single moving jaw) and at least [`MIN_ARM_JOINTS`] moving joints precede it, the tip moves
//! up to that joint's parent link (or its fixed link named like a tool frame).

use crate::{UrdfError, UrdfModel};

/// Most moving joints of one finger below the hand link where the fingers split.
pub(crate) const MAX_HAND_JOINTS: usize = 3;

/// Fewest moving joints an arm keeps when a gripper joint is taken off its end.
pub(crate) const MIN_ARM_JOINTS: usize = 3;

/// Whether a joint or link name reads like a gripper's: it contains `gripper`, `finger` or
/// `jaw`, or one of its words is `claw` or `rh` (robot hand).
fn gripper_like(name: &str) -> bool {
    let lower = name.to_lowercase();
    ["gripper", "finger", "jaw"]
        .iter()
        .any(|w| lower.contains(w))
        || lower
            .split(|c: char| !c.is_ascii_alphanumeric())
            .any(|w| matches!(w, "claw" | "rh"))
}

/// Most fingers of one hand (more equally long branches are no hand).
const MAX_FINGERS: usize = 8;

/// Whether a link name reads like a tool or flange frame: one of its `_`/`-`/`.`-separated
/// words (or the name) is `tool`, `tool0`, `flange`, `ee`, `eef`, `tcp`, `end_effector`...
fn tool_like(name: &str) -> bool {
    let lower = name.to_lowercase();
    if lower.contains("end_effector") || lower.contains("endeffector") {
        return true;
    }
    lower.split(|c: char| !c.is_ascii_alphanumeric()).any(|w| {
        matches!(
            w,
            "tool" | "tool0" | "flange" | "ee" | "eef" | "tcp" | "tool_frame"
        )
    })
}

impl UrdfModel {
    fn is_moving_joint(&self, k: usize) -> bool {
        self.robot
            .joints
            .get(k)
            .and_then(|j| j.kind)
            .is_some_and(|t| t.is_moving())
    }

    /// The default tip below `base` (see the module docs).
    pub(crate) fn default_tip(&self, base: usize) -> Result<usize, UrdfError> {
        let tip = self.arm_end(base)?;
        Ok(self.without_gripper(base, tip))
    }

    /// Moves `tip` up past gripper joints at its end (see the module docs).
    fn without_gripper(&self, base: usize, mut tip: usize) -> usize {
        for _ in 0..MAX_HAND_JOINTS {
            // The last moving joint above the tip, and the moving joints before it.
            let mut last = None;
            let mut before = 0;
            for link in self.ancestors(tip) {
                if link == base {
                    break;
                }
                let Some(k) = self.parent_joint.get(link).copied().flatten() else {
                    break;
                };
                if self.is_moving_joint(k) {
                    if last.is_none() {
                        last = Some(k);
                    } else {
                        before += 1;
                    }
                }
            }
            let Some(k) = last else { return tip };
            // The joint's name only: the link a wrist joint moves is often called the gripper.
            let name = self.robot.joints.get(k).map_or("", |j| j.name.as_str());
            if !gripper_like(name) || before < MIN_ARM_JOINTS {
                return tip;
            }
            let Some(&hand) = self.joint_parent.get(k) else {
                return tip;
            };
            let fixed = self.fixed_descendants(hand);
            tip = self.tool_below(hand, &fixed).unwrap_or(hand);
        }
        tip
    }

    /// The end of the longest run of moving joints below `base`, before a gripper is taken
    /// off it.
    fn arm_end(&self, base: usize) -> Result<usize, UrdfError> {
        let n = self.child_joints.len();
        // Per link below the base: moving joints from the base, and the link moved by the
        // last of them (the base itself before the first).
        let mut moving = vec![0usize; n];
        let mut last = vec![base; n];
        let mut leaves = Vec::new();
        let mut stack = vec![base];
        while let Some(link) = stack.pop() {
            let children = self
                .child_joints
                .get(link)
                .map(Vec::as_slice)
                .unwrap_or(&[]);
            if children.is_empty() {
                leaves.push(link);
            }
            let (m, l) = (
                moving.get(link).copied().unwrap_or(0),
                last.get(link).copied().unwrap_or(base),
            );
            for &k in children {
                let Some(&c) = self.joint_child.get(k) else {
                    continue;
                };
                let step = self.is_moving_joint(k);
                if let Some(slot) = moving.get_mut(c) {
                    *slot = m + usize::from(step);
                }
                if let Some(slot) = last.get_mut(c) {
                    *slot = if step { c } else { l };
                }
                stack.push(c);
            }
        }
        leaves.sort_unstable();
        let count = |l: usize| moving.get(l).copied().unwrap_or(0);
        let most = leaves.iter().map(|&l| count(l)).max().unwrap_or(0);
        let longest: Vec<usize> = leaves
            .iter()
            .copied()
            .filter(|&l| count(l) == most)
            .collect();
        let mut ends: Vec<usize> = longest
            .iter()
            .map(|&l| last.get(l).copied().unwrap_or(base))
            .collect();
        ends.sort_unstable();
        ends.dedup();
        let refuse = || {
            let shown: Vec<usize> = if most == 0 {
                leaves.clone()
            } else {
                longest.clone()
            };
            UrdfError::SeveralLeaves {
                base: self.link_name(base).to_owned(),
                leaves: shown
                    .iter()
                    .map(|&l| self.link_name(l).to_owned())
                    .collect(),
                moving: shown.iter().map(|&l| count(l)).collect(),
            }
        };
        match (ends.as_slice(), longest.as_slice()) {
            (_, [only]) => Ok(*only),
            _ if most == 0 => Err(refuse()),
            ([end], group) => Ok(self.tool_below(*end, group).unwrap_or(*end)),
            _ if ends.len() > MAX_FINGERS => Err(refuse()),
            _ => {
                // Fingers of one hand: the ends split a few moving joints below a longer arm.
                let hand = self.common_ancestor(&ends).ok_or_else(refuse)?;
                let finger = most - count(hand);
                if finger <= MAX_HAND_JOINTS && count(hand) > finger {
                    let fixed_leaves = self.fixed_descendants(hand);
                    Ok(self.tool_below(hand, &fixed_leaves).unwrap_or(hand))
                } else {
                    Err(refuse())
                }
            }
        }
    }

    /// Among `candidates` (links rigidly attached below `link`), the one named like a tool
    /// frame, if exactly one is.
    fn tool_below(&self, link: usize, candidates: &[usize]) -> Option<usize> {
        let tools: Vec<usize> = candidates
            .iter()
            .copied()
            .filter(|&c| c != link && tool_like(self.link_name(c)))
            .collect();
        match tools.as_slice() {
            [one] => Some(*one),
            _ => None,
        }
    }

    /// Links reached from `link` through fixed joints only.
    fn fixed_descendants(&self, link: usize) -> Vec<usize> {
        let mut out = Vec::new();
        let mut stack = vec![link];
        while let Some(l) = stack.pop() {
            for &k in self.child_joints.get(l).map(Vec::as_slice).unwrap_or(&[]) {
                if !self.is_moving_joint(k) {
                    if let Some(&c) = self.joint_child.get(k) {
                        out.push(c);
                        stack.push(c);
                    }
                }
            }
        }
        out
    }

    /// The deepest link above (or equal to) every one of `links`.
    fn common_ancestor(&self, links: &[usize]) -> Option<usize> {
        let (&first, rest) = links.split_first()?;
        let mut path: Vec<usize> = self.ancestors(first).collect();
        path.reverse(); // root first
        for &l in rest {
            let other: Vec<usize> = {
                let mut p: Vec<usize> = self.ancestors(l).collect();
                p.reverse();
                p
            };
            let common = path.iter().zip(&other).take_while(|(a, b)| a == b).count();
            path.truncate(common);
        }
        path.last().copied()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gripper_names() {
        for n in [
            "gripper",
            "jointGripper",
            "moving_jaw_link",
            "finger_joint1",
            "rh_r1_joint",
        ] {
            assert!(gripper_like(n), "{n}");
        }
        for n in ["joint6", "wrist_3_link", "shoulder", "rhino"] {
            assert!(!gripper_like(n), "{n}");
        }
    }

    #[test]
    fn tool_names() {
        for n in [
            "tool0",
            "flange",
            "ee_link",
            "iiwa_link_ee",
            "tcp",
            "tool_frame",
            "j2s6s200_end_effector",
            "panda_EE",
        ] {
            assert!(tool_like(n), "{n}");
        }
        for n in ["base_link", "camera_link", "link_6", "wrist_3_link", "knee"] {
            assert!(!tool_like(n), "{n}");
        }
    }
}
