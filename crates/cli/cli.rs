//! Command-line definitions and the exit-code contract: 0 success, 1 a check or verification
//! found a difference, 2 bad input or usage.

use std::ffi::OsString;
use std::io::Write;

use clap::{Args, Parser, Subcommand};
use dh_workflows::geometry::{Convention, Tolerance};
use dh_workflows::output::check_destinations;
use dh_workflows::render::Format;
use dh_workflows::sheet::ConventionDoc;
use dh_workflows::units::{AngleUnit, LengthUnit};

use crate::commands::batch::{batch, BatchArgs};
use crate::commands::check::{check, CheckArgs, CheckFormat, CHECK_ANGULAR, CHECK_LINEAR};
use crate::commands::convert::{convert, ConvertArgs};
use crate::commands::extract::{extract, ExtractArgs};
use crate::commands::to_urdf::{to_urdf, ToUrdfArgs};
use crate::commands::{calibrate, compensate, cpa, import, predict, simulate};
use crate::error::Outcome;
use crate::guard;
use crate::xacro_flags::XacroCli;

/// Denavit-Hartenberg parameters of serial manipulators: from URDFs, vendor DH sheets and
/// measurements of the real arm.
#[derive(Debug, Parser)]
#[command(name = "urdf-dh", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Extract a DH table (with base and tool transforms) from a URDF chain and prove it by
    /// forward kinematics against the URDF at many joint values.
    #[command(
        after_help = "EXAMPLES:\n  urdf-dh extract robot.urdf   # root link to the arm's tip, standard DH, text\n  urdf-dh extract robot.urdf --tip tool0 --convention modified --angle-unit deg\n  urdf-dh extract robot.urdf --format yaml > robot-dh.yaml   # the sheet format, proved as written\n  urdf-dh extract robot.urdf.xacro --xacro-arg arm:=gen3 \\\n    --package arm_description=../arm_description"
    )]
    Extract(ExtractCli),
    /// Extract many chains of many URDFs in one process (a list of `ROBOT [BASE [TIP]]` lines),
    /// one JSON line per table, each proved as `extract` proves it.
    #[command(
        after_help = "EXAMPLES:\n  printf 'ur5/robot.urdf\\npanda/robot.urdf base_link panda_link8\\n' > chains.list\n  urdf-dh batch chains.list --convention both > tables.jsonl"
    )]
    Batch(BatchCli),
    /// Check a URDF against a vendor's DH sheet: exit 0 when they describe the same kinematics,
    /// 1 naming every joint and parameter that differs.
    #[command(
        after_help = "EXAMPLES:\n  urdf-dh check robot.urdf --sheet vendor-dh.yaml --tip tool0\n  urdf-dh check robot.urdf --sheet vendor-dh.yaml --format json > report.json || cat report.json"
    )]
    Check(CheckCli),
    /// Convert a sheet to the other DH convention (or other units), exactly.
    #[command(
        after_help = "EXAMPLES:\n  urdf-dh convert vendor-dh.yaml --to modified\n  urdf-dh convert vendor-dh.yaml --to standard --length-unit mm --angle-unit deg --format markdown\n  urdf-dh convert ur5e --deltas calibration.conf > calibrated.yaml"
    )]
    Convert(ConvertCli),
    /// Write a URDF whose kinematics equal a DH sheet.
    #[command(
        after_help = "EXAMPLES:\n  urdf-dh to-urdf vendor-dh.yaml > robot.urdf\n  urdf-dh to-urdf vendor-dh.yaml --name my_arm --base-link base --tip-link flange > my_arm.urdf"
    )]
    ToUrdf(ToUrdfCli),
    /// Read a published measurement dataset as its authors left it and write the canonical
    /// measurement CSV.
    #[command(after_help = "EXAMPLES:\n  urdf-dh import dataset/poses.txt --out measured.csv")]
    Import(import::ImportCli),
    /// Fit a model to measured points: nominal, geometric and effect steps, each with its
    /// residuals on calibration and validation data.
    #[command(
        after_help = "EXAMPLES:\n  urdf-dh calibrate --model nominal.yaml --data measured.csv\n  urdf-dh calibrate --model nominal.yaml --data measured.csv --effects auto --out calibrated.yaml"
    )]
    Calibrate(calibrate::CalibrateCli),
    /// Predict a calibrated model's target positions (or tool poses) at given joint values,
    /// with each prediction's standard uncertainty.
    #[command(
        after_help = "EXAMPLES:\n  urdf-dh predict --model calibrated.yaml --joints poses.csv --out predicted.csv\n  urdf-dh predict --model calibrated.yaml --joints poses.csv --targets tool --frame base \\\n    --length-unit mm --angle-unit deg"
    )]
    Predict(predict::PredictCli),
    /// Correct a robot program's joint values so that the calibrated robot puts its tool where
    /// the nominal model does; exit 1 naming any pose that cannot be compensated.
    #[command(
        after_help = "EXAMPLES:\n  urdf-dh compensate --nominal vendor.yaml --model calibrated.yaml --joints program.csv \\\n    --out corrected.csv\n  urdf-dh compensate --nominal robot.urdf --tip tool0 --model calibrated.yaml \\\n    --joints program.csv --position-only"
    )]
    Compensate(compensate::CompensateCli),
    /// Circle-point analysis: joint axes from sweeps of one joint at a time, and their DH table.
    #[command(
        after_help = "EXAMPLES:\n  urdf-dh cpa sweeps.csv --format yaml > measured-dh.yaml\n  urdf-dh cpa sweeps.csv --model robot.urdf --plot sweeps.svg"
    )]
    Cpa(cpa::CpaCli),
    /// Simulate measurements of a model with known errors, noise and effects.
    #[command(
        after_help = "EXAMPLES:\n  urdf-dh simulate --model vendor.yaml --poses 200 --noise 0.00005 --out measured.csv \\\n    --truth truth.yaml"
    )]
    Simulate(simulate::SimulateCli),
    /// Print a shell completion script (bash, zsh, fish, elvish, powershell) to stdout.
    #[command(
        after_help = "EXAMPLES:\n  urdf-dh completions bash > ~/.local/share/bash-completion/completions/urdf-dh\n  urdf-dh completions zsh > ~/.zfunc/_urdf-dh"
    )]
    Completions {
        /// The shell.
        shell: clap_complete::Shell,
    },
    /// Print the manual page of urdf-dh or of one of its commands (roff), or write every page
    /// into a directory.
    #[command(
        after_help = "EXAMPLES:\n  urdf-dh man | man -l -\n  urdf-dh man extract > urdf-dh-extract.1\n  urdf-dh man --dir ~/.local/share/man/man1   # then: man urdf-dh-extract"
    )]
    Man(crate::manual::ManCli),
}

