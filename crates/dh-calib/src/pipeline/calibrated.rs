//! A calibrated model as a written sheet holds it, read back for predictions: the covariance
//! document ([`CovarianceDoc`]), the `calibration` section `calibrate` writes
//! ([`CalibrationRecord`]: device frame, targets, covariance, other sessions' frames), the
//! `truth` section of a simulated robot ([`TruthRecord`]), and the robot they make
//! ([`CalibratedRobot::new`]). Poses are `T_device_base` (metres, URDF roll-pitch-yaw radians),
//! targets in the tip frame (metres).

use dh_core::pose::from_xyz_rpy;
use dh_core::DhTable;
use nalgebra::{DMatrix, Isometry3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::{needs_gravity, GravityRecord};
use crate::covariance::Covariance;
use crate::effects::EffectContext;
use crate::effects_thermal::TimeUnit;
use crate::fit::CalibError;
use crate::predict::{effects_from_parameters, Calibrated};
use crate::tree::DhTree;

/// Farthest a target may be from the tip (metres) and still be a position on a tool.
pub const MAX_TARGET_DISTANCE: f64 = 100.0;

/// The covariance of a calibration's free parameters as a calibrated sheet holds it (in the
/// `calibration` section; SI units, parameter names as in [`crate::model`]).
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
    /// [`CalibratedError::RaggedCovariance`], and as [`Covariance::new`].
    pub fn covariance(&self) -> Result<Covariance, CalibratedError> {
        let n = self.parameters.len();
        if let Some(r) = self.matrix.iter().find(|r| r.len() != n) {
            return Err(CalibratedError::RaggedCovariance {
                expected: n,
                found: r.len(),
            });
        }
        let m =
            DMatrix::from_row_iterator(self.matrix.len(), n, self.matrix.iter().flatten().copied());
        Covariance::new(self.parameters.clone(), m).map_err(CalibratedError::Covariance)
    }
}

/// A pose as a sheet holds it (metres, roll-pitch-yaw radians).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PoseRecord {
    /// Translation (metres).
    pub xyz: [f64; 3],
    /// Roll, pitch, yaw (radians).
    pub rpy: [f64; 3],
}

impl PoseRecord {
    /// The pose.
    pub fn pose(&self) -> Isometry3<f64> {
        from_xyz_rpy(self.xyz, self.rpy)
    }
}

/// A target as a sheet holds it: its position in the tip frame (metres).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TargetRecord {
    /// Target name.
    pub name: String,
    /// Position in the tip frame (metres).
    pub xyz: [f64; 3],
    /// A 6-DoF target's rotation in the tip frame (URDF roll, pitch, yaw; radians); absent for
    /// a point target.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rpy: Option<[f64; 3]>,
    /// The branch it rides on, in a tree's calibration (its position is then in that
    /// branch's tip frame); absent for a serial robot.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub branch: Option<String>,
}

/// A session's device frame as a sheet holds it (metres, roll-pitch-yaw radians).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SessionRecord {
    /// The session's name.
    pub name: String,
    /// Translation (metres).
    pub xyz: [f64; 3],
    /// Roll, pitch, yaw (radians).
    pub rpy: [f64; 3],
}

/// What a prediction reads of a sheet's `calibration` section (other keys are the report's).
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
pub struct CalibrationRecord {
    /// `T_device_base` of the first session.
    #[serde(default)]
    pub device: Option<PoseRecord>,
    /// The fitted targets.
    #[serde(default)]
    pub targets: Vec<TargetRecord>,
    /// The covariance of the last step's free parameters.
    #[serde(default)]
    pub covariance: Option<CovarianceDoc>,
    /// Every measurement session's device frame but the first's (`device`).
    #[serde(default)]
    pub sessions: Vec<SessionRecord>,
    /// The first session's name, with several sessions (sheets written before it was kept
    /// lack it).
    #[serde(default)]
    pub first_session: Option<String>,
    /// The link masses and nominal geometry of the gravity effects (compliance, backlash),
    /// when the calibration selected any (sheets written before it was kept lack it).
    #[serde(default)]
    pub gravity_model: Option<GravityRecord>,
    /// What the `t` of its effects of time was (`s`: the data had a `time` column;
    /// `pose_order`: they had none), with an effect of time (`thermal_growth`). Sheets written
    /// before it was kept lack it: a prediction then takes its rows' `time` column as seconds
    /// and, without one, `--sequence`'s pose order, as the user gives them.
    #[serde(default)]
    pub time_unit: Option<TimeUnit>,
}

