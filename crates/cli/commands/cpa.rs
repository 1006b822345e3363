//! `urdf-dh cpa`: circle-point analysis of a measurement file in which one joint moves at a
//! time: the sweeps, a circle per joint, the axis lines, and the DH table the axes make (with
//! its base in the measuring device's frame), plus how the commanded joint motion compares with
//! the measured one.
//!
//! # Layout
//! The run is here; the JSON document's types are in `docs`, the comparison with a nominal
//! model in `compare`, the text report in `text` (re-exported here).

use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

use anyhow::Result;
use dh_calib::cpa::{analyse, CpaOptions, CpaResult, JointCpa};
use dh_calib::model::NEAR_PARALLEL;
use dh_core::{classify, Convention, DhTable, JointKind, Line, Tolerance};
use nalgebra::Isometry3;
use serde::Serialize;

use crate::error::{hinted, Outcome};
use crate::input::display_name;
use crate::measured::{header_joints, load_model, read_measurements, DataFile, DataUnits};
use crate::plot_motion::motion_svg;
use crate::render::{render_sheet, Format};
use crate::sheet::{PairDoc, SheetDoc, TolerancesDoc};
use crate::units::{AngleUnit, LengthUnit};

pub use dh_calib::cpa::{CPA_ANGULAR, CPA_LINEAR};

/// Output format of `cpa`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Default)]
pub enum CpaFormat {
    /// A readable report.
    #[default]
    Text,
    /// The sheet format with a `cpa` section, YAML.
    Yaml,
    /// The same, JSON.
    Json,
}

/// Everything `cpa` needs.
#[derive(Clone, Debug)]
pub struct CpaArgs {
    /// The measurement file.
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
    /// Output format.
    pub format: CpaFormat,
    /// Where to write the chart of each joint's measured against commanded motion (SVG), `-`
    /// for standard output (the report then goes to standard error).
    pub plot: Option<String>,
}

// The submodules import what they use through `use super::*`: the imports above and each
// other's items, re-exported here.
mod docs;
pub use docs::*;
mod compare;
use compare::*;
mod text;
use text::*;

/// Runs `cpa`.
///
/// # Errors
/// Bad model or data (naming the file, line and column), a joint without a sweep, sweeps that
/// fit no circle.
pub fn cpa(args: &CpaArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    let data_name = display_name(&args.data);
    let model = match &args.model {
        Some(m) => {
            let model = load_model(
                m,
                args.base.as_deref(),
                args.tip.as_deref(),
                args.convention,
            )?;
            for w in &model.warnings {
                writeln!(err, "urdf-dh: warning: {w}")?;
            }
            Some(model)
        }
        None => None,
    };
    let file = DataFile::read(&args.data)?;
    let (joints, prismatic, convention) = match &model {
        Some(m) => (m.measured_joints(), m.prismatic(), m.table.convention),
        None => (header_joints(&file)?, Vec::new(), args.convention),
    };
    let data = read_measurements(&file, &joints, &prismatic, args.units, err)?;
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
            let qs: Vec<Vec<f64>> = data.samples.iter().map(|s| s.q.clone()).collect();
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
    let report = match args.format {
        CpaFormat::Text => text(&doc, &sheet),
        CpaFormat::Yaml | CpaFormat::Json => {
            sheet.cpa = Some(serde_yaml::to_value(&doc)?);
            let format = if args.format == CpaFormat::Yaml {
                Format::Yaml
            } else {
                Format::Json
            };
            render_sheet(&sheet, format)?
        }
    };
    // The chart is written (or piped) before the report is printed: a chart that cannot be
    // written leaves no report claiming success. `--plot -`: the chart alone on standard output.
    if let Some(path) = &args.plot {
        let svg = motion_svg(
            &format!("circle-point analysis of {data_name}: measured against commanded motion"),
            &result.joints,
        );
        crate::output::write_all_or_stdout(&[(Path::new(path), svg.as_bytes())], out)?;
    }
    let report_sink: &mut dyn Write = if crate::output::any_stdout([args.plot.as_deref()]) {
        err
    } else {
        out
    };
    report_sink.write_all(report.as_bytes())?;
    Ok(Outcome::Pass)
}

/// Command-line arguments of `cpa`.
#[derive(Debug, clap::Args)]
pub struct CpaCli {
    /// The measurements (canonical CSV), one joint swept at a time; - for standard input.
    data: String,
    /// A model for the joint names and kinds, and nominal axes to compare with.
    #[arg(long, value_name = "MODEL")]
    model: Option<String>,
    /// Base link of a URDF model.
    #[arg(long)]
    base: Option<String>,
    /// Tip link of a URDF model.
    #[arg(long)]
    tip: Option<String>,
    /// DH convention of the extracted table (a sheet model brings its own).
    #[arg(long, value_enum, default_value_t = crate::sheet::ConventionDoc::Standard)]
    convention: crate::sheet::ConventionDoc,
    /// Measured axes whose common normal is shorter than this intersect (metres).
    #[arg(long, value_name = "M", default_value_t = CPA_LINEAR, value_parser = crate::guard::linear_tol)]
    linear_tol: f64,
    /// Measured axes this close to parallel are parallel (radians).
    #[arg(long, value_name = "RAD", default_value_t = CPA_ANGULAR, value_parser = crate::guard::angular_tol)]
    angular_tol: f64,
    /// Length unit of the measurement file (the output is in metres).
    #[arg(long, value_enum, default_value_t = LengthUnit::M)]
    length_unit: LengthUnit,
    /// Angle unit of the measurement file (the output is in radians).
    #[arg(long, value_enum, default_value_t = AngleUnit::Rad)]
    angle_unit: AngleUnit,
    /// Output format.
    #[arg(long, value_enum, default_value_t = CpaFormat::Text)]
    format: CpaFormat,
    /// Write a chart of each joint's measured minus commanded motion against the commanded
    /// value, with the fitted trend (SVG; - for standard output, the report then on standard
    /// error).
    #[arg(long, value_name = "SVG")]
    plot: Option<String>,
}

impl CpaCli {
    /// The arguments of [`cpa`].
    ///
    /// # Errors
    /// A tolerance that is negative or not finite.
    pub fn into_args(self) -> Result<CpaArgs> {
        Ok(CpaArgs {
            tolerance: Tolerance::new(self.linear_tol, self.angular_tol)
                .map_err(|e| anyhow::anyhow!("{e}"))?,
            data: self.data,
            model: self.model,
            base: self.base,
            tip: self.tip,
            convention: self.convention.into(),
            units: DataUnits {
                length: self.length_unit,
                angle: self.angle_unit,
            },
            format: self.format,
            plot: self.plot,
        })
    }
}
