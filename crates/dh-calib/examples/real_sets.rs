//! The published measurement sets in `../shared/measured` (outside the repository), each fitted
//! nominal -> geometric -> selected effects with the project's fixture models
//! (`fixtures/measured/<set>/`), printed as the Markdown of `docs/results.md`.
//!
//! ```sh
//! cargo run --release -p dh-calib --example real_sets            # every set
//! cargo run --release -p dh-calib --example real_sets -- boby    # one set
//! ```
//!
//! A set whose files are absent is skipped with a message on stderr. The fixture readers here
//! are deliberately small and serial (the CLI owns the full sheet format). The DLR Agile Justin
//! set is a kinematic tree: its tree sheet is read by the CLI (`urdf_dh::tree_sheet`), and it
//! runs there (`-- dlr` prints the commands; see docs/results.md).
#![allow(clippy::print_stdout, clippy::print_stderr)]

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use dh_calib::calibrate::{CalibrationOptions, Report};
use dh_calib::cpa::{analyse, CpaOptions};
use dh_calib::data::{Measurements, Split};
use dh_calib::diagnose::{diagnose_tree, CandidateStatus, DiagnoseOptions, EffectSelection};
use dh_calib::effects::{parse_label_in, EffectContext};
use dh_calib::gravity::{GravityModel, Inertial, Inertials};
use dh_calib::import::{import, Layout, Source};
use dh_calib::model::{Effect, Model, ModelOptions};
use dh_calib::tree::DhTree;
use dh_core::pose::from_xyz_rpy;
use dh_core::{Convention, DhRow, DhTable, JointKind, Limits};
use nalgebra::{Isometry3, Point3, Vector3};
use serde_yaml::Value;

const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");

fn shared(set: &str) -> PathBuf {
    Path::new(ROOT).join("../shared/measured").join(set)
}

fn fixture(set: &str, file: &str) -> PathBuf {
    Path::new(ROOT)
        .join("fixtures/measured")
        .join(set)
        .join(file)
}

type Error = Box<dyn std::error::Error>;

/// One set's run.
type Run = fn() -> Result<(), Error>;

fn read(path: &Path) -> Result<String, Error> {
    std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()).into())
}

fn load(layout: Layout, dir: &Path, files: &[&str]) -> Result<Measurements, Error> {
    let mut texts = Vec::new();
    for f in files {
        texts.push((*f, read(&dir.join(f))?));
    }
    let sources: Vec<Source<'_>> = texts
        .iter()
        .map(|(name, text)| Source { name, text })
        .collect();
    Ok(import(layout, &sources)?)
}

// ---------------------------------------------------------------- fixture readers

fn num(v: &Value) -> Result<f64, Error> {
    v.as_f64()
        .or_else(|| v.as_i64().map(|i| i as f64))
        .ok_or_else(|| format!("expected a number, found {v:?}").into())
}

fn vec3(v: &Value) -> Result<Vector3<f64>, Error> {
    let s = v.as_sequence().ok_or("expected [x, y, z]")?;
    if s.len() != 3 {
        return Err("expected three numbers".into());
    }
    Ok(Vector3::new(num(&s[0])?, num(&s[1])?, num(&s[2])?))
}

struct Units {
    length: f64,
    angle: f64,
}

fn units(doc: &Value) -> Units {
    Units {
        length: if doc["length_unit"].as_str() == Some("mm") {
            1e-3
        } else {
            1.0
        },
        angle: if doc["angle_unit"].as_str() == Some("deg") {
            std::f64::consts::PI / 180.0
        } else {
            1.0
        },
    }
}

fn pose(v: &Value, u: &Units) -> Result<Isometry3<f64>, Error> {
    if v.is_null() {
        return Ok(Isometry3::identity());
    }
    let t = vec3(&v["xyz"])? * u.length;
    let r = vec3(&v["rpy"])? * u.angle;
    Ok(from_xyz_rpy([t.x, t.y, t.z], [r.x, r.y, r.z]))
}

