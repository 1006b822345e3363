//! Simulated measurements of a model with known errors, for trying a calibration or the
//! circle-point analysis where the truth is known (`urdf-dh simulate`): the measurement set
//! ([`Simulated::data`]; the canonical CSV, [`Simulated::csv`]) and the truth (the true DH
//! sheet with a `truth` section: device frame, targets, errors, effects, noise, seed;
//! [`Simulated::truth`]).
//!
//! Frames and units: metres and radians; points in the device frame, targets in the tip frame,
//! the device frame `T_device_base` as in `dh_calib::simulate`.

use std::io::Write;
use std::path::Path;
use std::sync::Arc;

use anyhow::Result;
use dh_calib::csv::write_measurements;
use dh_calib::data::Measurements;
use dh_calib::effects::EffectContext;
use dh_calib::gravity::GravityModel;
use dh_calib::pipeline::{GravityRecord, PoseSi, TargetDoc};
use dh_calib::simulate::{
    plant_effects, simulate as run_simulation, Errors, Mode, SimulationOptions,
};
use dh_core::{Convention, DhTable, JointKind};
use serde::Serialize;

use crate::error::hinted;
use crate::measured::parse_effect_in;
use crate::model::load_model_noting;
use crate::ranges::MAX_SIM_SAMPLES;
use crate::sheet::SheetDoc;
use crate::text::escape;
use crate::units::{AngleUnit, LengthUnit};

/// Everything a simulation needs (metres and radians).
#[derive(Clone, Debug)]
pub struct SimulationRequest {
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
    /// Link masses for the gravity effects (`compliance:J`, `lateral_compliance:J`,
    /// `backlash:J`): an inertials file as `calibrate --inertials` reads it (its `gravity` key
    /// included); `None`: gravity effects are refused.
    pub inertials: Option<String>,
    /// Gravity in the robot's base link frame (m/s², three values), as `calibrate --gravity`:
    /// the direction of a planted `gravity_sag:J` and the gravity of the inertials' torques.
    /// `None`: the inertials file's `gravity`, else `(0, 0, -9.80665)`.
    pub gravity: Option<Vec<f64>>,
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
}

