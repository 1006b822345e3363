//! `urdf-dh calibrate`: fit a model to measured points and report each step.
//!
//! Steps (see `dh_calib::calibrate`): `nominal` (only the device frame and the targets are
//! estimated), `geometric` (every identifiable DH, base, tool, device and target parameter),
//! then the effects, when asked for. Each step reports the RMS, mean and largest 3-D distance
//! between modelled and measured points on the calibration data and on validation data (the
//! `--validate` file or the file's own validation split, else k-fold cross-validation over
//! poses). Without `--model` the start is the circle-point analysis of the data.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;
use std::sync::Arc;

use anyhow::{Context, Result};
use dh_calib::calibrate::Validation;
use dh_calib::calibrate::{calibrate as run_calibration, CalibrationOptions, NoiseSource, Report};
use dh_calib::cpa::{analyse, CpaOptions};
use dh_calib::data::{Measurements, Sample, Split};
use dh_calib::diagnose::{diagnose, DiagnoseOptions};
use dh_calib::effects::{label_of, parse_label_in, EffectContext};
use dh_calib::gravity::{GravityModel, Inertial, Inertials};
use dh_calib::model::{Effect, Model, ModelOptions};
use dh_calib::outliers::OutlierOptions;
use dh_calib::tree::DhTree;
use dh_core::pose::{from_xyz_rpy, to_xyz_rpy};
use dh_core::{Convention, DhTable, Tolerance};
use nalgebra::{Isometry3, Vector3};
use serde::Serialize;

use crate::commands::cpa::{CPA_ANGULAR, CPA_LINEAR};
use crate::commands::to_urdf::{check_urdf, urdf_of};
use crate::commands::written::{self, WrittenDoc};
use crate::error::{hinted, Outcome};
use crate::input::display_name;
use crate::measured::{
    header_joints, load_model, parse_effect, read_measurements, DataFile, DataUnits, LoadedModel,
};
use crate::plot::{residuals_svg, Panel, Residual, ResidualChart};
use crate::sheet::{ConventionDoc, EffectDoc, SheetDoc};
use crate::units::{AngleUnit, LengthUnit};

/// Which non-geometric effects to estimate after the geometric step.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum EffectsChoice {
    /// None: the report ends with `geometric`.
    None,
    /// Let the diagnosis of `dh_calib::diagnose` choose.
    Auto,
    /// These labels (`gear_ratio:<joint>`, ...).
    List(Vec<String>),
}

impl std::str::FromStr for EffectsChoice {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.trim() {
            "none" | "" => Ok(EffectsChoice::None),
            "auto" => Ok(EffectsChoice::Auto),
            list => Ok(EffectsChoice::List(
                list.split(',')
                    .map(|l| l.trim().to_string())
                    .filter(|l| !l.is_empty())
                    .collect(),
            )),
        }
    }
}

/// Output format of `calibrate`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Default)]
pub enum CalibrateFormat {
    /// A readable report.
    #[default]
    Text,
    /// JSON, metres and radians.
    Json,
}

/// Everything `calibrate` needs.
#[derive(Clone, Debug)]
pub struct CalibrateArgs {
    /// The model (URDF or DH sheet); `None` starts from circle-point analysis of the data.
    pub model: Option<String>,
    /// Base link of a URDF chain.
    pub base: Option<String>,
    /// Tip link of a URDF chain.
    pub tip: Option<String>,
    /// DH convention for a URDF model or the CPA start.
    pub convention: Convention,
    /// The measurement file.
    pub data: String,
    /// A separate validation file.
    pub validate: Option<String>,
    /// Units of the measurement files (and of `sigma`); reports are in metres and radians.
    pub units: DataUnits,
    /// Effects to estimate.
    pub effects: EffectsChoice,
    /// Keep only these targets (all when empty).
    pub targets: Vec<String>,
    /// Known per-axis noise (metres).
    pub sigma: Option<f64>,
    /// Folds of cross-validation.
    pub folds: usize,
    /// Output format.
    pub format: CalibrateFormat,
    /// Where to write the calibrated model (`.urdf` for a URDF, `.json` for a JSON sheet,
    /// otherwise a YAML sheet).
    pub out: Option<String>,
    /// Where to write the residual chart (SVG).
    pub plot: Option<String>,
    /// Link masses for the gravity effects (YAML); `None` takes a URDF model's inertials.
    pub inertials: Option<String>,
    /// Gravity in the base link frame (m/s²), three values.
    pub gravity: Option<Vec<f64>>,
    /// A payload at the tip: mass (kg) and centre in the tip frame (m), four values.
    pub payload: Option<Vec<f64>>,
    /// Most effects `--effects auto` adds (`dh_calib::diagnose::DiagnoseOptions::max_effects`).
    pub max_effects: usize,
    /// Fit the outliers with the rest (they are still named).
    pub keep_outliers: bool,
    /// No progress line on standard error.
    pub quiet: bool,
}

/// Reads an inertials file: `links: [{joint, mass, com: [x, y, z]}]` (kg, m) with
/// `com_frame: base_at_zero` (base link frame, every joint at zero; the default) or `dh` (the
/// row's DH frame), optional `payloads: [{mass, com}]` (tip frame) and `gravity: [x, y, z]`.
fn read_inertials(path: &str, table: &DhTable) -> Result<(Inertials, Option<Vector3<f64>>)> {
    let origin = display_name(path);
    let text = crate::input::read_text(path)?;
    crate::sheet::check_nesting(&text, &origin)?;
    let doc: serde_yaml::Value =
        serde_yaml::from_str(&text).with_context(|| format!("{origin}: not YAML"))?;
    let num = |v: &serde_yaml::Value, what: &str| -> Result<f64> {
        v.as_f64()
            .ok_or_else(|| anyhow::anyhow!("{origin}: {what}: expected a number, found {v:?}"))
    };
    let vec3 = |v: &serde_yaml::Value, what: &str| -> Result<Vector3<f64>> {
        match v.as_sequence().map(|s| s.as_slice()) {
            Some([x, y, z]) => Ok(Vector3::new(num(x, what)?, num(y, what)?, num(z, what)?)),
            _ => anyhow::bail!("{origin}: {what}: expected [x, y, z], found {v:?}"),
        }
    };
    let mut links = Vec::new();
    for l in doc["links"]
        .as_sequence()
        .map(|s| s.as_slice())
        .unwrap_or_default()
    {
        let joint = l["joint"]
            .as_str()
            .ok_or_else(|| anyhow::anyhow!("{origin}: a link without 'joint'"))?;
        links.push((
            joint.to_string(),
            num(&l["mass"], &format!("{joint} mass"))?,
            vec3(&l["com"], &format!("{joint} com"))?,
        ));
    }
    let mut payloads = Vec::new();
    for p in doc["payloads"]
        .as_sequence()
        .map(|s| s.as_slice())
        .unwrap_or_default()
    {
        payloads.push((
            0,
            Inertial {
                mass: num(&p["mass"], "payload mass")?,
                com: vec3(&p["com"], "payload com")?,
            },
        ));
    }
    let tree = DhTree::serial(table);
    let inertials = if doc["com_frame"].as_str() == Some("dh") {
        Inertials {
            links: links
                .into_iter()
                .map(|(j, mass, com)| (j, Inertial { mass, com }))
                .collect(),
            payloads,
        }
    } else {
        Inertials::from_zero_pose(&tree, &links, payloads)
            .map_err(|e| anyhow::anyhow!("{origin}: {e}"))?
    };
    let gravity = if doc["gravity"].is_null() {
        None
    } else {
        Some(vec3(&doc["gravity"], "gravity")?)
    };
    Ok((inertials, gravity))
}

/// What the gravity effects need: `--inertials`, else a URDF model's `<inertial>` masses
/// (rows named like its joints), with `--payload` and `--gravity`. `None` when there are no
/// masses at all.
pub(crate) fn gravity_inputs(
    args: &CalibrateArgs,
    table: &DhTable,
) -> Result<(Option<Inertials>, Vector3<f64>)> {
    let mut gravity = GravityModel::default_gravity();
    let mut inertials = match (&args.inertials, &args.model) {
        (Some(path), _) => {
            let (i, g) = read_inertials(path, table)?;
            if let Some(g) = g {
                gravity = g;
            }
            Some(i)
        }
        (None, Some(model)) if model.to_ascii_lowercase().ends_with(".urdf") => {
            let urdf = std::fs::read_to_string(model)
                .ok()
                .and_then(|t| urdf_axes::UrdfModel::parse(&t).ok());
            let bodies = urdf.as_ref().and_then(|u| {
                let chain = u.chain(args.base.as_deref(), args.tip.as_deref()).ok()?;
                urdf_axes::inertia::joint_inertials(u, &chain).ok()
            });
            match bodies {
                Some(b) if b.iter().any(|j| j.mass > 0.0) => {
                    let links: Vec<(String, f64, Vector3<f64>)> = b
                        .into_iter()
                        .filter(|j| j.mass > 0.0)
                        .map(|j| (j.joint, j.mass, j.com_at_zero))
                        .collect();
                    Inertials::from_zero_pose(&DhTree::serial(table), &links, vec![]).ok()
                }
                _ => None,
            }
        }
        _ => None,
    };
    if let Some(g) = &args.gravity {
        match g.as_slice() {
            [x, y, z] if g.iter().all(|v| v.is_finite()) => gravity = Vector3::new(*x, *y, *z),
            _ => {
                anyhow::bail!("--gravity: expected three finite numbers X,Y,Z in m/s², found {g:?}")
            }
        }
    }
    if let Some(p) = &args.payload {
        match p.as_slice() {
            [m, x, y, z] if p.iter().all(|v| v.is_finite()) && *m >= 0.0 => {
                inertials
                    .get_or_insert_with(Inertials::default)
                    .payloads
                    .push((
                        0,
                        Inertial {
                            mass: *m,
                            com: Vector3::new(*x, *y, *z),
                        },
                    ));
            }
            _ => anyhow::bail!(
                "--payload: expected MASS,X,Y,Z (kg, then metres in the tip frame), found {p:?}"
            ),
        }
    }
    Ok((inertials, gravity))
}

