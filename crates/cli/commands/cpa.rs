//! `urdf-dh cpa`: circle-point analysis of a measurement file in which one joint moves at a
//! time: the sweeps, a circle per joint, the axis lines, and the DH table the axes make (with
//! its base in the measuring device's frame), plus how the commanded joint motion compares with
//! the measured one.

use std::fmt::Write as _;
use std::io::Write;

use anyhow::Result;
use dh_calib::cpa::{analyse, CpaOptions, CpaResult, JointCpa};
use dh_calib::model::NEAR_PARALLEL;
use dh_core::{classify, Convention, DhTable, JointKind, Line, Tolerance};
use nalgebra::Isometry3;
use serde::Serialize;

use crate::error::{hinted, Outcome};
use crate::input::display_name;
use crate::measured::{header_joints, load_model, read_measurements, DataFile, DataUnits};
use crate::render::{render_sheet, Format};
use crate::sheet::{PairDoc, SheetDoc, TolerancesDoc};
use crate::units::{AngleUnit, LengthUnit};

/// Default linear tolerance of the extraction from measured axes: 0.1 mm. Measured axes never
/// intersect exactly; a laser tracker's axis lines scatter by tens of micrometres.
pub const CPA_LINEAR: f64 = 1e-4;
/// Default angular tolerance of the extraction from measured axes: 1 mrad (0.057 degrees).
/// Measured axes are never exactly parallel; without snapping, a pair a fraction of a milliradian
/// from parallel gives a common normal kilometres away. The snap's cost is in the warnings, and
/// `calibrate` estimates the remaining tilt (Hayati-Mirmirani).
pub const CPA_ANGULAR: f64 = 1e-3;

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
}

/// A joint that moved with the sweep's lead joint.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CoupledDoc {
    /// Joint name.
    pub joint: String,
    /// Its change per unit change of the lead joint.
    pub ratio: f64,
}

/// One sweep.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SweepDoc {
    /// The moving joint.
    pub joint: String,
    /// Joints moving with it in fixed proportion.
    pub coupled: Vec<CoupledDoc>,
    /// Distinct poses.
    pub poses: usize,
    /// Samples.
    pub samples: usize,
    /// Commanded span (radians or metres).
    pub span: f64,
    /// First and last line in the file.
    pub lines: [usize; 2],
    /// Whether this sweep defines the joint's axis.
    pub used: bool,
}

/// One target's own circle in a joint's sweep.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TargetCircleDoc {
    /// Target name.
    pub name: String,
    /// Points.
    pub points: usize,
    /// Radius (metres); absent for a prismatic joint.
    pub radius: Option<f64>,
    /// RMS distance from its own circle (or line), metres.
    pub path_rms: f64,
    /// RMS distance from its own plane (metres).
    pub plane_rms: Option<f64>,
    /// Distance of its centre from the common axis (metres).
    pub axis_offset: f64,
    /// Angle of its plane normal from the common axis (radians).
    pub axis_tilt: f64,
}

/// Commanded against measured motion.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MotionDoc {
    /// RMS of measured minus commanded (radians or metres), mean removed.
    pub rms: f64,
    /// Linear trend: measured = (1 + slope) commanded.
    pub slope: Option<f64>,
    /// RMS left after the linear trend.
    pub linear_rms: Option<f64>,
    /// Once-per-turn amplitude (radians).
    pub sinusoid_amplitude: Option<f64>,
    /// RMS left after the sinusoid.
    pub sinusoid_rms: Option<f64>,
    /// Per pose: commanded value and residual.
    pub poses: Vec<[f64; 2]>,
}

/// The axis line at the sweep's configuration (device frame).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AxisDoc {
    /// The point of the line nearest the device origin (metres).
    pub point: [f64; 3],
    /// Unit direction, the joint's positive sense.
    pub direction: [f64; 3],
}

/// What the analysis found about one joint.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct JointCpaDoc {
    /// Joint name.
    pub name: String,
    /// `revolute` or `prismatic`.
    pub kind: &'static str,
    /// Poses of the sweep used.
    pub poses: usize,
    /// Points fitted.
    pub points: usize,
    /// Largest target radius (metres).
    pub radius: Option<f64>,
    /// RMS radial distance from the circles about the common axis (metres).
    pub circle_rms: f64,
    /// RMS distance from the circles' planes (metres).
    pub plane_rms: Option<f64>,
    /// Commanded span (radians or metres).
    pub span: f64,
    /// The fitted axis.
    pub axis: AxisDoc,
    /// Commanded against measured motion.
    pub motion: MotionDoc,
    /// The targets' own circles.
    pub targets: Vec<TargetCircleDoc>,
}

