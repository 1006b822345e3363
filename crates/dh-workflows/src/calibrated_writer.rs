//! Writing a calibrated model (`calibrate --out`): the calibrated URDF (a minimal edit of the
//! user's own URDF, [`crate::urdf_edit`], or a fresh one, [`crate::urdf_writer`]) or DH sheet
//! with its `calibration` section (metres, radians, the last step's covariance), and the proof
//! on what is written ([`crate::written`]): read back, it predicts every measured point as the
//! fitted model does.
//!
//! Frames and units: the sheet's table is in the nominal model's units
//! ([`Nominal::units`]); the `calibration` section in metres and radians, its `device` the
//! robot's base link frame in the measuring device's frame (`T_device_base`), targets in the tip
//! frame.

use std::sync::Arc;

use anyhow::{Context, Result};
use dh_calib::calibrate::Report;
use dh_calib::data::Measurements;
use dh_calib::effects::EffectContext;
use dh_calib::gravity::GravityModel;
use dh_calib::model::{ModelOptions, SampleContext};
use dh_calib::pipeline::{
    CalibrationDoc, GravityRecord, PoseSi, SessionDoc, SessionFrameDoc, TargetDoc, WrittenDoc,
};
use dh_core::DhTable;
use nalgebra::{Isometry3, Vector3};
use serde::Serialize;

use crate::calibrated::CovarianceDoc;
use crate::sheet::{EffectDoc, SheetDoc};
use crate::units::{AngleUnit, LengthUnit};
use crate::urdf_writer::{check_urdf, urdf_of};
use crate::written;

/// The sheet's top-level `effects` of a calibration: every parameter of its fitted effects
/// ([`dh_calib::pipeline::ParameterDoc::is_effect`]) with its value (SI units), unit
/// and standard error; the serial and the tree sheet list them alike.
pub(crate) fn effect_docs(doc: &CalibrationDoc) -> Vec<EffectDoc> {
    doc.parameters
        .iter()
        .filter(|p| p.is_effect())
        .map(|p| EffectDoc {
            name: p.name.clone(),
            value: p.estimate,
            unit: p.unit.to_string(),
            std_error: p.std_error,
        })
        .collect()
}

/// The model a calibration started from, as its calibrated model is written: the nominal
/// table, the robot's name, the units of a written sheet, the URDF's base and tip links, and
/// the coupled joints of a sheet.
#[derive(Clone, Copy, Debug)]
pub struct Nominal<'a> {
    /// The nominal table (metres, radians).
    pub table: &'a DhTable,
    /// The robot's name, when the model gives one.
    pub robot: Option<&'a str>,
    /// Units of a written sheet.
    pub units: (LengthUnit, AngleUnit),
    /// Base and tip link names.
    pub links: (&'a str, &'a str),
    /// Coupled joints of a sheet: `(joint, [(driver, coefficient)])`.
    pub coupled: &'a [(String, Vec<(String, f64)>)],
}

/// `table` as the calibrated model of `nominal` without effects (see [`calibrated_text`]), for
/// the contact and tree paths.
///
/// # Errors
/// Serialisation failures, and names or values a URDF cannot hold.
pub fn calibrated_bytes(
    path: &str,
    nominal: &Nominal<'_>,
    table: &DhTable,
    source: String,
    calibration: serde_yaml::Value,
) -> Result<String> {
    calibrated_text(path, nominal, table, source, calibration, Vec::new())
}

