//! `urdf-dh`: Denavit-Hartenberg parameters of serial manipulators from URDFs, vendor DH sheets
//! and measurements. See README.md.

use std::process::ExitCode;

fn main() -> ExitCode {
    let stdout = std::io::stdout();
    // Standard error unlocked: each message takes the lock for its own write, so the progress
    // line's thread (crate::progress) can draw between them.
    let mut stderr = std::io::stderr();
    let code = urdf_dh::cli::run(std::env::args_os(), &mut stdout.lock(), &mut stderr);
    ExitCode::from(u8::try_from(code).unwrap_or(2))
}
