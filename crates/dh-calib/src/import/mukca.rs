//! MUKCa ball-in-socket contacts (TU Delft, platonics-delft/kinematics_calibration): a ball on
//! the flange placed by hand in socket 0 or socket 1 of a printed tool, the sockets 50 mm apart;
//! for each socket 20-30 joint configurations. Not a coordinate measurement: every sample is a
//! contact with an unknown fixed point (see [`crate::socket`]).
//!
//! # Layout
//! `data/<robot>/<placement>/hole_0.csv` and `hole_1.csv`: one joint configuration per line,
//! comma separated, radians, no header (7 columns for the Panda and the iiwa, 6 for the Gen3
//! lite). The `*_pose.csv` files beside them are forward kinematics the authors derived, not
//! measurements, and are not read.
//!
//! Sources are named `hole_0.csv`, `hole_1.csv` (one placement, called [`PLACEMENT`]) or
//! `<placement>/hole_0.csv`, `<placement>/hole_1.csv` (any number of placements, each a
//! directory of the robot's data; a placement needs both files).
//!
//! # Result
//! - joints `joint_1..joint_n`, radians, as recorded;
//! - one target, [`TARGET`] (the ball centre);
//! - per placement two sockets, `<placement>/0` and `<placement>/1`, each the other's partner at
//!   [`SOCKET_DISTANCE`] ± [`SOCKET_DISTANCE_SIGMA`]; a new placement is a new pair of unknown
//!   points (the tool was moved);
//! - every sample is for calibration (choose the held-out placements when importing: import
//!   them separately and pass them as validation); `config` is empty (no pose is repeated);
//!   `line` is the line in its file.

use super::{in_file, numbered, Source};
use crate::csv::{number, records, DataError};
use crate::data::{Measurements, Sample, Socket, SocketDistance, Split};

/// File of socket 0's configurations.
pub const HOLE_0: &str = "hole_0.csv";
/// File of socket 1's configurations.
pub const HOLE_1: &str = "hole_1.csv";
/// Placement name of files given without a directory.
pub const PLACEMENT: &str = "placement";
/// The target's name: the centre of the ball on the flange.
pub const TARGET: &str = "ball";
/// Centre distance of the tool's two sockets (metres): 50 mm by design (upstream README and
/// `OFFSET_DISTANCE` in its `utils.py`).
pub const SOCKET_DISTANCE: f64 = 0.05;
/// Its standard deviation (metres): the printed tool was checked with a caliper to better than
/// 0.1 mm (dataset SOURCE.md).
pub const SOCKET_DISTANCE_SIGMA: f64 = 1e-4;

/// Splits a source name into (placement, file name).
fn placement_of(name: &str) -> (&str, &str) {
    match name.rsplit_once('/') {
        Some((dir, file)) => (dir, file),
        None => (PLACEMENT, name),
    }
}