/// `--effects auto`: calibrate with the effects the diagnosis of `dh-calib` selects
/// (`dh_calib::diagnose`), returning its report (steps `nominal`, `geometric`, then one
/// `+<label>` per effect added, and the candidate table) and the effects it selected (for the
/// residual chart).
///
/// # Errors
/// A calibration or diagnosis that fails (bad inertials, too few samples).
pub fn auto_report(
    table: &DhTable,
    data: &Measurements,
    options: &CalibrationOptions,
    diag: &DiagnoseOptions,
    ctx: &EffectContext,
) -> Result<(Report, Vec<Arc<dyn Effect>>)> {
    let report = diagnose(table, data, options, diag)
        .map_err(|e| anyhow::anyhow!("calibration failed: {e}"))?;
    let effects = report
        .selected_effects
        .iter()
        .map(|l| parse_label_in(l, ctx).map_err(|e| anyhow::anyhow!("{e}")))
        .collect::<Result<_>>()?;
    Ok((report, effects))
}

/// One row of the candidate table (JSON `candidates`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CandidateDoc {
    /// The effect's label.
    pub label: String,
    /// First-order reduction of the calibration sum of squares beyond the geometric fit (m²).
    pub score: f64,
    /// Held-out RMS with it added, linearised (metres).
    pub val_rms: Option<f64>,
    /// Sine between its columns and the geometric ones (below 1e-3: aliased).
    pub independence: f64,
    /// selected, aliased, rejected, not selected, inert, rival.
    pub status: &'static str,
    /// Why a refitted candidate was not added (a rival's names the effect that did better).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
}

impl From<&dh_calib::diagnose::CandidateReport> for CandidateDoc {
    fn from(c: &dh_calib::diagnose::CandidateReport) -> Self {
        CandidateDoc {
            label: c.label.clone(),
            score: c.score,
            val_rms: c.val_rms,
            independence: c.independence,
            status: c.status.name(),
            reason: c.reason.clone(),
        }
    }
}

/// A step as reported (metres).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StepDoc {
    /// `nominal`, `geometric`, `effects`.
    pub label: String,
    /// Free parameters.
    pub free: usize,
    /// Solver iterations.
    pub iterations: usize,
    /// Calibration RMS before the step (the previous step's), `None` for the first.
    pub rms_before: Option<f64>,
    /// Validation RMS before the step.
    pub val_rms_before: Option<f64>,
    /// Calibration RMS.
    pub rms: f64,
    /// Calibration mean.
    pub mean: f64,
    /// Calibration max.
    pub max: f64,
    /// Validation RMS.
    pub val_rms: Option<f64>,
    /// Validation mean.
    pub val_mean: Option<f64>,
    /// Validation max.
    pub val_max: Option<f64>,
    /// Parameters the step would estimate but held at their start, not identifiable from the
    /// data (in `nominal`: device or target coordinates), with what absorbs them.
    pub fixed: Vec<FixedDoc>,
}

/// One parameter as reported.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ParameterDoc {
    /// Name (`<joint>.a`, `base.x`, `device.rz`, `target.<name>.x`, effect names).
    pub name: String,
    /// `m`, `rad` or `1`.
    pub unit: &'static str,
    /// Nominal value (for device and targets: the `nominal` step's estimate).
    pub nominal: f64,
    /// Estimate.
    pub estimate: f64,
    /// Standard error; `None` when held fixed.
    pub std_error: Option<f64>,
    /// Estimated (`false`: held at nominal).
    pub free: bool,
}

/// A parameter held at nominal.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FixedDoc {
    /// Its name.
    pub name: String,
    /// The free parameters that absorb it.
    pub aliases: Vec<String>,
}

impl From<&dh_calib::calibrate::FixedParameter> for FixedDoc {
    fn from(f: &dh_calib::calibrate::FixedParameter) -> Self {
        FixedDoc {
            name: f.name.clone(),
            aliases: f.aliases.clone(),
        }
    }
}

/// How validation was done.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ValidationDoc {
    /// `split`, `k-fold` or `none`.
    pub method: &'static str,
    /// Validation samples (split).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub samples: Option<usize>,
    /// Folds (k-fold).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub folds: Option<usize>,
    /// Pose groups (k-fold).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub groups: Option<usize>,
    /// Training samples each fold is fitted on, when the data are too many to fit every
    /// fold on all of its training samples (k-fold beyond `dh_calib::calibrate::CV_TRAINING_MAX`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub training_subsample: Option<usize>,
}

/// Where the noise level comes from.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct NoiseDoc {
    /// Per-axis standard deviation (metres).
    pub sigma: f64,
    /// `given`, `samples` or `repeats`.
    pub source: &'static str,
}

/// A position with a name.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TargetDoc {
    /// Target name.
    pub name: String,
    /// Position in the tip frame (metres).
    pub xyz: [f64; 3],
}

/// A pose, metres and radians (URDF roll-pitch-yaw).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PoseSi {
    /// Translation (metres).
    pub xyz: [f64; 3],
    /// Roll, pitch, yaw (radians).
    pub rpy: [f64; 3],
}

impl PoseSi {
    /// The pose of `p`.
    pub fn of(p: &Isometry3<f64>) -> Self {
        let (xyz, rpy) = to_xyz_rpy(p);
        Self { xyz, rpy }
    }
}

/// The JSON report; every length in metres, every angle in radians.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CalibrationDoc {
    /// Model file, or `cpa of <data>`.
    pub model: String,
    /// Data file.
    pub data: String,
    /// Validation file.
    pub validate: Option<String>,
    /// Convention of the model.
    pub convention: ConventionDoc,
    /// Always `{length: m, angle: rad}`.
    pub units: UnitsDoc,
    /// Calibration samples.
    pub samples: usize,
    /// Validation samples (split).
    pub validation_samples: usize,
    /// How validation was done.
    pub validation: ValidationDoc,
    /// The steps, in order.
    pub steps: Vec<StepDoc>,
    /// Calibration RMS of `nominal`.
    pub rms_before: f64,
    /// Calibration RMS of the last step.
    pub rms_after: f64,
    /// Validation RMS of `nominal`.
    pub val_rms_before: Option<f64>,
    /// Validation RMS of the last step.
    pub val_rms_after: Option<f64>,
    /// RMS 3-D residual noise alone would leave (metres), when the noise is known.
    pub noise_floor: Option<f64>,
    /// The noise level behind it.
    pub noise: Option<NoiseDoc>,
    /// Condition number of the scaled Jacobian of the free parameters.
    pub condition_number: f64,
    /// Free parameters of the last step.
    pub rank: usize,
    /// Residual standard deviation per coordinate (metres).
    pub sigma_hat: Option<f64>,
    /// Every parameter.
    pub parameters: Vec<ParameterDoc>,
    /// The parameters held at nominal.
    pub fixed: Vec<FixedDoc>,
    /// Labels of the effects estimated in the last step.
    pub selected_effects: Vec<String>,
    /// The candidate table of `--effects auto` (empty otherwise).
    pub candidates: Vec<CandidateDoc>,
    /// Estimated robot base in the device frame (of the first session with several).
    pub device: PoseSi,
    /// With several measurement sessions: each one's device frame and RMS; absent otherwise.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub sessions: Vec<super::calibrate_sessions::SessionDoc>,
    /// Estimated targets in the tip frame.
    pub targets: Vec<TargetDoc>,
    /// Remarks.
    pub notes: Vec<String>,
    /// The proof on the written model (`--out`), see [`crate::commands::written`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub written: Option<WrittenDoc>,
    /// The outlier screen; `null` when it did not run.
    pub outliers: Option<super::calibrate_findings::OutliersDoc>,
    /// The test of the final model and what it means.
    pub verdict: super::calibrate_findings::VerdictDoc,
    /// The rounds of `--effects` (every candidate's scores, every refit and why it was taken
    /// or not, the final structure); `null` without a diagnosis.
    pub diagnosis: Option<super::calibrate_findings::DiagnosisDoc>,
}

