//! A calibrated model as `predict` and `compensate` read it: the `dh-workflows` library's
//! [`dh_workflows::calibrated`], re-exported here under its old path.

pub use dh_workflows::calibrated::*;
