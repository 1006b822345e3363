//! Importers for published measurement datasets, each read as its authors left it.
//!
//! The library does no file I/O: the caller reads the files a [`Layout`] asks for
//! ([`Layout::files`]) and passes their texts as [`Source`]s; [`import`] returns a
//! [`Measurements`] set in metres and radians with points in the measuring device's frame.
//!
//! | layout | files | joints | targets | samples |
//! |---|---|---|---|---|
//! | [`Layout::Innopolis`] | `calibration_dataset.csv` | `joint_1..joint_6` | `A`, `B`, `C` | 3 per row |
//! | [`Layout::Boby`] | `N1N2N3Jval.csv` | `joint_1..joint_6` | `SMR1..SMR3` | 3 per row |
//! | [`Layout::Dlr`] | `measurements.csv` | `torso_1..3`, `right_1..7`, `left_1..7`, `head_1..2` | `right`, `left` | 2 per record |
//! | [`Layout::Liaowu`] | `CaliJointAngles.csv`, `CaliPosition.csv`, test files | `joint_1..joint_6` | `point1..3`, `test1`, `test2` | 1 per position row |
//! | [`Layout::Hilti`] | one of the `*.yaml` stationing files | from the file | `prism` | 1 per waypoint |
//! | [`Layout::Mukca`] | `hole_0.csv`, `hole_1.csv` (or `<placement>/hole_*.csv`) | `joint_1..joint_n` | `ball` | 1 contact per row |
//!
//! A user's own export, whatever its columns, separators and units, goes through
//! [`columns::parse`] with a [`columns::ColumnMap`] instead.
//!
//! Joint names must match the model's joint names when the set is fitted; the robots' names are
//! `joint_1..joint_n` unless the dataset names its joints itself (Hilti). Each layout's own module
//! documents its columns, units, splits and the choices made.

use std::fmt;
use std::str::FromStr;

use crate::csv::DataError;
use crate::data::Measurements;

/// Flow collections (`[`, `{`) nested deeper than this are refused before YAML or JSON parsing:
/// a sheet or stationing file needs a few levels, and libyaml's scanner takes time quadratic in
/// the depth (100 000 `[` took 22 s).
pub const MAX_FLOW_DEPTH: usize = 64;

/// The line (1-based) where `text` nests flow collections deeper than [`MAX_FLOW_DEPTH`], or
/// `None`: one linear pass that skips quoted strings and `#` comments.
pub fn too_deep_at(text: &str) -> Option<usize> {
    let (mut depth, mut line) = (0usize, 1usize);
    let mut quote: Option<char> = None;
    let mut comment = false;
    let mut previous = '\n';
    for c in text.chars() {
        if c == '\n' {
            line += 1;
            comment = false;
        } else if comment {
        } else if let Some(q) = quote {
            if c == q {
                quote = None;
            }
        } else {
            match c {
                '"' | '\'' => quote = Some(c),
                '#' if previous.is_whitespace() => comment = true,
                '[' | '{' => {
                    depth += 1;
                    if depth > MAX_FLOW_DEPTH {
                        return Some(line);
                    }
                }
                ']' | '}' => depth = depth.saturating_sub(1),
                _ => {}
            }
        }
        previous = c;
    }
    None
}

pub mod boby;
pub mod columns;
pub mod dlr;
pub mod hilti;
pub mod innopolis;
pub mod liaowu;
pub mod mat;
pub mod mukca;
mod table;

/// A published dataset's file layout.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Layout {
    /// Fanuc R-2000iC/165F, 24 configurations × 10 repeats, three markers (Innopolis
    /// University course data): see [`innopolis`].
    Innopolis,
    /// Industrial 6R robot swept one joint at a time under a laser tracker with three SMRs
    /// (Boby & Klimchik): see [`boby`].
    Boby,
    /// DLR Agile Justin humanoid upper body, 500 configurations, one Vicon marker per hand
    /// (Tenhumberg & Bäuml 2021): see [`dlr`].
    Dlr,
    /// ABB IRB 120 with three calibration points and two test points (Liao Wu et al. 2015):
    /// see [`liaowu`].
    Liaowu,
    /// Hilti construction robot (lifting column + Doosan arm) under a total station: see
    /// [`hilti`].
    Hilti,
    /// Ball-in-socket contacts of a Panda, iiwa or Gen3 lite (MUKCa, TU Delft), no measuring
    /// device: see [`mukca`].
    Mukca,
}

/// One file a layout reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FileSpec {
    /// File name as the dataset ships it (`*.yaml`: any one file of that kind).
    pub name: &'static str,
    /// Whether the import fails without it.
    pub required: bool,
}

