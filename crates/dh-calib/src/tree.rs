//! Kinematic trees of DH tables: a trunk and the branches it carries (two arms on one torso).
//!
//! # Frames
//! The trunk is an ordinary [`DhTable`]: its `base` is DH frame 0 in the robot's base link
//! frame and its `tool` is the branch point (the frame the branches are mounted on) in its
//! last DH frame. Each branch is a [`DhTable`] too, whose `base` is the branch's DH frame 0
//! in the branch point frame (the *mount*) and whose `tool` is the branch's tip in its last DH
//! frame. A target on branch `b` is at
//!
//! ```text
//! trunk.base · A_trunk(q) · trunk.tool · branch_b.base · A_b(q) · branch_b.tool · t
//! ```
//!
//! A serial robot is a trunk without branches; its tip is the trunk's tool.
//!
//! # Joints
//! The tree's joints are the trunk's rows followed by each branch's rows, in order; that is the
//! order of the joint values `q` every function of this crate takes for a tree, and joint names
//! must be unique across the tree. A DH row cannot be shared between two successors (in both
//! conventions a frame's `x` axis points at the next axis), which is why the branches hang on
//! a frame of their own rather than on the trunk's last row.

use dh_core::{Convention, DhRow, DhTable};
use nalgebra::Isometry3;

use crate::fit::CalibError;

/// A named branch of a [`DhTree`].
#[derive(Clone, Debug, PartialEq)]
pub struct Branch {
    /// Name (targets say which branch they ride on by this name).
    pub name: String,
    /// The branch's rows; `base` is the mount in the trunk's branch point frame.
    pub table: DhTable,
}

/// A trunk and its branches (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct DhTree {
    trunk: DhTable,
    branches: Vec<Branch>,
    rows: Vec<DhRow>,
    parent: Vec<Option<usize>>,
}

/// Which table of a tree a global row index falls in: `None` for the trunk, `Some(b)` for
/// branch `b`, and the row's index within that table.
pub type RowPlace = (Option<usize>, usize);

impl DhTree {
    /// A serial robot: the table is the trunk and there are no branches.
    pub fn serial(table: &DhTable) -> DhTree {
        DhTree {
            trunk: table.clone(),
            branches: vec![],
            rows: table.rows.clone(),
            parent: (0..table.rows.len()).map(|i| i.checked_sub(1)).collect(),
        }
    }

    /// A trunk carrying `branches`.
    ///
    /// # Errors
    /// [`CalibError::BadOption`] when a joint name repeats, a branch name repeats or is empty,
    /// or a branch has no rows.
    pub fn new(trunk: DhTable, branches: Vec<Branch>) -> Result<DhTree, CalibError> {
        let mut rows = trunk.rows.clone();
        let mut parent: Vec<Option<usize>> =
            (0..trunk.rows.len()).map(|i| i.checked_sub(1)).collect();
        let trunk_last = trunk.rows.len().checked_sub(1);
        for (k, b) in branches.iter().enumerate() {
            if b.name.is_empty() || branches[..k].iter().any(|o| o.name == b.name) {
                return Err(CalibError::BadOption {
                    what: "tree".into(),
                    reason: format!(
                        "expected unique, non-empty branch names, found '{}'",
                        b.name
                    ),
                });
            }
            if b.table.rows.is_empty() {
                return Err(CalibError::BadOption {
                    what: "tree".into(),
                    reason: format!(
                        "branch '{}': expected at least one joint, found none",
                        b.name
                    ),
                });
            }
            for (i, r) in b.table.rows.iter().enumerate() {
                parent.push(if i == 0 {
                    trunk_last
                } else {
                    Some(rows.len() - 1)
                });
                rows.push(r.clone());
            }
        }
        for (i, r) in rows.iter().enumerate() {
            if rows[..i].iter().any(|o| o.name == r.name) {
                return Err(CalibError::BadOption {
                    what: "tree".into(),
                    reason: format!("expected unique joint names, found '{}' twice", r.name),
                });
            }
        }
        Ok(DhTree {
            trunk,
            branches,
            rows,
            parent,
        })
    }

    /// The trunk.
    pub fn trunk(&self) -> &DhTable {
        &self.trunk
    }

    /// The branches (empty for a serial robot).
    pub fn branches(&self) -> &[Branch] {
        &self.branches
    }

    /// Every row of the tree in joint order (trunk, then each branch).
    pub fn rows(&self) -> &[DhRow] {
        &self.rows
    }