/// A consecutive pair of axes, nominal against measured.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PairComparisonDoc {
    /// The two joints.
    pub joints: [String; 2],
    /// Angle between the nominal axes (radians).
    pub nominal_angle: f64,
    /// Angle between the measured axes (radians).
    pub measured_angle: f64,
    /// Common-normal length of the nominal axes (metres); for a pair within 5 degrees of
    /// parallel the offset between the axes instead.
    pub nominal_distance: f64,
    /// The same for the measured axes (metres).
    pub measured_distance: f64,
}

/// The `cpa` section (metres and radians whatever the sheet's units).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CpaDoc {
    /// The data file.
    pub data: String,
    /// Always metres and radians.
    pub units: [&'static str; 2],
    /// Samples analysed.
    pub samples: usize,
    /// Target names.
    pub targets: Vec<String>,
    /// Every sweep found.
    pub sweeps: Vec<SweepDoc>,
    /// Per joint.
    pub joints: Vec<JointCpaDoc>,
    /// Nominal against measured axis pairs (with `--model`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub pairs: Vec<PairComparisonDoc>,
    /// The written table proved against the measured axes (see [`AxesProofDoc`]).
    pub proof: AxesProofDoc,
}

/// Forward kinematics of a table against the measured axes' own (the product of exponentials
/// of the zero-pose axis lines and the measured tip), at every measured joint vector: the
/// largest tip position and orientation differences (metres, radians), for the written table
/// and for the table that snaps every pair within the angular tolerance to parallel.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AxesProofDoc {
    /// Joint vectors compared.
    pub poses: usize,
    /// The written table: `[position, orientation]`.
    pub written: [f64; 2],
    /// The snapped table: `[position, orientation]`.
    pub snapped: [f64; 2],
}

/// `[max position, max orientation]` difference between `table`'s FK and the measured axes'.
fn against_axes(table: &DhTable, result: &CpaResult, qs: &[Vec<f64>]) -> [f64; 2] {
    let mut worst = [0.0f64; 2];
    for q in qs {
        let Ok(fk) = table.fk(q) else { continue };
        let mut t = Isometry3::identity();
        for (ax, &qi) in result.axes.iter().zip(q) {
            let e = ax.line.direction();
            t *= match ax.kind {
                JointKind::Revolute => {
                    let c = ax.line.point();
                    Isometry3::translation(c.x, c.y, c.z)
                        * Isometry3::rotation(e * qi)
                        * Isometry3::translation(-c.x, -c.y, -c.z)
                }
                JointKind::Prismatic => Isometry3::translation(e.x * qi, e.y * qi, e.z * qi),
            };
        }
        let (dp, dr) = dh_core::pose::pose_error(&fk, &(t * result.tip));
        worst = [worst[0].max(dp), worst[1].max(dr)];
    }
    worst
}

