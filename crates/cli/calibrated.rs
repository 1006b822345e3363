//! A calibrated model as `predict` and `compensate` read it: the `dh-sheet` library's
//! [`dh_sheet::calibrated`], re-exported here under its old path.

pub use dh_sheet::calibrated::*;
