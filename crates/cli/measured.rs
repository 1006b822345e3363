//! What the measured-data commands (`import`, `calibrate`, `cpa`, `simulate`, `predict`,
//! `compensate`) share: the model loader ([`dh_workflows::model`]), measurement files and effect
//! labels ([`dh_workflows::measured`]), the `dh-workflows` library's, re-exported here under their old
//! paths.

pub use dh_workflows::measured::*;
pub use dh_workflows::model::{
    is_urdf, load_model, measured_joints, prismatic, sheet_model, LoadedModel, SheetModel,
};
