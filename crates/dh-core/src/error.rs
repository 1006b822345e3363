use thiserror::Error;

/// Everything that can go wrong in pure geometry: bad numbers, not bad files.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum CoreError {
    /// A direction vector has zero length, so it names no line.
    #[error("{what}: direction has zero length")]
    ZeroDirection {
        /// What the direction belongs to (a joint name, "line").
        what: String,
    },
    /// A NaN or infinite number where a finite one is needed.
    #[error("{what}: expected a finite number, found {value}")]
    NonFinite {
        /// What the number belongs to.
        what: String,
        /// The offending value.
        value: f64,
    },
    /// A tolerance is negative, NaN or infinite.
    #[error("{what} tolerance: expected a finite value >= 0, found {value}")]
    InvalidTolerance {
        /// `linear` or `angular`.
        what: &'static str,
        /// The offending value.
        value: f64,
    },
    /// Joint values do not match the table's rows.
    #[error("expected {expected} joint values, found {found}")]
    JointCount {
        /// Rows in the table.
        expected: usize,
        /// Values given.
        found: usize,
    },
    /// A chain without a single moving joint has no DH table.
    #[error("the chain has no moving joint")]
    NoJoints,
}
