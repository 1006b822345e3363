//! The calibrated model of a contact calibration (ball-in-socket data, see
//! `dh_calib::socket`): with a single target (the ball) the target is folded into the tool, so
//! that the written model predicts the ball centre itself.

use anyhow::Result;
use dh_calib::pipeline::{ContactDoc, SocketDoc, TargetDoc};
use dh_calib::socket::SocketReport;
use dh_core::DhTable;
use nalgebra::{Isometry3, Translation3};
use serde::Serialize;

use super::Inputs;
use crate::calibrated_writer::calibrated_bytes;

/// The `calibration` section of a sheet calibrated from contacts (metres): the consistency
/// before and after, the sockets in the base link frame and the targets in the written tip
/// frame (zero for a ball folded into the tool).
#[derive(Serialize)]
struct ContactCalibrationSection {
    data: String,
    kind: &'static str,
    consistency_before: f64,
    consistency_after: f64,
    test_consistency_before: Option<f64>,
    test_consistency_after: Option<f64>,
    targets: Vec<TargetDoc>,
    sockets: Vec<SocketDoc>,
    effects: Vec<(String, f64)>,
}

/// The calibrated table to write: with one target (the ball), the target folded into the tool
/// (`tool · Tr(t)`, `t` in the tip frame), so that the model's tip is the ball centre and the
/// written model predicts the contacts without a target offset. Returns the table and the
/// targets left in its tip frame.
fn written_table(r: &SocketReport) -> (DhTable, Vec<TargetDoc>) {
    let mut table = r.calibrated.clone();
    match r.targets.as_slice() {
        [(name, t)] => {
            table.tool *= Isometry3::from_parts(Translation3::from(*t), Default::default());
            (
                table,
                vec![TargetDoc {
                    name: name.clone(),
                    xyz: [0.0; 3],
                    rpy: None,
                }],
            )
        }
        targets => (table, TargetDoc::list(targets)),
    }
}

/// The model calibrated from contacts (see [`written_table`]) as the point path writes it to
/// `path` (a URDF, a JSON or a YAML sheet).
///
/// # Errors
/// A model the writer cannot express (see [`calibrated_bytes`]).
pub(super) fn contact_model_bytes(
    path: &str,
    inputs: &Inputs,
    r: &SocketReport,
    doc: &ContactDoc,
) -> Result<String> {
    let (table, targets) = written_table(r);
    let first = doc.steps.first();
    let last = doc.steps.last();
    let section = ContactCalibrationSection {
        data: doc.data.clone(),
        kind: "contacts",
        consistency_before: first.map_or(0.0, |s| s.train.mean_abs),
        consistency_after: last.map_or(0.0, |s| s.train.mean_abs),
        test_consistency_before: first.and_then(|s| s.test.as_ref().map(|t| t.mean_abs)),
        test_consistency_after: last.and_then(|s| s.test.as_ref().map(|t| t.mean_abs)),
        targets,
        sockets: doc
            .sockets
            .iter()
            .map(|k| SocketDoc {
                name: k.name.clone(),
                position: k.position,
                samples: k.samples,
            })
            .collect(),
        effects: doc
            .parameters
            .iter()
            .filter(|p| p.is_effect())
            .map(|p| (p.name.clone(), p.estimate))
            .collect(),
    };
    let source = format!(
        "calibrated by urdf-dh calibrate from {} against the contacts of {}: consistency {:.6} m \
         -> {:.6} m",
        doc.model, doc.data, section.consistency_before, section.consistency_after
    );
    calibrated_bytes(
        path,
        &inputs.nominal(),
        &table,
        source,
        serde_yaml::to_value(&section)?,
    )
}
