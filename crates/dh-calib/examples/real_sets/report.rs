//! Printing a calibration as the Markdown of `docs/results.md`, and the figures it needs.

use super::*;

pub(crate) fn mm(v: f64) -> String {
    format!("{:.3}", v * 1e3)
}

pub(crate) fn opt_mm(v: Option<f64>) -> String {
    v.map_or("-".into(), mm)
}

pub(crate) fn steps_table(r: &Report, published: &[(&str, &str)]) {
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

pub(crate) fn diagnosis(r: &Report) {
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

pub(crate) fn diag_options(robot: &Robot, effects: EffectSelection) -> DiagnoseOptions {
    DiagnoseOptions {
        effects,
        inertials: robot.inertials.clone(),
        gravity: robot.gravity,
        ..DiagnoseOptions::default()
    }
}

pub(crate) fn context(robot: &Robot) -> Result<EffectContext, Error> {
    let gravity = match &robot.inertials {
        Some(i) => Some(Arc::new(GravityModel::new(&robot.tree, i, robot.gravity)?)),
        None => None,
    };
    Ok(EffectContext {
        tree: robot.tree.clone(),
        gravity,
        gravity_vector: robot.gravity,
    })
}

/// The calibrated model of a report (its tree or table, device, targets and effects), or the
/// nominal step's (nominal geometry, that step's device and targets, no effects).
pub(crate) fn rebuild(
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

pub(crate) fn rms(d: &[f64]) -> f64 {
    (d.iter().map(|v| v * v).sum::<f64>() / d.len().max(1) as f64).sqrt()
}

pub(crate) fn mean(d: &[f64]) -> f64 {
    d.iter().sum::<f64>() / d.len().max(1) as f64
}

pub(crate) fn maxv(d: &[f64]) -> f64 {
    d.iter().copied().fold(0.0, f64::max)
}

// ---------------------------------------------------------------- the sets
