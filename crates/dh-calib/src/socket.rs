//! Calibration from contacts with unknown fixed points: a ball on the flange placed by hand in
//! the sockets of a tool on the table, many joint configurations per socket, no measuring
//! device (MUKCa: G. Franzese, M. Spahn, J. Ramirez et al., "MUKCa: Accurate and Affordable
//! Cobot Calibration Without External Measurement Devices", 2025; data and code at
//! github.com/platonics-delft/kinematics_calibration).
//!
//! # Measurement model
//! A contact sample (a [`Sample`](crate::data::Sample) with a [`Socket`](crate::data::Socket))
//! says that target `k` (the ball centre, in the tip frame) sat in socket `s`:
//!
//! ```text
//! r = T_device_base · FK(q) · t_k − s        (3 residuals, metres)
//! ```
//!
//! with `s` the socket's unknown centre, three more parameters per socket (`socket.<name>.x|y|z`,
//! metres, in the device frame). A known distance `L ± σ_L` between two sockets (the tool's
//! sockets are 50 mm apart) is one more residual,
//!
//! ```text
//! r = (‖s_a − s_b‖ − L) · σ_point / σ_L
//! ```
//!
//! weighted so that both kinds are in units of the contact noise `σ_point` (per axis, metres):
//! the `sigma` option when given, otherwise the RMS per coordinate of the contact residuals of
//! the fit itself (iterated: fit, re-estimate, refit, until it changes by less than
//! [`SIGMA_CHANGE`]). Without distances the scale of the whole robot is free (every length,
//! target and socket times `1 + ε` fits as well); one distance fixes it to `σ_L / L` relative.
//!
//! # Gauge freedom
//! There is no measuring device: moving the device frame and every socket by the same rigid
//! motion changes no residual, so `device.*` is never observable. The sockets are reported in
//! the device frame held at the robot's base link frame (`T_device_base = I`), and the
//! identifiability analysis fixes `device.*` (priority 0, with `base.*` and `tool.*`) naming the
//! socket coordinates as its aliases.
//!
//! # Steps
//! - `as given`: no fit; the nominal model with its targets, each socket at the mean of its
//!   points;
//! - `nominal`: the targets and sockets;
//! - `geometric`: every identifiable DH, base, tool and target parameter with the sockets;
//! - `effects`: with the given effects, when there are any;
//! - or, with [`diagnose_sockets`] in automatic mode, one `+<label>` step per effect the rule
//!   selects (see there).
//!
//! # Consistency
//! [`Consistency`] is the figure MUKCa publishes (its `evaluate_model`): per placement (a pair
//! of sockets linked by a distance, or a lone socket), the mean Euclidean distance of each
//! modelled ball position to the mean of its socket's modelled positions, weighted by the
//! sockets' sample counts; then the plain mean over placements. It needs no socket estimate, so
//! it is computed alike on calibration and validation samples (sockets of held-out placements
//! are never fitted).
//!
//! # Layout
//! Items live in submodules and are re-exported here: the least-squares problem (`problem`),
//! the report's types (`report`), contacts and their consistency (`consistency`), a run's fits
//! (`run`), the entry points (`entry`) and the automatic selection of effects (`select`).

use std::collections::HashMap;
use std::sync::Arc;

use nalgebra::{DMatrix, Isometry3, Vector3};

use dh_core::DhTable;

use crate::calibrate::{prepare, CalibrationOptions, FixedParameter, ParameterEstimate, Stats};
use crate::data::{Measurements, Split};
use crate::diagnose::{
    bic, effect_context, paired_wilcoxon, DiagnoseOptions, EffectSelection, ALIAS_SINE,
};
use crate::effects;
use crate::findings::{CandidateReport, CandidateStatus, Trial};
use crate::fit::{self, CalibError, FitOutcome, Problem, Termination};
use crate::model::{xyz_rpy, Block, Effect, Field, Model, Observation, Observed};
use crate::stats;
use crate::tree::DhTree;

// The submodules import what they use through `use super::*`: the imports above and each
// other's items, re-exported here.
mod problem;
pub use problem::*;
mod report;
pub use report::*;
mod consistency;
pub use consistency::*;
mod run;
use run::*;
mod entry;
pub use entry::*;
mod select;
use select::*;
