//! The `urdf-dh` command line: files, formats and printing around the `dh-core`, `urdf-axes`
//! and `dh-calib` libraries. The binary is a thin `main` over [`cli::run`].
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
pub mod measured;
pub mod output;
pub mod plot;
pub mod progress;
pub mod readback;
pub mod readback_parse;
pub mod render;
pub mod sheet;
pub mod svg;
pub mod tree_sheet;
pub mod units;