    /// The row a row hangs on (`None` for the trunk's first row, and for a branch's first row
    /// when the trunk has no rows).
    pub fn parent(&self, row: usize) -> Option<usize> {
        self.parent.get(row).copied().flatten()
    }

    /// `true` when `row` lies on the path from the root to `descendant` (a row is its own
    /// ancestor).
    pub fn is_ancestor(&self, row: usize, descendant: usize) -> bool {
        let mut cur = Some(descendant);
        while let Some(c) = cur {
            if c == row {
                return true;
            }
            cur = self.parent(c);
        }
        false
    }

    /// Index of the row named `name`.
    pub fn row_index(&self, name: &str) -> Option<usize> {
        self.rows.iter().position(|r| r.name == name)
    }

    /// Where global row `row` sits: its table (`None` = trunk) and its index there.
    pub fn place(&self, row: usize) -> RowPlace {
        let n = self.trunk.rows.len();
        if row < n {
            return (None, row);
        }
        let mut start = n;
        for (b, br) in self.branches.iter().enumerate() {
            let len = br.table.rows.len();
            if row < start + len {
                return (Some(b), row - start);
            }
            start += len;
        }
        (None, row)
    }

    /// Global index of branch `b`'s first row.
    pub fn branch_start(&self, b: usize) -> usize {
        self.trunk.rows.len()
            + self.branches[..b.min(self.branches.len())]
                .iter()
                .map(|br| br.table.rows.len())
                .sum::<usize>()
    }

    /// Index of the branch named `name`.
    pub fn branch_index(&self, name: &str) -> Option<usize> {
        self.branches.iter().position(|b| b.name == name)
    }

    /// Number of chains from the root to a tip: 1 for a serial robot, else one per branch.
    pub fn chain_count(&self) -> usize {
        self.branches.len().max(1)
    }

    /// The rows (global indices) of chain `c` from the root (see [`DhTree::chain_count`]).
    pub fn chain_rows(&self, chain: usize) -> Vec<usize> {
        let mut out: Vec<usize> = (0..self.trunk.rows.len()).collect();
        if let Some(b) = self.branches.get(chain) {
            let s = self.branch_start(chain);
            out.extend(s..s + b.table.rows.len());
        }
        out
    }

    /// All rows as one table, in joint order, with the trunk's base and tool: the layout of `q`
    /// for effects and samplers. It is a kinematic chain only for a serial robot.
    pub fn joint_table(&self) -> DhTable {
        DhTable {
            convention: self.trunk.convention,
            base: self.trunk.base,
            tool: self.trunk.tool,
            rows: self.rows.clone(),
        }
    }

    /// A length that bounds the tree's size (metres): the largest [`DhTable::size`] of a chain
    /// from the root to a tip.
    pub fn size(&self) -> f64 {
        if self.branches.is_empty() {
            return self.trunk.size();
        }
        let trunk = self.trunk.size();
        self.branches
            .iter()
            .map(|b| trunk + b.table.size())
            .fold(1e-3, f64::max)
    }

    /// The DH frames after every row (in joint order) and the tip of every chain, in the base
    /// link frame, at joint values `q` (one per row). Row `i`'s frame is the one rigidly
    /// attached to the body that joint `i` moves: frame `i` of its table in both conventions.
    ///
    /// # Errors
    /// [`CalibError::Length`] when `q` does not have one value per row.
    pub fn frames(&self, q: &[f64]) -> Result<TreeFrames, CalibError> {
        if q.len() != self.rows.len() {
            return Err(CalibError::Length {
                what: "joint values".into(),
                expected: self.rows.len(),
                found: q.len(),
            });
        }
        let conv = |t: &DhTable| t.convention;
        let mut after = Vec::with_capacity(self.rows.len());
        let mut before = Vec::with_capacity(self.rows.len());
        let mut t = self.trunk.base;
        for (i, r) in self.trunk.rows.iter().enumerate() {
            before.push(t);
            t *= r.transform(conv(&self.trunk), q[i]);
            after.push(t);
        }
        let point = t * self.trunk.tool;
        let mut tips = Vec::with_capacity(self.chain_count());
        if self.branches.is_empty() {
            tips.push(point);
        }
        let mut k = self.trunk.rows.len();
        for b in &self.branches {
            let mut t = point * b.table.base;
            for r in &b.table.rows {
                before.push(t);
                t *= r.transform(conv(&b.table), q[k]);
                after.push(t);
                k += 1;
            }
            tips.push(t * b.table.tool);
        }
        Ok(TreeFrames {
            before,
            after,
            tips,
            conventions: self.row_conventions(),
        })
    }