#[derive(Debug, Args)]
struct ConvertCli {
    /// The DH sheet (YAML or JSON), - for standard input, or the name of a shipped nominal table
    /// (ur3, ur5, ur10, ur3e, ur5e, ur10e, ur16e, ur20, ur30).
    sheet: String,
    /// Target convention [default with --deltas: standard].
    #[arg(long, value_enum, required_unless_present = "deltas")]
    to: Option<ConventionDoc>,
    /// A UR controller's calibration.conf: write the sheet calibrated by its [mounting] deltas
    /// (standard DH delta_theta, delta_a, delta_d, delta_alpha).
    #[arg(long, value_name = "CALIBRATION.CONF")]
    deltas: Option<String>,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Yaml)]
    format: Format,
    /// Length unit of the output [default: the sheet's].
    #[arg(long, value_enum)]
    length_unit: Option<LengthUnit>,
    /// Angle unit of the output [default: the sheet's].
    #[arg(long, value_enum)]
    angle_unit: Option<AngleUnit>,
    #[command(flatten)]
    verify: VerifyCli,
}

/// The check of a written artefact against its source.
#[derive(Debug, Args)]
struct VerifyCli {
    /// Random joint-value samples of the check of what is written (the zero pose is always the
    /// first).
    #[arg(long, value_name = "N", default_value_t = 1000, value_parser = guard::samples)]
    samples: usize,
    /// Seed of the check's sampler.
    #[arg(long, value_name = "S", default_value_t = 0)]
    seed: u64,
}

#[derive(Debug, Args)]
struct ToUrdfCli {
    /// The DH sheet (YAML or JSON), or - for standard input.
    sheet: String,
    /// Robot name [default: the sheet's `robot`].
    #[arg(long)]
    name: Option<String>,
    /// Name of the base link.
    #[arg(long, default_value = "base_link")]
    base_link: String,
    /// Name of the tip link.
    #[arg(long, default_value = "tool0")]
    tip_link: String,
    #[command(flatten)]
    verify: VerifyCli,
}

