//! The entry point [`calibrate`]: the dispatch on the start and the data, and the three paths
//! (measured points of a serial robot, of a tree, contacts) with their effects and options.

use std::sync::Arc;

use nalgebra::Isometry3;

use super::{
    enough_samples, tables, Calibration, CalibrationDoc, ContactCalibration, ContactDoc,
    EffectsChoice, PathKind, PipelineError, PipelineOptions, Plan, PointsCalibration, Progress,
    Start, TreeCalibration, TreeCalibrationDoc,
};
use crate::calibrate::{calibrate as fit_serial, calibrate_tree as fit_tree, CalibrationOptions};
use crate::data::{Measurements, Split};
use crate::diagnose::{diagnose, diagnose_tree, DiagnoseOptions, EffectSelection};
use crate::effects::{parse_label_in, EffectContext};
use crate::gravity::GravityModel;
use crate::model::Effect;
use crate::outliers::OutlierOptions;
use crate::socket::diagnose_sockets;
use crate::tree::DhTree;

/// Calibrates `start` against `data` (calibration and validation samples; see
/// [`super::merge_validation`] for a separate validation set) as `urdf-dh calibrate` does: see
/// the module docs for the paths. `progress` is told when the fit starts and ends.
///
/// # Errors
/// Effect labels that name no effect of the model, link masses the gravity model cannot use,
/// too few calibration samples, targets of a tree on no branch, contact data with a tree, and a
/// fit that fails (see [`PipelineError`]).
pub fn calibrate(
    start: &Start,
    data: &Measurements,
    options: &PipelineOptions,
    progress: &mut dyn Progress,
) -> Result<Calibration, PipelineError> {
    let contacts = data.samples.iter().any(|s| s.socket.is_some());
    match start {
        Start::Tree(_) if contacts => Err(PipelineError::ContactsOnTree),
        Start::Tree(tree) => {
            calibrate_tree(tree, data, options, progress).map(|c| Calibration::Tree(Box::new(c)))
        }
        Start::Serial(table) | Start::Cpa(table) if contacts => {
            calibrate_contacts(table, data, options).map(|c| Calibration::Contacts(Box::new(c)))
        }
        Start::Serial(table) | Start::Cpa(table) => calibrate_points(
            table,
            matches!(start, Start::Cpa(_)),
            data,
            options,
            progress,
        )
        .map(|c| Calibration::Points(Box::new(c))),
    }
}

/// The effect context of `tree` with the gravity model of `options`' link masses.
fn context(tree: &DhTree, options: &PipelineOptions) -> Result<EffectContext, PipelineError> {
    Ok(EffectContext {
        tree: tree.clone(),
        gravity: match &options.inertials {
            Some(i) => Some(Arc::new(
                GravityModel::new(tree, i, options.gravity).map_err(PipelineError::Inertials)?,
            )),
            None => None,
        },
        gravity_vector: options.gravity,
    })
}

/// The effects of `labels` in `ctx`.
fn parse_all(
    labels: &[String],
    ctx: &EffectContext,
) -> Result<Vec<Arc<dyn Effect>>, PipelineError> {
    labels
        .iter()
        .map(|l| {
            parse_label_in(l, ctx).map_err(|source| PipelineError::Effect {
                label: l.clone(),
                source,
            })
        })
        .collect()
}

fn calibration_samples(data: &Measurements) -> usize {
    data.samples
        .iter()
        .filter(|s| s.split == Split::Calibration)
        .count()
}

fn outliers(options: &PipelineOptions) -> OutlierOptions {
    OutlierOptions {
        keep: options.keep_outliers,
        ..OutlierOptions::default()
    }
}

fn diagnose_options(options: &PipelineOptions, effects: EffectSelection) -> DiagnoseOptions {
    DiagnoseOptions {
        effects,
        inertials: options.inertials.clone(),
        gravity: options.gravity,
        max_effects: options.max_effects,
        alpha: options.alpha,
        ..DiagnoseOptions::default()
    }
}

/// Measured points of a serial robot; `cpa`: the table is a circle-point analysis, already in
/// the device frame.
fn calibrate_points(
    table: &dh_core::DhTable,
    cpa: bool,
    data: &Measurements,
    options: &PipelineOptions,
    progress: &mut dyn Progress,
) -> Result<PointsCalibration, PipelineError> {
    enough_samples(data)?;
    let ctx = context(&DhTree::serial(table), options)?;
    let effects = match &options.effects {
        EffectsChoice::List(labels) => parse_all(labels, &ctx)?,
        EffectsChoice::None | EffectsChoice::Auto => Vec::new(),
    };
    let fit_options = CalibrationOptions {
        folds: options.folds,
        sigma: options.sigma,
        effects: effects.clone(),
        // The CPA table is already in the device frame: its base is DH frame 0 there.
        device_guess: cpa.then(Isometry3::identity),
        outliers: outliers(options),
        ..CalibrationOptions::default()
    };
    let samples = calibration_samples(data);
    let searched = options.effects == EffectsChoice::Auto;
    progress.started(&Plan {
        kind: PathKind::Points,
        samples,
        targets: data.targets.len(),
        branches: 0,
        folds: options.folds,
        searched,
        work: samples * (options.folds + 1) * (2 + usize::from(!effects.is_empty())),
    });
    let fitted = if searched {
        // Every option but the effects: the diagnosis chooses them.
        let diag = diagnose_options(options, EffectSelection::default());
        diagnose(table, data, &fit_options, &diag).map_err(PipelineError::Search)
    } else {
        fit_serial(table, data, &fit_options).map_err(PipelineError::Calibration)
    };
    progress.finished();
    let report = fitted?;
    let effects = if searched {
        parse_all(&report.selected_effects, &ctx)?
    } else {
        effects
    };
    let doc = CalibrationDoc::new(&report, &options.names, table.convention, data);
    Ok(PointsCalibration {
        doc,
        report,
        effects,
    })
}

