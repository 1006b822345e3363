//! Dataset bytes -> `dh_calib::import::import` in the layout the first byte picks (Innopolis,
//! Boby, DLR, Liao Wu, Hilti, MUKCa). The rest is split at NUL bytes into the layout's files, in
//! the order of `Layout::files` (a wildcard name such as Hilti's `*.yaml` becomes `data.yaml`).
//! An accepted dataset must hold finite numbers only, and its canonical CSV
//! (`write_measurements`) must read back.
//!
//! Fails on a panic, a hang, a NaN or infinity in an accepted dataset, and on a written CSV
//! that does not read back.
#![no_main]

use dh_calib::csv::{parse_measurements, write_measurements, CsvOptions, DataError};
use dh_calib::import::{import, Layout, Source};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&pick, rest)) = data.split_first() else {
        return;
    };
    let layout = Layout::ALL[usize::from(pick) % Layout::ALL.len()];
    let Ok(text) = std::str::from_utf8(rest) else {
        return;
    };
    let names: Vec<String> = layout
        .files()
        .iter()
        .map(|f| match f.name.strip_prefix('*') {
            Some(ext) => format!("data{ext}"),
            None => f.name.to_owned(),
        })
        .collect();
    let sources: Vec<Source<'_>> = names
        .iter()
        .zip(text.split('\0'))
        .map(|(name, text)| Source { name, text })
        .collect();
    let Ok(m) = import(layout, &sources) else {
        return;
    };
    for s in &m.samples {
        assert!(
            s.q.iter().all(|v| v.is_finite()),
            "{layout}: line {}: q {:?}",
            s.line,
            s.q
        );
        assert!(
            s.point.iter().all(|v| v.is_finite()),
            "{layout}: line {}: point {:?}",
            s.line,
            s.point
        );
        assert!(s
            .sigma
            .is_none_or(|v| v.iter().all(|x| x.is_finite() && *x > 0.0)));
        assert!(s.target < m.targets.len().max(1));
    }
    let written = write_measurements(&m);
    match parse_measurements(&written, &m.joint_names, &CsvOptions::default()) {
        Ok(back) => assert_eq!(back.samples.len(), m.samples.len(), "{layout}\n{written}"),
        // Plausibility limits of metres and radians: the reader's unit check, not a fault.
        Err(DataError::SuspiciousUnit { .. }) => {}
        Err(e) => panic!("{layout}: the imported data's CSV does not read back: {e}\n{written}"),
    }
});
