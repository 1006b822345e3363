//! What the measured-data commands (`import`, `calibrate`, `cpa`, `simulate`, `predict`,
//! `compensate`) share: the model loader ([`dh_sheet::model`]), measurement files and effect
//! labels ([`dh_sheet::measured`]), the `dh-sheet` library's, re-exported here under their old
//! paths.

pub use dh_sheet::measured::*;
pub use dh_sheet::model::{
    is_urdf, load_model, measured_joints, prismatic, sheet_model, LoadedModel, SheetModel,
};
