//! Every real URDF in ../shared/robots (written by others) extracts, and forward kinematics of
//! the table agrees with the URDF's own. Needs ../shared; skips with a reason without it.

use dh_core::{compare, extract, Convention, Tolerance};
use urdf_axes::UrdfModel;

use crate::common::{robot_dirs, skip_without_shared};

#[test]
fn every_shared_urdf_extracts_with_fk_agreement() {
    let Some(shared) = skip_without_shared("corpus") else {
        return;
    };
    let dirs = robot_dirs(&shared, "robots");
    assert!(
        dirs.len() >= 40,
        "expected the shared corpus, found {} robots",
        dirs.len()
    );
    let mut chains = 0;
    let mut report = String::new();
    for dir in dirs {
        let id = dir.file_name().unwrap().to_string_lossy().into_owned();
        let text = std::fs::read(dir.join("robot.urdf")).unwrap();
        let model = UrdfModel::from_bytes(&text).unwrap_or_else(|e| panic!("{id}: {e}"));
        let root = model.root_link().to_string();
        for leaf in model.leaves() {
            let Ok(chain) = model.chain(Some(&root), Some(leaf)) else {
                continue;
            };
            if chain.axes().is_empty() {
                continue;
            }
            for convention in [Convention::Standard, Convention::Modified] {
                let ex = extract(
                    chain.axes(),
                    &chain.tip_pose(),
                    Tolerance::default(),
                    convention,
                )
                .unwrap_or_else(|e| panic!("{id} -> {leaf}: {e}"));
                let dev = compare(&ex.table, |q| chain.fk(q), 200, 1).unwrap();
                assert!(
                    dev.max_position_error <= ex.bound.position
                        && dev.max_orientation_error <= ex.bound.orientation,
                    "{id} -> {leaf} ({convention}): {dev:?} beyond {:?}",
                    ex.bound
                );
                if convention == Convention::Standard {
                    report += &format!(
                        "{id:<44} {leaf:<28} {:>2} joints  max err {:.1e} m {:.1e} rad  warnings {}\n",
                        ex.table.rows.len(), dev.max_position_error, dev.max_orientation_error, ex.warnings.len()
                    );
                }
            }
            chains += 1;
        }
    }
    println!("{report}");
    assert!(chains >= 40, "only {chains} chains extracted");
}
