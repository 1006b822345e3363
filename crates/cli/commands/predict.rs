//! `urdf-dh predict`: the calibrated model's positions (or tool poses) at given joint values,
//! with each prediction's standard uncertainty from the calibration's covariance
//! (`dh_calib::predict`).
//!
//! The output is a measurement CSV (joint columns, `x,y,z`, `target`, `config`) that every
//! reader of measurements accepts, with the uncertainty in `u_x,u_y,u_z` (and, for the tool,
//! its attitude in `roll,pitch,yaw` with `u_rx,u_ry,u_rz`), columns those readers ignore.

use std::io::Write;
use std::path::Path;

use anyhow::{Context, Result};
use dh_calib::predict::{Calibrated, Frame};
use dh_core::JointKind;

use crate::calibrated::{load_calibrated, CalibratedModel};
use crate::error::{hinted, Outcome};
use crate::input::display_name;
use crate::measured::{DataFile, DataUnits};
use crate::units::{AngleUnit, LengthUnit};

/// The frame option.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum FrameChoice {
    /// The measuring device's frame of the calibration (its `calibration` section).
    Device,
    /// The robot's base link frame.
    Base,
}

/// Command-line arguments of `predict`.
#[derive(Debug, clap::Args)]
pub struct PredictCli {
    /// The calibrated model (`calibrate --out`), or any model (URDF with --base/--tip, or a
    /// sheet), taken as exact.
    #[arg(long, value_name = "MODEL")]
    model: String,
    /// Base link of a URDF chain.
    #[arg(long)]
    base: Option<String>,
    /// Tip link of a URDF chain.
    #[arg(long)]
    tip: Option<String>,
    /// Joint values: a CSV with one column per measured joint (a measurement file will do);
    /// other columns are ignored, `config` is carried over.
    #[arg(long, value_name = "Q.csv")]
    joints: String,
    /// What to predict: target names (the calibration's), or `tool` for the tip frame's pose
    /// [default: the calibration's targets, else tool].
    #[arg(long, value_name = "NAME,...|tool", value_delimiter = ',')]
    targets: Vec<String>,
    /// Frame of the predictions [default: device when the model has a calibration section,
    /// else base].
    #[arg(long, value_enum)]
    frame: Option<FrameChoice>,
    /// With a calibration of several measurement sessions: predict in this session's device
    /// frame (one of the `calibration` section's `sessions`) [default: the first session's,
    /// the model's device frame].
    #[arg(long, value_name = "NAME")]
    session: Option<String>,
    /// Unit of lengths in the joint file and the output.
    #[arg(long, value_enum, default_value_t = LengthUnit::M)]
    length_unit: LengthUnit,
    /// Unit of angles in the joint file and the output.
    #[arg(long, value_enum, default_value_t = AngleUnit::Rad)]
    angle_unit: AngleUnit,
    /// The CSV to write (`-` or absent: standard output).
    #[arg(long, value_name = "P.csv")]
    out: Option<String>,
}

/// What the CLI passes to [`predict`].
#[derive(Clone, Debug)]
pub struct PredictArgs {
    /// See [`PredictCli`].
    pub model: String,
    /// URDF base link.
    pub base: Option<String>,
    /// URDF tip link.
    pub tip: Option<String>,
    /// Joint-value file.
    pub joints: String,
    /// Targets, or `["tool"]`; empty: the default.
    pub targets: Vec<String>,
    /// Frame; `None`: the default.
    pub frame: Option<FrameChoice>,
    /// Measurement session of the device frame; `None`: the first.
    pub session: Option<String>,
    /// Units of the joint file and the output.
    pub units: DataUnits,
    /// Output path (`None` or `-`: standard output).
    pub out: Option<String>,
    /// Joint values a library caller hands over as arrays instead of the file `joints` (which
    /// then only names them in messages); `None` on the command line.
    pub given: Option<dh_calib::csv::SampleArrays>,
}

impl PredictCli {
    /// The arguments of [`predict`].
    pub fn into_args(self) -> PredictArgs {
        PredictArgs {
            model: self.model,
            base: self.base,
            tip: self.tip,
            joints: self.joints,
            targets: self.targets,
            frame: self.frame,
            session: self.session,
            units: DataUnits {
                length: self.length_unit,
                angle: self.angle_unit,
            },
            out: self.out,
            given: None,
        }
    }
}

