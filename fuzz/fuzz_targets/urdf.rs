//! URDF bytes -> validated model -> chain -> DH table in both conventions -> verification ->
//! every output format -> the YAML and JSON read back as sheets.
//!
//! Fails on a panic, on a hang (libFuzzer's -timeout), and on any NaN or infinity in a table,
//! a transform or a verification figure of an input that was accepted.
#![no_main]

use dh_core::{Convention, DhTable, Tolerance};
use dh_workflows::render::{render_sheet, Format};
use dh_workflows::sheet::{Sheet, SheetDoc};
use dh_workflows::units::{AngleUnit, LengthUnit};
use libfuzzer_sys::fuzz_target;
use urdf_axes::UrdfModel;

fn finite_table(t: &DhTable) -> bool {
    let pose = |p: &nalgebra::Isometry3<f64>| {
        p.translation
            .vector
            .iter()
            .chain(p.rotation.coords.iter())
            .all(|v| v.is_finite())
    };
    pose(&t.base)
        && pose(&t.tool)
        && t.rows.iter().all(|r| {
            [r.a, r.alpha, r.d, r.theta].iter().all(|v| v.is_finite())
                && r.limits
                    .is_none_or(|l| l.lower.is_finite() && l.upper.is_finite())
        })
}

fuzz_target!(|data: &[u8]| {
    let Ok(model) = UrdfModel::from_bytes(data) else {
        return;
    };
    // The default chain, and one to every leaf (bounded, so a wide tree stays fast).
    let mut tips: Vec<Option<String>> = vec![None];
    tips.extend(
        model
            .leaves()
            .into_iter()
            .take(4)
            .map(|l| Some(l.to_owned())),
    );
    for tip in tips {
        let Ok(chain) = model.chain(None, tip.as_deref()) else {
            continue;
        };
        let pose = chain.tip_pose();
        assert!(
            pose.translation.vector.iter().all(|v| v.is_finite()),
            "tip pose {pose:?}"
        );
        for convention in [Convention::Standard, Convention::Modified] {
            let Ok(ex) = dh_core::extract(chain.axes(), &pose, Tolerance::default(), convention)
            else {
                continue;
            };
            assert!(finite_table(&ex.table), "non-finite table {:?}", ex.table);
            assert!(ex.bound.position.is_finite() && ex.bound.orientation.is_finite());
            if let Ok(dev) = dh_core::compare(&ex.table, |q| chain.fk(q), 4, 0) {
                assert!(
                    dev.max_position_error.is_finite() && dev.max_orientation_error.is_finite(),
                    "non-finite deviation {dev:?}"
                );
            }
            for (lu, au) in [
                (LengthUnit::M, AngleUnit::Rad),
                (LengthUnit::Mm, AngleUnit::Deg),
            ] {
                let doc = SheetDoc::from_table(&ex.table, lu, au);
                for format in [Format::Text, Format::Csv, Format::Markdown] {
                    assert!(render_sheet(&doc, format).is_ok());
                }
                // What extract writes, the sheet reader reads.
                for format in [Format::Yaml, Format::Json] {
                    let text = render_sheet(&doc, format).expect("render");
                    if let Err(e) = Sheet::parse(&text, "out") {
                        panic!("extract's {format:?} does not read back: {e:#}\n{text}");
                    }
                }
            }
        }
    }
});
