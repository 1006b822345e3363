//! Every robot of the shared corpus (`../shared/robots/*/robot.urdf`, beside the workspace) must
//! parse, and its chain must build with `fk(0) == tip_pose()`. Nothing is copied from there.

use std::fs;
use std::path::{Path, PathBuf};

use urdf_axes::{UrdfError, UrdfModel};

const CORPUS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/robots");

/// `urdf_chain:` base and tip links and the `urdf_mapping:` joint list of a NOTES.md, when
/// present.
#[derive(Debug, Default)]
struct Notes {
    base: Option<String>,
    tip: Option<String>,
    joints: Option<Vec<String>>,
}

fn value_after<'a>(line: &'a str, key: &str) -> Option<&'a str> {
    let rest = line.trim_start().strip_prefix(key)?;
    let v = rest.split('#').next()?.trim();
    Some(v.trim_matches(|c| c == '\'' || c == '"'))
}

fn read_notes(path: &Path) -> Notes {
    let Ok(text) = fs::read_to_string(path) else {
        return Notes::default();
    };
    let mut notes = Notes::default();
    let mut section = "";
    for line in text.lines() {
        if !line.starts_with(' ') {
            section = line.trim_end();
        }
        match section {
            "urdf_chain:" => {
                if let Some(v) = value_after(line, "base_link:") {
                    notes.base = Some(v.to_owned());
                }
                if let Some(v) = value_after(line, "tip_link:") {
                    notes.tip = Some(v.to_owned());
                }
            }
            s if s.starts_with("urdf_mapping:") => {
                if let Some(v) = value_after(line, "joints:") {
                    let names = v
                        .trim_matches(|c| c == '[' || c == ']')
                        .split(',')
                        .map(|n| n.trim().trim_matches(|c| c == '\'' || c == '"').to_owned())
                        .filter(|n| !n.is_empty())
                        .collect();
                    notes.joints.get_or_insert(names);
                }
            }
            _ => {}
        }
    }
    notes
}

fn check_chain(
    robot: &str,
    model: &UrdfModel,
    base: Option<&str>,
    tip: Option<&str>,
) -> Vec<String> {
    let chain = model
        .chain(base, tip)
        .unwrap_or_else(|e| panic!("{robot}: chain {base:?} -> {tip:?}: {e}"));
    let zero = vec![0.0; chain.axes().len()];
    let fk = chain.fk(&zero);
    let tip_pose = chain.tip_pose();
    assert!(
        (fk.translation.vector - tip_pose.translation.vector).norm() < 1e-12
            && fk.rotation.angle_to(&tip_pose.rotation) < 1e-12,
        "{robot}: fk(0) {fk} differs from tip_pose {tip_pose}"
    );
    let lines = chain.axis_lines(&zero).unwrap();
    for (l, ax) in lines.iter().zip(chain.axes()) {
        assert!(
            (l.direction() - ax.line.direction()).norm() < 1e-12
                && (l.moment() - ax.line.moment()).norm() < 1e-12,
            "{robot}: axis line of {} at q = 0 differs",
            ax.name
        );
    }
    chain.axes().iter().map(|a| a.name.clone()).collect()
}

#[test]
fn every_corpus_robot_parses_and_builds_its_chain() {
    let root = PathBuf::from(CORPUS);
    let Ok(dirs) = fs::read_dir(&root) else {
        test_skips::skip(&format!(
            "{} is absent (the shared robot corpus sits beside the workspace only on project \
             machines)",
            root.display()
        ));
        return;
    };
    let mut dirs: Vec<PathBuf> = dirs.filter_map(|d| d.ok().map(|d| d.path())).collect();
    dirs.sort();
    let mut robots = 0;
    let mut chains = 0;
    let mut noted = 0;
    let mut checked_lists = 0;
    for dir in dirs {
        let urdf = dir.join("robot.urdf");
        let Ok(bytes) = fs::read(&urdf) else { continue };
        let name = dir
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let model = UrdfModel::from_bytes(&bytes).unwrap_or_else(|e| panic!("{name}: {e}"));
        robots += 1;
        let notes = read_notes(&dir.join("NOTES.md"));
        if dir.join("dh.yaml").exists() && (notes.base.is_some() || notes.tip.is_some()) {
            let names = check_chain(&name, &model, notes.base.as_deref(), notes.tip.as_deref());
            if let Some(expected) = &notes.joints {
                assert_eq!(&names, expected, "{name}: moving joints of the noted chain");
                checked_lists += 1;
            }
            noted += 1;
            chains += 1;
        } else {
            match model.chain(None, None) {
                Ok(_) => {
                    check_chain(&name, &model, None, None);
                    chains += 1;
                }
                Err(UrdfError::SeveralLeaves { .. }) => {
                    for leaf in model.leaves() {
                        match model.chain(None, Some(leaf)) {
                            Ok(_) => {
                                check_chain(&name, &model, None, Some(leaf));
                                chains += 1;
                            }
                            Err(UrdfError::NoMovingJoint { .. }) => {}
                            Err(e) => panic!("{name}: chain to leaf {leaf}: {e}"),
                        }
                    }
                }
                Err(e) => panic!("{name}: default chain: {e}"),
            }
        }
    }
    assert!(robots > 0, "no robot.urdf found under {}", root.display());
    assert!(chains >= robots);
    // Two noted robots have `urdf_mapping: null` (deliberate mismatches), so no joint list.
    assert!(
        noted > 0 && checked_lists > 0,
        "NOTES.md urdf_chain or urdf_mapping joints not read ({noted} chains, {checked_lists} lists)"
    );
}
