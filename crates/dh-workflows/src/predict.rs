//! Using a calibration: the calibrated model's target positions (or tool poses) at given joint
//! values, each with its standard uncertainty from the calibration's covariance
//! ([`dh_calib::predict::Calibrated`]), as `urdf-dh predict` writes them and the Python package
//! returns them.
//!
//! [`read_joints`] reads joint values (a file, or arrays a caller hands over) in the model's
//! measured columns; [`frame_of`] chooses the frame (and the session's device frame);
//! [`predict`] computes [`Predictions`]: one [`Predicted`] per joint row and target.
//!
//! Frames and units: every position is in metres, in the measuring device's frame of the
//! calibration ([`Frame::Device`]) or the robot's base link frame ([`Frame::Base`]); a tool
//! attitude is URDF roll, pitch, yaw in radians (`R = Rz(yaw) Ry(pitch) Rx(roll)`); a tool's
//! rotation uncertainty is about the frame's axes, in radians.

use anyhow::{Context, Result};
use dh_calib::csv::SampleArrays;
use dh_calib::joints::JointRow;
use dh_calib::model::SampleContext;
use dh_calib::predict::Calibrated;
/// The frame predictions are in: the measuring device's or the robot's base link frame.
pub use dh_calib::predict::Frame;
use dh_core::JointKind;
use nalgebra::Vector3;

use crate::calibrated::CalibratedModel;
use crate::error::hinted;
use crate::input::display_name;
use crate::measured::{DataFile, DataUnits};
use crate::text::escape;

/// The target name that asks for the tip frame's pose.
pub const TOOL: &str = "tool";

/// Joint values in a model's measured columns, with their lines and configs.
#[derive(Clone, Debug)]
pub struct JointInput {
    /// The rows, values in metres and radians ([`JointRow::q`]).
    pub rows: Vec<JointRow>,
    /// Per column: prismatic (its values are lengths).
    pub prismatic: Vec<bool>,
    /// Per row, where it sits in a sequence of motions ([`in_sequence`]); empty: every row
    /// outside any sequence (no approach direction known).
    pub contexts: Vec<SampleContext>,
    /// The rows' source as messages name it (the file's display name).
    pub name: String,
}

pub use crate::timed_rows::timed_contexts;

mod branch;
mod sessions;
mod warnings;

use sessions::session_frames;
pub use warnings::{backlash_warnings, drift_warning, limit_warnings};

/// Takes `input`'s rows as the order in which the robot moves through them (a robot program, a
/// measurement file): each joint's approach direction at a row is the sign of its last motion
/// before it, as `calibrate` reads a measurement file (`dh_calib::effects_order`); at the
/// first row, and until a joint first moves, its direction is unknown.
pub fn in_sequence(model: &CalibratedModel, input: &mut JointInput) {
    let rows: Vec<Vec<f64>> = input.rows.iter().map(|r| model.joints.rows(&r.q)).collect();
    input.contexts = dh_calib::effects_order::sequence_contexts(
        rows.iter()
            .zip(&input.rows)
            .map(|(q, r)| (q.as_slice(), r.config.as_deref())),
    );
}

/// Reads `path`'s joint values for `model`'s measured columns ([`crate::measured::DataFile`],
/// `units` the file's), or those of `given` (arrays a library caller hands over in `units`;
/// `path` then only names them in messages).
///
/// # Errors
/// The file cannot be read; a missing column, a bad cell (naming the file, line and column).
pub fn read_joints(
    path: &str,
    given: Option<&SampleArrays>,
    model: &CalibratedModel,
    units: DataUnits,
) -> Result<JointInput> {
    let columns = &model.joints.columns;
    let table = &model.loaded.table;
    let prismatic_rows: Vec<&str> = table
        .rows
        .iter()
        .filter(|r| r.kind == JointKind::Prismatic)
        .map(|r| r.name.as_str())
        .chain(table.rows.iter().filter_map(|r| {
            (r.kind == JointKind::Prismatic)
                .then_some(r.mimic.as_ref().map(|m| m.joint.as_str()))
                .flatten()
        }))
        .collect();
    let prismatic: Vec<bool> = columns
        .iter()
        .map(|c| prismatic_rows.contains(&c.as_str()))
        .collect();
    let names: Vec<String> = columns
        .iter()
        .zip(&prismatic)
        .filter(|(_, p)| **p)
        .map(|(c, _)| c.clone())
        .collect();
    let opts = units.csv_options(&names);
    let rows = match given {
        Some(arrays) => arrays
            .with_joints(columns)
            .and_then(|a| dh_calib::joints::joint_rows(&a, &opts))
            .map_err(|e| anyhow::anyhow!("{}: {e}", display_name(path)))?,
        None => {
            let file = DataFile::read(path)?;
            dh_calib::joints::parse_joint_values(&file.text, columns, &opts)
                .map_err(|e| anyhow::anyhow!("{}: {e}", file.name))?
        }
    };
    Ok(JointInput {
        rows,
        prismatic,
        contexts: Vec::new(),
        name: display_name(path),
    })
}

