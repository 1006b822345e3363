//! A calibrated model as `predict` and `compensate` read it: a sheet written by `calibrate
//! --out` (its table, `effects`, and the `calibration` section's device frame, targets and
//! covariance), `simulate`'s truth file (the `truth` section's device frame, targets and
//! effects: the simulated robot itself, without uncertainty), or any other model (a URDF chain,
//! a sheet) taken as exact, without device frame, targets or uncertainty.

use anyhow::{Context, Result};
use dh_calib::effects::EffectContext;
use dh_calib::joints::JointMap;
use dh_calib::predict::{effects_from_parameters, Calibrated, Covariance};
use dh_core::Convention;
use nalgebra::{DMatrix, Isometry3, Vector3};
use serde::{Deserialize, Serialize};

use crate::error::hinted;
use crate::input::display_name;
use crate::measured::{load_model, sheet_model, LoadedModel};
use crate::sheet::parse_doc;

/// The covariance of a calibration's free parameters as a calibrated sheet holds it (in the
/// `calibration` section; SI units, parameter names as in `dh_calib::model`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CovarianceDoc {
    /// The parameters, in the matrix's order.
    pub parameters: Vec<String>,
    /// Rows of the symmetric matrix.
    pub matrix: Vec<Vec<f64>>,
}

impl CovarianceDoc {
    /// The document of `c`.
    pub fn of(c: &Covariance) -> Self {
        CovarianceDoc {
            parameters: c.parameters.clone(),
            matrix: c
                .matrix
                .row_iter()
                .map(|r| r.iter().copied().collect())
                .collect(),
        }
    }

    /// The covariance it holds.
    ///
    /// # Errors
    /// Ragged rows, and as [`Covariance::new`].
    pub fn covariance(&self) -> Result<Covariance> {
        let n = self.parameters.len();
        if let Some(r) = self.matrix.iter().find(|r| r.len() != n) {
            anyhow::bail!(
                "covariance: expected {n} values per row for {n} parameters, found a row of {}",
                r.len()
            );
        }
        let m =
            DMatrix::from_row_iterator(self.matrix.len(), n, self.matrix.iter().flatten().copied());
        Covariance::new(self.parameters.clone(), m).map_err(|e| anyhow::anyhow!("{e}"))
    }
}

/// What `predict` reads of a sheet's `calibration` section (other keys are the report's).
#[derive(Clone, Debug, Default, Deserialize)]
struct CalibrationRecord {
    #[serde(default)]
    device: Option<PoseRecord>,
    #[serde(default)]
    targets: Vec<TargetRecord>,
    #[serde(default)]
    covariance: Option<CovarianceDoc>,
    /// Every measurement session's device frame but the first's (`device`).
    #[serde(default)]
    sessions: Vec<SessionRecord>,
}

/// A session's device frame (metres, roll-pitch-yaw radians).
#[derive(Clone, Debug, Deserialize)]
struct SessionRecord {
    name: String,
    xyz: [f64; 3],
    rpy: [f64; 3],
}

/// What `predict` reads of a `simulate` truth file's `truth` section: the simulated robot's
/// device frame, targets and effect values (parameter name, value; SI units).
#[derive(Clone, Debug, Default, Deserialize)]
struct TruthRecord {
    #[serde(default)]
    device: Option<PoseRecord>,
    #[serde(default)]
    targets: Vec<TargetRecord>,
    #[serde(default)]
    effects: Vec<(String, f64)>,
    /// With several sessions: every session's device frame, the first's (`device`) included.
    #[serde(default)]
    sessions: Vec<(String, PoseRecord)>,
}

#[derive(Clone, Debug, Deserialize)]
struct PoseRecord {
    xyz: [f64; 3],
    rpy: [f64; 3],
}

#[derive(Clone, Debug, Deserialize)]
struct TargetRecord {
    name: String,
    xyz: [f64; 3],
}

/// A calibrated model, ready to predict.
pub struct CalibratedModel {
    /// The model as loaded (table, units, coupled joints, warnings).
    pub loaded: LoadedModel,
    /// The robot with its effects, device frame, targets and covariance.
    pub calibrated: Calibrated,
    /// Whether the file gave a device frame (a `calibration` section, or a `truth` section of
    /// `simulate`).
    pub has_device: bool,
    /// The map from measured joint columns to the table's rows.
    pub joints: JointMap,
    /// The other measurement sessions' device frames `T_device_base` (the `calibration`
    /// section's `sessions`), by name; `calibrated` holds the first session's.
    pub sessions: Vec<(String, Isometry3<f64>)>,
    /// The covariance as the file holds it (every session's device frame in it).
    covariance: Option<Covariance>,
}

impl CalibratedModel {
    /// Predicts from session `name`'s device frame (one of [`CalibratedModel::sessions`]),
    /// with its uncertainty (see [`Covariance::in_session`]).
    ///
    /// # Errors
    /// A name that is none of the other sessions', naming those there are.
    pub fn in_session(&mut self, name: &str) -> Result<()> {
        self.calibrated = self.for_session(name)?;
        Ok(())
    }

    /// The calibrated robot seen from session `name`'s device frame (see
    /// [`CalibratedModel::in_session`]).
    ///
    /// # Errors
    /// As [`CalibratedModel::in_session`].
    pub fn for_session(&self, name: &str) -> Result<Calibrated> {
        let Some((_, device)) = self.sessions.iter().find(|(n, _)| n == name) else {
            anyhow::bail!(
                "--session '{}': {}; the first session's frame is the model's device frame, used without --session",
                crate::guard::escape(name),
                if self.sessions.is_empty() {
                    "the model holds one measurement session".to_string()
                } else {
                    format!("expected one of {}", self.session_list())
                }
            );
        };
        let mut calibrated = self.calibrated.clone().with_device(device);
        if let Some(c) = &self.covariance {
            calibrated = calibrated
                .with_covariance(&c.in_session(Some(name)))
                .map_err(|e| anyhow::anyhow!("{e}"))?;
        }
        Ok(calibrated)
    }

