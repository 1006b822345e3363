//! The default tip on every robot of ../shared/robots (NOTES.md `urdf_chain:`, or the chain
//! line of SOURCE.md) and
//! ../shared/robots-ext (manifest.json): without `--tip`, a single-arm robot gives the listed
//! tip or a tip whose chain has the same moving joints; a robot listed with several chains
//! either gives one of them or is refused (two arms, a humanoid). Needs ../shared; skips with
//! a reason without it.

use std::collections::BTreeMap;
use std::path::Path;

use urdf_axes::UrdfModel;

use crate::common::skip_without_shared;

/// The chain of a SOURCE.md: "- Chain: base link `B`, tip link `T`, ...".
fn source_chain(path: &Path) -> Option<(String, String)> {
    let text = std::fs::read_to_string(path).ok()?;
    let line = text
        .lines()
        .find(|l| l.starts_with("- Chain: base link `"))?;
    let mut quoted = line.split('`').skip(1).step_by(2);
    Some((quoted.next()?.to_owned(), quoted.next()?.to_owned()))
}

/// The `urdf_chain:` base and tip of a NOTES.md.
fn notes_chain(path: &Path) -> Option<(String, String)> {
    let text = std::fs::read_to_string(path).ok()?;
    let mut lines = text.lines().skip_while(|l| l.trim_end() != "urdf_chain:");
    lines.next()?;
    let mut base = None;
    let mut tip = None;
    for l in lines.take_while(|l| l.starts_with(' ')) {
        let value = |key: &str| {
            l.trim()
                .strip_prefix(key)
                .map(|v| v.split('#').next().unwrap_or("").trim().to_owned())
        };
        base = base.or(value("base_link:"));
        tip = tip.or(value("tip_link:"));
    }
    Some((base?, tip?))
}

/// The moving joints of a chain, base to tip.
fn moving(
    model: &UrdfModel,
    base: Option<&str>,
    tip: Option<&str>,
) -> Result<(String, Vec<String>), String> {
    let chain = model.chain(base, tip).map_err(|e| e.to_string())?;
    Ok((
        chain.tip().to_owned(),
        chain.axes().iter().map(|a| a.name.clone()).collect(),
    ))
}

#[test]
fn the_default_tip_is_the_end_of_the_arm_on_every_single_arm_robot() {
    let Some(shared) = skip_without_shared("default tip") else {
        return;
    };
    // (corpus, robot) -> listed chains (base, tip).
    let mut robots: BTreeMap<(String, String), Vec<(String, String)>> = BTreeMap::new();
    let mut unlisted = Vec::new();
    for e in std::fs::read_dir(shared.join("robots")).unwrap().flatten() {
        let dir = e.path();
        if !dir.join("robot.urdf").is_file() {
            continue;
        }
        let id = e.file_name().to_string_lossy().into_owned();
        match notes_chain(&dir.join("NOTES.md")).or_else(|| source_chain(&dir.join("SOURCE.md"))) {
            Some(chain) => robots.entry(("robots".into(), id)).or_default().push(chain),
            None => unlisted.push(id),
        }
    }
    let manifest: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(shared.join("robots-ext/manifest.json")).unwrap(),
    )
    .unwrap();
    for c in manifest["chains"].as_array().unwrap() {
        if c["expect"] == "refuse" {
            continue;
        }
        let s = |k: &str| c[k].as_str().unwrap().to_owned();
        robots
            .entry(("robots-ext".into(), s("robot")))
            .or_default()
            .push((s("base"), s("tip")));
    }
    assert!(
        robots.len() >= 250,
        "expected both corpora, found {} robots",
        robots.len()
    );

    let (mut single, mut single_ok, mut multi, mut multi_one, mut multi_refused) = (0, 0, 0, 0, 0);
    let mut failures = Vec::new();
    for ((corpus, id), chains) in &robots {
        let bytes = std::fs::read(shared.join(corpus).join(id).join("robot.urdf")).unwrap();
        let model = UrdfModel::from_bytes(&bytes).unwrap_or_else(|e| panic!("{id}: {e}"));
        let got = moving(&model, None, None);
        let listed: Vec<(String, Vec<String>)> = chains
            .iter()
            .map(|(b, t)| moving(&model, Some(b), Some(t)).unwrap_or_else(|e| panic!("{id}: {e}")))
            .collect();
        let matches = got
            .as_ref()
            .is_ok_and(|(tip, joints)| listed.iter().any(|(t, j)| t == tip || j == joints));
        // Dual-arm robots of ../shared/robots list one arm in NOTES.md; their names say so.
        let several = chains.len() > 1 || id.contains("dual-arm");
        match (several, matches, &got) {
            (false, true, _) => single_ok += 1,
            (true, true, _) => multi_one += 1,
            (true, false, Err(_)) => multi_refused += 1,
            _ => failures.push(format!("{corpus}/{id}: default {got:?}, listed {chains:?}")),
        }
        if several {
            multi += 1;
        } else {
            single += 1;
        }
    }
    // Robots of ../shared/robots without a listed chain: the default must exist.
    for id in &unlisted {
        let bytes = std::fs::read(shared.join("robots").join(id).join("robot.urdf")).unwrap();
        let model = UrdfModel::from_bytes(&bytes).unwrap();
        if let Err(e) = moving(&model, None, None) {
            failures.push(format!("robots/{id}: {e}"));
        }
    }
    println!(
        "default tip: {single_ok}/{single} single-arm robots give the listed chain; of {multi} \
         robots listed with several chains {multi_one} give one of them and {multi_refused} are \
         refused as ambiguous; {} unlisted robots give a chain",
        unlisted.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
