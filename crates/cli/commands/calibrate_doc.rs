//! The documents `urdf-dh calibrate` writes: the JSON report's types (the library's, see
//! `dh_calib::pipeline`: [`CalibrationDoc`] and its parts; lengths in metres, angles in
//! radians, units named per parameter by [`unit_of`]) and the calibrated model (a URDF or a DH
//! sheet with its `calibration` section; the `dh-workflows` library's
//! [`dh_workflows::calibrated_writer`]).
//!
//! Shared by `calibrate`, its contact path and its tree path.

pub use dh_calib::pipeline::{
    unit_of, CalibrationDoc, CandidateDoc, FixedDoc, NoiseDoc, ParameterDoc, PoseSi, StepDoc,
    TargetDoc, UnitsDoc, ValidationDoc,
};
pub use dh_workflows::calibrated_writer::{calibrated_bytes, calibrated_text, Nominal};
