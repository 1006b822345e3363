//! The residual chart (`--plot`): each sample's modelled-to-measured distance before and after
//! calibration (metres), per pose, as an SVG.

use super::*;

/// Pose index of every sample: samples sharing `config` (or else joint values) are one pose,
/// numbered in order of first appearance; and the number of poses.
pub(super) fn pose_indices(data: &Measurements) -> (Vec<usize>, usize) {
    let mut ids: HashMap<String, usize> = HashMap::new();
    let v = data
        .samples
        .iter()
        .map(|s| {
            let key = match &s.config {
                Some(c) => format!("c{c}"),
                None => format!("q{:?}", s.q.iter().map(|v| v.to_bits()).collect::<Vec<_>>()),
            };
            let next = ids.len();
            *ids.entry(key).or_insert(next)
        })
        .collect();
    (v, ids.len())
}

/// Distances between the points `table` (with `effects` at `values`, the device frame and
/// the targets) predicts and the measured ones, per sample.
pub(super) fn distances(
    table: &DhTable,
    effects: &[(Arc<dyn Effect>, Vec<f64>)],
    device: &Isometry3<f64>,
    targets: &[Vector3<f64>],
    data: &Measurements,
) -> Result<Vec<f64>> {
    let mut model = Model::new(table, &data.targets, &ModelOptions::default())?;
    let mut x_effects = Vec::new();
    for (e, v) in effects {
        let range = model.add_effect(e.clone())?;
        x_effects.push((range, v.clone()));
    }
    model.set_device(device);
    for (k, t) in targets.iter().enumerate() {
        model.set_target(k, *t);
    }
    let mut x = vec![0.0; model.parameter_count()];
    for (range, v) in x_effects {
        for (i, val) in range.zip(v) {
            if let Some(slot) = x.get_mut(i) {
                *slot = val;
            }
        }
    }
    let q = row_values(table, data)?;
    // The effects of the sample order see each sample's place in the sequence, as the fit did.
    let contexts = dh_calib::effects_order::contexts_of(q.iter().map(Vec::as_slice), data);
    Ok(data
        .samples
        .iter()
        .zip(&q)
        .zip(&contexts)
        .map(|((s, q), c)| (model.point_in(&x, q, c, s.target) - s.point).norm())
        .collect())
}

/// The nominal-step device frame and targets, from the report's `nominal` column.
pub(super) fn nominal_frames(
    report: &Report,
    targets: &[String],
) -> (Isometry3<f64>, Vec<Vector3<f64>>) {
    let get = |name: &str| {
        report
            .parameters
            .iter()
            .find(|p| p.name == name)
            .map_or(0.0, |p| p.nominal)
    };
    let device = from_xyz_rpy(
        [get("device.x"), get("device.y"), get("device.z")],
        [get("device.rx"), get("device.ry"), get("device.rz")],
    );
    let t = targets
        .iter()
        .map(|n| {
            Vector3::new(
                get(&format!("target.{n}.x")),
                get(&format!("target.{n}.y")),
                get(&format!("target.{n}.z")),
            )
        })
        .collect();
    (device, t)
}

/// The residual chart: the `nominal` step's model and the final one.
pub(super) fn chart(
    data_name: &str,
    inputs: &Inputs,
    report: &Report,
    effects: &[Arc<dyn Effect>],
    unit: LengthUnit,
) -> Result<ResidualChart> {
    let data = &inputs.data;
    let (poses, count) = pose_indices(data);
    let (device0, targets0) = nominal_frames(report, &data.targets);
    let before = distances(&inputs.table, &[], &device0, &targets0, data)?;
    // The effects of the last step, with their estimates.
    let estimates: Vec<(Arc<dyn Effect>, Vec<f64>)> = effects
        .iter()
        .filter(|e| report.selected_effects.contains(&label_of(e.as_ref())))
        .map(|e| {
            let v = e
                .parameter_names()
                .iter()
                .map(|n| {
                    report
                        .parameters
                        .iter()
                        .find(|p| &p.name == n)
                        .map_or(0.0, |p| p.estimate)
                })
                .collect();
            (e.clone(), v)
        })
        .collect();
    let targets1: Vec<Vector3<f64>> = data
        .targets
        .iter()
        .map(|n| {
            report
                .targets
                .iter()
                .find(|(t, _)| t == n)
                .map_or_else(Vector3::zeros, |(_, p)| *p)
        })
        .collect();
    let after = distances(
        &report.calibrated,
        &estimates,
        &report.device,
        &targets1,
        data,
    )?;
    let panel = |label: String, d: Vec<f64>, rms: f64, floor: Option<f64>| Panel {
        label,
        residuals: d
            .into_iter()
            .zip(&poses)
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
        poses: count,
        panels: vec![
            panel(
                "before: nominal model (device frame and targets fitted)".into(),
                before,
                report.rms_before,
                None,
            ),
            panel(
                format!("after: {last}"),
                after,
                report.rms_after,
                report.noise_floor.as_ref().map(|n| n.rms),
            ),
        ],
    })
}