/// Units of the JSON report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct UnitsDoc {
    /// `m`.
    pub length: &'static str,
    /// `rad`.
    pub angle: &'static str,
}

/// The unit of a parameter, from its name (see `dh_calib::model`).
pub fn unit_of(name: &str) -> &'static str {
    if name.contains(':') || name == "scale" || name == "drift" {
        // Effect parameters (see `dh_calib::effects`).
        return match name.split(':').next() {
            Some("compliance" | "lateral_compliance") => "rad/(N m)",
            Some("gear_harmonic" | "gear_harmonic2" | "parallel_tilt" | "backlash") => "rad",
            // Radians, metres for a prismatic joint (the report's effect table says which).
            Some("backlash_direction") => "rad",
            Some("gear_ratio" | "coupling") => "rad/rad",
            _ => "1",
        };
    }
    match name.rsplit('.').next() {
        Some("a" | "d" | "x" | "y" | "z") => "m",
        Some("alpha" | "theta" | "beta" | "rx" | "ry" | "rz") => "rad",
        _ => "1",
    }
}

/// The model to start from, the data and the targets kept.
pub(crate) struct Inputs {
    pub(crate) table: DhTable,
    pub(crate) model_name: String,
    robot: Option<String>,
    units: (LengthUnit, AngleUnit),
    links: (String, String),
    coupled: Vec<(String, Vec<(String, f64)>)>,
    pub(crate) data: Measurements,
    cpa: bool,
}

/// Appends `extra`'s samples to `data` as validation samples, targets matched by name.
fn merge_validation(data: &mut Measurements, extra: Measurements) {
    let mut index: HashMap<String, usize> = data
        .targets
        .iter()
        .enumerate()
        .map(|(i, t)| (t.clone(), i))
        .collect();
    let sessions = super::calibrate_sessions::merge(data, &extra);
    for mut s in extra.samples {
        s.session = sessions.get(s.session).copied().unwrap_or(0);
        let name = extra.targets.get(s.target).cloned().unwrap_or_default();
        let next = data.targets.len();
        let k = *index.entry(name.clone()).or_insert_with(|| {
            data.targets.push(name);
            next
        });
        s.target = k;
        s.split = Split::Validation;
        data.samples.push(s);
    }
}

/// Keeps the samples of `keep` (by name) and renumbers the targets.
fn keep_targets(data: &mut Measurements, keep: &[String], origin: &str) -> Result<()> {
    for k in keep {
        if !data.targets.contains(k) {
            return Err(hinted(
                format!("{origin}: --targets names '{k}', which the data does not have"),
                format!("the data's targets: {}", data.targets.join(", ")),
            ));
        }
    }
    let old = std::mem::take(&mut data.targets);
    let mut map = vec![None; old.len()];
    for (i, t) in old.iter().enumerate() {
        if keep.contains(t) {
            map[i] = Some(data.targets.len());
            data.targets.push(t.clone());
        }
    }
    data.samples
        .retain_mut(|s| match map.get(s.target).copied().flatten() {
            Some(k) => {
                s.target = k;
                true
            }
            None => false,
        });
    Ok(())
}

fn load_inputs(args: &CalibrateArgs, err: &mut dyn Write) -> Result<Inputs> {
    let data_name = display_name(&args.data);
    let file = DataFile::read(&args.data)?;
    let (model, joints, prismatic) = match &args.model {
        Some(m) => {
            let model = load_model(
                m,
                args.base.as_deref(),
                args.tip.as_deref(),
                args.convention,
            )?;
            for w in &model.warnings {
                writeln!(err, "urdf-dh: warning: {w}")?;
            }
            let (j, p) = (model.measured_joints(), model.prismatic());
            (Some(model), j, p)
        }
        None => (None, header_joints(&file)?, Vec::new()),
    };
    let mut data = read_measurements(&file, &joints, &prismatic, args.units, err)?;
    if let Some(v) = &args.validate {
        let extra = read_measurements(&DataFile::read(v)?, &joints, &prismatic, args.units, err)?;
        merge_validation(&mut data, extra);
    }
    if let Some(m) = &model {
        m.couple(&mut data)
            .with_context(|| format!("{data_name}: applying the model's coupled joints"))?;
        for w in crate::measured::beyond_limits(&m.table, &data, &data_name) {
            writeln!(err, "urdf-dh: warning: {w}")?;
        }
    }
    if !args.targets.is_empty() {
        keep_targets(&mut data, &args.targets, &data_name)?;
    }
    Ok(match model {
        Some(LoadedModel {
            table,
            origin,
            robot,
            units,
            links,
            coupled,
            ..
        }) => Inputs {
            table,
            model_name: origin,
            robot,
            units,
            links,
            coupled,
            data,
            cpa: false,
        },
        None => {
            let opts = CpaOptions {
                convention: args.convention,
                tolerance: Tolerance::new(CPA_LINEAR, CPA_ANGULAR)
                    .map_err(|e| anyhow::anyhow!("{e}"))?,
                ..CpaOptions::default()
            };
            let cpa = analyse(&data, &opts).map_err(|e| {
                hinted(
                    format!("{data_name}: circle-point analysis failed: {e}"),
                    "without --model the start is the circle-point analysis of the data, which needs one sweep per joint; give a model with --model",
                )
            })?;
            Inputs {
                table: cpa.extraction.table,
                model_name: format!("circle-point analysis of {data_name}"),
                robot: None,
                units: (LengthUnit::M, AngleUnit::Rad),
                links: ("base_link".into(), "tool0".into()),
                coupled: Vec::new(),
                data,
                cpa: true,
            }
        }
    })
}

/// Refuses, before any fitting, point data that cannot determine its own unknowns: every step
/// estimates each target's position (3 parameters) and the device frame (6), and each sample
/// gives 3 coordinates, so fewer than `targets + 3` calibration samples fit nothing (200 rows
/// of 200 targets took minutes to say so).
pub(crate) fn enough_samples(data: &Measurements, data_name: &str) -> Result<()> {
    let cal: Vec<&Sample> = data
        .samples
        .iter()
        .filter(|s| s.split == Split::Calibration)
        .collect();
    let mut targets: Vec<usize> = cal.iter().map(|s| s.target).collect();
    targets.sort_unstable();
    targets.dedup();
    let needed = targets.len() + 3;
    if cal.len() < needed {
        return Err(hinted(
            format!(
                "{data_name}: expected at least {needed} calibration samples for {} target(s) (each target's position and the device frame are estimated: 3 per target + 6, 3 coordinates per sample), found {}",
                targets.len(),
                cal.len()
            ),
            "measure each target at several poses (the target column names the reflector, not the pose)",
        ));
    }
    Ok(())
}

