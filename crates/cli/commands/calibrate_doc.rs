//! The documents `urdf-dh calibrate` writes: the JSON report's types (the library's, see
//! `dh_calib::pipeline`: [`CalibrationDoc`] and its parts; lengths in metres, angles in
//! radians, units named per parameter by [`unit_of`]) and the calibrated model (a URDF or a DH
//! sheet with its `calibration` section).
//!
//! Shared by `calibrate`, its contact path and its tree path.

use anyhow::Result;
use dh_core::DhTable;

pub use dh_calib::pipeline::{
    unit_of, CalibrationDoc, CandidateDoc, FixedDoc, NoiseDoc, ParameterDoc, PoseSi, StepDoc,
    TargetDoc, UnitsDoc, ValidationDoc,
};

use crate::commands::calibrate_inputs::Inputs;
use crate::commands::to_urdf::{check_urdf, urdf_of};
use crate::sheet::{EffectDoc, SheetDoc};

/// `table` as the calibrated model of `inputs` without effects (see [`calibrated_text`]), for
/// the contact and tree paths.
///
/// # Errors
/// Serialisation failures, and names or values a URDF cannot hold.
pub(crate) fn calibrated_bytes(
    path: &str,
    inputs: &Inputs,
    table: &DhTable,
    source: String,
    calibration: serde_yaml::Value,
) -> Result<String> {
    calibrated_text(path, inputs, table, source, calibration, Vec::new())
}

/// `table` as the calibrated model of `inputs` (its robot name, links, units and coupled
/// joints): a URDF for `.urdf`, else a sheet (JSON for `.json`, else YAML) with `source`, the
/// `calibration` section and the estimated `effects`.
///
/// # Errors
/// Serialisation failures, and names or values a URDF cannot hold.
pub(crate) fn calibrated_text(
    path: &str,
    inputs: &Inputs,
    table: &DhTable,
    source: String,
    calibration: serde_yaml::Value,
    effects: Vec<EffectDoc>,
) -> Result<String> {
    let lower = path.to_ascii_lowercase();
    let robot = inputs.robot.clone().unwrap_or_else(|| "robot".into());
    let bytes = if lower.ends_with(".urdf") {
        check_urdf(table, &robot, &inputs.links.0, &inputs.links.1)?;
        urdf_of(table, &robot, &inputs.links.0, &inputs.links.1)
    } else {
        let (lu, au) = inputs.units;
        let mut sheet = SheetDoc::from_table(table, lu, au);
        sheet.robot = inputs.robot.clone();
        if !inputs.coupled.is_empty() {
            sheet.coupled = Some(
                inputs
                    .coupled
                    .iter()
                    .map(|(j, t)| (j.clone(), t.iter().cloned().collect()))
                    .collect(),
            );
        }
        sheet.source = Some(source);
        sheet.calibration = Some(calibration);
        sheet.effects = (!effects.is_empty()).then_some(effects);
        if lower.ends_with(".json") {
            serde_json::to_string_pretty(&sheet)? + "\n"
        } else {
            serde_yaml::to_string(&sheet)?
        }
    };
    Ok(bytes)
}
