//! Kinematic identification for DH models.
//!
//! Depends on `dh-core`, never on the CLI; never prints. Every concept is one hop from here:
//!
//! - Data: measurement sets ([`data`]), the canonical CSV ([`csv`]: reading, writing, units,
//!   column names), published datasets ([`import`]), joint-value files ([`joints`]) and
//!   measurement sessions with their own device frames ([`sessions`]).
//! - Models: the parametrised measurement model ([`model`]: points, and 6-DoF target poses
//!   with their own angular sigma) of serial robots and trees
//!   ([`tree`]); non-geometric effects ([`effects`]: labels, candidates, models), effects of
//!   the measurement order ([`effects_order`]) and gravity ([`gravity`]).
//! - Fitting: nonlinear least squares with identifiability analysis ([`fit`]); circle-point
//!   analysis for a start without a model ([`cpa`]); the calibration pipeline ([`calibrate`]:
//!   options, preparation, closed-form start, session steps, validation, identifiability,
//!   report, verdict); calibration from contacts with unknown fixed points ([`socket`]);
//!   outlier screening ([`outliers`]); the whole pipeline as one call, its report a plain
//!   document ([`pipeline`]: serial, tree and contact paths, the JSON report's types).
//! - Diagnosis: the automatic search for the effect a residual lacks ([`diagnose`]: selection
//!   loop, scoring and tests), its rival candidates ([`rivals`]) and its findings as data
//!   ([`findings`]: candidate table, residual tests, verdict).
//! - Using a calibration: predictions with uncertainty ([`predict`]), compensation of joint
//!   values ([`compensate`]), and a simulator with known truth ([`simulate`]).
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

pub mod calibrate;
pub mod compensate;
pub mod covariance;
pub mod cpa;
pub mod csv;
pub mod data;
pub mod diagnose;
mod effect_label;
pub mod effects;
pub mod effects_order;
pub mod effects_thermal;
pub mod findings;
pub mod fit;
pub mod gravity;
pub mod import;
pub mod joints;
pub mod model;
pub mod outliers;
pub mod pipeline;
pub mod predict;
mod prepare;
pub mod registration;
pub mod rivals;
pub mod sessions;
pub mod simulate;
pub mod socket;
mod stats;
#[cfg(test)]
mod test_robots;
pub mod tree;

pub use data::MIN_SIGMA;
pub use fit::CalibError;
