//! The report of `urdf-dh calibrate` on a tree sheet (see [`dh_workflows::tree_sheet`]): every chain
//! of the tree fitted at once, each measured target on the branch it names (the run and the
//! calibrated tree sheet are the library's, `dh_workflows::calibration`).
//!
//! The steps, validation, effects and report are those of a serial model; the text adds a
//! `tree` section saying which parameters, targets and mount belong to the trunk and to each
//! branch.

use dh_workflows::calibration::Tree;
use dh_workflows::fit::TableDoc;

use crate::commands::calibrate::text_for;

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

/// The text report of a tree calibration: the serial report with the tree section before its
/// closing `result:` line.
pub(crate) fn text(t: &Tree) -> String {
    let text = text_for(&t.inputs.model, &t.inputs.data, &t.calibration.doc.report);
    // The tree section goes before the closing `result:` line.
    let (body, result) = match text.rfind("result: ") {
        Some(k) => text.split_at(k),
        None => (text.as_str(), ""),
    };
    format!("{body}{}{result}", tree_text(&t.calibration.doc.tree))
}