/// Options shared by every command that reads a URDF chain.
#[derive(Debug, Args)]
struct ChainCli {
    /// Base link of the chain [default: the URDF's root link].
    #[arg(long)]
    base: Option<String>,
    /// Tip link of the chain [default: the end of the longest run of moving joints].
    #[arg(long)]
    tip: Option<String>,
}

/// Tolerances of the axis classification.
#[derive(Debug, Args)]
struct ToleranceCli {
    /// Common normals shorter than this count as zero (metres).
    #[arg(long, value_name = "M", default_value_t = Tolerance::DEFAULT_LINEAR, value_parser = guard::linear_tol)]
    linear_tol: f64,
    /// Axes this close to parallel count as parallel (radians).
    #[arg(long, value_name = "RAD", default_value_t = Tolerance::DEFAULT_ANGULAR, value_parser = guard::angular_tol)]
    angular_tol: f64,
}

impl ToleranceCli {
    fn tolerance(&self) -> anyhow::Result<Tolerance> {
        Tolerance::new(self.linear_tol, self.angular_tol).map_err(|e| anyhow::anyhow!("{e}"))
    }
}

#[derive(Debug, Args)]
struct ExtractCli {
    /// The robot: a URDF file, a .xacro file (expanded natively), or - for standard input.
    robot: String,
    #[command(flatten)]
    chain: ChainCli,
    #[command(flatten)]
    xacro: XacroCli,
    /// DH convention of the table.
    #[arg(long, value_enum, default_value_t = ConventionDoc::Standard)]
    convention: ConventionDoc,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
    /// Length unit of the output.
    #[arg(long, value_enum, default_value_t = LengthUnit::M)]
    length_unit: LengthUnit,
    /// Angle unit of the output.
    #[arg(long, value_enum, default_value_t = AngleUnit::Rad)]
    angle_unit: AngleUnit,
    #[command(flatten)]
    tol: ToleranceCli,
    /// Random joint-value samples of the self-check (the zero pose is always the first)
    /// [default: 1000, fewer beyond 10 000 joints: at most 1e7 joint evaluations in all, and
    /// never fewer than 10].
    #[arg(long, value_name = "N", value_parser = guard::samples)]
    samples: Option<usize>,
    /// Seed of the self-check's sampler.
    #[arg(long, value_name = "S", default_value_t = 0)]
    seed: u64,
    /// Also draw the DH frames (isometric and side view) into this SVG file (`-`: standard
    /// output, the table then goes to standard error).
    #[arg(long, value_name = "FILE", value_parser = guard::svg_output)]
    svg: Option<String>,
    /// Joint values for the drawing, comma-separated, radians (metres for prismatic joints)
    /// [default: all zero]; needs --svg.
    #[arg(
        long,
        requires = "svg",
        value_name = "Q1,Q2,...",
        value_delimiter = ',',
        allow_hyphen_values = true,
        value_parser = guard::joint_value
    )]
    q: Option<Vec<f64>>,
}

/// Conventions `batch` extracts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum Conventions {
    /// Standard DH only.
    Standard,
    /// Modified (Craig) DH only.
    Modified,
    /// Both, standard first.
    Both,
}

#[derive(Debug, Args)]
struct BatchCli {
    /// The list of chains, one per line: `ROBOT [BASE [TIP]]` (`-` for the default, `#` starts a
    /// comment; relative paths are relative to the list's folder), or - for standard input.
    list: String,
    /// DH convention(s) of the tables.
    #[arg(long, value_enum, default_value_t = Conventions::Standard)]
    convention: Conventions,
    /// Length unit of the output.
    #[arg(long, value_enum, default_value_t = LengthUnit::M)]
    length_unit: LengthUnit,
    /// Angle unit of the output.
    #[arg(long, value_enum, default_value_t = AngleUnit::Rad)]
    angle_unit: AngleUnit,
    #[command(flatten)]
    tol: ToleranceCli,
    #[command(flatten)]
    verify: VerifyCli,
    #[command(flatten)]
    xacro: XacroCli,
}

