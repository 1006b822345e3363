//! The residual chart (`--plot`): each sample's modelled-to-measured distance before and after
//! calibration (metres; the library's [`residuals`]), per pose, as an SVG; for a tree, a before
//! and an after panel per branch ([`tree_chart`], the library's [`calibration::tree_residuals`]).

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

/// The residual chart of a tree calibration: per branch, the residuals of the samples of its
/// targets before (the nominal tree, device frame and targets fitted) and after (the final
/// step, effects included), two panels a branch, the poses numbered over the whole data.
pub(super) fn tree_chart(
    data_name: &str,
    t: &calibration::Tree,
    unit: LengthUnit,
) -> Result<ResidualChart> {
    let (inputs, report) = (&t.inputs, &t.calibration.report);
    let data = &inputs.data;
    let nominal = &inputs.sheet.tree;
    let r = calibration::tree_residuals(t)?;
    let (chains, poses, before, after, count) =
        (&r.branches, &r.poses, &r.before, &r.after, r.pose_count);
    let last = report
        .steps
        .last()
        .map_or("geometric", |s| s.label.as_str());
    let mut panels = Vec::new();
    for (b, branch) in nominal.branches().iter().enumerate() {
        let panel = |label: String, d: &[f64]| {
            let residuals: Vec<Residual> = d
                .iter()
                .zip(poses)
                .zip(&data.samples)
                .filter(|(_, s)| chains.get(s.target) == Some(&b))
                .map(|((&distance, &pose), s)| Residual {
                    pose,
                    distance,
                    validation: s.split == Split::Validation,
                })
                .collect();
            let calibration: Vec<f64> = residuals
                .iter()
                .filter(|r| !r.validation)
                .map(|r| r.distance)
                .collect();
            let rms = (!calibration.is_empty()).then(|| {
                (calibration.iter().map(|d| d * d).sum::<f64>() / calibration.len() as f64).sqrt()
            });
            Panel {
                label,
                residuals,
                rms,
                floor: None,
            }
        };
        let name = crate::guard::escape(&branch.name);
        panels.push(panel(
            format!("branch {name}, before: nominal tree (device frame and targets fitted)"),
            before,
        ));
        panels.push(panel(format!("branch {name}, after: {last}"), after));
    }
    Ok(ResidualChart {
        title: format!(
            "residuals per pose and branch: {} against {} ({} samples of {} target(s))",
            inputs.origin,
            data_name,
            data.samples.len(),
            data.targets.len()
        ),
        unit,
        poses: count,
        panels,
    })
}
