//! `urdf-dh calibrate` of a tree sheet (see [`crate::tree_sheet`]): every chain of the tree
//! fitted at once, each measured target on the branch it names.
//!
//! The steps, validation, effects and report are those of a serial model
//! ([`crate::commands::calibrate`], `dh_calib::calibrate::calibrate_tree`,
//! `dh_calib::diagnose::diagnose_tree`); the report adds a `tree` section saying which
//! parameters, targets and mount belong to the trunk and to each branch. `--out` writes the
//! calibrated tree sheet (YAML, or JSON for `.json`).

use std::io::Write;
use std::path::Path;
use std::sync::Arc;

use anyhow::{Context, Result};
use dh_calib::calibrate::{calibrate_tree as fit_tree, CalibrationOptions, Report};
use dh_calib::data::{Measurements, Split};
use dh_calib::diagnose::{diagnose_tree, DiagnoseOptions};
use dh_calib::effects::{parse_label_in, EffectContext};
use dh_calib::gravity::GravityModel;
use dh_calib::model::Effect;
use dh_calib::tree::DhTree;
use serde::Serialize;

use crate::commands::calibrate::{
    read_data_for, report_for, CalibrateArgs, CalibrateFormat, CalibrationDoc, EffectsChoice,
    PoseSi,
};
use crate::error::{hinted, Outcome};
use crate::input::{display_name, read_text};
use crate::measured::LoadedModel;
use crate::sheet::parse_doc;
use crate::tree_sheet::{InertialsDoc, TreeSheet};

/// Work (calibration samples × (folds + 1) × steps) beyond which a run says it may take a
/// while, as for a serial model.
const LONG_RUN: usize = 200_000;

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

/// Which table a parameter of a tree belongs to: `None` for the trunk, `Some(b)` for branch
/// `b`; the device frame belongs to none (`Err(())`).
fn table_of(name: &str, tree: &DhTree, targets: &[(String, usize)]) -> Result<Option<usize>, ()> {
    if name.starts_with("device.") {
        return Err(());
    }
    if name.starts_with("base.") {
        return Ok(None);
    }
    if let Some(rest) = name.strip_prefix("target.") {
        // `target.<name>.<x|y|z>`: target names may hold dots, the coordinate may not.
        let target = rest.rsplit_once('.').map_or(rest, |(t, _)| t);
        return targets
            .iter()
            .find(|(t, _)| t == target)
            .map(|(_, b)| Some(*b))
            .ok_or(());
    }
    // Effects: `<kind>:<joint>[:<joint>]`, on the first joint's table; `scale` on none.
    let joint = match name.split_once(':') {
        Some((_, joints)) => joints.split(':').next().unwrap_or_default(),
        None => name.rsplit_once('.').map_or(name, |(j, _)| j),
    };
    if let Some(b) = joint
        .strip_suffix(".base")
        .and_then(|b| tree.branch_index(b))
    {
        return Ok(Some(b));
    }
    match tree.row_index(joint) {
        Some(r) => Ok(tree.place(r).0),
        None => Err(()),
    }
}

/// One table of the tree in the report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TableDoc {
    /// `trunk`, or the branch's name.
    pub name: String,
    /// Its joints, in order.
    pub joints: Vec<String>,
    /// The targets riding on it (a branch), none for the trunk.
    pub targets: Vec<String>,
    /// Estimated parameters of its rows, base or mount, targets and effects.
    pub free: Vec<String>,
    /// Parameters of it held at nominal.
    pub fixed: Vec<String>,
    /// The calibrated mount in the branch point frame (branches; metres, radians).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mount: Option<PoseSi>,
}

/// The JSON report of a tree: the serial report's keys and `tree`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TreeCalibrationDoc {
    /// Everything a serial calibration reports.
    #[serde(flatten)]
    pub report: CalibrationDoc,
    /// The trunk and each branch.
    pub tree: Vec<TableDoc>,
}