/// Largest magnitude of an `--error` or `--effect` value (metres, radians or the effect's own
/// unit): an error of a kilometre or a thousand radians is no robot's, and beyond it the
/// simulated points leave what the measurement reader accepts (100 m).
pub const MAX_SIM_VALUE: f64 = 1e3;

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
pub struct TruthSection {
    /// The data file's name.
    pub data: String,
    /// The random seed.
    pub seed: u64,
    /// Poses simulated.
    pub poses: usize,
    /// Samples written.
    pub samples: usize,
    /// Noise standard deviation per device axis (metres).
    pub sigma: f64,
    /// The true device frame (`T_device_base`).
    pub device: PoseSi,
    /// With several sessions: every session's true device frame, by name (`s1` is `device`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub sessions: Vec<(String, PoseSi)>,
    /// The true targets in the tip frame.
    pub targets: Vec<TargetDoc>,
    /// The planted geometric errors by parameter name (metres, radians).
    pub errors: Vec<(String, f64)>,
    /// The planted effects by label, in each effect's own unit.
    pub effects: Vec<(String, f64)>,
    /// The gravity model of planted gravity effects (see `dh_calib::pipeline::GravityRecord`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gravity_model: Option<GravityRecord>,
    /// With a planted effect of time, the unit of its `t`: seconds (the samples carry times).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_unit: Option<dh_calib::effects_thermal::TimeUnit>,
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

/// A simulation: the measurements, the CSV that holds them and the truth.
#[derive(Clone, Debug)]
pub struct Simulated {
    /// The measurements (joint values as the controller reports them: coupled joints
    /// uncoupled).
    pub data: Measurements,
    /// The canonical measurement CSV, a comment line first (model, seed, poses, noise, where
    /// the truth is); it reads back as [`Simulated::data`] (checked).
    pub csv: String,
    /// The true model: a DH sheet in metres and radians with its `truth` section.
    pub truth: SheetDoc,
    /// Poses simulated (samples over targets and repeats).
    pub poses: usize,
}

impl Simulated {
    /// The truth as YAML, as `simulate` writes it.
    ///
    /// # Errors
    /// Serialisation failures.
    pub fn truth_yaml(&self) -> Result<String> {
        Ok(serde_yaml::to_string(&self.truth)?)
    }
}

/// Simulates `req`: the data named `data_name` in the truth, the truth file `truth_name` in the
/// CSV's comment; the model's warnings go to `err`.
///
/// # Errors
/// A bad model, option, error or effect (naming it); a set too large; a simulation whose points
/// would not read back (a model far beyond robot size).
pub fn simulate(
    req: &SimulationRequest,
    data_name: &str,
    truth_name: &str,
    err: &mut dyn Write,
) -> Result<Simulated> {
    let args = req;
    let model = load_model_noting(
        &args.model,
        args.base.as_deref(),
        args.tip.as_deref(),
        args.convention,
        err,
    )?;
    if !(args.noise.is_finite() && args.noise >= 0.0) {
        anyhow::bail!("--noise: expected a length >= 0, found {}", args.noise);
    }
    let table = &model.table;
    // Each option is in range on its own; their product sizes the file (and the memory).
    let sweeps = if args.cpa { table.rows.len() } else { 1 };
    let samples = [sweeps, args.targets, args.repeats]
        .iter()
        .fold(args.poses, |n, k| n.saturating_mul(*k));
    if samples > MAX_SIM_SAMPLES {
        return Err(hinted(
            format!(
                "--poses {} x --targets {} x --repeats {}{}: expected at most {} samples, found {samples}",
                args.poses,
                args.targets,
                args.repeats,
                if args.cpa { format!(" x {sweeps} joint sweeps") } else { String::new() },
                MAX_SIM_SAMPLES
            ),
            "simulate fewer poses, targets or repeats",
        ));
    }
    let mut ctx = EffectContext::serial(table);
    let given = crate::calibration::gravity_given(args.gravity.as_deref())?;
    if let Some(g) = given {
        ctx.gravity_vector = g;
    }
    if let Some(path) = &args.inertials {
        let (inertials, gravity) = crate::calibration::read_inertials(path, table)?;
        let gravity = given
            .or(gravity)
            .unwrap_or_else(GravityModel::default_gravity);
        ctx.gravity = Some(Arc::new(
            GravityModel::serial(table, &inertials, gravity)
                .map_err(|e| anyhow::anyhow!("{}: {e}", crate::input::display_name(path)))?,
        ));
    }
    let effects = args
        .effects
        .iter()
        .map(|s| {
            let (label, values) = name_values(s, "effect")?;
            Ok((parse_effect_in(&label, &ctx)?, values))
        })
        .collect::<Result<Vec<_>>>()?;
    // The truth file carries the gravity model of planted gravity effects, as a calibrated
    // sheet does, so that it predicts.
    let gravity_model = effects
        .iter()
        .find_map(|(e, _)| e.gravity_model())
        .and_then(|g| GravityRecord::of(g));
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

    let out_name = data_name.to_string();
    let poses = data.samples.len() / (args.targets.max(1) * args.repeats.max(1));
    // Names escaped: a line feed in a file name would end the comment line and make the rest of
    // it the header (the reader then misses every joint column).
    let mut csv = format!(
        "# simulated by urdf-dh simulate from {} (seed {}, {} poses{}, noise {} m per axis); truth in {}\n",
        escape(&model.origin),
        args.seed,
        poses,
        if args.cpa { " in CPA sweeps" } else { "" },
        args.noise,
        escape(truth_name)
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
    // Escaped, as the sheet reader refuses control and bidi characters in these labels.
    sheet.robot = Some(format!("truth of {}", escape(&out_name)));
    sheet.source = Some(format!(
        "simulated by urdf-dh simulate from {} with the errors below",
        escape(&model.origin)
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
        time_unit: dh_calib::effects_thermal::TimeUnit::of_calibration(
            applied.iter().map(|(n, _)| n.as_str()),
            &data,
        ),
        effects: applied,
        gravity_model,
    };
    sheet.truth = Some(serde_yaml::to_value(&section)?);
    // What simulate writes as the truth, the sheet reader reads: planted errors the reader
    // refuses (a tilt beta beyond a right angle) are refused here, not when the truth is read.
    crate::Sheet::parse(&serde_yaml::to_string(&sheet)?, truth_name).map_err(|e| {
        hinted(
            format!("simulate: the true model would not read back: {e:#}"),
            "plant errors a DH sheet can hold (a tilt beta within 1.5707963 rad, 90 degrees)",
        )
    })?;
    Ok(Simulated {
        data,
        csv,
        truth: sheet,
        poses,
    })
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