fn table(doc: &Value, convention: Convention, u: &Units) -> Result<DhTable, Error> {
    let mut rows = Vec::new();
    for j in doc["joints"].as_sequence().ok_or("expected 'joints'")? {
        let name = j["name"].as_str().ok_or("joint without a name")?;
        let (a, alpha, d, theta) = (
            num(&j["a"])? * u.length,
            num(&j["alpha"])? * u.angle,
            num(&j["d"])? * u.length,
            num(&j["theta"])? * u.angle,
        );
        let mut row = if j["type"].as_str() == Some("prismatic") {
            DhRow::prismatic(name, a, alpha, d, theta)
        } else {
            DhRow::revolute(name, a, alpha, d, theta)
        };
        if !j["lower"].is_null() {
            let s = if row.kind == JointKind::Prismatic {
                u.length
            } else {
                u.angle
            };
            row.limits = Some(Limits {
                lower: num(&j["lower"])? * s,
                upper: num(&j["upper"])? * s,
            });
        }
        rows.push(row);
    }
    Ok(DhTable {
        convention,
        base: pose(&doc["base"], u)?,
        tool: pose(&doc["tool"], u)?,
        rows,
    })
}

fn convention(doc: &Value) -> Convention {
    if doc["convention"].as_str() == Some("modified") {
        Convention::Modified
    } else {
        Convention::Standard
    }
}

/// A serial DH sheet, with its coupled joints and the inertials of `inertials.yaml` beside it.
struct Robot {
    tree: DhTree,
    coupled: Vec<(String, Vec<(String, f64)>)>,
    inertials: Option<Inertials>,
    gravity: Vector3<f64>,
}

fn read_inertials(doc: &Value, tree: &DhTree) -> Result<(Inertials, Vector3<f64>), Error> {
    let gravity = if doc["gravity"].is_null() {
        GravityModel::default_gravity()
    } else {
        vec3(&doc["gravity"])?
    };
    let mut links = Vec::new();
    for l in doc["links"].as_sequence().ok_or("expected 'links'")? {
        let name = l["joint"]
            .as_str()
            .ok_or("link without a joint")?
            .to_string();
        links.push((name, num(&l["mass"])?, vec3(&l["com"])?));
    }
    let mut payloads = Vec::new();
    if let Some(ps) = doc["payloads"].as_sequence() {
        for p in ps {
            payloads.push((
                0,
                Inertial {
                    mass: num(&p["mass"])?,
                    com: vec3(&p["com"])?,
                },
            ));
        }
    }
    let inertials = if doc["com_frame"].as_str() == Some("dh") {
        Inertials {
            links: links
                .into_iter()
                .map(|(n, mass, com)| (n, Inertial { mass, com }))
                .collect(),
            payloads,
        }
    } else {
        Inertials::from_zero_pose(tree, &links, payloads)?
    };
    Ok((inertials, gravity))
}

fn read_robot(set: &str) -> Result<Robot, Error> {
    let doc: Value = serde_yaml::from_str(&read(&fixture(set, "model.yaml"))?)?;
    let u = units(&doc);
    let conv = convention(&doc);
    let trunk = table(&doc, conv, &u)?;
    if !doc["branches"].is_null() {
        return Err(format!("{set}: a tree sheet; trees run through urdf-dh calibrate").into());
    }
    let tree = DhTree::serial(&trunk);
    let mut coupled = Vec::new();
    if let Some(map) = doc["coupled"].as_mapping() {
        for (k, v) in map {
            let terms = v
                .as_mapping()
                .ok_or("expected driver: coefficient pairs")?
                .iter()
                .map(|(d, c)| Ok((d.as_str().ok_or("bad driver")?.to_string(), num(c)?)))
                .collect::<Result<Vec<_>, Error>>()?;
            coupled.push((k.as_str().ok_or("bad coupled joint")?.to_string(), terms));
        }
    }
    let path = fixture(set, "inertials.yaml");
    let inertial_doc = if path.exists() {
        Some(serde_yaml::from_str::<Value>(&read(&path)?)?)
    } else {
        None
    };
    let (inertials, gravity) = match inertial_doc {
        Some(d) => {
            let (i, g) = read_inertials(&d, &tree)?;
            (Some(i), g)
        }
        None => (None, GravityModel::default_gravity()),
    };
    Ok(Robot {
        tree,
        coupled,
        inertials,
        gravity,
    })
}