/// Measured points of a tree.
fn calibrate_tree(
    tree: &DhTree,
    data: &Measurements,
    options: &PipelineOptions,
    progress: &mut dyn Progress,
) -> Result<TreeCalibration, PipelineError> {
    enough_samples(data)?;
    let target_branches = target_branches(tree, data)?;
    let ctx = context(tree, options)?;
    let effects = match &options.effects {
        EffectsChoice::List(labels) => parse_all(labels, &ctx)?,
        EffectsChoice::None | EffectsChoice::Auto => Vec::new(),
    };
    let fit_options = CalibrationOptions {
        folds: options.folds,
        sigma: options.sigma,
        effects,
        target_branches: target_branches
            .iter()
            .map(|(t, b)| (t.clone(), tree.branches()[*b].name.clone()))
            .collect(),
        outliers: outliers(options),
        ..CalibrationOptions::default()
    };
    let samples = calibration_samples(data);
    let steps = 2 + usize::from(options.effects != EffectsChoice::None);
    progress.started(&Plan {
        kind: PathKind::Tree,
        samples,
        targets: data.targets.len(),
        branches: tree.branches().len(),
        folds: options.folds,
        searched: options.effects == EffectsChoice::Auto,
        work: samples * (options.folds + 1) * steps,
    });
    let fitted = match &options.effects {
        EffectsChoice::Auto => {
            let diag = diagnose_options(options, EffectSelection::default());
            diagnose_tree(tree, data, &fit_options, &diag)
        }
        EffectsChoice::None | EffectsChoice::List(_) => fit_tree(tree, data, &fit_options),
    };
    progress.finished();
    let report = fitted.map_err(PipelineError::Calibration)?;
    let calibrated = report.tree.clone().unwrap_or_else(|| tree.clone());
    let table = tree.joint_table();
    let serial = CalibrationDoc::new(&report, &options.names, table.convention, data);
    let tree_doc = tables(tree, &calibrated, &serial, &target_branches);
    Ok(TreeCalibration {
        doc: TreeCalibrationDoc {
            report: serial,
            tree: tree_doc,
        },
        report,
        calibrated,
        target_branches,
    })
}

/// The `(target, branch index)` of every target of `data`: the branch of the target's own name,
/// or of the part before its first `/` (`right/wrist`).
///
/// # Errors
/// [`PipelineError::NoBranch`] for a target on no branch.
pub fn target_branches(
    tree: &DhTree,
    data: &Measurements,
) -> Result<Vec<(String, usize)>, PipelineError> {
    data.targets
        .iter()
        .map(|t| {
            let own = tree.branch_index(t);
            let before = t.split_once('/').and_then(|(b, _)| tree.branch_index(b));
            own.or(before)
                .map(|b| (t.clone(), b))
                .ok_or_else(|| PipelineError::NoBranch {
                    target: t.clone(),
                    branches: tree.branches().iter().map(|b| b.name.clone()).collect(),
                })
        })
        .collect()
}

/// Contacts with unknown fixed points (see [`crate::socket`]).
fn calibrate_contacts(
    table: &dh_core::DhTable,
    data: &Measurements,
    options: &PipelineOptions,
) -> Result<ContactCalibration, PipelineError> {
    let effects = match &options.effects {
        EffectsChoice::None => EffectSelection::None,
        EffectsChoice::Auto => EffectSelection::Auto,
        EffectsChoice::List(labels) => {
            parse_all(labels, &context(&DhTree::serial(table), options)?)?;
            EffectSelection::Labels(labels.clone())
        }
    };
    let fit_options = CalibrationOptions {
        sigma: options.sigma,
        ..CalibrationOptions::default()
    };
    let diag = DiagnoseOptions {
        effects,
        inertials: options.inertials.clone(),
        gravity: options.gravity,
        max_effects: options.max_effects,
        alpha: options.alpha,
        ..DiagnoseOptions::default()
    };
    let report = diagnose_sockets(&DhTree::serial(table), data, &fit_options, &diag)
        .map_err(PipelineError::Calibration)?;
    let doc = ContactDoc::new(&options.names.model, &options.names.data, &report);
    Ok(ContactCalibration { doc, report })
}
