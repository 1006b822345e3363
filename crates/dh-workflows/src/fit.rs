//! The fitting's types a face names: the `dh-calib` library's, re-exported here so that the
//! faces (the command line, the Python package, the web page) depend on this one layer. What a
//! calibration reads and runs is [`crate::calibration`]; these are its parts that a face shows.
//!
//! Units: the documents' lengths are in metres and angles in radians, each parameter's unit
//! named by [`unit_of`]; points are in the measuring device's frame.

// The measurements and the effects asked for.
pub use dh_calib::data::{Measurements, Split};
pub use dh_calib::model::Effect;
pub use dh_calib::pipeline::EffectsChoice;

// The fit's progress, for a face that shows it ([`Silent`] shows nothing).
pub use dh_calib::pipeline::{Plan, Progress, Silent};

// The fit's report and the JSON documents of `calibrate` (serial, contacts, tree).
pub use dh_calib::calibrate::Report;
pub use dh_calib::pipeline::{
    unit_of, CalibrationDoc, CandidateDoc, ContactDoc, FixedDoc, NoiseDoc, ParameterDoc, PoseSi,
    SessionDoc, SessionFrameDoc, StepDoc, TableDoc, TargetDoc, TreeCalibrationDoc, UnitsDoc,
    ValidationDoc,
};

// The findings beyond the fit: outliers, diagnosis, the verdict, and the test's level.
pub use dh_calib::findings::DEFAULT_ALPHA;
// When a parameter counts as identified: an effect's estimate, in standard errors from zero; a
// geometric parameter's standard error at the measured points, in noise floors.
pub use dh_calib::pipeline::{
    documents, DiagnosisDoc, GivenBackDoc, JudgedDoc, OutlierDoc, OutliersDoc, RoundDoc,
    StructureDoc, TestDoc, TrialDoc, VerdictDoc,
};
pub use dh_calib::pipeline::{GEOMETRIC_FLOOR_RATIO, IDENTIFIED_SIGMAS};

// Contacts (ball-in-socket layouts): the distances of each contact.
pub use dh_calib::socket::{ContactDistance, SocketReport};
