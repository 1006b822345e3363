//! Reading input files (or standard input) with errors that name the file. The readers of text
//! and robot files (a URDF's chain, [`load_chain`], with its warnings, [`urdf_warnings`]) are
//! the `dh-workflows` library's ([`dh_workflows::input`]), re-exported here under their old paths.

use anyhow::Result;

pub use dh_workflows::input::{
    chain_error, display_name, load_chain, load_chain_bytes, read_bytes, read_data_bytes,
    read_data_text, read_robot, read_robot_bytes, read_text, urdf_warnings, utf8_text,
};

/// Reads a data table: UTF-8 text, or a MATLAB level-5 `.mat` file as the CSV text of its
/// numeric variables ([`dh_calib::import::mat`]; what it leaves out is warned on `err`).
///
/// # Errors
/// As [`read_text`]; a `.mat` file that does not read (naming the file).
pub fn read_table(path: &str, err: &mut dyn std::io::Write) -> Result<String> {
    let bytes = read_data_bytes(path)?;
    if !dh_calib::import::mat::is_mat(&bytes) {
        return utf8_text(path, bytes);
    }
    let origin = display_name(path);
    let (text, notes) =
        dh_calib::import::mat::to_csv(&bytes).map_err(|e| anyhow::anyhow!("{origin}: {e}"))?;
    for n in notes {
        writeln!(err, "urdf-dh: warning: {origin}: {n}")?;
    }
    Ok(text)
}