/// Adds (or replaces) the coupled joints' columns: value = Σ coefficient × driver.
fn apply_coupling(
    m: &mut Measurements,
    coupled: &[(String, Vec<(String, f64)>)],
) -> Result<(), Error> {
    for (joint, terms) in coupled {
        let idx: Vec<(usize, f64)> = terms
            .iter()
            .map(|(d, c)| {
                m.joint_names
                    .iter()
                    .position(|n| n == d)
                    .map(|i| (i, *c))
                    .ok_or_else(|| format!("coupled joint {joint}: no column {d}"))
            })
            .collect::<Result<_, _>>()?;
        let at = m.joint_names.iter().position(|n| n == joint);
        let col = match at {
            Some(i) => i,
            None => {
                m.joint_names.push(joint.clone());
                for s in &mut m.samples {
                    s.q.push(0.0);
                }
                m.joint_names.len() - 1
            }
        };
        for s in &mut m.samples {
            // A term on the joint itself keeps its own value (FANUC J2/J3: J3 + J2).
            s.q[col] = idx.iter().map(|(i, c)| c * s.q[*i]).sum();
        }
    }
    Ok(())
}

// ---------------------------------------------------------------- reports

fn mm(v: f64) -> String {
    format!("{:.3}", v * 1e3)
}

fn opt_mm(v: Option<f64>) -> String {
    v.map_or("-".into(), mm)
}

fn steps_table(r: &Report, published: &[(&str, &str)]) {
    println!("| step | free | RMS cal before [mm] | RMS cal after [mm] | mean cal [mm] | max cal [mm] | RMS held-out before [mm] | RMS held-out after [mm] | published |");
    println!("|---|---|---|---|---|---|---|---|---|");
    for s in &r.steps {
        let p = published
            .iter()
            .find(|(l, _)| *l == s.label)
            .map_or("", |(_, v)| *v);
        println!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            s.label,
            s.free,
            opt_mm(s.rms_before),
            mm(s.rms),
            mm(s.mean),
            mm(s.max),
            opt_mm(s.val_rms_before),
            opt_mm(s.val_rms),
            p
        );
    }
    println!();
}

