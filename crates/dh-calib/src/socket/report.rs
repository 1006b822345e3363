//! What a socket calibration reports: the consistency of the contacts with one fixed point
//! per socket ([`Consistency`], [`ConsistencyStep`]), the estimates and steps
//! ([`SocketEstimate`], [`SocketStep`]), the contact distances ([`ContactDistance`]) and the
//! whole [`SocketReport`]. Metres, radians.

use super::*;

/// The consistency figures of one set of contacts (see the module docs), metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Consistency {
    /// MUKCa's "mean absolute error": per placement the mean distance to the socket mean, then
    /// the mean over placements.
    pub mean_abs: f64,
    /// RMS distance to the socket mean over every point.
    pub rms: f64,
    /// Largest distance to the socket mean.
    pub max: f64,
    /// Mean over the distances of `|‖m_a − m_b‖ − L|` with `m` the socket means (MUKCa's
    /// "distortion"); `None` without distances.
    pub distance_error: Option<f64>,
    /// Number of placements.
    pub placements: usize,
    /// Number of points.
    pub points: usize,
}

/// Consistency before and after one step.
#[derive(Clone, Debug, PartialEq)]
pub struct ConsistencyStep {
    /// `as given`, `nominal`, `geometric` or `effects`.
    pub label: String,
    /// On the calibration contacts.
    pub train: Consistency,
    /// On the validation contacts, when there are any.
    pub test: Option<Consistency>,
}

/// A socket's estimated centre.
#[derive(Clone, Debug, PartialEq)]
pub struct SocketEstimate {
    /// Its name.
    pub name: String,
    /// Centre in the device frame (the robot's base link frame, see the module docs), metres.
    pub position: Vector3<f64>,
    /// Standard errors per axis (metres), when the fit gives them.
    pub std_error: Option<Vector3<f64>>,
    /// Contact samples in it.
    pub samples: usize,
}

/// One fitted step.
#[derive(Clone, Debug, PartialEq)]
pub struct SocketStep {
    /// `nominal`, `geometric` or `effects`.
    pub label: String,
    /// RMS distance of the calibration contacts to their fitted sockets (metres).
    pub rms: f64,
    /// Mean of those distances (metres).
    pub mean: f64,
    /// Largest (metres).
    pub max: f64,
    /// RMS distance of the validation contacts to their socket's modelled mean (metres).
    pub val_rms: Option<f64>,
    /// Number of free parameters (sockets included).
    pub free: usize,
    /// Solver iterations (last noise pass).
    pub iterations: usize,
    /// Why the solver stopped.
    pub termination: Termination,
}

/// One contact's distance to the mean of its socket's modelled positions (the consistency's
/// distance, see the module docs), metres.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactDistance {
    /// Index of the sample in the measurements.
    pub sample: usize,
    /// Whether it is a validation contact.
    pub validation: bool,
    /// Its socket's name.
    pub socket: String,
    /// With the model as given.
    pub as_given: f64,
    /// After the last step.
    pub last: f64,
}

/// The result of [`calibrate_sockets`]. Lengths in metres, angles in radians.
#[derive(Clone, Debug, PartialEq)]
pub struct SocketReport {
    /// The fitted steps, in order.
    pub steps: Vec<SocketStep>,
    /// Every model parameter, then the socket coordinates (`socket.<name>.x|y|z`, nominal = the
    /// `as given` socket means).
    pub parameters: Vec<ParameterEstimate>,
    /// Parameters held at their start because the data cannot identify them, with aliases.
    pub fixed: Vec<FixedParameter>,
    /// The calibrated table, tilts in their rows' `beta` (see [`Model::table_at`]).
    pub calibrated: DhTable,
    /// Estimated target positions in the tip frame.
    pub targets: Vec<(String, Vector3<f64>)>,
    /// Condition number of the scaled Jacobian of the last step's free parameters.
    pub condition_number: f64,
    /// Residual standard deviation of the last fit (weighted residuals, metres).
    pub sigma_hat: Option<f64>,
    /// Remarks (gauge freedom, scale).
    pub notes: Vec<String>,
    /// Consistency per step, `as given` first.
    pub consistency: Vec<ConsistencyStep>,
    /// The calibration sockets.
    pub sockets: Vec<SocketEstimate>,
    /// The known distances between calibration sockets.
    pub constraints: Vec<SocketConstraint>,
    /// The contact noise that weighted the distances in the last step (metres per axis).
    pub sigma_point: f64,
    /// Labels of the effects estimated in the last step (declared, or selected by
    /// [`diagnose_sockets`]).
    pub selected_effects: Vec<String>,
    /// The candidate table of the first round of [`diagnose_sockets`] (empty otherwise), best
    /// score first. `val_rms` is the held-out RMS distance to the socket means after the full
    /// refit, for the candidates that were refitted (metres).
    pub candidates: Vec<CandidateReport>,
    /// Every full refit of a candidate, in order, with the tests of the rule.
    pub trials: Vec<Trial>,
    /// Every contact's distance to its socket's modelled mean, as given and after the last
    /// step, in the order of the measurements.
    pub distances: Vec<ContactDistance>,
}
