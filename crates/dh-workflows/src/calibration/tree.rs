//! Calibrating a tree sheet (see [`crate::tree_sheet`]): every chain of the tree fitted at
//! once, each measured target on the branch it names. The steps, validation, effects and report
//! are those of a serial model, with a `tree` section saying which parameters, targets and mount
//! belong to the trunk and to each branch; the calibrated model is a tree sheet (YAML, or JSON
//! for `.json`).

use std::io::Write;

use anyhow::{Context, Result};
use dh_calib::calibrate::Report;
use dh_calib::data::Measurements;
use dh_calib::effects::EffectContext;
use dh_calib::gravity::{GravityModel, Inertials};
use dh_calib::pipeline::{
    self, needs_gravity, target_branches, Calibration, GravityRecord, PipelineError, Progress,
    SessionDoc, SessionFrameDoc, Start, TreeCalibration,
};
use dh_calib::predict::{Calibrated, Frame};
use dh_calib::tree::DhTree;
use nalgebra::Vector3;
use serde::Serialize;

use super::inputs::{enough_samples, read_data_for};
use super::serial::{check_sigma, pipeline_options};
use super::CalibrationRequest;
use crate::calibrated::CovarianceDoc;
use crate::calibrated_writer::SectionSummary;
use crate::error::hinted;
use crate::input::{display_name, read_text};
use crate::model::LoadedModel;
use crate::sheet::parse_doc;
use crate::tree_sheet::{InertialsDoc, TreeSheet};

/// The tree sheet `args.model` names, with its file name: `None` for a URDF, a serial sheet,
/// standard input (a tree sheet is read from a file) or a file that does not parse (the serial
/// path then reports it as it always has).
///
/// # Errors
/// A tree sheet that parses but is invalid (names the file, line, branch and joint).
pub fn tree_model(args: &CalibrationRequest) -> Result<Option<(TreeSheet, String)>> {
    let Some(path) = args.model.as_deref() else {
        return Ok(None);
    };
    let lower = path.to_ascii_lowercase();
    if path == "-"
        || [".urdf", ".xacro", ".xml"]
            .iter()
            .any(|e| lower.ends_with(e))
    {
        return Ok(None);
    }
    let Ok(text) = read_text(path) else {
        return Ok(None);
    };
    if text
        .trim_start_matches('\u{feff}')
        .trim_start()
        .starts_with('<')
    {
        return Ok(None);
    }
    let origin = display_name(path);
    let Ok(doc) = parse_doc(&text, &origin) else {
        return Ok(None);
    };
    if doc.branches.is_none() {
        return Ok(None);
    }
    Ok(Some((TreeSheet::from_doc(doc, &text, &origin)?, origin)))
}

/// Refuses the options that do not apply to the tree `origin`: a chain (`base`, `tip`), a
/// payload at one tip, a URDF as the calibrated model.
///
/// # Errors
/// The first such option, with a hint.
pub fn check_tree_options(args: &CalibrationRequest, origin: &str) -> Result<()> {
    if args.base.is_some() || args.tip.is_some() {
        return Err(hinted(
            format!("{origin}: --base and --tip choose a chain of a URDF, but the model is a tree sheet"),
            "drop --base/--tip: the targets say which branch they ride on",
        ));
    }
    if args.payload.is_some() {
        return Err(hinted(
            format!("--payload: {origin} is a tree with one tip per branch"),
            "give payloads in the sheet's (or --inertials file's) inertials: payloads: [{branch: NAME, mass: KG, com: [X, Y, Z]}]",
        ));
    }
    Ok(())
}

/// Refuses a URDF as the calibrated model of a tree.
///
/// # Errors
/// `args.out` ending in `.urdf`.
pub fn check_tree_out(args: &CalibrationRequest) -> Result<()> {
    if let Some(path) = &args.out {
        if path.to_ascii_lowercase().ends_with(".urdf") {
            return Err(hinted(
                format!(
                    "--out {}: a tree is written as a tree sheet, not a URDF",
                    display_name(path)
                ),
                "write it as .yaml or .json",
            ));
        }
    }
    Ok(())
}

