//! The device frame each joint row is predicted from, for a joint file of several
//! measurement sessions.

use anyhow::Result;
use dh_calib::predict::Calibrated;

use super::{Frame, JointInput};
use crate::calibrated::CalibratedModel;
use crate::error::hinted;
use crate::input::display_name;
use crate::text::escape;

/// The robot each row is predicted with: `frames[row_frame[i]]` for row `i`, and the warnings
/// to show. Without a session asked, in the device frame, a joint file with a `session` column
/// (a measurement file of several sessions) has each row predicted from its own session's
/// device frame: the model's first session (its `device`) or one of its other `sessions`.
///
/// A name the model does not hold is refused, naming it, its first line and the sessions the
/// model has: predicted in another session's frame it would be silently wrong by the distance
/// between the two frames. A sheet written before the first session's name was kept
/// (`first_session`) leaves one name unmatched: it is taken as the first, with a warning.
///
/// # Errors
/// A session the model does not hold (see above); several sessions in the file of a model
/// calibrated on one.
pub(super) fn session_frames(
    model: &CalibratedModel,
    input: &JointInput,
    frame: Frame,
    session: Option<&str>,
    joints_name: &str,
    origin: &str,
) -> Result<(Vec<Calibrated>, Vec<usize>, Vec<String>)> {
    let first = vec![model.calibrated.clone()];
    // Each name with its first line.
    let mut names: Vec<(&str, usize)> = Vec::new();
    for r in &input.rows {
        if let Some(s) = r.session.as_deref() {
            if !names.iter().any(|(n, _)| *n == s) {
                names.push((s, r.line));
            }
        }
    }
    if session.is_some() || frame == Frame::Base || names.is_empty() {
        return Ok((first, vec![0; input.rows.len()], Vec::new()));
    }
    let file = display_name(joints_name);
    let quoted = |v: &[&str]| {
        v.iter()
            .map(|n| format!("'{}'", escape(n)))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let known: Vec<&str> = model
        .first_session
        .as_deref()
        .into_iter()
        .chain(model.sessions.iter().map(|(n, _)| n.as_str()))
        .collect();
    let unknown: Vec<(&str, usize)> = names
        .iter()
        .copied()
        .filter(|(n, _)| !known.contains(n))
        .collect();
    let mut warnings = Vec::new();
    // The name taken as the first session's, when the model does not give it.
    let mut assumed_first: Option<&str> = None;
    if model.sessions.is_empty() && model.first_session.is_none() {
        // A model of one session: the file's one name is it.
        if names.len() > 1 {
            let all: Vec<&str> = names.iter().map(|(n, _)| *n).collect();
            return Err(hinted(
                format!(
                    "{file}: line {}: the file has sessions {}, but {origin} was calibrated on one measurement session",
                    names[1].1,
                    quoted(&all)
                ),
                "predict every row in the model's device frame with --session left out and one session's rows, or calibrate on every session",
            ));
        }
        return Ok((first, vec![0; input.rows.len()], Vec::new()));
    }
    if let Some(&(name, line)) = unknown.first() {
        if model.first_session.is_some() || unknown.len() > 1 {
            return Err(hinted(
                format!(
                    "{file}: line {line}, column 'session': {} is no session of {origin}; expected one of {}",
                    quoted(&[name]),
                    if model.first_session.is_some() {
                        quoted(&known)
                    } else {
                        format!("{} and the first session's, which the model does not name ({} not in it: at most one can be the first)", quoted(&known), quoted(&unknown.iter().map(|(n, _)| *n).collect::<Vec<_>>()))
                    }
                ),
                "a session's rows are predicted from that session's device frame: name the sessions as in the calibration's data, or predict every row from one session with --session NAME",
            ));
        }
        warnings.push(format!(
            "{file}: session '{}' (first at line {line}) is not named in {origin}, which names {} and holds the first session's frame without its name: '{}' is taken as the first session",
            escape(name),
            quoted(&known),
            escape(name)
        ));
        assumed_first = Some(name);
    }
    let mut frames = first;
    let mut index: Vec<(&str, usize)> = Vec::new();
    for &(n, _) in &names {
        if Some(n) == assumed_first || Some(n) == model.first_session.as_deref() {
            index.push((n, 0));
        } else {
            frames.push(model.for_session(n)?);
            index.push((n, frames.len() - 1));
        }
    }
    let row_frame = input
        .rows
        .iter()
        .map(|r| {
            r.session
                .as_deref()
                .and_then(|s| index.iter().find(|(n, _)| *n == s))
                .map_or(0, |(_, k)| *k)
        })
        .collect();
    Ok((frames, row_frame, warnings))
}
