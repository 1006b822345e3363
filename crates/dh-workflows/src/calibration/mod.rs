//! Calibration as `urdf-dh calibrate` runs it, for any Rust caller: a nominal model (URDF, DH
//! sheet, tree sheet, or none: the circle-point analysis of the data) fitted to measured points
//! or contacts, each step reported, the calibrated model written and proved as written.
//!
//! [`load`] reads what a [`CalibrationRequest`] names (model, measurements from files or
//! arrays, link masses) into a [`Loaded`]; [`Loaded::calibrate`] runs
//! `dh_calib::pipeline::calibrate` on it (serial points, contacts or a tree) and returns a
//! [`Calibrated`]: the report as plain data ([`Calibrated::json`]) and the calibrated model's
//! file ([`Calibrated::model_file`], proved before it is returned). [`run`] does both with no
//! progress. Warnings go to `err` as `urdf-dh: warning:` lines.
//!
//! Units: the request's lengths are in the data's unit; every report is in metres and radians,
//! frames as in `dh_calib::pipeline` (device frame, base link frame, tip frame).
//!
//! ```no_run
//! use dh_workflows::calibration::{run, CalibrationRequest};
//!
//! let mut request = CalibrationRequest::new(Some("robot.urdf".into()), "points.csv");
//! request.effects = "auto".parse().expect("a choice");
//! let mut warnings = Vec::new();
//! let calibrated = run(&request, &mut warnings)?;
//! println!("{}", calibrated.json()?);
//! # Ok::<(), anyhow::Error>(())
//! ```

mod contacts;
mod inputs;
mod request;
mod residuals;
mod serial;
mod tree;
mod tree_residuals;

use std::io::Write;

use anyhow::Result;
use dh_calib::pipeline::{Plan, Progress, Silent};

use crate::tree_sheet::TreeSheet;

pub use inputs::{
    enough_samples, gravity_given, gravity_inputs, keep_targets, load_inputs, read_data_for,
    read_inertials, read_sets, too_few, Inputs,
};
pub use request::{CalibrationRequest, GivenData, DEFAULT_FOLDS, DEFAULT_MAX_EFFECTS};
pub use residuals::{residuals, Residuals};
pub use serial::{check_sigma, pipeline_options, serial_error, Contacts, Points};
pub use tree::{check_tree_options, check_tree_out, load_tree, tree_model, Tree, TreeInputs};
pub use tree_residuals::{tree_residuals, TreeResiduals};

/// The model to calibrate and the data read for it.
#[derive(Clone, Debug)]
pub enum Loaded {
    /// A serial model (or the circle-point start): points, or contacts when the data has a
    /// socket column.
    Serial(Box<Inputs>),
    /// A tree sheet.
    Tree(Box<TreeInputs>),
}

/// What the model of `args` is: a tree sheet (with its file name, its options checked) or not.
///
/// # Errors
/// An invalid tree sheet; options a tree does not take.
pub fn identify(args: &CalibrationRequest) -> Result<Option<(TreeSheet, String)>> {
    match tree_model(args)? {
        Some((sheet, origin)) => {
            check_tree_options(args, &origin)?;
            Ok(Some((sheet, origin)))
        }
        None => Ok(None),
    }
}

/// Reads everything `args` names: [`identify`], then [`load_tree`] or [`load_inputs`].
///
/// # Errors
/// As those.
pub fn load(args: &CalibrationRequest, err: &mut dyn Write) -> Result<Loaded> {
    match identify(args)? {
        Some((sheet, origin)) => Ok(Loaded::Tree(Box::new(load_tree(args, sheet, origin, err)?))),
        None => Ok(Loaded::Serial(Box::new(load_inputs(args, err)?))),
    }
}

impl Loaded {
    /// Whether the data are contacts (a socket column) rather than measured points.
    pub fn is_contacts(&self) -> bool {
        match self {
            Loaded::Serial(i) => i.data.samples.iter().any(|s| s.socket.is_some()),
            Loaded::Tree(_) => false,
        }
    }

    /// What a progress report says the run is about (names only, so that it can be kept
    /// while [`Loaded::calibrate`] consumes `self`).
    pub fn subject(&self) -> Subject {
        match self {
            Loaded::Serial(i) => Subject {
                model: i.model_name.clone(),
                tree: false,
            },
            Loaded::Tree(t) => Subject {
                model: t.origin.clone(),
                tree: true,
            },
        }
    }

