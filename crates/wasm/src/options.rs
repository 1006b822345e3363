//! The options of each binding, read from JSON text with the CLI's defaults; keys in snake case
//! as the CLI's flags (`length_unit`), camel case accepted too (`lengthUnit`), unknown keys
//! refused so that a misspelt option is not silently ignored.

use std::collections::BTreeMap;
use std::sync::Arc;

use anyhow::{bail, Result};
use dh_workflows::check::{CHECK_ANGULAR, CHECK_LINEAR};
use dh_workflows::extract::ExtractOptions;
use dh_workflows::geometry::Tolerance;
use dh_workflows::input::{MemoryFiles, RobotFiles};
use dh_workflows::sheet::ConventionDoc;
use dh_workflows::xacro::XacroOptions;
use dh_workflows::{AngleUnit, Format, LengthUnit};
use serde::de::DeserializeOwned;
use serde::Deserialize;

/// Parses `text` (empty: every default) as options of type `T`.
fn parse<T: DeserializeOwned>(text: &str, what: &str) -> Result<T> {
    let text = if text.trim().is_empty() { "{}" } else { text };
    serde_json::from_str(text).map_err(|e| anyhow::anyhow!("{what} options: {e}"))
}

/// The robot file `text` at `path` (default `/NAME`) among `files`, with the xacro options.
fn robot_files(
    text: &str,
    name: &str,
    path: Option<&str>,
    files: &BTreeMap<String, String>,
    args: &[String],
    packages: &[String],
) -> Result<RobotFiles> {
    let top = path.map_or_else(|| format!("/{name}"), str::to_string);
    let mut all: MemoryFiles = files
        .iter()
        .map(|(p, t)| (urdf_xacro_path(p), t.clone().into_bytes()))
        .collect();
    all.insert(urdf_xacro_path(&top), text.as_bytes().to_vec());
    let mut xacro = XacroOptions::default();
    for a in args {
        xacro
            .add_arg(a)
            .map_err(|e| anyhow::anyhow!("xacro argument: {e}"))?;
    }
    for p in packages {
        xacro
            .add_package(p)
            .map_err(|e| anyhow::anyhow!("package folder: {e}"))?;
    }
    Ok(RobotFiles {
        top: top.into(),
        files: Arc::new(all),
        xacro,
    })
}

/// A path of the in-memory tree, `.` and `..` applied.
fn urdf_xacro_path(p: &str) -> std::path::PathBuf {
    dh_workflows::input::normalize_path(std::path::Path::new(p))
}

fn default_robot_name() -> String {
    "robot.urdf".into()
}

fn default_sheet_name() -> String {
    "sheet.yaml".into()
}

fn default_format() -> String {
    "json".into()
}

fn default_linear() -> f64 {
    Tolerance::DEFAULT_LINEAR
}

fn default_angular() -> f64 {
    Tolerance::DEFAULT_ANGULAR
}

fn default_check_linear() -> f64 {
    CHECK_LINEAR
}

fn default_check_angular() -> f64 {
    CHECK_ANGULAR
}

fn default_base_link() -> String {
    "base_link".into()
}

fn default_tip_link() -> String {
    "tool0".into()
}

fn default_samples() -> usize {
    1000
}

/// Options of `extract` (the CLI's flags of the same names and defaults).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExtractOptionsDoc {
    /// The robot file's name, as messages show it.
    #[serde(default = "default_robot_name")]
    pub name: String,
    /// Where the robot file sits among `files` (default: `/` and its name).
    #[serde(default)]
    pub path: Option<String>,
    /// The files beside the robot file, by path (text): includes, packages, YAML.
    #[serde(default)]
    pub files: BTreeMap<String, String>,
    /// A xacro file's arguments, `NAME:=VALUE` (the CLI's `--xacro-arg`).
    #[serde(default, alias = "xacroArgs")]
    pub xacro_args: Vec<String>,
    /// Package folders among `files`, `NAME=DIR` (the CLI's `--package`); others are found by
    /// their `package.xml`.
    #[serde(default)]
    pub packages: Vec<String>,
    /// Base link (default: the root link).
    #[serde(default)]
    pub base: Option<String>,
    /// Tip link (default: the end of the longest run of moving joints).
    #[serde(default)]
    pub tip: Option<String>,
    /// DH convention.
    #[serde(default)]
    pub convention: Option<ConventionDoc>,
    /// Output format: `text`, `yaml`, `json`, `csv` or `markdown`.
    #[serde(default = "default_format")]
    pub format: String,
    /// Length unit of the output.
    #[serde(default, alias = "lengthUnit")]
    pub length_unit: LengthUnit,
    /// Angle unit of the output.
    #[serde(default, alias = "angleUnit")]
    pub angle_unit: AngleUnit,
    /// Common normals shorter than this count as zero (metres).
    #[serde(default = "default_linear", alias = "linearTol")]
    pub linear_tol: f64,
    /// Axes this close to parallel count as parallel (radians).
    #[serde(default = "default_angular", alias = "angularTol")]
    pub angular_tol: f64,
    /// Joint-value samples of the self-check (default as the CLI's).
    #[serde(default)]
    pub samples: Option<usize>,
    /// Seed of the self-check's sampler.
    #[serde(default)]
    pub seed: u64,
}

