//! `urdf-dh batch`: many chains of many URDFs in one process, one JSON line per table.
//!
//! The list names one chain per line: `ROBOT [BASE [TIP]]` (whitespace-separated, `-` for the
//! default, `#` starts a comment); a relative ROBOT path is relative to the list's folder. Each
//! URDF is read and validated once however many of its chains are listed, files are spread over
//! the machine's cores, and every table is proved as written, exactly as `extract --format json`
//! proves it. Output order is the list's.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use anyhow::{bail, Result};
use dh_workflows::geometry::{Convention, Tolerance};
use dh_workflows::input::chain_error;
use dh_workflows::input::Chain;
use dh_workflows::input::{display_name, read_robot, read_text};
use dh_workflows::render::Format;
use dh_workflows::sheet::SheetDoc;
use dh_workflows::units::{AngleUnit, LengthUnit};
use nalgebra::Isometry3;
use serde::Serialize;

use crate::commands::extract::{extract_chain, prove_extracted_with, ExtractOptions};
use crate::error::Outcome;

/// Everything `batch` needs.
#[derive(Clone, Debug)]
pub struct BatchArgs {
    /// The list of chains (a file or `-`).
    pub list: String,
    /// The conventions to extract each chain in.
    pub conventions: Vec<Convention>,
    /// Length unit of the output.
    pub length_unit: LengthUnit,
    /// Angle unit of the output.
    pub angle_unit: AngleUnit,
    /// Tolerances for the axis classification.
    pub tolerance: Tolerance,
    /// Joint-value samples of each proof.
    pub samples: usize,
    /// Seed of the sampler.
    pub seed: u64,
}

/// One line of the list.
#[derive(Clone, Debug)]
struct Entry {
    line: usize,
    robot: String,
    path: PathBuf,
    base: Option<String>,
    tip: Option<String>,
}

/// One output line.
#[derive(Serialize)]
struct Record<'a> {
    /// Line of the list.
    line: usize,
    robot: &'a str,
    base: Option<&'a str>,
    tip: Option<&'a str>,
    convention: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    sheet: Option<SheetDoc>,
    #[serde(skip_serializing_if = "Option::is_none")]
    error: Option<String>,
}

/// The result of one chain in one convention.
#[derive(Clone)]
enum Done {
    Proved { sheet: Box<SheetDoc>, passed: bool },
    Refused(String),
}

/// The URDF's tip poses at the joint values of one chain's proof, kept for the proof of its next
/// convention. The sampler draws the same values for both tables of a chain (it reads the rows'
/// kinds, limits and mimics, which the conventions share, and the table's size only for
/// unlimited prismatic joints); a kept pose is used only for the very same values, bit for bit,
/// so every proof compares with exactly what `Chain::fk` gives.
#[derive(Default)]
struct KeptPoses {
    /// The joint values of sample `k` at `q[k * n..(k + 1) * n]` (radians or metres).
    q: Vec<f64>,
    /// The tip link's pose in the base link frame at sample `k`.
    poses: Vec<Isometry3<f64>>,
}

impl KeptPoses {
    /// The oracle of one proof: the pose kept for the proof's `k`-th sample when its joint
    /// values are the ones kept, else `chain.fk(q)`, then kept for the next proof.
    fn oracle(&mut self) -> impl FnMut(&Chain, &[f64]) -> Isometry3<f64> + '_ {
        let mut k = 0;
        move |chain, q| {
            let n = q.len();
            let range = k * n..(k + 1) * n;
            let same = self
                .q
                .get(range.clone())
                .is_some_and(|kept| kept.iter().zip(q).all(|(a, b)| a.to_bits() == b.to_bits()));
            let pose = if same {
                self.poses[k]
            } else {
                let pose = chain.fk(q);
                if k < self.poses.len() {
                    self.q[range].copy_from_slice(q);
                    self.poses[k] = pose;
                } else {
                    // Samples come in order: `k` is the next one to keep.
                    self.q.extend_from_slice(q);
                    self.poses.push(pose);
                }
                pose
            };
            k += 1;
            pose
        }
    }
}

fn parse_list(text: &str, origin: &str, folder: &Path) -> Result<Vec<Entry>> {
    let mut entries = Vec::new();
    for (k, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("");
        let fields: Vec<&str> = line.split_whitespace().collect();
        if fields.is_empty() {
            continue;
        }
        if fields.len() > 3 {
            bail!(
                "{origin} (line {}): expected 'ROBOT [BASE [TIP]]', found {} fields",
                k + 1,
                fields.len()
            );
        }
        let opt = |i: usize| {
            fields
                .get(i)
                .filter(|f| **f != "-")
                .map(|f| (*f).to_string())
        };
        let robot = fields[0].to_string();
        let path = if Path::new(&robot).is_absolute() {
            PathBuf::from(&robot)
        } else {
            folder.join(&robot)
        };
        entries.push(Entry {
            line: k + 1,
            robot,
            path,
            base: opt(1),
            tip: opt(2),
        });
    }
    if entries.is_empty() {
        bail!("{origin}: the list names no chain; expected lines 'ROBOT [BASE [TIP]]'");
    }
    Ok(entries)
}

