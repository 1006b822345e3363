//! Measurement sessions in `calibrate`'s reports and written sheet (see `dh_calib::sessions`):
//! each session's device frame `T_device_base` (the robot's base link frame in that session's
//! device frame; metres, URDF roll-pitch-yaw radians) and its RMS.

use std::fmt::Write as _;

use dh_calib::calibrate::Report;
use dh_calib::data::Measurements;
use nalgebra::Isometry3;
use serde::Serialize;

use super::calibrate::PoseSi;

/// One session in the JSON report (metres, radians).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SessionDoc {
    /// The session's name (the `session` column).
    pub name: String,
    /// Its device frame: the robot base in the device frame.
    pub device: PoseSi,
    /// Its calibration samples.
    pub samples: usize,
    /// RMS distance of its calibration samples at the final fit (metres).
    pub rms: Option<f64>,
    /// Its validation samples.
    pub validation_samples: usize,
    /// RMS distance of its validation samples at the final fit (metres).
    pub val_rms: Option<f64>,
    /// `true`: no calibration sample, the frame was fitted on its validation samples with the
    /// robot fixed (6 parameters).
    pub fitted_on_validation: bool,
}

/// A session's device frame in the written sheet's `calibration.sessions` list.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SessionFrameDoc {
    /// The session's name.
    pub name: String,
    /// Translation (metres).
    pub xyz: [f64; 3],
    /// Roll, pitch, yaw (radians).
    pub rpy: [f64; 3],
}

/// The sessions of `report`, the `device` block's first; empty for a set of one session (the
/// report's `device` says it all).
pub fn docs(report: &Report) -> Vec<SessionDoc> {
    if report.sessions.len() <= 1 {
        return Vec::new();
    }
    report
        .sessions
        .iter()
        .map(|s| SessionDoc {
            name: s.name.clone(),
            device: PoseSi::of(&s.device),
            samples: s.samples,
            rms: s.rms,
            validation_samples: s.val_samples,
            val_rms: s.val_rms,
            fitted_on_validation: s.fitted_on_validation,
        })
        .collect()
}

/// The frames of every session but the first (whose frame the sheet's `device` holds).
pub fn frames(docs: &[SessionDoc]) -> Vec<SessionFrameDoc> {
    docs.iter()
        .skip(1)
        .map(|s| SessionFrameDoc {
            name: s.name.clone(),
            xyz: s.device.xyz,
            rpy: s.device.rpy,
        })
        .collect()
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

/// The largest difference (metres, or radians for the rotation) between the sessions written
/// (`docs` but the first) and those read back.
pub fn read_back_deviation(docs: &[SessionDoc], back: &[(String, Isometry3<f64>)]) -> f64 {
    let written = frames(docs);
    if written.len() != back.len() {
        return f64::INFINITY;
    }
    written
        .iter()
        .zip(back)
        .map(|(w, (name, b))| {
            if &w.name != name {
                return f64::INFINITY;
            }
            let d = dh_core::pose::from_xyz_rpy(w.xyz, w.rpy).inverse() * b;
            d.translation.vector.norm().max(d.rotation.angle())
        })
        .fold(0.0, f64::max)
}

/// Name of the session of a validation file without a `session` column when the calibration
/// data names its sessions (or the other way round).
pub const UNNAMED_VALIDATION: &str = "validation";

/// Matches the sessions of `extra` (a validation file) to those of `data` by name, adding the
/// new ones to `data.sessions`; returns `data`'s index of each of `extra`'s sessions. When
/// neither names sessions, everything stays in one session. When only one of them does, the
/// other's samples are one session of their own (`"1"` for the calibration data,
/// [`UNNAMED_VALIDATION`] for the validation file), whose frame is then estimated apart.
pub fn merge(data: &mut Measurements, extra: &Measurements) -> Vec<usize> {
    if data.sessions.is_empty() && extra.sessions.is_empty() {
        return vec![0];
    }
    if data.sessions.is_empty() {
        data.sessions.push(data.session_name(0));
    }
    let names: Vec<String> = if extra.sessions.is_empty() {
        vec![UNNAMED_VALIDATION.to_string()]
    } else {
        extra.sessions.clone()
    };
    names
        .into_iter()
        .map(|n| match data.sessions.iter().position(|s| *s == n) {
            Some(i) => i,
            None => {
                data.sessions.push(n);
                data.sessions.len() - 1
            }
        })
        .collect()
}
