//! Each measured point's residual before and after a calibration of a serial model from
//! points ([`Residuals`], [`residuals`]): the distance between the point the model predicts and the one
//! measured (device frame, metres), with the `nominal` step's model (device frame and targets
//! fitted on the nominal table) and with the final one (the calibrated table, the last step's
//! effects at their estimates). What the residual chart (`calibrate --plot`) and the HTML
//! report (`calibrate --report`) draw.

use std::collections::HashMap;
use std::sync::Arc;

use anyhow::Result;
use dh_calib::calibrate::Report;
use dh_calib::data::Measurements;
use dh_calib::effects::label_of;
use dh_calib::model::{Effect, Model, ModelOptions};
use dh_core::pose::from_xyz_rpy;
use dh_core::DhTable;
use nalgebra::{Isometry3, Vector3};

use super::Inputs;
use crate::calibrated_writer::row_values;

/// Every sample's residual before and after, and its pose.
#[derive(Clone, Debug, PartialEq)]
pub struct Residuals {
    /// Distance with the `nominal` step's model, per sample in file order (metres).
    pub before: Vec<f64>,
    /// Distance with the final model, per sample (metres).
    pub after: Vec<f64>,
    /// Each sample's pose index (samples sharing `config`, or else joint values, are one pose,
    /// numbered in order of first appearance).
    pub poses: Vec<usize>,
    /// Number of poses.
    pub pose_count: usize,
}