/// `table` as the calibrated model of `nominal` (its robot name, links, units and coupled
/// joints): a URDF for `.urdf`, else a sheet (JSON for `.json`, else YAML) with `source`, the
/// `calibration` section and the estimated `effects`.
///
/// # Errors
/// Serialisation failures, and names or values a URDF cannot hold.
pub fn calibrated_text(
    path: &str,
    nominal: &Nominal<'_>,
    table: &DhTable,
    source: String,
    calibration: serde_yaml::Value,
    effects: Vec<EffectDoc>,
) -> Result<String> {
    let lower = path.to_ascii_lowercase();
    let robot = nominal.robot.unwrap_or("robot");
    let (base, tip) = nominal.links;
    let bytes = if lower.ends_with(".urdf") {
        check_urdf(table, robot, base, tip)?;
        urdf_of(table, robot, base, tip)
    } else {
        let (lu, au) = nominal.units;
        let mut sheet = SheetDoc::from_table(table, lu, au);
        sheet.robot = nominal.robot.map(str::to_string);
        if !nominal.coupled.is_empty() {
            sheet.coupled = Some(
                nominal
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
            crate::text::json_pretty(&sheet)? + "\n"
        } else {
            serde_yaml::to_string(&sheet)?
        }
    };
    Ok(bytes)
}

/// Joint values of every sample of `data` in `table`'s row order (mimic rows follow their
/// drivers).
///
/// # Errors
/// A row without a column in the data (nor a driver that has one).
pub fn row_values(table: &DhTable, data: &Measurements) -> Result<Vec<Vec<f64>>> {
    let column = |name: &str| data.joint_names.iter().position(|n| n == name);
    let mut sources = Vec::with_capacity(table.rows.len());
    for r in &table.rows {
        let s = match (column(&r.name), &r.mimic) {
            (Some(c), _) => (c, 1.0, 0.0),
            (None, Some(m)) => (
                column(&m.joint).with_context(|| format!("no column for joint '{}'", m.joint))?,
                m.multiplier,
                m.offset,
            ),
            (None, None) => anyhow::bail!("no column for joint '{}'", r.name),
        };
        sources.push(s);
    }
    Ok(data
        .samples
        .iter()
        .map(|s| {
            sources
                .iter()
                .map(|&(c, m, o)| m * s.q.get(c).copied().unwrap_or(0.0) + o)
                .collect()
        })
        .collect())
}

/// The calibrated model's text for `path` (a URDF for `.urdf`, a JSON sheet for `.json`, else
/// YAML), written from `nominal` fitted to `data` (`report`, `doc`; `model_path` the nominal
/// model's file, edited when both are URDFs), and the proof on it (see [`crate::written`]).
///
/// # Errors
/// Serialisation failures, and an artefact that does not read back.
pub fn model_text(
    path: &str,
    model_path: Option<&str>,
    nominal: &Nominal<'_>,
    data: &Measurements,
    report: &Report,
    doc: &CalibrationDoc,
    gravity: Option<&Arc<GravityModel>>,
) -> Result<(String, WrittenDoc)> {
    let calibration = CalibrationSection {
        summary: SectionSummary::of(doc),
        sessions: SessionDoc::frames(&doc.sessions),
        first_session: (doc.sessions.len() > 1)
            .then(|| doc.sessions.first().map(|s| s.name.clone()))
            .flatten(),
        targets: doc.targets.clone(),
        effects: doc.estimated_effects(),
        time_unit: doc.time_unit(data),
        covariance: report.covariance.as_ref().map(CovarianceDoc::of),
        // Only with an effect that needs it: the masses are no part of a geometric model.
        gravity_model: gravity.and_then(|g| GravityRecord::of(g)),
    };
    let source = format!(
        "calibrated by urdf-dh calibrate from {} against {}: RMS {:.6} m -> {:.6} m",
        doc.model, doc.data, doc.rms_before, doc.rms_after
    );
    let effects = effect_docs(doc);
    // A model whose own rows put a near-parallel pair's common normal far away (an URDF
    // extracted beyond its angular tolerance) is written in the Hayati form: the same
    // kinematics, bounded lengths. The length bound is the size of the model in that form.
    let hayati = ModelOptions::DEFAULT_HAYATI_THRESHOLD;
    let size = nominal.table.hayati_form(hayati).size();
    let longest = |t: &DhTable| {
        t.rows
            .iter()
            .flat_map(|r| [r.a.abs(), r.d.abs()])
            .fold(0.0, f64::max)
    };
    let table = if longest(&report.calibrated) > size + written::LENGTH_MARGIN {
        report.calibrated.hayati_form(hayati)
    } else {
        report.calibrated.clone()
    };
    let urdf = |p: &str| p.to_ascii_lowercase().ends_with(".urdf");
    // A URDF model written as a URDF: a minimal edit of the user's own file.
    let text = match model_path.filter(|m| urdf(m) && urdf(path) && *m != "-") {
        Some(m) => crate::urdf_edit::minimal_edit(
            &crate::input::read_text(m)?,
            nominal.table,
            // Row for row the nominal table's counterpart, so each joint frame moves by the
            // fit's small change, whatever the rows' form.
            &report.calibrated,
            nominal.links.0,
            nominal.links.1,
        )
        .with_context(|| {
            format!(
                "{}: writing the calibrated model as an edit of the model URDF",
                crate::text::output_name(path)
            )
        })?,
        None => calibrated_text(
            path,
            nominal,
            &table,
            source,
            serde_yaml::to_value(&calibration)?,
            effects,
        )?,
    };
    let q = row_values(&report.calibrated, data)?;
    let target: Vec<usize> = data.samples.iter().map(|s| s.target).collect();
    let targets: Vec<Vector3<f64>> = report.targets.iter().map(|(_, p)| *p).collect();
    let proof = written::prove(
        path,
        &text,
        &report.calibrated,
        size,
        nominal.links,
        &written::Predictions {
            q: &q,
            target: &target,
            targets: &targets,
            device: report.device,
        },
    )?;
    let proof = predict_proof(
        path,
        &text,
        (report, gravity),
        &doc.sessions,
        &q,
        &target,
        proof,
    )?;
    Ok((text, proof))
}

/// The time (seconds since the first sample) at which [`predict_proof`] also compares the
/// predictions, so that effects of time are read back: an hour, a warm-up's scale.
const PROOF_TIME: f64 = 3600.0;

/// The second half of the proof for a sheet: `predict` reads it back (effects, device frame,
/// targets, covariance) and its predictions of every measured point, effects included, are the
/// fitted model's within [`written::WRITTEN_TOLERANCE`]. `gravity` is the gravity model of
/// the report's gravity effects (compliance, backlash), which the sheet carries as
/// `calibration.gravity_model`.
///
/// # Errors
/// A sheet `predict` cannot read: a defect of the writer, reported as such.
pub fn predict_proof(
    path: &str,
    text: &str,
    (report, gravity): (&Report, Option<&Arc<GravityModel>>),
    sessions: &[SessionDoc],
    q: &[Vec<f64>],
    target: &[usize],
    mut proof: WrittenDoc,
) -> Result<WrittenDoc> {
    if path.to_ascii_lowercase().ends_with(".urdf") {
        return Ok(proof);
    }
    let mut ctx = EffectContext::serial(&report.calibrated);
    ctx.gravity = gravity.cloned();
    let Ok(mut fitted) = dh_calib::predict::Calibrated::from_report(report, &ctx) else {
        return Ok(proof);
    };
    let name = crate::text::output_name(path);
    let mut back = crate::calibrated::calibrated_sheet(text, &name).with_context(|| {
        format!(
            "{name}: the calibrated sheet does not read back for predict (a defect of the writer)"
        )
    })?;
    let frame = dh_calib::predict::Frame::Device;
    let mut worst = 0.0f64;
    // At the sequence's start (effects of time and order neutral) and, where they act, an
    // hour (or the whole session) in: effects of time must read back too.
    let late = SampleContext {
        time: Some(PROOF_TIME),
        order: 1.0,
        ..SampleContext::default()
    };
    for context in [SampleContext::default(), late] {
        back.calibrated.set_context(context.clone());
        fitted.set_context(context);
        for (q, &k) in q.iter().zip(target) {
            let d = (back.calibrated.point(q, k, frame) - fitted.point(q, k, frame)).norm();
            worst = worst.max(if d.is_finite() { d } else { f64::INFINITY });
        }
    }
    // The other sessions' device frames read back as written.
    worst = worst.max(read_back_deviation(sessions, &back.sessions));
    proof.max_deviation = proof.max_deviation.max(worst);
    proof.passed &= worst <= written::WRITTEN_TOLERANCE;
    Ok(proof)
}

/// The first keys of every calibrated model's `calibration` section (a serial sheet's and a
/// tree sheet's): the data, the RMS before and after (metres) and the device frame.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SectionSummary {
    /// The measurement file's name.
    pub data: String,
    /// Calibration RMS (m) of the first step ...
    pub rms_before: f64,
    /// ... and of the last.
    pub rms_after: f64,
    /// Validation RMS (m) of the first step, when there was validation ...
    pub val_rms_before: Option<f64>,
    /// ... and of the last.
    pub val_rms_after: Option<f64>,
    /// `T_device_base` (m, URDF rpy in rad).
    pub device: PoseSi,
}

