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
//! here. The arguments and documents this command shares with `crate::commands::sockets` and
//! `crate::commands::calibrate_tree` are in `crate::commands::calibrate_args` and
//! `crate::commands::calibrate_doc`, re-exported here; the run (files and rendering) is in
//! `run`, the text report in `text`, the residual chart (`--plot`) in `chart`.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;
use std::sync::Arc;

use anyhow::{Context, Result};
use dh_calib::calibrate::Report;
use dh_calib::data::{Measurements, Split};
use dh_calib::effects::label_of;
use dh_calib::model::{Effect, Model, ModelOptions};
use dh_calib::pipeline::{self, Plan};
use dh_core::pose::from_xyz_rpy;
use dh_calib::tree::DhTree;
use dh_core::DhTable;
use nalgebra::{Isometry3, Vector3};

use crate::error::Outcome;
use crate::input::display_name;
use crate::measured::{DataUnits, LoadedModel};
use crate::plot::{residuals_svg, Panel, Residual, ResidualChart};
use crate::progress::PipelineProgress;
use crate::units::{AngleUnit, LengthUnit};
use dh_workflows::calibrated_writer::row_values;

pub use super::calibrate_args::*;
pub use super::calibrate_doc::*;
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
mod chart_tests;
#[cfg(test)]
mod tests;
