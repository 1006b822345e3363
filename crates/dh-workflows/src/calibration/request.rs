//! What a calibration is asked to do ([`CalibrationRequest`]): the files (or arrays) it reads,
//! their units, the effects to look for and the fit's settings, as plain values. The command
//! line's `urdf-dh calibrate` options map one to one onto its fields.

use anyhow::Result;
use dh_calib::pipeline::EffectsChoice;
use dh_core::Convention;

use crate::measured::DataUnits;
use crate::output::check_destinations;

/// Default folds of the cross-validation ([`CalibrationRequest::folds`]).
pub const DEFAULT_FOLDS: usize = 5;
/// Default most effects an automatic search adds ([`CalibrationRequest::max_effects`]).
pub const DEFAULT_MAX_EFFECTS: usize = 12;

/// Everything a calibration needs. Lengths in the data's unit ([`CalibrationRequest::units`]),
/// gravity in m/s², payloads in kg and metres; reports are in metres and radians.
#[derive(Clone, Debug)]
pub struct CalibrationRequest {
    /// The model (URDF, DH sheet or tree sheet); `None` starts from the circle-point analysis
    /// of the data.
    pub model: Option<String>,
    /// Base link of a URDF chain.
    pub base: Option<String>,
    /// Tip link of a URDF chain.
    pub tip: Option<String>,
    /// DH convention for a URDF model or the circle-point start.
    pub convention: Convention,
    /// The measurement file (with [`CalibrationRequest::given`], only the name in messages).
    pub data: String,
    /// A separate validation file.
    pub validate: Option<String>,
    /// Units of the measurement files and arrays (and of `sigma`).
    pub units: DataUnits,
    /// Effects to estimate after the geometric step.
    pub effects: EffectsChoice,
    /// Keep only these targets (all when empty).
    pub targets: Vec<String>,
    /// Known per-axis noise, in the data's length unit.
    pub sigma: Option<f64>,
    /// Folds of cross-validation ([`DEFAULT_FOLDS`]).
    pub folds: usize,
    /// Where the calibrated model is to be written (`.urdf` for a URDF, `.json` for a JSON
    /// sheet, otherwise a YAML sheet; `-` for standard output): decides the format of
    /// [`Calibrated::model_file`](super::Calibrated::model_file) and is refused early when a
    /// tree cannot take it.
    pub out: Option<String>,
    /// Link masses for the gravity effects (YAML); `None` takes a URDF model's inertials (a
    /// tree sheet's own).
    pub inertials: Option<String>,
    /// Gravity in the base link frame (m/s²), three values.
    pub gravity: Option<Vec<f64>>,
    /// A payload at the tip: mass (kg) and centre in the tip frame (m), four values.
    pub payload: Option<Vec<f64>>,
    /// Most effects an automatic search adds ([`DEFAULT_MAX_EFFECTS`]).
    pub max_effects: usize,
    /// Significance level of the diagnosis's tests.
    pub alpha: f64,
    /// Fit the outliers with the rest (they are still named).
    pub keep_outliers: bool,
    /// Measurements handed over as arrays instead of the files `data` and `validate` (which
    /// then only name them in messages); `None` reads the files.
    pub given: Option<GivenData>,
}

impl CalibrationRequest {
    /// A request for `model` (None: the circle-point start) against the file `data`, with the
    /// defaults of the command line: standard convention, metres and radians, no effects,
    /// every target, [`DEFAULT_FOLDS`], [`DEFAULT_MAX_EFFECTS`], the diagnosis's default level.
    pub fn new(model: Option<String>, data: impl Into<String>) -> Self {
        Self {
            model,
            base: None,
            tip: None,
            convention: Convention::Standard,
            data: data.into(),
            validate: None,
            units: DataUnits::default(),
            effects: EffectsChoice::None,
            targets: Vec::new(),
            sigma: None,
            folds: DEFAULT_FOLDS,
            out: None,
            inertials: None,
            gravity: None,
            payload: None,
            max_effects: DEFAULT_MAX_EFFECTS,
            alpha: dh_calib::findings::DEFAULT_ALPHA,
            keep_outliers: false,
            given: None,
        }
    }

    /// Refuses an output that is one of the inputs (however spelled), or whose folder is
    /// missing: [`Self::out`] and `more` (option, path), against the model, data, validation
    /// and inertials files.
    ///
    /// # Errors
    /// The first such output, naming the option.
    pub fn check_destinations(&self, more: &[(&str, &str)]) -> Result<()> {
        let inputs: Vec<(&str, &str)> = [
            ("--model", self.model.as_deref()),
            ("--data", self.given.is_none().then_some(self.data.as_str())),
            ("--validate", self.validate.as_deref()),
            ("--inertials", self.inertials.as_deref()),
        ]
        .into_iter()
        .filter_map(|(o, p)| Some((o, p?)))
        .collect();
        let mut outputs: Vec<(&str, &str)> =
            self.out.iter().map(|o| ("--out", o.as_str())).collect();
        outputs.extend_from_slice(more);
        check_destinations(&inputs, &outputs)
    }
}

/// Measurements given as arrays (see [`dh_calib::csv::SampleArrays`]; units those of
/// [`CalibrationRequest::units`]), read as the files are: the model's measured joints are taken
/// from the arrays' joint columns by name.
#[derive(Clone, Debug)]
pub struct GivenData {
    /// The measurements.
    pub data: dh_calib::csv::SampleArrays,
    /// The validation measurements, if any.
    pub validate: Option<dh_calib::csv::SampleArrays>,
}
