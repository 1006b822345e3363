//! Reading robot files: a URDF or `.xacro` file (or standard input, `-`) as bytes within
//! [`urdf_axes::MAX_URDF_BYTES`], as UTF-8 text, and a URDF's chain ([`load_chain`]) with its
//! warnings ([`urdf_warnings`]). Errors name the file as [`display_name`] shows it (no
//! directories), with a hint where the user can do something ([`crate::error::Hinted`]).

use std::path::Path;

use anyhow::{Context, Result};
/// A robot file's model and the chain read from it (`urdf_axes`'s), as [`load_chain`] returns
/// them.
pub use urdf_axes::{Chain, UrdfModel};

use crate::error::hinted;

mod memory;
mod source;

pub use memory::{MemoryFiles, RobotFiles};
pub use urdf_xacro::files::normalize as normalize_path;

pub use source::{
    read_capped, read_within, reading_once, too_large, TooLarge, MAX_DATA_BYTES, MAX_TEXT_BYTES,
};

/// Reads `path`, or standard input when it is `-`, as bytes, refusing more than
/// [`urdf_axes::MAX_URDF_BYTES`] without reading further (so `- < /dev/zero` stops there).
///
/// # Errors
/// The file cannot be read; the message names it. Too long: [`urdf_axes::UrdfError::TooLarge`]
/// in the context "`NAME`: invalid robot file" (the format, told by the root element, is not
/// known before the file is read).
pub fn read_robot_bytes(path: &str) -> Result<Vec<u8>> {
    read_capped(path, urdf_axes::MAX_URDF_BYTES)?.map_err(|t| {
        anyhow::Error::new(urdf_axes::UrdfError::TooLarge {
            size: t.size,
            limit: t.limit,
        })
        .context(format!("{}: invalid robot file", display_name(path)))
    })
}

/// Reads a text input (a sheet, a list, a model, an inertials file): `path`, or standard input
/// when it is `-`, as bytes, at most [`MAX_TEXT_BYTES`] of them, opened once
/// ([`reading_once`]).
///
/// # Errors
/// The file cannot be read, or is larger than the cap; the message names it.
pub fn read_bytes(path: &str) -> Result<Vec<u8>> {
    read_within(path, &display_name(path), MAX_TEXT_BYTES, "a text file")
}

/// Reads a data input (measurements, joint values): as [`read_bytes`] with the cap
/// [`MAX_DATA_BYTES`].
///
/// # Errors
/// The file cannot be read, or is larger than the cap; the message names it.
pub fn read_data_bytes(path: &str) -> Result<Vec<u8>> {
    read_within(path, &display_name(path), MAX_DATA_BYTES, "a data file")
}

/// [`read_data_bytes`] as UTF-8 text (see [`utf8_text`]).
///
/// # Errors
/// As [`read_data_bytes`] and [`utf8_text`].
pub fn read_data_text(path: &str) -> Result<String> {
    utf8_text(path, read_data_bytes(path)?)
}

/// Reads `path` (or `-`) as UTF-8 text, without the byte-order mark some editors put first
/// (the YAML parser would take it for part of the first key; URDF and JSON readers skip it).
///
/// # Errors
/// The file cannot be read or is not UTF-8 (the message gives the line of the first bad byte).
pub fn read_text(path: &str) -> Result<String> {
    utf8_text(path, read_bytes(path)?)
}

/// The bytes read from `path` as UTF-8 text.
///
/// # Errors
/// Not UTF-8 (the message gives the line of the first bad byte).
pub fn utf8_text(path: &str, mut bytes: Vec<u8>) -> Result<String> {
    if bytes.starts_with(b"\xEF\xBB\xBF") {
        bytes.drain(..3);
    }
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let line = e.as_bytes()[..at].iter().filter(|&&b| b == b'\n').count() + 1;
        hinted(
            format!(
                "{}: line {line}: expected UTF-8 text, found a byte that is not (offset {at})",
                crate::text::quote(path)
            ),
            "convert the file to UTF-8, e.g. iconv -f latin1 -t utf-8 FILE > FILE.utf8",
        )
    })
}

/// Reads a robot description: a URDF, or a `.xacro` file expanded natively
/// ([`crate::xacro::expand`], with the options set by [`crate::xacro::set_default_options`]).
///
/// # Errors
/// The file cannot be read; a `.xacro` file that does not expand (the message names the file
/// and line).
pub fn read_robot(path: &str) -> Result<Vec<u8>> {
    if !path.ends_with(".xacro") {
        return read_robot_bytes(path);
    }
    read_robot_with(path, &crate::xacro::default_options())
}

/// [`read_robot`] with the xacro options given (arguments, package folders).
///
/// # Errors
/// As [`read_robot`].
pub fn read_robot_with(path: &str, xacro: &crate::xacro::XacroOptions) -> Result<Vec<u8>> {
    if !path.ends_with(".xacro") {
        return read_robot_bytes(path);
    }
    let shown = crate::text::quote(path);
    if !Path::new(path).is_file() {
        anyhow::bail!("{shown}: cannot read the file: no such file");
    }
    crate::xacro::expand_with(path, xacro)
}

