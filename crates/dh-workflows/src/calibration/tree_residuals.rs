//! Each measured point's residual before and after a calibration of a tree ([`TreeResiduals`],
//! [`tree_residuals`]): the distance between the point the tree predicts and the one measured
//! (device frame, metres), each target on its branch, with the nominal tree (device frame and
//! targets at the `nominal` step's values) and with the calibrated one (the last step's effects
//! at their estimates, parsed on the nominal tree with its masses as the fit parsed them). What
//! the residual chart of a tree (`calibrate --plot`) draws, one panel pair per branch.

use std::sync::Arc;

use anyhow::Result;
use dh_calib::data::Measurements;
use dh_calib::effects::{parse_label_in, EffectContext};
use dh_calib::gravity::GravityModel;
use dh_calib::model::{Effect, Model, ModelOptions};
use dh_calib::tree::DhTree;
use nalgebra::{Isometry3, Vector3};

use super::residuals::{estimate, fitted_targets, model_distances, nominal_frames, pose_indices};
use super::Tree;
use crate::calibrated_writer::row_values;

/// Every sample's residual before and after a tree calibration, its pose and its branch.
#[derive(Clone, Debug, PartialEq)]
pub struct TreeResiduals {
    /// Distance with the nominal tree, per sample in file order (metres).
    pub before: Vec<f64>,
    /// Distance with the calibrated tree and its effects, per sample (metres).
    pub after: Vec<f64>,
    /// Each sample's pose index (as [`super::Residuals::poses`]).
    pub poses: Vec<usize>,
    /// Number of poses.
    pub pose_count: usize,
    /// Each target's branch (index into the tree's branches), in the data's target order.
    pub branches: Vec<usize>,
}

/// Distances between the points `tree` (with `effects` at their values, the device frame and
/// the targets, target `k` on branch `branches[k]`) predicts and the measured ones, per
/// sample; `q` the samples' joint values in the tree's row order.
fn distances(
    tree: &DhTree,
    branches: &[usize],
    effects: &[(Arc<dyn Effect>, Vec<f64>)],
    frames: (&Isometry3<f64>, &[Vector3<f64>]),
    data: &Measurements,
    q: &[Vec<f64>],
) -> Result<Vec<f64>> {
    let on: Vec<(String, usize)> = data
        .targets
        .iter()
        .cloned()
        .zip(branches.iter().copied())
        .collect();
    let model = Model::new_tree(tree, &on, &ModelOptions::default())?;
    model_distances(model, effects, frames, data, q)
}

/// The residuals of the tree calibration `t`.
///
/// # Errors
/// A model that cannot be built from the trees, an effect label that no longer parses on the
/// nominal tree, joint values the trees cannot take.
pub fn tree_residuals(t: &Tree) -> Result<TreeResiduals> {
    let (inputs, c) = (&t.inputs, &t.calibration);
    let (data, report) = (&inputs.data, &c.report);
    let nominal = &inputs.sheet.tree;
    let branches: Vec<usize> = data
        .targets
        .iter()
        .map(|name| {
            c.target_branches
                .iter()
                .find(|(n, _)| n == name)
                .map_or(0, |(_, b)| *b)
        })
        .collect();
    let q = row_values(&inputs.model.table, data)?;
    let (poses, pose_count) = pose_indices(data);
    let (device0, targets0) = nominal_frames(report, &data.targets);
    let before = distances(nominal, &branches, &[], (&device0, &targets0), data, &q)?;
    let ctx = EffectContext {
        tree: nominal.clone(),
        gravity: match &inputs.inertials {
            Some(i) => Some(Arc::new(GravityModel::new(nominal, i, inputs.gravity)?)),
            None => None,
        },
        gravity_vector: inputs.gravity,
    };
    let effects = report
        .selected_effects
        .iter()
        .map(|label| {
            let e = parse_label_in(label, &ctx)?;
            let v = e
                .parameter_names()
                .iter()
                .map(|n| estimate(report, n))
                .collect();
            Ok((e, v))
        })
        .collect::<Result<Vec<_>, dh_calib::CalibError>>()?;
    let targets1 = fitted_targets(report, &data.targets);
    let after = distances(
        &c.calibrated,
        &branches,
        &effects,
        (&report.device, &targets1),
        data,
        &q,
    )?;
    Ok(TreeResiduals {
        before,
        after,
        poses,
        pose_count,
        branches,
    })
}
