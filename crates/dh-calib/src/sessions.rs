//! Measurement sessions: a device (a laser tracker) moved between days, so that each session
//! has its own device frame `T_device_base` while the robot's geometry and effects are shared.
//!
//! # Frames and parameters
//! Session `s`'s point is `p = T_s · FK(q) · t_k` with `T_s` the robot's base link frame in
//! that session's device frame (metres, radians). The first session with calibration samples
//! uses the model's `device` block (`device.x|y|z|rx|ry|rz`); every other calibration session
//! gets its own block `session.<name>.x|y|z|rx|ry|rz`, laid out as `device.*` (a small motion
//! of the robot in its own base frame, see [`crate::model`]).
//!
//! # Unseen sessions
//! A validation session without calibration samples has no estimated frame: its frame is fitted
//! on its own validation samples with the robot fixed (6 parameters, the closed-form rigid
//! registration of the model's points to the measured ones, the device scale left out), and
//! only then are its samples compared with the model.

use std::collections::HashMap;

use nalgebra::{Isometry3, Point3, Vector3};

use crate::data::{Measurements, Split};
use crate::fit::CalibError;
use crate::model::{Model, Observation, Observed};
use crate::prepare::Prepared;
use crate::registration::register;

/// Poses a session needs at least: a rigid frame needs three non-collinear points.
pub const MIN_SESSION_POSES: usize = 3;

/// One session's device frame and fit, in a [`crate::calibrate::Report`].
#[derive(Clone, Debug, PartialEq)]
pub struct SessionReport {
    /// Its name (the `session` column; `"1"` for a set without one).
    pub name: String,
    /// `T_device_base`: the robot's base link frame in this session's device frame.
    pub device: Isometry3<f64>,
    /// Calibration samples of the session.
    pub samples: usize,
    /// RMS distance of its calibration samples at the final fit (metres); `None` without any.
    pub rms: Option<f64>,
    /// Validation samples of the session.
    pub val_samples: usize,
    /// RMS distance of its validation samples at the final fit (metres); `None` without any.
    pub val_rms: Option<f64>,
    /// `true` when the session has no calibration sample and its frame was fitted on its
    /// validation samples with the robot fixed (6 parameters).
    pub fitted_on_validation: bool,
}

/// Checks the sessions of `data`: every used session has a non-empty name and at least
/// [`MIN_SESSION_POSES`] distinct poses (samples sharing `config`, or else the same joint
/// values, are one pose) of calibration samples, or of validation samples for a session
/// without calibration samples (whose frame they fix).
///
/// # Errors
/// [`CalibError::BadOption`] naming the session and its first sample's line.
pub fn check(data: &Measurements) -> Result<(), CalibError> {
    if data.sessions.is_empty() {
        return Ok(());
    }
    // (session, split) -> (first line, poses)
    let mut seen: HashMap<(usize, bool), (usize, Vec<String>)> = HashMap::new();
    for s in &data.samples {
        let name = data
            .sessions
            .get(s.session)
            .ok_or_else(|| CalibError::BadOption {
                what: format!("sample at line {}", s.line),
                reason: format!(
                    "expected a session index below {}, found {}",
                    data.sessions.len(),
                    s.session
                ),
            })?;
        if name.trim().is_empty() {
            return Err(CalibError::BadOption {
                what: format!("sample at line {}", s.line),
                reason: "expected a session name, found an empty one".into(),
            });
        }
        let key = match &s.config {
            Some(c) => c.to_string(),
            None => format!("{:?}", s.q),
        };
        let e = seen
            .entry((s.session, s.split == Split::Validation))
            .or_insert((s.line, Vec::new()));
        if !e.1.contains(&key) {
            e.1.push(key);
        }
    }
    let calibrated: Vec<usize> = seen.keys().filter(|k| !k.1).map(|k| k.0).collect();
    let mut found: Vec<_> = seen.into_iter().collect();
    found.sort_by_key(|(_, (line, _))| *line);
    for ((s, val), (line, poses)) in found {
        // Validation samples of a calibrated session use its frame: any number will do.
        if val && calibrated.contains(&s) {
            continue;
        }
        if poses.len() < MIN_SESSION_POSES {
            return Err(CalibError::BadOption {
                what: format!(
                    "session '{}' (first sample at line {line})",
                    data.sessions[s]
                ),
                reason: format!(
                    "expected at least {MIN_SESSION_POSES} poses of {} samples to fix its \
                     device frame, found {}",
                    if val { "validation" } else { "calibration" },
                    poses.len()
                ),
            });
        }
    }
    Ok(())
}