#[derive(Debug, Args)]
struct CheckCli {
    /// The robot: a URDF file, a .xacro file, or - for standard input.
    robot: String,
    /// The DH sheet (YAML or JSON, the format `extract --format yaml` writes).
    #[arg(long, value_name = "SHEET")]
    sheet: String,
    #[command(flatten)]
    chain: ChainCli,
    #[command(flatten)]
    xacro: XacroCli,
    /// Lengths that differ by less than this match (metres).
    #[arg(long, value_name = "M", default_value_t = CHECK_LINEAR, value_parser = guard::linear_tol)]
    linear_tol: f64,
    /// Angles that differ by less than this match (radians).
    #[arg(long, value_name = "RAD", default_value_t = CHECK_ANGULAR, value_parser = guard::angular_tol)]
    angular_tol: f64,
    /// Output format.
    #[arg(long, value_enum, default_value_t = CheckFormat::Text)]
    format: CheckFormat,
}

/// Runs the command line `args`, writing results to `out` and messages to `err`; returns the
/// exit code.
pub fn run<I, T>(args: I, out: &mut dyn Write, err: &mut dyn Write) -> i32
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    // Every message goes through one escaping rule (guard::escape): a name quoted from a file
    // or an argument cannot drive the terminal.
    let mut err = crate::guard::Escaping(err);
    let err: &mut dyn Write = &mut err;
    let args: Vec<OsString> = args.into_iter().map(Into::into).collect();
    let cli = match parse(&args) {
        Ok(cli) => cli,
        Err(e) => {
            // Plain text: output may be a pipe or a log, and snapshots must not hold escape
            // codes. Usage errors start like every other error.
            let mut text = e.render().to_string();
            if let Some(rest) = text.strip_prefix("error: ") {
                text = format!("urdf-dh: error: {rest}");
            }
            if let Some(option) = similar_option(&args, &e) {
                // clap's "to pass '--tpi' as a value, use '-- --tpi'" misleads when the option
                // was mistyped: the hint says which one was meant.
                if let Some(at) = text.find("\n  tip: to pass '") {
                    if let Some(end) = text[at + 1..].find("\n\n") {
                        text.replace_range(at + 1..at + 1 + end + 2, "");
                    }
                }
                text.push_str(&format!("hint: did you mean '{option}'?\n"));
            }
            let code = e.exit_code();
            let sink: &mut dyn Write = if code == 0 { out } else { err };
            let _ = sink.write_all(text.as_bytes());
            return if code == 0 { 0 } else { 2 };
        }
    };
    // Standard output is flushed before the exit code is decided: a result that did not reach
    // it (a full disk, a closed pipe) is a failure, not a success.
    let done = flushed(dispatch(cli, &args, out, err), out);
    match done {
        Ok(Outcome::Pass) => 0,
        Ok(Outcome::Differs) => 1,
        // The reader of stdout went away (`| head`): stop quietly, as other Unix tools do.
        Err(e)
            if e.chain().any(|c| {
                c.downcast_ref::<std::io::Error>()
                    .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
            }) =>
        {
            0
        }
        Err(e) => {
            // One line each: a line feed inside a quoted name is escaped too.
            let message = format!("{e:#}");
            let _ = writeln!(err, "urdf-dh: error: {}", crate::guard::escape(&message));
            if let Some(h) = dh_workflows::error::hint_for(&e) {
                let _ = writeln!(err, "hint: {}", crate::guard::escape(&h));
            }
            2
        }
    }
}

/// Runs one command as [`run`] does, for callers in process (the Python package): the
/// command's error (with its hint, see [`dh_workflows::error::hint_for`]) is returned, not printed, and
/// a usage error is an error whose message is clap's.
///
/// # Errors
/// Usage errors and every error of the command.
pub fn run_command<I, T>(
    args: I,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> anyhow::Result<Outcome>
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    let args: Vec<OsString> = args.into_iter().map(Into::into).collect();
    let cli = parse(&args).map_err(|e| {
        let text = e.render().to_string();
        let message = text.strip_prefix("error: ").unwrap_or(&text).trim_end();
        match similar_option(&args, &e) {
            Some(option) => {
                dh_workflows::error::hinted(message, format!("did you mean '{option}'?"))
            }
            None => anyhow::anyhow!("{message}"),
        }
    })?;
    flushed(dispatch(cli, &args, out, err), out)
}