/// The name that asks for the tip frame's pose.
pub const TOOL: &str = "tool";

/// Joint values of a joint file in the model's measured columns, with their lines and configs.
pub(crate) struct JointInput {
    pub(crate) rows: Vec<dh_calib::joints::JointRow>,
    /// Per column: prismatic.
    pub(crate) prismatic: Vec<bool>,
}

/// Reads `path`'s joint values for `model`'s measured columns, or those of `given` (arrays a
/// library caller handed over; `path` then names them in messages).
pub(crate) fn read_joints(
    path: &str,
    given: Option<&dh_calib::csv::SampleArrays>,
    model: &CalibratedModel,
    units: DataUnits,
) -> Result<JointInput> {
    let columns = &model.joints.columns;
    let prismatic_rows: Vec<&str> = model
        .loaded
        .table
        .rows
        .iter()
        .filter(|r| r.kind == JointKind::Prismatic)
        .map(|r| r.name.as_str())
        .chain(model.loaded.table.rows.iter().filter_map(|r| {
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
    Ok(JointInput { rows, prismatic })
}

/// A number as the output writes it: shortest round-trip form.
pub(crate) fn cell(v: f64) -> String {
    format!("{v:?}")
}

/// A joint value in the output's units.
pub(crate) fn joint_cell(v: f64, prismatic: bool, units: DataUnits) -> String {
    if prismatic {
        cell(v / units.length.metres())
    } else {
        cell(v / units.angle.radians())
    }
}

/// Quotes a name cell when needed (as the measurement writer does).
pub(crate) fn quoted(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) || s.trim() != s || s.starts_with('#') || s.is_empty() {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// Runs `predict`.
///
/// # Errors
/// Bad model or joint files (naming the file, line and column), unknown targets, a device
/// frame asked of a model without one, failed writes.
pub fn predict(args: &PredictArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    let mut model = load_calibrated(&args.model, args.base.as_deref(), args.tip.as_deref())?;
    let origin = display_name(&args.model);
    if let Some(name) = &args.session {
        model.in_session(name).map_err(|e| {
            hinted(
                format!("{origin}: {e}"),
                "the sessions are listed in the `calibration` section's `sessions`",
            )
        })?;
        if args.frame == Some(FrameChoice::Base) {
            writeln!(err, "urdf-dh: warning: --session changes the device frame only; --frame base predicts in the base link frame")?;
        }
    }
    for w in model
        .loaded
        .warnings
        .iter()
        .filter(|w| !w.contains(": effects: "))
    {
        writeln!(err, "urdf-dh: warning: {w}")?;
    }
    let frame = match (args.frame, model.has_device) {
        (Some(FrameChoice::Device), false) => {
            return Err(hinted(
                format!("{origin}: --frame device: the model has no device frame (no calibration section)"),
                "predict in the robot's base link frame (--frame base), or give the sheet calibrate --out wrote",
            ))
        }
        (Some(FrameChoice::Device), true) | (None, true) => Frame::Device,
        (Some(FrameChoice::Base), _) | (None, false) => Frame::Base,
    };
    let input = read_joints(&args.joints, args.given.as_ref(), &model, args.units)?;
    let known = model.calibrated.targets();
    let index_of = |t: &str| -> Result<usize> {
        known.iter().position(|(n, _)| n == t).ok_or_else(|| {
            hinted(
                format!(
                    "{origin} has no target '{}'; it has {}",
                    crate::guard::escape(t),
                    if known.is_empty() {
                        "none".to_string()
                    } else {
                        known
                            .iter()
                            .map(|(n, _)| format!("'{}'", crate::guard::escape(n)))
                            .collect::<Vec<_>>()
                            .join(", ")
                    }
                ),
                "name the calibration's targets, or predict the tool frame with --targets tool",
            )
        })
    };
    // What each row predicts: the named targets, the tool, or (a measurement file, no
    // --targets) the row's own target.
    let per_row = args.targets.is_empty()
        && !known.is_empty()
        && input.rows.iter().all(|r| r.target.is_some());
    let wanted: Vec<String> = if args.targets.is_empty() {
        if known.is_empty() {
            vec![TOOL.into()]
        } else {
            known.iter().map(|(n, _)| n.clone()).collect()
        }
    } else {
        args.targets.clone()
    };
    let tool = !per_row && wanted.iter().any(|t| t == TOOL);
    if tool && wanted.len() > 1 {
        anyhow::bail!("--targets: expected target names or 'tool', found both");
    }
    let mut plan: Vec<Vec<(usize, String)>> = Vec::with_capacity(input.rows.len());
    if per_row {
        for r in &input.rows {
            let t = r.target.clone().unwrap_or_default();
            let k = index_of(&t).with_context(|| {
                format!(
                    "{}: line {}, column 'target'",
                    display_name(&args.joints),
                    r.line
                )
            })?;
            plan.push(vec![(k, t)]);
        }
    } else if !tool {
        let mut indices = Vec::new();
        for t in &wanted {
            indices.push((index_of(t).context("--targets")?, t.clone()));
        }
        plan = vec![indices; input.rows.len()];
    }
    let (frames, row_frame) = session_frames(&model, &input, frame, args, &origin)?;
    let seen = Seen {
        frames: &frames,
        row_frame: &row_frame,
    };
    let text = render(&model, &input, frame, tool, &plan, args, &origin, &seen);
    let path = args.out.as_deref().unwrap_or(crate::output::STDIO);
    crate::output::write_all_or_stdout(&[(Path::new(path), text.as_bytes())], out)?;
    let uncertainty = if model.calibrated.has_covariance() {
        "with standard uncertainties from the calibration's covariance"
    } else {
        "without uncertainty (the model has no covariance: calibrate --out writes one)"
    };
    let report: &mut dyn Write = if path == crate::output::STDIO {
        err
    } else {
        out
    };
    writeln!(
        report,
        "predicted {} pose(s) x {} of {origin} in the {} frame, {uncertainty}{}",
        input.rows.len(),
        if tool {
            "the tool pose".to_string()
        } else if per_row {
            "each row's own target".to_string()
        } else {
            format!("{} target(s)", wanted.len())
        },
        match frame {
            Frame::Device => "device",
            Frame::Base => "base link",
        },
        if path == crate::output::STDIO {
            String::new()
        } else {
            format!(": {}", display_name(path))
        }
    )?;
    Ok(Outcome::Pass)
}

/// The calibrated robot as each row sees it: `frames[row_frame[i]]` for row `i`.
struct Seen<'a> {
    frames: &'a [Calibrated],
    row_frame: &'a [usize],
}

impl Seen<'_> {
    /// Whether rows are predicted from their own sessions' frames.
    fn per_session(&self) -> bool {
        self.frames.len() > 1
    }
}

/// The robot each row is predicted with. Without `--session`, in the device frame, a joint
/// file with a `session` column (a measurement file of several sessions) has each row
/// predicted from its own session's device frame: the model's `sessions`, and the model's
/// device frame for the first session, whose name the model does not hold (so at most one of
/// the file's sessions may be missing from the model).
fn session_frames(
    model: &CalibratedModel,
    input: &JointInput,
    frame: Frame,
    args: &PredictArgs,
    origin: &str,
) -> Result<(Vec<Calibrated>, Vec<usize>)> {
    let first = vec![model.calibrated.clone()];
    let mut names: Vec<&str> = Vec::new();
    for r in &input.rows {
        if let Some(s) = r.session.as_deref() {
            if !names.contains(&s) {
                names.push(s);
            }
        }
    }
    if args.session.is_some()
        || frame == Frame::Base
        || names.is_empty()
        || model.sessions.is_empty()
    {
        return Ok((first, vec![0; input.rows.len()]));
    }
    let unknown: Vec<&str> = names
        .iter()
        .copied()
        .filter(|n| !model.sessions.iter().any(|(m, _)| m == n))
        .collect();
    if unknown.len() > 1 {
        return Err(hinted(
            format!(
                "{}: sessions {} are not in {origin}, which holds the first session's device frame and those of {}: at most one of the file's sessions can be the first",
                display_name(&args.joints),
                unknown
                    .iter()
                    .map(|n| format!("'{}'", crate::guard::escape(n)))
                    .collect::<Vec<_>>()
                    .join(", "),
                model.session_list()
            ),
            "predict every row from one session's frame with --session NAME (or without it, the first's)",
        ));
    }
    let mut frames = first;
    let mut index: Vec<(&str, usize)> = Vec::new();
    for n in names {
        if unknown.contains(&n) {
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
    Ok((frames, row_frame))
}

#[allow(clippy::too_many_arguments)]
fn render(
    model: &CalibratedModel,
    input: &JointInput,
    frame: Frame,
    tool: bool,
    plan: &[Vec<(usize, String)>],
    args: &PredictArgs,
    origin: &str,
    seen: &Seen<'_>,
) -> String {
    let units = args.units;
    let lu = units.length;
    let au = units.angle;
    let with_u = model.calibrated.has_covariance();
    let sessions = input.rows.iter().any(|r| r.session.is_some());
    let mut text = format!(
        "# predicted by urdf-dh predict from {origin} in the {} frame; joints in {} ({} for prismatic), x,y,z in {}{}{}\n",
        match (frame, &args.session) {
            (Frame::Device, Some(s)) => format!("device (session '{}')", crate::guard::escape(s)),
            (Frame::Device, None) if seen.per_session() => {
                "device (each row's session's)".to_string()
            }
            (Frame::Device, None) => "device".to_string(),
            (Frame::Base, _) => "base link".to_string(),
        },
        au.symbol(),
        lu.symbol(),
        lu.symbol(),
        if tool {
            format!(", roll,pitch,yaw in {} (URDF rpy)", au.symbol())
        } else {
            String::new()
        },
        if with_u {
            format!(
                "; u_* standard uncertainty (1 sigma, first order from the calibration's covariance){}",
                if tool {
                    format!(", u_rx,u_ry,u_rz about the frame's axes in {}", au.symbol())
                } else {
                    String::new()
                }
            )
        } else {
            String::new()
        }
    );
    let mut header: Vec<String> = model.joints.columns.iter().map(|n| quoted(n)).collect();
    header.extend(["x", "y", "z"].map(String::from));
    if tool {
        header.extend(["roll", "pitch", "yaw"].map(String::from));
    }
    header.extend(["target", "config"].map(String::from));
    if sessions {
        header.push("session".into());
    }
    if with_u {
        header.extend(["u_x", "u_y", "u_z"].map(String::from));
        if tool {
            header.extend(["u_rx", "u_ry", "u_rz"].map(String::from));
        }
    }
    text.push_str(&header.join(","));
    text.push('\n');
    let length = |v: f64| cell(v / lu.metres());
    let angle = |v: f64| cell(v / au.radians());
    for (i, row) in input.rows.iter().enumerate() {
        let c = &seen.frames[seen.row_frame.get(i).copied().unwrap_or(0)];
        let q = model.joints.rows(&row.q);
        let joints: Vec<String> = row
            .q
            .iter()
            .zip(&input.prismatic)
            .map(|(v, p)| joint_cell(*v, *p, units))
            .collect();
        // The cells after the target: the config, and the session when the file has them.
        let mut ids = vec![quoted(
            &row.config
                .clone()
                .unwrap_or_else(|| format!("line{}", row.line)),
        )];
        if sessions {
            ids.push(row.session.as_deref().map(quoted).unwrap_or_default());
        }
        let mut lines: Vec<Vec<String>> = Vec::new();
        if tool {
            let pose = c.tool(&q, frame);
            let (xyz, rpy) = dh_core::pose::to_xyz_rpy(&pose);
            let mut cells = joints.clone();
            cells.extend(xyz.iter().map(|v| length(*v)));
            cells.extend(rpy.iter().map(|v| angle(*v)));
            cells.push(TOOL.to_string());
            cells.extend(ids.iter().cloned());
            if let Some(u) = c.tool_uncertainty(&q, frame) {
                cells.extend((0..3).map(|i| length(u[i])));
                cells.extend((3..6).map(|i| angle(u[i])));
            }
            lines.push(cells);
        } else {
            for (k, name) in plan.get(i).into_iter().flatten() {
                let p = c.point(&q, *k, frame);
                let mut cells = joints.clone();
                cells.extend(p.iter().map(|v| length(*v)));
                cells.push(quoted(name));
                cells.extend(ids.iter().cloned());
                if let Some(u) = c.point_uncertainty(&q, *k, frame) {
                    cells.extend(u.iter().map(|v| length(*v)));
                }
                lines.push(cells);
            }
        }
        for l in lines {
            text.push_str(&l.join(","));
            text.push('\n');
        }
    }
    text
}
