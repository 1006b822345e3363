//! The calibrated robot of a tree ([`crate::tree`]): each target rides on its branch, and each
//! branch's tip is a tool of its own.
//!
//! # Frames
//! As the parent module's, with `FK` the chain of the target's branch: a target `t_k` on branch
//! `b` is at `T_device_base · trunk.base · A_trunk(q) · trunk.tool · b.base · A_b(q) · b.tool ·
//! t_k` (see [`crate::tree`]); `q` holds one value per row of the tree, in its joint order.
//! The tool of branch `b` ([`Calibrated::tool_of`]) is that chain's tip.
//!
//! # Uncertainty
//! A tip's uncertainty is propagated as the frame of a target at the tip's origin, one per
//! branch, added to the model after the calibration's targets: the covariance has no parameter
//! of it, so only the chain's parameters (and the device frame's, in [`super::Frame::Device`])
//! move it, exactly as [`Calibrated::tool_uncertainty`] does for a serial robot.

use dh_core::DhTable;
use nalgebra::{Isometry3, Vector3};

use super::{Calibrated, EffectValues};
use crate::fit::CalibError;
use crate::model::{Model, ModelOptions};
use crate::tree::DhTree;

/// The name of the target at branch `b`'s tip: a control character no data file's target name
/// may hold, so that it never meets a measured target.
fn tip_name(branch: &str) -> String {
    format!("\u{1}tip:{branch}")
}

/// A target of a tree's calibration: its name, its position in its branch's tip frame
/// (metres) and the branch (index into [`DhTree::branches`]).
pub type TreeTarget = (String, Vector3<f64>, usize);

impl Calibrated {
    /// The calibrated `tree` with its `effects` at their values, the device frame
    /// `T_device_base` and the targets (each on its branch), all metres and radians.
    ///
    /// # Errors
    /// As [`Calibrated::new`]; [`CalibError::BadOption`] for a branch index out of range or a
    /// tree without branches.
    pub fn new_tree(
        tree: &DhTree,
        effects: &[EffectValues],
        device: &Isometry3<f64>,
        targets: &[TreeTarget],
    ) -> Result<Self, CalibError> {
        if tree.branches().is_empty() {
            return Err(CalibError::BadOption {
                what: "tree".into(),
                reason: "expected at least one branch, found none".into(),
            });
        }
        let mut on: Vec<(String, usize)> =
            targets.iter().map(|(n, _, b)| (n.clone(), *b)).collect();
        let real = on.len();
        on.extend(
            tree.branches()
                .iter()
                .enumerate()
                .map(|(b, br)| (tip_name(&br.name), b)),
        );
        let model = Model::new_tree(tree, &on, &ModelOptions::default())?;
        let positions: Vec<Vector3<f64>> = targets.iter().map(|(_, p, _)| *p).collect();
        let mut c = Self::build(model, effects, device, &positions)?;
        c.real_targets = real;
        c.tools = (real..on.len()).collect();
        Ok(c)
    }

