//! `urdf-dh`: Denavit-Hartenberg parameters of serial manipulators from URDFs, vendor DH sheets
//! and measurements. See README.md.

use std::process::ExitCode;

fn main() -> ExitCode {
    let stdout = std::io::stdout();
    let stderr = std::io::stderr();
    let code = urdf_dh::cli::run(std::env::args_os(), &mut stdout.lock(), &mut stderr.lock());
    ExitCode::from(u8::try_from(code).unwrap_or(2))
}