/// Runs `calibrate`.
///
/// # Errors
/// Bad model or data files (naming the file, line and column), unknown effects, a calibration
/// that cannot start (too few samples, collinear points), failed writes.
pub fn calibrate(
    args: &CalibrateArgs,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> Result<Outcome> {
    let inputs = load_inputs(args, err)?;
    if inputs.data.samples.iter().any(|s| s.socket.is_some()) {
        return crate::commands::sockets::calibrate_contacts(args, &inputs, out, err);
    }
    enough_samples(&inputs.data, &display_name(&args.data))?;
    let (inertials, gravity) = gravity_inputs(args, &inputs.table)?;
    let ctx = EffectContext {
        tree: DhTree::serial(&inputs.table),
        gravity: match &inertials {
            Some(i) => Some(Arc::new(
                GravityModel::serial(&inputs.table, i, gravity)
                    .map_err(|e| anyhow::anyhow!("inertials: {e}"))?,
            )),
            None => None,
        },
    };
    let effects: Vec<Arc<dyn Effect>> = match &args.effects {
        EffectsChoice::List(labels) => labels
            .iter()
            .map(|l| match parse_label_in(l, &ctx) {
                Ok(e) => Ok(e),
                // The CLI's message names the kinds and joints.
                Err(_) => parse_effect(l, &inputs.table),
            })
            .collect::<Result<_>>()?,
        EffectsChoice::None | EffectsChoice::Auto => Vec::new(),
    };
    if let Some(s) = args.sigma {
        if !(s.is_finite() && s > 0.0) {
            anyhow::bail!("--sigma: expected a positive length, found {s}");
        }
    }
    let options = CalibrationOptions {
        folds: args.folds,
        sigma: args.sigma.map(|s| s * args.units.length.metres()),
        effects: effects.clone(),
        // The CPA table is already in the device frame: its base is DH frame 0 there.
        device_guess: inputs.cpa.then(Isometry3::identity),
        outliers: OutlierOptions {
            keep: args.keep_outliers,
            ..OutlierOptions::default()
        },
        ..CalibrationOptions::default()
    };
    let cal = inputs
        .data
        .samples
        .iter()
        .filter(|s| s.split == Split::Calibration)
        .count();
    // A rough size of the work: samples times folds times steps.
    if cal * (args.folds + 1) * (2 + usize::from(!effects.is_empty())) > 200_000 {
        writeln!(
            err,
            "urdf-dh: calibrating {} ({} samples, {} targets, {}-fold cross-validation unless there is a validation split); this may take a while",
            inputs.model_name,
            cal,
            inputs.data.targets.len(),
            args.folds
        )?;
    }
    let failed = |e: dh_calib::CalibError| {
        anyhow::anyhow!("{}: calibration failed: {e}", display_name(&args.data))
    };
    let progress = crate::progress::Progress::start(
        &format!(
            "calibrating {} against {} ({cal} samples{})",
            inputs.model_name,
            display_name(&args.data),
            if args.effects == EffectsChoice::Auto {
                ", effects searched"
            } else {
                ""
            }
        ),
        args.quiet,
    );
    let (report, effects) = match &args.effects {
        EffectsChoice::Auto => {
            let diag = DiagnoseOptions {
                inertials,
                gravity,
                max_effects: args.max_effects,
                ..DiagnoseOptions::default()
            };
            auto_report(&inputs.table, &inputs.data, &options, &diag, &ctx)?
        }
        EffectsChoice::None | EffectsChoice::List(_) => (
            run_calibration(&inputs.table, &inputs.data, &options).map_err(failed)?,
            effects,
        ),
    };
    drop(progress);
    let mut doc = document(args, &inputs, &report);
    // Every output file is built (and the model proved as written) before any is written, and
    // all are written or none.
    let mut files = Vec::new();
    if let Some(path) = &args.out {
        let (text, proof) = model_text(path, args.model.as_deref(), &inputs, &report, &doc)?;
        let passed = proof.passed;
        doc.written = Some(proof);
        if passed {
            if path.to_ascii_lowercase().ends_with(".urdf") && !report.selected_effects.is_empty() {
                writeln!(
                    err,
                    "urdf-dh: warning: {}: a URDF cannot express the estimated effects {}; it holds the geometric part (write a sheet to keep them)",
                    display_name(path),
                    report.selected_effects.iter().map(|e| format!("'{e}'")).collect::<Vec<_>>().join(", ")
                )?;
            }
            files.push((Path::new(path), text));
        }
    }
    let proved = doc.written.as_ref().is_none_or(|w| w.passed);
    if let Some(path) = &args.plot {
        // Residuals are millimetres or less on any arm: the chart reads best in mm whatever
        // the report's unit.
        let chart = chart(
            &display_name(&args.data),
            &inputs,
            &report,
            &effects,
            LengthUnit::Mm,
        )?;
        files.push((Path::new(path), residuals_svg(&chart)));
    }
    // A model that fails its proof is not written, and neither is anything else.
    // `--out -` or `--plot -`: that artefact on standard output, the report on standard error.
    let piped = crate::output::any_stdout([args.out.as_deref(), args.plot.as_deref()]);
    if proved {
        let files: Vec<(&Path, &[u8])> = files.iter().map(|(p, b)| (*p, b.as_bytes())).collect();
        crate::output::write_all_or_stdout(&files, out)?;
    }
    let report_sink: &mut dyn Write = if piped { err } else { out };
    match args.format {
        CalibrateFormat::Json => {
            report_sink.write_all((serde_json::to_string_pretty(&doc)? + "\n").as_bytes())?;
        }
        CalibrateFormat::Text => report_sink.write_all(text(&doc, &inputs).as_bytes())?,
    }
    Ok(if proved {
        Outcome::Pass
    } else {
        Outcome::Differs
    })
}

fn document(args: &CalibrateArgs, inputs: &Inputs, report: &Report) -> CalibrationDoc {
    let validation = match &report.validation {
        Validation::Split { samples } => ValidationDoc {
            method: "split",
            samples: Some(*samples),
            folds: None,
            groups: None,
            training_subsample: None,
        },
        Validation::CrossValidation {
            folds,
            groups,
            training_subsample,
        } => ValidationDoc {
            method: "k-fold",
            samples: None,
            folds: Some(*folds),
            groups: Some(*groups),
            training_subsample: *training_subsample,
        },
        Validation::None => ValidationDoc {
            method: "none",
            samples: None,
            folds: None,
            groups: None,
            training_subsample: None,
        },
    };
    let val_count = inputs
        .data
        .samples
        .iter()
        .filter(|s| s.split == Split::Validation)
        .count();
    let (outliers, verdict, diagnosis) = super::calibrate_findings::documents(report);
    CalibrationDoc {
        model: inputs.model_name.clone(),
        data: display_name(&args.data),
        validate: args.validate.as_deref().map(display_name),
        convention: inputs.table.convention.into(),
        units: UnitsDoc {
            length: "m",
            angle: "rad",
        },
        samples: inputs.data.samples.len() - val_count,
        validation_samples: val_count,
        validation,
        steps: report
            .steps
            .iter()
            .map(|s| StepDoc {
                label: s.label.clone(),
                free: s.free,
                iterations: s.iterations,
                rms_before: s.rms_before,
                val_rms_before: s.val_rms_before,
                rms: s.rms,
                mean: s.mean,
                max: s.max,
                val_rms: s.val_rms,
                val_mean: s.val_mean,
                val_max: s.val_max,
                fixed: s.fixed.iter().map(FixedDoc::from).collect(),
            })
            .collect(),
        rms_before: report.rms_before,
        rms_after: report.rms_after,
        val_rms_before: report.val_rms_before,
        val_rms_after: report.val_rms_after,
        noise_floor: report.noise_floor.as_ref().map(|n| n.rms),
        noise: report.noise_floor.as_ref().map(|n| NoiseDoc {
            sigma: n.sigma,
            source: match n.source {
                NoiseSource::Given => "given",
                NoiseSource::Samples => "samples",
                NoiseSource::Repeats { .. } => "repeats",
            },
        }),
        condition_number: report.condition_number,
        rank: report.rank,
        sigma_hat: report.sigma_hat,
        parameters: report
            .parameters
            .iter()
            .map(|p| ParameterDoc {
                name: p.name.clone(),
                unit: unit_of(&p.name),
                nominal: p.nominal,
                estimate: p.estimate,
                std_error: p.std_error,
                free: p.free,
            })
            .collect(),
        fixed: report.fixed.iter().map(FixedDoc::from).collect(),
        selected_effects: report.selected_effects.clone(),
        candidates: report.candidates.iter().map(CandidateDoc::from).collect(),
        device: PoseSi::of(&report.device),
        sessions: super::calibrate_sessions::docs(report),
        targets: report
            .targets
            .iter()
            .map(|(n, p)| TargetDoc {
                name: n.clone(),
                xyz: [p.x, p.y, p.z],
            })
            .collect(),
        notes: report.notes.clone(),
        written: None,
        outliers,
        verdict,
        diagnosis,
    }
}

/// A length in the report's unit with micrometre resolution.
fn len(v: f64, unit: LengthUnit) -> String {
    let v = v / unit.metres();
    let s = match unit {
        LengthUnit::M => format!("{v:.6}"),
        LengthUnit::Mm => format!("{v:.3}"),
    };
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        s.trim_start_matches('-').to_string()
    } else {
        s
    }
}

/// A parameter value in its unit (lengths and angles in the report's units).
/// A standard error as [`value`] prints it, or in scientific notation in the same unit when
/// that would print only zeros (a fit of millions of points pins lengths below a micrometre).
fn std_error(e: f64, unit: &str, units: DataUnits) -> String {
    let fixed = value(e, unit, units);
    if e == 0.0 || !fixed.chars().all(|c| c == '0' || c == '.') {
        return fixed;
    }
    let shown = match (unit, units.angle) {
        ("m", _) => e / units.length.metres(),
        ("rad", AngleUnit::Deg) => e.to_degrees(),
        _ => e,
    };
    format!("{shown:.1e}")
}

fn value(v: f64, unit: &str, units: DataUnits) -> String {
    let s = match unit {
        "m" => return len(v, units.length),
        "rad" => match units.angle {
            AngleUnit::Rad => format!("{v:.7}"),
            AngleUnit::Deg => format!("{:.5}", v.to_degrees()),
        },
        _ => format!("{v:.4e}"),
    };
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        s.trim_start_matches('-').to_string()
    } else {
        s
    }
}

fn unit_label(unit: &str, units: DataUnits) -> &'static str {
    match unit {
        "m" => units.length.symbol(),
        "rad" => units.angle.symbol(),
        _ => "1",
    }
}

