//! The whole `urdf-dh extract` on the Franka Panda fixture: read the URDF, validate the chain,
//! extract the DH table, verify it by forward kinematics at 1000 joint samples against the
//! URDF, render the text table (target: 2 ms). Measured in process through `cli::run`, which is
//! everything the binary does after start-up; a second benchmark spawns the binary for the
//! cost a shell user sees (process start-up included).
#![allow(missing_docs)]

use std::hint::black_box;
use std::path::PathBuf;
use std::process::Command;

use criterion::{criterion_group, criterion_main, Criterion};

fn panda() -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures/robots/franka_panda/robot.urdf")
        .to_string_lossy()
        .into_owned()
}

fn extract_in_process(c: &mut Criterion) {
    let path = panda();
    let args = ["urdf-dh", "extract", path.as_str(), "--samples", "1000"];
    // Once outside the timing: the run must pass its own verification.
    let (mut out, mut err) = (Vec::new(), Vec::new());
    assert_eq!(urdf_dh::cli::run(args, &mut out, &mut err), 0);
    c.bench_function(
        "extract panda, 1000-sample verification (in process)",
        |b| {
            b.iter(|| {
                let (mut out, mut err) = (Vec::with_capacity(4096), Vec::new());
                let code = urdf_dh::cli::run(black_box(args), &mut out, &mut err);
                black_box((code, out))
            })
        },
    );
}

/// The same in YAML, the format the Python package's `urdf_dh.extract` writes and proves
/// (`crates/python/bench.py` compares with this figure).
fn extract_yaml_in_process(c: &mut Criterion) {
    let path = panda();
    let args = [
        "urdf-dh",
        "extract",
        path.as_str(),
        "--samples",
        "1000",
        "--format",
        "yaml",
    ];
    let (mut out, mut err) = (Vec::new(), Vec::new());
    assert_eq!(urdf_dh::cli::run(args, &mut out, &mut err), 0);
    c.bench_function("extract panda --format yaml (in process)", |b| {
        b.iter(|| {
            let (mut out, mut err) = (Vec::with_capacity(4096), Vec::new());
            let code = urdf_dh::cli::run(black_box(args), &mut out, &mut err);
            black_box((code, out))
        })
    });
}

fn extract_process(c: &mut Criterion) {
    // Cargo builds the binary for the package's benches and says where.
    let exe = env!("CARGO_BIN_EXE_urdf-dh");
    let path = panda();
    c.bench_function(
        "extract panda, 1000-sample verification (spawned binary)",
        |b| {
            b.iter(|| {
                let out = Command::new(exe)
                    .args(["extract", path.as_str(), "--samples", "1000"])
                    .output()
                    .expect("run urdf-dh");
                assert!(out.status.success());
                black_box(out.stdout)
            })
        },
    );
}

criterion_group!(
    benches,
    extract_in_process,
    extract_yaml_in_process,
    extract_process
);
criterion_main!(benches);