/// The sessions of `cal`, in order of first appearance.
pub(crate) fn sessions_of(cal: &[Observed]) -> Vec<usize> {
    let mut out: Vec<usize> = Vec::new();
    for o in cal {
        if !out.contains(&o.session) {
            out.push(o.session);
        }
    }
    out
}

/// Gives every calibration session after the first its own device block.
pub(crate) fn add_blocks(model: &mut Model, data: &Measurements, cal: &[Observed]) {
    for s in sessions_of(cal).into_iter().skip(1) {
        model.add_session(s, &data.session_name(s), &Isometry3::identity());
    }
}

/// The model's point of `o` in the robot's base link frame (no device frame, no scale).
fn base_point(model: &Model, x: &[f64], o: &Observed) -> Vector3<f64> {
    match &o.observation {
        Observation::Point { target, .. } | Observation::TargetPose { target, .. } => {
            let fk = model.robot_fk_of(x, &o.q, model.target_chain(*target));
            (fk * Point3::from(model.target_at(x, *target))).coords
        }
        Observation::Pose(_) => model.robot_fk(x, &o.q).translation.vector,
    }
}

fn measured(o: &Observed) -> Vector3<f64> {
    o.observation.position()
}

/// Per session of `obs` in `sessions`: the rigid registration of the model's base-frame points
/// at `x` to the measured ones (the least-squares `T_device_base` with the robot fixed).
///
/// # Errors
/// Those of [`register`].
pub(crate) fn register_each(
    model: &Model,
    x: &[f64],
    obs: &[Observed],
    sessions: &[usize],
) -> Result<Vec<(usize, Isometry3<f64>)>, CalibError> {
    sessions
        .iter()
        .map(|&s| {
            let own: Vec<&Observed> = obs.iter().filter(|o| o.session == s).collect();
            // The model's points on every core (a closed-form start reads 100 000 of them).
            let a = crate::fit::in_segments(&own, |o| base_point(model, x, o));
            let b: Vec<Vector3<f64>> = own.iter().map(|o| measured(o)).collect();
            register(&a, &b).map(|t| (s, t))
        })
        .collect()
}

/// The frames of the validation sessions that no calibration sample measured, fitted on their
/// validation samples at `x` (see the module docs); empty when there are none or registration
/// fails (their samples are then compared with the `device` frame).
pub(crate) fn unseen_frames(
    model: &Model,
    x: &[f64],
    prep: &Prepared,
) -> Vec<(usize, Isometry3<f64>)> {
    let seen = sessions_of(&prep.cal);
    let unseen: Vec<usize> = sessions_of(&prep.val)
        .into_iter()
        .filter(|s| !seen.contains(s))
        .collect();
    if unseen.is_empty() {
        return Vec::new();
    }
    register_each(model, x, &prep.val, &unseen).unwrap_or_default()
}

/// Distance (metres) of `o` to the model at `x` with its session's device frame `frame`
/// (the device scale applied as [`Model::point`] does).
pub(crate) fn distance_in(model: &Model, x: &[f64], o: &Observed, frame: &Isometry3<f64>) -> f64 {
    let p = frame * Point3::from(base_point(model, x, o));
    (p.coords * model.scale_at(x, &o.q) - measured(o)).norm()
}

