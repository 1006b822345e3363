//! Kinematic identification for DH models.
//!
//! Measurement sets ([`data`]), their text formats ([`csv`], [`import`]), circle-point analysis
//! ([`cpa`]), the parametrised measurement model ([`model`]) of serial robots and trees
//! ([`tree`]), least-squares fitting with identifiability analysis ([`fit`]), the calibration
//! pipeline ([`calibrate`]), non-geometric effects ([`effects`], [`gravity`]) and the automatic
//! diagnosis that traces a residual to the effect the model lacks ([`diagnose`]), and a
//! simulator ([`simulate`]). Depends on `dh-core`, never on the CLI; never prints.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

pub mod calibrate;
pub mod compensate;
pub mod cpa;
pub mod csv;
pub mod data;
pub mod diagnose;
pub mod effects;
pub mod effects_order;
pub mod findings;
pub mod fit;
pub mod gravity;
pub mod import;
pub mod joints;
pub mod model;
pub mod outliers;
pub mod predict;
pub mod rivals;
pub mod sessions;
pub mod simulate;
pub mod socket;
mod stats;
pub mod tree;

pub use fit::CalibError;
