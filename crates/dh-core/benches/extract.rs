//! Speed of the extraction core: a 7-joint arm (Panda-like), and chains of 10, 100, 1000
//! joints to show linear growth.

use std::f64::consts::FRAC_PI_2;
use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use dh_core::{extract, Convention, DhRow, DhTable, JointAxis, JointKind, Line, Tolerance};
use nalgebra::Isometry3;

/// Axis lines of a table at q = 0: z axes of its frames (standard convention).
fn axes_of(table: &DhTable) -> (Vec<JointAxis>, Isometry3<f64>) {
    let q = vec![0.0; table.rows.len()];
    let frames = table.frames(&q).expect("joint count");
    let axes = table
        .rows
        .iter()
        .zip(&frames)
        .map(|(r, f)| JointAxis {
            name: r.name.clone(),
            kind: JointKind::Revolute,
            line: Line::through(f.translation.vector, f.rotation * nalgebra::Vector3::z())
                .expect("finite"),
            limits: None,
            mimic: None,
        })
        .collect();
    (axes, table.fk(&q).expect("joint count"))
}

fn panda_like() -> DhTable {
    let rows = [
        (0.0, -FRAC_PI_2, 0.333),
        (0.0, FRAC_PI_2, 0.0),
        (0.0825, FRAC_PI_2, 0.316),
        (-0.0825, -FRAC_PI_2, 0.0),
        (0.0, FRAC_PI_2, 0.384),
        (0.088, FRAC_PI_2, 0.0),
        (0.0, 0.0, 0.107),
    ];
    DhTable {
        convention: Convention::Standard,
        base: Isometry3::identity(),
        tool: Isometry3::identity(),
        rows: rows
            .iter()
            .enumerate()
            .map(|(i, &(a, alpha, d))| {
                DhRow::revolute(&format!("j{i}"), a, alpha, d, 0.1 * i as f64)
            })
            .collect(),
    }
}

/// A long chain mixing every pair class: skew, parallel, intersecting, coincident.
fn long_chain(n: usize) -> DhTable {
    let pattern = [
        (0.1, FRAC_PI_2, 0.05),
        (0.2, 0.0, 0.0),
        (0.0, -FRAC_PI_2, 0.1),
        (0.0, 0.0, 0.0),
        (0.05, 0.3, 0.02),
    ];
    DhTable {
        convention: Convention::Standard,
        base: Isometry3::identity(),
        tool: Isometry3::identity(),
        rows: (0..n)
            .map(|i| {
                let (a, alpha, d) = pattern[i % pattern.len()];
                DhRow::revolute(&format!("j{i}"), a, alpha, d, 0.0)
            })
            .collect(),
    }
}

fn bench(c: &mut Criterion) {
    let (axes, tip) = axes_of(&panda_like());
    c.bench_function("extract 7-joint arm", |b| {
        b.iter(|| {
            extract(
                black_box(&axes),
                black_box(&tip),
                Tolerance::default(),
                Convention::Standard,
            )
        })
    });
    let table = panda_like();
    let q = [0.1, -0.2, 0.3, -1.5, 0.4, 1.2, -0.3];
    c.bench_function("fk 7-joint arm", |b| b.iter(|| table.fk(black_box(&q))));

    let mut group = c.benchmark_group("extract n-joint chain");
    for n in [10usize, 100, 1000] {
        let (axes, tip) = axes_of(&long_chain(n));
        group.throughput(Throughput::Elements(n as u64));
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| {
                extract(
                    black_box(&axes),
                    black_box(&tip),
                    Tolerance::default(),
                    Convention::Standard,
                )
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
