//! The `urdf-dh` command line: files, options and printing around the `dh-core`, `urdf-axes`,
//! `dh-calib` and `dh-workflows` libraries. The binary is a thin `main` over [`cli::run`].
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

pub mod calibrated;
pub mod cli;
pub mod commands;
pub mod error;
pub mod guard;
pub mod input;
pub mod manual;
pub mod measured;
pub mod output;
pub mod plot;
pub mod plot_motion;
pub mod progress;
pub mod readback;
pub mod stdout;
pub mod svg;
pub mod xacro_flags;

// The sheet formats, their units and writers are the `dh-workflows` library's; the CLI keeps their
// old paths (`urdf_dh::sheet`, `crate::units`, ...) for its commands and for callers of this
// crate.
pub use dh_workflows::{render, sheet, tree_sheet, units};
