//! Tree-sheet bytes (YAML or JSON with `branches`) -> `TreeSheet` -> frames of the tree at three
//! joint vectors -> written in mm/deg and read back.
//!
//! Fails on a panic, a hang, a NaN or infinity in the frames of an accepted tree, and on a
//! written tree that does not read back.
#![no_main]

use dh_workflows::render::{render_sheet, Format};
use dh_workflows::tree_sheet::TreeSheet;
use dh_workflows::units::{AngleUnit, LengthUnit};
use libfuzzer_sys::fuzz_target;

fn finite(p: &nalgebra::Isometry3<f64>) -> bool {
    p.translation
        .vector
        .iter()
        .chain(p.rotation.coords.iter())
        .all(|v| v.is_finite())
}

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(sheet) = TreeSheet::parse(text, "fuzz.yaml") else {
        return;
    };
    let n = sheet.tree.rows().len();
    for q in [vec![0.0; n], vec![0.7; n], vec![-2.5; n]] {
        if let Ok(frames) = sheet.tree.frames(&q) {
            assert!(
                frames.after.iter().chain(&frames.tips).all(finite),
                "non-finite frames of an accepted tree\n{text}"
            );
        }
    }
    let doc = TreeSheet::to_doc(
        &sheet.tree,
        &sheet.coupled,
        sheet.inertials.clone(),
        LengthUnit::Mm,
        AngleUnit::Deg,
    );
    for format in [Format::Yaml, Format::Json] {
        let written = render_sheet(&doc, format).expect("render");
        if let Err(e) = TreeSheet::parse(&written, "again.yaml") {
            panic!("a tree written from an accepted tree does not read back: {e:#}\n{written}");
        }
    }
});