/// The command line's definition: [`Cli`], every option that takes a value also taking a
/// negative number (`--noise -1` then meets the option's own range check, "expected a length
/// in [0, ...], found -1", instead of clap's "unexpected argument '-1'"; no option of urdf-dh
/// is a digit).
fn command() -> clap::Command {
    use clap::CommandFactory;
    crate::manual::sized(Cli::command()).mut_subcommands(|c| {
        c.mut_args(|a| {
            if a.get_action().takes_values() {
                a.allow_negative_numbers(true)
            } else {
                a
            }
        })
    })
}

/// Parses `args` (the program name first) with [`command`].
fn parse(args: &[OsString]) -> Result<Cli, clap::Error> {
    use clap::FromArgMatches;
    let mut cmd = command();
    let matches = cmd.try_get_matches_from_mut(args.iter().cloned())?;
    Cli::from_arg_matches(&matches).map_err(|e| e.format(&mut cmd))
}

/// The long option of the subcommand in `args` closest to the unknown one `e` names, when
/// clap suggested none (its similarity threshold misses a dropped letter in a short name:
/// `--tp` for `--tip`): at most two edits away, and fewer edits than the option has letters.
fn similar_option(args: &[OsString], e: &clap::Error) -> Option<String> {
    use clap::error::{ContextKind, ContextValue, ErrorKind};
    if e.kind() != ErrorKind::UnknownArgument || e.get(ContextKind::SuggestedArg).is_some() {
        return None;
    }
    let Some(ContextValue::String(given)) = e.get(ContextKind::InvalidArg) else {
        return None;
    };
    let given = given.strip_prefix("--")?.split('=').next()?;
    let cmd = command();
    let sub = args
        .iter()
        .skip(1)
        .filter_map(|a| a.to_str())
        .find_map(|a| cmd.find_subcommand(a))?;
    sub.get_arguments()
        .filter_map(clap::Arg::get_long)
        .map(|long| (strsim::levenshtein(given, long), long))
        .filter(|&(d, long)| d <= 2 && d < long.chars().count())
        .min()
        .map(|(_, long)| format!("--{long}"))
}

/// `outcome`, once `out` is flushed: an error when the flush fails (the message names standard
/// output, see [`crate::stdout::Stdout`]).
fn flushed(outcome: anyhow::Result<Outcome>, out: &mut dyn Write) -> anyhow::Result<Outcome> {
    let outcome = outcome?;
    out.flush()?;
    Ok(outcome)
}

