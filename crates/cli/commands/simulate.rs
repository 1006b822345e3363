//! `urdf-dh simulate`: measurements of a model with known errors, for trying `calibrate` and
//! `cpa` where the truth is known. Writes the canonical measurement CSV and, beside it, a truth
//! file: the true DH sheet with a `truth` section (device frame, targets, errors, effects,
//! noise, seed).

use std::io::Write;
use std::path::Path;

use anyhow::Result;
use dh_calib::csv::write_measurements;
use dh_calib::simulate::{
    plant_effects, simulate as run_simulation, Errors, Mode, SimulationOptions,
};
use dh_core::{Convention, DhTable, JointKind};
use serde::Serialize;

use crate::commands::calibrate::{PoseSi, TargetDoc};
use crate::error::{hinted, Outcome};
use crate::input::display_name;
use crate::measured::{load_model, parse_effect};
use crate::output::check_destinations;
use crate::sheet::SheetDoc;
use crate::units::{AngleUnit, LengthUnit};

/// Everything `simulate` needs.
#[derive(Clone, Debug)]
pub struct SimulateArgs {
    /// The nominal model.
    pub model: String,
    /// Base link of a URDF chain.
    pub base: Option<String>,
    /// Tip link of a URDF chain.
    pub tip: Option<String>,
    /// Convention for a URDF model.
    pub convention: Convention,
    /// Random poses; with `cpa`, poses per joint.
    pub poses: usize,
    /// Noise standard deviation per device axis (metres).
    pub noise: f64,
    /// A 6-DoF device: the noise standard deviation of each measured orientation per axis
    /// (radians); `None`: points (see `dh_calib::simulate::SimulationOptions::orientation_sigma`).
    pub orientation_noise: Option<f64>,
    /// Sweep one joint at a time instead of random poses.
    pub cpa: bool,
    /// Width of each CPA sweep (radians); `None`: a quarter turn or the narrowest joint range.
    pub arc: Option<f64>,
    /// Effects and their values (`gear_ratio:joint_2=1e-3`).
    pub effects: Vec<String>,
    /// Geometric errors by parameter name (`joint_2.a=0.001`).
    pub errors: Vec<String>,
    /// Random errors on every DH parameter: largest length (metres) and angle (radians).
    pub random_errors: Option<(f64, f64)>,
    /// Targets on the tool.
    pub targets: usize,
    /// Measurements per pose.
    pub repeats: usize,
    /// Fraction of poses (the last ones) held out for validation.
    pub validation: f64,
    /// Measurement sessions: consecutive blocks of poses, each measured from its own device
    /// frame (see `dh_calib::simulate::SimulationOptions::sessions`).
    pub sessions: usize,
    /// Seed.
    pub seed: u64,
    /// The CSV to write.
    pub out: String,
    /// The truth file; `None`: beside `out`, `<stem>.truth.yaml`.
    pub truth: Option<String>,
}

/// Largest magnitude of an `--error` or `--effect` value (metres, radians or the effect's own
/// unit): an error of a kilometre or a thousand radians is no robot's, and beyond it the
/// simulated points leave what the measurement reader accepts (100 m).
const MAX_SIM_VALUE: f64 = 1e3;

/// `NAME=VALUE[,VALUE...]`, each value finite and within [`MAX_SIM_VALUE`].
fn name_values(s: &str, what: &str) -> Result<(String, Vec<f64>)> {
    let (name, values) = s.split_once('=').ok_or_else(|| {
        hinted(
            format!("{what} '{s}': expected NAME=VALUE, found no '='"),
            format!("e.g. --{what} joint_2.a=0.001"),
        )
    })?;
    let values = values
        .split(',')
        .map(|v| {
            v.trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite() && v.abs() <= MAX_SIM_VALUE)
                .ok_or_else(|| {
                    anyhow::anyhow!(
                        "--{what} '{s}': expected a number in [-{MAX_SIM_VALUE}, {MAX_SIM_VALUE}], found '{}'",
                        v.trim()
                    )
                })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok((name.trim().to_string(), values))
}

/// The truth section (metres and radians).
#[derive(Clone, Debug, PartialEq, Serialize)]
struct TruthSection {
    data: String,
    seed: u64,
    poses: usize,
    samples: usize,
    sigma: f64,
    device: PoseSi,
    /// With several sessions: every session's true device frame, by name (`s1` is `device`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    sessions: Vec<(String, PoseSi)>,
    targets: Vec<TargetDoc>,
    errors: Vec<(String, f64)>,
    effects: Vec<(String, f64)>,
}

/// The CPA sweeps: home at the middle of each joint's range, one arc for all.
fn cpa_mode(table: &DhTable, poses: usize, arc: Option<f64>) -> Result<Mode> {
    if let Some(r) = table.rows.iter().find(|r| r.kind == JointKind::Prismatic) {
        return Err(hinted(
            format!(
                "--cpa: joint '{}' is prismatic; the simulator sweeps every joint by one arc in radians",
                r.name
            ),
            "simulate random poses instead (drop --cpa)",
        ));
    }
    let narrowest = table
        .rows
        .iter()
        .filter_map(|r| r.limits.map(|l| l.upper - l.lower))
        .fold(std::f64::consts::FRAC_PI_2, f64::min);
    let arc = arc.unwrap_or(narrowest);
    if !(arc.is_finite() && arc > 0.0) {
        anyhow::bail!("--arc: expected a positive angle, found {arc}");
    }
    let home = table
        .rows
        .iter()
        .map(|r| r.limits.map_or(0.0, |l| 0.5 * (l.lower + l.upper)))
        .collect();
    Ok(Mode::Cpa {
        angles: poses,
        arc,
        home: Some(home),
    })
}

/// The truth file's default path: `D.csv` -> `D.truth.yaml`.
pub fn truth_path(out: &str) -> String {
    let p = Path::new(out);
    let stem = p
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "data".into());
    p.with_file_name(format!("{stem}.truth.yaml"))
        .to_string_lossy()
        .into_owned()
}

