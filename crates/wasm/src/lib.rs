//! WebAssembly bindings of urdf-dh for the web page (`web/`): a face like the CLI and the Python
//! package, with no domain logic of its own. Each function calls the `dh-workflows` entry points
//! that `urdf-dh extract`, `check` and `to-urdf` call, and returns the text those commands
//! print on standard output, byte for byte. [`Robot`] holds one extraction (made once per file
//! and settings) and gives its texts, its warnings and the forward kinematics of the robot file
//! and of its DH table for the page's 3-D view.
//!
//! Options come as JSON text (`{"base": "panda_link0", "convention": "modified"}`), so the
//! JavaScript side passes plain objects through `JSON.stringify`; errors are JavaScript
//! `Error`s carrying the CLI's message (`robot.urdf: cannot choose the chain: ...`).
//!
//! Built by `web/build.sh` for `wasm32-unknown-unknown`, where no thread can be spawned: the
//! library's parallel loops (`dh_core::parallel`) run on the calling thread there.

mod options;
mod scene;

use anyhow::Context as _;
use dh_workflows::extract::{extract_files, Extracted};
use dh_workflows::input::urdf_warnings;
use dh_workflows::Sheet;
use wasm_bindgen::prelude::*;

pub use options::{CheckOptions, ExtractOptionsDoc, ToUrdfOptions};
pub use scene::Robot;

/// An anyhow error as a JavaScript `Error`, its causes joined as the CLI prints them after
/// `urdf-dh: error: `, and the CLI's `hint:` line after a line feed where it gives one.
fn js_error(e: anyhow::Error) -> JsError {
    match dh_workflows::error::hint_for(&e) {
        Some(hint) => JsError::new(&format!("{e:#}\nhint: {hint}")),
        None => JsError::new(&format!("{e:#}")),
    }
}

/// `urdf-dh extract ROBOT --format F ...`: the text the CLI prints, proved as written (the
/// verification is part of the text).
///
/// `options` (JSON): `name` (the file name, as the CLI shows it in messages; default
/// `robot.urdf`; a `.xacro` name is expanded), `path` (where the file sits among `files`,
/// default `/NAME`), `files` (`{path: text}`: the files beside it, for xacro includes,
/// `$(find PKG)`, `load_yaml` and MJCF includes), `xacro_args` (`["NAME:=VALUE"]`),
/// `packages` (`["NAME=DIR"]`), `base`, `tip`, `convention` (`standard`|`modified`), `format`
/// (`text`|`yaml`|`json`|`csv`|`markdown`, default `json`), `length_unit` (`m`|`mm`),
/// `angle_unit` (`rad`|`deg`), `linear_tol`, `angular_tol`, `samples`, `seed`: the CLI's
/// defaults for every one left out.
///
/// # Errors
/// The CLI's error for the same input: an invalid robot file, an unknown base or tip, a chain
/// without moving joints, bad options.
#[wasm_bindgen]
pub fn extract(text: &str, options: &str) -> Result<String, JsError> {
    let o = ExtractOptionsDoc::parse(options).map_err(js_error)?;
    let format = o.format().map_err(js_error)?;
    Robot::extract(text, &o)?
        .output_as(format)
        .map_err(js_error)
}

/// The extraction `options` describe, as `urdf-dh extract` makes it before its proof.
fn extracted(text: &str, o: &ExtractOptionsDoc) -> anyhow::Result<Extracted> {
    extract_files(
        &o.robot(text)?,
        o.base.as_deref(),
        o.tip.as_deref(),
        &o.options()?,
    )
}

/// The warnings `urdf-dh extract` prints on standard error for the same input and options
/// (without the `urdf-dh: warning: ` prefix), as a JSON array of strings.
///
/// # Errors
/// As [`extract`].
#[wasm_bindgen]
pub fn extract_warnings(text: &str, options: &str) -> Result<String, JsError> {
    let o = ExtractOptionsDoc::parse(options).map_err(js_error)?;
    Robot::extract(text, &o)?.warnings()
}

