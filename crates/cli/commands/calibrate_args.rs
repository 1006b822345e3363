//! The arguments of `urdf-dh calibrate`: the command line as clap reads it ([`CalibrateCli`])
//! and the settings [`crate::commands::calibrate::calibrate`] runs with ([`CalibrateArgs`]: the
//! library's [`CalibrationRequest`], the output format, the chart, the progress line).
//!
//! Shared by `calibrate`, its contact rendering (`crate::commands::sockets`) and its tree
//! rendering (`crate::commands::calibrate_tree`), so that none of them imports another for them.

use dh_workflows::fit::EffectsChoice;
use dh_workflows::measured::DataUnits;
use dh_workflows::sheet::ConventionDoc;
use dh_workflows::units::{AngleUnit, LengthUnit};

pub use dh_workflows::calibration::{CalibrationRequest, GivenData};

/// Output format of `calibrate`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Default)]
pub enum CalibrateFormat {
    /// A readable report.
    #[default]
    Text,
    /// JSON, metres and radians.
    Json,
}

/// Everything `calibrate` needs: the library's request and how the command line renders it.
#[derive(Clone, Debug)]
pub struct CalibrateArgs {
    /// The calibration itself ([`dh_workflows::calibration`]).
    pub request: CalibrationRequest,
    /// Output format.
    pub format: CalibrateFormat,
    /// Where to write the residual chart (SVG).
    pub plot: Option<String>,
    /// Where to write the report as one self-contained HTML page.
    pub report: Option<String>,
    /// No progress line on standard error.
    pub quiet: bool,
    /// The command line as the run was given it (the program as `urdf-dh`), for the report
    /// page's provenance; empty for a caller that gives none.
    pub command_line: Vec<String>,
}

