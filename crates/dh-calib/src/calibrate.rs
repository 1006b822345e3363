//! The geometric calibration pipeline: register, fit the device frame and targets, find what
//! the data can identify, fit the identifiable DH errors, validate each step.
//!
//! # Steps
//! 1. Closed-form start: the device frame by rigid registration (Kabsch, "A solution for the
//!    best rotation to relate two sets of vectors", Acta Cryst. A32, 1976; Horn, "Closed-form
//!    solution of absolute orientation using unit quaternions", JOSA A 4(4), 1987) of the
//!    nominal model's points to the measured ones, alternated with the closed-form target
//!    positions given the frame, so that any device pose converges.
//! 2. `nominal`: only the device frame and the targets are estimated.
//! 3. Identifiability at that estimate over every geometric parameter
//!    ([`crate::fit::identifiability`]): the non-identifiable ones are fixed at nominal and
//!    reported with their aliases.
//! 4. `geometric`: the identifiable DH, base, tool, device and target parameters together.
//! 5. `effects` (only when effects are given): the same with the effect parameters added.
//!
//! Each step reports the RMS, mean and largest Euclidean distance between modelled and measured
//! points on the calibration samples and on validation samples: the validation split when
//! there is one, else k-fold cross-validation over poses (samples sharing `config`, or else the
//! same joint values, stay in one fold).
//!
//! # Layout
//! Items live in submodules and are re-exported here: the options (`options`), the report's
//! types (`report`), the closed-form start (`start`; preparing the data is the private `crate::prepare`'s,
//! the rigid registration [`crate::registration`]'s), held-out
//! errors (`validation`), the session and its steps (`session`), the entry points
//! (`pipeline`), identifiability and estimates (`identify`), and the residual tests of the
//! verdict (`verdict`). The diagnosis's data types are in [`crate::findings`].

use std::collections::HashMap;
use std::sync::Arc;

use dh_core::DhTable;
use nalgebra::{DMatrix, Isometry3, Matrix3, Vector3};

use crate::data::Measurements;
use crate::fit::{self, CalibError, FitOptions, FitOutcome, Termination};
use crate::model::{
    xyz_rpy, Block, Effect, Model, ModelOptions, ModelProblem, Observation, Observed,
    PairParametrisation, SampleContext, SubsetProblem,
};
use crate::tree::DhTree;

// The submodules import what they use through `use super::*`: the imports above and each
// other's items, re-exported here.
mod options;
pub use options::*;
mod report;
pub(crate) use crate::prepare::*;
pub use crate::registration::register;
pub use report::*;
mod start;
use start::*;
mod validation;
pub use validation::*;
mod one_step;
mod residuals_at;
pub(crate) use residuals_at::{ResidualsAt, SessionProblem};
mod rows_at;
pub(crate) use rows_at::sample_rows;
mod left_out;
pub(crate) use left_out::LeftOut;
mod session;
pub(crate) use session::*;
mod pipeline;
pub use pipeline::*;
mod identify;
pub(crate) use identify::*;
mod screen;
mod shape_start;
pub(crate) use shape_start::{best_shape, sequence_span, shape_start};
mod structure;
mod verdict;
pub use screen::screen;
pub(crate) use screen::{check_level, confirmed_at, screen_from, Confirmation};
pub(crate) use verdict::*;
#[cfg(test)]
mod tests;
