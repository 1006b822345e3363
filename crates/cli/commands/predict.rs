//! `urdf-dh predict`: the calibrated model's positions (or tool poses) at given joint values,
//! with each prediction's standard uncertainty from the calibration's covariance
//! (`dh_workflows::predict`).
//!
//! The output is a measurement CSV (joint columns, `x,y,z`, `target`, `config`) that every
//! reader of measurements accepts, with the uncertainty in `u_x,u_y,u_z` (and, for the tool,
//! its attitude in `roll,pitch,yaw` with `u_rx,u_ry,u_rz`), columns those readers ignore.

use std::io::Write;
use std::path::Path;

use anyhow::Result;
use dh_workflows::calibrated::{load_calibrated, CalibratedModel};
use dh_workflows::input::display_name;
use dh_workflows::measured::DataUnits;
use dh_workflows::predict::{frame_of, rows_text, Frame, Predictions, Wanted};
use dh_workflows::units::{AngleUnit, LengthUnit};

use crate::error::Outcome;

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
    #[command(flatten)]
    pub xacro: crate::xacro_flags::XacroCli,
    /// Joint values: a CSV with one column per measured joint (a measurement file will do);
    /// other columns are ignored, `config` is carried over.
    #[arg(long, value_name = "Q.csv")]
    joints: String,
    /// What to predict: target names (the calibration's), or `tool` for the tip frame's pose
    /// [default: the calibration's targets, else tool].
    #[arg(long, value_name = "NAME,...|tool", value_delimiter = ',')]
    targets: Vec<String>,
    /// With a calibrated tree: the branch whose targets (by default) or tool (`--targets
    /// tool`) are predicted [default: every target on its own branch; the tool needs one
    /// chosen when the tree has several branches].
    #[arg(long, value_name = "NAME")]
    branch: Option<String>,
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
    #[arg(long, value_name = "P.csv", value_parser = crate::guard::csv_output)]
    out: Option<String>,
    /// The joint rows are in the order the robot moves through them: each joint's approach
    /// direction (for a `backlash_direction` effect) is the sign of its last motion, as
    /// calibrate reads a measurement file [default: unknown, the backlash added to the
    /// uncertainty].
    #[arg(long)]
    sequence: bool,
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
    /// A calibrated tree's branch ([`PredictCli`]'s `--branch`); `None`: every branch.
    pub branch: Option<String>,
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
    pub given: Option<dh_workflows::measured::SampleArrays>,
    /// The rows are a sequence of motions ([`dh_workflows::predict::in_sequence`]).
    pub sequence: bool,
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
            branch: self.branch,
            frame: self.frame,
            session: self.session,
            units: DataUnits {
                length: self.length_unit,
                angle: self.angle_unit,
            },
            out: self.out,
            given: None,
            sequence: self.sequence,
        }
    }
}

pub use dh_workflows::predict::{read_joints, JointInput, TOOL};

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

