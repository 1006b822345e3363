//! The calibration pipeline as one call: a start model, measurements and plain options in, the
//! report as a plain document (and the calibrated model) out, exactly what `urdf-dh calibrate`
//! runs and prints.
//!
//! [`calibrate`] dispatches on the start and the data: contact data (samples with a `socket`)
//! goes to [`crate::socket::diagnose_sockets`], a tree ([`Start::Tree`]) to
//! [`crate::calibrate::calibrate_tree`] (or [`crate::diagnose::diagnose_tree`] with
//! [`EffectsChoice::Auto`]), a serial table to [`crate::calibrate::calibrate`] (or
//! [`crate::diagnose::diagnose`]). The report is [`CalibrationDoc`] (trees:
//! [`TreeCalibrationDoc`]; contacts: [`ContactDoc`]), serialisable both ways with serde; every
//! length in metres, every angle in radians, poses as `T_device_base` (the robot's base link
//! frame in the measuring device's frame).
//!
//! The pipeline never prints: a caller that shows progress implements [`Progress`].
//!
//! # Layout
//! The entry point and its options are here and in `run`; the report's types in `doc`
//! (steps, parameters, sessions), `findings_doc` (outliers, verdict, diagnosis), `tree_doc`
//! and `contact_doc`; building the report from [`crate::calibrate::Report`] in `build`; the
//! preparation of the measurements (a validation set merged in, targets kept) in `inputs`; a
//! calibrated model read back from a written sheet's sections in `calibrated`.

use std::sync::Arc;

use dh_core::DhTable;
use nalgebra::Vector3;
use thiserror::Error;

use crate::calibrate::Report;
use crate::cpa::CpaError;
use crate::fit::CalibError;
use crate::gravity::{GravityModel, Inertials};
use crate::model::Effect;
use crate::socket::SocketReport;
use crate::tree::DhTree;

mod build;
mod calibrated;
mod contact_doc;
mod doc;
mod findings_doc;
mod gravity_record;
mod identification;
mod inputs;
mod run;
mod tree_doc;

pub use build::*;
pub use calibrated::*;
pub use contact_doc::*;
pub use doc::*;
pub use findings_doc::*;
pub use gravity_record::*;
pub use identification::*;
pub use inputs::*;
pub use run::*;
pub use tree_doc::*;

/// The model a calibration starts from.
#[derive(Clone, Debug)]
pub enum Start {
    /// A serial DH table (a URDF chain, a DH sheet), in the robot's base link frame.
    Serial(DhTable),
    /// A table found by circle-point analysis of the data ([`Start::cpa`]): already in the
    /// device frame, so the device frame starts at identity.
    Cpa(DhTable),
    /// A tree: a trunk and branches; each target rides on the branch it names (see
    /// [`crate::calibrate::CalibrationOptions::target_branches`]).
    Tree(DhTree),
}

impl Start {
    /// The circle-point analysis of `data` ([`crate::cpa::analyse`]) as a start.
    ///
    /// # Errors
    /// [`PipelineError::Cpa`]: data without one sweep per joint, and as
    /// [`crate::cpa::analyse`].
    pub fn cpa(
        data: &crate::data::Measurements,
        options: &crate::cpa::CpaOptions,
    ) -> Result<Start, PipelineError> {
        crate::cpa::analyse(data, options)
            .map(|r| Start::Cpa(r.extraction.table))
            .map_err(PipelineError::Cpa)
    }

    /// The table of a serial start, or a tree's joint table ([`DhTree::joint_table`]).
    pub fn table(&self) -> DhTable {
        match self {
            Start::Serial(t) | Start::Cpa(t) => t.clone(),
            Start::Tree(t) => t.joint_table(),
        }
    }
}

/// Which non-geometric effects to estimate after the geometric step.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum EffectsChoice {
    /// None: the report ends with `geometric`.
    #[default]
    None,
    /// Let the diagnosis ([`crate::diagnose`]) choose, at most
    /// [`PipelineOptions::max_effects`].
    Auto,
    /// These labels (`gear_ratio:<joint>`, ..., see [`crate::effects::parse_label_in`]).
    List(Vec<String>),
}

