//! `urdf-dh import`: a published dataset, read as its authors left it, written as the canonical
//! measurement CSV (metres, radians, points in the device frame).

use std::io::Write;
use std::path::Path;

use anyhow::{Context, Result};
use dh_workflows::error::hinted;
use dh_workflows::fit::{Measurements, Split};
use dh_workflows::import::{
    import as import_layout, joint_name_problem, mukca, parse_columns, write_measurements,
    ColumnMap, DataError, Layout, Source,
};
use dh_workflows::input::{display_name, read_text};
use dh_workflows::measured::RESERVED_COLUMNS;
use dh_workflows::output::check_destinations;
use dh_workflows::text::escape;

use crate::error::Outcome;

/// Everything `import` needs.
#[derive(Clone, Debug)]
pub struct ImportArgs {
    /// The dataset's layout; `None` detects it from the file names.
    pub layout: Option<Layout>,
    /// `--layout columns`: the user's own export, read by this column map (one file).
    pub columns: Option<ColumnMap>,
    /// The dataset's files (a directory stands for every file in it).
    pub files: Vec<String>,
    /// Where to write the CSV; `None` is standard output.
    pub out: Option<String>,
}

/// The ball-in-socket files of a MUKCa placement directory.
const PLACEMENT_FILES: [&str; 2] = [mukca::HOLE_0, mukca::HOLE_1];

/// A data table's text ([`dh_workflows::import::read_table`]), what a `.mat` file's reading left
/// out warned on `err`.
fn read_table(path: &str, err: &mut dyn Write) -> Result<String> {
    let (text, notes) = dh_workflows::import::read_table(path)?;
    for n in notes {
        writeln!(err, "urdf-dh: warning: {n}")?;
    }
    Ok(text)
}

