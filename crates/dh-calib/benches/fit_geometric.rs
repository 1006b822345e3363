//! Geometric calibration speed: 150 poses of a 6R arm (target: 20 ms for the geometric step),
//! the per-sample cost of the model's residuals and analytic Jacobian (what every Gauss-Newton
//! pass over a large set spends most of its time on) and 100 000 samples (target: 10 s, memory
//! linear in the samples).
#![allow(missing_docs)]

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use dh_calib::calibrate::{calibrate, CalibrationOptions};
use dh_calib::data::{Measurements, Split};
use dh_calib::fit::{self, FitOptions};
use dh_calib::model::{Block, Model, ModelOptions, ModelProblem, Observation, Observed};
use dh_calib::simulate::{simulate, Errors, SimulationOptions};
use dh_core::{Convention, DhRow, DhTable, Limits};
use nalgebra::Isometry3;

fn kr_like() -> DhTable {
    use std::f64::consts::{FRAC_PI_2, PI};
    let lim = |mut r: DhRow, lo: f64, hi: f64| {
        r.limits = Some(Limits {
            lower: lo.to_radians(),
            upper: hi.to_radians(),
        });
        r
    };
    DhTable {
        convention: Convention::Standard,
        base: Isometry3::identity(),
        tool: Isometry3::identity(),
        rows: vec![
            lim(
                DhRow::revolute("a1", 0.35, -FRAC_PI_2, 0.675, 0.0),
                -185.0,
                185.0,
            ),
            lim(
                DhRow::revolute("a2", 1.15, 0.0, 0.0, -FRAC_PI_2),
                -140.0,
                -5.0,
            ),
            lim(
                DhRow::revolute("a3", 0.041, FRAC_PI_2, 0.0, 0.0),
                -120.0,
                155.0,
            ),
            lim(
                DhRow::revolute("a4", 0.0, -FRAC_PI_2, -1.2, 0.0),
                -350.0,
                350.0,
            ),
            lim(
                DhRow::revolute("a5", 0.0, FRAC_PI_2, 0.0, 0.0),
                -125.0,
                125.0,
            ),
            lim(DhRow::revolute("a6", 0.0, PI, -0.215, 0.0), -350.0, 350.0),
        ],
    }
}

fn data(poses: usize, validation: f64) -> Measurements {
    let (d, _) = simulate(
        &kr_like(),
        &SimulationOptions {
            poses,
            sigma: 5e-5,
            errors: Errors::Random {
                length: 1e-3,
                angle: 0.05_f64.to_radians(),
            },
            validation_fraction: validation,
            ..Default::default()
        },
    )
    .unwrap();
    d
}

/// The model after a full calibration with its device frame and targets, the calibration
/// observations, zero errors and the free set: solving from there is the geometric step.
fn setup(table: &DhTable, data: &Measurements) -> (Model, Vec<Observed>, Vec<f64>, Vec<usize>) {
    let report = calibrate(table, data, &CalibrationOptions::default()).unwrap();
    let mut model = Model::new(table, &data.targets, &ModelOptions::default()).unwrap();
    model.set_device(&report.device);
    for (k, (_, t)) in report.targets.iter().enumerate() {
        model.set_target(k, *t);
    }
    let obs: Vec<Observed> = data
        .samples
        .iter()
        .filter(|s| s.split == Split::Calibration)
        .map(|s| Observed {
            session: 0,
            q: s.q.clone(),
            observation: Observation::Point {
                target: s.target,
                point: s.point,
            },
            context: Default::default(),
        })
        .collect();
    let fixed: Vec<usize> = report
        .fixed
        .iter()
        .filter_map(|f| model.index_of(&f.name))
        .collect();
    let free: Vec<usize> = model
        .indices(|b| !matches!(b, Block::Effect(_)))
        .into_iter()
        .filter(|i| !fixed.contains(i))
        .collect();
    let x = vec![0.0; model.parameter_count()];
    (model, obs, x, free)
}

fn bench(c: &mut Criterion) {
    let table = kr_like();
    let small = data(150, 0.0);
    let (model, obs, x0, free) = setup(&table, &small);
    let scales = model.scales();
    let problem = ModelProblem {
        model: &model,
        observations: &obs,
    };
    let mut g = c.benchmark_group("150 poses");
    g.bench_function("geometric step", |b| {
        b.iter(|| {
            fit::solve(
                &problem,
                black_box(&x0),
                &free,
                &scales,
                &FitOptions::default(),
            )
            .unwrap()
        })
    });
    g.bench_function("identifiability", |b| {
        let all = model.indices(|b| !matches!(b, Block::Effect(_)));
        let prio: Vec<u32> = all.iter().map(|&i| model.priorities()[i]).collect();
        b.iter(|| {
            let f = fit::factor(&problem, &x0, &all, &scales).unwrap();
            fit::identifiability(&f.r, &vec![1.0; all.len()], &prio, 1e-6).unwrap()
        })
    });
    g.finish();

    // One Gauss-Newton pass's model work per sample, at fitted parameters (every op of the
    // chain away from zero, as after a fit's first step): residuals alone, and residuals with
    // the Jacobian of the free columns. Criterion reports the time per sample.
    let fitted = fit::solve(&problem, &x0, &free, &scales, &FitOptions::default())
        .unwrap()
        .x;
    let mut g = c.benchmark_group("per sample");
    g.throughput(Throughput::Elements(obs.len() as u64));
    g.bench_function("residuals", |b| {
        let mut r = [0.0; 3];
        b.iter(|| {
            for o in &obs {
                model.residuals(black_box(&fitted), o, &mut r);
                black_box(&r);
            }
        })
    });
    g.bench_function("residuals and Jacobian", |b| {
        let (mut r, mut j) = ([0.0; 3], vec![0.0; 3 * free.len()]);
        b.iter(|| {
            for o in &obs {
                model.jacobian(black_box(&fitted), o, &free, &mut r, &mut j);
                black_box(&j);
            }
        })
    });
    g.finish();

    let mut g = c.benchmark_group("150 poses");
    let held_out = data(150, 0.2);
    g.bench_function("calibrate, validation split", |b| {
        b.iter(|| calibrate(&table, black_box(&held_out), &CalibrationOptions::default()).unwrap())
    });
    g.bench_function("calibrate, 5-fold cross-validation", |b| {
        b.iter(|| calibrate(&table, black_box(&small), &CalibrationOptions::default()).unwrap())
    });
    g.finish();

    let large = data(100_000, 0.1);
    let mut g = c.benchmark_group("100000 samples");
    g.sample_size(10).measurement_time(Duration::from_secs(30));
    g.bench_function("calibrate, validation split", |b| {
        b.iter(|| calibrate(&table, black_box(&large), &CalibrationOptions::default()).unwrap())
    });
    // One factor pass over every calibration sample at the nominal point: beyond
    // `fit::SEGMENT_BLOCKS` blocks, the Gram matrix of the scaled Jacobian on every core (the
    // QR when it is ill-conditioned), a pass of each large fit's iterations.
    let (model, obs, x0, free) = setup(&table, &large);
    let scales = model.scales();
    let problem = ModelProblem {
        model: &model,
        observations: &obs,
    };
    g.throughput(Throughput::Elements(obs.len() as u64));
    g.bench_function("factor of the geometric columns", |b| {
        b.iter(|| fit::factor(&problem, black_box(&x0), &free, &scales).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
