//! The `urdf-dh` command line: files, options and printing around the `dh-workflows` library, the
//! one layer it calls. The binary is a thin `main` over [`cli::run`].
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

pub mod cli;
pub mod commands;
pub mod error;
pub mod guard;
pub mod manual;
pub mod plot;
pub mod plot_motion;
pub mod progress;
pub mod stdout;
pub mod svg;
pub mod xacro_flags;