fn diagnosis(r: &Report) {
    let Some(d) = &r.diagnosis else { return };
    println!(
        "Residual test after the geometric step: {}.",
        d.residual_test.summary
    );
    if let Some(n) = d.residual_test.noise_rms {
        println!("Noise estimate (RMS 3-D): {} mm.", mm(n));
    }
    println!();
    println!("Candidates (first round, best score first; held-out RMS linearised):");
    println!();
    println!("| label | score [mm²] | independence | held-out RMS if added [mm] | status |");
    println!("|---|---|---|---|---|");
    for c in r.candidates.iter().take(12) {
        println!(
            "| {} | {:.4} | {:.3} | {} | {} |",
            c.label,
            c.score * 1e6,
            c.independence,
            opt_mm(c.val_rms),
            c.status.name()
        );
    }
    let aliased: Vec<&str> = r
        .candidates
        .iter()
        .filter(|c| c.status == CandidateStatus::Aliased)
        .map(|c| c.label.as_str())
        .collect();
    println!(
        "\n{} candidates scored; aliased: {}.\n",
        r.candidates.len(),
        if aliased.is_empty() {
            "none".to_string()
        } else {
            aliased.join(", ")
        }
    );
    for (i, round) in d.rounds.iter().enumerate() {
        for t in &round.trials {
            println!(
                "- round {}: `{}`: RMS {} mm, held-out {} mm, F = {:.1} (p = {:.1e}, threshold {:.1e}), BIC {:.1} -> {:.1}, held-out Wilcoxon z = {} -> {}",
                i + 1,
                t.label,
                mm(t.rms),
                opt_mm(t.val_rms),
                t.f,
                t.f_p,
                t.f_threshold,
                t.bic.0,
                t.bic.1,
                t.held_out
                    .map_or("-".into(), |(t, p)| format!("{t:.2} (p = {p:.1e})")),
                if t.accepted {
                    "added".to_string()
                } else {
                    format!("rejected: {}", t.reason)
                }
            );
        }
    }
    println!("\nSelected effects: {:?}.", r.selected_effects);
    if !d.effect_parameters.is_empty() {
        println!("\n| parameter | estimate | std. error | unit | stiffness |");
        println!("|---|---|---|---|---|");
        for e in &d.effect_parameters {
            println!(
                "| {} | {:.4e} | {} | {} | {} |",
                e.name,
                e.value,
                e.std_error.map_or("-".into(), |s| format!("{s:.1e}")),
                e.unit,
                e.stiffness
                    .as_ref()
                    .map_or(String::new(), |(s, se, u)| format!(
                        "{s:.4e} ± {} {u}",
                        se.map_or("-".into(), |v| format!("{v:.1e}"))
                    ))
            );
        }
    }
    let unexplained: Vec<String> = d
        .structure
        .iter()
        .filter(|s| s.significant)
        .map(|s| {
            format!(
                "{} (statistic {:.2}, p = {:.1e})",
                s.variable, s.statistic, s.p_value
            )
        })
        .collect();
    println!(
        "\nResidual structure left (joint angles, pose order): {}.",
        if unexplained.is_empty() {
            "none significant".to_string()
        } else {
            unexplained.join("; ")
        }
    );
    for s in d.structure.iter().filter(|s| s.significant) {
        let bins: Vec<String> = s
            .bins
            .iter()
            .map(|(c, rms, mean)| format!("{c:.2}: {} / {}", mm(*rms), mm(*mean)))
            .collect();
        println!(
            "  - {} bins (centre: RMS / |mean| mm): {}",
            s.variable,
            bins.join(", ")
        );
    }
    for n in &d.notes {
        println!("- note: {n}");
    }
    println!();
}

fn diag_options(robot: &Robot, effects: EffectSelection) -> DiagnoseOptions {
    DiagnoseOptions {
        effects,
        inertials: robot.inertials.clone(),
        gravity: robot.gravity,
        ..DiagnoseOptions::default()
    }
}

fn context(robot: &Robot) -> Result<EffectContext, Error> {
    let gravity = match &robot.inertials {
        Some(i) => Some(Arc::new(GravityModel::new(&robot.tree, i, robot.gravity)?)),
        None => None,
    };
    Ok(EffectContext {
        tree: robot.tree.clone(),
        gravity,
    })
}

/// The calibrated model of a report (its tree or table, device, targets and effects), or the
/// nominal step's (nominal geometry, that step's device and targets, no effects).
fn rebuild(
    r: &Report,
    robot: &Robot,
    ctx: &EffectContext,
    nominal: bool,
    targets: &[(String, usize)],
) -> Result<(Model, Vec<f64>), Error> {
    let value = |name: &str| -> Option<(f64, f64)> {
        r.parameters
            .iter()
            .find(|p| p.name == name)
            .map(|p| (p.nominal, p.estimate))
    };
    let tree = if nominal {
        robot.tree.clone()
    } else {
        match &r.tree {
            Some(t) => t.clone(),
            None => DhTree::serial(&r.calibrated),
        }
    };
    let mut model = Model::new_tree(&tree, targets, &ModelOptions::default())?;
    let pick = |n: &str| value(n).map(|(a, b)| if nominal { a } else { b });
    let dev = |f: &str| pick(&format!("device.{f}")).unwrap_or(0.0);
    let device = from_xyz_rpy(
        [dev("x"), dev("y"), dev("z")],
        [dev("rx"), dev("ry"), dev("rz")],
    );
    model.set_device(&device);
    for (k, (name, _)) in targets.iter().enumerate() {
        if let (Some(x), Some(y), Some(z)) = (
            pick(&format!("target.{name}.x")),
            pick(&format!("target.{name}.y")),
            pick(&format!("target.{name}.z")),
        ) {
            model.set_target(k, Vector3::new(x, y, z));
        }
    }
    if !nominal {
        for label in &r.selected_effects {
            model.add_effect(parse_label_in(label, ctx)?)?;
        }
    }
    let mut x = vec![0.0; model.parameter_count()];
    if !nominal {
        for (c, p) in model.parameters().iter().enumerate() {
            if matches!(p.block, dh_calib::model::Block::Effect(_)) {
                if let Some((_, v)) = value(&p.name) {
                    x[c] = v;
                }
            }
        }
    }
    Ok((model, x))
}