/// The tree section of the report.
fn tables(
    tree: &DhTree,
    calibrated: &DhTree,
    doc: &CalibrationDoc,
    targets: &[(String, usize)],
) -> Vec<TableDoc> {
    let mut out = Vec::with_capacity(tree.branches().len() + 1);
    let names = |rows: &[dh_core::DhRow]| rows.iter().map(|r| r.name.clone()).collect();
    let params = |b: Option<usize>, free: bool| -> Vec<String> {
        doc.parameters
            .iter()
            .filter(|p| p.free == free && table_of(&p.name, tree, targets) == Ok(b))
            .map(|p| p.name.clone())
            .collect()
    };
    out.push(TableDoc {
        name: "trunk".into(),
        joints: names(&tree.trunk().rows),
        targets: Vec::new(),
        free: params(None, true),
        fixed: params(None, false),
        mount: None,
    });
    for (b, br) in tree.branches().iter().enumerate() {
        out.push(TableDoc {
            name: br.name.clone(),
            joints: names(&br.table.rows),
            targets: targets
                .iter()
                .filter(|(_, c)| *c == b)
                .map(|(t, _)| t.clone())
                .collect(),
            free: params(Some(b), true),
            fixed: params(Some(b), false),
            mount: calibrated
                .branches()
                .get(b)
                .map(|c| PoseSi::of(&c.table.base)),
        });
    }
    out
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

/// The `(target, branch index)` of every target of `data` (see [`crate::tree_sheet`]).
fn target_branches(
    tree: &DhTree,
    data: &Measurements,
    data_name: &str,
) -> Result<Vec<(String, usize)>> {
    let branches = tree
        .branches()
        .iter()
        .map(|b| b.name.as_str())
        .collect::<Vec<_>>()
        .join(", ");
    data.targets
        .iter()
        .map(|t| {
            TreeSheet::branch_of(tree, t)
                .and_then(|b| tree.branch_index(b))
                .map(|b| (t.clone(), b))
                .ok_or_else(|| {
                    hinted(
                        format!(
                            "{data_name}: target '{t}': expected a branch name of the tree ({branches}) or BRANCH/NAME, found no such branch"
                        ),
                        "a target rides on the branch of its own name, or on the branch before the first '/' of it (right/wrist); rename the target or the branch",
                    )
                })
        })
        .collect()
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
    let targets = target_branches(tree, &data, &data_name)?;
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
    let ctx = EffectContext {
        tree: tree.clone(),
        gravity: match &inertials {
            Some(i) => Some(Arc::new(
                GravityModel::new(tree, i, gravity)
                    .map_err(|e| anyhow::anyhow!("inertials: {e}"))?,
            )),
            None => None,
        },
    };
    let effects: Vec<Arc<dyn Effect>> = match &args.effects {
        EffectsChoice::List(labels) => labels
            .iter()
            .map(|l| {
                parse_label_in(l, &ctx).map_err(|e| {
                    hinted(
                        format!("{e}"),
                        format!(
                            "effects are named <kind>:<joint> (coupling:<joint>:<driver>; scale alone; compliance needs inertials); the tree's joints: {}",
                            tree.rows()
                                .iter()
                                .map(|r| r.name.as_str())
                                .collect::<Vec<_>>()
                                .join(", ")
                        ),
                    )
                })
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
        target_branches: targets
            .iter()
            .map(|(t, b)| (t.clone(), tree.branches()[*b].name.clone()))
            .collect(),
        outliers: dh_calib::outliers::OutlierOptions {
            keep: args.keep_outliers,
            ..dh_calib::outliers::OutlierOptions::default()
        },
        ..CalibrationOptions::default()
    };
    let cal = data
        .samples
        .iter()
        .filter(|s| s.split == Split::Calibration)
        .count();
    let steps = 2 + usize::from(args.effects != EffectsChoice::None);
    if cal * (args.folds + 1) * steps > LONG_RUN {
        writeln!(
            err,
            "urdf-dh: calibrating {origin} ({cal} samples, {} targets on {} branches, {}-fold cross-validation unless there is a validation split); this may take a while",
            data.targets.len(),
            tree.branches().len(),
            args.folds
        )?;
    }
    let failed = |e: dh_calib::CalibError| anyhow::anyhow!("{data_name}: calibration failed: {e}");
    let progress = crate::progress::Progress::start(
        &format!("calibrating {origin} against {data_name} ({cal} samples)"),
        args.quiet,
    );
    let report: Report = match &args.effects {
        EffectsChoice::Auto => {
            let diag = DiagnoseOptions {
                inertials,
                gravity,
                max_effects: args.max_effects,
                ..DiagnoseOptions::default()
            };
            diagnose_tree(tree, &data, &options, &diag).map_err(failed)?
        }
        EffectsChoice::None | EffectsChoice::List(_) => {
            fit_tree(tree, &data, &options).map_err(failed)?
        }
    };
    drop(progress);
    let calibrated = report.tree.clone().unwrap_or_else(|| tree.clone());
    let (doc, text) = report_for(args, &model, &data, &report);
    let tables = tables(tree, &calibrated, &doc, &targets);
    // The file first: a run that cannot write it prints no report.
    if let Some(path) = &args.out {
        write_tree(
            path,
            sheet,
            &calibrated,
            &doc,
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
            let doc = TreeCalibrationDoc {
                report: doc.clone(),
                tree: tables.clone(),
            };
            out.write_all((serde_json::to_string_pretty(&doc)? + "\n").as_bytes())?;
        }
        CalibrateFormat::Text => {
            // The tree section goes before the closing `result:` line.
            let (body, result) = match text.rfind("result: ") {
                Some(k) => text.split_at(k),
                None => (text.as_str(), ""),
            };
            out.write_all(body.as_bytes())?;
            out.write_all(tree_text(&tables).as_bytes())?;
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
            .filter(|p| p.free && (p.name.contains(':') || p.name == "scale" || p.name == "drift"))
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parameters_belong_to_their_table() {
        let sheet = TreeSheet::parse(
            "convention: modified\nlength_unit: m\nangle_unit: rad\njoints:\n  - {name: t1, type: revolute, a: 0, alpha: 0, d: 0.2, theta: 0}\nbranches:\n  - name: r\n    joints: [{name: r1, type: revolute, a: 0.3, alpha: 0, d: 0, theta: 0}]\n  - name: l\n    joints: [{name: l1, type: revolute, a: 0.3, alpha: 0, d: 0, theta: 0}]\n",
            "t.yaml",
        )
        .unwrap();
        let t = &sheet.tree;
        let targets = [("r".to_string(), 0), ("l/m.1".to_string(), 1)];
        assert_eq!(table_of("device.x", t, &targets), Err(()));
        assert_eq!(table_of("base.rz", t, &targets), Ok(None));
        assert_eq!(table_of("t1.theta", t, &targets), Ok(None));
        assert_eq!(table_of("r1.a", t, &targets), Ok(Some(0)));
        assert_eq!(table_of("l.base.x", t, &targets), Ok(Some(1)));
        assert_eq!(table_of("target.l/m.1.z", t, &targets), Ok(Some(1)));
        assert_eq!(table_of("compliance:l1", t, &targets), Ok(Some(1)));
        assert_eq!(table_of("coupling:r1:t1", t, &targets), Ok(Some(0)));
        assert_eq!(table_of("scale", t, &targets), Err(()));
    }
}