/// Every chain of one URDF file, in every convention.
fn run_file(entries: &[&Entry], args: &BatchArgs) -> Vec<Vec<Done>> {
    let path = entries[0].path.to_string_lossy().into_owned();
    let name = display_name(&path);
    let model = read_robot(&path).and_then(|bytes| {
        dh_workflows::input::read_model(
            &bytes,
            &name,
            dh_workflows::input::folder_of(&path).as_deref(),
        )
        .map_err(|e| anyhow::anyhow!("{e:#}"))
    });
    entries
        .iter()
        .map(|entry| {
            let model = match &model {
                Ok(m) => m,
                Err(e) => return vec![Done::Refused(format!("{e:#}")); args.conventions.len()],
            };
            // The poses of the first convention's proof serve the second's.
            let mut kept = KeptPoses::default();
            args.conventions
                .iter()
                .map(|&convention| {
                    let mut one = || -> Result<Done> {
                        let chain = model
                            .chain(entry.base.as_deref(), entry.tip.as_deref())
                            .map_err(|e| chain_error(&name, model, e))?;
                        let options = ExtractOptions {
                            convention,
                            length_unit: args.length_unit,
                            angle_unit: args.angle_unit,
                            tolerance: args.tolerance,
                        };
                        let mut ex = extract_chain(model, chain, &name, &options)?;
                        let (_, passed) = prove_extracted_with(
                            &mut ex,
                            Format::Json,
                            args.samples,
                            args.seed,
                            kept.oracle(),
                        )?;
                        Ok(Done::Proved {
                            sheet: Box::new(ex.sheet),
                            passed,
                        })
                    };
                    one().unwrap_or_else(|e| Done::Refused(format!("{e:#}")))
                })
                .collect()
        })
        .collect()
}

/// Runs `batch`: one JSON line per chain and convention on `out`, a summary on `err`. Exit 0
/// when every table is proved, 1 when one fails its proof, 2 when a chain is refused (bad
/// input; the other chains are still written).
///
/// # Errors
/// An unreadable or empty list.
pub fn batch(args: &BatchArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    let origin = display_name(&args.list);
    let text = read_text(&args.list)?;
    let folder = if args.list == "-" {
        PathBuf::from(".")
    } else {
        Path::new(&args.list)
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_default()
    };
    let entries = parse_list(&text, &origin, &folder)?;
    // One group per file, in order of first mention; files spread over the cores.
    let mut groups: BTreeMap<&Path, Vec<usize>> = BTreeMap::new();
    for (i, e) in entries.iter().enumerate() {
        groups.entry(e.path.as_path()).or_default().push(i);
    }
    let groups: Vec<Vec<usize>> = groups.into_values().collect();
    let workers = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(groups.len())
        .max(1);
    // Each worker takes the next file not yet taken, so that a worker slowed by a large file
    // or by another process on its core leaves the rest to the others.
    let next = AtomicUsize::new(0);
    let mut results: Vec<Option<Vec<Done>>> = vec![None; entries.len()];
    std::thread::scope(|scope| {
        let handles: Vec<_> = (0..workers)
            .map(|_| {
                let (groups, entries, next) = (&groups, &entries, &next);
                scope.spawn(move || {
                    let mut done = Vec::new();
                    while let Some(group) = groups.get(next.fetch_add(1, Ordering::Relaxed)) {
                        let members: Vec<&Entry> = group.iter().map(|&i| &entries[i]).collect();
                        for (i, r) in group.iter().zip(run_file(&members, args)) {
                            done.push((*i, r));
                        }
                    }
                    done
                })
            })
            .collect();
        for h in handles {
            // A worker that panicked leaves its chains as None, reported below.
            if let Ok(done) = h.join() {
                for (i, r) in done {
                    results[i] = Some(r);
                }
            }
        }
    });
    let (mut proved, mut failed, mut refused) = (0usize, 0usize, 0usize);
    for (entry, result) in entries.iter().zip(results) {
        let result = result.unwrap_or_else(|| {
            vec![
                Done::Refused("internal error: the chain was not processed".into());
                args.conventions.len()
            ]
        });
        for (&convention, done) in args.conventions.iter().zip(result) {
            let (sheet, error) = match done {
                Done::Proved { sheet, passed } => {
                    if passed {
                        proved += 1;
                    } else {
                        failed += 1;
                    }
                    (Some(*sheet), None)
                }
                Done::Refused(e) => {
                    refused += 1;
                    (None, Some(e))
                }
            };
            let record = Record {
                line: entry.line,
                robot: &entry.robot,
                base: entry.base.as_deref(),
                tip: entry.tip.as_deref(),
                convention: convention.to_string(),
                sheet,
                error,
            };
            writeln!(out, "{}", crate::guard::json_line(&record)?)?;
        }
    }
    writeln!(
        err,
        "urdf-dh: batch: {} tables: {proved} proved, {failed} failed their proof, {refused} refused",
        proved + failed + refused
    )?;
    if refused > 0 {
        bail!(
            "{refused} of {} tables refused (their lines carry the error)",
            proved + failed + refused
        );
    }
    Ok(if failed > 0 {
        Outcome::Differs
    } else {
        Outcome::Pass
    })
}
