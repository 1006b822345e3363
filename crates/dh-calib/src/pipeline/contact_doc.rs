//! The report of a calibration from contacts (see [`crate::socket`]) as a plain document
//! ([`ContactDoc`]): what `urdf-dh calibrate --format json` prints for contact data. Lengths in
//! metres, angles in radians; socket centres in the robot's base link frame.

use serde::{Deserialize, Serialize};

use super::doc::{CandidateDoc, FixedDoc};
use crate::socket::{Consistency, SocketReport};

/// Consistency figures (metres): how far the modelled contacts of each socket lie from their
/// mean (see [`Consistency`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ConsistencyDoc {
    /// Mean distance of each modelled point to its socket's mean, per placement, averaged.
    pub mean_abs: f64,
    /// RMS of those distances.
    pub rms: f64,
    /// Largest of them.
    pub max: f64,
    /// |socket means' distance - known distance|, when distances are known.
    pub distance_error: Option<f64>,
    /// Placements.
    pub placements: usize,
    /// Contacts.
    pub points: usize,
}

impl From<&Consistency> for ConsistencyDoc {
    fn from(c: &Consistency) -> Self {
        Self {
            mean_abs: c.mean_abs,
            rms: c.rms,
            max: c.max,
            distance_error: c.distance_error,
            placements: c.placements,
            points: c.points,
        }
    }
}

/// One step of a contact calibration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContactStepDoc {
    /// The step's label.
    pub label: String,
    /// Free parameters (`None` for the model as given).
    pub free: Option<usize>,
    /// RMS residual of the step's fit (metres; `None` for the model as given).
    pub rms: Option<f64>,
    /// Consistency on the training placements.
    pub train: ConsistencyDoc,
    /// Consistency on the test placements, when there are any.
    pub test: Option<ConsistencyDoc>,
}

/// One parameter of a contact calibration (SI units: metres, radians).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContactParameterDoc {
    /// Name (`<joint>.a`, `base.x`, `socket.<name>.x`, effect names).
    pub name: String,
    /// Nominal value.
    pub nominal: f64,
    /// Estimate.
    pub estimate: f64,
    /// Standard error; `None` when held fixed.
    pub std_error: Option<f64>,
    /// Estimated (`false`: held at nominal).
    pub free: bool,
}

impl ContactParameterDoc {
    /// Whether this is an effect's parameter (see [`super::is_effect`]), free or held at the
    /// value the fit used: what a calibrated sheet of contacts lists, as
    /// [`super::ParameterDoc::is_effect`] says.
    pub fn is_effect(&self) -> bool {
        super::is_effect(&self.name)
    }
}

/// A fitted socket centre.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SocketDoc {
    /// Its name (the `socket` column).
    pub name: String,
    /// Centre in the robot's base link frame (metres).
    pub position: [f64; 3],
    /// Contacts in it.
    pub samples: usize,
}

/// One full refit of an effect candidate (JSON `trials`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContactTrialDoc {
    /// The effect's label.
    pub label: String,
    /// RMS with it (metres).
    pub rms: f64,
    /// Held-out RMS with it (metres).
    pub val_rms: Option<f64>,
    /// F-to-enter.
    pub f: f64,
    /// p-value of `f`.
    pub f_p: f64,
    /// The level `f_p` had to beat.
    pub f_threshold: f64,
    /// p-value of the held-out test.
    pub held_out_p: Option<f64>,
    /// Taken or not.
    pub accepted: bool,
    /// Why.
    pub reason: String,
}

/// The report of a contact calibration: metres and radians.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContactDoc {
    /// The model's name.
    pub model: String,
    /// The data's name.
    pub data: String,
    /// Always `contacts`.
    pub kind: String,
    /// The steps, in order.
    pub steps: Vec<ContactStepDoc>,
    /// Contact noise weighting the distances (metres).
    pub sigma_point: f64,
    /// Condition number of the scaled Jacobian of the free parameters.
    pub condition_number: f64,
    /// The fitted sockets.
    pub sockets: Vec<SocketDoc>,
    /// Every parameter.
    pub parameters: Vec<ContactParameterDoc>,
    /// The parameters held at nominal, with what absorbs them.
    pub fixed: Vec<FixedDoc>,
    /// Labels of the effects estimated in the last step.
    pub selected_effects: Vec<String>,
    /// The candidate table of the first round (empty without an effect search).
    pub candidates: Vec<CandidateDoc>,
    /// The refits of the effect search.
    pub trials: Vec<ContactTrialDoc>,
    /// Remarks.
    pub notes: Vec<String>,
}

impl ContactDoc {
    /// The document of `r`, a calibration of model `model` against contact data `data` (the
    /// names a caller gives them).
    pub fn new(model: &str, data: &str, r: &SocketReport) -> Self {
        ContactDoc {
            model: model.into(),
            data: data.into(),
            kind: "contacts".into(),
            steps: r
                .consistency
                .iter()
                .map(|c| {
                    let s = r.steps.iter().find(|s| s.label == c.label);
                    ContactStepDoc {
                        label: c.label.clone(),
                        free: s.map(|s| s.free),
                        rms: s.map(|s| s.rms),
                        train: (&c.train).into(),
                        test: c.test.as_ref().map(Into::into),
                    }
                })
                .collect(),
            sigma_point: r.sigma_point,
            condition_number: r.condition_number,
            sockets: r
                .sockets
                .iter()
                .map(|s| SocketDoc {
                    name: s.name.clone(),
                    position: [s.position.x, s.position.y, s.position.z],
                    samples: s.samples,
                })
                .collect(),
            parameters: r
                .parameters
                .iter()
                .map(|p| ContactParameterDoc {
                    name: p.name.clone(),
                    nominal: p.nominal,
                    estimate: p.estimate,
                    std_error: p.std_error,
                    free: p.free,
                })
                .collect(),
            fixed: r.fixed.iter().map(FixedDoc::from).collect(),
            selected_effects: r.selected_effects.clone(),
            candidates: r.candidates.iter().map(CandidateDoc::from).collect(),
            trials: r
                .trials
                .iter()
                .map(|t| ContactTrialDoc {
                    label: t.label.clone(),
                    rms: t.rms,
                    val_rms: t.val_rms,
                    f: t.f,
                    f_p: t.f_p,
                    f_threshold: t.f_threshold,
                    held_out_p: t.held_out.map(|h| h.1),
                    accepted: t.accepted,
                    reason: t.reason.clone(),
                })
                .collect(),
            notes: r.notes.clone(),
        }
    }
}
