//! What a calibration reads: the nominal model, the measurements (the validation file merged
//! as validation samples, the model's coupled joints applied, the requested targets kept), and
//! the masses the gravity effects need (an inertials file in kg and metres, or a URDF's
//! `<inertial>`). Warnings go to `err` as `urdf-dh: warning:` lines, as everywhere in this
//! crate.
//!
//! Shared by the serial, contact and tree paths.

use std::io::Write;

use anyhow::{Context, Result};
use dh_calib::cpa::{analyse, CpaOptions};
use dh_calib::data::Measurements;
use dh_calib::gravity::{GravityModel, Inertial, Inertials};
use dh_calib::pipeline::{merge_validation, PipelineError};
use dh_calib::tree::DhTree;
use dh_core::{DhTable, Tolerance};
use nalgebra::Vector3;

use dh_calib::cpa::{CPA_ANGULAR, CPA_LINEAR};

use super::CalibrationRequest;
use crate::error::hinted;
use crate::input::display_name;
use crate::measured::{DataFile, DataSource};
use crate::model::{load_model_noting, LoadedModel};
use crate::units::{AngleUnit, LengthUnit};

/// Reads an inertials file: `links: [{joint, mass, com: [x, y, z]}]` (kg, m) with
/// `com_frame: base_at_zero` (base link frame, every joint at zero; the default) or `dh` (the
/// row's DH frame), optional `payloads: [{mass, com}]` (tip frame) and `gravity: [x, y, z]`.
pub fn read_inertials(path: &str, table: &DhTable) -> Result<(Inertials, Option<Vector3<f64>>)> {
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

/// The gravity vector `--gravity` gives (m/s², the robot's base link frame), `None` when it
/// gives none.
///
/// # Errors
/// Not three finite numbers.
pub fn gravity_given(values: Option<&[f64]>) -> Result<Option<Vector3<f64>>> {
    match values {
        None => Ok(None),
        Some([x, y, z]) if [x, y, z].iter().all(|v| v.is_finite()) => {
            Ok(Some(Vector3::new(*x, *y, *z)))
        }
        Some(g) => {
            anyhow::bail!("--gravity: expected three finite numbers X,Y,Z in m/s², found {g:?}")
        }
    }
}

/// What the gravity effects need: `--inertials`, else a URDF model's `<inertial>` masses
/// (rows named like its joints), with `--payload` and `--gravity`. `None` when there are no
/// masses at all.
pub fn gravity_inputs(
    args: &CalibrationRequest,
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
            let urdf = crate::input::read_text(model)
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
    if let Some(g) = gravity_given(args.gravity.as_deref())? {
        gravity = g;
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

/// The model to start from and the data it is fitted to (metres and radians).
#[derive(Clone, Debug)]
pub struct Inputs {
    /// The nominal table (base and tool included); for a tree, its joint table.
    pub table: DhTable,
    /// What the report calls the model: its file name, or the circle-point analysis.
    pub model_name: String,
    /// The robot's name, when the model gives one.
    pub robot: Option<String>,
    /// The model's own units, in which the calibrated model is written.
    pub units: (LengthUnit, AngleUnit),
    /// The base and tip link names.
    pub links: (String, String),
    /// Joints that follow another (`mimic`): each with its drivers and multipliers.
    pub coupled: Vec<(String, Vec<(String, f64)>)>,
    /// The measurements, validation samples merged, coupled joints applied, targets kept.
    pub data: Measurements,
    /// Whether the model is the circle-point analysis of the data (no model given).
    pub cpa: bool,
}

impl Inputs {
    /// The nominal model as the calibrated model is written from it
    /// ([`crate::calibrated_writer`]).
    pub fn nominal(&self) -> crate::calibrated_writer::Nominal<'_> {
        crate::calibrated_writer::Nominal {
            table: &self.table,
            robot: self.robot.as_deref(),
            units: self.units,
            links: (&self.links.0, &self.links.1),
            coupled: &self.coupled,
        }
    }
}

/// Keeps the samples of `keep` (by name) and renumbers the targets
/// (`dh_calib::pipeline::keep_targets`), naming the data file `origin` in the error.
pub fn keep_targets(data: &mut Measurements, keep: &[String], origin: &str) -> Result<()> {
    dh_calib::pipeline::keep_targets(data, keep).map_err(|e| match e {
        PipelineError::UnknownTarget { target, targets } => hinted(
            format!("{origin}: --targets names '{target}', which the data does not have"),
            format!("the data's targets: {}", targets.join(", ")),
        ),
        e => anyhow::anyhow!("{origin}: {e}"),
    })
}

/// Reads what `args` names for a serial model (or the circle-point start): the data file
/// first (its faults are reported first), then the model (its warnings on `err`), then the
/// measurements for it.
///
/// # Errors
/// Unreadable or invalid files, naming the file and line; a circle-point analysis that fails.
pub fn load_inputs(args: &CalibrationRequest, err: &mut dyn Write) -> Result<Inputs> {
    let data_name = display_name(&args.data);
    // The data file is read before the model, so that its faults are reported first.
    let file = match &args.given {
        None => Some(DataFile::read(&args.data)?),
        Some(_) => None,
    };
    let model = args
        .model
        .as_deref()
        .map(|m| {
            load_model_noting(
                m,
                args.base.as_deref(),
                args.tip.as_deref(),
                args.convention,
                err,
            )
        })
        .transpose()?;
    let mut data = read_sets(args, model.as_ref(), file, err)?;
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

/// The measurements of `args` for `model` (without a model: every joint column of the data),
/// the validation set merged as validation samples: read from the files `--data` and
/// `--validate` (`file`: the data file if already read), or from the arrays a library caller
/// handed over ([`CalibrationRequest::given`]; a validation file beside given data is read).
///
/// # Errors
/// Unreadable files, bad cells (naming the file or array, the line or row, and the column).
pub fn read_sets(
    args: &CalibrationRequest,
    model: Option<&LoadedModel>,
    file: Option<DataFile>,
    err: &mut dyn Write,
) -> Result<Measurements> {
    let prismatic = model.map(LoadedModel::prismatic).unwrap_or_default();
    let source = match (&args.given, file) {
        (Some(given), _) => DataSource::Arrays(&given.data, display_name(&args.data)),
        (None, Some(file)) => DataSource::File(file),
        (None, None) => DataSource::File(DataFile::read(&args.data)?),
    };
    let joints = source.joints(model)?;
    let mut data = source.read(&joints, &prismatic, args.units, err)?;
    // The validation set: given arrays, else the validation file; with the data's joints.
    let validation = match (
        args.given.as_ref().and_then(|g| g.validate.as_ref()),
        &args.validate,
    ) {
        (Some(v), name) => Some(DataSource::Arrays(
            v,
            display_name(name.as_deref().unwrap_or("<validate>")),
        )),
        (None, Some(path)) => Some(DataSource::File(DataFile::read(path)?)),
        (None, None) => None,
    };
    if let Some(v) = validation {
        merge_validation(&mut data, v.read(&joints, &prismatic, args.units, err)?);
    }
    Ok(data)
}

/// Refuses, before any fitting, point data that cannot determine its own unknowns
/// (`dh_calib::pipeline::enough_samples`), naming the data file `data_name`.
pub fn enough_samples(data: &Measurements, data_name: &str) -> Result<()> {
    dh_calib::pipeline::enough_samples(data).map_err(|e| too_few(e, data_name))
}

/// The message for [`PipelineError::TooFewSamples`] (other errors as they are,
/// after the file name).
pub fn too_few(e: PipelineError, data_name: &str) -> anyhow::Error {
    match e {
        PipelineError::TooFewSamples { .. } => hinted(
            format!("{data_name}: {e}"),
            "measure each target at several poses (the target column names the reflector, not the pose)",
        ),
        e => anyhow::anyhow!("{data_name}: {e}"),
    }
}

/// The measurement files of `args` read for `model` as `calibrate` reads them for a serial
/// model: the `--validate` file merged as validation samples, the coupled joints applied and
/// `--targets` kept (the tree path reads a tree's data through it).
///
/// # Errors
/// As [`read_sets`]; coupled joints the data cannot drive; unknown targets.
pub fn read_data_for(
    args: &CalibrationRequest,
    model: &LoadedModel,
    err: &mut dyn Write,
) -> Result<Measurements> {
    let data_name = display_name(&args.data);
    let mut data = read_sets(args, Some(model), None, err)?;
    model
        .couple(&mut data)
        .with_context(|| format!("{data_name}: applying the model's coupled joints"))?;
    if !args.targets.is_empty() {
        keep_targets(&mut data, &args.targets, &data_name)?;
    }
    Ok(data)
}

#[cfg(test)]
mod gravity_tests {
    use super::*;

    /// calibrate, its tree form and simulate read `--gravity` through this one function.
    #[test]
    fn gravity_is_three_finite_numbers_or_an_error_naming_the_option() {
        assert_eq!(gravity_given(None).unwrap(), None);
        assert_eq!(
            gravity_given(Some(&[-9.81, 0.0, 0.0])).unwrap(),
            Some(Vector3::new(-9.81, 0.0, 0.0))
        );
        for bad in [&[1.0, 2.0][..], &[0.0, f64::NAN, 1.0][..]] {
            let e = gravity_given(Some(bad)).unwrap_err().to_string();
            assert!(
                e.starts_with("--gravity: expected three finite numbers X,Y,Z in m/s², found"),
                "{e}"
            );
        }
    }
}