impl std::str::FromStr for EffectsChoice {
    type Err = String;
    /// `none` (or nothing), `auto`, or comma-separated labels.
    fn from_str(s: &str) -> Result<Self, String> {
        match s.trim() {
            "none" | "" => Ok(EffectsChoice::None),
            "auto" => Ok(EffectsChoice::Auto),
            list => Ok(EffectsChoice::List(
                list.split(',')
                    .map(|l| l.trim().to_string())
                    .filter(|l| !l.is_empty())
                    .collect(),
            )),
        }
    }
}

/// The options of [`calibrate`], as plain values.
#[derive(Clone, Debug)]
pub struct PipelineOptions {
    /// Which effects to estimate.
    pub effects: EffectsChoice,
    /// Most effects [`EffectsChoice::Auto`] adds. Default 12.
    pub max_effects: usize,
    /// Significance level of the diagnosis's tests (entry F test, held-out signed-rank test,
    /// the final model's verdict), in (0, 0.5]. Default [`crate::findings::DEFAULT_ALPHA`]
    /// (0.01); a higher level takes effects on weaker evidence.
    pub alpha: f64,
    /// Folds of cross-validation without a validation split (at least 2). Default 5.
    pub folds: usize,
    /// Known per-axis measurement noise (metres); `None`: the samples' own or the scatter of
    /// repeated poses.
    pub sigma: Option<f64>,
    /// Fit the outliers with the rest (they are still named). Not used for contacts.
    pub keep_outliers: bool,
    /// Link masses for the gravity effects (compliance, backlash); `None`: no gravity effects.
    pub inertials: Option<Inertials>,
    /// Gravity in the robot's base link frame (m/s²). Default `(0, 0, -9.80665)`.
    pub gravity: Vector3<f64>,
    /// The names the report gives the model and data.
    pub names: Names,
}

impl Default for PipelineOptions {
    fn default() -> Self {
        PipelineOptions {
            effects: EffectsChoice::None,
            max_effects: 12,
            alpha: crate::findings::DEFAULT_ALPHA,
            folds: 5,
            sigma: None,
            keep_outliers: false,
            inertials: None,
            gravity: GravityModel::default_gravity(),
            names: Names::default(),
        }
    }
}

/// Which path a calibration takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PathKind {
    /// Measured points of a serial robot.
    Points,
    /// Measured points of a tree.
    Tree,
    /// Contacts with unknown fixed points.
    Contacts,
}

/// What a calibration is about to do, for a progress display.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Plan {
    /// The path.
    pub kind: PathKind,
    /// Calibration samples.
    pub samples: usize,
    /// Targets of the data.
    pub targets: usize,
    /// Branches of a tree (0 for a serial robot).
    pub branches: usize,
    /// Folds of cross-validation (unless there is a validation split).
    pub folds: usize,
    /// Whether the effects are searched ([`EffectsChoice::Auto`]).
    pub searched: bool,
    /// A rough size of the work: calibration samples × (folds + 1) × steps.
    pub work: usize,
}

impl Plan {
    /// Work beyond which a run may take a while (a second or more per step).
    pub const LONG: usize = 200_000;

    /// Whether the run may take a while.
    pub fn is_long(&self) -> bool {
        self.work > Self::LONG
    }
}

/// Progress of a calibration: told when the fit starts and when it is over (whatever its
/// outcome). The pipeline never prints; a terminal caller draws a progress line.
pub trait Progress {
    /// The fit is about to start.
    fn started(&mut self, plan: &Plan);
    /// The fit is over.
    fn finished(&mut self);
}

/// A [`Progress`] that shows nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct Silent;

impl Progress for Silent {
    fn started(&mut self, _: &Plan) {}
    fn finished(&mut self) {}
}