    fn row_conventions(&self) -> Vec<Convention> {
        let mut v = vec![self.trunk.convention; self.trunk.rows.len()];
        for b in &self.branches {
            v.extend(std::iter::repeat_n(b.table.convention, b.table.rows.len()));
        }
        v
    }
}

/// Frames of a tree at some joint values (see [`DhTree::frames`]), in the base link frame.
#[derive(Clone, Debug, PartialEq)]
pub struct TreeFrames {
    /// Per row: the frame the row's transform starts from.
    pub before: Vec<Isometry3<f64>>,
    /// Per row: the frame after the row (attached to the body the joint moves).
    pub after: Vec<Isometry3<f64>>,
    /// Per chain: the tip (the table's tool applied).
    pub tips: Vec<Isometry3<f64>>,
    /// Per row: its table's convention.
    pub conventions: Vec<Convention>,
}

impl TreeFrames {
    /// Row `i`'s joint axis: a point on it and its unit direction (the DH `z` of the frame the
    /// joint turns or slides about: `before · Rz…` in the standard convention, the frame after
    /// `Rx(alpha) Tx(a) Ry(beta)` in the modified one).
    pub fn axis(
        &self,
        row: usize,
        table_row: &DhRow,
    ) -> (nalgebra::Vector3<f64>, nalgebra::Vector3<f64>) {
        match self.conventions[row] {
            Convention::Standard => {
                let f = &self.before[row];
                (f.translation.vector, f.rotation * nalgebra::Vector3::z())
            }
            Convention::Modified => {
                let f = self.before[row]
                    * Isometry3::rotation(nalgebra::Vector3::x() * table_row.alpha)
                    * Isometry3::translation(table_row.a, 0.0, 0.0)
                    * Isometry3::rotation(nalgebra::Vector3::y() * table_row.beta);
                (f.translation.vector, f.rotation * nalgebra::Vector3::z())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use dh_core::DhRow;

    fn arm(prefix: &str) -> DhTable {
        DhTable {
            convention: Convention::Modified,
            base: Isometry3::translation(0.0, 0.1, 0.0),
            tool: Isometry3::translation(0.0, 0.0, 0.05),
            rows: vec![
                DhRow::revolute(&format!("{prefix}1"), 0.0, 0.0, 0.0, 0.0),
                DhRow::revolute(&format!("{prefix}2"), 0.3, 0.0, 0.0, 0.0),
            ],
        }
    }

    #[test]
    fn a_tree_is_the_chains_it_joins() {
        let trunk = DhTable {
            convention: Convention::Modified,
            base: Isometry3::identity(),
            tool: Isometry3::translation(0.0, 0.0, 0.2),
            rows: vec![DhRow::revolute("t1", 0.0, 0.0, 0.5, 0.0)],
        };
        let tree = DhTree::new(
            trunk.clone(),
            vec![
                Branch {
                    name: "r".into(),
                    table: arm("r"),
                },
                Branch {
                    name: "l".into(),
                    table: arm("l"),
                },
            ],
        )
        .unwrap();
        assert_eq!(tree.rows().len(), 5);
        assert_eq!(tree.parent(1), Some(0));
        assert_eq!(tree.parent(3), Some(0));
        assert_eq!(tree.parent(4), Some(3));
        assert!(tree.is_ancestor(0, 4) && !tree.is_ancestor(1, 4));
        assert_eq!(tree.chain_rows(1), vec![0, 3, 4]);
        assert_eq!(tree.place(4), (Some(1), 1));
        let q = [0.3, 0.1, -0.2, 0.5, 0.7];
        let f = tree.frames(&q).unwrap();
        // Chain "l" as one serial computation.
        let l = arm("l");
        let expect = trunk.fk(&q[..1]).unwrap() * l.fk(&q[3..]).unwrap();
        let (dp, dr) = dh_core::pose::pose_error(&f.tips[1], &expect);
        assert!(dp < 1e-12 && dr < 1e-12);
        assert!(DhTree::new(
            trunk,
            vec![
                Branch {
                    name: "r".into(),
                    table: arm("r"),
                },
                Branch {
                    name: "l".into(),
                    table: arm("r"),
                },
            ],
        )
        .is_err());
    }
}