/// The MUKCa placement files in `dir` (named `<dir name>/<file>`), or in its subdirectories when
/// it is a robot's directory (named `<subdirectory>/<file>`); empty when it is neither.
fn placements(dir: &Path) -> Result<Vec<(String, String)>> {
    let base = |d: &Path| d.file_name().map(|n| n.to_string_lossy().into_owned());
    let files_of = |d: &Path| -> Result<Vec<(String, String)>> {
        let mut out = Vec::new();
        if PLACEMENT_FILES.iter().all(|f| d.join(f).is_file()) {
            let name = base(d).unwrap_or_else(|| mukca::PLACEMENT.into());
            for f in PLACEMENT_FILES {
                let path = d.join(f).to_string_lossy().into_owned();
                out.push((format!("{name}/{f}"), read_text(&path)?));
            }
        }
        Ok(out)
    };
    let own = files_of(dir)?;
    if !own.is_empty() {
        return Ok(own);
    }
    let mut subdirs: Vec<_> = std::fs::read_dir(dir)
        .with_context(|| format!("{}: cannot read the directory", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_dir())
        .collect();
    subdirs.sort();
    let mut out = Vec::new();
    for d in subdirs {
        out.extend(files_of(&d)?);
    }
    Ok(out)
}

/// The files named by `args`: directories expanded to their files (sorted), each with its file
/// name and text (a MATLAB `.mat` file as the CSV text of its variables, see
/// [`dh_workflows::import::read_table`]),
/// and what a directory held that was not read, named with the reason. Files that are not
/// UTF-8 text inside a directory are left out (datasets ship images and archives beside their
/// data), as are subdirectories and special files (a FIFO is never opened); the list of what
/// was left out is for the message when no layout fits. A MUKCa placement directory (with
/// `hole_0.csv` and `hole_1.csv`), or a robot directory of them, gives its placement files
/// named `<placement>/<file>`.
fn gather(args: &[String], err: &mut dyn Write) -> Result<Gathered> {
    let mut out = Gathered::default();
    for a in args {
        let p = Path::new(a);
        let mukca = if p.is_dir() {
            placements(p)?
        } else {
            Vec::new()
        };
        if !mukca.is_empty() {
            out.files.extend(mukca);
        } else if p.is_dir() {
            let mut entries: Vec<_> = std::fs::read_dir(p)
                .with_context(|| format!("{}: cannot read the directory", escape(a)))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .collect();
            entries.sort();
            for e in entries {
                let path = e.to_string_lossy().into_owned();
                let name = display_name(&path);
                if e.is_dir() {
                    out.left_out
                        .push(format!("'{}' (a directory)", escape(&name)));
                } else if !e.is_file() {
                    out.left_out
                        .push(format!("'{}' (not a regular file)", escape(&name)));
                } else {
                    match read_table(&path, err) {
                        Ok(text) => out.files.push((name, text)),
                        Err(e) => out.left_out.push(format!(
                            "'{}' ({})",
                            escape(&name),
                            first_line(&format!("{e:#}"))
                        )),
                    }
                }
            }
        } else {
            out.files.push((display_name(a), read_table(a, err)?));
        }
    }
    Ok(out)
}

/// The files [`gather`] read, and what it left out.
#[derive(Default)]
struct Gathered {
    /// (file name, text).
    files: Vec<(String, String)>,
    /// `'name' (why)` for each directory entry not read.
    left_out: Vec<String>,
}

/// The first line of a message, at most 120 characters (a reason in a list).
fn first_line(text: &str) -> String {
    let line = text.lines().next().unwrap_or("");
    match line.char_indices().nth(120) {
        Some((k, _)) => format!("{}...", &line[..k]),
        None => line.to_string(),
    }
}

/// Runs `import`.
///
/// # Errors
/// Unreadable files, an undetectable layout, any parse error of the layout (naming the file,
/// line and column), a failed write.
pub fn import(args: &ImportArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    if let Some(path) = &args.out {
        let inputs: Vec<(&str, &str)> = args.files.iter().map(|f| ("FILE", f.as_str())).collect();
        check_destinations(&inputs, &[("--out", path)])?;
    }
    if let Some(map) = &args.columns {
        let path = &args.files[0];
        let text = read_table(path, err)?;
        let name = escape(&display_name(path)).into_owned();
        let (data, notes) = parse_columns(&text, map).map_err(|e| {
            let message = format!("{name}: {e}");
            match e {
                DataError::Incomplete { .. } => hinted(
                    message,
                    "--skip-incomplete leaves out the rows with an empty or NaN number (a warning counts them)",
                ),
                _ => anyhow::anyhow!(message),
            }
        })?;
        for n in notes {
            writeln!(err, "urdf-dh: warning: {name}: {n}")?;
        }
        let header = format!(
            "# imported by urdf-dh import --layout columns from {name}\n# metres and radians; points in the measuring device's frame\n"
        );
        return write_import(args, &data, header, out, err);
    }
    let Gathered { files, left_out } = gather(&args.files, err)?;
    let names: Vec<&str> = files.iter().map(|(n, _)| n.as_str()).collect();
    let shown: Vec<String> = names.iter().map(|n| escape(n).into_owned()).collect();
    let layouts = || {
        Layout::ALL
            .iter()
            .map(|l| {
                let f: Vec<&str> = l.files().iter().map(|f| f.name).collect();
                format!("{l} ({})", f.join(", "))
            })
            .collect::<Vec<_>>()
            .join("; ")
    };
    let layout = match args.layout {
        Some(l) => l,
        None => match Layout::detect_all(&names).as_slice() {
            [one] => *one,
            [] => {
                let found = match (names.is_empty(), left_out.is_empty()) {
                    (true, true) => "cannot tell the dataset's layout: found no file".to_string(),
                    (true, false) => format!(
                        "cannot tell the dataset's layout: found no file it could read, only {}",
                        left_out.join(", ")
                    ),
                    (false, true) => format!(
                        "cannot tell the dataset's layout from the file names {}",
                        shown.join(", ")
                    ),
                    (false, false) => format!(
                        "cannot tell the dataset's layout from the file names {} (left out: {})",
                        shown.join(", "),
                        left_out.join(", ")
                    ),
                };
                return Err(hinted(
                    found,
                    format!("name it with --layout: {}", layouts()),
                ));
            }
            several => {
                let fits: Vec<String> = several
                    .iter()
                    .map(|l| {
                        let f: Vec<&str> = l
                            .files()
                            .iter()
                            .filter(|f| f.required)
                            .map(|f| f.name)
                            .collect();
                        format!("{l} ({})", f.join(", "))
                    })
                    .collect();
                return Err(hinted(
                    format!("the files fit more than one layout: {}", fits.join("; ")),
                    "name the dataset's layout with --layout, or give only its files",
                ));
            }
        },
    };
    let sources: Vec<Source<'_>> = files
        .iter()
        .map(|(name, text)| Source { name, text })
        .collect();
    let data = import_layout(layout, &sources).map_err(|e| {
        hinted(
            e.to_string(),
            format!(
                "layout '{layout}' reads {}",
                layout
                    .files()
                    .iter()
                    .map(|f| if f.required {
                        f.name.to_string()
                    } else {
                        format!("[{}]", f.name)
                    })
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        )
    })?;
    let header = format!(
        "# imported by urdf-dh import --layout {layout} from {}\n# metres and radians; points in the measuring device's frame\n",
        shown.join(" ")
    );
    write_import(args, &data, header, out, err)
}

/// Writes the imported `data` (after the comment lines `header`) to `--out` or standard output,
/// with a summary on standard error.
fn write_import(
    args: &ImportArgs,
    data: &Measurements,
    header: String,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> Result<Outcome> {
    let validation = data
        .samples
        .iter()
        .filter(|s| s.split == Split::Validation)
        .count();
    let mut text = header;
    text.push_str(&write_measurements(data));
    match &args.out {
        Some(path) => {
            dh_workflows::output::write_all_or_stdout(&[(Path::new(path), text.as_bytes())], out)?;
            writeln!(
                err,
                "urdf-dh: {}: {} samples ({} for validation) of {} target(s) {}, joints {}",
                display_name(path),
                data.samples.len(),
                validation,
                data.targets.len(),
                data.targets.join(", "),
                data.joint_names.join(", ")
            )?;
        }
        None => out.write_all(text.as_bytes())?,
    }
    Ok(Outcome::Pass)
}

/// Command-line arguments of `import`.
#[derive(Debug, clap::Args)]
pub struct ImportCli {
    /// The dataset's layout: innopolis, boby, dlr, liaowu, hilti, mukca, or columns (your own
    /// export, mapped by --joints and --points) [default: detected from the file names].
    #[arg(long, value_parser = parse_layout)]
    layout: Option<LayoutChoice>,
    /// `--layout columns`: the joint columns, in the model's order: 1-based numbers, ranges
    /// or header names (`2-7`, `q1,q2,q3`).
    #[arg(long, value_name = "COLS")]
    joints: Option<String>,
    /// `--layout columns`: the x, y, z columns of the measured point.
    #[arg(long, value_name = "COLS")]
    points: Option<String>,
    /// `--layout columns`: the joint names to write [default: the header's, else joint_1..n].
    #[arg(long, value_name = "NAMES", value_delimiter = ',')]
    joint_names: Vec<String>,
    /// `--layout columns`: the target (reflector, marker) column [default: one target, t1].
    #[arg(long, value_name = "COL")]
    target: Option<String>,
    /// `--layout columns`: the point's standard deviation column (its length unit).
    #[arg(long, value_name = "COL", conflicts_with = "sigma_axes")]
    sigma: Option<String>,
    /// `--layout columns`: the point's standard deviation per axis: the x, y, z columns (its
    /// length unit), written as sx, sy, sz.
    #[arg(long, value_name = "COLS")]
    sigma_axes: Option<String>,
    /// `--layout columns`: leave out the rows with an empty or NaN joint, coordinate or sigma
    /// (poses the device did not log); a warning counts them and names the first.
    #[arg(long)]
    skip_incomplete: bool,
    /// `--layout columns`: the pose identifier column (repeats of a pose share it).
    #[arg(long, value_name = "COL")]
    config: Option<String>,
    /// `--layout columns`: the split column (calibration/train, validation/test).
    #[arg(long, value_name = "COL")]
    set: Option<String>,
    /// `--layout columns`: the measurement session column (the device was moved between
    /// sessions; each gets its own device frame).
    #[arg(long, value_name = "COL")]
    session: Option<String>,
    /// `--layout columns`: the time column (seconds, any origin): written as the `time` column
    /// that effects of time (thermal_growth) read.
    #[arg(long, value_name = "COL")]
    time: Option<String>,
    /// `--layout columns`: a 6-DoF device's orientation of the target frame in the device
    /// frame, as a quaternion: its columns in the order qw, qx, qy, qz (scalar first, whatever
    /// the file's order); needs --sigma-rot and --sigma.
    #[arg(long, value_name = "COLS", conflicts_with = "rpy")]
    quaternion: Option<String>,
    /// `--layout columns`: the orientation as roll, pitch, yaw columns (URDF's
    /// Rz(yaw)·Ry(pitch)·Rx(roll), in --angle-unit); needs --sigma-rot and --sigma.
    #[arg(long, value_name = "COLS")]
    rpy: Option<String>,
    /// `--layout columns`: the orientation's standard deviation per axis column (in
    /// --angle-unit).
    #[arg(long, value_name = "COL")]
    sigma_rot: Option<String>,
    /// `--layout columns`: the separator [default: `,`, `;` or tab, detected].
    #[arg(long, value_enum)]
    delimiter: Option<Delimiter>,
    /// `--layout columns`: the first line is data, not a header.
    #[arg(long)]
    no_header: bool,
    /// `--layout columns`: unit of the points, sigmas and prismatic joints.
    #[arg(long, value_enum, default_value_t = dh_workflows::units::LengthUnit::M)]
    length_unit: dh_workflows::units::LengthUnit,
    /// `--layout columns`: unit of the revolute joints.
    #[arg(long, value_enum, default_value_t = dh_workflows::units::AngleUnit::Rad)]
    angle_unit: dh_workflows::units::AngleUnit,
    /// `--layout columns`: the prismatic joints (by written name).
    #[arg(long, value_name = "NAMES", value_delimiter = ',')]
    prismatic: Vec<String>,
    /// The dataset's files as published (a directory stands for all its files).
    #[arg(required = true, value_name = "FILE")]
    files: Vec<String>,
    /// Write the CSV here (atomically) instead of standard output (`-` is standard output too).
    #[arg(long, value_name = "D.csv", value_parser = crate::guard::csv_output)]
    out: Option<String>,
}

/// A published dataset's layout, or the user's own columns.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LayoutChoice {
    /// One of the published layouts.
    Known(Layout),
    /// `--layout columns`.
    Columns,
}

/// The separator of `--layout columns`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Delimiter {
    /// `,`
    Comma,
    /// `;`
    Semicolon,
    /// A tab.
    Tab,
}

fn parse_layout(s: &str) -> Result<LayoutChoice, String> {
    if s == "columns" {
        return Ok(LayoutChoice::Columns);
    }
    s.parse().map(LayoutChoice::Known)
}

impl ImportCli {
    /// The arguments of [`import`].
    ///
    /// # Errors
    /// Column options without `--layout columns`, or `--layout columns` without `--joints` and
    /// `--points` (three columns), or a malformed column list.
    pub fn into_args(self) -> Result<ImportArgs> {
        use dh_workflows::import::{ColumnRef, OrientationMap, RotationColumns};
        let given_columns = self.joints.is_some()
            || self.points.is_some()
            || self.sigma_axes.is_some()
            || self.skip_incomplete
            || self.quaternion.is_some()
            || self.rpy.is_some()
            || self.sigma_rot.is_some()
            || self.time.is_some();
        let columns = match self.layout {
            Some(LayoutChoice::Columns) => {
                let list = |option: &str, v: &Option<String>| -> Result<Vec<ColumnRef>> {
                    let text = v.as_deref().ok_or_else(|| {
                        hinted(
                            format!("--layout columns: expected {option}, found none"),
                            "urdf-dh import --layout columns --joints 1-6 --points 7-9 export.csv",
                        )
                    })?;
                    ColumnRef::parse_list(text).map_err(|e| anyhow::anyhow!("{option}: {e}"))
                };
                let one = |option: &str, v: &Option<String>| -> Result<Option<ColumnRef>> {
                    match v {
                        None => Ok(None),
                        Some(_) => {
                            let l = list(option, v)?;
                            match <[ColumnRef; 1]>::try_from(l) {
                                Ok([c]) => Ok(Some(c)),
                                Err(l) => anyhow::bail!(
                                    "{option}: expected one column, found {}",
                                    l.len()
                                ),
                            }
                        }
                    }
                };
                let points = list("--points", &self.points)?;
                let point = <[ColumnRef; 3]>::try_from(points).map_err(|p| {
                    anyhow::anyhow!("--points: expected 3 columns (x, y, z), found {}", p.len())
                })?;
                let rotation = match (&self.quaternion, &self.rpy) {
                    (Some(_), _) => Some(RotationColumns::Quaternion(
                        <[ColumnRef; 4]>::try_from(list("--quaternion", &self.quaternion)?)
                            .map_err(|c| {
                                anyhow::anyhow!(
                                    "--quaternion: expected 4 columns (qw, qx, qy, qz), found {}",
                                    c.len()
                                )
                            })?,
                    )),
                    (None, Some(_)) => Some(RotationColumns::Rpy(
                        <[ColumnRef; 3]>::try_from(list("--rpy", &self.rpy)?).map_err(|c| {
                            anyhow::anyhow!(
                                "--rpy: expected 3 columns (roll, pitch, yaw), found {}",
                                c.len()
                            )
                        })?,
                    )),
                    (None, None) => None,
                };
                let orientation = match (rotation, one("--sigma-rot", &self.sigma_rot)?) {
                    (Some(rotation), Some(sigma)) => {
                        if self.sigma.is_none() && self.sigma_axes.is_none() {
                            return Err(hinted(
                                "--quaternion/--rpy: expected --sigma as well (the position sigma weighs the angle against the position), found none".to_string(),
                                "urdf-dh import --layout columns --joints 1-6 --points 7-9 --sigma 10 --quaternion 11-14 --sigma-rot 15 export.csv",
                            ));
                        }
                        Some(OrientationMap { rotation, sigma })
                    }
                    (Some(_), None) => {
                        return Err(hinted(
                            "--quaternion/--rpy: expected --sigma-rot (the orientation's standard deviation column), found none".to_string(),
                            "urdf-dh import --layout columns --joints 1-6 --points 7-9 --sigma 10 --quaternion 11-14 --sigma-rot 15 export.csv",
                        ))
                    }
                    (None, Some(_)) => {
                        anyhow::bail!("--sigma-rot: expected --quaternion or --rpy, found neither")
                    }
                    (None, None) => None,
                };
                if self.files.len() != 1 {
                    anyhow::bail!(
                        "--layout columns: expected one file, found {}",
                        self.files.len()
                    );
                }
                if !self.joint_names.is_empty() {
                    if let Some(problem) = joint_name_problem(&self.joint_names) {
                        return Err(hinted(
                            format!(
                                "--joint-names: expected names the measurement CSV can hold (distinct, none a reserved column, no control or bidi characters), found {problem}"
                            ),
                            format!(
                                "the reserved columns are {}",
                                RESERVED_COLUMNS.join(", ")
                            ),
                        ));
                    }
                }
                if let Some(p) = self.prismatic.iter().find(|p| p.trim().is_empty()) {
                    anyhow::bail!("--prismatic: expected joint names, found '{}'", escape(p));
                }
                let sigma_axes = match &self.sigma_axes {
                    None => None,
                    Some(_) => Some(
                        <[ColumnRef; 3]>::try_from(list("--sigma-axes", &self.sigma_axes)?)
                            .map_err(|c| {
                                anyhow::anyhow!(
                                    "--sigma-axes: expected 3 columns (sx, sy, sz), found {}",
                                    c.len()
                                )
                            })?,
                    ),
                };
                Some(ColumnMap {
                    joints: list("--joints", &self.joints)?,
                    joint_names: self.joint_names,
                    sigma_axes,
                    skip_incomplete: self.skip_incomplete,
                    point,
                    target: one("--target", &self.target)?,
                    sigma: one("--sigma", &self.sigma)?,
                    config: one("--config", &self.config)?,
                    set: one("--set", &self.set)?,
                    session: one("--session", &self.session)?,
                    time: one("--time", &self.time)?,
                    orientation,
                    delimiter: self.delimiter.map(|d| match d {
                        Delimiter::Comma => ',',
                        Delimiter::Semicolon => ';',
                        Delimiter::Tab => '\t',
                    }),
                    header: !self.no_header,
                    length_scale: self.length_unit.metres(),
                    angle_scale: self.angle_unit.radians(),
                    prismatic: self.prismatic,
                })
            }
            _ if given_columns => {
                return Err(hinted(
                    "--joints/--points/--sigma-axes/--skip-incomplete/--quaternion/--rpy/--sigma-rot/--time: expected --layout columns, found another layout".to_string(),
                    "column options map your own export: urdf-dh import --layout columns --joints 1-6 --points 7-9 export.csv",
                ))
            }
            _ => None,
        };
        Ok(ImportArgs {
            layout: match self.layout {
                Some(LayoutChoice::Known(l)) => Some(l),
                _ => None,
            },
            columns,
            files: self.files,
            out: self.out,
        })
    }
}
