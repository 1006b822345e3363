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

/// The provenance of a `--report` page of this run: `inputs` (option, path) read and hashed,
/// the command line as this process got it, the tool's version, the date (UTC, or
/// `SOURCE_DATE_EPOCH`).
pub(crate) fn report_provenance(inputs: &[(&str, &str)]) -> dh_workflows::report_html::Provenance {
    let command = std::env::args_os()
        .enumerate()
        .map(|(i, a)| {
            if i == 0 {
                "urdf-dh".to_string()
            } else {
                a.to_string_lossy().into_owned()
            }
        })
        .collect();
    dh_workflows::report_html::Provenance::now("urdf-dh", command, inputs)
}
