//! Reading input files (or standard input) with errors that name the file. The robot files'
//! readers (a URDF's chain, [`load_chain`], with its warnings, [`urdf_warnings`]) are the
//! `dh-sheet` library's ([`dh_sheet::input`]), re-exported here under their old paths.

use std::io::Read;

use anyhow::{Context, Result};

pub use dh_sheet::input::{
    chain_error, display_name, load_chain, load_chain_bytes, read_robot, read_robot_bytes,
    urdf_warnings, utf8_text,
};

/// Reads `path`, or standard input when it is `-`, as bytes.
///
/// # Errors
/// The file cannot be read; the message names it.
pub fn read_bytes(path: &str) -> Result<Vec<u8>> {
    if path == "-" {
        let mut buf = Vec::new();
        std::io::stdin()
            .read_to_end(&mut buf)
            .context("reading standard input")?;
        return Ok(buf);
    }
    std::fs::read(path).with_context(|| format!("{path}: cannot read the file"))
}

/// Reads `path` (or `-`) as UTF-8 text, without the byte-order mark some editors put first
/// (the YAML parser would take it for part of the first key; URDF and JSON readers skip it).
///
/// # Errors
/// The file cannot be read or is not UTF-8 (the message gives the line of the first bad byte).
pub fn read_text(path: &str) -> Result<String> {
    utf8_text(path, read_bytes(path)?)
}

/// Reads a data table: UTF-8 text, or a MATLAB level-5 `.mat` file as the CSV text of its
/// numeric variables ([`dh_calib::import::mat`]; what it leaves out is warned on `err`).
///
/// # Errors
/// As [`read_text`]; a `.mat` file that does not read (naming the file).
pub fn read_table(path: &str, err: &mut dyn std::io::Write) -> Result<String> {
    let bytes = read_bytes(path)?;
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
