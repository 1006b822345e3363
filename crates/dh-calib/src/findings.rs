//! The diagnosis's findings as data: what became of each effect candidate ([`CandidateReport`],
//! [`Trial`], [`Round`]), the tests of a model's residual against the noise
//! ([`ResidualTest`], [`StructureCheck`]), the effect parameters estimated
//! ([`EffectEstimate`]), the whole diagnosis ([`Diagnosis`]) and the verdict on the final model
//! ([`Verdict`]).
//!
//! Data only: [`crate::diagnose`] fills them,
//! [`crate::calibrate`] carries them in its [`crate::calibrate::Report`], and neither has to
//! import the other for them. Lengths in metres, angles in radians, as in the report.

/// Significance level of the tests by default (the diagnosis's and the final verdict's).
pub const DEFAULT_ALPHA: f64 = 0.01;

/// The verdict on the final model: its residual tested against the noise (chi-square with a
/// known sigma, lack of fit against the pure error of repeated poses; neither: no test), what
/// that means, and the structure the residual still has.
#[derive(Clone, Debug, PartialEq)]
pub struct Verdict {
    /// The test of the final model's residual (the same tests as the diagnosis's step 1).
    pub test: ResidualTest,
    /// Its level.
    pub alpha: f64,
    /// `Some(true)` when nothing significant remains, `Some(false)` when something does,
    /// `None` when no test is possible.
    pub complete: Option<bool>,
    /// Final calibration RMS over the noise floor, when there is a floor; for a 6-DoF set, the
    /// position's and the orientation's ratios together, each over its own noise
    /// (`sqrt((n p² + k a²) / (n + k))`, `n` samples, `k` of them with an orientation).
    pub ratio: Option<f64>,
    /// The position's ratio alone (RMS 3-D distance over [`crate::calibrate::NoiseFloor::rms`]).
    pub position_ratio: Option<f64>,
    /// The orientation's ratio alone (angle RMS over
    /// [`crate::calibrate::NoiseFloor::angle_rms`]); `None` without 6-DoF samples.
    pub angle_ratio: Option<f64>,
    /// `model complete`, `residual remains: N x the floor` (or `residual remains` without a
    /// floor; for a 6-DoF set followed by ` (position P x, orientation A x)`), or
    /// `no test possible`.
    pub summary: String,
    /// Residual structure of the final model against each joint and the pose order (see
    /// [`crate::diagnose`], step 5).
    pub structure: Vec<StructureCheck>,
    /// What the verdict means for the selected effects and the residual's structure.
    pub notes: Vec<String>,
}

/// What became of a candidate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CandidateStatus {
    /// Added to the model.
    Selected,
    /// Mimicked by the parameters already estimated; never selected.
    Aliased,
    /// Refitted and rejected by the rule (see the round's trials).
    Rejected,
    /// Not added (score too small, not tried, or selection stopped).
    NotSelected,
    /// Its columns are zero on these data, it couples two joints one of which moved less
    /// than [`crate::diagnose::MIN_JOINT_MOTION`] in them, or it is a `backlash_direction` of a joint that
    /// reverses fewer than [`crate::effects_order::MIN_REVERSALS`] times in them: never
    /// selected.
    Inert,
    /// Passed the rule's tests but a rival effect of the same joint's quantity did better
    /// (see [`crate::rivals`]; the reason names it).
    Rival,
}

impl CandidateStatus {
    /// Lowercase name for reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::Selected => "selected",
            Self::Aliased => "aliased",
            Self::Rejected => "rejected",
            Self::NotSelected => "not selected",
            Self::Inert => "inert",
            Self::Rival => "rival",
        }
    }
}

/// One row of the candidate table.
#[derive(Clone, Debug, PartialEq)]
pub struct CandidateReport {
    /// The effect's label.
    pub label: String,
    /// Number of parameters.
    pub parameters: usize,
    /// First-order reduction of the calibration sum of squares (m²) beyond the parameters
    /// estimated when it was scored.
    pub score: f64,
    /// Sine of the angle between its columns and the estimated ones (1: independent).
    pub independence: f64,
    /// Held-out RMS (metres) with it added, linearised; `None` without validation.
    pub val_rms: Option<f64>,
    /// What became of it.
    pub status: CandidateStatus,
    /// Why it was not added, when it was refitted and rejected or lost to a rival (its last
    /// trial's reason).
    pub reason: Option<String>,
}

