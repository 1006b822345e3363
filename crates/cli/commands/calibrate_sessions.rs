//! Measurement sessions in `calibrate`'s text report and written sheet (see
//! the library's fit; the JSON documents are `dh_workflows::fit`'s):
//! each session's device frame `T_device_base` (the robot's base link frame in that session's
//! device frame; metres, URDF roll-pitch-yaw radians) and its RMS.

use std::fmt::Write as _;

use dh_workflows::fit::{SessionDoc, SessionFrameDoc};

/// The frames of every session but the first (whose frame the sheet's `device` holds).
pub fn frames(docs: &[SessionDoc]) -> Vec<SessionFrameDoc> {
    SessionDoc::frames(docs)
}

/// The text report's lines for `docs` (nothing for one session); `xyz`, `rpy` and `len`
/// format a position, angles and a length.
pub fn text(
    s: &mut String,
    docs: &[SessionDoc],
    xyz: &dyn Fn([f64; 3]) -> String,
    rpy: &dyn Fn([f64; 3]) -> String,
    len: &dyn Fn(Option<f64>) -> String,
) {
    if docs.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "sessions (each its own device frame; the first is the device frame above):"
    );
    let width = crate::guard::column_width(docs.iter().map(|d| d.name.as_str()), 4);
    for d in docs {
        let _ = writeln!(
            s,
            "  {:<width$} xyz [m] {}  rpy [rad] {}  rms {} ({} samples)  validation rms {} ({} samples){}",
            crate::guard::escape(&d.name),
            xyz(d.device.xyz),
            rpy(d.device.rpy),
            len(d.rms),
            d.samples,
            len(d.val_rms),
            d.validation_samples,
            if d.fitted_on_validation {
                "  frame fitted on its validation samples (6 parameters)"
            } else {
                ""
            }
        );
    }
}