impl ExtractOptionsDoc {
    /// Reads the options from JSON text.
    ///
    /// # Errors
    /// Text that is not a JSON object of these options.
    pub fn parse(text: &str) -> Result<Self> {
        parse(text, "extract")
    }

    /// The robot file `text` among the files these options give.
    ///
    /// # Errors
    /// A malformed xacro argument or package folder.
    pub fn robot(&self, text: &str) -> Result<RobotFiles> {
        robot_files(
            text,
            &self.name,
            self.path.as_deref(),
            &self.files,
            &self.xacro_args,
            &self.packages,
        )
    }

    /// The library's extraction options.
    ///
    /// # Errors
    /// Tolerances that are not positive and finite.
    pub fn options(&self) -> Result<ExtractOptions> {
        Ok(ExtractOptions {
            convention: self.convention.unwrap_or(ConventionDoc::Standard).into(),
            length_unit: self.length_unit,
            angle_unit: self.angle_unit,
            tolerance: Tolerance::new(self.linear_tol, self.angular_tol)
                .map_err(|e| anyhow::anyhow!("{e}"))?,
        })
    }

    /// The output format.
    ///
    /// # Errors
    /// A name that is none of the CLI's `--format` values.
    pub fn format(&self) -> Result<Format> {
        format_named(&self.format)
    }
}

/// The output format called `name`.
///
/// # Errors
/// A name that is none of the CLI's `--format` values.
pub fn format_named(name: &str) -> Result<Format> {
    Ok(match name {
        "text" => Format::Text,
        "yaml" => Format::Yaml,
        "json" => Format::Json,
        "csv" => Format::Csv,
        "markdown" => Format::Markdown,
        other => bail!("format: expected one of text, yaml, json, csv, markdown, found '{other}'"),
    })
}

/// Options of `check` (the CLI's flags of the same names and defaults).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CheckOptions {
    /// The robot file's name, as messages show it.
    #[serde(default = "default_robot_name")]
    pub name: String,
    /// As [`ExtractOptionsDoc::path`].
    #[serde(default)]
    pub path: Option<String>,
    /// As [`ExtractOptionsDoc::files`].
    #[serde(default)]
    pub files: BTreeMap<String, String>,
    /// As [`ExtractOptionsDoc::xacro_args`].
    #[serde(default, alias = "xacroArgs")]
    pub xacro_args: Vec<String>,
    /// As [`ExtractOptionsDoc::packages`].
    #[serde(default)]
    pub packages: Vec<String>,
    /// The sheet's file name, as messages show it.
    #[serde(default = "default_sheet_name", alias = "sheetName")]
    pub sheet_name: String,
    /// Base link.
    #[serde(default)]
    pub base: Option<String>,
    /// Tip link.
    #[serde(default)]
    pub tip: Option<String>,
    /// Length tolerance (metres).
    #[serde(default = "default_check_linear", alias = "linearTol")]
    pub linear_tol: f64,
    /// Angle tolerance (radians).
    #[serde(default = "default_check_angular", alias = "angularTol")]
    pub angular_tol: f64,
}

impl CheckOptions {
    /// Reads the options from JSON text.
    ///
    /// # Errors
    /// Text that is not a JSON object of these options.
    pub fn parse(text: &str) -> Result<Self> {
        parse(text, "check")
    }

    /// As [`ExtractOptionsDoc::robot`].
    ///
    /// # Errors
    /// As [`ExtractOptionsDoc::robot`].
    pub fn robot(&self, text: &str) -> Result<RobotFiles> {
        robot_files(
            text,
            &self.name,
            self.path.as_deref(),
            &self.files,
            &self.xacro_args,
            &self.packages,
        )
    }

    /// The comparison's tolerances.
    ///
    /// # Errors
    /// Tolerances that are not positive and finite.
    pub fn tolerance(&self) -> Result<Tolerance> {
        Tolerance::new(self.linear_tol, self.angular_tol).map_err(|e| anyhow::anyhow!("{e}"))
    }
}

/// Options of `to-urdf` (the CLI's flags of the same names and defaults).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ToUrdfOptions {
    /// The sheet's file name, as the proof comment names it.
    #[serde(default = "default_sheet_name", alias = "sheetName")]
    pub sheet_name: String,
    /// Robot name (default: the sheet's `robot`, else `robot`).
    #[serde(default)]
    pub name: Option<String>,
    /// Name of the base link.
    #[serde(default = "default_base_link", alias = "baseLink")]
    pub base_link: String,
    /// Name of the tip link.
    #[serde(default = "default_tip_link", alias = "tipLink")]
    pub tip_link: String,
    /// Joint-value samples of the check of the written URDF.
    #[serde(default = "default_samples")]
    pub samples: usize,
    /// Seed of the check's sampler.
    #[serde(default)]
    pub seed: u64,
}

impl ToUrdfOptions {
    /// Reads the options from JSON text.
    ///
    /// # Errors
    /// Text that is not a JSON object of these options.
    pub fn parse(text: &str) -> Result<Self> {
        parse(text, "to-urdf")
    }
}