/// The readable report: metres and radians, like the JSON (the unit options say what the
/// measurement files hold, not how to print).
fn text(doc: &CalibrationDoc, inputs: &Inputs) -> String {
    let units = DataUnits::default();
    let lu = units.length;
    let l = |v: f64| len(v, lu);
    let o = |v: Option<f64>| v.map_or_else(|| "-".to_string(), |v| len(v, lu));
    let mut s = String::new();
    let robot = inputs
        .robot
        .as_deref()
        .map(|r| format!("{r}, "))
        .unwrap_or_default();
    let _ = writeln!(
        s,
        "calibration of {robot}{} ({} DH, {} joints) against {}",
        doc.model,
        inputs.table.convention,
        inputs.table.rows.len(),
        doc.data
    );
    let validation = match doc.validation.method {
        "split" => format!(
            "validation on {} held-out samples{}",
            doc.validation_samples,
            doc.validate
                .as_deref()
                .map(|v| format!(" ({v})"))
                .unwrap_or_default()
        ),
        "k-fold" => format!(
            "{}-fold cross-validation over {} poses{}",
            doc.validation.folds.unwrap_or(0),
            doc.validation.groups.unwrap_or(0),
            doc.validation
                .training_subsample
                .map(|n| format!(" (each fold fitted on {n} evenly spaced training samples)"))
                .unwrap_or_default()
        ),
        _ => "no validation (fewer than 2 poses)".to_string(),
    };
    let _ = writeln!(
        s,
        "data: {} calibration samples of {} target(s) ({}); {validation}",
        doc.samples,
        doc.targets.len(),
        doc.targets
            .iter()
            .map(|t| t.name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    );
    match (&doc.noise, doc.noise_floor) {
        (Some(n), Some(f)) => {
            let _ = writeln!(
                s,
                "noise: {} {} per axis ({}); noise floor {} {} RMS",
                l(n.sigma),
                lu.symbol(),
                match n.source {
                    "given" => "given with --sigma",
                    "samples" => "the samples' sigma",
                    _ => "pure error of repeated poses",
                },
                l(f),
                lu.symbol()
            );
        }
        _ => {
            let _ = writeln!(
                s,
                "noise: unknown (no sigma column, no repeated poses, no --sigma)"
            );
        }
    }
    let _ = writeln!(
        s,
        "{:<12} {:>5} {:>5} {:>11} {:>11} {:>11} {:>11} {:>11} {:>11}  [{}]",
        "step",
        "free",
        "iter",
        "rms",
        "mean",
        "max",
        "val_rms",
        "val_mean",
        "val_max",
        lu.symbol()
    );
    for st in &doc.steps {
        let _ = writeln!(
            s,
            "{:<12} {:>5} {:>5} {:>11} {:>11} {:>11} {:>11} {:>11} {:>11}",
            st.label,
            st.free,
            st.iterations,
            l(st.rms),
            l(st.mean),
            l(st.max),
            o(st.val_rms),
            o(st.val_mean),
            o(st.val_max)
        );
    }
    // What the nominal step could not estimate (targets seen at one tool orientation only,
    // aliased with the device frame) stayed at the closed-form start.
    if let Some(first) = doc.steps.first().filter(|st| !st.fixed.is_empty()) {
        let _ = writeln!(
            s,
            "{} step: held at the start ({}; not identifiable from this data):",
            first.label,
            first.fixed.len()
        );
        for f in &first.fixed {
            let _ = writeln!(s, "  {:<28} {}", f.name, absorbed(&f.aliases));
        }
    }
    let _ = writeln!(
        s,
        "identifiability: {} free parameters, condition number {:.3e}{}",
        doc.rank,
        doc.condition_number,
        doc.sigma_hat
            .map(|v| format!(", residual sigma {} {} per coordinate", l(v), lu.symbol()))
            .unwrap_or_default()
    );
    if doc.fixed.is_empty() {
        let _ = writeln!(s, "fixed at nominal: none");
    } else {
        let _ = writeln!(
            s,
            "fixed at nominal ({}; not identifiable from this data):",
            doc.fixed.len()
        );
        for f in &doc.fixed {
            let _ = writeln!(s, "  {:<28} {}", f.name, absorbed(&f.aliases));
        }
    }
    let _ = writeln!(
        s,
        "estimated parameters (nominal -> estimate +- standard error):"
    );
    let width = crate::guard::column_width(doc.parameters.iter().map(|p| p.name.as_str()), 4);
    for p in doc.parameters.iter().filter(|p| {
        p.free
            && !p.name.starts_with("device.")
            && !p.name.starts_with("session.")
            && !p.name.starts_with("target.")
    }) {
        let _ = writeln!(
            s,
            "  {:<width$} [{:>3}] {:>13} -> {:>13} +- {}",
            crate::guard::escape(&p.name),
            unit_label(p.unit, units),
            value(p.nominal, p.unit, units),
            value(p.estimate, p.unit, units),
            p.std_error
                .map_or_else(|| "-".into(), |e| std_error(e, p.unit, units))
        );
    }
    let rpy = |r: [f64; 3]| {
        r.map(|v| value(v, "rad", units))
            .into_iter()
            .collect::<Vec<_>>()
            .join(" ")
    };
    let xyz = |p: [f64; 3]| p.map(l).into_iter().collect::<Vec<_>>().join(" ");
    let _ = writeln!(
        s,
        "device frame (robot base in the device frame): xyz [{}] {}  rpy [{}] {}",
        lu.symbol(),
        xyz(doc.device.xyz),
        units.angle.symbol(),
        rpy(doc.device.rpy)
    );
    super::calibrate_sessions::text(&mut s, &doc.sessions, &xyz, &rpy, &o);
    for t in &doc.targets {
        let _ = writeln!(
            s,
            "target {} (tip frame): xyz [{}] {}",
            t.name,
            lu.symbol(),
            xyz(t.xyz)
        );
    }
    if !doc.candidates.is_empty() {
        let _ = writeln!(
            s,
            "effect candidates (first round, best score first; score = SSR reduction beyond the geometric fit, held-out RMS linearised):"
        );
        let _ = writeln!(
            s,
            "  {:<32} {:>12} {:>12} {:>12}  status",
            "label",
            format!("score [{}²]", lu.symbol()),
            "independence",
            format!("val_rms [{}]", lu.symbol())
        );
        let scale = lu.metres();
        for c in doc.candidates.iter().take(15) {
            let _ = writeln!(
                s,
                "  {:<32} {:>12.4e} {:>12.4} {:>12}  {}",
                c.label,
                c.score / (scale * scale),
                c.independence,
                o(c.val_rms),
                match (c.status, &c.reason) {
                    ("rival", Some(r)) => format!("rival ({r})"),
                    (s, _) => s.to_string(),
                }
            );
        }
        if doc.candidates.len() > 15 {
            let _ = writeln!(
                s,
                "  ... {} more (see --format json)",
                doc.candidates.len() - 15
            );
        }
    }
    if !doc.selected_effects.is_empty() {
        let _ = writeln!(s, "effects: {}", doc.selected_effects.join(", "));
        for p in doc
            .parameters
            .iter()
            .filter(|p| p.name.contains(':') || p.name == "scale" || p.name == "drift")
        {
            let stiffness = (p.unit == "rad/(N m)" && p.estimate != 0.0).then(|| {
                format!(
                    "  (stiffness {:.4e}{} N m/rad)",
                    1.0 / p.estimate,
                    p.std_error
                        .map(|e| format!(" +- {:.1e}", e / (p.estimate * p.estimate)))
                        .unwrap_or_default()
                )
            });
            let _ = writeln!(
                s,
                "  {} = {:.6e}{} {}{}",
                p.name,
                p.estimate,
                p.std_error
                    .map(|e| format!(" +- {e:.1e}"))
                    .unwrap_or_default(),
                p.unit,
                stiffness.unwrap_or_default()
            );
        }
    }
    for n in &doc.notes {
        let _ = writeln!(s, "note: {n}");
    }
    s.push_str(&super::calibrate_findings::text(
        doc.outliers.as_ref(),
        &doc.verdict,
    ));
    if let Some(w) = &doc.written {
        let _ = writeln!(s, "{}", crate::commands::written::line(w));
    }
    let _ = writeln!(
        s,
        "result: RMS {} -> {} {}{}",
        l(doc.rms_before),
        l(doc.rms_after),
        lu.symbol(),
        match (doc.val_rms_before, doc.val_rms_after) {
            (Some(b), Some(a)) => format!(" (validation {} -> {} {})", l(b), l(a), lu.symbol()),
            _ => String::new(),
        }
    );
    s
}

/// How a fixed parameter's error shows in the data: the free parameters that absorb it.
fn absorbed(aliases: &[String]) -> String {
    if aliases.is_empty() {
        "no effect on the data".to_string()
    } else {
        format!("absorbed by {}", aliases.join(", "))
    }
}

/// The calibrated model's text for `path` (a URDF for `.urdf`, a JSON sheet for `.json`, else
/// YAML) and the proof on it (see [`crate::commands::written`]).
///
/// # Errors
/// Serialisation failures, and an artefact that does not read back.
fn model_text(
    path: &str,
    model_path: Option<&str>,
    inputs: &Inputs,
    report: &Report,
    doc: &CalibrationDoc,
) -> Result<(String, WrittenDoc)> {
    let calibration = CalibrationSection {
        data: doc.data.clone(),
        rms_before: doc.rms_before,
        rms_after: doc.rms_after,
        val_rms_before: doc.val_rms_before,
        val_rms_after: doc.val_rms_after,
        device: doc.device.clone(),
        sessions: super::calibrate_sessions::frames(&doc.sessions),
        targets: doc.targets.clone(),
        effects: doc
            .parameters
            .iter()
            // Effect parameters are named `<kind>:<joints>` or `scale`
            // (`dh_calib::effects`), whatever their unit.
            .filter(|p| p.free && (p.name.contains(':') || p.name == "scale" || p.name == "drift"))
            .map(|p| (p.name.clone(), p.estimate))
            .collect(),
        covariance: report
            .covariance
            .as_ref()
            .map(crate::calibrated::CovarianceDoc::of),
    };
    let source = format!(
        "calibrated by urdf-dh calibrate from {} against {}: RMS {:.6} m -> {:.6} m",
        doc.model, doc.data, doc.rms_before, doc.rms_after
    );
    let effects: Vec<EffectDoc> = doc
        .parameters
        .iter()
        .filter(|p| p.free && (p.name.contains(':') || p.name == "scale" || p.name == "drift"))
        .map(|p| EffectDoc {
            name: p.name.clone(),
            value: p.estimate,
            unit: p.unit.to_string(),
            std_error: p.std_error,
        })
        .collect();
    // A model whose own rows put a near-parallel pair's common normal far away (an URDF
    // extracted beyond its angular tolerance) is written in the Hayati form: the same
    // kinematics, bounded lengths. The length bound is the size of the model in that form.
    let hayati = ModelOptions::DEFAULT_HAYATI_THRESHOLD;
    let size = inputs.table.hayati_form(hayati).size();
    let longest = |t: &DhTable| {
        t.rows
            .iter()
            .flat_map(|r| [r.a.abs(), r.d.abs()])
            .fold(0.0, f64::max)
    };
    let table = if longest(&report.calibrated) > size + written::LENGTH_MARGIN {
        report.calibrated.hayati_form(hayati)
    } else {
        report.calibrated.clone()
    };
    let urdf = |p: &str| p.to_ascii_lowercase().ends_with(".urdf");
    // A URDF model written as a URDF: a minimal edit of the user's own file.
    let text = match model_path.filter(|m| urdf(m) && urdf(path) && *m != "-") {
        Some(m) => crate::commands::urdf_edit::minimal_edit(
            &crate::input::read_text(m)?,
            &inputs.table,
            // Row for row the nominal table's counterpart, so each joint frame moves by the
            // fit's small change, whatever the rows' form.
            &report.calibrated,
            &inputs.links.0,
            &inputs.links.1,
        )
        .with_context(|| {
            format!(
                "{}: writing the calibrated model as an edit of the model URDF",
                display_name(path)
            )
        })?,
        None => calibrated_text(
            path,
            inputs,
            &table,
            source,
            serde_yaml::to_value(&calibration)?,
            effects,
        )?,
    };
    let q = row_values(&report.calibrated, &inputs.data)?;
    let target: Vec<usize> = inputs.data.samples.iter().map(|s| s.target).collect();
    let targets: Vec<Vector3<f64>> = report.targets.iter().map(|(_, p)| *p).collect();
    let proof = written::prove(
        path,
        &text,
        &report.calibrated,
        size,
        (&inputs.links.0, &inputs.links.1),
        &written::Predictions {
            q: &q,
            target: &target,
            targets: &targets,
            device: report.device,
        },
    )?;
    let proof = predict_proof(path, &text, report, &doc.sessions, &q, &target, proof)?;
    Ok((text, proof))
}

/// The second half of the proof for a sheet: `predict` reads it back (effects, device frame,
/// targets, covariance) and its predictions of every measured point, effects included, are the
/// fitted model's within [`written::WRITTEN_TOLERANCE`]. A model with gravity effects (which
/// need the link masses `predict` does not take) keeps the geometric proof alone.
///
/// # Errors
/// A sheet `predict` cannot read: a defect of the writer, reported as such.
fn predict_proof(
    path: &str,
    text: &str,
    report: &Report,
    sessions: &[super::calibrate_sessions::SessionDoc],
    q: &[Vec<f64>],
    target: &[usize],
    mut proof: WrittenDoc,
) -> Result<WrittenDoc> {
    if path.to_ascii_lowercase().ends_with(".urdf") {
        return Ok(proof);
    }
    let ctx = EffectContext::serial(&report.calibrated);
    let Ok(fitted) = dh_calib::predict::Calibrated::from_report(report, &ctx) else {
        return Ok(proof);
    };
    let name = display_name(path);
    let back = crate::calibrated::calibrated_sheet(text, &name).with_context(|| {
        format!(
            "{name}: the calibrated sheet does not read back for predict (a defect of the writer)"
        )
    })?;
    let frame = dh_calib::predict::Frame::Device;
    let mut worst = 0.0f64;
    for (q, &k) in q.iter().zip(target) {
        let d = (back.calibrated.point(q, k, frame) - fitted.point(q, k, frame)).norm();
        worst = worst.max(if d.is_finite() { d } else { f64::INFINITY });
    }
    // The other sessions' device frames read back as written.
    worst = worst.max(super::calibrate_sessions::read_back_deviation(
        sessions,
        &back.sessions,
    ));
    proof.max_deviation = proof.max_deviation.max(worst);
    proof.passed &= worst <= written::WRITTEN_TOLERANCE;
    Ok(proof)
}

/// `table` as the calibrated model of `inputs` without effects (see [`calibrated_text`]), for
/// the contact and tree paths.
///
/// # Errors
/// Serialisation failures, and names or values a URDF cannot hold.
pub(crate) fn calibrated_bytes(
    path: &str,
    inputs: &Inputs,
    table: &DhTable,
    source: String,
    calibration: serde_yaml::Value,
) -> Result<String> {
    calibrated_text(path, inputs, table, source, calibration, Vec::new())
}

/// `table` as the calibrated model of `inputs` (its robot name, links, units and coupled
/// joints): a URDF for `.urdf`, else a sheet (JSON for `.json`, else YAML) with `source`, the
/// `calibration` section and the estimated `effects`.
///
/// # Errors
/// Serialisation failures, and names or values a URDF cannot hold.
fn calibrated_text(
    path: &str,
    inputs: &Inputs,
    table: &DhTable,
    source: String,
    calibration: serde_yaml::Value,
    effects: Vec<EffectDoc>,
) -> Result<String> {
    let lower = path.to_ascii_lowercase();
    let robot = inputs.robot.clone().unwrap_or_else(|| "robot".into());
    let bytes = if lower.ends_with(".urdf") {
        check_urdf(table, &robot, &inputs.links.0, &inputs.links.1)?;
        urdf_of(table, &robot, &inputs.links.0, &inputs.links.1)
    } else {
        let (lu, au) = inputs.units;
        let mut sheet = SheetDoc::from_table(table, lu, au);
        sheet.robot = inputs.robot.clone();
        if !inputs.coupled.is_empty() {
            sheet.coupled = Some(
                inputs
                    .coupled
                    .iter()
                    .map(|(j, t)| (j.clone(), t.iter().cloned().collect()))
                    .collect(),
            );
        }
        sheet.source = Some(source);
        sheet.calibration = Some(calibration);
        sheet.effects = (!effects.is_empty()).then_some(effects);
        if lower.ends_with(".json") {
            serde_json::to_string_pretty(&sheet)? + "\n"
        } else {
            serde_yaml::to_string(&sheet)?
        }
    };
    Ok(bytes)
}

/// The `calibration` section of a calibrated sheet (metres, radians): what the table was
/// fitted with, and the frames it needs to predict the measured points.
#[derive(Clone, Debug, PartialEq, Serialize)]
struct CalibrationSection {
    data: String,
    rms_before: f64,
    rms_after: f64,
    val_rms_before: Option<f64>,
    val_rms_after: Option<f64>,
    device: PoseSi,
    /// Every session's device frame but the first's (`device`), with several sessions.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    sessions: Vec<super::calibrate_sessions::SessionFrameDoc>,
    targets: Vec<TargetDoc>,
    effects: Vec<(String, f64)>,
    /// Covariance of the last step's free parameters: what `predict` propagates.
    #[serde(skip_serializing_if = "Option::is_none")]
    covariance: Option<crate::calibrated::CovarianceDoc>,
}

/// Joint values of every sample in `table`'s row order (mimic rows follow their drivers).
fn row_values(table: &DhTable, data: &Measurements) -> Result<Vec<Vec<f64>>> {
    let column = |name: &str| data.joint_names.iter().position(|n| n == name);
    let mut sources = Vec::with_capacity(table.rows.len());
    for r in &table.rows {
        let s = match (column(&r.name), &r.mimic) {
            (Some(c), _) => (c, 1.0, 0.0),
            (None, Some(m)) => (
                column(&m.joint).with_context(|| format!("no column for joint '{}'", m.joint))?,
                m.multiplier,
                m.offset,
            ),
            (None, None) => anyhow::bail!("no column for joint '{}'", r.name),
        };
        sources.push(s);
    }
    Ok(data
        .samples
        .iter()
        .map(|s| {
            sources
                .iter()
                .map(|&(c, m, o)| m * s.q.get(c).copied().unwrap_or(0.0) + o)
                .collect()
        })
        .collect())
}

/// Pose index of every sample: samples sharing `config` (or else joint values) are one pose,
/// numbered in order of first appearance; and the number of poses.
fn pose_indices(data: &Measurements) -> (Vec<usize>, usize) {
    let mut ids: HashMap<String, usize> = HashMap::new();
    let v = data
        .samples
        .iter()
        .map(|s| {
            let key = match &s.config {
                Some(c) => format!("c{c}"),
                None => format!("q{:?}", s.q.iter().map(|v| v.to_bits()).collect::<Vec<_>>()),
            };
            let next = ids.len();
            *ids.entry(key).or_insert(next)
        })
        .collect();
    (v, ids.len())
}

/// Distances between the points `table` (with `effects` at `values`, the device frame and
/// the targets) predicts and the measured ones, per sample.
fn distances(
    table: &DhTable,
    effects: &[(Arc<dyn Effect>, Vec<f64>)],
    device: &Isometry3<f64>,
    targets: &[Vector3<f64>],
    data: &Measurements,
) -> Result<Vec<f64>> {
    let mut model = Model::new(table, &data.targets, &ModelOptions::default())?;
    let mut x_effects = Vec::new();
    for (e, v) in effects {
        let range = model.add_effect(e.clone())?;
        x_effects.push((range, v.clone()));
    }
    model.set_device(device);
    for (k, t) in targets.iter().enumerate() {
        model.set_target(k, *t);
    }
    let mut x = vec![0.0; model.parameter_count()];
    for (range, v) in x_effects {
        for (i, val) in range.zip(v) {
            if let Some(slot) = x.get_mut(i) {
                *slot = val;
            }
        }
    }
    let q = row_values(table, data)?;
    // The effects of the sample order see each sample's place in the sequence, as the fit did.
    let contexts = dh_calib::effects_order::contexts_of(q.iter().map(Vec::as_slice), data);
    Ok(data
        .samples
        .iter()
        .zip(&q)
        .zip(&contexts)
        .map(|((s, q), c)| (model.point_in(&x, q, c, s.target) - s.point).norm())
        .collect())
}

/// The nominal-step device frame and targets, from the report's `nominal` column.
fn nominal_frames(report: &Report, targets: &[String]) -> (Isometry3<f64>, Vec<Vector3<f64>>) {
    let get = |name: &str| {
        report
            .parameters
            .iter()
            .find(|p| p.name == name)
            .map_or(0.0, |p| p.nominal)
    };
    let device = from_xyz_rpy(
        [get("device.x"), get("device.y"), get("device.z")],
        [get("device.rx"), get("device.ry"), get("device.rz")],
    );
    let t = targets
        .iter()
        .map(|n| {
            Vector3::new(
                get(&format!("target.{n}.x")),
                get(&format!("target.{n}.y")),
                get(&format!("target.{n}.z")),
            )
        })
        .collect();
    (device, t)
}

/// The residual chart: the `nominal` step's model and the final one.
fn chart(
    data_name: &str,
    inputs: &Inputs,
    report: &Report,
    effects: &[Arc<dyn Effect>],
    unit: LengthUnit,
) -> Result<ResidualChart> {
    let data = &inputs.data;
    let (poses, count) = pose_indices(data);
    let (device0, targets0) = nominal_frames(report, &data.targets);
    let before = distances(&inputs.table, &[], &device0, &targets0, data)?;
    // The effects of the last step, with their estimates.
    let estimates: Vec<(Arc<dyn Effect>, Vec<f64>)> = effects
        .iter()
        .filter(|e| report.selected_effects.contains(&label_of(e.as_ref())))
        .map(|e| {
            let v = e
                .parameter_names()
                .iter()
                .map(|n| {
                    report
                        .parameters
                        .iter()
                        .find(|p| &p.name == n)
                        .map_or(0.0, |p| p.estimate)
                })
                .collect();
            (e.clone(), v)
        })
        .collect();
    let targets1: Vec<Vector3<f64>> = data
        .targets
        .iter()
        .map(|n| {
            report
                .targets
                .iter()
                .find(|(t, _)| t == n)
                .map_or_else(Vector3::zeros, |(_, p)| *p)
        })
        .collect();
    let after = distances(
        &report.calibrated,
        &estimates,
        &report.device,
        &targets1,
        data,
    )?;
    let panel = |label: String, d: Vec<f64>, rms: f64, floor: Option<f64>| Panel {
        label,
        residuals: d
            .into_iter()
            .zip(&poses)
            .zip(&data.samples)
            .map(|((distance, &pose), s)| Residual {
                pose,
                distance,
                validation: s.split == Split::Validation,
            })
            .collect(),
        rms: Some(rms),
        floor,
    };
    let last = report
        .steps
        .last()
        .map_or("geometric", |s| s.label.as_str());
    Ok(ResidualChart {
        title: format!(
            "residuals per pose: {} against {} ({} samples of {} target(s))",
            inputs.model_name,
            data_name,
            data.samples.len(),
            data.targets.len()
        ),
        unit,
        poses: count,
        panels: vec![
            panel(
                "before: nominal model (device frame and targets fitted)".into(),
                before,
                report.rms_before,
                None,
            ),
            panel(
                format!("after: {last}"),
                after,
                report.rms_after,
                report.noise_floor.as_ref().map(|n| n.rms),
            ),
        ],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn standard_errors_below_the_printed_digits_switch_to_scientific() {
        let units = DataUnits {
            length: LengthUnit::M,
            angle: AngleUnit::Rad,
        };
        assert_eq!(std_error(2.5e-5, "m", units), "0.000025");
        assert_eq!(std_error(1.3e-7, "m", units), "1.3e-7");
        assert_eq!(std_error(0.0, "m", units), "0.000000");
        assert_eq!(std_error(4e-9, "rad", units), "4.0e-9");
        let mm = DataUnits {
            length: LengthUnit::Mm,
            angle: AngleUnit::Deg,
        };
        assert_eq!(std_error(1.3e-7, "m", mm), "1.3e-4");
    }

    #[test]
    fn effects_choice_parses() {
        assert_eq!("none".parse(), Ok(EffectsChoice::None));
        assert_eq!("auto".parse(), Ok(EffectsChoice::Auto));
        assert_eq!(
            "gear_ratio:j2, gear_ratio:j3".parse(),
            Ok(EffectsChoice::List(vec![
                "gear_ratio:j2".into(),
                "gear_ratio:j3".into()
            ]))
        );
    }

    #[test]
    fn units_of_parameters() {
        assert_eq!(unit_of("joint_2.a"), "m");
        assert_eq!(unit_of("joint_2.beta"), "rad");
        assert_eq!(unit_of("target.SMR1.z"), "m");
        assert_eq!(unit_of("device.rz"), "rad");
        assert_eq!(unit_of("gear_ratio:joint_2"), "rad/rad");
    }
}

/// Command-line arguments of `calibrate`.
#[derive(Debug, clap::Args)]
pub struct CalibrateCli {
    /// The nominal model: a URDF (with --base/--tip), a DH sheet, or a tree sheet (a sheet
    /// with `branches`; targets ride on the branch they name) [default: circle-point analysis
    /// of the data].
    #[arg(long, value_name = "MODEL")]
    model: Option<String>,
    /// Base link of a URDF chain [default: the root link].
    #[arg(long)]
    base: Option<String>,
    /// Tip link of a URDF chain [default: the end of the longest run of moving joints].
    #[arg(long)]
    tip: Option<String>,
    /// DH convention for a URDF model or the CPA start.
    #[arg(long, value_enum, default_value_t = ConventionDoc::Standard)]
    convention: ConventionDoc,
    /// The measurements (canonical CSV; see `urdf-dh import` for published layouts).
    #[arg(long, value_name = "D.csv")]
    data: String,
    /// Held-out measurements to validate on [default: the data's own `set` column, else
    /// k-fold cross-validation over poses].
    #[arg(long, value_name = "V.csv")]
    validate: Option<String>,
    /// Effects to estimate after the geometric step: none, auto, or labels such as
    /// gear_ratio:joint_2,gear_ratio:joint_3. Labels: gear_ratio:J, gear_harmonic:J (once per
    /// turn), gear_harmonic2:J (twice), gear_harmonic:J:2 (both), coupling:J:K, scale,
    /// parallel_tilt:J, backlash_direction:J (after the direction of J's last motion, in the
    /// file's pose order), drift (lengths growing with the pose order), and with link masses
    /// compliance:J, lateral_compliance:J, backlash:J.
    #[arg(long, value_name = "none|auto|LIST", default_value = "none")]
    effects: EffectsChoice,
    /// Use only these targets of the data (comma-separated names) [default: all].
    #[arg(long, value_name = "NAMES", value_delimiter = ',')]
    targets: Vec<String>,
    /// Known measurement noise per axis, in the length unit [default: the data's sigma column
    /// or the scatter of repeated poses].
    #[arg(long, value_name = "SIGMA", value_parser = crate::guard::sigma)]
    sigma: Option<f64>,
    /// Folds of the cross-validation.
    #[arg(long, value_name = "K", default_value_t = 5, value_parser = crate::guard::folds)]
    folds: usize,
    /// Length unit of the measurement files and --sigma (reports are in metres).
    #[arg(long, value_enum, default_value_t = LengthUnit::M)]
    length_unit: LengthUnit,
    /// Angle unit of the measurement files (reports are in radians).
    #[arg(long, value_enum, default_value_t = AngleUnit::Rad)]
    angle_unit: AngleUnit,
    /// Output format (JSON: metres and radians).
    #[arg(long, value_enum, default_value_t = CalibrateFormat::Text)]
    format: CalibrateFormat,
    /// Write the calibrated model here: a DH sheet (.yaml, .json) or a URDF (.urdf); `-` writes
    /// a YAML sheet to standard output and the report to standard error.
    #[arg(long, value_name = "FILE")]
    out: Option<String>,
    /// Write an SVG chart of the residuals per pose, before and after (`-`: standard output,
    /// the report then goes to standard error).
    #[arg(long, value_name = "FILE.svg")]
    plot: Option<String>,
    /// Link masses for the compliance effects: YAML with `links: [{joint, mass, com}]` (kg,
    /// m; `com_frame: base_at_zero` or `dh`) and optional `payloads`, `gravity` [default: a
    /// URDF model's inertials, a tree sheet's own `inertials`; none for a sheet, and
    /// compliance is skipped].
    #[arg(long, value_name = "FILE")]
    inertials: Option<String>,
    /// Gravity in the robot's base link frame, m/s² [default: 0,0,-9.80665].
    #[arg(
        long,
        value_name = "X,Y,Z",
        value_delimiter = ',',
        allow_hyphen_values = true,
        value_parser = crate::guard::gravity
    )]
    gravity: Option<Vec<f64>>,
    /// A payload at the tip: mass in kg, then its centre in the tip frame in metres.
    #[arg(
        long,
        value_name = "M,X,Y,Z",
        value_delimiter = ',',
        allow_hyphen_values = true,
        value_parser = crate::guard::payload
    )]
    payload: Option<Vec<f64>>,
    /// Most effects --effects auto adds before it stops (a guard; the run's notes say when it
    /// stopped the selection).
    #[arg(long, value_name = "N", default_value_t = 12, value_parser = crate::guard::max_effects)]
    max_effects: usize,
    /// Fit every point: the outliers (points beyond a Bonferroni bound over the standardised
    /// residuals, see dh_calib::outliers) are still named but not left out.
    #[arg(long)]
    keep_outliers: bool,
    /// No progress line: a terminal otherwise shows what a run over a second is doing, and
    /// for how long, on standard error (never in pipes, logs or the report).
    #[arg(long, short)]
    quiet: bool,
}