/// `urdf-dh check ROBOT SHEET --format json`: the JSON report the CLI prints (its `warnings`
/// hold the comparison's remarks; [`check_warnings`] gives the other lines of standard error).
///
/// `options` (JSON): `name` (the URDF's file name), `sheet_name`, `base`, `tip`,
/// `linear_tol`, `angular_tol`.
///
/// # Errors
/// The CLI's error for the same input: an invalid URDF or sheet, an unknown base or tip.
#[wasm_bindgen]
pub fn check(urdf: &str, sheet: &str, options: &str) -> Result<String, JsError> {
    let o = CheckOptions::parse(options).map_err(js_error)?;
    run_check(urdf, sheet, &o)
        .map(|(json, _)| json)
        .map_err(js_error)
}

/// The lines `urdf-dh check` prints on standard error before its report (the URDF's warnings
/// for the chain and the sheet's effects that a check ignores), as a JSON array of strings.
///
/// # Errors
/// As [`check`].
#[wasm_bindgen]
pub fn check_warnings(urdf: &str, sheet: &str, options: &str) -> Result<String, JsError> {
    let o = CheckOptions::parse(options).map_err(js_error)?;
    run_check(urdf, sheet, &o)
        .and_then(|(_, w)| Ok(serde_json::to_string(&w)?))
        .map_err(js_error)
}

fn run_check(text: &str, sheet: &str, o: &CheckOptions) -> anyhow::Result<(String, Vec<String>)> {
    let robot = o.robot(text)?;
    let (model, chain, mut warnings) = robot.load_chain(o.base.as_deref(), o.tip.as_deref())?;
    warnings.extend(urdf_warnings(&robot.name(), &model, &chain));
    let sheet = Sheet::parse(sheet, &o.sheet_name)?;
    warnings.extend(sheet.effects_warning(&o.sheet_name, "check compares the DH kinematics alone"));
    let report = dh_workflows::compare(&chain, &sheet, o.tolerance()?)?;
    let json = serde_json::to_string_pretty(&report).context("writing the report")? + "\n";
    Ok((json, warnings))
}

/// `urdf-dh to-urdf SHEET`: the URDF the CLI writes for a DH sheet (YAML or JSON text), with
/// its proof as a comment after the root element.
///
/// `options` (JSON): `sheet_name` (the sheet's file name, named in the proof comment),
/// `name` (robot name), `base_link` (default `base_link`), `tip_link` (default `tool0`),
/// `samples` (default 1000), `seed` (default 0).
///
/// # Errors
/// The CLI's error for the same input: an invalid sheet, names a URDF cannot carry.
#[wasm_bindgen]
pub fn to_urdf(sheet: &str, options: &str) -> Result<String, JsError> {
    let o = ToUrdfOptions::parse(options).map_err(js_error)?;
    let run = || -> anyhow::Result<String> {
        let sheet = Sheet::parse(sheet, &o.sheet_name)?;
        let (text, _proof) = dh_workflows::urdf_writer::write_proved(
            &sheet,
            &o.sheet_name,
            o.name.as_deref(),
            &o.base_link,
            &o.tip_link,
            o.samples,
            o.seed,
        )?;
        Ok(text)
    };
    run().map_err(js_error)
}

/// The link tree of a robot file, for choosing a chain: JSON `{robot, format, root, links:
/// [{name, parent, joint}], default: {base, tip} | null, default_error: string | null}`
/// (`format` is `URDF`, `MJCF` or `SDFormat`; `parent` and `joint` are `null` for the root;
/// `default` is the chain `extract` takes without `base` and `tip`).
///
/// `options` (JSON): those of [`extract`] that say how to read the file (`name`, `path`,
/// `files`, `xacro_args`, `packages`); the others are ignored.
///
/// # Errors
/// An invalid robot file (the CLI's message).
#[wasm_bindgen]
pub fn tree(text: &str, options: &str) -> Result<String, JsError> {
    let o = ExtractOptionsDoc::parse(options).map_err(js_error)?;
    scene::tree(&o.robot(text).map_err(js_error)?).map_err(js_error)
}