fn rms(d: &[f64]) -> f64 {
    (d.iter().map(|v| v * v).sum::<f64>() / d.len().max(1) as f64).sqrt()
}

fn mean(d: &[f64]) -> f64 {
    d.iter().sum::<f64>() / d.len().max(1) as f64
}

fn maxv(d: &[f64]) -> f64 {
    d.iter().copied().fold(0.0, f64::max)
}

// ---------------------------------------------------------------- the sets

fn innopolis() -> Result<(), Error> {
    let set = "innopolis_fanuc_r2000ic_165f";
    let data = load(
        Layout::Innopolis,
        &shared("innopolis_fanuc_r2000ic_165f_3markers"),
        &["calibration_dataset.csv"],
    )?;
    let robot = read_robot(set)?;
    println!("## Innopolis FANUC R-2000iC/165F (24 poses x 10 repeats x 3 markers)\n");
    // Leave one pose out: 24 folds over the 24 configurations (repeats stay together).
    let options = CalibrationOptions {
        folds: 24,
        ..CalibrationOptions::default()
    };
    let r = diagnose_tree(
        &robot.tree,
        &data,
        &options,
        &diag_options(&robot, EffectSelection::Auto),
    )?;
    println!("Held-out: leave one pose out (24 folds, the 10 repeats and 3 markers of a pose together).\n");
    steps_table(
        &r,
        &[
            ("nominal", "13.15 (base + tool only, RMS)"),
            ("geometric", "0.53 (RMS, same data)"),
        ],
    );
    diagnosis(&r);
    if let Some(f) = &r.noise_floor {
        println!(
            "Noise floor (pure error of the repeats, {:?}): {} mm RMS 3-D after the fit; per axis sigma {} mm.\n",
            f.source,
            mm(f.rms),
            mm(f.sigma)
        );
    }
    // How far down the data lets the best candidates go, declared rather than selected.
    let best: Vec<String> = r
        .candidates
        .iter()
        .filter(|c| c.status != CandidateStatus::Aliased)
        .take(3)
        .map(|c| c.label.clone())
        .collect();
    for n in 1..=best.len() {
        let labels = best[..n].to_vec();
        let e = diagnose_tree(
            &robot.tree,
            &data,
            &options,
            &diag_options(&robot, EffectSelection::Labels(labels.clone())),
        )?;
        println!(
            "Declared (not selected) {}: RMS {} mm, leave-one-pose-out RMS {} mm.",
            labels.join(" + "),
            mm(e.rms_after),
            opt_mm(e.val_rms_after)
        );
    }
    println!();
    Ok(())
}