impl CalibrateCli {
    /// The arguments of [`calibrate`].
    pub fn into_args(self) -> CalibrateArgs {
        CalibrateArgs {
            model: self.model,
            base: self.base,
            tip: self.tip,
            convention: self.convention.into(),
            data: self.data,
            validate: self.validate,
            units: DataUnits {
                length: self.length_unit,
                angle: self.angle_unit,
            },
            effects: self.effects,
            targets: self.targets,
            sigma: self.sigma,
            folds: self.folds,
            format: self.format,
            out: self.out,
            plot: self.plot,
            inertials: self.inertials,
            gravity: self.gravity,
            payload: self.payload,
            max_effects: self.max_effects,
            keep_outliers: self.keep_outliers,
            quiet: self.quiet,
        }
    }
}

#[cfg(test)]
mod chart_tests {
    use super::*;
    use dh_calib::simulate::{simulate, Errors, SimulationOptions};
    use dh_core::DhRow;

    fn arm() -> DhTable {
        let h = std::f64::consts::FRAC_PI_2;
        DhTable {
            convention: Convention::Standard,
            base: Isometry3::identity(),
            tool: Isometry3::identity(),
            rows: vec![
                DhRow::revolute("j1", 0.0, h, 0.4, 0.0),
                DhRow::revolute("j2", 0.5, 0.0, 0.0, 0.0),
                DhRow::revolute("j3", 0.1, h, 0.0, 0.0),
                DhRow::revolute("j4", 0.0, -h, 0.45, 0.0),
                DhRow::revolute("j5", 0.0, h, 0.0, 0.0),
                DhRow::revolute("j6", 0.0, 0.0, 0.1, 0.0),
            ],
        }
    }

