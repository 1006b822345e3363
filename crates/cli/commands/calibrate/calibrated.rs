//! Writing the calibrated model (`--out`): the calibrated URDF or sheet with its `calibration`
//! section (metres, radians, the last step's covariance), checked by predicting the measured
//! points back from what was written.

use super::*;

/// The calibrated model's text for `path` (a URDF for `.urdf`, a JSON sheet for `.json`, else
/// YAML) and the proof on it (see [`crate::commands::written`]).
///
/// # Errors
/// Serialisation failures, and an artefact that does not read back.
pub(super) fn model_text(
    path: &str,
    model_path: Option<&str>,
    inputs: &Inputs,
    report: &Report,
    doc: &CalibrationDoc,
) -> Result<(String, WrittenDoc)> {
    let calibration = CalibrationSection {
        data: doc.data.clone(),
        rms_before: doc.rms_before,
        rms_after: doc.rms_after,
        val_rms_before: doc.val_rms_before,
        val_rms_after: doc.val_rms_after,
        device: doc.device.clone(),
        sessions: crate::commands::calibrate_sessions::frames(&doc.sessions),
        targets: doc.targets.clone(),
        effects: doc
            .parameters
            .iter()
            // Effect parameters are named `<kind>:<joints>` or `scale`
            // (`dh_calib::effects`), whatever their unit.
            .filter(|p| p.free && (p.name.contains(':') || p.name == "scale" || p.name == "drift"))
            .map(|p| (p.name.clone(), p.estimate))
            .collect(),
        covariance: report
            .covariance
            .as_ref()
            .map(crate::calibrated::CovarianceDoc::of),
    };
    let source = format!(
        "calibrated by urdf-dh calibrate from {} against {}: RMS {:.6} m -> {:.6} m",
        doc.model, doc.data, doc.rms_before, doc.rms_after
    );
    let effects: Vec<EffectDoc> = doc
        .parameters
        .iter()
        .filter(|p| p.free && (p.name.contains(':') || p.name == "scale" || p.name == "drift"))
        .map(|p| EffectDoc {
            name: p.name.clone(),
            value: p.estimate,
            unit: p.unit.to_string(),
            std_error: p.std_error,
        })
        .collect();
    // A model whose own rows put a near-parallel pair's common normal far away (an URDF
    // extracted beyond its angular tolerance) is written in the Hayati form: the same
    // kinematics, bounded lengths. The length bound is the size of the model in that form.
    let hayati = ModelOptions::DEFAULT_HAYATI_THRESHOLD;
    let size = inputs.table.hayati_form(hayati).size();
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
        Some(m) => crate::commands::urdf_edit::minimal_edit(
            &crate::input::read_text(m)?,
            &inputs.table,
            // Row for row the nominal table's counterpart, so each joint frame moves by the
            // fit's small change, whatever the rows' form.
            &report.calibrated,
            &inputs.links.0,
            &inputs.links.1,
        )
        .with_context(|| {
            format!(
                "{}: writing the calibrated model as an edit of the model URDF",
                display_name(path)
            )
        })?,
        None => calibrated_text(
            path,
            inputs,
            &table,
            source,
            serde_yaml::to_value(&calibration)?,
            effects,
        )?,
    };
    let q = row_values(&report.calibrated, &inputs.data)?;
    let target: Vec<usize> = inputs.data.samples.iter().map(|s| s.target).collect();
    let targets: Vec<Vector3<f64>> = report.targets.iter().map(|(_, p)| *p).collect();
    let proof = written::prove(
        path,
        &text,
        &report.calibrated,
        size,
        (&inputs.links.0, &inputs.links.1),
        &written::Predictions {
            q: &q,
            target: &target,
            targets: &targets,
            device: report.device,
        },
    )?;
    let proof = predict_proof(path, &text, report, &doc.sessions, &q, &target, proof)?;
    Ok((text, proof))
}

/// The second half of the proof for a sheet: `predict` reads it back (effects, device frame,
/// targets, covariance) and its predictions of every measured point, effects included, are the
/// fitted model's within [`written::WRITTEN_TOLERANCE`]. A model with gravity effects (which
/// need the link masses `predict` does not take) keeps the geometric proof alone.
///
/// # Errors
/// A sheet `predict` cannot read: a defect of the writer, reported as such.
pub(super) fn predict_proof(
    path: &str,
    text: &str,
    report: &Report,
    sessions: &[crate::commands::calibrate_sessions::SessionDoc],
    q: &[Vec<f64>],
    target: &[usize],
    mut proof: WrittenDoc,
) -> Result<WrittenDoc> {
    if path.to_ascii_lowercase().ends_with(".urdf") {
        return Ok(proof);
    }
    let ctx = EffectContext::serial(&report.calibrated);
    let Ok(fitted) = dh_calib::predict::Calibrated::from_report(report, &ctx) else {
        return Ok(proof);
    };
    let name = display_name(path);
    let back = crate::calibrated::calibrated_sheet(text, &name).with_context(|| {
        format!(
            "{name}: the calibrated sheet does not read back for predict (a defect of the writer)"
        )
    })?;
    let frame = dh_calib::predict::Frame::Device;
    let mut worst = 0.0f64;
    for (q, &k) in q.iter().zip(target) {
        let d = (back.calibrated.point(q, k, frame) - fitted.point(q, k, frame)).norm();
        worst = worst.max(if d.is_finite() { d } else { f64::INFINITY });
    }
    // The other sessions' device frames read back as written.
    worst = worst.max(crate::commands::calibrate_sessions::read_back_deviation(
        sessions,
        &back.sessions,
    ));
    proof.max_deviation = proof.max_deviation.max(worst);
    proof.passed &= worst <= written::WRITTEN_TOLERANCE;
    Ok(proof)
}

/// The `calibration` section of a calibrated sheet (metres, radians): what the table was
/// fitted with, and the frames it needs to predict the measured points.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub(super) struct CalibrationSection {
    pub(super) data: String,
    pub(super) rms_before: f64,
    pub(super) rms_after: f64,
    pub(super) val_rms_before: Option<f64>,
    pub(super) val_rms_after: Option<f64>,
    pub(super) device: PoseSi,
    /// Every session's device frame but the first's (`device`), with several sessions.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub(super) sessions: Vec<crate::commands::calibrate_sessions::SessionFrameDoc>,
    pub(super) targets: Vec<TargetDoc>,
    pub(super) effects: Vec<(String, f64)>,
    /// Covariance of the last step's free parameters: what `predict` propagates.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) covariance: Option<crate::calibrated::CovarianceDoc>,
}
