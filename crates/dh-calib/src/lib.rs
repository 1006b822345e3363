//! Kinematic identification for DH models.
//!
//! Measurement sets ([`data`]), their text formats ([`csv`], [`import`]), circle-point analysis
//! ([`cpa`]), the parametrised measurement model ([`model`]), least-squares fitting with
//! identifiability analysis ([`fit`]), the calibration pipeline ([`calibrate`]) and a simulator
//! ([`simulate`]). Depends on `dh-core`, never on the CLI; never prints.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

pub mod calibrate;
pub mod cpa;
pub mod csv;
pub mod data;
pub mod fit;
pub mod import;
pub mod model;
pub mod simulate;

pub use fit::CalibError;
