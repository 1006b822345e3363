//! Native expansion of [xacro](https://github.com/ros/xacro) files, the XML macro language most
//! ROS robot descriptions are kept in, into plain URDF, without Python.
//!
//! It follows Python's xacro 2.x (the `--in-order` processing that is its only mode): properties
//! with lazy evaluation, scoping (`scope="parent"`/`"global"`, macro-local tables), `default=`,
//! block properties; macros with defaults (`a:=1`), forwarded defaults (`a:=^`, `a:=^|1`) and
//! block parameters (`*b`, `**b`); `xacro:include` with `$(find pkg)` ([`packages`]);
//! `xacro:arg` and `$(arg)`; `${}` expressions ([`expr`]: Python's expression grammar and
//! semantics, `math`, `xacro.load_yaml`); `$(eval)`, `$(env)`, `$(optenv)`, `$(dirname)`,
//! `$(cwd)`; `xacro:if`/`unless`, `xacro:insert_block`, `xacro:element`, `xacro:attribute`,
//! `xacro:call`. A construct it does not support (namespaced or globbed includes, lambdas,
//! comprehensions, `%` formatting) is refused as [`XacroError::Unsupported`], naming the
//! construct and where it is, so that a caller can fall back to Python's `xacro`.
//!
//! Guards: macro calls nest at most [`MAX_MACRO_DEPTH`] deep, includes [`MAX_INCLUDE_DEPTH`]
//! deep and never in a cycle, lazy properties refer to one another at most
//! [`MAX_EVAL_DEPTH`] deep and never in a cycle, and the expanded document is at most
//! [`MAX_OUTPUT_BYTES`]. Errors name the file, its line, the include chain and the macro
//! being expanded.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

mod expand;
pub mod expr;
pub mod files;
mod macros;
pub mod packages;
mod text;
pub mod tree;
pub mod value;
mod yaml;

use std::path::{Path, PathBuf};

/// Macro calls nested deeper than this are refused (a macro that calls itself without end).
pub const MAX_MACRO_DEPTH: usize = 100;
/// Includes nested deeper than this are refused.
pub const MAX_INCLUDE_DEPTH: usize = 64;
/// Lazy properties whose values refer to further properties deeper than this are refused.
pub const MAX_EVAL_DEPTH: usize = 200;
/// The expanded document, and any file read, is at most this many bytes (64 MiB, the limit
/// of the URDF reader).
pub const MAX_OUTPUT_BYTES: usize = 64 << 20;

/// What the caller gives the expansion besides the file.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// `name:=value` arguments, as `xacro FILE name:=value` takes them; they win over the
    /// `<xacro:arg default=...>` of the file.
    pub args: Vec<(String, String)>,
    /// Package folders for `$(find NAME)`, searched before `ROS_PACKAGE_PATH` and
    /// `AMENT_PREFIX_PATH`.
    pub packages: Vec<(String, PathBuf)>,
    /// A smaller limit than [`MAX_OUTPUT_BYTES`] on the expanded document, if any.
    pub max_bytes: Option<usize>,
    /// The files to read instead of the disk, if any: then every file (the top file,
    /// includes, YAML) is taken from this tree, and `$(find PKG)` looks in [`Options::packages`]
    /// and then at the `package.xml` files of the tree (or a folder named PKG), never at
    /// `ROS_PACKAGE_PATH` (a browser page has no disk).
    pub files: Option<std::sync::Arc<files::MemoryFiles>>,
}

impl Options {
    /// Parses a `NAME:=VALUE` argument into [`Options::args`].
    ///
    /// # Errors
    /// No `:=` or an empty name: the message says what was expected.
    pub fn add_arg(&mut self, spec: &str) -> Result<(), String> {
        match spec.split_once(":=") {
            Some((name, value)) if !name.trim().is_empty() => {
                self.args.push((name.trim().to_string(), value.to_string()));
                Ok(())
            }
            _ => Err(format!("expected NAME:=VALUE, found '{spec}'")),
        }
    }

    /// Parses a `NAME=DIR` package folder into [`Options::packages`].
    ///
    /// # Errors
    /// No `=` or an empty name or folder.
    pub fn add_package(&mut self, spec: &str) -> Result<(), String> {
        match spec.split_once('=') {
            Some((name, dir)) if !name.trim().is_empty() && !dir.is_empty() => {
                self.packages
                    .push((name.trim().to_string(), PathBuf::from(dir)));
                Ok(())
            }
            _ => Err(format!("expected NAME=DIR, found '{spec}'")),
        }
    }
}

/// The result of an expansion.
#[derive(Clone, Debug)]
pub struct Expansion {
    /// The expanded XML document.
    pub xml: String,
    /// Every file read (the top file, includes, YAML files), in the order first read.
    pub files: Vec<PathBuf>,
    /// Notes on questionable input that did not stop the expansion.
    pub warnings: Vec<String>,
}

/// Why an expansion failed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum XacroError {
    /// The input is wrong: the message names the file, line, include chain and macro.
    Invalid(String),
    /// The input uses a construct the native expansion does not support.
    Unsupported {
        /// The construct, e.g. `lambda expressions`.
        construct: String,
        /// The full message, with file and line.
        message: String,
    },
}

impl std::fmt::Display for XacroError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            XacroError::Invalid(m) => f.write_str(m),
            XacroError::Unsupported { message, .. } => f.write_str(message),
        }
    }
}

impl std::error::Error for XacroError {}

/// Expands the xacro file `path`.
///
/// The expansion runs on a thread of its own with a large stack, so that deeply nested
/// (but legal) documents do not overflow the caller's.
///
/// # Errors
/// [`XacroError::Invalid`] for unreadable or malformed files and every xacro error (undefined
/// property, argument or macro, missing package, division by zero, recursion, include cycle,
/// size); [`XacroError::Unsupported`] for constructs not supported natively.
pub fn expand_file(path: &Path, options: &Options) -> Result<Expansion, XacroError> {
    expand_on_a_large_stack(path, options)
}

/// WebAssembly in a browser has no threads: the expansion runs on the caller's stack there.
#[cfg(target_arch = "wasm32")]
fn expand_on_a_large_stack(path: &Path, options: &Options) -> Result<Expansion, XacroError> {
    expand::Expander::new(options).run(path)
}

#[cfg(not(target_arch = "wasm32"))]
fn expand_on_a_large_stack(path: &Path, options: &Options) -> Result<Expansion, XacroError> {
    const STACK_BYTES: usize = 256 << 20;
    std::thread::scope(|s| {
        std::thread::Builder::new()
            .name("xacro".into())
            .stack_size(STACK_BYTES)
            .spawn_scoped(s, || expand::Expander::new(options).run(path))
            .map_err(|e| XacroError::Invalid(format!("cannot start the expansion: {e}")))?
            .join()
            .unwrap_or_else(|_| {
                Err(XacroError::Invalid(
                    "the xacro expansion failed unexpectedly".into(),
                ))
            })
    })
}
