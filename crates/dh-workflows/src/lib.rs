//! What urdf-dh reads, writes and runs, for every caller: the one library layer its faces (the
//! command line, the Python package, the web page) call. Whole workflows (extract and check
//! with their proofs, convert, simulate, circle-point analysis, calibrate, predict, compensate)
//! and the file formats they read and write (DH sheets as a vendor or `urdf-dh extract` writes
//! them, tree sheets, measurement files, calibrated models, URDF/xacro/MJCF/SDFormat inputs).
//! What the `urdf-dh` command line reads and writes, a Rust caller reads and writes here, with
//! the same checks and the same messages. The geometry (`dh_core`) and the fitting
//! (`dh_calib`) below it are re-exported where a caller needs their types: [`geometry`], [`fit`],
//! and beside the workflow that uses them ([`input`], [`import`], [`cpa_report`], [`predict`],
//! [`compensate`], [`measured`]); a face needs no other library crate.
//!
//! Where each concept lives:
//!
//! | module | holds |
//! |---|---|
//! | [`sheet`] | the serial sheet format: [`SheetDoc`] as written (YAML, JSON), [`Sheet`] in SI units, reading and validation (rows, poses, mimics, couplings, effects) |
//! | [`tree_sheet`] | tree sheets (a trunk and `branches`) and link masses: [`TreeSheet`], [`InertialsDoc`](tree_sheet::InertialsDoc) |
//! | [`units`] | [`LengthUnit`], [`AngleUnit`], and the rounding of printed values |
//! | [`render`] | writing a sheet as a text table, YAML, JSON, CSV or Markdown ([`Format`]) |
//! | [`read_back`] | reading every written format back (the CSV, text and Markdown tables) |
//! | [`prove`] | proving a written sheet: read back at its precision and compared with its source by forward kinematics |
//! | [`extract`] | a URDF chain's DH table as a sheet with the extraction's facts, and its proof ([`prove_extracted`](extract::prove_extracted)) |
//! | [`check`] | [`compare`]: a URDF chain against a sheet, as a [`CheckReport`] |
//! | [`ranges`] | the ranges of the numeric options (tolerances, sigmas, counts, levels), one parser each |
//! | [`ur`] | a Universal Robots controller's factory calibration (`calibration.conf` deltas) on the UR family's shipped nominal tables |
//! | [`urdf_writer`] | a DH table written as a URDF with the same kinematics, and its proof (read back and extracted again) |
//! | [`urdf_edit`] | a calibrated table written as a minimal edit of the user's own URDF (only the chain's joint origins change) |
//! | [`written`] | the proof of a calibrated model as written: read back, it predicts every measured point as the fit did |
//! | [`text`] | escaping names for messages and tables |
//! | [`error`] | [`SheetError`], every refusal, with its [`hint`](SheetError::hint); [`Hinted`](error::Hinted), a message with a hint |
//! | [`input`] | reading robot files (URDF, `.xacro`, standard input) and a URDF's chain |
//! | [`xacro`] | `.xacro` files expanded natively (arguments, package folders), Python's `xacro` only for a construct the native expansion refuses |
//! | [`measured`] | measurement files in the canonical CSV layout ([`DataFile`](measured::DataFile), [`DataUnits`](measured::DataUnits)), effect labels, joint values beyond their limits |
//! | [`calibrated`] | a calibrated model as `calibrate --out` writes it (device frame, targets, sessions, covariance), read back to predict |
//! | [`predict`] | a calibrated model's target positions or tool poses at joint values, with their uncertainty |
//! | [`compensate`] | the joint values with which a calibrated robot reaches what the nominal model reaches at commanded values |
//! | [`calibration`] | a whole calibration as `calibrate` runs it: a [`CalibrationRequest`](calibration::CalibrationRequest) (files or arrays) loaded, fitted (points, contacts or a tree), its report and its calibrated model proved as written |
//! | [`calibrated_writer`] | writing a calibrated model (`calibrate --out`): a sheet with its `calibration` section or a URDF, proved as written |
//! | [`output`] | writing files all or nothing (staged, synced, renamed), `-` for standard output, and refusing an output that is an input |
//! | [`cpa_report`] | circle-point analysis as `cpa` runs it: the table the measured axes make, as a sheet, and the report's document (sweeps, circles, commanded against measured motion, the comparison with a nominal model) |
//! | [`report_html`] | a calibration's or circle-point analysis's report as one self-contained HTML page (`--report`): plots, findings, provenance |
//! | [`simulation`] | simulated measurements of a model with planted errors and effects, the CSV and the truth sheet `simulate` writes |
//! | [`import`] | published datasets as their authors left them (the importers), and data tables read as text or MATLAB `.mat` |
//! | [`geometry`] | the geometry's types a face names (DH tables, conventions, tolerances, lines), `dh_core`'s |
//! | [`fit`] | the fitting's types a face names (measurements, effects, progress, the report's documents), `dh_calib`'s |
//! | [`model`] | the robot model of the measured-data commands: a URDF chain extracted and verified, or a DH sheet ([`load_model`](model::load_model)) |
//!
//! Frames and units: a sheet's numbers are in its own `length_unit` and `angle_unit`; every
//! type read from one ([`Sheet`], [`TreeSheet`], the `dh_core` tables) is in metres and radians.
//! `base` is DH frame 0 in the base link frame, `tool` the tip link frame in the last DH frame.
//!
//! ```
//! use dh_workflows::{render_sheet, Format, Sheet, SheetDoc};
//!
//! let text = "convention: standard\nlength_unit: mm\nangle_unit: deg\njoints:\n  \
//!             - {name: j1, type: revolute, a: 180, alpha: -90, d: 400, theta: 0}\n";
//! let sheet = Sheet::parse(text, "robot.yaml")?;
//! assert!((sheet.table.rows[0].a - 0.18).abs() < 1e-15); // metres
//! let doc = SheetDoc::from_table(&sheet.table, sheet.length_unit, sheet.angle_unit);
//! let yaml = render_sheet(&doc, Format::Yaml)?;
//! assert_eq!(Sheet::parse(&yaml, "written")?.table.rows[0].name, "j1");
//! # Ok::<(), dh_workflows::SheetError>(())
//! ```
//!
//! The optional feature `clap` derives `clap::ValueEnum` for the unit, convention and format
//! enums.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

pub mod calibrated;
pub mod calibrated_writer;
pub mod calibration;
pub mod check;
pub mod compensate;
pub mod cpa_report;
pub mod error;
pub mod extract;
pub mod fit;
pub mod geometry;
pub mod import;
pub mod input;
pub mod measured;
pub mod model;
pub mod output;
pub mod poe;
pub mod predict;
pub mod prove;
pub mod ranges;
pub mod read_back;
pub mod render;
pub mod report_html;
pub mod sheet;
pub mod simulation;
pub mod sniff;
pub mod text;
mod timed_rows;
pub mod tree_sheet;
pub mod units;
pub mod ur;
pub mod urdf_edit;
pub mod urdf_writer;
pub mod written;
pub mod xacro;

pub use check::{compare, CheckReport};
pub use error::SheetError;
pub use render::{render_sheet, Format};
pub use sheet::{parse_doc, Sheet, SheetDoc};
pub use tree_sheet::TreeSheet;
pub use units::{AngleUnit, LengthUnit};
