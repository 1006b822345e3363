//! The residual chart (`--plot`): each sample's modelled-to-measured distance before and after
//! calibration (metres), per pose, as an SVG; for a tree, a before and an after panel per
//! branch ([`tree_chart`]).

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

/// Distances between the points the tree `tree` (with `effects` at their values, the device
/// frame and the targets, each on its branch `chains[k]`) predicts and the measured ones, per
/// sample; `q` the samples' values in the tree's row order.
fn tree_distances(
    tree: &DhTree,
    chains: &[usize],
    effects: &[(Arc<dyn Effect>, Vec<f64>)],
    device: &Isometry3<f64>,
    targets: &[Vector3<f64>],
    data: &Measurements,
    q: &[Vec<f64>],
) -> Result<Vec<f64>> {
    let on: Vec<(String, usize)> = data
        .targets
        .iter()
        .cloned()
        .zip(chains.iter().copied())
        .collect();
    let mut model = Model::new_tree(tree, &on, &ModelOptions::default())?;
    let mut values = Vec::new();
    for (e, v) in effects {
        values.push((model.add_effect(e.clone())?, v.clone()));
    }
    model.set_device(device);
    for (k, t) in targets.iter().enumerate() {
        model.set_target(k, *t);
    }
    let mut x = vec![0.0; model.parameter_count()];
    for (range, v) in values {
        for (i, val) in range.zip(v) {
            if let Some(slot) = x.get_mut(i) {
                *slot = val;
            }
        }
    }
    let contexts = dh_calib::effects_order::contexts_of(q.iter().map(Vec::as_slice), data);
    Ok(data
        .samples
        .iter()
        .zip(q)
        .zip(&contexts)
        .map(|((s, q), c)| (model.point_in(&x, q, c, s.target) - s.point).norm())
        .collect())
}

/// The residual chart of a tree calibration: per branch, the residuals of the samples of its
/// targets before (the nominal tree, device frame and targets fitted) and after (the final
/// step, effects included), two panels a branch, the poses numbered over the whole data.
pub(super) fn tree_chart(
    data_name: &str,
    t: &calibration::Tree,
    unit: LengthUnit,
) -> Result<ResidualChart> {
    let (inputs, c) = (&t.inputs, &t.calibration);
    let (data, report) = (&inputs.data, &c.report);
    let nominal = &inputs.sheet.tree;
    let branch_of = |name: &str| {
        c.target_branches
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, b)| *b)
    };
    let chains: Vec<usize> = data
        .targets
        .iter()
        .map(|n| branch_of(n).unwrap_or(0))
        .collect();
    let q = row_values(&inputs.model.table, data)?;
    let (poses, count) = pose_indices(data);
    let (device0, targets0) = nominal_frames(report, &data.targets);
    let before = tree_distances(nominal, &chains, &[], &device0, &targets0, data, &q)?;
    // The selected effects, parsed as the fit parsed them: on the nominal tree, with its masses.
    let ctx = dh_calib::effects::EffectContext {
        tree: nominal.clone(),
        gravity: match &inputs.inertials {
            Some(i) => Some(Arc::new(dh_calib::gravity::GravityModel::new(
                nominal,
                i,
                inputs.gravity,
            )?)),
            None => None,
        },
    };
    let estimate = |n: &String| {
        report
            .parameters
            .iter()
            .find(|p| &p.name == n)
            .map_or(0.0, |p| p.estimate)
    };
    let effects = report
        .selected_effects
        .iter()
        .map(|label| {
            let e = dh_calib::effects::parse_label_in(label, &ctx)?;
            let v = e.parameter_names().iter().map(estimate).collect();
            Ok((e, v))
        })
        .collect::<Result<Vec<_>, dh_calib::CalibError>>()?;
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
    let after = tree_distances(
        &c.calibrated,
        &chains,
        &effects,
        &report.device,
        &targets1,
        data,
        &q,
    )?;
    let last = report
        .steps
        .last()
        .map_or("geometric", |s| s.label.as_str());
    let mut panels = Vec::new();
    for (b, branch) in nominal.branches().iter().enumerate() {
        let panel = |label: String, d: &[f64]| {
            let residuals: Vec<Residual> = d
                .iter()
                .zip(&poses)
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
            &before,
        ));
        panels.push(panel(format!("branch {name}, after: {last}"), &after));
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