/// The text of one file of a dataset, under its file name (no directory; [`Layout::Mukca`]
/// takes `<placement>/<file>` to tell placements apart).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Source<'a> {
    /// File name, as in [`FileSpec::name`].
    pub name: &'a str,
    /// File contents.
    pub text: &'a str,
}

impl Layout {
    /// Every layout.
    pub const ALL: [Layout; 6] = [
        Layout::Innopolis,
        Layout::Boby,
        Layout::Dlr,
        Layout::Liaowu,
        Layout::Hilti,
        Layout::Mukca,
    ];

    /// The layout's name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Layout::Innopolis => "innopolis",
            Layout::Boby => "boby",
            Layout::Dlr => "dlr",
            Layout::Liaowu => "liaowu",
            Layout::Hilti => "hilti",
            Layout::Mukca => "mukca",
        }
    }

    /// The files the layout reads. A layout with a single file takes any one [`Source`]
    /// whatever its name.
    pub fn files(self) -> &'static [FileSpec] {
        const fn req(name: &'static str) -> FileSpec {
            FileSpec {
                name,
                required: true,
            }
        }
        const fn opt(name: &'static str) -> FileSpec {
            FileSpec {
                name,
                required: false,
            }
        }
        const INNOPOLIS: &[FileSpec] = &[req(innopolis::FILE)];
        const BOBY: &[FileSpec] = &[req(boby::FILE)];
        const DLR: &[FileSpec] = &[req(dlr::FILE)];
        const LIAOWU: &[FileSpec] = &[
            req(liaowu::CALIBRATION_JOINTS),
            req(liaowu::CALIBRATION_POSITIONS),
            opt(liaowu::TEST_JOINTS[0]),
            opt(liaowu::TEST_POSITIONS[0]),
            opt(liaowu::TEST_JOINTS[1]),
            opt(liaowu::TEST_POSITIONS[1]),
        ];
        const HILTI: &[FileSpec] = &[req("*.yaml")];
        const MUKCA: &[FileSpec] = &[req(mukca::HOLE_0), req(mukca::HOLE_1)];
        match self {
            Layout::Innopolis => INNOPOLIS,
            Layout::Boby => BOBY,
            Layout::Dlr => DLR,
            Layout::Liaowu => LIAOWU,
            Layout::Hilti => HILTI,
            Layout::Mukca => MUKCA,
        }
    }

    /// The layout whose required files are all among `names` (file names; a name
    /// `<directory>/<file>` counts as `<file>`), the first in [`Layout::ALL`] order; `None`
    /// when no layout fits. [`Layout::detect_all`] says when several fit.
    pub fn detect(names: &[&str]) -> Option<Layout> {
        Layout::detect_all(names).into_iter().next()
    }

    /// Every layout whose required files are all among `names`, in [`Layout::ALL`] order: a
    /// folder holding two datasets' files fits two layouts, and taking the first would drop
    /// the other without a word.
    pub fn detect_all(names: &[&str]) -> Vec<Layout> {
        Layout::ALL
            .into_iter()
            .filter(|layout| {
                layout.files().iter().filter(|f| f.required).all(|f| {
                    match f.name.strip_prefix('*') {
                        Some(ext) => names.iter().any(|n| n.ends_with(ext)),
                        None => names.iter().any(|n| {
                            n.rsplit('/')
                                .next()
                                .is_some_and(|base| same_file(base, f.name))
                        }),
                    }
                })
            })
            .collect()
    }
}

impl fmt::Display for Layout {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Layout {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Layout::ALL
            .into_iter()
            .find(|l| l.name() == s)
            .ok_or_else(|| {
                let names: Vec<&str> = Layout::ALL.iter().map(|l| l.name()).collect();
                format!("expected one of {}, found '{s}'", names.join(", "))
            })
    }
}

/// Reads a dataset in `layout` from the texts of its files.
///
/// Returns metres and radians, points in the measuring device's frame; joint and target names
/// as the layout's module documents; `Sample::line` is the 1-based line in the file holding the
/// point.
///
/// # Errors
/// [`DataError::MissingFile`] when a required file is not among `sources`; otherwise the
/// layout's parse errors, wrapped in [`DataError::InFile`] with the file's name.
pub fn import(layout: Layout, sources: &[Source<'_>]) -> Result<Measurements, DataError> {
    let files = Files { layout, sources };
    match layout {
        Layout::Innopolis => files.single(innopolis::parse),
        Layout::Boby => files.single(boby::parse),
        Layout::Dlr => files.single(dlr::parse),
        Layout::Hilti => files.single(hilti::parse),
        Layout::Liaowu => liaowu::parse(&files),
        Layout::Mukca => mukca::parse(sources),
    }
}

/// Looks up a layout's files among the sources.
/// Whether a file given as `given` is the layout's file `spec`: the same name, or a MATLAB
/// export of a CSV file (`calibration_dataset.mat` for `calibration_dataset.csv`), read as its
/// CSV text by [`mat::to_csv`].
fn same_file(given: &str, spec: &str) -> bool {
    given == spec
        || given
            .strip_suffix(".mat")
            .zip(spec.strip_suffix(".csv"))
            .is_some_and(|(a, b)| a == b)
}

pub(crate) struct Files<'s, 'a> {
    layout: Layout,
    sources: &'s [Source<'a>],
}

