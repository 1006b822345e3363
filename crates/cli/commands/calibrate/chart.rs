//! The residual chart (`--plot`): each sample's modelled-to-measured distance before and after
//! calibration (metres; the library's [`residuals`]), per pose, as an SVG.

use super::*;

/// The residual chart: the `nominal` step's model and the final one.
pub(super) fn chart(
    data_name: &str,
    inputs: &Inputs,
    report: &Report,
    effects: &[Arc<dyn Effect>],
    unit: LengthUnit,
) -> Result<ResidualChart> {
    let data = &inputs.data;
    let r = residuals(inputs, report, effects)?;
    let panel = |label: String, d: &[f64], rms: f64, floor: Option<f64>| Panel {
        label,
        residuals: d
            .iter()
            .copied()
            .zip(&r.poses)
            .zip(&data.samples)
            .map(|((distance, &pose), s)| Residual {
                pose,
                distance,
                validation: s.split == Split::Validation,
            })
            .collect(),
        rms: Some(rms),
        floor,
    };
    let last = report
        .steps
        .last()
        .map_or("geometric", |s| s.label.as_str());
    Ok(ResidualChart {
        title: format!(
            "residuals per pose: {} against {} ({} samples of {} target(s))",
            inputs.model_name,
            data_name,
            data.samples.len(),
            data.targets.len()
        ),
        unit,
        poses: r.pose_count,
        panels: vec![
            panel(
                "before: nominal model (device frame and targets fitted)".into(),
                &r.before,
                report.rms_before,
                None,
            ),
            panel(
                format!("after: {last}"),
                &r.after,
                report.rms_after,
                report.noise_floor.as_ref().map(|n| n.rms),
            ),
        ],
    })
}