    /// The chart recomputes every residual from the report (nominal-step frames, calibrated
    /// table, effect estimates): its RMS must be the report's, or the chart shows another fit.
    #[test]
    fn chart_residuals_reproduce_the_reported_rms() {
        let table = arm();
        let (data, _) = simulate(
            &table,
            &SimulationOptions {
                poses: 60,
                sigma: 2e-5,
                target_count: 2,
                errors: Errors::Explicit(vec![("j2.a".into(), 4e-4), ("j3.theta".into(), 1e-3)]),
                ..SimulationOptions::default()
            },
        )
        .unwrap();
        let effects: Vec<Arc<dyn Effect>> =
            vec![dh_calib::effects::parse_label("gear_ratio:j2", &table).unwrap()];
        for with_effects in [false, true] {
            let options = CalibrationOptions {
                effects: if with_effects {
                    effects.clone()
                } else {
                    vec![]
                },
                ..CalibrationOptions::default()
            };
            let report = run_calibration(&table, &data, &options).unwrap();
            let inputs = Inputs {
                table: table.clone(),
                model_name: "arm".into(),
                robot: None,
                units: (LengthUnit::M, AngleUnit::Rad),
                links: ("base_link".into(), "tool0".into()),
                coupled: vec![],
                data: data.clone(),
                cpa: false,
            };
            let chart = chart("d.csv", &inputs, &report, &effects, LengthUnit::Mm).unwrap();
            let rms = |p: &Panel| {
                let d: Vec<f64> = p.residuals.iter().map(|r| r.distance).collect();
                (d.iter().map(|v| v * v).sum::<f64>() / d.len() as f64).sqrt()
            };
            assert!(
                (rms(&chart.panels[0]) - report.rms_before).abs() < 1e-9,
                "before {} {}",
                rms(&chart.panels[0]),
                report.rms_before
            );
            assert!(
                // The calibrated table folds Hayati tilts into DH values to within
                // dh_calib::model::FOLD_TOLERANCE (1e-9 m, 1e-9 rad).
                (rms(&chart.panels[1]) - report.rms_after).abs() < 1e-8,
                "after {} {}",
                rms(&chart.panels[1]),
                report.rms_after
            );
            assert_eq!(chart.poses, 60);
        }
    }
}

