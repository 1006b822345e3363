//! Sheet bytes (YAML or JSON) -> `Sheet` -> forward kinematics, both conventions, and a write
//! and re-read of the table in other units.
//!
//! Fails on a panic, a hang, and on any NaN or infinity coming out of a sheet that was accepted
//! (an accepted sheet has finite numbers, so its kinematics must be finite too).
#![no_main]

use dh_core::Convention;
use dh_workflows::render::{render_sheet, Format};
use dh_workflows::sheet::{Sheet, SheetDoc};
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
    let Ok(sheet) = Sheet::parse(text, "fuzz.yaml") else {
        return;
    };
    let table = &sheet.table;
    let n = table.rows.len();
    for q in [vec![0.0; n], vec![0.7; n], vec![-2.5; n]] {
        if let Ok(p) = table.fk(&q) {
            assert!(
                finite(&p),
                "non-finite FK of an accepted sheet: {p:?}\n{text}"
            );
        }
    }
    for c in [Convention::Standard, Convention::Modified] {
        let other = table.to_convention(c);
        if let Ok(p) = other.fk(&vec![0.3; n]) {
            assert!(
                finite(&p),
                "non-finite FK after conversion to {c:?}: {p:?}\n{text}"
            );
        }
    }
    let doc = SheetDoc::from_table(table, LengthUnit::Mm, AngleUnit::Deg);
    let yaml = render_sheet(&doc, Format::Yaml).expect("render");
    if let Err(e) = Sheet::parse(&yaml, "again.yaml") {
        panic!("a sheet written from an accepted sheet does not read back: {e:#}\n{yaml}");
    }
    for format in [Format::Text, Format::Csv, Format::Markdown, Format::Json] {
        assert!(render_sheet(&doc, format).is_ok());
    }
});