/// Parses the sources of one or more placements (see the [module docs](self)).
///
/// # Errors
/// [`DataError::MissingFile`] when no `hole_0.csv` is given or a placement lacks one of its two
/// files; otherwise, wrapped in [`DataError::InFile`] with the file's name: an empty file, a
/// cell that is not a finite number, a line whose column count differs from the first line of
/// the first file, a value beyond 8π (not radians).
pub fn parse(sources: &[Source<'_>]) -> Result<Measurements, DataError> {
    let given = || sources.iter().map(|s| s.name.to_string()).collect();
    let mut placements: Vec<&str> = Vec::new();
    for s in sources {
        let (p, file) = placement_of(s.name);
        if (file == HOLE_0 || file == HOLE_1) && !placements.contains(&p) {
            placements.push(p);
        }
    }
    if placements.is_empty() {
        return Err(DataError::MissingFile {
            layout: "mukca",
            file: HOLE_0,
            given: given(),
        });
    }
    let mut joints: Option<usize> = None;
    let mut samples = Vec::new();
    for p in &placements {
        for (hole, file) in [HOLE_0, HOLE_1].iter().enumerate() {
            let source = sources
                .iter()
                .find(|s| placement_of(s.name) == (*p, *file))
                .ok_or_else(|| DataError::MissingFile {
                    layout: "mukca",
                    file,
                    given: given(),
                })?;
            let socket = format!("{p}/{hole}");
            let partner = format!("{p}/{}", 1 - hole);
            let rows = parse_file(source.text, &mut joints).map_err(|e| in_file(source.name, e))?;
            for (q, line) in rows {
                samples.push(Sample {
                    time: None,
                    orientation: None,
                    session: 0,
                    q: q.into(),
                    target: 0,
                    point: Default::default(),
                    sigma: None,
                    config: None,
                    split: Split::Calibration,
                    line,
                    socket: Some(Box::new(Socket {
                        name: socket.clone(),
                        partner: Some(SocketDistance {
                            socket: partner.clone(),
                            distance: SOCKET_DISTANCE,
                            sigma: SOCKET_DISTANCE_SIGMA,
                        }),
                    })),
                });
            }
        }
    }
    Ok(Measurements {
        sessions: Vec::new(),
        joint_names: numbered("joint", joints.unwrap_or(0)),
        targets: vec![TARGET.into()],
        samples,
    })
}

/// A revolute joint value beyond this many radians (four turns) is no joint angle in radians.
const MAX_RADIANS: f64 = 8.0 * std::f64::consts::PI;

/// The rows of one file with their lines; `joints` is the column count of the first row read.
fn parse_file(text: &str, joints: &mut Option<usize>) -> Result<Vec<(Vec<f64>, usize)>, DataError> {
    let recs = records(text, ',', true)?;
    if recs.is_empty() {
        return Err(DataError::Empty {
            found: "an empty file",
        });
    }
    let mut out = Vec::with_capacity(recs.len());
    for r in recs {
        let n = *joints.get_or_insert(r.fields.len());
        if r.fields.len() != n {
            return Err(DataError::FieldCount {
                line: r.line,
                expected: n,
                found: r.fields.len(),
            });
        }
        let mut q = Vec::with_capacity(n);
        for (i, f) in r.fields.iter().enumerate() {
            let column = format!("joint_{}", i + 1);
            let v = number(f, r.line, &column)?;
            if v.abs() > MAX_RADIANS {
                return Err(DataError::SuspiciousUnit {
                    line: r.line,
                    column,
                    value: v,
                    unit: "rad",
                    hint: "is beyond four turns; the layout records radians",
                });
            }
            q.push(v);
        }
        out.push((q, r.line));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    const ROWS: &str = "0.1,0.2,0.3\n0.4,0.5,0.6\n";

    fn src<'a>(name: &'a str, text: &'a str) -> Source<'a> {
        Source { name, text }
    }

    #[test]
    fn two_placements_make_four_sockets() {
        let m = parse(&[
            src("front/hole_0.csv", ROWS),
            src("front/hole_1.csv", "1,2,3\n"),
            src("left/hole_1.csv", ROWS),
            src("left/hole_0.csv", ROWS),
            src("left/hole_0_pose.csv", "not, read\n"),
        ])
        .unwrap();
        assert_eq!(m.joint_names, vec!["joint_1", "joint_2", "joint_3"]);
        assert_eq!(m.samples.len(), 7);
        let names: Vec<&str> = m
            .samples
            .iter()
            .map(|s| s.socket.as_ref().unwrap().name.as_str())
            .collect();
        assert_eq!(
            names,
            ["front/0", "front/0", "front/1", "left/0", "left/0", "left/1", "left/1"]
        );
        let p = m.samples[2]
            .socket
            .as_ref()
            .unwrap()
            .partner
            .as_ref()
            .unwrap();
        assert_eq!((p.socket.as_str(), p.distance), ("front/0", 0.05));
        assert_eq!((m.samples[1].q[2], m.samples[1].line), (0.6, 2));
    }

    #[test]
    fn errors_name_file_and_line() {
        let e = parse(&[src("hole_0.csv", ROWS), src("hole_1.csv", "1,2,3\n1,x,3\n")])
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "hole_1.csv: line 2, column 'joint_2': expected a number, found 'x'"
        );
        let e = parse(&[src("a/hole_0.csv", ROWS), src("a/hole_1.csv", "1,2\n")])
            .unwrap_err()
            .to_string();
        assert_eq!(e, "a/hole_1.csv: line 1: expected 3 fields, found 2");
        let e = parse(&[src("a/hole_0.csv", ROWS)]).unwrap_err().to_string();
        assert!(
            e.starts_with("layout 'mukca' needs file 'hole_1.csv'"),
            "{e}"
        );
    }
}
