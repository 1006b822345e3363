//! A calibrated model as `predict` and `compensate` read it: a sheet written by `calibrate
//! --out` (its table, `effects`, and the `calibration` section's device frame, targets and
//! covariance), `simulate`'s truth file (the `truth` section's device frame, targets and
//! effects: the simulated robot itself, without uncertainty), or any other model (a URDF chain,
//! a sheet) taken as exact, without device frame, targets or uncertainty. A tree sheet
//! (`branches`, written by `calibrate --out` for a tree) is read the same way: its rows are the
//! tree's in joint order and each target rides on the branch its `branch` names (see
//! [`crate::predict`] for choosing a branch). The sections and the
//! robot they make are `dh_calib::pipeline`'s (`CalibrationRecord`, `CalibratedRobot`); this
//! module finds and reads the file and words the errors.

use anyhow::{Context, Result};
use dh_calib::effects_thermal::TimeUnit;
use dh_calib::joints::JointMap;
pub use dh_calib::pipeline::CovarianceDoc;
use dh_calib::pipeline::{CalibratedError, CalibratedRobot, CalibrationRecord, TruthRecord};
use dh_calib::predict::{Calibrated, Covariance};
use dh_core::Convention;
use nalgebra::Isometry3;

use crate::error::hinted;
use crate::input::display_name;
use crate::model::{is_urdf, load_model, sheet_model, LoadedModel};
use crate::sheet::{parse_doc, SheetDoc};
use crate::tree_sheet::TreeSheet;

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
    /// The first session's name (whose frame `calibrated` holds), when the file gives it
    /// (`calibrate --out` writes it with several sessions; older sheets lack it).
    pub first_session: Option<String>,
    /// What the `t` of its effects of time was (the `calibration` or `truth` section's
    /// `time_unit`: seconds, or the pose order in `[0, 1]`); `None` without an effect of time,
    /// and for a sheet written before it was kept (see [`crate::predict::timed_contexts`]).
    pub time_unit: Option<TimeUnit>,
    /// The covariance as the file holds it (every session's device frame in it).
    covariance: Option<Covariance>,
    /// A tree's branch chosen for predictions and compensation (index into its branches, see
    /// [`CalibratedModel::choose_branch`]); `None`: every branch (targets each on their own),
    /// or a serial robot.
    pub branch: Option<usize>,
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
        if self.first_session.as_deref() == Some(name) {
            return Ok(self.calibrated.clone());
        }
        let Some((_, device)) = self.sessions.iter().find(|(n, _)| n == name) else {
            anyhow::bail!(
                "--session '{}': {}; the first session's frame is the model's device frame, used without --session",
                crate::text::escape(name),
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
            .map(|(n, _)| format!("'{}'", crate::text::escape(n)))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// Loads `path` (see the module docs).
///
/// # Errors
/// As [`load_model`]; a `calibration` section or `effects` that do not read (naming the file);
/// gravity effects without the `calibration.gravity_model` that evaluates them.
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
        if !is_urdf(path, &text) {
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
    let doc = parse_doc(text, origin)?;
    if doc.branches.is_some() {
        return calibrated_tree(doc, text, origin);
    }
    let loaded = sheet_model(text, origin)?.loaded;
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
            let (record, effects) = truth.into_calibration();
            effect_values.extend(effects);
            record
        }
        (None, None) => CalibrationRecord::default(),
    };
    assemble(loaded, record, effect_values, origin)
}

/// The calibrated model of a tree sheet (`branches`; see [`crate::tree_sheet`]): its tree,
/// `effects` and `calibration` section (each target on the branch it names), or the tree
/// taken as exact without one.
///
/// # Errors
/// As [`TreeSheet::parse`]; a `calibration` section or `effects` that do not read; a target
/// on no branch of the tree.
fn calibrated_tree(doc: SheetDoc, text: &str, origin: &str) -> Result<CalibratedModel> {
    let effect_values: Vec<(String, f64)> = doc
        .effects
        .clone()
        .unwrap_or_default()
        .into_iter()
        .map(|e| (e.name, e.value))
        .collect();
    let calibration = doc.calibration.clone();
    let sheet = TreeSheet::from_doc(doc, text, origin)?;
    let record: CalibrationRecord = match calibration {
        Some(c) => {
            serde_yaml::from_value(c).with_context(|| format!("{origin}: calibration section"))?
        }
        None => CalibrationRecord::default(),
    };
    let loaded = LoadedModel::of_tree(&sheet, origin);
    let robot = CalibratedRobot::new_tree(&sheet.tree, &effect_values, &record)
        .map_err(|e| robot_error(e, origin))?;
    Ok(model_of(loaded, robot))
}

fn assemble(
    loaded: LoadedModel,
    record: CalibrationRecord,
    effect_values: Vec<(String, f64)>,
    origin: &str,
) -> Result<CalibratedModel> {
    let robot = CalibratedRobot::new(&loaded.table, &effect_values, &record)
        .map_err(|e| robot_error(e, origin))?;
    Ok(model_of(loaded, robot))
}

/// The message of a calibrated robot that does not read from the file shown as `origin`.
fn robot_error(e: CalibratedError, origin: &str) -> anyhow::Error {
    match e {
        CalibratedError::MissingGravity { .. } => hinted(
            format!("{origin}: {e}"),
            "the file was written before calibrate kept them: calibrate again with the same --inertials and --out, which writes `calibration.gravity_model`",
        ),
        CalibratedError::Effects(_) => hinted(
            format!("{origin}: {e}"),
            "effects are read as calibrate writes them: `effects` and `calibration.effects` by parameter name",
        ),
        CalibratedError::RaggedCovariance { .. } | CalibratedError::Covariance(_) => {
            anyhow::anyhow!("{e}").context(format!("{origin}: calibration"))
        }
        e => anyhow::anyhow!("{origin}: {e}"),
    }
}

/// The model of `loaded` and the robot read from its file.
fn model_of(loaded: LoadedModel, robot: CalibratedRobot) -> CalibratedModel {
    let joints = JointMap::new(&loaded.table, &loaded.coupled);
    CalibratedModel {
        loaded,
        calibrated: robot.calibrated,
        has_device: robot.has_device,
        joints,
        sessions: robot.sessions,
        first_session: robot.first_session,
        time_unit: robot.time_unit,
        covariance: robot.covariance,
        branch: None,
    }
}