    /// Runs the calibration, telling `progress` when the fit starts and ends (contacts run
    /// silently).
    ///
    /// # Errors
    /// A bad `sigma`, effect label or inertials; a calibration that cannot start (too few
    /// samples, collinear points).
    pub fn calibrate(
        self,
        args: &CalibrationRequest,
        progress: &mut dyn Progress,
    ) -> Result<Calibrated> {
        let contacts = self.is_contacts();
        match self {
            Loaded::Serial(inputs) if contacts => {
                Ok(Calibrated::Contacts(serial::contacts(args, *inputs)?))
            }
            Loaded::Serial(inputs) => {
                Ok(Calibrated::Points(serial::points(args, *inputs, progress)?))
            }
            Loaded::Tree(inputs) => Ok(Calibrated::Tree(tree::calibrate_tree(
                args, *inputs, progress,
            )?)),
        }
    }
}

/// The model a run calibrates, for progress messages ([`Loaded::subject`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Subject {
    /// The model's name in the report.
    pub model: String,
    /// Whether it is a tree.
    pub tree: bool,
}

impl Subject {
    /// The notice printed before a run that may take a while, for `plan` (None for a short
    /// run).
    pub fn notice(&self, plan: &Plan) -> Option<String> {
        let model = &self.model;
        plan.is_long().then(|| if self.tree {
            format!(
                "urdf-dh: calibrating {model} ({} samples, {} targets on {} branches, {}-fold cross-validation unless there is a validation split); this may take a while",
                plan.samples, plan.targets, plan.branches, plan.folds
            )
        } else {
            format!(
                "urdf-dh: calibrating {model} ({} samples, {} targets, {}-fold cross-validation unless there is a validation split); this may take a while",
                plan.samples, plan.targets, plan.folds
            )
        })
    }

    /// What a progress line says while `plan` runs on the data `data_name`.
    pub fn label(&self, plan: &Plan, data_name: &str) -> String {
        let searched = if plan.searched && !self.tree {
            ", effects searched"
        } else {
            ""
        };
        format!(
            "calibrating {} against {data_name} ({} samples{searched})",
            self.model, plan.samples
        )
    }
}

/// A finished calibration, by path: its report and what the calibrated model is written from.
#[derive(Clone, Debug)]
pub enum Calibrated {
    /// Measured points of a serial model.
    Points(Box<Points>),
    /// Contacts of a serial model.
    Contacts(Box<Contacts>),
    /// Measured points of a tree.
    Tree(Box<Tree>),
}

impl Calibrated {
    /// The report as `calibrate --format json` prints it (metres, radians; pretty-printed, one
    /// trailing newline).
    ///
    /// # Errors
    /// Serialisation failures.
    pub fn json(&self) -> Result<String> {
        let text = match self {
            Calibrated::Points(p) => crate::text::json_pretty(&p.calibration.doc)?,
            Calibrated::Contacts(c) => crate::text::json_pretty(&c.calibration.doc)?,
            Calibrated::Tree(t) => crate::text::json_pretty(&t.calibration.doc)?,
        };
        Ok(text + "\n")
    }

    /// The calibrated model as written to `path` (a URDF for `.urdf`, a JSON sheet for
    /// `.json`, else a YAML sheet; a tree as a tree sheet), `model_path` the nominal model's
    /// file (a URDF written as an edit of it). A points model is proved as written (read back,
    /// it predicts every measured point as the fit did; the proof goes into the report's
    /// `written`): `None` when the proof fails, and then nothing may be written. A URDF that
    /// cannot hold the estimated effects is warned about on `err`.
    ///
    /// # Errors
    /// A model the format cannot express; serialisation failures.
    pub fn model_file(
        &mut self,
        path: &str,
        model_path: Option<&str>,
        err: &mut dyn Write,
    ) -> Result<Option<String>> {
        match self {
            Calibrated::Points(p) => p.model_file(path, model_path, err),
            Calibrated::Contacts(c) => c.model_file(path).map(Some),
            Calibrated::Tree(t) => t.model_file(path).map(Some),
        }
    }

    /// Whether the written model (if any) passed its proof.
    pub fn proved(&self) -> bool {
        match self {
            Calibrated::Points(p) => p.calibration.doc.written.as_ref().is_none_or(|w| w.passed),
            Calibrated::Contacts(_) | Calibrated::Tree(_) => true,
        }
    }
}

/// [`load`] and [`Loaded::calibrate`] with no progress: the whole calibration of `args`,
/// warnings on `err`.
///
/// # Errors
/// As those.
pub fn run(args: &CalibrationRequest, err: &mut dyn Write) -> Result<Calibrated> {
    load(args, err)?.calibrate(args, &mut Silent)
}
