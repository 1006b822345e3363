//! Published datasets read as their authors left them (`urdf-dh import`): the `dh-calib`
//! library's importers, re-exported here so that the faces depend on this one layer, and the
//! reading of a data table ([`read_table`]: UTF-8 text, or a MATLAB level-5 `.mat` file as the
//! CSV text of its numeric variables).
//!
//! Units: what the importers return is the canonical measurement set, metres and radians,
//! points in the device frame ([`Measurements`](crate::fit::Measurements)), written by [`write_measurements`].

use anyhow::Result;

use crate::input::{display_name, read_data_bytes, utf8_text};

pub use dh_calib::csv::{joint_name_problem, write_measurements, DataError};
pub use dh_calib::import::columns::{
    parse as parse_columns, ColumnMap, ColumnRef, OrientationMap, RotationColumns,
};
pub use dh_calib::import::{import, Layout, Source};

/// The MUKCa layout's file names: the two ball-in-socket files of one placement directory and
/// the name a placement takes when its directory has none.
pub mod mukca {
    pub use dh_calib::import::mukca::{HOLE_0, HOLE_1, PLACEMENT};
}

/// Reads a data table at `path` (`-` for standard input): UTF-8 text as it is, or a MATLAB
/// level-5 `.mat` file as the CSV text of its numeric variables (`dh_calib::import::mat`), with
/// notes on what that leaves out, each starting with the file's name.
///
/// # Errors
/// A file that does not read or is not UTF-8; a `.mat` file that does not read (naming the
/// file).
pub fn read_table(path: &str) -> Result<(String, Vec<String>)> {
    let bytes = read_data_bytes(path)?;
    if !dh_calib::import::mat::is_mat(&bytes) {
        return Ok((utf8_text(path, bytes)?, Vec::new()));
    }
    let origin = display_name(path);
    let (text, notes) =
        dh_calib::import::mat::to_csv(&bytes).map_err(|e| anyhow::anyhow!("{origin}: {e}"))?;
    Ok((
        text,
        notes
            .into_iter()
            .map(|n| format!("{origin}: {n}"))
            .collect(),
    ))
}