/// The frame of a prediction from `model` (read from the file shown as `origin`): `asked`, or
/// the device frame when the model has one, else the base link frame. With `session`, the
/// model is moved to that measurement session's device frame first
/// ([`CalibratedModel::in_session`]). Returns the frame and the warnings to show.
///
/// # Errors
/// An unknown session; the device frame asked of a model without one.
pub fn frame_of(
    model: &mut CalibratedModel,
    asked: Option<Frame>,
    session: Option<&str>,
    origin: &str,
) -> Result<(Frame, Vec<String>)> {
    let mut warnings = Vec::new();
    if let Some(name) = session {
        model.in_session(name).map_err(|e| {
            hinted(
                format!("{origin}: {e}"),
                "the sessions are listed in the `calibration` section's `sessions`",
            )
        })?;
        if asked == Some(Frame::Base) {
            warnings.push("--session changes the device frame only; --frame base predicts in the base link frame".to_string());
        }
    }
    let frame = match (asked, model.has_device) {
        (Some(Frame::Device), false) => {
            return Err(hinted(
                format!("{origin}: --frame device: the model has no device frame (no calibration section)"),
                "predict in the robot's base link frame (--frame base), or give the sheet calibrate --out wrote",
            ))
        }
        (Some(Frame::Device), true) | (None, true) => Frame::Device,
        (Some(Frame::Base), _) | (None, false) => Frame::Base,
    };
    Ok((frame, warnings))
}

/// What the rows predict.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Wanted {
    /// The tool pose ([`TOOL`]).
    Tool,
    /// These targets at every row.
    Targets(Vec<String>),
    /// Each row's own target (a measurement file's `target` column).
    RowTarget,
}

/// One prediction: a row's target position, or its tool pose.
#[derive(Clone, Debug)]
pub struct Predicted {
    /// The index of the joint row ([`JointInput::rows`]).
    pub row: usize,
    /// The target's name, or [`TOOL`].
    pub target: String,
    /// Position (m) in the prediction's frame.
    pub position: Vector3<f64>,
    /// The attitude (URDF roll, pitch, yaw; rad) of the tool ([`Wanted::Tool`]) or of a 6-DoF
    /// target (one calibrated with orientations); `None` for a point target.
    pub rpy: Option<[f64; 3]>,
    /// Standard uncertainty (1 sigma, first order): of the position's x, y, z (m), then, with
    /// an attitude, of the rotation about the frame's axes (rad); `None` without covariance.
    pub uncertainty: Option<Vec<f64>>,
}

/// The predictions of [`predict`].
#[derive(Clone, Debug)]
pub struct Predictions {
    /// The frame of every position.
    pub frame: Frame,
    /// What each row predicts.
    pub wanted: Wanted,
    /// Whether each row was predicted from its own measurement session's device frame (a
    /// joint file with a `session` column, in the device frame, without a session asked).
    pub per_session: bool,
    /// Whether the model has a covariance (then every prediction has its uncertainty).
    pub has_uncertainty: bool,
    /// Whether any prediction has an attitude (the tool, or a 6-DoF target).
    pub has_attitude: bool,
    /// One per joint row and target, in row order.
    pub predicted: Vec<Predicted>,
    /// What the caller should be told (the CLI prints them as `urdf-dh: warning:` lines, the
    /// Python package as warnings): joint values outside their joints' limits
    /// ([`limit_warnings`]).
    pub warnings: Vec<String>,
}

