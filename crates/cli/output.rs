//! Writing output files so that a failed run never leaves one half-written, and no output
//! lands on an input: the `dh-workflows` library's [`dh_workflows::output`], re-exported here under its
//! old path.

pub use dh_workflows::output::*;