/// Pose index of every sample: samples sharing `config` (or else joint values) are one pose,
/// numbered in order of first appearance; and the number of poses.
pub fn pose_indices(data: &Measurements) -> (Vec<usize>, usize) {
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

/// Distances between the points `table` (with `effects` at their values, the device frame and
/// the targets) predicts and the measured ones, per sample (metres).
///
/// # Errors
/// A model that cannot be built from `table`, joint values the table cannot take.
pub fn distances(
    table: &DhTable,
    effects: &[(Arc<dyn Effect>, Vec<f64>)],
    device: &Isometry3<f64>,
    targets: &[Vector3<f64>],
    data: &Measurements,
) -> Result<Vec<f64>> {
    let model = Model::new(table, &data.targets, &ModelOptions::default())?;
    let q = row_values(table, data)?;
    model_distances(model, effects, (device, targets), data, &q)
}

/// Distances between the points `model` (with `effects` added at their values, the device
/// frame and the targets of `frames`) predicts and the measured ones, per sample (metres); `q`
/// the samples' joint values in the model's row order. Serial and tree models alike.
pub(super) fn model_distances(
    mut model: Model,
    effects: &[(Arc<dyn Effect>, Vec<f64>)],
    frames: (&Isometry3<f64>, &[Vector3<f64>]),
    data: &Measurements,
    q: &[Vec<f64>],
) -> Result<Vec<f64>> {
    let mut values = Vec::new();
    for (e, v) in effects {
        values.push((model.add_effect(e.clone())?, v.clone()));
    }
    model.set_device(frames.0);
    for (k, t) in frames.1.iter().enumerate() {
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
    // The effects of the sample order see each sample's place in the sequence, as the fit did.
    let contexts = dh_calib::effects_order::contexts_of(q.iter().map(Vec::as_slice), data);
    Ok(data
        .samples
        .iter()
        .zip(q)
        .zip(&contexts)
        .map(|((s, q), c)| (model.point_in(&x, q, c, s.target) - s.point).norm())
        .collect())
}

/// The estimate of the parameter `name` in `report` (0 where it is not reported).
pub(super) fn estimate(report: &Report, name: &str) -> f64 {
    report
        .parameters
        .iter()
        .find(|p| p.name == name)
        .map_or(0.0, |p| p.estimate)
}

/// The fitted position of each of `targets` on the tool (metres; zero where not reported).
pub(super) fn fitted_targets(report: &Report, targets: &[String]) -> Vec<Vector3<f64>> {
    targets
        .iter()
        .map(|n| {
            report
                .targets
                .iter()
                .find(|(t, _)| t == n)
                .map_or_else(Vector3::zeros, |(_, p)| *p)
        })
        .collect()
}

/// The nominal-step device frame and targets, from the report's `nominal` column.
pub fn nominal_frames(report: &Report, targets: &[String]) -> (Isometry3<f64>, Vec<Vector3<f64>>) {
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

/// The residuals of the calibration `report` of `inputs`, `effects` the last step's effects
/// (those of `report.selected_effects` are applied at their estimates).
///
/// # Errors
/// A model that cannot be built from the tables, joint values they cannot take.
pub fn residuals(
    inputs: &Inputs,
    report: &Report,
    effects: &[Arc<dyn Effect>],
) -> Result<Residuals> {
    {
        let data = &inputs.data;
        let (poses, pose_count) = pose_indices(data);
        let (device0, targets0) = nominal_frames(report, &data.targets);
        let before = distances(&inputs.table, &[], &device0, &targets0, data)?;
        let estimates: Vec<(Arc<dyn Effect>, Vec<f64>)> = effects
            .iter()
            .filter(|e| report.selected_effects.contains(&label_of(e.as_ref())))
            .map(|e| {
                let v = e
                    .parameter_names()
                    .iter()
                    .map(|n| estimate(report, n))
                    .collect();
                (e.clone(), v)
            })
            .collect();
        let targets1 = fitted_targets(report, &data.targets);
        let after = distances(
            &report.calibrated,
            &estimates,
            &report.device,
            &targets1,
            data,
        )?;
        Ok(Residuals {
            before,
            after,
            poses,
            pose_count,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::units::{AngleUnit, LengthUnit};
    use dh_calib::calibrate::{calibrate, CalibrationOptions};
    use dh_calib::simulate::{simulate, Errors, SimulationOptions};
    use dh_core::{Convention, DhRow};

    fn arm() -> DhTable {
        let h = std::f64::consts::FRAC_PI_2;
        DhTable {
            convention: Convention::Standard,
            base: Isometry3::identity(),
            tool: Isometry3::identity(),
            rows: vec![
                DhRow::revolute("j1", 0.0, h, 0.4, 0.0),
                DhRow::revolute("j2", 0.5, 0.0, 0.0, 0.0),
                DhRow::revolute("j3", 0.1, h, 0.0, 0.0),
                DhRow::revolute("j4", 0.0, -h, 0.45, 0.0),
                DhRow::revolute("j5", 0.0, h, 0.0, 0.0),
                DhRow::revolute("j6", 0.0, 0.0, 0.1, 0.0),
            ],
        }
    }

    fn rms(d: &[f64]) -> f64 {
        (d.iter().map(|v| v * v).sum::<f64>() / d.len() as f64).sqrt()
    }

    /// The residuals are recomputed from the report (nominal-step frames, calibrated table,
    /// effect estimates): their RMS must be the report's, or a chart of them shows another fit.
    /// (Moved from the CLI's chart, which now draws these.)
    #[test]
    fn residuals_reproduce_the_reported_rms() {
        let table = arm();
        let (data, _) = simulate(
            &table,
            &SimulationOptions {
                poses: 60,
                sigma: 2e-5,
                target_count: 2,
                errors: Errors::Explicit(vec![("j2.a".into(), 4e-4), ("j3.theta".into(), 1e-3)]),
                ..SimulationOptions::default()
            },
        )
        .unwrap();
        let effects: Vec<Arc<dyn Effect>> =
            vec![dh_calib::effects::parse_label("gear_ratio:j2", &table).unwrap()];
        for with_effects in [false, true] {
            let options = CalibrationOptions {
                effects: if with_effects {
                    effects.clone()
                } else {
                    vec![]
                },
                ..CalibrationOptions::default()
            };
            let report = calibrate(&table, &data, &options).unwrap();
            let inputs = Inputs {
                table: table.clone(),
                model_name: "arm".into(),
                robot: None,
                units: (LengthUnit::M, AngleUnit::Rad),
                links: ("base_link".into(), "tool0".into()),
                coupled: vec![],
                data: data.clone(),
                cpa: false,
            };
            let r = residuals(&inputs, &report, &effects).unwrap();
            assert!(
                (rms(&r.before) - report.rms_before).abs() < 1e-9,
                "before {} {}",
                rms(&r.before),
                report.rms_before
            );
            assert!(
                // The calibrated table folds Hayati tilts into DH values to within
                // dh_calib::model::FOLD_TOLERANCE (1e-9 m, 1e-9 rad).
                (rms(&r.after) - report.rms_after).abs() < 1e-8,
                "after {} {}",
                rms(&r.after),
                report.rms_after
            );
            assert_eq!(r.pose_count, 60);
            assert_eq!(r.poses.len(), data.samples.len());
        }
    }
}