/// A tree sheet and the data read for it.
#[derive(Clone, Debug)]
pub struct TreeInputs {
    /// The tree sheet.
    pub sheet: TreeSheet,
    /// Its file name.
    pub origin: String,
    /// The tree as a model of the measured-data commands (its joint table).
    pub model: LoadedModel,
    /// The measurements (validation merged, coupled joints applied, targets kept).
    pub data: Measurements,
    /// Each target's branch (by index into the tree's branches).
    pub targets: Vec<(String, usize)>,
    /// The link masses (the inertials file's, else the sheet's own) and where they came from.
    pub inertials_doc: Option<InertialsDoc>,
    /// The masses for the gravity effects.
    pub inertials: Option<Inertials>,
    /// Gravity in the base link frame (m/s²).
    pub gravity: Vector3<f64>,
}

/// Reads the data and masses of the tree `sheet` (file `origin`), warnings on `err`.
///
/// # Errors
/// Bad data files (naming the file, line and column), contact data, targets on no branch, bad
/// inertials or gravity.
pub fn load_tree(
    args: &CalibrationRequest,
    sheet: TreeSheet,
    origin: String,
    err: &mut dyn Write,
) -> Result<TreeInputs> {
    check_tree_out(args)?;
    for w in &sheet.warnings {
        writeln!(err, "urdf-dh: warning: {w}")?;
    }
    let tree = &sheet.tree;
    let model = LoadedModel::of_tree(&sheet, &origin);
    let data_name = display_name(&args.data);
    let data = read_data_for(args, &model, err)?;
    if data.samples.iter().any(|s| s.socket.is_some()) {
        return Err(hinted(
            format!("{data_name}: contact data (a 'socket' column) is calibrated for serial models only; {origin} is a tree"),
            "give a serial sheet of the chain that made the contacts",
        ));
    }
    enough_samples(&data, &data_name)?;
    let targets = target_branches(tree, &data).map_err(|e| match e {
        PipelineError::NoBranch { .. } => hinted(
            format!("{data_name}: {e}"),
            "a target rides on the branch of its own name, or on the branch before the first '/' of it (right/wrist); rename the target or the branch",
        ),
        e => anyhow::anyhow!("{data_name}: {e}"),
    })?;
    // Link masses: the inertials file, else the sheet's own.
    let inertials_doc = match &args.inertials {
        Some(path) => {
            let text = read_text(path)?;
            Some((
                InertialsDoc::parse(&text, &display_name(path))?,
                display_name(path),
                Some(text),
            ))
        }
        None => sheet.inertials.clone().map(|i| (i, origin.clone(), None)),
    };
    let mut gravity = GravityModel::default_gravity();
    let inertials = match &inertials_doc {
        Some((doc, from, text)) => {
            let (i, g) = doc.to_inertials(tree, from, text.as_deref())?;
            if let Some(g) = g {
                gravity = g;
            }
            Some(i)
        }
        None => None,
    };
    if let Some(g) = super::inputs::gravity_given(args.gravity.as_deref())? {
        gravity = g;
    }
    Ok(TreeInputs {
        sheet,
        origin,
        model,
        data,
        targets,
        inertials_doc: inertials_doc.map(|(d, _, _)| d),
        inertials,
        gravity,
    })
}

