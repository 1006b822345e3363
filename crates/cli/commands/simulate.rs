//! `urdf-dh simulate`: measurements of a model with known errors, for trying `calibrate` and
//! `cpa` where the truth is known (the library's [`dh_workflows::simulation`]). Writes the
//! canonical measurement CSV and, beside it, a truth file: the true DH sheet with a `truth`
//! section (device frame, targets, errors, effects, noise, seed).

use std::io::Write;
use std::path::Path;

use anyhow::Result;
use dh_workflows::error::hinted;
use dh_workflows::output::check_destinations;
use dh_workflows::simulation::simulate as run;
pub use dh_workflows::simulation::{truth_path, SimulationRequest};

use crate::error::Outcome;

/// Everything `simulate` needs: the library's request and the files to write.
#[derive(Clone, Debug)]
pub struct SimulateArgs {
    /// The simulation ([`dh_workflows::simulation`]).
    pub request: SimulationRequest,
    /// The CSV to write.
    pub out: String,
    /// The truth file; `None`: beside `out`, `<stem>.truth.yaml`.
    pub truth: Option<String>,
}

/// Runs `simulate`: both files written, or neither.
///
/// # Errors
/// A bad model, option or effect; failed writes.
pub fn simulate(args: &SimulateArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    if args.out == dh_workflows::output::STDIO && args.truth.is_none() {
        return Err(hinted(
            "--out -: the measurements go to standard output, so the truth needs a file of its own: expected --truth FILE, found none".to_string(),
            "urdf-dh simulate --model M --out - --truth truth.yaml | ...",
        ));
    }
    let truth_file = args.truth.clone().unwrap_or_else(|| truth_path(&args.out));
    check_destinations(
        &[("--model", &args.request.model)],
        &[("--out", &args.out), ("--truth", &truth_file)],
    )?;
    // Outputs: `-` is standard output, not standard input.
    let out_name = crate::guard::output_name(&args.out);
    let sim = run(
        &args.request,
        &out_name,
        &crate::guard::output_name(&truth_file),
        err,
    )?;
    let truth_text = sim.truth_yaml()?;
    dh_workflows::output::write_all_or_stdout(
        &[
            (Path::new(&args.out), sim.csv.as_bytes()),
            (Path::new(&truth_file), truth_text.as_bytes()),
        ],
        out,
    )?;
    writeln!(
        err,
        "urdf-dh: {out_name}: {} samples at {} poses of {} target(s); truth in {}",
        sim.data.samples.len(),
        sim.poses,
        sim.data.targets.len(),
        crate::guard::output_name(&truth_file)
    )?;
    Ok(Outcome::Pass)
}