/// What a prediction reads of a `simulate` truth file's `truth` section: the simulated robot's
/// device frame, targets and effect values (parameter name, value; SI units).
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
pub struct TruthRecord {
    /// True `T_device_base` of the first session.
    #[serde(default)]
    pub device: Option<PoseRecord>,
    /// True targets.
    #[serde(default)]
    pub targets: Vec<TargetRecord>,
    /// True effect values.
    #[serde(default)]
    pub effects: Vec<(String, f64)>,
    /// With several sessions: every session's device frame, the first's (`device`) included.
    #[serde(default)]
    pub sessions: Vec<(String, PoseRecord)>,
    /// The gravity model of planted gravity effects.
    #[serde(default)]
    pub gravity_model: Option<GravityRecord>,
    /// What the `t` of the planted effects of time was (`simulate` writes times: `s`).
    #[serde(default)]
    pub time_unit: Option<TimeUnit>,
}

impl TruthRecord {
    /// The truth as a calibration section without covariance, and its effect values.
    pub fn into_calibration(self) -> (CalibrationRecord, Vec<(String, f64)>) {
        let record = CalibrationRecord {
            first_session: self.sessions.first().map(|(n, _)| n.clone()),
            device: self.device,
            targets: self.targets,
            covariance: None,
            gravity_model: self.gravity_model,
            time_unit: self.time_unit,
            sessions: self
                .sessions
                .into_iter()
                .skip(1)
                .map(|(name, p)| SessionRecord {
                    name,
                    xyz: p.xyz,
                    rpy: p.rpy,
                })
                .collect(),
        };
        (record, self.effects)
    }
}

/// What stops a calibrated model from being read back.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum CalibratedError {
    /// Effect values that make no effect of the table (gravity effects need link masses).
    #[error("effects: {0}")]
    Effects(CalibError),
    /// Gravity effects in a file without the gravity model they were fitted with.
    #[error("effects: {} need the gravity, link masses and nominal geometry the calibration was run with (`calibration.gravity_model`), which the file does not hold", .effects.iter().map(|e| format!("'{e}'")).collect::<Vec<_>>().join(", "))]
    MissingGravity {
        /// The gravity effects' parameters.
        effects: Vec<String>,
    },
    /// A gravity model that does not fit the table.
    #[error("{0}")]
    Gravity(CalibError),
    /// A target too far from the tip, or not finite.
    #[error("calibration: target '{name}' at {position:?} m is not a position on a tool")]
    Target {
        /// The target.
        name: String,
        /// Its position in the tip frame (metres).
        position: Vector3<f64>,
    },
    /// A covariance row of the wrong length.
    #[error("covariance: expected {expected} values per row for {expected} parameters, found a row of {found}")]
    RaggedCovariance {
        /// Values per row expected.
        expected: usize,
        /// Values found.
        found: usize,
    },
    /// A covariance that is not one (see [`Covariance::new`]).
    #[error("{0}")]
    Covariance(CalibError),
    /// A covariance that does not fit the robot (see [`Calibrated::with_covariance`]).
    #[error("calibration: {0}")]
    Uncertainty(CalibError),
    /// A robot that cannot be built from the table, effects, device and targets.
    #[error("{0}")]
    Robot(CalibError),
    /// A tree's target without a branch, or on a branch the tree does not have.
    #[error("calibration: target '{name}': expected the branch it rides on (one of {}), found {}", .branches.iter().map(|b| format!("'{b}'")).collect::<Vec<_>>().join(", "), .found.as_ref().map_or_else(|| "none".to_string(), |b| format!("'{b}'")))]
    TargetBranch {
        /// The target.
        name: String,
        /// The branch it names, if any.
        found: Option<String>,
        /// The tree's branches.
        branches: Vec<String>,
    },
}

/// The calibrated robot of a sheet: ready to predict from the first session's device frame.
#[derive(Clone, Debug)]
pub struct CalibratedRobot {
    /// The robot with its effects, device frame, targets and the first session's covariance.
    pub calibrated: Calibrated,
    /// Whether the record gave a device frame.
    pub has_device: bool,
    /// The other measurement sessions' device frames `T_device_base`, by name.
    pub sessions: Vec<(String, Isometry3<f64>)>,
    /// The first session's name, when the record gives it.
    pub first_session: Option<String>,
    /// The covariance as the record holds it (every session's device frame in it).
    pub covariance: Option<Covariance>,
    /// What the `t` of its effects of time was, when the record says
    /// ([`CalibrationRecord::time_unit`]).
    pub time_unit: Option<TimeUnit>,
}

