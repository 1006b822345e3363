//! `urdf_dh._native`: the Python face of the `urdf-dh` library, thin on purpose.
//!
//! Every computation is the library's: extraction and its proof and `check`'s comparison
//! (`table`: `dh_workflows::extract`, `dh_workflows::check`), prediction and compensation
//! (`calibration`: `dh_workflows::predict`, `dh_workflows::compensate`), and calibration
//! (`dh_workflows::calibration`, which reads the files or arrays and runs serial, tree and contact
//! data through the fitting library), simulated measurements (`simulation`:
//! `dh_workflows::simulation`) and circle-point analysis (`cpa`: `dh_workflows::cpa_report`), with measurements and joint values handed over as
//! arrays, no files; this crate only converts arguments and results. Poses cross as 4x4
//! homogeneous matrices (nested lists, row-major; metres and radians), which the pure-Python
//! package turns into numpy arrays. Errors carry the CLI's message (`{e:#}`, the whole context
//! chain) and its `hint:` line.

use pyo3::create_exception;
use pyo3::exceptions::{PyFileNotFoundError, PyValueError};
use pyo3::prelude::*;

mod calibration;
mod cpa;
mod simulation;
mod table;

create_exception!(
    _native,
    UrdfDhError,
    PyValueError,
    "Bad input (invalid URDF or sheet, unknown link, ...): the message `urdf-dh` prints after `urdf-dh: error:`; `.hint` holds its `hint:` line or None."
);

/// The Python exception for a library error: `FileNotFoundError` when a file is missing,
/// otherwise [`UrdfDhError`] with the CLI's message and hint.
pub(crate) fn to_py(py: Python<'_>, e: anyhow::Error) -> PyErr {
    let message = format!("{e:#}");
    let missing = e
        .chain()
        .filter_map(|c| c.downcast_ref::<std::io::Error>())
        .any(|io| io.kind() == std::io::ErrorKind::NotFound);
    if missing {
        return PyFileNotFoundError::new_err(message);
    }
    let err = UrdfDhError::new_err(message);
    let hint = dh_workflows::error::hint_for(&e);
    // Setting an attribute on a fresh exception object cannot fail in practice; if it does, the
    // exception still carries the message, and `hint` falls back to the class attribute.
    let _ = err.value(py).setattr("hint", hint);
    err
}

/// A number argument checked by the command line's own range of it ([`dh_workflows::ranges`]),
/// the error naming the Python argument `name`: `samples: expected a number of samples in [1,
/// 1000000], found 0`.
pub(crate) fn ranged<T>(
    name: &str,
    value: &str,
    guard: fn(&str) -> Result<T, String>,
) -> anyhow::Result<T> {
    guard(value).map_err(|e| anyhow::anyhow!("{name}: {e}"))
}

/// [`ranged`] for a float Python handed over as a number (written as Rust reads it back:
/// `NaN`, `inf` and every finite value round-trip).
pub(crate) fn ranged_f64(
    name: &str,
    value: f64,
    guard: fn(&str) -> Result<f64, String>,
) -> anyhow::Result<f64> {
    ranged(name, &format!("{value:?}"), guard)
}

/// The native module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    table::register(m)?;
    calibration::register(m)?;
    simulation::register(m)?;
    cpa::register(m)?;
    m.add("UrdfDhError", m.py().get_type::<UrdfDhError>())?;
    Ok(())
}