/// Predicts with `model` (in `frame`, see [`frame_of`]) at the joint rows of `input` (read
/// from the file shown as `joints_name`): the `targets` named, or [`TOOL`]; with none, each
/// row's own target (a measurement file whose every row names a target), else every target of
/// the calibration, else the tool. A tree's targets each ride on their own branch; with a
/// branch chosen ([`CalibratedModel::choose_branch`]) the default is that branch's targets
/// (else its tool) at every row, and the tool is that branch's (a tree of several branches
/// needs one chosen for the tool). `session`: the session asked (see [`frame_of`]); without it
/// and in the device frame, the rows of a joint file with a `session` column are predicted from
/// their sessions' device frames.
///
/// # Errors
/// An unknown target (naming the file's line, or `--targets`), targets and the tool together,
/// a target on another branch than the one chosen, the tool of a tree without a branch chosen,
/// sessions of the file unknown to the model; an effect of time without the rows' times
/// ([`timed_contexts`]).
pub fn predict(
    model: &CalibratedModel,
    frame: Frame,
    input: &JointInput,
    targets: &[String],
    session: Option<&str>,
    joints_name: &str,
    origin: &str,
) -> Result<Predictions> {
    let known = model.calibrated.targets();
    let index_of = |t: &str| -> Result<usize> {
        known.iter().position(|(n, _)| n == t).ok_or_else(|| {
            hinted(
                format!(
                    "{origin} has no target '{}'; it has {}",
                    escape(t),
                    if known.is_empty() {
                        "none".to_string()
                    } else {
                        known
                            .iter()
                            .map(|(n, _)| format!("'{}'", escape(n)))
                            .collect::<Vec<_>>()
                            .join(", ")
                    }
                ),
                "name the calibration's targets, or predict the tool frame with --targets tool",
            )
        })
    };
    // A tree's branch chosen with --branch: its targets only, its tool.
    let on_branch = |k: usize| {
        model
            .branch
            .is_none_or(|b| model.calibrated.target_branch(k) == b)
    };
    let per_row = targets.is_empty()
        && model.branch.is_none()
        && !known.is_empty()
        && input.rows.iter().all(|r| r.target.is_some());
    let wanted: Vec<String> = if targets.is_empty() {
        let own: Vec<String> = (0..known.len())
            .filter(|&k| on_branch(k))
            .map(|k| known[k].0.clone())
            .collect();
        if own.is_empty() {
            vec![TOOL.into()]
        } else {
            own
        }
    } else {
        targets.to_vec()
    };
    let tool = !per_row && wanted.iter().any(|t| t == TOOL);
    if tool && wanted.len() > 1 {
        anyhow::bail!("--targets: expected target names or 'tool', found both");
    }
    let chain = if tool {
        model.tool_chain("--targets tool", origin)?
    } else {
        0
    };
    // The targets' indices and names: one per row (each row's own), or the same for every row.
    let mut plan: Vec<(usize, String)> = Vec::new();
    if per_row {
        plan.reserve(input.rows.len());
        for r in &input.rows {
            let t = r.target.clone().unwrap_or_default();
            let k = index_of(&t).with_context(|| {
                format!(
                    "{}: line {}, column 'target'",
                    display_name(joints_name),
                    r.line
                )
            })?;
            plan.push((k, t));
        }
    } else if !tool {
        for t in &wanted {
            let k = index_of(t).context("--targets")?;
            if !on_branch(k) {
                return Err(hinted(
                    format!(
                        "--targets: target '{}' of {origin} rides on branch '{}', not on --branch '{}'",
                        escape(t),
                        escape(model.branch_name(model.calibrated.target_branch(k))),
                        escape(model.branch.map_or("", |b| model.branch_name(b)))
                    ),
                    "name the chosen branch's targets, or leave --targets out to predict them all",
                ));
            }
            plan.push((k, t.clone()));
        }
    }
    let (frames, row_frame, mut warnings) =
        session_frames(model, input, frame, session, joints_name, origin)?;
    warnings.extend(limit_warnings(model, input, joints_name));
    warnings.extend(backlash_warnings(model, input));
    let contexts = timed_contexts(model, input)?;
    warnings.extend(drift_warning(model, input, frame));
    // Blocks of rows on every core (each row depends on its own values alone).
    let blocks = input.rows.len().div_ceil(BLOCK_ROWS);
    let predict_block = |b: usize| -> Vec<Predicted> {
        let rows = b * BLOCK_ROWS..((b + 1) * BLOCK_ROWS).min(input.rows.len());
        let per = if per_row || tool { 1 } else { plan.len() };
        let mut out = Vec::with_capacity(rows.len() * per);
        // Each block predicts from its own copies when rows carry their place in a sequence.
        let mut sequenced: Vec<Option<Calibrated>> = vec![None; frames.len()];
        for i in rows {
            let f = row_frame.get(i).copied().unwrap_or(0);
            let c = match contexts.get(i) {
                Some(ctx) => {
                    let c = sequenced[f].get_or_insert_with(|| frames[f].clone());
                    c.set_context(ctx.clone());
                    &*c
                }
                None => &frames[f],
            };
            let targets: &[(usize, String)] = if per_row {
                plan.get(i).map_or(&[], std::slice::from_ref)
            } else {
                &plan
            };
            predict_row(
                c,
                frame,
                &model.joints.rows(&input.rows[i].q),
                i,
                tool.then_some(chain),
                targets,
                &mut out,
            );
        }
        out
    };
    let predicted: Vec<Predicted> = dh_core::parallel::map(blocks, predict_block)
        .ok_or_else(|| anyhow::anyhow!("a block of predictions was lost (a thread failed)"))?
        .into_iter()
        .flatten()
        .collect();
    Ok(Predictions {
        frame,
        wanted: if tool {
            Wanted::Tool
        } else if per_row {
            Wanted::RowTarget
        } else {
            Wanted::Targets(wanted)
        },
        per_session: frames.len() > 1,
        has_uncertainty: model.calibrated.has_covariance(),
        has_attitude: predicted.iter().any(|p| p.rpy.is_some()),
        predicted,
        warnings,
    })
}

