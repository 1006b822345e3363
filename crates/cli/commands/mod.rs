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

/// The command line `args` as the report page's provenance records it: the program named
/// `urdf-dh`, each argument as text (lossy where it is not UTF-8).
pub(crate) fn command_line(args: &[std::ffi::OsString]) -> Vec<String> {
    args.iter()
        .enumerate()
        .map(|(i, a)| {
            if i == 0 {
                "urdf-dh".to_string()
            } else {
                a.to_string_lossy().into_owned()
            }
        })
        .collect()
}

/// The provenance of a `--report` page of this run: `inputs` (option, path) read and hashed,
/// the `command` line as the run was given it, the tool's version, the date (UTC, or
/// `SOURCE_DATE_EPOCH`).
pub(crate) fn report_provenance(
    command: &[String],
    inputs: &[(&str, &str)],
) -> dh_workflows::report_html::Provenance {
    dh_workflows::report_html::Provenance::now("urdf-dh", command.to_vec(), inputs)
}
