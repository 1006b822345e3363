//! `urdf-dh calibrate` of a tree sheet (see [`crate::tree_sheet`]): every chain of the tree
//! fitted at once, each measured target on the branch it names.
//!
//! The steps, validation, effects and report are those of a serial model
//! ([`crate::commands::calibrate`], `dh_calib::pipeline::calibrate` with a tree start); the
//! report adds a `tree` section saying which
//! parameters, targets and mount belong to the trunk and to each branch. `--out` writes the
//! calibrated tree sheet (YAML, or JSON for `.json`).

use std::io::Write;
use std::path::Path;

use anyhow::{Context, Result};
use dh_calib::gravity::GravityModel;
use dh_calib::pipeline::{self, target_branches, Calibration, PipelineError, Plan, Start};
pub use dh_calib::pipeline::{TableDoc, TreeCalibrationDoc};
use dh_calib::tree::DhTree;
use serde::Serialize;

use crate::commands::calibrate::{
    check_sigma, pipeline_options, read_data_for, text_for, too_few, CalibrateArgs,
    CalibrateFormat, CalibrationDoc, PoseSi,
};
use crate::error::{hinted, Outcome};
use crate::input::{display_name, read_text};
use crate::measured::LoadedModel;
use crate::progress::PipelineProgress;
use crate::sheet::parse_doc;
use crate::tree_sheet::{InertialsDoc, TreeSheet};

