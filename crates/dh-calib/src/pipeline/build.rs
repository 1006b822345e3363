//! Building the report document of a calibration ([`CalibrationDoc::new`]) from the library's
//! [`Report`]: the figures as they are (metres, radians), with the names of the model and data
//! files the caller read and the sample counts of the data.

use super::doc::{
    CalibrationDoc, CandidateDoc, ConventionDoc, FixedDoc, NoiseDoc, ParameterDoc, PoseSi,
    SessionDoc, StepDoc, TargetDoc, UnitsDoc, ValidationDoc,
};
use super::findings_doc::documents;
use crate::calibrate::{NoiseSource, Report, Validation};
use crate::data::{Measurements, Split};

/// The names a report gives its inputs: whatever the caller calls them (file names for the
/// command line; never absolute paths, so that reports stay comparable).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Names {
    /// The model (a file name, or `circle-point analysis of <data>`).
    pub model: String,
    /// The measurements.
    pub data: String,
    /// A separate validation set, when there is one.
    pub validate: Option<String>,
}

impl CalibrationDoc {
    /// The document of `report`, a calibration of a model in `convention` against `data` (the
    /// calibration and validation samples it was fitted and validated on), naming them as
    /// `names` says. `written` is `None`: a writer of the calibrated model fills it in.
    pub fn new(
        report: &Report,
        names: &Names,
        convention: dh_core::Convention,
        data: &Measurements,
    ) -> Self {
        let validation = match &report.validation {
            Validation::Split { samples } => ValidationDoc {
                method: "split".into(),
                samples: Some(*samples),
                folds: None,
                groups: None,
                training_subsample: None,
                fold_fits: None,
            },
            Validation::CrossValidation {
                folds,
                groups,
                training_subsample,
                one_step,
            } => ValidationDoc {
                method: "k-fold".into(),
                samples: None,
                folds: Some(*folds),
                groups: Some(*groups),
                training_subsample: *training_subsample,
                fold_fits: one_step.then(|| "one-step".into()),
            },
            Validation::None => ValidationDoc {
                method: "none".into(),
                samples: None,
                folds: None,
                groups: None,
                training_subsample: None,
                fold_fits: None,
            },
        };
        let val_count = data
            .samples
            .iter()
            .filter(|s| s.split == Split::Validation)
            .count();
        let (outliers, verdict, diagnosis) = documents(report);
        // Geometric parameters: their standard errors at the points against the noise floor.
        let judge = super::Identification::new(report, data.samples.len() - val_count);
        let timed = crate::effects_order::has_times(data);
        CalibrationDoc {
            model: names.model.clone(),
            data: names.data.clone(),
            validate: names.validate.clone(),
            convention: ConventionDoc::from(convention),
            units: UnitsDoc {
                length: "m".into(),
                angle: "rad".into(),
            },
            samples: data.samples.len() - val_count,
            validation_samples: val_count,
            validation,
            steps: report
                .steps
                .iter()
                .map(|s| StepDoc {
                    label: s.label.clone(),
                    free: s.free,
                    iterations: s.iterations,
                    rms_before: s.rms_before,
                    val_rms_before: s.val_rms_before,
                    rms: s.rms,
                    mean: s.mean,
                    max: s.max,
                    val_rms: s.val_rms,
                    val_mean: s.val_mean,
                    val_max: s.val_max,
                    angle_rms: s.angle_rms,
                    val_angle_rms: s.val_angle_rms,
                    fixed: s.fixed.iter().map(FixedDoc::from).collect(),
                })
                .collect(),
            rms_before: report.rms_before,
            rms_after: report.rms_after,
            val_rms_before: report.val_rms_before,
            val_rms_after: report.val_rms_after,
            noise_floor: report.noise_floor.as_ref().map(|n| n.rms),
            angle_noise_floor: report.noise_floor.as_ref().and_then(|n| n.angle_rms),
            noise: report.noise_floor.as_ref().map(|n| NoiseDoc {
                sigma: n.sigma,
                source: match n.source {
                    NoiseSource::Given => "given",
                    NoiseSource::Samples => "samples",
                    NoiseSource::Repeats { .. } => "repeats",
                }
                .into(),
            }),
            condition_number: report.condition_number,
            rank: report.rank,
            sigma_hat: report.sigma_hat,
            parameters: report
                .parameters
                .iter()
                .map(|p| ParameterDoc {
                    name: p.name.clone(),
                    unit: super::doc::unit_in(&p.name, timed).into(),
                    nominal: p.nominal,
                    estimate: p.estimate,
                    std_error: p.std_error,
                    free: p.free,
                    identified: p.free
                        && ParameterDoc::identifies(&p.name, p.estimate, p.std_error, &judge),
                    derived: super::doc::DerivedDoc::of(&p.name, p.estimate, p.std_error, timed),
                })
                .collect(),
            fixed: report.fixed.iter().map(FixedDoc::from).collect(),
            selected_effects: report.selected_effects.clone(),
            candidates: report.candidates.iter().map(CandidateDoc::from).collect(),
            device: PoseSi::of(&report.device),
            sessions: session_docs(report),
            targets: TargetDoc::list_with(&report.targets, &report.target_rotations),
            notes: report.notes.clone(),
            written: None,
            outliers,
            verdict,
            diagnosis,
        }
    }

    /// The free effect parameters of the last step, `(name, estimate)` (names `<kind>:<joints>`,
    /// `scale` or `drift`, see [`crate::effects`]; units by [`super::doc::unit_of`]).
    pub fn effect_estimates(&self) -> Vec<(String, f64)> {
        self.parameters
            .iter()
            .filter(|p| p.free && is_effect(&p.name))
            .map(|p| (p.name.clone(), p.estimate))
            .collect()
    }
}

/// Whether a parameter name is an effect's (`<kind>:<joints>`, `scale`, `drift` or
/// `thermal_growth.k|ln_tau`, see [`crate::effects`]) rather than a geometric one.
pub fn is_effect(name: &str) -> bool {
    name.contains(':')
        || name == "scale"
        || name == "drift"
        || crate::model::Effect::parameter_names(&crate::effects_thermal::ThermalGrowth)
            .iter()
            .any(|p| p == name)
}

/// The sessions of `report`, the `device` block's first; empty for a set of one session (the
/// report's `device` says it all).
fn session_docs(report: &Report) -> Vec<SessionDoc> {
    if report.sessions.len() <= 1 {
        return Vec::new();
    }
    report
        .sessions
        .iter()
        .map(|s| SessionDoc {
            name: s.name.clone(),
            device: PoseSi::of(&s.device),
            samples: s.samples,
            rms: s.rms,
            validation_samples: s.val_samples,
            val_rms: s.val_rms,
            fitted_on_validation: s.fitted_on_validation,
        })
        .collect()
}