    /// The other sessions' names, quoted, for messages.
    pub fn session_list(&self) -> String {
        self.sessions
            .iter()
            .map(|(n, _)| format!("'{}'", crate::guard::escape(n)))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// Loads `path` (see the module docs).
///
/// # Errors
/// As [`load_model`]; a `calibration` section or `effects` that do not read (naming the file);
/// gravity effects, which need the link masses.
pub fn load_calibrated(
    path: &str,
    base: Option<&str>,
    tip: Option<&str>,
) -> Result<CalibratedModel> {
    let origin = display_name(path);
    if path == "-" {
        return Err(hinted(
            "<stdin>: the calibrated model must be given as a file",
            "save it to a file first: urdf-dh calibrate ... --out calibrated.yaml",
        ));
    }
    let lower = path.to_ascii_lowercase();
    if !lower.ends_with(".xacro") {
        let text = crate::input::read_text(path)?;
        if !crate::measured::is_urdf(path, &text) {
            if base.is_some() || tip.is_some() {
                return Err(hinted(
                    format!("{origin}: --base and --tip choose a chain of a URDF, but the model is a DH sheet"),
                    "drop --base/--tip, or give the URDF as --model",
                ));
            }
            return calibrated_sheet(&text, &origin);
        }
    }
    let loaded = load_model(path, base, tip, Convention::Standard)?;
    assemble(loaded, CalibrationRecord::default(), Vec::new(), &origin)
}

/// The calibrated model of a sheet's `text` (see the module docs).
///
/// # Errors
/// As [`crate::sheet::Sheet::parse`]; a `calibration` section or `effects` that do not read.
pub fn calibrated_sheet(text: &str, origin: &str) -> Result<CalibratedModel> {
    let loaded = sheet_model(text, origin)?.loaded;
    let doc = parse_doc(text, origin)?;
    let mut effect_values: Vec<(String, f64)> = doc
        .effects
        .unwrap_or_default()
        .into_iter()
        .map(|e| (e.name, e.value))
        .collect();
    let record = match (doc.calibration, doc.truth) {
        (Some(c), _) => {
            serde_yaml::from_value(c).with_context(|| format!("{origin}: calibration section"))?
        }
        // A simulated robot's truth file: the device frame, targets and effects it simulated.
        (None, Some(t)) => {
            let truth: TruthRecord =
                serde_yaml::from_value(t).with_context(|| format!("{origin}: truth section"))?;
            effect_values.extend(truth.effects);
            CalibrationRecord {
                device: truth.device,
                targets: truth.targets,
                covariance: None,
                sessions: truth
                    .sessions
                    .into_iter()
                    .skip(1)
                    .map(|(name, p)| SessionRecord {
                        name,
                        xyz: p.xyz,
                        rpy: p.rpy,
                    })
                    .collect(),
            }
        }
        (None, None) => CalibrationRecord::default(),
    };
    assemble(loaded, record, effect_values, origin)
}

fn assemble(
    loaded: LoadedModel,
    record: CalibrationRecord,
    effect_values: Vec<(String, f64)>,
    origin: &str,
) -> Result<CalibratedModel> {
    let ctx = EffectContext::serial(&loaded.table);
    let effects = effects_from_parameters(&effect_values, &ctx).map_err(|e| {
        hinted(
            format!("{origin}: effects: {e}"),
            "gravity effects (compliance, backlash) need the link masses and cannot be predicted yet; every other effect is read as calibrate writes it",
        )
    })?;
    let has_device = record.device.is_some();
    let sessions = record
        .sessions
        .iter()
        .map(|s| (s.name.clone(), dh_core::pose::from_xyz_rpy(s.xyz, s.rpy)))
        .collect();
    let device = record.device.map_or_else(Isometry3::identity, |p| {
        dh_core::pose::from_xyz_rpy(p.xyz, p.rpy)
    });
    let targets: Vec<(String, Vector3<f64>)> = record
        .targets
        .iter()
        .map(|t| (t.name.clone(), Vector3::from(t.xyz)))
        .collect();
    for (name, p) in &targets {
        if !p.iter().all(|v| v.is_finite()) || p.norm() > 100.0 {
            anyhow::bail!(
                "{origin}: calibration: target '{name}' at {p:?} m is not a position on a tool"
            );
        }
    }
    let mut calibrated = Calibrated::new(&loaded.table, &effects, &device, &targets)
        .map_err(|e| anyhow::anyhow!("{origin}: {e}"))?;
    let covariance = match &record.covariance {
        Some(c) => Some(
            c.covariance()
                .with_context(|| format!("{origin}: calibration"))?,
        ),
        None => None,
    };
    if let Some(c) = &covariance {
        // The first session's frame is the device frame: the other sessions' are left out.
        calibrated = calibrated
            .with_covariance(&c.in_session(None))
            .map_err(|e| anyhow::anyhow!("{origin}: calibration: {e}"))?;
    }
    let joints = JointMap::new(&loaded.table, &loaded.coupled);
    Ok(CalibratedModel {
        loaded,
        calibrated,
        has_device,
        joints,
        sessions,
        covariance,
    })
}