/// The tree sheet `--model` names, with its file name: `None` for a URDF, a serial sheet,
/// standard input (a tree sheet is read from a file) or a file that does not parse (the
/// serial path then reports it as it always has).
///
/// # Errors
/// A tree sheet that parses but is invalid (names the file, line, branch and joint).
pub fn tree_model(args: &CalibrateArgs) -> Result<Option<(TreeSheet, String)>> {
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

/// The text of the tree section.
fn tree_text(tables: &[TableDoc]) -> String {
    let mut s = format!(
        "tree: trunk and {} branch(es); parameters per table (free / held):\n",
        tables.len().saturating_sub(1)
    );
    for t in tables {
        let what = if t.name == "trunk" {
            "trunk".to_string()
        } else {
            format!("branch {}", t.name)
        };
        s += &format!(
            "  {what}: joints {}; {} free, {} held{}\n",
            t.joints.join(", "),
            t.free.len(),
            t.fixed.len(),
            if t.targets.is_empty() {
                String::new()
            } else {
                format!("; targets {}", t.targets.join(", "))
            }
        );
        if let Some(m) = &t.mount {
            s += &format!(
                "    mount (branch point frame): xyz [m] {:.6} {:.6} {:.6}  rpy [rad] {:.7} {:.7} {:.7}\n",
                m.xyz[0], m.xyz[1], m.xyz[2], m.rpy[0], m.rpy[1], m.rpy[2]
            );
        }
        if !t.free.is_empty() {
            s += &format!("    free: {}\n", t.free.join(", "));
        }
    }
    s
}

/// Runs `calibrate` on a tree sheet.
///
/// # Errors
/// Bad data files (naming the file, line and column), targets on no branch, options that do
/// not apply to a tree (`--base`/`--tip`, `--payload`, `--plot`, `--out *.urdf`), unknown
/// effects, bad inertials, a calibration that cannot start, failed writes.
pub fn calibrate_tree(
    args: &CalibrateArgs,
    sheet: &TreeSheet,
    origin: &str,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> Result<Outcome> {
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
    if args.plot.is_some() {
        return Err(hinted(
            format!(
                "--plot: the residual chart is drawn for serial models only; {origin} is a tree"
            ),
            "drop --plot; the JSON report (--format json) has every step's figures",
        ));
    }
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
    for w in &sheet.warnings {
        writeln!(err, "urdf-dh: warning: {w}")?;
    }
    let tree = &sheet.tree;
    let model = LoadedModel::of_tree(sheet, origin);
    let data_name = display_name(&args.data);
    let data = read_data_for(args, &model, err)?;
    if data.samples.iter().any(|s| s.socket.is_some()) {
        return Err(hinted(
            format!("{data_name}: contact data (a 'socket' column) is calibrated for serial models only; {origin} is a tree"),
            "give a serial sheet of the chain that made the contacts",
        ));
    }
    crate::commands::calibrate::enough_samples(&data, &data_name)?;
    let targets = target_branches(tree, &data).map_err(|e| match e {
        PipelineError::NoBranch { .. } => hinted(
            format!("{data_name}: {e}"),
            "a target rides on the branch of its own name, or on the branch before the first '/' of it (right/wrist); rename the target or the branch",
        ),
        e => anyhow::anyhow!("{data_name}: {e}"),
    })?;
    // Link masses: --inertials, else the sheet's own.
    let inertials_doc = match &args.inertials {
        Some(path) => {
            let text = read_text(path)?;
            Some((
                InertialsDoc::parse(&text, &display_name(path))?,
                display_name(path),
                Some(text),
            ))
        }
        None => sheet
            .inertials
            .clone()
            .map(|i| (i, origin.to_string(), None)),
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
    if let Some(g) = &args.gravity {
        match g.as_slice() {
            [x, y, z] if g.iter().all(|v| v.is_finite()) => {
                gravity = nalgebra::Vector3::new(*x, *y, *z);
            }
            _ => {
                anyhow::bail!("--gravity: expected three finite numbers X,Y,Z in m/s², found {g:?}")
            }
        }
    }
    check_sigma(args)?;
    let options = pipeline_options(args, origin, inertials, gravity);
    let notice = |p: &Plan| {
        p.is_long().then(|| {
            format!(
                "urdf-dh: calibrating {origin} ({} samples, {} targets on {} branches, {}-fold cross-validation unless there is a validation split); this may take a while",
                p.samples, p.targets, p.branches, p.folds
            )
        })
    };
    let label = |p: &Plan| {
        format!(
            "calibrating {origin} against {data_name} ({} samples)",
            p.samples
        )
    };
    let mut progress = PipelineProgress::new(err, args.quiet, &notice, &label);
    let run = pipeline::calibrate(&Start::Tree(tree.clone()), &data, &options, &mut progress);
    progress.check()?;
    drop(progress);
    let calibration = match run {
        Ok(Calibration::Tree(c)) => c,
        Ok(_) => anyhow::bail!("{data_name}: calibration took another path than a tree's"),
        Err(e @ PipelineError::Effect { .. }) => {
            return Err(hinted(
                format!("{e}"),
                format!(
                    "effects are named <kind>:<joint> (coupling:<joint>:<driver>; scale alone; compliance needs inertials); the tree's joints: {}",
                    tree.rows()
                        .iter()
                        .map(|r| r.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ))
        }
        Err(e @ PipelineError::Inertials(_)) => return Err(anyhow::anyhow!("{e}")),
        Err(e) => return Err(too_few(e, &data_name)),
    };
    let calibrated = &calibration.calibrated;
    let doc = &calibration.doc.report;
    let text = text_for(&model, &data, doc);
    let tables = &calibration.doc.tree;
    // The file first: a run that cannot write it prints no report.
    if let Some(path) = &args.out {
        write_tree(
            path,
            sheet,
            calibrated,
            doc,
            &targets,
            inertials_doc.map(|(d, _, _)| d),
            out,
        )?;
    }
    // `--out -`: the tree sheet on standard output, the report on standard error.
    let out: &mut dyn Write = if crate::output::any_stdout([args.out.as_deref()]) {
        err
    } else {
        out
    };
    match args.format {
        CalibrateFormat::Json => {
            out.write_all((serde_json::to_string_pretty(&calibration.doc)? + "\n").as_bytes())?;
        }
        CalibrateFormat::Text => {
            // The tree section goes before the closing `result:` line.
            let (body, result) = match text.rfind("result: ") {
                Some(k) => text.split_at(k),
                None => (text.as_str(), ""),
            };
            out.write_all(body.as_bytes())?;
            out.write_all(tree_text(tables).as_bytes())?;
            out.write_all(result.as_bytes())?;
        }
    }
    Ok(Outcome::Pass)
}

/// The `calibration` section of a calibrated tree sheet (metres, radians).
#[derive(Clone, Debug, PartialEq, Serialize)]
struct TreeCalibrationSection {
    data: String,
    rms_before: f64,
    rms_after: f64,
    val_rms_before: Option<f64>,
    val_rms_after: Option<f64>,
    device: PoseSi,
    targets: Vec<TreeTargetDoc>,
    effects: Vec<(String, f64)>,
}

/// A fitted target and the branch it rides on.
#[derive(Clone, Debug, PartialEq, Serialize)]
struct TreeTargetDoc {
    name: String,
    branch: String,
    /// Position in the branch's tip frame (metres).
    xyz: [f64; 3],
}

/// Writes the calibrated tree sheet (JSON for `.json`, else YAML), atomically.
fn write_tree(
    path: &str,
    sheet: &TreeSheet,
    calibrated: &DhTree,
    doc: &CalibrationDoc,
    targets: &[(String, usize)],
    inertials: Option<InertialsDoc>,
    stdout: &mut dyn Write,
) -> Result<()> {
    let mut out = TreeSheet::to_doc(
        calibrated,
        &sheet.coupled,
        inertials,
        sheet.length_unit,
        sheet.angle_unit,
    );
    out.robot = sheet.robot.clone();
    out.source = Some(format!(
        "calibrated by urdf-dh calibrate from {} against {}: RMS {:.6} m -> {:.6} m",
        doc.model, doc.data, doc.rms_before, doc.rms_after
    ));
    let section = TreeCalibrationSection {
        data: doc.data.clone(),
        rms_before: doc.rms_before,
        rms_after: doc.rms_after,
        val_rms_before: doc.val_rms_before,
        val_rms_after: doc.val_rms_after,
        device: doc.device.clone(),
        targets: doc
            .targets
            .iter()
            .map(|t| TreeTargetDoc {
                name: t.name.clone(),
                branch: targets
                    .iter()
                    .find(|(n, _)| n == &t.name)
                    .and_then(|(_, b)| calibrated.branches().get(*b))
                    .map(|b| b.name.clone())
                    .unwrap_or_default(),
                xyz: t.xyz,
            })
            .collect(),
        effects: doc
            .parameters
            .iter()
            .filter(|p| p.is_estimated_effect())
            .map(|p| (p.name.clone(), p.estimate))
            .collect(),
    };
    out.calibration = Some(serde_yaml::to_value(&section)?);
    let bytes = if path.to_ascii_lowercase().ends_with(".json") {
        serde_json::to_string_pretty(&out)? + "\n"
    } else {
        serde_yaml::to_string(&out)?
    };
    crate::output::write_all_or_stdout(&[(Path::new(path), bytes.as_bytes())], stdout)
        .with_context(|| format!("writing the calibrated tree to {}", display_name(path)))
}
