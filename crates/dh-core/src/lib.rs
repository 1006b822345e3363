//! Pure line geometry for Denavit-Hartenberg (DH) extraction.
//!
//! Implements "Automatic Extraction of DH Parameters of Serial Manipulators using Line
//! Geometry" (Rajeevlochana, Saha, Kumar) with the corrections of its errata: Plücker lines
//! ([`Line`], eq. 1), the dual line product (eq. 3), classification of consecutive joint axes
//! ([`classify`]), and the recursive DH frame construction of §3.1 ([`extract()`]) generalised to
//! real robots (base and tool transforms, prismatic and mimic joints, both conventions).
//!
//! No file, no XML, no printing: the same core serves URDFs, vendor sheets and measured axes.
//!
//! Frames: every input is expressed in the robot's base link frame; lengths are metres, angles
//! radians.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

pub mod check;
pub mod equivalence;
mod error;
pub mod extract;
pub mod line;
pub mod literal;
pub mod math;
pub mod parallel;
pub mod pose;
pub mod precision;
pub mod registration;
pub mod relation;
pub mod table;
pub mod tolerance;
pub mod verify;

pub use check::{check_sheet, FkBound, SheetCheck};
pub use equivalence::{compare_tables, kind_code, Difference, Equivalence, Freedom, Parameter};
pub use error::CoreError;
pub use extract::{extract, Bound, Extraction, JointAxis, PairReport, Warning};
pub use line::{DualNumber, Line};
pub use literal::{fit_literal, LiteralFit, LITERAL_SAMPLES};
pub use precision::{compare_while_writing, compare_written, written_bound, Precision};
pub use registration::{axis_lines, register_axes, AxisLine};
pub use relation::{classify, PairGeometry, Relation};
pub use table::{Convention, DhRow, DhTable, JointKind, Limits, Mimic, PreparedFk};
pub use tolerance::Tolerance;
pub use verify::{compare, Deviation, JointSampler};