fn arr(v: &nalgebra::Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

fn joint_doc(j: &JointCpa) -> JointCpaDoc {
    let m = &j.motion;
    JointCpaDoc {
        name: j.name.clone(),
        kind: match j.kind {
            JointKind::Revolute => "revolute",
            JointKind::Prismatic => "prismatic",
        },
        poses: j.poses,
        points: j.points,
        radius: j.radius,
        circle_rms: j.circle_rms,
        plane_rms: j.plane_rms,
        span: j.span,
        axis: AxisDoc {
            point: arr(&j.axis.point()),
            direction: arr(&j.axis.direction()),
        },
        motion: MotionDoc {
            rms: m.rms,
            slope: m.linear.map(|l| l.slope),
            linear_rms: m.linear.map(|l| l.rms),
            sinusoid_amplitude: m.sinusoid.map(|s| s.amplitude),
            sinusoid_rms: m.sinusoid.map(|s| s.rms),
            poses: m.poses.iter().map(|p| [p.commanded, p.residual]).collect(),
        },
        targets: j
            .targets
            .iter()
            .map(|t| TargetCircleDoc {
                name: t.name.clone(),
                points: t.points,
                radius: t.radius,
                path_rms: t.path_rms,
                plane_rms: t.plane_rms,
                axis_offset: t.axis_offset,
                axis_tilt: t.axis_tilt,
            })
            .collect(),
    }
}

/// The joint axes of `table` at `q = 0`, in its base link frame.
fn nominal_axes(table: &DhTable) -> Result<Vec<Line>> {
    let zeros = vec![0.0; table.rows.len()];
    let frames = table.frames(&zeros)?;
    let offset = match table.convention {
        Convention::Standard => 0,
        Convention::Modified => 1,
    };
    (0..table.rows.len())
        .map(|i| {
            let f = frames
                .get(i + offset)
                .ok_or_else(|| anyhow::anyhow!("the table has no frame {}", i + offset))?;
            Ok(Line::through(
                f.translation.vector,
                f.rotation * nalgebra::Vector3::z(),
            )?)
        })
        .collect()
}

/// Whether two axes at `angle` (radians, `[0, pi]`) are within 5 degrees of parallel.
fn near_parallel(angle: f64) -> bool {
    angle.min(std::f64::consts::PI - angle) < NEAR_PARALLEL
}

/// Per axis, the point where a DH frame would sit on it: on the first, the point nearest the
/// origin; on a later one, the foot of the common normal with the previous axis, or for a
/// (nearly) parallel pair the foot of the previous axis's point. Offsets of parallel axes are
/// measured there, where the arm is, rather than near a far-away origin.
fn anchors(axes: &[&Line]) -> Vec<nalgebra::Vector3<f64>> {
    let mut out: Vec<nalgebra::Vector3<f64>> = Vec::with_capacity(axes.len());
    for (i, a) in axes.iter().enumerate() {
        let p = match (i, out.last()) {
            (0, _) | (_, None) => a.point(),
            (_, Some(prev)) => {
                let b = axes[i - 1];
                if near_parallel(b.angle_to(a)) {
                    a.foot_of(prev)
                } else {
                    b.closest_points(a)
                        .map_or_else(|| a.foot_of(prev), |(_, q)| q)
                }
            }
        };
        out.push(p);
    }
    out
}

fn pair_comparison(nominal: &DhTable, cpa: &CpaResult) -> Result<Vec<PairComparisonDoc>> {
    let tol = Tolerance::default();
    let nominal_axes = nominal_axes(nominal)?;
    // The rows the data measured, in chain order, nominal and measured side by side.
    let mut both: Vec<(&str, &Line, &Line)> = Vec::new();
    for (row, n) in nominal.rows.iter().zip(&nominal_axes) {
        if let Some(m) = cpa.axes.iter().find(|a| a.name == row.name) {
            both.push((&row.name, n, &m.line));
        }
    }
    let n_axes: Vec<&Line> = both.iter().map(|b| b.1).collect();
    let m_axes: Vec<&Line> = both.iter().map(|b| b.2).collect();
    let (n_at, m_at) = (anchors(&n_axes), anchors(&m_axes));
    let mut out = Vec::new();
    for i in 1..both.len() {
        let n = classify(n_axes[i - 1], n_axes[i], tol);
        let m = classify(m_axes[i - 1], m_axes[i], tol);
        // The common normal of nearly parallel measured axes lies anywhere along them; their
        // offset at the arm is what can be compared.
        let (nd, md) = if near_parallel(n.angle) && near_parallel(m.angle) {
            (
                n_axes[i].distance_to_point(&n_at[i - 1]),
                m_axes[i].distance_to_point(&m_at[i - 1]),
            )
        } else {
            (n.distance, m.distance)
        };
        out.push(PairComparisonDoc {
            joints: [both[i - 1].0.to_string(), both[i].0.to_string()],
            nominal_angle: n.angle,
            measured_angle: m.angle,
            nominal_distance: nd,
            measured_distance: md,
        });
    }
    Ok(out)
}

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
    match args.format {
        CpaFormat::Text => {
            out.write_all(text(&doc, &sheet).as_bytes())?;
        }
        CpaFormat::Yaml | CpaFormat::Json => {
            sheet.cpa = Some(serde_yaml::to_value(&doc)?);
            let format = if args.format == CpaFormat::Yaml {
                Format::Yaml
            } else {
                Format::Json
            };
            out.write_all(render_sheet(&sheet, format)?.as_bytes())?;
        }
    }
    Ok(Outcome::Pass)
}