/// A display name for a path argument (`<stdin>` for `-`), without directories so that outputs
/// stay the same wherever the file lives, as messages and reports quote names
/// ([`crate::text::quote`]: control and bidi characters escaped, cut to
/// [`crate::text::MAX_QUOTED`] characters, so that a path of 10^8 characters makes a message of
/// a few hundred). Outputs are named by [`crate::text::output_name`] (`<stdout>` for `-`).
pub fn display_name(path: &str) -> String {
    if path == "-" {
        return "<stdin>".into();
    }
    let name = Path::new(path)
        .file_name()
        .map(|f| f.to_string_lossy())
        .unwrap_or(std::borrow::Cow::Borrowed(path));
    crate::text::quote(&name)
}

/// Loads the URDF and its chain.
///
/// # Errors
/// Unreadable file, invalid URDF, unknown or ambiguous base/tip.
pub fn load_chain(path: &str, base: Option<&str>, tip: Option<&str>) -> Result<(UrdfModel, Chain)> {
    let bytes = read_robot(path)?;
    load_chain_in(
        &bytes,
        &display_name(path),
        folder_of(path).as_deref(),
        base,
        tip,
    )
}

/// The folder of the robot file `path`, against which an MJCF `<include>` is resolved; `None`
/// for standard input (`-`).
pub fn folder_of(path: &str) -> Option<std::path::PathBuf> {
    if path == "-" {
        return None;
    }
    Some(match Path::new(path).parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    })
}

/// Reads the robot model of `bytes`, the file shown as `name` in folder `dir` (`None` when
/// it was not read from a file): MJCF when its root element is `<mujoco>` (only the prolog is
/// looked at), else URDF.
///
/// # Errors
/// An invalid model, named after the format read ("`NAME`: invalid MJCF", "`NAME`: invalid
/// SDFormat" or "`NAME`: invalid URDF", [`UrdfModel::format_name_of`]).
pub fn read_model(bytes: &[u8], name: &str, dir: Option<&Path>) -> Result<UrdfModel> {
    read_model_with(bytes, name, dir, None)
}

/// [`read_model`] with an MJCF's `<include>`s read from `files` (when given) instead of the disk.
///
/// # Errors
/// As [`read_model`].
pub fn read_model_with(
    bytes: &[u8],
    name: &str,
    dir: Option<&Path>,
    files: Option<&MemoryFiles>,
) -> Result<UrdfModel> {
    if urdf_axes::mjcf::is_mjcf(bytes) {
        return urdf_axes::mjcf::from_bytes_with(bytes, dir, files)
            .with_context(|| format!("{name}: invalid MJCF"));
    }
    let format = UrdfModel::format_name_of(bytes);
    UrdfModel::from_bytes(bytes).map_err(|e| match crate::sniff::not_a_robot(bytes) {
        // A sheet, a CSV or an image given as the robot: say what it is and what reads it.
        Some(s) => crate::error::hinted(
            format!("{name}: invalid {format}: {e}; the file is {}", s.what),
            s.hint,
        ),
        None => anyhow::Error::new(e).context(format!("{name}: invalid {format}")),
    })
}

/// Loads the chain of a URDF given as bytes; `name` names it in error messages (a file name, or
/// `<string>` for XML text a library caller passed).
///
/// # Errors
/// Invalid URDF, unknown or ambiguous base/tip.
pub fn load_chain_bytes(
    bytes: &[u8],
    name: &str,
    base: Option<&str>,
    tip: Option<&str>,
) -> Result<(UrdfModel, Chain)> {
    load_chain_in(bytes, name, None, base, tip)
}

/// [`load_chain_bytes`] of a model read from a file in folder `dir` (`None`: not from a file),
/// URDF or MJCF ([`read_model`]).
///
/// # Errors
/// Invalid model, unknown or ambiguous base/tip.
pub fn load_chain_in(
    bytes: &[u8],
    name: &str,
    dir: Option<&Path>,
    base: Option<&str>,
    tip: Option<&str>,
) -> Result<(UrdfModel, Chain)> {
    let model = read_model(bytes, name, dir)?;
    let chain = model
        .chain(base, tip)
        .map_err(|e| chain_error(name, &model, e))?;
    Ok((model, chain))
}

/// The error of choosing a chain of `model`, the file shown as `name`: a fault of a joint on the
/// chain is a fault of the file ("invalid URDF", or the model's own format: "invalid MJCF",
/// "invalid SDFormat"), not of the choice ("cannot choose the chain").
pub fn chain_error(name: &str, model: &UrdfModel, e: urdf_axes::UrdfError) -> anyhow::Error {
    let context = if e.is_choice() {
        format!("{name}: cannot choose the chain")
    } else {
        format!("{name}: invalid {}", model.format_name())
    };
    anyhow::Error::new(e).context(context)
}

/// The warnings of reading the URDF that concern `chain`, each prefixed with the file's name
/// (`name`), for `urdf-dh: warning:` lines.
pub fn urdf_warnings(name: &str, model: &UrdfModel, chain: &Chain) -> Vec<String> {
    model
        .warnings_for(chain)
        .iter()
        .map(|w| format!("{name}: {w}"))
        .collect()
}