/// Runs one command, every input opened once ([`dh_workflows::input::reading_once`]: standard input
/// and FIFOs can be read only once).
/// The warnings of the xacro expansions the command made are written to `err` after it.
/// Runs the parsed command line `cli`; `args` is the command line as given (the report page's
/// provenance records it).
fn dispatch(
    cli: Cli,
    args: &[OsString],
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> anyhow::Result<Outcome> {
    let line = crate::commands::command_line(args);
    let result = dh_workflows::input::reading_once(|| dispatch_command(cli, line, out, err));
    for w in dh_workflows::xacro::take_warnings() {
        writeln!(err, "urdf-dh: warning: {w}")?;
    }
    result
}

fn dispatch_command(
    cli: Cli,
    line: Vec<String>,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> anyhow::Result<Outcome> {
    match cli.command {
        Command::Extract(a) => {
            a.xacro.apply()?;
            if let Some(svg) = &a.svg {
                check_destinations(&[("ROBOT", &a.robot)], &[("--svg", svg)])?;
            }
            let args = ExtractArgs {
                path: a.robot,
                base: a.chain.base,
                tip: a.chain.tip,
                convention: a.convention.into(),
                format: a.format,
                length_unit: a.length_unit,
                angle_unit: a.angle_unit,
                tolerance: a.tol.tolerance()?,
                samples: a.samples,
                seed: a.seed,
                svg: a.svg,
                q: a.q,
            };
            extract(&args, out, err)
        }
        Command::Check(a) => {
            a.xacro.apply()?;
            let args = CheckArgs {
                robot: a.robot,
                sheet: a.sheet,
                base: a.chain.base,
                tip: a.chain.tip,
                tolerance: Tolerance::new(a.linear_tol, a.angular_tol)
                    .map_err(|e| anyhow::anyhow!("{e}"))?,
                format: a.format,
            };
            check(&args, out, err)
        }
        Command::Batch(a) => {
            a.xacro.apply()?;
            batch(
                &BatchArgs {
                    list: a.list,
                    conventions: match a.convention {
                        Conventions::Standard => vec![Convention::Standard],
                        Conventions::Modified => vec![Convention::Modified],
                        Conventions::Both => {
                            vec![Convention::Standard, Convention::Modified]
                        }
                    },
                    length_unit: a.length_unit,
                    angle_unit: a.angle_unit,
                    tolerance: a.tol.tolerance()?,
                    samples: a.verify.samples,
                    seed: a.verify.seed,
                },
                out,
                err,
            )
        }
        Command::Convert(a) => convert(
            &ConvertArgs {
                sheet: a.sheet,
                to: a.to.map_or(Convention::Standard, Into::into),
                deltas: a.deltas,
                format: a.format,
                length_unit: a.length_unit,
                angle_unit: a.angle_unit,
                samples: a.verify.samples,
                seed: a.verify.seed,
            },
            out,
            err,
        ),
        Command::ToUrdf(a) => to_urdf(
            &ToUrdfArgs {
                sheet: a.sheet,
                name: a.name,
                base_link: a.base_link,
                tip_link: a.tip_link,
                samples: a.verify.samples,
                seed: a.verify.seed,
            },
            out,
            err,
        ),
        Command::Import(a) => import::import(&a.into_args()?, out, err),
        Command::Calibrate(a) => {
            a.xacro.apply()?;
            let mut args = a.into_args();
            args.command_line = line;
            run_calibrate(&args, out, err)
        }
        Command::Predict(a) => {
            a.xacro.apply()?;
            run_predict(&a.into_args(), out, err)
        }
        Command::Compensate(a) => {
            a.xacro.apply()?;
            run_compensate(&a.into_args(), out, err)
        }
        Command::Cpa(a) => {
            a.xacro.apply()?;
            let mut args = a.into_args()?;
            args.command_line = line;
            if let Some(plot) = &args.plot {
                let inputs: Vec<(&str, &str)> = [
                    ("DATA", Some(args.request.data.as_str())),
                    ("--model", args.request.model.as_deref()),
                ]
                .into_iter()
                .filter_map(|(o, p)| Some((o, p?)))
                .collect();
                check_destinations(&inputs, &[("--plot", plot)])?;
            }
            cpa::cpa(&args, out, err)
        }
        Command::Simulate(a) => {
            a.xacro.apply()?;
            simulate::simulate(&a.into_args(), out, err)
        }
        Command::Completions { shell } => {
            use clap::CommandFactory;
            // Into a buffer first: clap_complete panics on a failed write (`> /dev/full`).
            let mut script = Vec::new();
            clap_complete::generate(shell, &mut Cli::command(), "urdf-dh", &mut script);
            out.write_all(&script)?;
            Ok(Outcome::Pass)
        }
        Command::Man(a) => crate::manual::man(&a, out),
    }
}

/// Runs `calibrate` with `args` as the command line does (the library entry of
/// `urdf-dh calibrate`): [`calibrate::calibrate`], outputs checked against the inputs first.
///
/// # Errors
/// As [`calibrate::calibrate`].
pub fn run_calibrate(
    args: &calibrate::CalibrateArgs,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> anyhow::Result<Outcome> {
    calibrate::calibrate(args, out, err)
}

/// Runs `predict` with `args` as the command line does (the library entry of `urdf-dh predict`):
/// the output checked against the inputs, then [`predict::predict`].
///
/// # Errors
/// As [`predict::predict`].
pub fn run_predict(
    args: &predict::PredictArgs,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> anyhow::Result<Outcome> {
    let outputs: Vec<(&str, &str)> = args.out.iter().map(|o| ("--out", o.as_str())).collect();
    check_destinations(
        &[("--model", &args.model), ("--joints", &args.joints)],
        &outputs,
    )?;
    predict::predict(args, out, err)
}

/// Runs `compensate` with `args` as the command line does (the library entry of
/// `urdf-dh compensate`): the output checked against the inputs, then
/// [`compensate::compensate`].
///
/// # Errors
/// As [`compensate::compensate`].
pub fn run_compensate(
    args: &compensate::CompensateArgs,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> anyhow::Result<Outcome> {
    let outputs: Vec<(&str, &str)> = args.out.iter().map(|o| ("--out", o.as_str())).collect();
    check_destinations(
        &[
            ("--nominal", &args.nominal),
            ("--model", &args.model),
            ("--joints", &args.joints),
        ],
        &outputs,
    )?;
    compensate::compensate(args, out, err)
}