impl<'a> Files<'_, 'a> {
    fn given(&self) -> Vec<String> {
        self.sources.iter().map(|s| s.name.to_string()).collect()
    }

    /// The one file of a single-file layout: the source named as the layout says, or else the
    /// only source given.
    fn single(
        &self,
        parse: impl Fn(&str) -> Result<Measurements, DataError>,
    ) -> Result<Measurements, DataError> {
        let spec = self.layout.files()[0];
        // `*.yaml`: the files of that kind among those given (a dataset directory holds others).
        let matching: Vec<&Source<'_>> = match spec.name.strip_prefix('*') {
            Some(ext) => self
                .sources
                .iter()
                .filter(|s| s.name.to_ascii_lowercase().ends_with(ext))
                .collect(),
            None => self
                .sources
                .iter()
                .filter(|s| same_file(s.name, spec.name))
                .collect(),
        };
        let source = match (self.sources, matching.as_slice()) {
            ([only], _) => only,
            (_, [only]) => *only,
            (_, []) => {
                return Err(DataError::MissingFile {
                    layout: self.layout.name(),
                    file: spec.name,
                    given: self.given(),
                })
            }
            (_, several) => {
                return Err(DataError::Content {
                    expected: format!(
                        "one {} file for layout '{}' (each is a measurement session of its own)",
                        spec.name,
                        self.layout.name()
                    ),
                    found: format!(
                        "{}: {}; name the one to import",
                        several.len(),
                        several
                            .iter()
                            .map(|s| format!("'{}'", s.name))
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                })
            }
        };
        parse(source.text).map_err(|e| in_file(source.name, e))
    }

    /// The text of file `name`, `None` when it was not given.
    pub(crate) fn optional(&self, name: &str) -> Option<&'a str> {
        self.sources
            .iter()
            .find(|s| same_file(s.name, name))
            .map(|s| s.text)
    }

    /// The text of file `name`.
    ///
    /// # Errors
    /// [`DataError::MissingFile`] when it was not given.
    pub(crate) fn required(&self, name: &'static str) -> Result<&'a str, DataError> {
        self.optional(name).ok_or_else(|| DataError::MissingFile {
            layout: self.layout.name(),
            file: name,
            given: self.given(),
        })
    }
}

/// Wraps `e` with the file it came from.
pub(crate) fn in_file(name: &str, e: DataError) -> DataError {
    DataError::InFile {
        file: name.to_string(),
        source: Box::new(e),
    }
}

/// `prefix_1..prefix_n`.
pub(crate) fn numbered(prefix: &str, n: usize) -> Vec<String> {
    (1..=n).map(|i| format!("{prefix}_{i}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layouts_parse_from_their_names() {
        for layout in Layout::ALL {
            assert_eq!(layout.name().parse::<Layout>(), Ok(layout));
        }
        assert_eq!(
            "fanuc".parse::<Layout>().unwrap_err(),
            "expected one of innopolis, boby, dlr, liaowu, hilti, mukca, found 'fanuc'"
        );
    }

    #[test]
    fn detect_by_file_names() {
        assert_eq!(
            Layout::detect(&["N1N2N3Jval.csv", "SOURCE.md"]),
            Some(Layout::Boby)
        );
        assert_eq!(
            Layout::detect(&["CaliPosition.csv", "CaliJointAngles.csv"]),
            Some(Layout::Liaowu)
        );
        assert_eq!(Layout::detect(&["flat.yaml"]), Some(Layout::Hilti));
        assert_eq!(Layout::detect(&["CaliPosition.csv"]), None);
        assert_eq!(
            Layout::detect_all(&["calibration_dataset.csv", "N1N2N3Jval.csv"]),
            vec![Layout::Innopolis, Layout::Boby]
        );
        assert_eq!(
            Layout::detect(&["front/hole_0.csv", "front/hole_1.csv", "SOURCE.md"]),
            Some(Layout::Mukca)
        );
    }

    #[test]
    fn missing_file_names_what_was_given() {
        let e = import(
            Layout::Liaowu,
            &[Source {
                name: "CaliPosition.csv",
                text: "",
            }],
        )
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "layout 'liaowu' needs file 'CaliJointAngles.csv', which was not given; \
             given: 'CaliPosition.csv'"
        );
    }
}
