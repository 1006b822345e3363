//! Reading `.xacro` robot files: expanded natively ([`urdf_xacro`]), without Python. Python's
//! `xacro` command is used only where the native expansion refuses a construct (a namespaced
//! or globbed include, a lambda, a comprehension), and a warning names the construct, file and
//! line.
//!
//! The expansion's options (`name:=value` arguments, `NAME=DIR` package folders) are given per
//! call ([`expand_with`]) or set once for the process ([`set_default_options`], what the CLI
//! does with `--xacro-arg` / `--package`), so that every command that reads a robot through
//! [`crate::input::read_robot`] sees them. Warnings go to the sink a face installs
//! ([`set_warning_sink`]); without one they are kept for [`take_warnings`].

use std::path::Path;
use std::process::Command;
use std::sync::{Mutex, PoisonError};

use anyhow::Result;
pub use urdf_xacro::Options as XacroOptions;
use urdf_xacro::XacroError;

use crate::error::hinted;

/// A function that shows a warning (the CLI writes `urdf-dh: warning: ...` to stderr).
pub type WarningSink = Box<dyn Fn(&str) + Send>;

static DEFAULT_OPTIONS: Mutex<Option<XacroOptions>> = Mutex::new(None);
static SINK: Mutex<Option<WarningSink>> = Mutex::new(None);
static PENDING: Mutex<Vec<String>> = Mutex::new(Vec::new());

/// Sets the options every later [`crate::input::read_robot`] of a `.xacro` file uses.
pub fn set_default_options(options: XacroOptions) {
    *DEFAULT_OPTIONS
        .lock()
        .unwrap_or_else(PoisonError::into_inner) = Some(options);
}

/// The options set by [`set_default_options`] (empty when none were set).
pub fn default_options() -> XacroOptions {
    DEFAULT_OPTIONS
        .lock()
        .unwrap_or_else(PoisonError::into_inner)
        .clone()
        .unwrap_or_default()
}

/// Installs the function that shows warnings of later expansions.
pub fn set_warning_sink(sink: WarningSink) {
    *SINK.lock().unwrap_or_else(PoisonError::into_inner) = Some(sink);
}

/// The warnings of expansions made without a sink, oldest first; the list is emptied.
pub fn take_warnings() -> Vec<String> {
    std::mem::take(&mut *PENDING.lock().unwrap_or_else(PoisonError::into_inner))
}

fn warn(message: String) {
    let sink = SINK.lock().unwrap_or_else(PoisonError::into_inner);
    match &*sink {
        Some(show) => show(&message),
        None => PENDING
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .push(message),
    }
}

/// Expands the `.xacro` file `path` with the default options ([`set_default_options`]).
///
/// # Errors
/// As [`expand_with`].
pub fn expand(path: &str) -> Result<Vec<u8>> {
    expand_with(path, &default_options())
}

/// Expands the `.xacro` file `path` into URDF bytes.
///
/// # Errors
/// Whatever the expansion finds wrong, naming the file (with the include chain) and line; a
/// construct the native expansion refuses when Python's `xacro` is not on PATH or fails too.
pub fn expand_with(path: &str, options: &XacroOptions) -> Result<Vec<u8>> {
    match urdf_xacro::expand_file(Path::new(path), options) {
        Ok(done) => {
            for w in done.warnings {
                warn(w);
            }
            Ok(done.xml.into_bytes())
        }
        Err(XacroError::Invalid(message)) => Err(match hint_for(&message) {
            Some(hint) => hinted(message, hint),
            None => anyhow::anyhow!(message),
        }),
        Err(XacroError::Unsupported { message, .. }) => {
            let bytes = external(path, options, &message)?;
            warn(format!(
                "{message}; expanded with Python's 'xacro' command instead"
            ));
            Ok(bytes)
        }
    }
}

/// Expands the `.xacro` file `path` of the in-memory tree `options.files` into URDF bytes,
/// returning the expansion's warnings instead of showing them (a page shows them itself).
///
/// # Errors
/// As [`expand_with`]; a construct the native expansion refuses is an error (Python's `xacro`
/// cannot read files held in memory).
pub fn expand_in_memory(path: &Path, options: &XacroOptions) -> Result<(Vec<u8>, Vec<String>)> {
    match urdf_xacro::expand_file(path, options) {
        Ok(done) => Ok((done.xml.into_bytes(), done.warnings)),
        Err(XacroError::Invalid(message)) => Err(match hint_for(&message) {
            Some(hint) => hinted(message, hint),
            None => anyhow::anyhow!(message),
        }),
        Err(XacroError::Unsupported { message, .. }) => Err(hinted(
            message,
            "expand the file with Python's xacro (xacro FILE > robot.urdf) and give the URDF",
        )),
    }
}

/// The remedy of an expansion error the user can fix from the command line.
fn hint_for(message: &str) -> Option<String> {
    let quoted = |after: &str| {
        let start = message.find(after)? + after.len();
        let end = start + message[start..].find('\'')?;
        Some(message[start..end].to_string())
    };
    if let Some(name) = quoted("undefined argument '") {
        return Some(format!(
            "give it as --xacro-arg {name}:=VALUE (xacro_args={{'{name}': ...}} in Python)"
        ));
    }
    if message.contains("not found (looked in the given package folders") {
        let name = quoted("package '").unwrap_or_else(|| "NAME".into());
        return Some(format!(
            "give the package's folder as --package {name}=DIR (packages={{'{name}': DIR}} in Python), or put a folder that holds it on ROS_PACKAGE_PATH"
        ));
    }
    None
}

/// Python's `xacro` on `path`, for a construct the native expansion refused (`why`).
fn external(path: &str, options: &XacroOptions, why: &str) -> Result<Vec<u8>> {
    let mut cmd = Command::new("xacro");
    cmd.arg(path);
    for (name, value) in &options.args {
        cmd.arg(format!("{name}:={value}"));
    }
    if !options.packages.is_empty() {
        // A package folder holds its package.xml: put each on ROS_PACKAGE_PATH first.
        let mut dirs: Vec<std::path::PathBuf> =
            options.packages.iter().map(|(_, d)| d.clone()).collect();
        if let Some(old) = std::env::var_os("ROS_PACKAGE_PATH") {
            dirs.extend(std::env::split_paths(&old));
        }
        if let Ok(joined) = std::env::join_paths(dirs) {
            cmd.env("ROS_PACKAGE_PATH", joined);
        }
    }
    let path = crate::text::quote(path);
    let out = cmd.output().map_err(|_| {
        hinted(
            format!("{why}, and the 'xacro' command is not on PATH"),
            format!("install it with 'pip install xacro', or expand the file yourself: xacro {path} > robot.urdf"),
        )
    })?;
    if !out.status.success() {
        let stderr = String::from_utf8_lossy(&out.stderr);
        return Err(hinted(
            format!("{why}; Python's xacro failed too: {}", stderr.trim()),
            format!("try it by hand: xacro {path}"),
        ));
    }
    Ok(out.stdout)
}