/// One full refit of a candidate and the tests of the rule.
#[derive(Clone, Debug, PartialEq)]
pub struct Trial {
    /// The candidate.
    pub label: String,
    /// Calibration RMS after the refit (metres).
    pub rms: f64,
    /// Held-out RMS after the refit (metres).
    pub val_rms: Option<f64>,
    /// F-to-enter and its p-value.
    pub f: f64,
    /// p-value of `f`.
    pub f_p: f64,
    /// The Bonferroni threshold it was compared with (`alpha / K`).
    pub f_threshold: f64,
    /// BIC before and after.
    pub bic: (f64, f64),
    /// Wilcoxon signed-rank `z` of the held-out improvement over pose groups and its one-sided
    /// p-value.
    pub held_out: Option<(f64, f64)>,
    /// Whether it was added.
    pub accepted: bool,
    /// Why not, when not.
    pub reason: String,
}

/// One round of scoring.
#[derive(Clone, Debug, PartialEq)]
pub struct Round {
    /// Calibration RMS at the start of the round (metres).
    pub rms: f64,
    /// Held-out RMS at the start, linearised as the candidates' (metres).
    pub val_rms: Option<f64>,
    /// Every candidate scored, best score first.
    pub candidates: Vec<CandidateReport>,
    /// The candidates refitted, in order.
    pub trials: Vec<Trial>,
}

/// Where the noise estimate of the residual test comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NoiseTest {
    /// Known per-axis standard deviations: chi-square.
    KnownSigma,
    /// Repeated poses: lack-of-fit F test against the pure error.
    PureError,
    /// Neither: no test.
    None,
}

/// Step 1: is anything left after the geometric step?
#[derive(Clone, Debug, PartialEq)]
pub struct ResidualTest {
    /// Which test.
    pub kind: NoiseTest,
    /// The statistic (chi-square or F); `None` without a test.
    pub statistic: Option<f64>,
    /// Its degrees of freedom (one or two).
    pub dof: (f64, f64),
    /// Its p-value.
    pub p_value: Option<f64>,
    /// RMS 3-D noise implied by the estimate (metres), when there is one.
    pub noise_rms: Option<f64>,
    /// Whether something is left (true without a test).
    pub significant: bool,
    /// One line for the user.
    pub summary: String,
}

/// Step 5: residual structure against one variable.
#[derive(Clone, Debug, PartialEq)]
pub struct StructureCheck {
    /// A joint name, `pose order` (lag-1 correlation), `time` (a smooth trend along the pose
    /// order) or `gravity lever at <joint>` (see the verdict's structure tests).
    pub variable: String,
    /// The statistic (F, chi-square or z).
    pub statistic: f64,
    /// Its p-value.
    pub p_value: f64,
    /// Significant at `alpha / K`, `K` the tests made (each joint, the pose order, time and
    /// each gravity lever arm).
    pub significant: bool,
    /// Binned residuals: `(bin centre, RMS of the residual, length of the mean residual
    /// vector)` in the variable's unit (radians, metres, or pose index) and metres.
    pub bins: Vec<(f64, f64, f64)>,
}

/// An estimated effect parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct EffectEstimate {
    /// Parameter name.
    pub name: String,
    /// Estimate.
    pub value: f64,
    /// Standard error.
    pub std_error: Option<f64>,
    /// Unit.
    pub unit: String,
    /// For a compliance: the stiffness `1 / c` with its standard error (`σ_c / c²`) and unit.
    pub stiffness: Option<(f64, Option<f64>, String)>,
}

/// What the diagnosis found (the report's `diagnosis`).
#[derive(Clone, Debug, PartialEq)]
pub struct Diagnosis {
    /// The selection rule ([`crate::diagnose::RULE`]).
    pub rule: String,
    /// Significance level.
    pub alpha: f64,
    /// Step 1.
    pub residual_test: ResidualTest,
    /// Each round of scoring.
    pub rounds: Vec<Round>,
    /// Selected effects' parameters.
    pub effect_parameters: Vec<EffectEstimate>,
    /// Step 5.
    pub structure: Vec<StructureCheck>,
    /// Remarks (skipped candidates, unexplained structure).
    pub notes: Vec<String>,
}