// ---------------------------------------------------------------- hooks for trees

/// The measurement files of `args` read for `model` as `calibrate` reads them for a serial
/// model: the `--validate` file merged as validation samples, the coupled joints applied and
/// `--targets` kept (`crate::commands::calibrate_tree` reads a tree's data through it).
///
/// # Errors
/// As the data of [`calibrate`].
pub(crate) fn read_data_for(
    args: &CalibrateArgs,
    model: &LoadedModel,
    err: &mut dyn Write,
) -> Result<Measurements> {
    let data_name = display_name(&args.data);
    let (joints, prismatic) = (model.measured_joints(), model.prismatic());
    let mut data = read_measurements(
        &DataFile::read(&args.data)?,
        &joints,
        &prismatic,
        args.units,
        err,
    )?;
    if let Some(v) = &args.validate {
        let extra = read_measurements(&DataFile::read(v)?, &joints, &prismatic, args.units, err)?;
        merge_validation(&mut data, extra);
    }
    model
        .couple(&mut data)
        .with_context(|| format!("{data_name}: applying the model's coupled joints"))?;
    if !args.targets.is_empty() {
        keep_targets(&mut data, &args.targets, &data_name)?;
    }
    Ok(data)
}

/// The JSON document and the text report of `report`, a calibration of `model` (for a tree,
/// `model.table` is its joint table) against `data`, as `calibrate` prints them.
pub(crate) fn report_for(
    args: &CalibrateArgs,
    model: &LoadedModel,
    data: &Measurements,
    report: &Report,
) -> (CalibrationDoc, String) {
    let inputs = Inputs {
        table: model.table.clone(),
        model_name: model.origin.clone(),
        robot: model.robot.clone(),
        units: model.units,
        links: model.links.clone(),
        coupled: model.coupled.clone(),
        data: data.clone(),
        cpa: false,
    };
    let doc = document(args, &inputs, report);
    let text = text(&doc, &inputs);
    (doc, text)
}