impl CalibratedRobot {
    /// The robot of `table` with the effect values `effects` (name, value; see
    /// [`effects_from_parameters`]) and `record`'s frames, targets and covariance.
    ///
    /// # Errors
    /// [`CalibratedError`]: effects that do not read, targets that are no positions on a tool,
    /// a covariance that is not one.
    pub fn new(
        table: &DhTable,
        effects: &[(String, f64)],
        record: &CalibrationRecord,
    ) -> Result<Self, CalibratedError> {
        Self::of(&DhTree::serial(table), effects, record)
    }

    /// The robot of a calibrated `tree` (see [`crate::tree`]), as [`CalibratedRobot::new`]:
    /// each of `record`'s targets rides on the branch its `branch` names. A tree without
    /// branches is a serial robot.
    ///
    /// # Errors
    /// As [`CalibratedRobot::new`]; [`CalibratedError::TargetBranch`] for a target without a
    /// branch of the tree.
    pub fn new_tree(
        tree: &DhTree,
        effects: &[(String, f64)],
        record: &CalibrationRecord,
    ) -> Result<Self, CalibratedError> {
        Self::of(tree, effects, record)
    }

    fn of(
        tree: &DhTree,
        effects: &[(String, f64)],
        record: &CalibrationRecord,
    ) -> Result<Self, CalibratedError> {
        let mut ctx = EffectContext::serial(tree.trunk());
        ctx.tree = tree.clone();
        match &record.gravity_model {
            Some(g) => {
                ctx.gravity = Some(std::sync::Arc::new(
                    g.model_of(tree).map_err(CalibratedError::Gravity)?,
                ));
            }
            None => {
                let missing: Vec<String> = effects
                    .iter()
                    .filter(|(n, _)| needs_gravity(n))
                    .map(|(n, _)| n.clone())
                    .collect();
                if !missing.is_empty() {
                    return Err(CalibratedError::MissingGravity { effects: missing });
                }
            }
        }
        let effects = effects_from_parameters(effects, &ctx).map_err(CalibratedError::Effects)?;
        let sessions = record
            .sessions
            .iter()
            .map(|s| (s.name.clone(), from_xyz_rpy(s.xyz, s.rpy)))
            .collect();
        let device = record
            .device
            .as_ref()
            .map_or_else(Isometry3::identity, PoseRecord::pose);
        let targets: Vec<(String, Vector3<f64>)> = record
            .targets
            .iter()
            .map(|t| (t.name.clone(), Vector3::from(t.xyz)))
            .collect();
        for (name, p) in &targets {
            if !p.iter().all(|v| v.is_finite()) || p.norm() > MAX_TARGET_DISTANCE {
                return Err(CalibratedError::Target {
                    name: name.clone(),
                    position: *p,
                });
            }
        }
        let rotations: Vec<Option<UnitQuaternion<f64>>> = record
            .targets
            .iter()
            .map(|t| t.rpy.map(|rpy| from_xyz_rpy([0.0; 3], rpy).rotation))
            .collect();
        let robot = if tree.branches().is_empty() {
            Calibrated::new(tree.trunk(), &effects, &device, &targets)
        } else {
            let names: Vec<String> = tree.branches().iter().map(|b| b.name.clone()).collect();
            let mut on = Vec::with_capacity(targets.len());
            for ((name, p), t) in targets.iter().zip(&record.targets) {
                let b = t
                    .branch
                    .as_deref()
                    .and_then(|b| tree.branch_index(b))
                    .ok_or_else(|| CalibratedError::TargetBranch {
                        name: name.clone(),
                        found: t.branch.clone(),
                        branches: names.clone(),
                    })?;
                on.push((name.clone(), *p, b));
            }
            Calibrated::new_tree(tree, &effects, &device, &on)
        };
        let mut calibrated = robot
            .map_err(CalibratedError::Robot)?
            .with_target_rotations(&rotations);
        let covariance = match &record.covariance {
            Some(c) => Some(c.covariance()?),
            None => None,
        };
        if let Some(c) = &covariance {
            // The first session's frame is the device frame: the other sessions' are left out.
            calibrated = calibrated
                .with_covariance(&c.in_session(None))
                .map_err(CalibratedError::Uncertainty)?;
        }
        Ok(CalibratedRobot {
            calibrated,
            has_device: record.device.is_some(),
            sessions,
            first_session: record.first_session.clone(),
            covariance,
            time_unit: record.time_unit,
        })
    }
}
