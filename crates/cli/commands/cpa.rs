//! `urdf-dh cpa`: circle-point analysis of a measurement file in which one joint moves at a
//! time: the sweeps, a circle per joint, the axis lines, and the DH table the axes make (with
//! its base in the measuring device's frame), plus how the commanded joint motion compares with
//! the measured one.
//!
//! # Layout
//! The analysis, its document and the comparison with a nominal model are the library's
//! [`dh_workflows::cpa_report`] (re-exported here); the text report is in `text`, the chart in
//! `crate::plot_motion`.

use std::io::Write;
use std::path::Path;

use anyhow::Result;
use dh_workflows::cpa_report::cpa as run;
pub use dh_workflows::cpa_report::*;
use dh_workflows::geometry::Tolerance;
use dh_workflows::input::display_name;
use dh_workflows::render::{render_sheet, Format};
use dh_workflows::units::{AngleUnit, LengthUnit};

use crate::error::Outcome;
use crate::plot_motion::motion_svg;

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

/// Everything `cpa` needs: the library's request and how the command line renders it.
#[derive(Clone, Debug)]
pub struct CpaArgs {
    /// The analysis ([`dh_workflows::cpa_report`]).
    pub request: CpaRequest,
    /// Output format.
    pub format: CpaFormat,
    /// Where to write the chart of each joint's measured against commanded motion (SVG), `-`
    /// for standard output (the report then goes to standard error).
    pub plot: Option<String>,
    /// Where to write the report as one self-contained HTML page.
    pub report: Option<String>,
    /// The command line as the run was given it (the program as `urdf-dh`), for the report
    /// page's provenance; empty for a caller that gives none.
    pub command_line: Vec<String>,
}

mod text;
use text::*;

/// Runs `cpa`.
///
/// # Errors
/// Bad model or data (naming the file, line and column), a joint without a sweep, sweeps that
/// fit no circle.
pub fn cpa(args: &CpaArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    let data_name = display_name(&args.request.data);
    if let Some(page) = &args.report {
        let inputs: Vec<(&str, &str)> = [
            ("DATA", Some(args.request.data.as_str())),
            ("--model", args.request.model.as_deref()),
        ]
        .into_iter()
        .filter_map(|(o, p)| Some((o, p?)))
        .collect();
        let mut outputs = vec![("--report", page.as_str())];
        outputs.extend(args.plot.iter().map(|p| ("--plot", p.as_str())));
        dh_workflows::output::check_destinations(&inputs, &outputs)?;
    }
    let r = run(&args.request, err)?;
    let report = match args.format {
        CpaFormat::Text => text(&r.doc, &r.sheet),
        CpaFormat::Yaml => render_sheet(&r.sheet_with_report()?, Format::Yaml)?,
        CpaFormat::Json => render_sheet(&r.sheet_with_report()?, Format::Json)?,
    };
    // The chart is written (or piped) before the report is printed: a chart that cannot be
    // written leaves no report claiming success. `--plot -`: the chart alone on standard output.
    // The chart and the page are written together, all or nothing.
    let mut files: Vec<(&Path, String)> = Vec::new();
    if let Some(path) = &args.plot {
        let svg = motion_svg(
            &format!("circle-point analysis of {data_name}: measured against commanded motion"),
            &r.result.joints,
        );
        files.push((Path::new(path), svg));
    }
    if let Some(path) = &args.report {
        let inputs: Vec<(&str, &str)> = [
            (
                "DATA",
                (args.request.given.is_none()).then_some(args.request.data.as_str()),
            ),
            ("--model", args.request.model.as_deref()),
        ]
        .into_iter()
        .filter_map(|(o, p)| Some((o, p?)))
        .collect();
        let provenance = crate::commands::report_provenance(&args.command_line, &inputs);
        files.push((
            Path::new(path),
            dh_workflows::report_html::cpa_page(&r, &provenance),
        ));
    }
    if !files.is_empty() {
        let files: Vec<(&Path, &[u8])> = files.iter().map(|(p, b)| (*p, b.as_bytes())).collect();
        dh_workflows::output::write_all_or_stdout(&files, out)?;
    }
    let report_sink: &mut dyn Write =
        if dh_workflows::output::any_stdout([args.plot.as_deref(), args.report.as_deref()]) {
            err
        } else {
            out
        };
    report_sink.write_all(report.as_bytes())?;
    // Points left out are named in the report; a sweep whose screen left out too many (or did
    // not settle) has no trustworthy axis.
    let unsound: Vec<&str> = r
        .result
        .joints
        .iter()
        .filter(|j| !j.screen.sound())
        .map(|j| j.name.as_str())
        .collect();
    if unsound.is_empty() {
        Ok(Outcome::Pass)
    } else {
        writeln!(
            err,
            "urdf-dh: the fits of {} left out more than a quarter of their points: their axes are not to be trusted",
            unsound
                .iter()
                .map(|n| format!("'{}'", crate::guard::escape(n)))
                .collect::<Vec<_>>()
                .join(", ")
        )?;
        Ok(Outcome::Differs)
    }
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
    #[command(flatten)]
    pub xacro: crate::xacro_flags::XacroCli,
    /// DH convention of the extracted table (a sheet model brings its own).
    #[arg(long, value_enum, default_value_t = dh_workflows::sheet::ConventionDoc::Standard)]
    convention: dh_workflows::sheet::ConventionDoc,
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
    #[arg(long, value_name = "SVG", value_parser = crate::guard::svg_output)]
    plot: Option<String>,
    /// Write the report as one self-contained HTML page: the sweeps, each joint's circles and
    /// axis, per-point residual and motion plots, the points left out, the DH table, the proof
    /// and the inputs' provenance (SHA-256); inline SVG, no script, opens offline.
    #[arg(long, value_name = "FILE.html", value_parser = crate::guard::html_output)]
    report: Option<String>,
}

impl CpaCli {
    /// The arguments of [`cpa`].
    ///
    /// # Errors
    /// A tolerance that is negative or not finite.
    pub fn into_args(self) -> Result<CpaArgs> {
        Ok(CpaArgs {
            request: CpaRequest {
                tolerance: Tolerance::new(self.linear_tol, self.angular_tol)
                    .map_err(|e| anyhow::anyhow!("{e}"))?,
                data: self.data,
                model: self.model,
                base: self.base,
                tip: self.tip,
                convention: self.convention.into(),
                units: dh_workflows::measured::DataUnits {
                    length: self.length_unit,
                    angle: self.angle_unit,
                },
                given: None,
            },
            format: self.format,
            plot: self.plot,
            report: self.report,
            command_line: Vec::new(),
        })
    }
}
