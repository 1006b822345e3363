//! Calibration and circle-point analysis reports as one self-contained HTML page
//! (`urdf-dh calibrate --report`, `urdf-dh cpa --report`): inline CSS and SVG plots, no
//! script, nothing fetched (a content-security policy forbids it), so the page opens offline
//! and prints cleanly. Built from the same documents the text and JSON reports print
//! ([`crate::calibration::Calibrated`], [`crate::cpa_report::CpaReport`]), so its figures are
//! theirs.
//!
//! A calibration page holds: a summary card with the verdict; the steps with their RMS before
//! and after on calibration and validation data; each sample's residual against pose order
//! and each joint, outliers ringed (serial models from points; contacts: each contact's
//! distance to its socket); the outliers listed (pose, target, size in sigma); the diagnosis's
//! candidates with their scores and why each was taken or rejected; the parameters with
//! standard errors, the most correlated pairs and the condition number; the verdict and the
//! noise floor; the settings and levels used; and the inputs' provenance ([`Provenance`]:
//! files with SHA-256 and size, the command line, the tool's version, the date).
//!
//! Every string from an input (joint, target, file names) is escaped ([`page::esc`]); a number
//! that is missing or not finite prints `n/a`. The markup is well-formed XML (XHTML-compatible
//! HTML5), so an XML parser reads it too. Lengths are shown in millimetres, angles in degrees
//! (the JSON report keeps metres and radians).
//!
//! # Layout
//! `page` (skeleton, styles, escaping, tables), `svg` (plots), `provenance`, and one module per
//! page: `calibration` (points and trees), `parameters` (estimates, correlations), `findings` (outliers, diagnosis, verdict, shared by
//! points and trees), `contacts`, `cpa`.

mod calibration;
mod contacts;
mod cpa;
mod findings;
pub mod page;
mod parameters;
mod provenance;
pub mod svg;

pub use calibration::calibration_page;
pub use cpa::cpa_page;
pub use provenance::{sha256_hex, utc, InputFile, Provenance};