    /// The calibrated robot of a tree's [`crate::calibrate::Report`] (its `tree`, which a
    /// tree's fit always sets), as [`Calibrated::from_report`]: `branches` gives each target's
    /// branch (`crate::pipeline::TreeCalibration::target_branches`), `ctx` the tree's
    /// effect context (its masses for gravity effects).
    ///
    /// # Errors
    /// As [`Calibrated::new_tree`]; a report without a tree or a target without a branch.
    pub fn from_tree_report(
        report: &crate::calibrate::Report,
        branches: &[(String, usize)],
        ctx: &crate::effects::EffectContext,
    ) -> Result<Self, CalibError> {
        let tree = report.tree.as_ref().ok_or_else(|| CalibError::BadOption {
            what: "report".into(),
            reason: "expected a tree's report, found a serial one".into(),
        })?;
        let targets = report
            .targets
            .iter()
            .map(|(name, p)| {
                branches
                    .iter()
                    .find(|(t, _)| t == name)
                    .map(|(_, b)| (name.clone(), *p, *b))
                    .ok_or_else(|| CalibError::BadOption {
                        what: format!("target '{name}'"),
                        reason: "expected the branch it rides on, found none".into(),
                    })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let effects = super::report_effects(report, ctx)?;
        let c = Self::new_tree(tree, &effects, &report.device, &targets)?
            .with_target_rotations(&report.target_rotations);
        match &report.covariance {
            Some(cov) => c.with_covariance(cov),
            None => Ok(c),
        }
    }

    /// The robot's tree (a trunk without branches for a serial robot).
    pub fn tree(&self) -> &DhTree {
        self.model.tree()
    }

    /// The number of chains with a tool: one per branch of a tree, 1 for a serial robot.
    pub fn chains(&self) -> usize {
        self.model.tree().chain_count()
    }

    /// The branch (index into the tree's branches) target `k` rides on; 0 for a serial
    /// robot.
    pub fn target_branch(&self, k: usize) -> usize {
        self.model.target_chain(k)
    }

    /// The calibrated rows of every chain in joint order (a tree's joint table, see
    /// [`DhTree::joint_table`]; the table itself for a serial robot).
    pub fn joint_table(&self) -> &DhTable {
        self.table()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::predict::Frame;
    use crate::tree::Branch;
    use dh_core::{Convention, DhRow};

    fn arm(prefix: &str, y: f64) -> DhTable {
        DhTable {
            convention: Convention::Modified,
            base: Isometry3::translation(0.0, y, 0.0),
            tool: Isometry3::translation(0.0, 0.0, 0.05),
            rows: vec![
                DhRow::revolute(&format!("{prefix}1"), 0.0, 0.0, 0.0, 0.0),
                DhRow::revolute(&format!("{prefix}2"), 0.3, 0.4, 0.0, 0.0),
            ],
        }
    }

    fn tree() -> DhTree {
        DhTree::new(
            DhTable {
                convention: Convention::Modified,
                base: Isometry3::identity(),
                tool: Isometry3::translation(0.0, 0.0, 0.2),
                rows: vec![DhRow::revolute("t1", 0.0, 0.0, 0.5, 0.0)],
            },
            vec![
                Branch {
                    name: "r".into(),
                    table: arm("r", -0.1),
                },
                Branch {
                    name: "l".into(),
                    table: arm("l", 0.1),
                },
            ],
        )
        .unwrap()
    }

    /// Each target and each tool is its own chain's: the tree's frames, through the device
    /// frame, to the last bit of a serial computation.
    #[test]
    fn a_tree_predicts_each_branch_on_its_own_chain() {
        let tree = tree();
        let device = Isometry3::new(Vector3::new(1.0, -0.2, 0.3), Vector3::new(0.0, 0.1, 0.5));
        let targets = [
            ("r".to_string(), Vector3::new(0.01, 0.0, 0.02), 0),
            ("l/m".to_string(), Vector3::new(0.0, -0.02, 0.03), 1),
        ];
        let c = Calibrated::new_tree(&tree, &[], &device, &targets).unwrap();
        assert_eq!(c.targets().len(), 2);
        assert_eq!(
            (c.target_branch(0), c.target_branch(1), c.chains()),
            (0, 1, 2)
        );
        let q = [0.3, 0.1, -0.2, 0.5, 0.7];
        let f = tree.frames(&q).unwrap();
        for (k, (_, t, b)) in targets.iter().enumerate() {
            let want = device * f.tips[*b] * nalgebra::Point3::from(*t);
            assert!((c.point(&q, k, Frame::Device) - want.coords).norm() < 1e-12);
            let tip = c.tool_of(&q, *b, Frame::Base);
            let (dp, dr) = dh_core::pose::pose_error(&tip, &f.tips[*b]);
            assert!(dp < 1e-12 && dr < 1e-12, "{dp} {dr}");
        }
        // A joint of branch l does not move branch r's tool.
        let mut moved = q;
        moved[4] += 0.3;
        let (dp, dr) = dh_core::pose::pose_error(
            &c.tool_of(&moved, 0, Frame::Base),
            &c.tool_of(&q, 0, Frame::Base),
        );
        assert!(dp < 1e-15 && dr < 1e-15, "{dp:e} m, {dr:e} rad");
        assert!(Calibrated::new_tree(&DhTree::serial(tree.trunk()), &[], &device, &[]).is_err());
    }
}
