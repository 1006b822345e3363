//! Circle-point analysis as `urdf-dh cpa` runs it, for any Rust caller: a measurement file in
//! which one joint moves at a time -> the sweeps, a circle per joint, the axis lines, and the
//! DH table the axes make (its base in the measuring device's frame), how the commanded joint
//! motion compares with the measured one, and (with a nominal model) how the measured axes
//! compare with the model's. The analysis itself is `dh_calib::cpa`.
//!
//! [`cpa`] returns a [`CpaReport`]: the table as a sheet ([`CpaReport::sheet`], metres and
//! radians, `base_link: device`) and the report's document ([`CpaDoc`], serialisable; the
//! sheet's `cpa` section in YAML and JSON output).
//!
//! # Layout
//! The run is here; the document's types are in `docs`, the comparison with a nominal model and
//! the proof against the measured axes in `compare` (re-exported here).

use std::io::Write;

use anyhow::Result;
use dh_calib::cpa::{analyse, CpaOptions, CpaResult};
use dh_calib::model::NEAR_PARALLEL;
use dh_core::{classify, Convention, DhTable, JointKind, Line, Tolerance};
use nalgebra::Isometry3;
use serde::Serialize;

use crate::error::hinted;
use crate::input::display_name;
use crate::measured::{DataFile, DataSource, DataUnits};
use crate::model::load_model_noting;
use crate::sheet::{PairDoc, SheetDoc, TolerancesDoc};
use crate::units::{AngleUnit, LengthUnit};

// The submodules import what they use through `use super::*`: the imports above and each
// other's items, re-exported here.
mod docs;
pub use docs::*;

// The analysis's own types a face shows (`dh_calib::cpa`'s): each joint's sweeps and circle,
// its commanded against measured motion, and the default tolerances of `cpa`.
pub use dh_calib::cpa::{
    JointCpa, LinearTrend, MotionCheck, PoseResidual, SweepScreen, CPA_ANGULAR, CPA_LINEAR,
};
mod compare;
use compare::*;

/// Everything a circle-point analysis needs.
#[derive(Clone, Debug)]
pub struct CpaRequest {
    /// The measurement file (`-` for standard input), or the name of [`CpaRequest::given`].
    pub data: String,
    /// A model giving the joint names, kinds and convention, and the nominal axes to compare.
    pub model: Option<String>,
    /// Base link of a URDF model.
    pub base: Option<String>,
    /// Tip link of a URDF model.
    pub tip: Option<String>,
    /// Convention of the extracted table (without a sheet model).
    pub convention: Convention,
    /// Tolerance of the DH extraction from the measured axes.
    pub tolerance: Tolerance,
    /// Units of the measurement file; the output is in metres and radians.
    pub units: DataUnits,
    /// Measurements handed over as arrays instead of the file `data` (which then only names
    /// them in messages); `None` reads the file.
    pub given: Option<dh_calib::csv::SampleArrays>,
}

/// A finished circle-point analysis.
#[derive(Clone, Debug)]
pub struct CpaReport {
    /// The analysis (sweeps, circles, axes, the extraction).
    pub result: CpaResult,
    /// The extracted table as a sheet (metres, radians; pairs, tolerances, warnings).
    pub sheet: SheetDoc,
    /// The report's document.
    pub doc: CpaDoc,
    /// The measurements analysed (SI units), for the report page's per-point plots.
    pub data: dh_calib::data::Measurements,
}

impl CpaReport {
    /// The sheet with the report as its `cpa` section (what `cpa --format yaml|json` writes).
    ///
    /// # Errors
    /// Serialisation failures.
    pub fn sheet_with_report(&self) -> Result<SheetDoc> {
        let mut sheet = self.sheet.clone();
        sheet.cpa = Some(serde_yaml::to_value(&self.doc)?);
        Ok(sheet)
    }
}