/// Command-line arguments of `calibrate`.
#[derive(Debug, clap::Args)]
pub struct CalibrateCli {
    /// The nominal model: a URDF (with --base/--tip), a DH sheet, or a tree sheet (a sheet
    /// with `branches`; targets ride on the branch they name) [default: circle-point analysis
    /// of the data].
    #[arg(long, value_name = "MODEL")]
    model: Option<String>,
    /// Base link of a URDF chain [default: the root link].
    #[arg(long)]
    base: Option<String>,
    /// Tip link of a URDF chain [default: the end of the longest run of moving joints].
    #[arg(long)]
    tip: Option<String>,
    #[command(flatten)]
    pub xacro: crate::xacro_flags::XacroCli,
    /// DH convention for a URDF model or the CPA start.
    #[arg(long, value_enum, default_value_t = ConventionDoc::Standard)]
    convention: ConventionDoc,
    /// The measurements (canonical CSV; see `urdf-dh import` for published layouts).
    #[arg(long, value_name = "D.csv")]
    data: String,
    /// Held-out measurements to validate on [default: the data's own `set` column, else
    /// k-fold cross-validation over poses].
    #[arg(long, value_name = "V.csv")]
    validate: Option<String>,
    /// Effects to estimate after the geometric step: none, auto, or labels such as
    /// gear_ratio:joint_2,gear_ratio:joint_3. Labels: gear_ratio:J, gear_harmonic:J (once per
    /// turn), gear_harmonic2:J (twice), gear_harmonic:J:2 (both), coupling:J:K, scale,
    /// parallel_tilt:J, backlash_direction:J (after the direction of J's last motion, in the
    /// file's pose order), drift (lengths growing with the pose order), gravity_sag:J (the tip
    /// sinking along gravity with the cube of its lever arm about J), and with link masses
    /// compliance:J, lateral_compliance:J, backlash:J.
    #[arg(long, value_name = "none|auto|LIST", default_value = "none")]
    effects: EffectsChoice,
    /// Use only these targets of the data (comma-separated names) [default: all].
    #[arg(long, value_name = "NAMES", value_delimiter = ',')]
    targets: Vec<String>,
    /// Known measurement noise per axis, in the length unit [default: the data's sigma column
    /// or the scatter of repeated poses].
    #[arg(long, value_name = "SIGMA", value_parser = crate::guard::sigma)]
    sigma: Option<f64>,
    /// Folds of the cross-validation.
    #[arg(long, value_name = "K", default_value_t = dh_workflows::calibration::DEFAULT_FOLDS, value_parser = crate::guard::folds)]
    folds: usize,
    /// Length unit of the measurement files and --sigma (reports are in metres).
    #[arg(long, value_enum, default_value_t = LengthUnit::M)]
    length_unit: LengthUnit,
    /// Angle unit of the measurement files (reports are in radians).
    #[arg(long, value_enum, default_value_t = AngleUnit::Rad)]
    angle_unit: AngleUnit,
    /// Output format (JSON: metres and radians).
    #[arg(long, value_enum, default_value_t = CalibrateFormat::Text)]
    format: CalibrateFormat,
    /// Write the calibrated model here: a DH sheet (.yaml, .json) or a URDF (.urdf); `-` writes
    /// a YAML sheet to standard output and the report to standard error.
    #[arg(long, value_name = "FILE", value_parser = crate::guard::model_output)]
    out: Option<String>,
    /// Write an SVG chart of the residuals per pose, before and after (`-`: standard output,
    /// the report then goes to standard error).
    #[arg(long, value_name = "FILE.svg", value_parser = crate::guard::svg_output)]
    plot: Option<String>,
    /// Write the report as one self-contained HTML page: the steps, residual plots, outliers,
    /// the diagnosis, parameters with standard errors and correlations, the verdict and the
    /// inputs' provenance (SHA-256); inline SVG, no script, opens offline.
    #[arg(long, value_name = "FILE.html", value_parser = crate::guard::html_output)]
    report: Option<String>,
    /// Link masses for the compliance effects: YAML with `links: [{joint, mass, com}]` (kg,
    /// m; `com_frame: base_at_zero` or `dh`) and optional `payloads`, `gravity` [default: a
    /// URDF model's inertials, a tree sheet's own `inertials`; none for a sheet, and
    /// compliance is skipped].
    #[arg(long, value_name = "FILE")]
    inertials: Option<String>,
    /// Gravity in the robot's base link frame, m/s² [default: 0,0,-9.80665]: the gravity
    /// effects' and the verdict's gravity structure tests' direction.
    #[arg(
        long,
        value_name = "X,Y,Z",
        value_delimiter = ',',
        allow_hyphen_values = true,
        value_parser = crate::guard::gravity
    )]
    gravity: Option<Vec<f64>>,
    /// A payload at the tip: mass in kg, then its centre in the tip frame in metres.
    #[arg(
        long,
        value_name = "M,X,Y,Z",
        value_delimiter = ',',
        allow_hyphen_values = true,
        value_parser = crate::guard::payload
    )]
    payload: Option<Vec<f64>>,
    /// Most effects --effects auto adds before it stops (a guard; the run's notes say when it
    /// stopped the selection).
    #[arg(long, value_name = "N", default_value_t = dh_workflows::calibration::DEFAULT_MAX_EFFECTS, value_parser = crate::guard::max_effects)]
    max_effects: usize,
    /// Significance level of every test of the diagnosis: an effect enters when its F test
    /// passes at ALPHA divided by the number of candidates and its held-out gain is
    /// significant at ALPHA; the final verdict tests at ALPHA. Higher takes effects on weaker evidence (small sets).
    #[arg(long, value_name = "ALPHA", default_value_t = 0.01, value_parser = crate::guard::alpha)]
    alpha: f64,
    /// Fit every point: the outliers (points beyond a Bonferroni bound over the standardised
    /// residuals, see dh_calib::outliers) are still named but not left out.
    #[arg(long)]
    keep_outliers: bool,
    /// No progress line: a terminal otherwise shows what a run over a second is doing, and
    /// for how long, on standard error (never in pipes, logs or the report).
    #[arg(long, short)]
    quiet: bool,
}

impl CalibrateCli {
    /// The arguments of [`calibrate`](crate::commands::calibrate::calibrate).
    pub fn into_args(self) -> CalibrateArgs {
        CalibrateArgs {
            request: CalibrationRequest {
                model: self.model,
                base: self.base,
                tip: self.tip,
                convention: self.convention.into(),
                data: self.data,
                validate: self.validate,
                units: DataUnits {
                    length: self.length_unit,
                    angle: self.angle_unit,
                },
                effects: self.effects,
                targets: self.targets,
                sigma: self.sigma,
                folds: self.folds,
                out: self.out,
                inertials: self.inertials,
                gravity: self.gravity,
                payload: self.payload,
                max_effects: self.max_effects,
                alpha: self.alpha,
                keep_outliers: self.keep_outliers,
                given: None,
            },
            format: self.format,
            plot: self.plot,
            report: self.report,
            command_line: Vec::new(),
            quiet: self.quiet,
        }
    }
}
