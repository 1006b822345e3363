//! WebAssembly bindings of urdf-dh for the web page (`web/`): a face like the CLI and the Python
//! package, with no domain logic of its own. Each function calls the `dh-workflows` entry points
//! that `urdf-dh extract`, `check` and `to-urdf` call, and returns the text those commands
//! print on standard output, byte for byte; [`Robot`] adds the forward kinematics of the URDF
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
use dh_workflows::extract::{default_samples, extract_bytes, prove_extracted, Extracted};
use dh_workflows::input::{load_chain_bytes, urdf_warnings};
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
/// `robot.urdf`), `base`, `tip`, `convention` (`standard`|`modified`), `format`
/// (`text`|`yaml`|`json`|`csv`|`markdown`, default `json`), `length_unit` (`m`|`mm`),
/// `angle_unit` (`rad`|`deg`), `linear_tol`, `angular_tol`, `samples`, `seed`: the CLI's
/// defaults for every one left out.
///
/// # Errors
/// The CLI's error for the same input: an invalid URDF, an unknown base or tip, a chain
/// without moving joints, bad options.
#[wasm_bindgen]
pub fn extract(urdf: &str, options: &str) -> Result<String, JsError> {
    let o = ExtractOptionsDoc::parse(options).map_err(js_error)?;
    run_extract(urdf.as_bytes(), &o).map_err(js_error)
}

/// The extraction `options` describe, as `urdf-dh extract` makes it before its proof.
fn extracted(urdf: &[u8], o: &ExtractOptionsDoc) -> anyhow::Result<Extracted> {
    extract_bytes(
        urdf,
        &o.name,
        o.base.as_deref(),
        o.tip.as_deref(),
        &o.options()?,
    )
}

fn run_extract(urdf: &[u8], o: &ExtractOptionsDoc) -> anyhow::Result<String> {
    let mut ex = extracted(urdf, o)?;
    let samples = o
        .samples
        .unwrap_or_else(|| default_samples(ex.extraction.table.rows.len()));
    let (text, _passed) = prove_extracted(&mut ex, o.format()?, samples, o.seed)?;
    Ok(text)
}

/// The warnings `urdf-dh extract` prints on standard error for the same input and options
/// (without the `urdf-dh: warning: ` prefix), as a JSON array of strings.
///
/// # Errors
/// As [`extract`].
#[wasm_bindgen]
pub fn extract_warnings(urdf: &str, options: &str) -> Result<String, JsError> {
    let o = ExtractOptionsDoc::parse(options).map_err(js_error)?;
    let ex = extracted(urdf.as_bytes(), &o).map_err(js_error)?;
    let all: Vec<String> = ex
        .urdf_warnings
        .iter()
        .cloned()
        .chain(ex.extraction.warnings.iter().map(|w| w.to_string()))
        .collect();
    serde_json::to_string(&all).map_err(|e| JsError::new(&e.to_string()))
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
    run_check(urdf.as_bytes(), sheet, &o)
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
    run_check(urdf.as_bytes(), sheet, &o)
        .and_then(|(_, w)| Ok(serde_json::to_string(&w)?))
        .map_err(js_error)
}

fn run_check(urdf: &[u8], sheet: &str, o: &CheckOptions) -> anyhow::Result<(String, Vec<String>)> {
    let (model, chain) = load_chain_bytes(urdf, &o.name, o.base.as_deref(), o.tip.as_deref())?;
    let mut warnings = urdf_warnings(&o.name, &model, &chain);
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

/// The link tree of a URDF, for choosing a chain: JSON `{robot, root, links: [{name, parent,
/// joint}], default: {base, tip} | null, default_error: string | null}` (`parent` and `joint`
/// are `null` for the root; `default` is the chain `extract` takes without `base` and `tip`).
///
/// # Errors
/// An invalid URDF (the CLI's message).
#[wasm_bindgen]
pub fn tree(urdf: &str, name: &str) -> Result<String, JsError> {
    scene::tree(urdf.as_bytes(), name).map_err(js_error)
}