/// Runs the circle-point analysis of `args`; the model's warnings go to `err`.
///
/// # Errors
/// Bad model or data (naming the file, line and column), a joint without a sweep, sweeps that
/// fit no circle.
pub fn cpa(args: &CpaRequest, err: &mut dyn Write) -> Result<CpaReport> {
    let data_name = display_name(&args.data);
    let model = args
        .model
        .as_deref()
        .map(|m| {
            load_model_noting(
                m,
                args.base.as_deref(),
                args.tip.as_deref(),
                args.convention,
                err,
            )
        })
        .transpose()?;
    let (prismatic, convention) = match &model {
        Some(m) => (m.prismatic(), m.table.convention),
        None => (Vec::new(), args.convention),
    };
    let source = match &args.given {
        None => DataSource::File(DataFile::read(&args.data)?),
        Some(arrays) => DataSource::Arrays(arrays, data_name.clone()),
    };
    let joints = source.joints(model.as_ref())?;
    let data = source.read(&joints, &prismatic, args.units, err)?;
    let options = CpaOptions {
        prismatic,
        convention,
        tolerance: args.tolerance,
        ..CpaOptions::default()
    };
    let result = analyse(&data, &options).map_err(|e| {
        hinted(
            format!("{data_name}: circle-point analysis failed: {e}"),
            "the data must sweep each joint in turn (at least 4 poses per joint, the others still)",
        )
    })?;
    let pairs = match &model {
        Some(m) => pair_comparison(&m.table, &result)?,
        None => Vec::new(),
    };
    // The unit options say what the file holds; the output is in metres and radians (`urdf-dh
    // convert` gives other units).
    let (lu, au) = (LengthUnit::M, AngleUnit::Rad);
    let table = &result.extraction.table;
    let mut sheet = SheetDoc::from_table(table, lu, au);
    sheet.robot = Some(format!("circle-point analysis of {data_name}"));
    sheet.source = model
        .as_ref()
        .map(|m| format!("joint names and kinds from {}", m.origin));
    sheet.base_link = Some("device".into());
    sheet.tip_link = Some("tip".into());
    sheet.pairs = Some(
        result
            .extraction
            .pairs
            .iter()
            .map(|p| PairDoc {
                joints: [
                    table.rows[p.first].name.clone(),
                    table.rows[p.first + 1].name.clone(),
                ],
                relation: p.geometry.relation.to_string(),
                angle: au.from_si_unwrapped(p.geometry.angle),
                distance: lu.from_si(p.geometry.distance),
            })
            .collect(),
    );
    sheet.tolerances = Some(TolerancesDoc {
        linear: result.extraction.tolerance.linear,
        angular: result.extraction.tolerance.angular,
    });
    sheet.warnings = Some(
        result
            .extraction
            .warnings
            .iter()
            .map(|w| w.to_string())
            .collect(),
    );
    let doc = CpaDoc {
        data: data_name.clone(),
        units: ["m", "rad"],
        samples: data.samples.len(),
        targets: data.targets.clone(),
        sweeps: result
            .sweeps
            .iter()
            .map(|s| SweepDoc {
                joint: s.name.clone(),
                coupled: s
                    .coupled
                    .iter()
                    .map(|c| CoupledDoc {
                        joint: c.name.clone(),
                        ratio: c.ratio,
                    })
                    .collect(),
                poses: s.poses,
                samples: s.samples.len(),
                span: s.span,
                lines: [s.lines.0, s.lines.1],
                used: s.used,
            })
            .collect(),
        joints: result.joints.iter().map(joint_doc).collect(),
        pairs,
        proof: {
            let qs: Vec<Vec<f64>> = data.samples.iter().map(|s| s.q.to_vec()).collect();
            let snapped = dh_core::extract(
                &result.axes,
                &result.tip,
                options.tolerance,
                options.convention,
            )
            .map_or_else(|_| table.clone(), |e| e.table);
            AxesProofDoc {
                poses: qs.len(),
                written: against_axes(table, &result, &qs),
                snapped: against_axes(&snapped, &result, &qs),
            }
        },
    };
    Ok(CpaReport {
        result,
        sheet,
        doc,
        data,
    })
}