/// Rows predicted per block of work on one core ([`predict`]).
const BLOCK_ROWS: usize = 4096;

/// The predictions of one row `i` (row values `q`) by `c` in `frame`: the tool pose of chain
/// `tool` (a tree's branch, 0 for a serial robot), or the `targets` (index, name), appended
/// to `out`.
fn predict_row(
    c: &Calibrated,
    frame: Frame,
    q: &[f64],
    i: usize,
    tool: Option<usize>,
    targets: &[(usize, String)],
    out: &mut Vec<Predicted>,
) {
    if let Some(chain) = tool {
        let pose = c.tool_of(q, chain, frame);
        let (xyz, rpy) = dh_core::pose::to_xyz_rpy(&pose);
        out.push(Predicted {
            row: i,
            target: TOOL.into(),
            position: Vector3::from(xyz),
            rpy: Some(rpy),
            uncertainty: c
                .tool_uncertainty_of(q, chain, frame)
                .map(|u| u.as_slice().to_vec()),
        });
        return;
    }
    for (k, name) in targets {
        // A 6-DoF target's orientation (and its uncertainty) follows its position.
        let rotation = c.target_orientation(q, *k, frame);
        let mut uncertainty = c
            .point_uncertainty(q, *k, frame)
            .map(|u| u.as_slice().to_vec());
        if let (Some(u), Some(r)) = (
            uncertainty.as_mut(),
            c.target_orientation_uncertainty(q, *k, frame),
        ) {
            u.extend(r.iter());
        }
        out.push(Predicted {
            row: i,
            target: name.clone(),
            position: c.point(q, *k, frame),
            rpy: rotation.map(|r| dh_core::pose::rpy_of(&r.to_rotation_matrix())),
            uncertainty,
        });
    }
}

/// The text of `predicted`, each prediction written by `row`, in blocks on every core and
/// joined in order (millions of rows write in a fraction of the time). A block whose thread
/// failed is written on the calling thread instead, so the text is always whole.
pub fn rows_text(predicted: &[Predicted], row: impl Fn(&mut String, &Predicted) + Sync) -> String {
    const BLOCK: usize = 8192;
    let write_block = |b: usize| -> String {
        let mut t = String::new();
        let range = b * BLOCK..((b + 1) * BLOCK).min(predicted.len());
        for p in predicted.get(range).unwrap_or_default() {
            row(&mut t, p);
        }
        t
    };
    let blocks = predicted.len().div_ceil(BLOCK);
    match dh_core::parallel::map(blocks, write_block) {
        Some(parts) => parts.concat(),
        None => (0..blocks).map(write_block).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Written in blocks on every core, the rows come out whole and in order, across block
    /// boundaries (8192 rows a block).
    #[test]
    fn rows_text_is_every_row_in_order() {
        let predicted: Vec<Predicted> = (0..20_000)
            .map(|row| Predicted {
                row,
                target: "t".into(),
                position: Vector3::new(row as f64, 0.0, 0.0),
                rpy: None,
                uncertainty: None,
            })
            .collect();
        let text = rows_text(&predicted, |t, p| t.push_str(&format!("{}\n", p.row)));
        let rows: Vec<usize> = text.lines().map(|l| l.parse().unwrap()).collect();
        assert_eq!(rows, (0..20_000).collect::<Vec<_>>());
        assert_eq!(rows_text(&[], |t, _| t.push('x')), "");
    }
}
