//! The crate's error type: one enum for modelling, simulating and fitting measurements.
//!
//! Messages are lowercase, "expected X, found Y", naming the parameter, joint or file.

use thiserror::Error;

/// Everything that can go wrong while modelling, simulating or fitting measurements.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum CalibError {
    /// A residual or Jacobian entry is NaN or infinite.
    #[error("{what}: expected finite numbers, found a NaN or infinite value")]
    NonFinite {
        /// Where it was found.
        what: String,
    },
    /// A parameter index is out of range, or a scale is not a positive finite number.
    #[error("parameter {index}: {reason}")]
    BadParameter {
        /// Parameter index.
        index: usize,
        /// What is wrong with it.
        reason: String,
    },
    /// Lengths of inputs that must agree do not.
    #[error("{what}: expected {expected} values, found {found}")]
    Length {
        /// What was measured.
        what: String,
        /// Expected length.
        expected: usize,
        /// Actual length.
        found: usize,
    },
    /// The SVD did not converge.
    #[error("singular value decomposition did not converge ({what})")]
    NoConvergence {
        /// Which decomposition.
        what: String,
    },
    /// A joint of the model has no column in the measurements and follows no joint that has.
    #[error("joint '{joint}': expected a column in the measurements, found none")]
    MissingJoint {
        /// Joint name.
        joint: String,
    },
    /// A sample names a target that does not exist.
    #[error("sample at line {line}: expected a target index below {count}, found {target}")]
    BadTarget {
        /// 1-based source line (0 when generated).
        line: usize,
        /// The index given.
        target: usize,
        /// Number of targets.
        count: usize,
    },
    /// Too few samples to determine what must be estimated.
    #[error("{what}: expected at least {needed} samples, found {found}")]
    TooFewSamples {
        /// What needed them.
        what: String,
        /// Samples needed.
        needed: usize,
        /// Samples available.
        found: usize,
    },
    /// The measured or modelled points are degenerate (all on one line) so no frame fits them.
    #[error("{what}: points are collinear or coincident, no unique rigid registration")]
    Degenerate {
        /// What was being registered.
        what: String,
    },
    /// A name in the input matches no parameter of the model.
    #[error("expected a parameter name of the model, found '{name}'")]
    UnknownParameter {
        /// The unknown name.
        name: String,
    },
    /// An option is out of its range.
    #[error("{what}: {reason}")]
    BadOption {
        /// Which option.
        what: String,
        /// Expected range.
        reason: String,
    },
    /// The model's kinematics are invalid.
    #[error(transparent)]
    Core(#[from] dh_core::CoreError),
}
