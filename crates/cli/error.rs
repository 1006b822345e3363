//! Errors the CLI reports with a hint, and the exit-code contract.

pub use dh_workflows::error::{hint_for, hinted, Hinted};

/// What a successful run found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// Exit 0: verified, matched.
    Pass,
    /// Exit 1: a check or verification found a difference.
    Differs,
}