/// Per session named in `names` (one unnamed session when empty): its frame at `x` and the
/// RMS of its calibration and validation distances (`cal_d`, `val_d` in the order of
/// `prep.cal`, `prep.val`). The first entry is the session of the `device` block (the first
/// with calibration samples), the others follow in file order.
pub(crate) fn reports(
    model: &Model,
    x: &[f64],
    names: &[String],
    prep: &Prepared,
    cal_d: &[f64],
    val_d: &[f64],
) -> Vec<SessionReport> {
    let unseen = unseen_frames(model, x, prep);
    let rms = |d: &[f64]| {
        (!d.is_empty()).then(|| (d.iter().map(|v| v * v).sum::<f64>() / d.len() as f64).sqrt())
    };
    // The `device` block's session first, then the others in file order.
    let mut order = sessions_of(&prep.cal);
    order.truncate(1);
    let first = order.first().copied();
    order.extend((0..names.len().max(1)).filter(|s| Some(*s) != first));
    order
        .into_iter()
        .filter_map(|s| {
            let c: Vec<f64> = prep
                .cal
                .iter()
                .zip(cal_d)
                .filter(|(o, _)| o.session == s)
                .map(|(_, d)| *d)
                .collect();
            let v: Vec<f64> = prep
                .val
                .iter()
                .zip(val_d)
                .filter(|(o, _)| o.session == s)
                .map(|(_, d)| *d)
                .collect();
            if c.is_empty() && v.is_empty() {
                return None;
            }
            let own = unseen.iter().find(|(u, _)| *u == s).map(|(_, t)| *t);
            Some(SessionReport {
                name: names.get(s).cloned().unwrap_or_else(|| (s + 1).to_string()),
                device: own.unwrap_or_else(|| model.session_device_at(x, s)),
                samples: c.len(),
                rms: rms(&c),
                val_samples: v.len(),
                val_rms: rms(&v),
                fitted_on_validation: own.is_some(),
            })
        })
        .collect()
}

/// A note for each validation session without calibration samples (see the module docs).
pub(crate) fn unseen_notes(data: &Measurements, prep: &Prepared) -> Vec<String> {
    let seen = sessions_of(&prep.cal);
    sessions_of(&prep.val)
        .into_iter()
        .filter(|s| !seen.contains(s))
        .map(|s| {
            let n = prep.val.iter().filter(|o| o.session == s).count();
            format!(
                "session '{}' has no calibration sample; its device frame is fitted on its own {n} \
                 validation samples with the robot fixed (6 parameters) before they are compared",
                data.session_name(s)
            )
        })
        .collect()
}

/// A note when validation samples without their own session are far worse than the
/// calibration (`val_rms` above [`MOVED_RATIO`] times `rms` and above [`MOVED_RMS`]): the
/// device was probably moved between them, which a `session` column would say.
pub(crate) fn moved_note(sessions: usize, rms: f64, val_rms: Option<f64>) -> Option<String> {
    let v = val_rms?;
    (sessions <= 1 && v > MOVED_RATIO * rms && v > MOVED_RMS).then(|| {
        format!(
            "the validation RMS ({v:.6} m) is {:.0} x the calibration RMS: if the validation data was measured in another session (the device moved), name each sample's session in a `session` column so that each gets its own device frame",
            v / rms.max(f64::MIN_POSITIVE)
        )
    })
}

/// The validation RMS over the calibration RMS above which a note suggests that the validation
/// data were measured in another session (with [`MOVED_RMS`]).
pub const MOVED_RATIO: f64 = 100.0;
/// The validation RMS (metres) above which, with [`MOVED_RATIO`], that note is given.
pub const MOVED_RMS: f64 = 0.01;

/// The validation observations for the effect search's linearised held-out figures
/// ([`crate::diagnose`]): those of an unseen session (see [`unseen_frames`]) are moved from
/// their fitted frame `T_u` into the `device` block's frame `T_d` at `x`
/// (`p' = T_d · T_u⁻¹ · p`), where the model compares them; the frame is held at its fit at `x`
/// (not refitted per candidate). The others are unchanged.
pub(crate) fn val_for_linearisation(model: &Model, x: &[f64], prep: &Prepared) -> Vec<Observed> {
    let unseen = unseen_frames(model, x, prep);
    if unseen.is_empty() {
        return prep.val.clone();
    }
    let device = model.device_at(x);
    prep.val
        .iter()
        .map(|o| {
            let mut o = o.clone();
            if let Some((_, t)) = unseen.iter().find(|(s, _)| *s == o.session) {
                let to_device = device * t.inverse();
                match &mut o.observation {
                    Observation::Point { point, .. } => {
                        *point = (to_device * Point3::from(*point)).coords;
                    }
                    Observation::Pose(p) | Observation::TargetPose { pose: p, .. } => {
                        **p = to_device * **p;
                    }
                }
            }
            o
        })
        .collect()
}