/// The message for a pipeline error of a tree calibration (effect labels named after the
/// tree's joints).
pub(super) fn tree_error(e: PipelineError, tree: &DhTree, data_name: &str) -> anyhow::Error {
    match e {
        e @ PipelineError::Effect { .. } => hinted(
            format!("{e}"),
            format!(
                "effects are named <kind>:<joint> (coupling:<joint>:<driver>; scale alone; compliance needs inertials); the tree's joints: {}",
                tree.rows()
                    .iter()
                    .map(|r| r.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        ),
        e @ PipelineError::Inertials(_) => anyhow::anyhow!("{e}"),
        e => super::inputs::too_few(e, data_name),
    }
}

/// The `calibration` section of a calibrated tree sheet (metres, radians): the serial sheet's
/// keys (see [`crate::calibrated_writer::CalibrationSection`]), each target with its branch,
/// and the gravity model of a tree.
#[derive(Clone, Debug, PartialEq, Serialize)]
struct TreeCalibrationSection {
    #[serde(flatten)]
    summary: SectionSummary,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    sessions: Vec<SessionFrameDoc>,
    #[serde(skip_serializing_if = "Option::is_none")]
    first_session: Option<String>,
    targets: Vec<TreeTargetDoc>,
    effects: Vec<(String, f64)>,
    /// What the `t` of the effects of time was (`s` or `pose_order`), with one, as a serial
    /// sheet records it (`dh_calib::effects_thermal::TimeUnit`).
    #[serde(skip_serializing_if = "Option::is_none")]
    time_unit: Option<dh_calib::effects_thermal::TimeUnit>,
    /// Covariance of the last step's free parameters: what `predict` propagates.
    #[serde(skip_serializing_if = "Option::is_none")]
    covariance: Option<CovarianceDoc>,
    /// The link masses and nominal tree of the gravity effects, with any selected.
    #[serde(skip_serializing_if = "Option::is_none")]
    gravity_model: Option<GravityRecord>,
}

/// A fitted target and the branch it rides on.
#[derive(Clone, Debug, PartialEq, Serialize)]
struct TreeTargetDoc {
    name: String,
    branch: String,
    /// Position in the branch's tip frame (metres).
    xyz: [f64; 3],
    /// A 6-DoF target's rotation in the tip frame (URDF roll, pitch, yaw; radians).
    #[serde(skip_serializing_if = "Option::is_none")]
    rpy: Option<[f64; 3]>,
}

/// The gravity model of the effects of `report` that need one (compliance, backlash), from
/// the tree's nominal geometry and masses as the calibration used them; `None` without such an
/// effect or without masses.
fn tree_gravity(inputs: &TreeInputs, report: &Report) -> Option<GravityRecord> {
    let needs = report.selected_effects.iter().any(|e| needs_gravity(e));
    let inertials = inputs.inertials.as_ref().filter(|_| needs)?;
    let g = GravityModel::new(&inputs.sheet.tree, inertials, inputs.gravity).ok()?;
    GravityRecord::of(&g)
}

/// The calibrated tree sheet as written to `path` (JSON for `.json`, else YAML): the tree, its
/// estimated `effects`, and the `calibration` section predict reads.
///
/// # Errors
/// Serialisation failures.
pub(super) fn tree_bytes(
    path: &str,
    inputs: &TreeInputs,
    calibration: &TreeCalibration,
) -> Result<String> {
    let (calibrated, doc) = (&calibration.calibrated, &calibration.doc.report);
    let sheet = &inputs.sheet;
    let mut out = TreeSheet::to_doc(
        calibrated,
        &sheet.coupled,
        inputs.inertials_doc.clone(),
        sheet.length_unit,
        sheet.angle_unit,
    );
    out.robot = sheet.robot.clone();
    out.source = Some(format!(
        "calibrated by urdf-dh calibrate from {} against {}: RMS {:.6} m -> {:.6} m",
        doc.model, doc.data, doc.rms_before, doc.rms_after
    ));
    let effects = crate::calibrated_writer::effect_docs(doc);
    out.effects = (!effects.is_empty()).then_some(effects);
    let section = TreeCalibrationSection {
        summary: SectionSummary::of(doc),
        sessions: SessionDoc::frames(&doc.sessions),
        first_session: (doc.sessions.len() > 1)
            .then(|| doc.sessions.first().map(|s| s.name.clone()))
            .flatten(),
        targets: doc
            .targets
            .iter()
            .map(|t| TreeTargetDoc {
                name: t.name.clone(),
                branch: inputs
                    .targets
                    .iter()
                    .find(|(n, _)| n == &t.name)
                    .and_then(|(_, b)| calibrated.branches().get(*b))
                    .map(|b| b.name.clone())
                    .unwrap_or_default(),
                xyz: t.xyz,
                rpy: t.rpy,
            })
            .collect(),
        effects: doc.estimated_effects(),
        time_unit: doc.time_unit(&inputs.data),
        covariance: calibration
            .report
            .covariance
            .as_ref()
            .map(CovarianceDoc::of),
        gravity_model: tree_gravity(inputs, &calibration.report),
    };
    out.calibration = Some(serde_yaml::to_value(&section)?);
    Ok(if path.to_ascii_lowercase().ends_with(".json") {
        crate::text::json_pretty(&out)? + "\n"
    } else {
        serde_yaml::to_string(&out)?
    })
}

/// A calibration of a tree, with the inputs it ran on.
#[derive(Clone, Debug)]
pub struct Tree {
    /// The pipeline's result: the report (with its `tree` section), the calibrated tree.
    pub calibration: TreeCalibration,
    /// The tree sheet and data it ran on.
    pub inputs: TreeInputs,
}

/// Calibrates the tree of `inputs`.
pub(super) fn calibrate_tree(
    args: &CalibrationRequest,
    inputs: TreeInputs,
    progress: &mut dyn Progress,
) -> Result<Box<Tree>> {
    check_sigma(args)?;
    let data_name = display_name(&args.data);
    let options = pipeline_options(
        args,
        &inputs.origin,
        inputs.inertials.clone(),
        inputs.gravity,
    );
    let tree = &inputs.sheet.tree;
    match pipeline::calibrate(&Start::Tree(tree.clone()), &inputs.data, &options, progress) {
        Ok(Calibration::Tree(c)) => Ok(Box::new(Tree {
            calibration: *c,
            inputs,
        })),
        Ok(_) => anyhow::bail!("{data_name}: calibration took another path than a tree's"),
        Err(e) => Err(tree_error(e, tree, &data_name)),
    }
}

impl Tree {
    /// The calibrated tree sheet as written to `path`, proved: read back as `predict` reads
    /// it, it predicts every measured point as the fitted tree does (see [`prove_tree`]).
    ///
    /// # Errors
    /// Serialisation failures; a sheet that does not read back or predicts otherwise (a defect
    /// of the writer, reported as such).
    pub(super) fn model_file(&self, path: &str) -> Result<String> {
        let text = tree_bytes(path, &self.inputs, &self.calibration)?;
        prove_tree(path, &text, self)?;
        Ok(text)
    }
}

/// The proof on a written tree sheet: `predict` reads `text` back (tree, effects, gravity model,
/// device frame, targets on their branches) and its predictions of every measured point, in the
/// device frame, are the fitted tree's within [`crate::written::WRITTEN_TOLERANCE`].
///
/// # Errors
/// A sheet that does not read back, or predicts a point farther than the tolerance from the
/// fit, naming the largest deviation.
fn prove_tree(path: &str, text: &str, t: &Tree) -> Result<()> {
    let (c, inputs) = (&t.calibration, &t.inputs);
    let tree = &inputs.sheet.tree;
    let gravity = match &inputs.inertials {
        Some(i) => GravityModel::new(tree, i, inputs.gravity)
            .ok()
            .map(std::sync::Arc::new),
        None => None,
    };
    let ctx = EffectContext {
        tree: tree.clone(),
        gravity,
        gravity_vector: inputs.gravity,
    };
    // A fit the library cannot rebuild in memory has nothing to compare with (as for a serial
    // sheet): the reading back is still required.
    let fitted = Calibrated::from_tree_report(&c.report, &c.target_branches, &ctx).ok();
    let name = crate::text::output_name(path);
    let back = crate::calibrated::calibrated_sheet(text, &name).with_context(|| {
        format!("{name}: the calibrated tree sheet does not read back for predict (a defect of the writer)")
    })?;
    let Some(fitted) = fitted else {
        return Ok(());
    };
    let q = crate::calibrated_writer::row_values(&tree.joint_table(), &inputs.data)?;
    let frame = Frame::Device;
    let mut worst = 0.0f64;
    for (q, s) in q.iter().zip(&inputs.data.samples) {
        let d =
            (back.calibrated.point(q, s.target, frame) - fitted.point(q, s.target, frame)).norm();
        worst = worst.max(if d.is_finite() { d } else { f64::INFINITY });
    }
    if worst > crate::written::WRITTEN_TOLERANCE {
        anyhow::bail!(
            "{name}: read back, the calibrated tree sheet predicts a measured point {worst:e} m from the fit (tolerance {:e} m): a defect of the writer",
            crate::written::WRITTEN_TOLERANCE
        );
    }
    Ok(())
}
