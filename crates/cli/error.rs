//! The exit-code contract (errors with their hints are the library's, `dh_workflows::error`).

/// What a successful run found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// Exit 0: verified, matched.
    Pass,
    /// Exit 1: a check or verification found a difference.
    Differs,
}
