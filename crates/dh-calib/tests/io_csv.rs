//! The canonical CSV through the public API: writing then reading gives the same set back,
//! bit for bit, for sets with every optional column and awkward names.

use nalgebra::Vector3;
use proptest::prelude::*;

use dh_calib::csv::{parse_measurements, write_measurements, AngleUnit, CsvOptions, LengthUnit};
use dh_calib::data::{Measurements, Sample, Split};

/// Any finite value in a range the unit checks accept, including subnormals, zero signs and
/// values needing all 17 significant digits.
fn coordinate(limit: f64) -> impl Strategy<Value = f64> {
    prop_oneof![
        (-limit..limit),
        Just(0.0),
        Just(-0.0),
        Just(5e-324),
        Just(0.1 + 0.2),
        Just(-limit * (1.0 - f64::EPSILON)),
    ]
}

/// Names with delimiters, quotes, spaces, a leading '#' and non-ASCII letters, never empty
/// (control and bidi characters are refused by the reader: see
/// `names_with_control_or_bidi_characters_are_refused`).
fn name() -> impl Strategy<Value = String> {
    prop_oneof![
        "[a-z_][a-z0-9_]{0,8}",
        Just("with, comma".to_string()),
        Just("\"quoted\"".to_string()),
        Just(" padded ".to_string()),
        Just("#hash".to_string()),
        Just("Gelenk ä".to_string()),
    ]
}

fn split() -> impl Strategy<Value = Split> {
    prop_oneof![Just(Split::Calibration), Just(Split::Validation)]
}

fn sigma() -> impl Strategy<Value = Option<Vector3<f64>>> {
    prop_oneof![
        Just(None),
        (1e-9..1e-2f64).prop_map(|s| Some(Vector3::repeat(s))),
        (1e-9..1e-2f64, 1e-9..1e-2f64, 1e-9..1e-2f64)
            .prop_map(|(a, b, c)| Some(Vector3::new(a, b, c))),
    ]
}

fn sample(joints: usize, targets: usize) -> impl Strategy<Value = Sample> {
    (
        proptest::collection::vec(coordinate(25.0), joints),
        0..targets,
        (coordinate(99.0), coordinate(99.0), coordinate(99.0)),
        sigma(),
        proptest::option::of(name()),
        split(),
    )
        .prop_map(|(q, target, (x, y, z), sigma, config, split)| Sample {
            time: None,
            orientation: None,
            session: 0,
            q: q.into(),
            target,
            point: Vector3::new(x, y, z),
            sigma,
            config: config.map(Into::into),
            split,
            line: 0,
            socket: None,
        })
}

/// A measurement set whose targets are numbered in order of first use (as the writer and
/// reader number them).
fn measurements() -> impl Strategy<Value = Measurements> {
    (1usize..4, 1usize..4)
        .prop_flat_map(|(joints, targets)| {
            (
                proptest::collection::vec(sample(joints, targets), 1..12),
                Just(joints),
                proptest::collection::vec(name(), targets),
            )
        })
        .prop_map(|(mut samples, joints, names)| {
            let mut order: Vec<usize> = Vec::new();
            for s in &mut samples {
                let k = match order.iter().position(|&t| t == s.target) {
                    Some(k) => k,
                    None => {
                        order.push(s.target);
                        order.len() - 1
                    }
                };
                s.target = k;
            }
            // Distinct target names in first-use order.
            let targets = order
                .iter()
                .enumerate()
                .map(|(k, &t)| format!("{}{k}", names[t]))
                .collect();
            Measurements {
                sessions: Vec::new(),
                joint_names: (0..joints).map(|j| format!("joint {j}")).collect(),
                targets,
                samples,
            }
        })
}

proptest! {
    #[test]
    fn write_then_parse_is_identity(m in measurements()) {
        let text = write_measurements(&m);
        let back = parse_measurements(&text, &m.joint_names, &CsvOptions::default())
            .map_err(|e| TestCaseError::fail(format!("{e}\n{text}")))?;
        prop_assert_eq!(back.targets.clone(), m.targets.clone());
        prop_assert_eq!(back.samples.len(), m.samples.len());
        for (a, b) in back.samples.iter().zip(&m.samples) {
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            prop_assert_eq!(bits(&a.q), bits(&b.q));
            prop_assert_eq!(bits(a.point.as_slice()), bits(b.point.as_slice()));
            prop_assert_eq!(a.sigma, b.sigma);
            prop_assert_eq!(&a.config, &b.config);
            prop_assert_eq!((a.target, a.split), (b.target, b.split));
            prop_assert!(a.line > 1);
        }
    }
}

#[test]
fn names_with_control_or_bidi_characters_are_refused() {
    let names = ["j".to_string()];
    for (cell, column, code) in [
        ("\"two\nlines\"", "config", "U+000A"),
        ("t\u{1b}[2J", "target", "U+001B"),
        ("t\u{202e}1", "target", "U+202E"),
    ] {
        let text = if column == "config" {
            format!("j,x,y,z,config\n0,0,0,0,{cell}\n")
        } else {
            format!("j,x,y,z,target\n0,0,0,0,{cell}\n")
        };
        let e = parse_measurements(&text, &names, &CsvOptions::default())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(&format!("line 2: expected a name without control or bidi characters in column '{column}', found {code}")),
            "{e}"
        );
    }
    // A header column too.
    let e = parse_measurements(
        "j,x,y,z,t\u{7}\n0,0,0,0,a\n",
        &names,
        &CsvOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("line 1") && e.contains("U+0007"), "{e}");
}

#[test]
fn millimetres_and_degrees_read_as_metres_and_radians() {
    let text = "\
# a laser tracker export
j1,j2,x,y,z,sigma
90,-45,1000,2000,-3000,0.015
";
    let opts = CsvOptions {
        length_unit: LengthUnit::Millimetre,
        angle_unit: AngleUnit::Degree,
        prismatic: Vec::new(),
    };
    let names = ["j1".to_string(), "j2".to_string()];
    let m = parse_measurements(text, &names, &opts).unwrap();
    let s = &m.samples[0];
    assert_eq!(s.q[..], [90f64.to_radians(), (-45f64).to_radians()]);
    assert_eq!(s.point, Vector3::new(1.0, 2.0, -3.0));
    assert!((s.sigma.unwrap() - Vector3::repeat(1.5e-5)).norm() < 1e-20);
    assert_eq!(s.line, 3);
    // The same file read as metres is refused with a hint.
    let e = parse_measurements(text, &names, &CsvOptions::default()).unwrap_err();
    assert_eq!(
        e.to_string(),
        "line 3, column 'j1': 90 rad looks like degrees; pass --angle-unit deg"
    );
}
