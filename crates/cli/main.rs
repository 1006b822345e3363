//! `urdf-dh`: Denavit-Hartenberg parameters of serial manipulators from URDFs, vendor DH sheets
//! and measurements. See README.md.

use std::process::ExitCode;

fn main() -> ExitCode {
    let stdout = std::io::stdout();
    // Before anything is written: a closed standard output (`>&-`) refuses every write, so a
    // result is never lost to the runtime's stand-in /dev/null (see urdf_dh::stdout).
    let mut out = urdf_dh::stdout::Stdout::new(stdout.lock(), urdf_dh::stdout::was_closed());
    // Standard error unlocked: each message takes the lock for its own write, so the progress
    // line's thread (crate::progress) can draw between them.
    let mut stderr = std::io::stderr();
    let code = urdf_dh::cli::run(std::env::args_os(), &mut out, &mut stderr);
    ExitCode::from(u8::try_from(code).unwrap_or(2))
}