fn boby() -> Result<(), Error> {
    let set = "boby_klimchik_fanuc_r2000ic_165f";
    let raw = load(
        Layout::Boby,
        &shared("boby_klimchik_laser_tracker_cpa"),
        &["N1N2N3Jval.csv"],
    )?;
    let mut data = raw.clone();
    let robot = read_robot(set)?;
    // FANUC J2/J3 interaction (the sheet's `coupled`): the serial joint 3 is J3 + J2.
    apply_coupling(&mut data, &robot.coupled)?;
    println!("## Boby & Klimchik laser-tracker CPA (36 poses x 3 SMRs, one joint at a time)\n");
    let options = CalibrationOptions {
        folds: 6,
        outliers: dh_calib::outliers::OutlierOptions {
            keep: std::env::var("LW_KEEP").is_ok(),
            ..Default::default()
        },
        ..CalibrationOptions::default()
    };
    let r = diagnose_tree(
        &robot.tree,
        &data,
        &options,
        &diag_options(&robot, EffectSelection::Auto),
    )?;
    println!("Held-out: 6-fold cross-validation over the 36 poses.\n");
    steps_table(&r, &[]);
    diagnosis(&r);
    // Commanded against measured joint angles, before and after the selected effects.
    let cpa = analyse(&raw, &CpaOptions::default())?;
    let ctx = context(&robot)?;
    let effects: Vec<Arc<dyn Effect>> = r
        .selected_effects
        .iter()
        .map(|l| parse_label_in(l, &ctx))
        .collect::<Result<_, _>>()?;
    let values: HashMap<String, f64> = r
        .parameters
        .iter()
        .map(|p| (p.name.clone(), p.estimate))
        .collect();
    println!("Joint angle residual (CPA: angle measured on the fitted circle minus commanded, mean removed), before and after subtracting what the selected effects predict for that joint:\n");
    println!("| joint | poses | span [deg] | RMS before [arcsec] | max before [arcsec] | RMS after [arcsec] | max after [arcsec] | CPA: linear slope / RMS after the line [arcsec] |");
    println!("|---|---|---|---|---|---|---|---|");
    let arcsec = 180.0 * 3600.0 / std::f64::consts::PI;
    for j in &cpa.joints {
        let sweep = &cpa.sweeps[j.sweep];
        // One q per pose, in sweep order.
        let mut qs: Vec<Vec<f64>> = Vec::new();
        for &s in &sweep.samples {
            let q = &data.samples[s].q;
            if qs.last() != Some(q) {
                qs.push(q.clone());
            }
        }
        if qs.len() != j.motion.poses.len() {
            continue;
        }
        let predicted: Vec<f64> = qs
            .iter()
            .map(|q| {
                effects
                    .iter()
                    .filter(|e| {
                        e.joint() == j.name && e.field() == dh_calib::model::EffectField::Theta
                    })
                    .map(|e| {
                        let p: Vec<f64> = e
                            .parameter_names()
                            .iter()
                            .map(|n| values.get(n).copied().unwrap_or(0.0))
                            .collect();
                        e.delta(q, &p)
                    })
                    .sum()
            })
            .collect();
        let before: Vec<f64> = j.motion.poses.iter().map(|p| p.residual).collect();
        let (mb, mp) = (mean(&before), mean(&predicted));
        let b: Vec<f64> = before.iter().map(|v| (v - mb) * arcsec).collect();
        let a: Vec<f64> = before
            .iter()
            .zip(&predicted)
            .map(|(v, p)| ((v - mb) - (p - mp)) * arcsec)
            .collect();
        let amax = |v: &[f64]| v.iter().map(|x| x.abs()).fold(0.0, f64::max);
        println!(
            "| {} | {} | {:.0} | {:.1} | {:.1} | {:.1} | {:.1} | {} |",
            j.name,
            qs.len(),
            j.span.to_degrees(),
            rms(&b),
            amax(&b),
            rms(&a),
            amax(&a),
            j.motion.linear.as_ref().map_or("-".into(), |l| format!(
                "{:.2e} / {:.1}",
                l.slope,
                l.rms * arcsec
            ))
        );
    }
    println!();
    Ok(())
}