/// Command-line arguments of `simulate`.
#[derive(Debug, clap::Args)]
pub struct SimulateCli {
    /// The nominal model: a URDF (with --base/--tip) or a DH sheet.
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
    /// DH convention for a URDF model.
    #[arg(long, value_enum, default_value_t = dh_workflows::sheet::ConventionDoc::Standard)]
    convention: dh_workflows::sheet::ConventionDoc,
    /// Random poses within the joint limits; with --cpa, poses per joint sweep.
    #[arg(long, value_name = "N", default_value_t = 100, value_parser = crate::guard::poses)]
    poses: usize,
    /// Gaussian noise, standard deviation per device axis (metres).
    #[arg(long, value_name = "SIGMA", default_value_t = 0.0, value_parser = crate::guard::noise)]
    noise: f64,
    /// A 6-DoF device (a tracker's 6-DoF probe): every sample also measures the target frame's
    /// orientation (columns qw,qx,qy,qz,sigma_rot) with this Gaussian noise per axis
    /// (radians); needs --noise > 0.
    #[arg(long, value_name = "SIGMA_ROT", value_parser = crate::guard::orientation_noise)]
    orientation_noise: Option<f64>,
    /// Sweep one joint at a time (circle-point analysis data) instead of random poses.
    #[arg(long)]
    cpa: bool,
    /// Width of each CPA sweep (radians) [default: a quarter turn, or the narrowest joint
    /// range]; needs --cpa.
    #[arg(long, value_name = "RAD", requires = "cpa", value_parser = crate::guard::arc)]
    arc: Option<f64>,
    /// An effect of the true robot, LABEL=VALUE (e.g. gear_ratio:elbow_joint=0.001); repeatable.
    #[arg(long = "effect", value_name = "LABEL=VALUE")]
    effects: Vec<String>,
    /// Link masses for the gravity effects (compliance:J, lateral_compliance:J, backlash:J), as
    /// calibrate --inertials reads them; the truth file keeps them so that it predicts. A
    /// gravity_sag:J needs none (its gravity: this file's `gravity`, else -z of the base).
    #[arg(long, value_name = "FILE")]
    inertials: Option<String>,
    /// Gravity in the robot's base link frame, m/s² [default: the inertials file's `gravity`,
    /// else 0,0,-9.80665]: the direction of a gravity_sag:J and of the inertials' torques, as
    /// calibrate --gravity takes it.
    #[arg(
        long,
        value_name = "X,Y,Z",
        value_delimiter = ',',
        allow_hyphen_values = true,
        value_parser = crate::guard::gravity
    )]
    gravity: Option<Vec<f64>>,
    /// A geometric error of the true robot, NAME=VALUE in metres or radians (e.g.
    /// elbow_joint.a=0.0005); repeatable.
    #[arg(long = "error", value_name = "NAME=VALUE", allow_hyphen_values = true)]
    errors: Vec<String>,
    /// Random errors on every DH parameter, uniform within LENGTH metres and ANGLE radians.
    #[arg(long, value_name = "LENGTH,ANGLE", value_parser = crate::guard::random_errors)]
    random_errors: Option<(f64, f64)>,
    /// Targets (reflectors) on the tool, placed at random within 0.1 m of the tip.
    #[arg(long, value_name = "K", default_value_t = 1, value_parser = crate::guard::small_count)]
    targets: usize,
    /// Measurements of each pose.
    #[arg(long, value_name = "R", default_value_t = 1, value_parser = crate::guard::small_count)]
    repeats: usize,
    /// Fraction of the poses (the last ones) marked for validation.
    #[arg(long, value_name = "F", default_value_t = 0.0, value_parser = crate::guard::fraction)]
    validation: f64,
    /// Measurement sessions: the poses are split into N consecutive blocks, each measured from
    /// its own device frame (moved by up to 0.5 m and 30 degrees from the first), and the CSV
    /// gets a `session` column (s1, s2, ...).
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = crate::guard::small_count)]
    sessions: usize,
    /// Seed of the random stream (a seed reproduces a data set exactly).
    #[arg(long, value_name = "S", default_value_t = 1)]
    seed: u64,
    /// The measurement CSV to write (`-`: standard output; --truth is then required).
    #[arg(long, value_name = "D.csv", value_parser = crate::guard::csv_output)]
    out: String,
    /// The truth file [default: D.truth.yaml beside --out].
    #[arg(long, value_name = "FILE", value_parser = crate::guard::yaml_output)]
    truth: Option<String>,
}

impl SimulateCli {
    /// The arguments of [`simulate`].
    pub fn into_args(self) -> SimulateArgs {
        SimulateArgs {
            request: SimulationRequest {
                model: self.model,
                base: self.base,
                tip: self.tip,
                convention: self.convention.into(),
                poses: self.poses,
                noise: self.noise,
                orientation_noise: self.orientation_noise,
                cpa: self.cpa,
                arc: self.arc,
                effects: self.effects,
                inertials: self.inertials,
                gravity: self.gravity,
                errors: self.errors,
                random_errors: self.random_errors,
                targets: self.targets,
                repeats: self.repeats,
                validation: self.validation,
                sessions: self.sessions,
                seed: self.seed,
            },
            out: self.out,
            truth: self.truth,
        }
    }
}
