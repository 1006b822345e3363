//! The serial paths of a calibration: measured points ([`Points`]) and contacts
//! ([`Contacts`]), the pipeline's options from a request ([`pipeline_options`]) and its errors
//! worded with the model's joints ([`serial_error`]).

use std::io::Write;

use anyhow::Result;
use dh_calib::gravity::Inertials;
use dh_calib::pipeline::{
    self, Calibration, ContactCalibration, Names, PipelineError, PipelineOptions,
    PointsCalibration, Progress, Silent, Start,
};
use dh_core::DhTable;
use nalgebra::Vector3;

use super::contacts::contact_model_bytes;
use super::inputs::{enough_samples, gravity_inputs, too_few, Inputs};
use super::CalibrationRequest;
use crate::calibrated_writer::model_text;
use crate::input::display_name;
use crate::measured::parse_effect;

/// The pipeline options of `args` with the link masses and gravity read for it, the report
/// naming the model `model` and the files as given (`sigma` converted to metres).
pub fn pipeline_options(
    args: &CalibrationRequest,
    model: &str,
    inertials: Option<Inertials>,
    gravity: Vector3<f64>,
) -> PipelineOptions {
    PipelineOptions {
        effects: args.effects.clone(),
        max_effects: args.max_effects,
        alpha: args.alpha,
        folds: args.folds,
        sigma: args.sigma.map(|s| s * args.units.length.metres()),
        keep_outliers: args.keep_outliers,
        inertials,
        gravity,
        names: Names {
            model: model.to_string(),
            data: display_name(&args.data),
            validate: args.validate.as_deref().map(display_name),
        },
    }
}

/// Refuses a `sigma` outside [`crate::ranges::sigma`]'s range (in the files' length unit), or
/// below [`crate::ranges::MIN_SIGMA`] metres once converted (1e-9 mm is below a nanometre).
///
/// # Errors
/// That `sigma`.
pub fn check_sigma(args: &CalibrationRequest) -> Result<()> {
    if let Some(s) = args.sigma {
        crate::ranges::sigma(&s.to_string()).map_err(|e| anyhow::anyhow!("--sigma: {e}"))?;
        let metres = s * args.units.length.metres();
        if metres < crate::ranges::MIN_SIGMA {
            anyhow::bail!(
                "--sigma: expected a standard deviation of at least {:e} m, found {s} ({metres:e} m)",
                crate::ranges::MIN_SIGMA
            );
        }
    }
    Ok(())
}

/// The message for a pipeline error of a serial model `table` (an effect label named after the
/// model's joints, the data file named).
pub fn serial_error(e: PipelineError, table: &DhTable, data_name: &str) -> anyhow::Error {
    match e {
        PipelineError::Effect { ref label, .. } => match parse_effect(label, table) {
            Err(message) => message,
            Ok(_) => anyhow::anyhow!("{e}"),
        },
        PipelineError::Inertials(_) | PipelineError::Search(_) => anyhow::anyhow!("{e}"),
        e => too_few(e, data_name),
    }
}

/// A calibration of a serial model from measured points, with the inputs it ran on.
#[derive(Clone, Debug)]
pub struct Points {
    /// The pipeline's result: the report as a document, the library's report, the effects.
    pub calibration: PointsCalibration,
    /// The model and data it ran on.
    pub inputs: Inputs,
}

/// A calibration of a serial model from contacts, with the inputs it ran on.
#[derive(Clone, Debug)]
pub struct Contacts {
    /// The pipeline's result: the report as a document and the library's report.
    pub calibration: ContactCalibration,
    /// The model and data it ran on.
    pub inputs: Inputs,
}

/// Calibrates the serial model of `inputs` from measured points.
pub(super) fn points(
    args: &CalibrationRequest,
    inputs: Inputs,
    progress: &mut dyn Progress,
) -> Result<Box<Points>> {
    let data_name = display_name(&args.data);
    enough_samples(&inputs.data, &data_name)?;
    let (inertials, gravity) = gravity_inputs(args, &inputs.table)?;
    check_sigma(args)?;
    let options = pipeline_options(args, &inputs.model_name, inertials, gravity);
    let start = if inputs.cpa {
        Start::Cpa(inputs.table.clone())
    } else {
        Start::Serial(inputs.table.clone())
    };
    match pipeline::calibrate(&start, &inputs.data, &options, progress) {
        Ok(Calibration::Points(c)) => Ok(Box::new(Points {
            calibration: *c,
            inputs,
        })),
        Ok(_) => anyhow::bail!("{data_name}: calibration took another path than a serial model's"),
        Err(e) => Err(serial_error(e, &inputs.table, &data_name)),
    }
}

/// Calibrates the serial model of `inputs` from contacts.
pub(super) fn contacts(args: &CalibrationRequest, inputs: Inputs) -> Result<Box<Contacts>> {
    let table = &inputs.table;
    check_sigma(args)?;
    let (inertials, gravity) = gravity_inputs(args, table)?;
    let name = display_name(&args.data);
    let options = pipeline_options(args, &inputs.model_name, inertials, gravity);
    let run = pipeline::calibrate(
        &Start::Serial(table.clone()),
        &inputs.data,
        &options,
        &mut Silent,
    );
    match run {
        Ok(Calibration::Contacts(c)) => Ok(Box::new(Contacts {
            calibration: *c,
            inputs,
        })),
        Ok(_) => anyhow::bail!("{name}: calibration took another path than contacts'"),
        Err(e) => Err(serial_error(e, table, &name)),
    }
}

impl Points {
    /// The calibrated model as written to `path`, proved as written (see
    /// [`super::Calibrated::model_file`]).
    pub(super) fn model_file(
        &mut self,
        path: &str,
        model_path: Option<&str>,
        err: &mut dyn Write,
    ) -> Result<Option<String>> {
        let c = &mut self.calibration;
        let (text, proof) = model_text(
            path,
            model_path,
            &self.inputs.nominal(),
            &self.inputs.data,
            &c.report,
            &c.doc,
            c.effects.iter().find_map(|e| e.gravity_model()),
        )?;
        let passed = proof.passed;
        c.doc.written = Some(proof);
        if !passed {
            return Ok(None);
        }
        if path.to_ascii_lowercase().ends_with(".urdf") && !c.report.selected_effects.is_empty() {
            writeln!(
                err,
                "urdf-dh: warning: {}: a URDF cannot express the estimated effects {}; it holds the geometric part (write a sheet to keep them)",
                crate::text::output_name(path),
                c.report
                    .selected_effects
                    .iter()
                    .map(|e| format!("'{e}'"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )?;
        }
        Ok(Some(text))
    }
}

impl Contacts {
    /// The calibrated model as written to `path`.
    pub(super) fn model_file(&self, path: &str) -> Result<String> {
        contact_model_bytes(
            path,
            &self.inputs,
            &self.calibration.report,
            &self.calibration.doc,
        )
    }
}