/// A calibration of measured points of a serial robot.
#[derive(Clone, Debug)]
pub struct PointsCalibration {
    /// The report, as a document.
    pub doc: CalibrationDoc,
    /// The library's report (every figure, the covariance, the calibrated table).
    pub report: Report,
    /// The effects of the last step (for predictions and charts).
    pub effects: Vec<Arc<dyn Effect>>,
}

/// A calibration of a tree.
#[derive(Clone, Debug)]
pub struct TreeCalibration {
    /// The report, as a document (the serial report's keys and `tree`).
    pub doc: TreeCalibrationDoc,
    /// The library's report.
    pub report: Report,
    /// The calibrated tree.
    pub calibrated: DhTree,
    /// Each target's branch, by index into the tree's branches.
    pub target_branches: Vec<(String, usize)>,
}

/// A calibration from contacts.
#[derive(Clone, Debug)]
pub struct ContactCalibration {
    /// The report, as a document.
    pub doc: ContactDoc,
    /// The library's report.
    pub report: SocketReport,
}

/// What [`calibrate`] returns, by path.
#[derive(Clone, Debug)]
pub enum Calibration {
    /// Measured points of a serial robot.
    Points(Box<PointsCalibration>),
    /// Measured points of a tree.
    Tree(Box<TreeCalibration>),
    /// Contacts.
    Contacts(Box<ContactCalibration>),
}

impl Calibration {
    /// The report as JSON (metres, radians), as `urdf-dh calibrate --format json` prints it
    /// (without the proof on a written model).
    ///
    /// # Errors
    /// A serialisation failure.
    pub fn to_json(&self) -> Result<String, serde_json::Error> {
        match self {
            Calibration::Points(c) => serde_json::to_string_pretty(&c.doc),
            Calibration::Tree(c) => serde_json::to_string_pretty(&c.doc),
            Calibration::Contacts(c) => serde_json::to_string_pretty(&c.doc),
        }
    }

    /// The calibrated joint table (a tree's joint table, see [`DhTree::joint_table`]).
    pub fn calibrated_table(&self) -> DhTable {
        match self {
            Calibration::Points(c) => c.report.calibrated.clone(),
            Calibration::Tree(c) => c.calibrated.joint_table(),
            Calibration::Contacts(c) => c.report.calibrated.clone(),
        }
    }
}

/// What can stop a calibration pipeline.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum PipelineError {
    /// An effect label that names no effect of the model.
    #[error("{source}")]
    Effect {
        /// The label.
        label: String,
        /// Why it does not parse.
        source: CalibError,
    },
    /// Link masses the gravity model cannot use.
    #[error("inertials: {0}")]
    Inertials(CalibError),
    /// The circle-point analysis of the data failed.
    #[error("circle-point analysis failed: {0}")]
    Cpa(CpaError),
    /// Too few calibration samples for the unknowns.
    #[error("expected at least {needed} calibration samples for {targets} target(s) (each target's position and the device frame are estimated: 3 per target + 6, 3 coordinates per sample), found {found}")]
    TooFewSamples {
        /// Samples needed.
        needed: usize,
        /// Targets measured.
        targets: usize,
        /// Calibration samples found.
        found: usize,
    },
    /// A target to keep that the data does not have.
    #[error("targets names '{target}', which the data does not have")]
    UnknownTarget {
        /// The name.
        target: String,
        /// The data's targets.
        targets: Vec<String>,
    },
    /// A target of a tree's data that rides on no branch.
    #[error("target '{target}': expected a branch name of the tree ({}) or BRANCH/NAME, found no such branch", branches.join(", "))]
    NoBranch {
        /// The target.
        target: String,
        /// The tree's branches.
        branches: Vec<String>,
    },
    /// Contact data with a tree (contacts are calibrated for serial robots only).
    #[error("contact data (a 'socket' column) is calibrated for serial models only")]
    ContactsOnTree,
    /// The fit failed.
    #[error("calibration failed: {0}")]
    Calibration(CalibError),
    /// The effect search of a serial robot ([`crate::diagnose::diagnose`]) failed.
    #[error("calibration failed: {0}")]
    Search(CalibError),
}