/// Appends `s` to `t` as [`quoted`] writes it, without a copy when it needs no quotes.
fn push_quoted(t: &mut String, s: &str) {
    if s.contains([',', '"', '\n', '\r']) || s.trim() != s || s.starts_with('#') || s.is_empty() {
        t.push_str(&quoted(s));
    } else {
        t.push_str(s);
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
    if let Some(b) = &args.branch {
        model.choose_branch(b, &origin)?;
    }
    let asked = args.frame.map(|f| match f {
        FrameChoice::Device => Frame::Device,
        FrameChoice::Base => Frame::Base,
    });
    let (frame, warnings) = frame_of(&mut model, asked, args.session.as_deref(), &origin)?;
    for w in warnings.iter().chain(
        model
            .loaded
            .warnings
            .iter()
            .filter(|w| !w.contains(": effects: ")),
    ) {
        writeln!(err, "urdf-dh: warning: {w}")?;
    }
    let mut input = read_joints(&args.joints, args.given.as_ref(), &model, args.units)?;
    if args.sequence {
        dh_workflows::predict::in_sequence(&model, &mut input);
    }
    let predictions = dh_workflows::predict::predict(
        &model,
        frame,
        &input,
        &args.targets,
        args.session.as_deref(),
        &args.joints,
        &origin,
    )?;
    for w in &predictions.warnings {
        writeln!(err, "urdf-dh: warning: {w}")?;
    }
    let text = render(&model, &input, &predictions, args, &origin);
    let path = args.out.as_deref().unwrap_or(dh_workflows::output::STDIO);
    dh_workflows::output::write_all_or_stdout(&[(Path::new(path), text.as_bytes())], out)?;
    let uncertainty = if predictions.has_uncertainty {
        "with standard uncertainties from the calibration's covariance"
    } else {
        "without uncertainty (the model has no covariance: calibrate --out writes one)"
    };
    let report: &mut dyn Write = if path == dh_workflows::output::STDIO {
        err
    } else {
        out
    };
    writeln!(
        report,
        "predicted {} pose(s) x {} of {origin} in the {} frame, {uncertainty}{}",
        input.rows.len(),
        match &predictions.wanted {
            Wanted::Tool => "the tool pose".to_string(),
            Wanted::RowTarget => "each row's own target".to_string(),
            Wanted::Targets(t) => format!("{} target(s)", t.len()),
        },
        match frame {
            Frame::Device => "device",
            Frame::Base => "base link",
        },
        if path == dh_workflows::output::STDIO {
            String::new()
        } else {
            format!(": {}", display_name(path))
        }
    )?;
    Ok(Outcome::Pass)
}

/// The CSV of `predictions` (from `input`'s joint rows), in `args`' units.
fn render(
    model: &CalibratedModel,
    input: &JointInput,
    predictions: &Predictions,
    args: &PredictArgs,
    origin: &str,
) -> String {
    let units = args.units;
    let lu = units.length;
    let au = units.angle;
    // Attitude columns for the tool and for 6-DoF targets (empty cells for point targets).
    let attitude = predictions.has_attitude;
    let with_u = predictions.has_uncertainty;
    let sessions = input.rows.iter().any(|r| r.session.is_some());
    let mut text = format!(
        "# predicted by urdf-dh predict from {origin} in the {} frame; joints in {} ({} for prismatic), x,y,z in {}{}{}\n",
        match (predictions.frame, &args.session) {
            (Frame::Device, Some(s)) => format!("device (session '{}')", crate::guard::escape(s)),
            (Frame::Device, None) if predictions.per_session => {
                "device (each row's session's)".to_string()
            }
            (Frame::Device, None) => "device".to_string(),
            (Frame::Base, _) => "base link".to_string(),
        },
        au.symbol(),
        lu.symbol(),
        lu.symbol(),
        if attitude {
            format!(", roll,pitch,yaw in {} (URDF rpy)", au.symbol())
        } else {
            String::new()
        },
        if with_u {
            format!(
                "; u_* standard uncertainty (1 sigma, first order from the calibration's covariance){}",
                if attitude {
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
    if attitude {
        header.extend(["roll", "pitch", "yaw"].map(String::from));
    }
    header.extend(["target", "config"].map(String::from));
    if sessions {
        header.push("session".into());
    }
    if with_u {
        header.extend(["u_x", "u_y", "u_z"].map(String::from));
        if attitude {
            header.extend(["u_rx", "u_ry", "u_rz"].map(String::from));
        }
    }
    text.push_str(&header.join(","));
    text.push('\n');
    // Written on every core, joined in order.
    text.push_str(&rows_text(&predictions.predicted, |t, p| {
        write_row(t, p, input, units, attitude, sessions)
    }));
    text
}

/// Appends the CSV row of prediction `p` (of `input`'s row `p.row`) to `t`: the cells
/// [`render`]'s header names, each number in its shortest round-trip form ([`cell`]).
fn write_row(
    t: &mut String,
    p: &dh_workflows::predict::Predicted,
    input: &JointInput,
    units: DataUnits,
    attitude: bool,
    sessions: bool,
) {
    use std::fmt::Write as _;
    let Some(row) = input.rows.get(p.row) else {
        return;
    };
    let (lm, ar) = (units.length.metres(), units.angle.radians());
    let mut first = true;
    let mut num = |t: &mut String, v: f64| {
        if !std::mem::take(&mut first) {
            t.push(',');
        }
        let _ = write!(t, "{v:?}");
    };
    for (v, pr) in row.q.iter().zip(&input.prismatic) {
        num(t, if *pr { v / lm } else { v / ar });
    }
    for v in p.position.iter() {
        num(t, v / lm);
    }
    match p.rpy {
        Some(rpy) => rpy.iter().for_each(|v| num(t, v / ar)),
        None if attitude => t.push_str(",,,"),
        None => {}
    }
    t.push(',');
    push_quoted(t, &p.target);
    // The config, and the session when the file has them.
    t.push(',');
    match &row.config {
        Some(c) => push_quoted(t, c),
        None => {
            let _ = write!(t, "line{}", row.line);
        }
    }
    if sessions {
        t.push(',');
        if let Some(s) = row.session.as_deref() {
            push_quoted(t, s);
        }
    }
    if let Some(u) = &p.uncertainty {
        u.iter().take(3).for_each(|v| num(t, v / lm));
        u.iter().skip(3).for_each(|v| num(t, v / ar));
        if attitude && u.len() == 3 {
            t.push_str(",,,");
        }
    }
    t.push('\n');
}
