//! `urdf-dh calibrate`: fit a model to measured points and report each step.
//!
//! Steps (see `dh_calib::calibrate`): `nominal` (only the device frame and the targets are
//! estimated), `geometric` (every identifiable DH, base, tool, device and target parameter),
//! then the effects, when asked for. Each step reports the RMS, mean and largest 3-D distance
//! between modelled and measured points on the calibration data and on validation data (the
//! `--validate` file or the file's own validation split, else k-fold cross-validation over
//! poses). Without `--model` the start is the circle-point analysis of the data.
//!
//! # Layout
//! The calibration itself (inputs, the serial, contact and tree paths, the calibrated model
//! proved as written) is the library's [`dh_workflows::calibration`]; its inputs are re-exported
//! here. The arguments this command shares with `crate::commands::sockets` and
//! `crate::commands::calibrate_tree` are in `crate::commands::calibrate_args`, re-exported here
//! (the report's documents are the library's, `dh_workflows::fit`); the run (files and rendering) is in
//! `run`, the text report in `text`, the residual chart (`--plot`) in `chart`.

use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;
use std::sync::Arc;

use anyhow::{Context, Result};
use dh_workflows::calibration::residuals;
use dh_workflows::fit::{CalibrationDoc, Effect, Measurements, Plan, Report, Silent, Split};
use dh_workflows::input::display_name;
use dh_workflows::measured::DataUnits;
use dh_workflows::model::LoadedModel;
use dh_workflows::units::{AngleUnit, LengthUnit};

use crate::error::Outcome;
use crate::plot::{residuals_svg, Panel, Residual, ResidualChart};
use crate::progress::PipelineProgress;

pub use super::calibrate_args::*;
pub use dh_workflows::calibration::{self as calibration, Calibrated, Inputs, Loaded};

// The submodules import what they use through `use super::*`: the imports above and each
// other's items, re-exported here.

mod run;
pub use run::*;
mod text;
use text::*;
mod chart;
use chart::*;
#[cfg(test)]
mod tests;