fn liaowu() -> Result<(), Error> {
    let set = "liaowu_abb_irb120";
    let dir = shared("liaowu_abb_irb120_position");
    let all = load(
        Layout::Liaowu,
        &dir,
        &[
            "CaliJointAngles.csv",
            "CaliPosition.csv",
            "TestJointAngles.csv",
            "TestPosition.csv",
            "TestJointAngles2.csv",
            "TestPosition2.csv",
        ],
    )?;
    let robot = read_robot(set)?;
    // The test points are targets of their own, never measured during calibration: they are
    // predicted from their position at the zero configuration, as the paper does.
    let mut cal = all.clone();
    cal.samples.retain(|s| s.split == Split::Calibration);
    println!("## Liao Wu et al. ABB IRB 120 (36 poses x 3 points; test sets of 10 and 30 poses)\n");
    let options = CalibrationOptions {
        folds: 6,
        outliers: dh_calib::outliers::OutlierOptions {
            keep: std::env::var("LW_KEEP").is_ok(),
            ..Default::default()
        },
        ..CalibrationOptions::default()
    };
    let r = diagnose_tree(
        &robot.tree,
        &cal,
        &options,
        &diag_options(&robot, EffectSelection::Auto),
    )?;
    println!("Held-out in the table: 6-fold cross-validation over the 36 calibration poses.\n");
    steps_table(&r, &[]);
    diagnosis(&r);
    // Test sets.
    let ctx = context(&robot)?;
    let targets: Vec<(String, usize)> = cal.targets.iter().map(|t| (t.clone(), 0)).collect();
    let zero = dh_calib::import::liaowu::TARGETS_AT_ZERO;
    let geometric = diagnose_tree(
        &robot.tree,
        &cal,
        &options,
        &diag_options(&robot, EffectSelection::None),
    )?;
    // The paper's declared pair, and the automatic selection at a laxer level: 36 poses give
    // the second compliance a held-out p of about 0.02.
    let declared = diagnose_tree(
        &robot.tree,
        &cal,
        &options,
        &diag_options(
            &robot,
            EffectSelection::Labels(vec![
                "compliance:joint_2".into(),
                "compliance:joint_3".into(),
            ]),
        ),
    )?;
    let lax = diagnose_tree(
        &robot.tree,
        &cal,
        &options,
        &DiagnoseOptions {
            alpha: 0.05,
            ..diag_options(&robot, EffectSelection::Auto)
        },
    )?;
    let lax_label = format!(
        "geometric + automatic at level 0.05 ({})",
        lax.selected_effects.join(", ")
    );
    let mut rows = Vec::new();
    for (label, nominal, report) in [
        ("nominal step", true, &r),
        ("geometric", false, &geometric),
        ("geometric + selected effects", false, &r),
        (
            "geometric + compliance:joint_2, compliance:joint_3 (the paper's)",
            false,
            &declared,
        ),
        (lax_label.as_str(), false, &lax),
    ] {
        let (model, x) = rebuild(report, &robot, &ctx, nominal, &targets)?;
        let q0 = vec![0.0; 6];
        let tip0 = model.tip(&x, &q0);
        let mut per_set = Vec::new();
        for (k, name) in [(3usize, "test1"), (4, "test2")] {
            let p0 = Vector3::new(zero[k][0], zero[k][1], zero[k][2]);
            let t = tip0.inverse_transform_point(&Point3::from(p0)).coords;
            let d: Vec<f64> = all
                .samples
                .iter()
                .filter(|s| s.target == k)
                .map(|s| {
                    let p = model.tip(&x, &s.q) * Point3::from(t);
                    (p.coords - s.point).norm()
                })
                .collect();
            per_set.push((name, d));
        }
        rows.push((label, per_set));
    }
    println!("Test points (predicted from their measured position at the zero configuration, as in the paper's Experiment.m):\n");
    println!("| model | test set 1 (10) mean / max [mm] | test set 2 (30) mean / max [mm] | all 40 mean / max / RMS [mm] |");
    println!("|---|---|---|---|");
    for (label, sets) in &rows {
        let all: Vec<f64> = sets.iter().flat_map(|(_, d)| d.iter().copied()).collect();
        println!(
            "| {label} | {} / {} | {} / {} | {} / {} / {} |",
            mm(mean(&sets[0].1)),
            mm(maxv(&sets[0].1)),
            mm(mean(&sets[1].1)),
            mm(maxv(&sets[1].1)),
            mm(mean(&all)),
            mm(maxv(&all)),
            mm(rms(&all))
        );
    }
    println!();
    Ok(())
}

/// The DLR Agile Justin tree runs through the CLI, which reads its tree sheet.
fn dlr() -> Result<(), Error> {
    eprintln!(
        "dlr: the Agile Justin tree runs through the CLI (docs/results.md):\n  \
         urdf-dh import --layout dlr ../shared/measured/dlr_agile_justin_vicon/measurements.csv --out dlr.csv\n  \
         urdf-dh calibrate --model fixtures/measured/dlr_agile_justin/model.yaml --data dlr.csv \\\n    \
         --folds 10 --effects auto --max-effects 40"
    );
    Ok(())
}