/// Runs `simulate`.
///
/// # Errors
/// A bad model, option or effect; failed writes.
pub fn simulate(args: &SimulateArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    if args.out == crate::output::STDIO && args.truth.is_none() {
        return Err(hinted(
            "--out -: the measurements go to standard output, so the truth needs a file of its own: expected --truth FILE, found none".to_string(),
            "urdf-dh simulate --model M --out - --truth truth.yaml | ...",
        ));
    }
    let truth_file = args.truth.clone().unwrap_or_else(|| truth_path(&args.out));
    check_destinations(
        &[("--model", &args.model)],
        &[("--out", &args.out), ("--truth", &truth_file)],
    )?;
    let model = load_model(
        &args.model,
        args.base.as_deref(),
        args.tip.as_deref(),
        args.convention,
    )?;
    for w in &model.warnings {
        writeln!(err, "urdf-dh: warning: {w}")?;
    }
    if !(args.noise.is_finite() && args.noise >= 0.0) {
        anyhow::bail!("--noise: expected a length >= 0, found {}", args.noise);
    }
    let table = &model.table;
    // Each option is in range on its own; their product sizes the file (and the memory).
    let sweeps = if args.cpa { table.rows.len() } else { 1 };
    let samples = [sweeps, args.targets, args.repeats]
        .iter()
        .fold(args.poses, |n, k| n.saturating_mul(*k));
    if samples > crate::guard::MAX_SIM_SAMPLES {
        return Err(hinted(
            format!(
                "--poses {} x --targets {} x --repeats {}{}: expected at most {} samples, found {samples}",
                args.poses,
                args.targets,
                args.repeats,
                if args.cpa { format!(" x {sweeps} joint sweeps") } else { String::new() },
                crate::guard::MAX_SIM_SAMPLES
            ),
            "simulate fewer poses, targets or repeats",
        ));
    }
    let effects = args
        .effects
        .iter()
        .map(|s| {
            let (label, values) = name_values(s, "effect")?;
            Ok((parse_effect(&label, table)?, values))
        })
        .collect::<Result<Vec<_>>>()?;
    let errors = match (args.random_errors, args.errors.is_empty()) {
        (Some(_), false) => anyhow::bail!("give --error or --random-errors, not both"),
        (Some((length, angle)), true) => Errors::Random { length, angle },
        (None, false) => Errors::Explicit(
            args.errors
                .iter()
                .map(|s| {
                    let (name, v) = name_values(s, "error")?;
                    match v.as_slice() {
                        [v] => Ok((name, *v)),
                        _ => anyhow::bail!("error '{s}': expected one value"),
                    }
                })
                .collect::<Result<_>>()?,
        ),
        (None, true) => Errors::None,
    };
    let mode = if args.cpa {
        cpa_mode(table, args.poses, args.arc)?
    } else {
        Mode::Random
    };
    let options = SimulationOptions {
        seed: args.seed,
        poses: args.poses,
        mode,
        sigma: args.noise,
        target_count: args.targets,
        errors,
        validation_fraction: args.validation,
        repeats: args.repeats,
        sessions: args.sessions,
        orientation_sigma: args.orientation_noise,
        ..SimulationOptions::default()
    };
    if args.orientation_noise.is_some() && args.noise == 0.0 {
        anyhow::bail!(
            "--orientation-noise: expected --noise > 0 as well (the position sigma weighs the angle), found --noise 0"
        );
    }
    let (mut data, truth) = run_simulation(table, &options).map_err(|e| {
        let msg = format!("simulation failed: {e}");
        match e {
            dh_calib::CalibError::UnknownParameter { .. } => hinted(
                msg,
                "parameters are named <joint>.a|alpha|d|theta|beta, base.x|y|z|rx|ry|rz, tool.*, device.*, target.t1.x|y|z",
            ),
            _ => anyhow::anyhow!(msg),
        }
    })?;
    // Effects change the positions and, for a 6-DoF device, the orientations.
    let applied = plant_effects(table, &mut data, &truth, &effects, &options.model)?;
    // The simulator draws the rows' (serial) values; the file holds what the controller reports.
    model.uncouple(&mut data)?;
    if args.noise == 0.0 {
        // Exact points: no standard deviation rather than a zero one (which no file may hold).
        for s in &mut data.samples {
            s.sigma = None;
        }
    }

    let out_name = display_name(&args.out);
    let truth_path = args.truth.clone().unwrap_or_else(|| truth_path(&args.out));
    let poses = data.samples.len() / (args.targets.max(1) * args.repeats.max(1));
    let mut csv = format!(
        "# simulated by urdf-dh simulate from {} (seed {}, {} poses{}, noise {} m per axis); truth in {}\n",
        model.origin,
        args.seed,
        poses,
        if args.cpa { " in CPA sweeps" } else { "" },
        args.noise,
        display_name(&truth_path)
    );
    csv.push_str(&write_measurements(&data));
    // What simulate writes, calibrate reads: a model whose points leave the reader's limits
    // (coordinates beyond 100 m, joint values beyond four turns) is refused here, not there.
    let opts = dh_calib::csv::CsvOptions {
        length_unit: dh_calib::csv::LengthUnit::Metre,
        angle_unit: dh_calib::csv::AngleUnit::Radian,
        prismatic: model.prismatic(),
    };
    dh_calib::csv::parse_measurements(&csv, &data.joint_names, &opts).map_err(|e| {
        hinted(
            format!("simulate: the simulated data would not read back: {e}"),
            "simulate a model of robot size (points within 100 m of the device, joint ranges within four turns)",
        )
    })?;

    let mut sheet = SheetDoc::from_table(&truth.table, LengthUnit::M, AngleUnit::Rad);
    sheet.robot = Some(format!("truth of {out_name}"));
    sheet.source = Some(format!(
        "simulated by urdf-dh simulate from {} with the errors below",
        model.origin
    ));
    let section = TruthSection {
        data: out_name.clone(),
        seed: args.seed,
        poses,
        samples: data.samples.len(),
        sigma: truth.sigma,
        device: PoseSi::of(&truth.device),
        sessions: if data.sessions.is_empty() {
            Vec::new()
        } else {
            (0..truth.sessions.len())
                .map(|s| (data.session_name(s), PoseSi::of(&truth.sessions[s])))
                .collect()
        },
        targets: if args.orientation_noise.is_some() {
            let rotations: Vec<_> = truth.target_rotations.iter().copied().map(Some).collect();
            TargetDoc::list_with(&truth.targets, &rotations)
        } else {
            TargetDoc::list(&truth.targets)
        },
        errors: truth.errors.clone(),
        effects: applied,
    };
    sheet.truth = Some(serde_yaml::to_value(&section)?);
    let truth_text = serde_yaml::to_string(&sheet)?;
    // Both files or neither.
    crate::output::write_all_or_stdout(
        &[
            (Path::new(&args.out), csv.as_bytes()),
            (Path::new(&truth_path), truth_text.as_bytes()),
        ],
        out,
    )?;
    writeln!(
        err,
        "urdf-dh: {out_name}: {} samples at {poses} poses of {} target(s); truth in {}",
        data.samples.len(),
        data.targets.len(),
        display_name(&truth_path)
    )?;
    Ok(Outcome::Pass)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn truth_beside_the_data() {
        assert_eq!(truth_path("d/sim.csv"), "d/sim.truth.yaml");
        assert_eq!(truth_path("sim"), "sim.truth.yaml");
    }

    #[test]
    fn name_values_parse() {
        assert_eq!(
            name_values("gear_ratio:j2=1e-3", "effect").unwrap(),
            ("gear_ratio:j2".to_string(), vec![1e-3])
        );
        assert!(name_values("j2.a", "error").is_err());
        assert!(name_values("j2.a=x", "error").is_err());
        assert!(name_values("j2.a=inf", "error").is_err());
    }
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
    /// DH convention for a URDF model.
    #[arg(long, value_enum, default_value_t = crate::sheet::ConventionDoc::Standard)]
    convention: crate::sheet::ConventionDoc,
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
    /// range].
    #[arg(long, value_name = "RAD", value_parser = crate::guard::arc)]
    arc: Option<f64>,
    /// An effect of the true robot, LABEL=VALUE (e.g. gear_ratio:elbow_joint=0.001); repeatable.
    #[arg(long = "effect", value_name = "LABEL=VALUE")]
    effects: Vec<String>,
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
    #[arg(long, value_name = "D.csv")]
    out: String,
    /// The truth file [default: D.truth.yaml beside --out].
    #[arg(long, value_name = "FILE")]
    truth: Option<String>,
}

impl SimulateCli {
    /// The arguments of [`simulate`].
    pub fn into_args(self) -> SimulateArgs {
        SimulateArgs {
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
            errors: self.errors,
            random_errors: self.random_errors,
            targets: self.targets,
            repeats: self.repeats,
            validation: self.validation,
            sessions: self.sessions,
            seed: self.seed,
            out: self.out,
            truth: self.truth,
        }
    }
}
