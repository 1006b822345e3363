//! One module per subcommand, plus what several share: `calibrate`'s arguments
//! ([`calibrate_args`]), which its contact report ([`sockets`]) and tree report
//! ([`calibrate_tree`]) use too, and its findings
//! ([`calibrate_findings`]) and sessions ([`calibrate_sessions`]). What `calibrate` reads and
//! runs is the library's `dh_workflows::calibration`.

pub mod batch;
pub mod calibrate;
pub mod calibrate_args;
pub mod calibrate_findings;
pub mod calibrate_sessions;
pub mod calibrate_tree;
pub mod check;
pub mod compensate;
pub mod convert;
pub mod cpa;
pub mod extract;
pub mod import;
pub mod predict;
pub mod simulate;
pub mod sockets;
pub mod to_urdf;