impl SectionSummary {
    /// The summary of the calibration `doc`.
    pub fn of(doc: &CalibrationDoc) -> Self {
        Self {
            data: doc.data.clone(),
            rms_before: doc.rms_before,
            rms_after: doc.rms_after,
            val_rms_before: doc.val_rms_before,
            val_rms_after: doc.val_rms_after,
            device: doc.device.clone(),
        }
    }
}

/// The `calibration` section of a calibrated sheet (metres, radians): what the table was
/// fitted with, and the frames it needs to predict the measured points.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CalibrationSection {
    /// What it was fitted to and how well (the keys `data` to `device`).
    #[serde(flatten)]
    pub summary: SectionSummary,
    /// Every session's device frame but the first's (`device`), with several sessions.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub sessions: Vec<SessionFrameDoc>,
    /// The first session's name (its frame is `device`), with several sessions: what a
    /// prediction checks a joint file's `session` column against.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub first_session: Option<String>,
    /// The targets in the tip frame (m).
    pub targets: Vec<TargetDoc>,
    /// The estimated effects' values by label (SI units).
    pub effects: Vec<(String, f64)>,
    /// What the `t` of the effects of time was (`s` or `pose_order`), with one
    /// (`dh_calib::effects_thermal::TimeUnit`): what a prediction checks its rows against.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_unit: Option<dh_calib::effects_thermal::TimeUnit>,
    /// Covariance of the last step's free parameters: what `predict` propagates.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub covariance: Option<CovarianceDoc>,
    /// The link masses and nominal geometry of the gravity effects, with any selected (see
    /// `dh_calib::pipeline::GravityRecord`): what `predict` and `compensate` evaluate them with.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gravity_model: Option<GravityRecord>,
}

/// The largest difference (metres, or radians for the rotation) between the sessions written
/// (`docs` but the first) and those read back.
pub fn read_back_deviation(docs: &[SessionDoc], back: &[(String, Isometry3<f64>)]) -> f64 {
    let written = SessionDoc::frames(docs);
    if written.len() != back.len() {
        return f64::INFINITY;
    }
    written
        .iter()
        .zip(back)
        .map(|(w, (name, b))| {
            if &w.name != name {
                return f64::INFINITY;
            }
            let d = dh_core::pose::from_xyz_rpy(w.xyz, w.rpy).inverse() * b;
            d.translation.vector.norm().max(d.rotation.angle())
        })
        .fold(0.0, f64::max)
}
