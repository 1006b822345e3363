//! `urdf-dh import`: a published dataset, read as its authors left it, written as the canonical
//! measurement CSV (metres, radians, points in the device frame).

use std::io::Write;
use std::path::Path;

use anyhow::{Context, Result};
use dh_calib::csv::write_measurements;
use dh_calib::data::Split;
use dh_calib::import::{import as import_layout, mukca, Layout, Source};

use crate::error::{hinted, Outcome};
use crate::input::{display_name, read_text};
use crate::output::check_destinations;

/// Everything `import` needs.
#[derive(Clone, Debug)]
pub struct ImportArgs {
    /// The dataset's layout; `None` detects it from the file names.
    pub layout: Option<Layout>,
    /// The dataset's files (a directory stands for every file in it).
    pub files: Vec<String>,
    /// Where to write the CSV; `None` is standard output.
    pub out: Option<String>,
}

/// The ball-in-socket files of a MUKCa placement directory.
const PLACEMENT_FILES: [&str; 2] = [mukca::HOLE_0, mukca::HOLE_1];

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
/// name and text. Files that are not UTF-8 text inside a directory are skipped (datasets ship
/// images and archives beside their data). A MUKCa placement directory (with `hole_0.csv` and
/// `hole_1.csv`), or a robot directory of them, gives its placement files named
/// `<placement>/<file>`.
fn gather(args: &[String]) -> Result<Vec<(String, String)>> {
    let mut out = Vec::new();
    for a in args {
        let p = Path::new(a);
        let mukca = if p.is_dir() {
            placements(p)?
        } else {
            Vec::new()
        };
        if !mukca.is_empty() {
            out.extend(mukca);
        } else if p.is_dir() {
            let mut entries: Vec<_> = std::fs::read_dir(p)
                .with_context(|| format!("{a}: cannot read the directory"))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.is_file())
                .collect();
            entries.sort();
            for e in entries {
                let path = e.to_string_lossy().into_owned();
                if let Ok(text) = read_text(&path) {
                    out.push((display_name(&path), text));
                }
            }
        } else {
            out.push((display_name(a), read_text(a)?));
        }
    }
    Ok(out)
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
    let files = gather(&args.files)?;
    let names: Vec<&str> = files.iter().map(|(n, _)| n.as_str()).collect();
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
        None => Layout::detect(&names).ok_or_else(|| {
            hinted(
                format!(
                    "cannot tell the dataset's layout from the file names {}",
                    names.join(", ")
                ),
                format!("name it with --layout: {}", layouts()),
            )
        })?,
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
    let validation = data
        .samples
        .iter()
        .filter(|s| s.split == Split::Validation)
        .count();
    let mut text = format!(
        "# imported by urdf-dh import --layout {layout} from {}\n# metres and radians; points in the measuring device's frame\n",
        names.join(" ")
    );
    text.push_str(&write_measurements(&data));
    match &args.out {
        Some(path) => {
            crate::output::write_all_or_stdout(&[(Path::new(path), text.as_bytes())], out)?;
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
    /// The dataset's layout: innopolis, boby, dlr, liaowu, hilti, mukca [default: detected from
    /// the file names].
    #[arg(long, value_parser = parse_layout)]
    layout: Option<Layout>,
    /// The dataset's files as published (a directory stands for all its files).
    #[arg(required = true, value_name = "FILE")]
    files: Vec<String>,
    /// Write the CSV here (atomically) instead of standard output (`-` is standard output too).
    #[arg(long, value_name = "D.csv")]
    out: Option<String>,
}

fn parse_layout(s: &str) -> Result<Layout, String> {
    s.parse()
}

impl ImportCli {
    /// The arguments of [`import`].
    pub fn into_args(self) -> ImportArgs {
        ImportArgs {
            layout: self.layout,
            files: self.files,
            out: self.out,
        }
    }
}
