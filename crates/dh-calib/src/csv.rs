//! The canonical measurement CSV: reading ([`parse_measurements`]) and writing
//! ([`write_measurements`]).
//!
//! # Layout
//! One header line, then one measured point per line:
//!
//! ```text
//! # comment lines start with '#'; blank lines are skipped
//! joint_1,joint_2,x,y,z,target,config,sigma,set
//! 0.1,-0.25,1.2034,0.4411,0.9873,A,7,1e-5,train
//! ```
//!
//! - one column per joint, named exactly as the model's joints: radians for revolute joints,
//!   metres for prismatic ones (other units through [`CsvOptions`]);
//! - `x`, `y`, `z`: the measured position of a target on the tool, in the measuring device's
//!   own frame, metres;
//! - optional `target`: which reflector or marker was measured (a name; targets are numbered in
//!   order of first appearance; without the column every row measures one target called
//!   [`DEFAULT_TARGET`]);
//! - optional `config`: pose identifier, rows with the same id repeat one pose (an empty cell
//!   means none);
//! - optional `sigma` (isotropic) or `sx`, `sy`, `sz` (per axis): the point's standard deviation
//!   in the length unit (an empty cell means unknown);
//! - optional `set`: `train`/`calibration` or `test`/`validation` (an empty cell or no column
//!   means calibration);
//! - optional `socket`: a contact sample (see [`crate::socket`]): the target sat in the unknown
//!   fixed point of this name, and the row's `x`, `y`, `z` cells are empty (the columns may be
//!   absent when every row is a contact); with it, optional `partner`, `distance` and
//!   `distance_sigma`: another socket at a known centre-to-centre distance from this one and
//!   its standard deviation, in the length unit (both needed when `partner` is given);
//! - optional `session`: the measurement session (a non-empty name): the device was moved
//!   between sessions, each has its own device frame (see [`crate::sessions`]); without the
//!   column every row is in one session;
//! - optional `qw`, `qx`, `qy`, `qz` (all four, scalar first, as trackers export it) and
//!   `sigma_rot`: a 6-DoF device's measured orientation of the target frame in the device
//!   frame, a unit quaternion, and the standard deviation of each component of its rotation
//!   vector in radians (whatever the angle unit). A row with the four cells empty is a point;
//!   see [`QUATERNION_NORM_TOLERANCE`] for the norm.
//!
//! Other columns are ignored. Cells may be double-quoted (`""` inside quotes is one quote).
//! Column names and cells are trimmed of surrounding spaces.
//!
//! # Layout
//! Items live in submodules and are re-exported here: names, limits and errors (`error`), units
//! and reader settings (`units`), the lexer (`records`), the header's columns (`columns`), the
//! reader (`reader`) and the writer (`writer`).

use std::fmt;
use std::str::FromStr;

use nalgebra::Vector3;
use thiserror::Error;

use crate::data::{CompactString, Measurements, Sample, Socket, SocketDistance, Split};

// The submodules import what they use through `use super::*`: the imports above and each
// other's items, re-exported here.
mod error;
pub use error::*;
mod units;
pub use units::*;
mod records;
pub(crate) use records::*;
mod columns;
pub use columns::*;
mod reader;
pub use reader::*;
mod chunks;
use chunks::*;
mod orientation;
pub use orientation::*;
mod writer;
pub use writer::*;
mod arrays;
pub use arrays::*;
#[cfg(test)]
mod tests;