/// The MUKCa robot and placements of the upstream result `calibrated_urdf/panda_6`: trained
/// on `front` (its `config.yaml`), tested on the robot's other placements (`left`, `right`), as
/// its `compute_improved_performance` does.
const MUKCA_ROBOT: &str = "panda_6";
const MUKCA_TRAIN: &[&str] = &["front"];
const MUKCA_TEST: &[&str] = &["left", "right"];

/// The contacts of `placements` of `robot`, marked `split`.
fn mukca_load(robot: &str, placements: &[&str], split: Split) -> Result<Measurements, Error> {
    let dir = shared("mukca_ball_socket_panda_iiwa")
        .join("data")
        .join(robot);
    let mut texts = Vec::new();
    for p in placements {
        for f in ["hole_0.csv", "hole_1.csv"] {
            texts.push((format!("{p}/{f}"), read(&dir.join(p).join(f))?));
        }
    }
    let sources: Vec<Source<'_>> = texts
        .iter()
        .map(|(name, text)| Source { name, text })
        .collect();
    let mut m = import(Layout::Mukca, &sources)?;
    for s in &mut m.samples {
        s.split = split;
    }
    Ok(m)
}

fn mukca() -> Result<(), Error> {
    use dh_calib::socket::calibrate_sockets;
    let robot = read_robot("mukca_panda")?;
    let mut data = mukca_load(MUKCA_ROBOT, MUKCA_TRAIN, Split::Calibration)?;
    data.samples
        .extend(mukca_load(MUKCA_ROBOT, MUKCA_TEST, Split::Validation)?.samples);
    let r = calibrate_sockets(&robot.tree, &data, &CalibrationOptions::default())?;
    println!(
        "## MUKCa Franka Panda ({MUKCA_ROBOT}), ball-in-socket contacts\n\n\
         Train: {} ({} contacts); test: {} ({} contacts). Consistency = mean distance of each \
         modelled ball position to its socket's mean (MUKCa's mean absolute error), mm.\n",
        MUKCA_TRAIN.join(", "),
        r.consistency[0].train.points,
        MUKCA_TEST.join(", "),
        r.consistency[0].test.map_or(0, |t| t.points),
    );
    println!("| step | free | RMS to fitted sockets | train consistency | train distance error | test consistency | test RMS | test distance error |");
    println!("|---|---|---|---|---|---|---|---|");
    for c in &r.consistency {
        let step = r.steps.iter().find(|s| s.label == c.label);
        println!(
            "| {} | {} | {} | {} | {} | {} | {} | {} |",
            c.label,
            step.map_or("-".into(), |s| s.free.to_string()),
            step.map_or("-".into(), |s| mm(s.rms)),
            mm(c.train.mean_abs),
            opt_mm(c.train.distance_error),
            opt_mm(c.test.map(|t| t.mean_abs)),
            opt_mm(c.test.map(|t| t.rms)),
            opt_mm(c.test.and_then(|t| t.distance_error)),
        );
    }
    println!(
        "\npublished (MUKCa README): train 8.28 -> 0.168, test 7.79 -> 0.347\n\
         contact noise that weighted the distance: {} mm; fixed: {}\n",
        mm(r.sigma_point),
        r.fixed
            .iter()
            .map(|f| f.name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    );
    for n in &r.notes {
        println!("- {n}");
    }
    Ok(())
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let sets: [(&str, Run); 5] = [
        ("innopolis", innopolis),
        ("boby", boby),
        ("dlr", dlr),
        ("liaowu", liaowu),
        ("mukca", mukca),
    ];
    for (name, run) in sets {
        if !args.is_empty() && !args.iter().any(|a| a == name) {
            continue;
        }
        if let Err(e) = run() {
            eprintln!("{name}: skipped: {e}");
        }
    }
}
