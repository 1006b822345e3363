//! The proof on the artefact: `calibrate --out` reads back the bytes it is about to write, with
//! the readers every other command uses, and checks that they predict what the fitted model
//! predicts, and that no written length is beyond the robot's size plus a metre.
//!
//! Predictions are the measured targets' positions in the device frame at every measured pose:
//! `p = T_device_base · FK_written(q) · t_k` against `T_device_base · FK_fitted(q) · t_k`, with
//! `FK_fitted` the calibrated table the fit produced (its Hayati tilts in their rows; effects
//! are no part of a DH table and are listed in the sheet's `effects` section instead).

use anyhow::{Context, Result};
use dh_core::DhTable;
use nalgebra::{Isometry3, Point3, Vector3};
use urdf_axes::UrdfModel;

use crate::sheet::Sheet;

/// Largest deviation (metres) between the read-back artefact's predictions and the fitted
/// model's. Sheets print values to a picometre and 1e-12 rad, URDFs to 1e-15: over a chain of
/// a few dozen values with lever arms of a few metres the rounding stays below 1e-10 m, so a
/// nanometre leaves a margin of ten and still catches any real loss (a dropped tilt of 1e-6 rad
/// at 1 m is a thousand times larger).
pub const WRITTEN_TOLERANCE: f64 = 1e-9;

/// Margin (metres) beyond the robot's size that a written length may reach: a calibrated link
/// is the nominal one plus millimetres, never a common normal kilometres away.
pub const LENGTH_MARGIN: f64 = 1.0;

/// Forward kinematics of a read-back artefact.
type Fk = Box<dyn Fn(&[f64]) -> Result<Isometry3<f64>>>;

/// What the read-back found (metres): the library's document (`dh_calib::pipeline`), which a
/// report carries as its `written` field.
pub use dh_calib::pipeline::WrittenDoc;

/// The measured poses and targets the proof predicts at.
pub struct Predictions<'a> {
    /// Joint values per sample, in the table's row order.
    pub q: &'a [Vec<f64>],
    /// Target index per sample.
    pub target: &'a [usize],
    /// Estimated targets in the tip frame (metres).
    pub targets: &'a [Vector3<f64>],
    /// Estimated `T_device_base`.
    pub device: Isometry3<f64>,
}

/// Reads back `text` (the artefact for `path`: a URDF for `.urdf`, else a sheet) and compares
/// its predictions with `fitted`'s; `nominal_size` is the size of the model the fit started
/// from (see [`DhTable::size`]), `links` the URDF's base and tip link names.
///
/// # Errors
/// The artefact does not read back (a defect of the writer, reported as such), or has the
/// wrong joint count.
pub fn prove(
    path: &str,
    text: &str,
    fitted: &DhTable,
    nominal_size: f64,
    links: (&str, &str),
    at: &Predictions<'_>,
) -> Result<WrittenDoc> {
    let name = crate::text::output_name(path);
    let lower = path.to_ascii_lowercase();
    let back = |q: &[f64]| -> Result<Isometry3<f64>> { Ok(fitted.fk(q)?) };
    let (written_fk, max_length): (Fk, f64) = if lower.ends_with(".urdf") {
        let model = UrdfModel::from_bytes(text.as_bytes())
            .with_context(|| format!("{name}: the written URDF does not read back"))?;
        let chain = model
            .chain(Some(links.0), Some(links.1))
            .with_context(|| format!("{name}: the written URDF's chain does not read back"))?;
        (
            Box::new(move |q: &[f64]| Ok(chain.try_fk(q)?)),
            longest_origin(text),
        )
    } else {
        let sheet = Sheet::parse(text, &name)
            .with_context(|| format!("{name}: the written sheet does not read back"))?;
        let t = sheet.table;
        let longest = t
            .rows
            .iter()
            .flat_map(|r| [r.a.abs(), r.d.abs()])
            .chain([
                t.base.translation.vector.norm(),
                t.tool.translation.vector.norm(),
            ])
            .fold(0.0, f64::max);
        (Box::new(move |q: &[f64]| Ok(t.fk(q)?)), longest)
    };
    let mut max_deviation: f64 = 0.0;
    for (q, &k) in at.q.iter().zip(at.target) {
        let t = Point3::from(at.targets.get(k).copied().unwrap_or_default());
        let want = at.device * back(q)? * t;
        let got = at.device * written_fk(q)? * t;
        let d = (want - got).norm();
        // NaN must fail, not pass.
        max_deviation = if d.is_nan() {
            f64::INFINITY
        } else {
            max_deviation.max(d)
        };
    }
    let length_bound = nominal_size + LENGTH_MARGIN;
    Ok(WrittenDoc {
        path: name,
        points: at.q.len(),
        max_deviation,
        bound: WRITTEN_TOLERANCE,
        max_length,
        length_bound,
        passed: max_deviation <= WRITTEN_TOLERANCE && max_length <= length_bound,
    })
}

/// The longest `xyz` offset (metres) of any `<origin>` in a URDF's text; an unreadable one
/// counts as infinitely long.
fn longest_origin(text: &str) -> f64 {
    let mut longest: f64 = 0.0;
    for element in text.split("<origin").skip(1) {
        let attributes = element.split('>').next().unwrap_or_default();
        let Some((_, xyz)) = attributes.split_once("xyz=\"") else {
            continue;
        };
        let values: Vec<f64> = xyz
            .split('"')
            .next()
            .unwrap_or_default()
            .split_whitespace()
            .map(|v| v.parse().unwrap_or(f64::INFINITY))
            .collect();
        longest = longest.max(values.iter().map(|v| v * v).sum::<f64>().sqrt());
    }
    longest
}

/// The report's line for `w`.
pub fn line(w: &WrittenDoc) -> String {
    format!(
        "written: {} read back: {} predicted points, max deviation from the fitted model {:.1e} m (bound {:.0e}); longest written length {:.6} m (bound {:.6}): {}",
        w.path,
        w.points,
        w.max_deviation,
        w.bound,
        w.max_length,
        w.length_bound,
        if w.passed {
            "PASS"
        } else {
            "FAIL, not written"
        }
    )
}