/// `v` with `decimals`, `-0` as `0`.
fn fixed(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        s.trim_start_matches('-').to_string()
    } else {
        s
    }
}

fn text(doc: &CpaDoc, sheet: &SheetDoc) -> String {
    let (lu, au) = (LengthUnit::M, AngleUnit::Rad);
    let l = |v: f64| match lu {
        LengthUnit::M => fixed(v, 6),
        LengthUnit::Mm => fixed(v * 1e3, 3),
    };
    // Joint-motion residuals are small angles: a tenth of a microradian resolves them.
    let a = |v: f64| match au {
        AngleUnit::Rad => fixed(v, 7),
        AngleUnit::Deg => fixed(v.to_degrees(), 5),
    };
    let span = |v: f64, kind: &str| {
        if kind == "prismatic" {
            format!("{} {}", l(v), lu.symbol())
        } else {
            format!("{} {}", a(v), au.symbol())
        }
    };
    let mut s = String::new();
    let _ = writeln!(
        s,
        "circle-point analysis of {}: {} samples of {} target(s) ({}), device frame",
        doc.data,
        doc.samples,
        doc.targets.len(),
        doc.targets.join(", ")
    );
    let _ = writeln!(s, "sweeps:");
    for sw in &doc.sweeps {
        let coupled: String = sw
            .coupled
            .iter()
            .map(|c| format!(" with {} x {}", c.joint, fixed(c.ratio, 4)))
            .collect();
        let kind = doc
            .joints
            .iter()
            .find(|j| j.name == sw.joint)
            .map_or("revolute", |j| j.kind);
        let _ = writeln!(
            s,
            "  {}{coupled}: lines {}-{}, {} poses, span {}{}",
            sw.joint,
            sw.lines[0],
            sw.lines[1],
            sw.poses,
            span(sw.span, kind),
            if sw.used { "" } else { " (not used)" }
        );
    }
    let _ = writeln!(
        s,
        "joints (lengths in {}, angles in {}):",
        lu.symbol(),
        au.symbol()
    );
    let w = crate::guard::column_width(doc.joints.iter().map(|j| j.name.as_str()), 5);
    let _ = writeln!(
        s,
        "  {:<w$} {:>5} {:>6} {:>12} {:>11} {:>11} {:>11} {:>12}",
        "joint",
        "poses",
        "points",
        "radius",
        "circle_rms",
        "plane_rms",
        "motion_rms",
        "motion_slope"
    );
    for j in &doc.joints {
        let motion = |v: f64| {
            if j.kind == "prismatic" {
                l(v)
            } else {
                a(v)
            }
        };
        let _ = writeln!(
            s,
            "  {:<w$} {:>5} {:>6} {:>12} {:>11} {:>11} {:>11} {:>12}",
            crate::guard::escape(&j.name),
            j.poses,
            j.points,
            j.radius.map_or_else(|| "-".into(), l),
            l(j.circle_rms),
            j.plane_rms.map_or_else(|| "-".into(), l),
            motion(j.motion.rms),
            j.motion
                .slope
                .map_or_else(|| "-".into(), |v| format!("{v:.3e}"))
        );
    }
    let _ = writeln!(
        s,
        "  (motion: measured minus commanded joint motion, mean removed; slope: measured = (1 + slope) x commanded)"
    );
    if !doc.pairs.is_empty() {
        let _ = writeln!(s, "axis pairs, nominal -> measured:");
        for p in &doc.pairs {
            let _ = writeln!(
                s,
                "  {} -> {}: angle {} -> {} {}, distance {} -> {} {}",
                p.joints[0],
                p.joints[1],
                a(p.nominal_angle),
                a(p.measured_angle),
                au.symbol(),
                l(p.nominal_distance),
                l(p.measured_distance),
                lu.symbol()
            );
        }
    }
    let _ = writeln!(
        s,
        "table against the measured axes (FK at the {} measured joint vectors): max {:.3e} m, {:.3e} rad (snapping near-parallel pairs would give {:.3e} m, {:.3e} rad)",
        doc.proof.poses, doc.proof.written[0], doc.proof.written[1], doc.proof.snapped[0], doc.proof.snapped[1]
    );
    let _ = writeln!(s, "extracted DH table (base: DH frame 0 in the device frame; tool: the tip frame at the last joint's circle centre):");
    s.push_str(&render_sheet(sheet, Format::Text).unwrap_or_default());
    s
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
        })
    }
}
