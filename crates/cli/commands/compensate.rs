//! `urdf-dh compensate`: the joint values with which the calibrated robot puts its tool where
//! the nominal model puts it at the commanded values (`dh_workflows::compensate`), with the error
//! that remains per pose.
//!
//! The output is a joint-value CSV in the input's units (readable by `predict` and
//! `compensate` itself), with `config` and the per-pose errors before and after.

use std::io::Write;
use std::path::Path;

use anyhow::Result;
use dh_workflows::calibrated::load_calibrated;
use dh_workflows::compensate::{
    failed_poses, same_joints, CompensateOptions, NominalModel, DEFAULT_MAX_CHANGE,
};
use dh_workflows::input::display_name;
use dh_workflows::measured::DataUnits;
use dh_workflows::units::{AngleUnit, LengthUnit};

use crate::commands::predict::{cell, joint_cell, quoted, read_joints};
use crate::error::Outcome;

/// Command-line arguments of `compensate`.
#[derive(Debug, clap::Args)]
pub struct CompensateCli {
    /// The nominal model the robot program was computed with (URDF with --base/--tip, or a
    /// DH sheet; for a calibrated tree, the nominal tree sheet).
    #[arg(long, value_name = "NOMINAL")]
    nominal: String,
    /// Base link of a URDF nominal model.
    #[arg(long)]
    base: Option<String>,
    /// Tip link of a URDF nominal model.
    #[arg(long)]
    tip: Option<String>,
    #[command(flatten)]
    pub xacro: crate::xacro_flags::XacroCli,
    /// The calibrated model (`calibrate --out`), with the nominal model's joints.
    #[arg(long, value_name = "CALIBRATED")]
    model: String,
    /// The commanded joint values: a CSV with one column per measured joint; `config` is
    /// carried over, other columns are ignored.
    #[arg(long, value_name = "Q.csv")]
    joints: String,
    /// With a calibrated tree: the branch whose tool is compensated (only the joints of its
    /// chain, the trunk's and the branch's, move) [default: the only branch].
    #[arg(long, value_name = "NAME")]
    branch: Option<String>,
    /// Match the tool's position only, not its orientation.
    #[arg(long)]
    position_only: bool,
    /// Largest change of a joint from its commanded value: radians (metres for prismatic
    /// joints), whatever the file's units [default: 0.05].
    #[arg(long, value_name = "CHANGE", value_parser = crate::guard::max_change)]
    max_change: Option<f64>,
    /// Unit of lengths in the joint file and the output.
    #[arg(long, value_enum, default_value_t = LengthUnit::M)]
    length_unit: LengthUnit,
    /// Unit of angles in the joint file and the output.
    #[arg(long, value_enum, default_value_t = AngleUnit::Rad)]
    angle_unit: AngleUnit,
    /// The CSV to write (`-` or absent: standard output).
    #[arg(long, value_name = "C.csv", value_parser = crate::guard::csv_output)]
    out: Option<String>,
    /// The joint rows are in the order the robot moves through them: each joint's approach
    /// direction (for a `backlash_direction` effect) is the sign of its commanded motion
    /// [default: unknown, compensated midway between the gear's flanks].
    #[arg(long)]
    sequence: bool,
}

