//! Measurement CSV bytes -> `dh_calib::csv::parse_measurements` with the joint names the
//! header suggests and the units picked by the first byte (bit 0: mm, bit 1: deg, bit 2: the
//! first joint prismatic; high nibble 0xf: a joint column that the header lacks) -> every value finite -> written back with
//! `write_measurements` and read again to the same samples.
//!
//! Fails on a panic, a hang, a NaN or infinity in an accepted file, and on a round trip that
//! changes a sample.
#![no_main]

use dh_calib::csv::{parse_measurements, write_measurements, AngleUnit, CsvOptions, LengthUnit};
use libfuzzer_sys::fuzz_target;

/// Header columns that are not joints: the format's own list (a joint named like one is refused,
/// tested in dh-calib; the target skips them to reach the row reader).
const NOT_JOINTS: &[&str] = &dh_calib::csv::RESERVED_COLUMNS;

fuzz_target!(|data: &[u8]| {
    let Some((&mode, rest)) = data.split_first() else {
        return;
    };
    let Ok(text) = std::str::from_utf8(rest) else {
        return;
    };
    // Joint names: the header's other columns (the first non-comment line, split on commas,
    // without quote handling: a rough guess is enough to reach the row reader), at most 12.
    let header = text
        .lines()
        .find(|l| !l.trim().is_empty() && !l.trim_start().starts_with('#'))
        .unwrap_or("");
    let mut joints: Vec<String> = header
        .split(',')
        .map(|c| c.trim().trim_matches('"').to_owned())
        .filter(|c| !c.is_empty() && !NOT_JOINTS.contains(&c.as_str()))
        .take(12)
        .collect();
    joints.dedup();
    if mode & 0xf0 == 0xf0 {
        joints.push("joint_missing".into());
    }
    let opts = CsvOptions {
        length_unit: if mode & 1 == 0 {
            LengthUnit::Metre
        } else {
            LengthUnit::Millimetre
        },
        angle_unit: if mode & 2 == 0 {
            AngleUnit::Radian
        } else {
            AngleUnit::Degree
        },
        prismatic: if mode & 4 == 0 {
            vec![]
        } else {
            joints.iter().take(1).cloned().collect()
        },
    };
    let Ok(m) = parse_measurements(text, &joints, &opts) else {
        return;
    };
    for s in &m.samples {
        assert!(
            s.q.iter().all(|v| v.is_finite()),
            "line {}: q {:?}",
            s.line,
            s.q
        );
        assert!(
            s.point.iter().all(|v| v.is_finite()),
            "line {}: point {:?}",
            s.line,
            s.point
        );
        assert!(s
            .sigma
            .is_none_or(|v| v.iter().all(|x| x.is_finite() && *x > 0.0)));
        assert!(s.target < m.targets.len());
    }
    // Written back in metres and radians, read with the default options: the same samples.
    let written = write_measurements(&m);
    let canonical = CsvOptions {
        prismatic: opts.prismatic.clone(),
        ..CsvOptions::default()
    };
    let back = match parse_measurements(&written, &m.joint_names, &canonical) {
        Ok(b) => b,
        // Values accepted in degrees or millimetres may be beyond the plausibility limits of
        // radians and metres; that refusal is the reader's unit check, not a round-trip fault.
        Err(dh_calib::csv::DataError::SuspiciousUnit { .. })
            if opts.angle_unit == AngleUnit::Degree
                || opts.length_unit == LengthUnit::Millimetre =>
        {
            return
        }
        Err(e) => panic!("written measurements do not read back: {e}\n{written}"),
    };
    assert_eq!(back.samples.len(), m.samples.len());
    for (a, b) in m.samples.iter().zip(&back.samples) {
        assert_eq!(a.q, b.q, "q changed\n{written}");
        assert_eq!(a.point, b.point, "point changed\n{written}");
        assert_eq!(a.sigma, b.sigma, "sigma changed\n{written}");
        assert_eq!(a.config, b.config, "config changed\n{written}");
        assert_eq!(a.split, b.split, "split changed\n{written}");
        assert_eq!(
            m.targets[a.target], back.targets[b.target],
            "target changed\n{written}"
        );
    }
});