/// What the CLI passes to [`compensate`].
#[derive(Clone, Debug)]
pub struct CompensateArgs {
    /// The nominal model.
    pub nominal: String,
    /// URDF base link of the nominal model.
    pub base: Option<String>,
    /// URDF tip link of the nominal model.
    pub tip: Option<String>,
    /// The calibrated model.
    pub model: String,
    /// Commanded joint values.
    pub joints: String,
    /// A calibrated tree's branch ([`CompensateCli`]'s `--branch`).
    pub branch: Option<String>,
    /// Position only.
    pub position_only: bool,
    /// Largest joint change in radians (metres for prismatic joints).
    pub max_change: f64,
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

impl CompensateCli {
    /// The arguments of [`compensate`].
    pub fn into_args(self) -> CompensateArgs {
        CompensateArgs {
            nominal: self.nominal,
            base: self.base,
            tip: self.tip,
            model: self.model,
            joints: self.joints,
            branch: self.branch,
            position_only: self.position_only,
            max_change: self.max_change.unwrap_or(DEFAULT_MAX_CHANGE),
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

/// Runs `compensate`. Exit 1 when a pose cannot be compensated (no convergence, or joint
/// values beyond their limits), naming each.
///
/// # Errors
/// Bad model or joint files, models with different joints, failed writes.
pub fn compensate(
    args: &CompensateArgs,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> Result<Outcome> {
    let mut model = load_calibrated(&args.model, None, None)?;
    let (n_origin, c_origin) = (display_name(&args.nominal), display_name(&args.model));
    if let Some(b) = &args.branch {
        model.choose_branch(b, &c_origin)?;
    }
    let chain = model.tool_chain("compensate", &c_origin)?;
    // A calibrated tree reaches what the nominal tree's branch reaches.
    let nominal = NominalModel::load(
        &args.nominal,
        args.base.as_deref(),
        args.tip.as_deref(),
        &model,
    )?;
    same_joints(&nominal.rows(), &model, (&n_origin, &c_origin))?;
    for w in model
        .loaded
        .warnings
        .iter()
        .filter(|w| !w.contains(": effects: "))
    {
        writeln!(err, "urdf-dh: warning: {w}")?;
    }
    let mut input = read_joints(&args.joints, args.given.as_ref(), &model, args.units)?;
    if args.sequence {
        dh_workflows::predict::in_sequence(&model, &mut input);
    }
    for w in dh_workflows::predict::backlash_warnings(&model, &input) {
        writeln!(err, "urdf-dh: warning: {w}")?;
    }
    let options = CompensateOptions {
        orientation: !args.position_only,
        max_change: args.max_change,
        chain,
        ..CompensateOptions::default()
    };
    let (lu, au) = (args.units.length, args.units.angle);
    let branch = if model.is_tree() {
        format!(", the tool of branch '{}'", model.branch_name(chain))
    } else {
        String::new()
    };
    let mut text = format!(
        "# compensated by urdf-dh compensate: {c_origin} reaching what {n_origin} reaches at the commanded values ({}{branch}); joints in {} ({} for prismatic), errors of the tool in the base link frame: position_* in {}, orientation_* in {}; status: compensated, or why not (max_change, unreachable, no_convergence, beyond_limits: those rows hold the nearest values found, not a correction)\n",
        if args.position_only { "position only" } else { "position and orientation" },
        au.symbol(),
        lu.symbol(),
        lu.symbol(),
        au.symbol()
    );
    let mut header: Vec<String> = model.joints.columns.iter().map(|n| quoted(n)).collect();
    header.extend(
        [
            "config",
            "position_before",
            "orientation_before",
            "position_error",
            "orientation_error",
            "status",
        ]
        .map(String::from),
    );
    text.push_str(&header.join(","));
    text.push('\n');
    let (mut before_max, mut after_max, mut rot_before_max, mut rot_after_max, mut change_max) =
        (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let mut sum_before = 0.0;
    let mut sum_after = 0.0;
    let rows = nominal.compensate(&model, &input, &options)?;
    let failed = failed_poses(&rows, args.max_change, lu, au);
    for (row, given) in rows.iter().zip(&input.rows) {
        let c = &row.result;
        before_max = before_max.max(c.error_before.0);
        rot_before_max = rot_before_max.max(c.error_before.1);
        after_max = after_max.max(c.position_error);
        rot_after_max = rot_after_max.max(c.orientation_error);
        sum_before += c.error_before.0 * c.error_before.0;
        sum_after += c.position_error * c.position_error;
        for ((a, b), p) in c.q.iter().zip(&given.q).zip(&input.prismatic) {
            if !p {
                change_max = change_max.max((a - b).abs());
            }
        }
        let mut cells: Vec<String> =
            c.q.iter()
                .zip(&input.prismatic)
                .map(|(v, p)| joint_cell(*v, *p, args.units))
                .collect();
        cells.push(quoted(&row.config));
        cells.push(cell(c.error_before.0 / lu.metres()));
        cells.push(cell(c.error_before.1 / au.radians()));
        cells.push(cell(c.position_error / lu.metres()));
        cells.push(cell(c.orientation_error / au.radians()));
        cells.push(row.status().to_string());
        text.push_str(&cells.join(","));
        text.push('\n');
    }
    let path = args.out.as_deref().unwrap_or(dh_workflows::output::STDIO);
    dh_workflows::output::write_all_or_stdout(&[(Path::new(path), text.as_bytes())], out)?;
    let report: &mut dyn Write = if path == dh_workflows::output::STDIO {
        err
    } else {
        out
    };
    let n = input.rows.len() as f64;
    writeln!(
        report,
        "compensated {} pose(s): {c_origin} against {n_origin}{}",
        input.rows.len(),
        if path == dh_workflows::output::STDIO {
            String::new()
        } else {
            format!(" -> {}", display_name(path))
        }
    )?;
    writeln!(
        report,
        "tool position error at the commanded values: RMS {:.6} max {:.6} {}; after compensation: RMS {:.3e} max {:.3e} {} (tolerance {:.0e} m)",
        (sum_before / n).sqrt() / lu.metres(),
        before_max / lu.metres(),
        lu.symbol(),
        (sum_after / n).sqrt() / lu.metres(),
        after_max / lu.metres(),
        lu.symbol(),
        options.position_tolerance
    )?;
    writeln!(
        report,
        "tool orientation error: max {:.6} {} before, {:.3e} {} after{}; largest joint change {:.6} {}",
        rot_before_max / au.radians(),
        au.symbol(),
        rot_after_max / au.radians(),
        au.symbol(),
        if args.position_only { " (not matched: --position-only)" } else { "" },
        change_max / au.radians(),
        au.symbol()
    )?;
    if failed.is_empty() {
        writeln!(report, "result: every pose compensated")?;
        Ok(Outcome::Pass)
    } else {
        let rows: usize = failed.iter().map(|f| f.lines.len()).sum();
        writeln!(
            report,
            "result: {} pose(s) not compensated{}:",
            failed.len(),
            if rows > failed.len() {
                format!(" ({rows} rows)")
            } else {
                String::new()
            }
        )?;
        for f in &failed {
            writeln!(report, "  {f}")?;
        }
        Ok(Outcome::Differs)
    }
}
