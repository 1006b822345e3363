//! The proof on the artefact: how far a table written at a given precision may stray from the
//! one it was written from, and the check of what was written against the source.
//!
//! A table leaves the program as decimal text (a YAML sheet, a fixed-decimal text table, a
//! URDF). What the user receives is that text read back, not the table in memory, so the
//! self-check reads the written text back and compares *that* with the source (the URDF, the
//! input sheet, the fitted model) by forward kinematics. The bound it must meet is the source's
//! own bound (snapping, float arithmetic) plus what the written precision allows:
//! [`written_bound`].

use nalgebra::Isometry3;

use crate::extract::Bound;
use crate::pose::pose_error;
use crate::table::{DhTable, JointKind};
use crate::verify::{Deviation, JointSampler};
use crate::CoreError;

/// The precision at which a table is written: the largest rounding error of one written value.
///
/// `length` is in metres and `angle` in radians (half the step of the last printed decimal, plus
/// any snapping the writer does); `relative` covers the float error of unit conversion and of
/// the shortest round-trip decimal form, per unit of the value's magnitude.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Precision {
    /// Largest absolute rounding of a written length (metres).
    pub length: f64,
    /// Largest absolute rounding of a written angle (radians).
    pub angle: f64,
    /// Largest relative error of any written value (dimensionless).
    pub relative: f64,
}

impl Precision {
    /// Four machine epsilons per value: unit conversion (one multiply or divide), the decimal
    /// round trip (half an ulp) and the reader's conversion back, with margin.
    pub const FLOAT_RELATIVE: f64 = 4.0 * f64::EPSILON;

    /// Values written in full (shortest round-trip form) after rounding to `length` metres and
    /// `angle` radians.
    pub fn rounded(length: f64, angle: f64) -> Precision {
        Precision {
            length,
            angle,
            relative: Self::FLOAT_RELATIVE,
        }
    }
}

/// The largest tip deviation (position in metres, orientation in radians) that writing `table`
/// at `precision` can cause, to first order in the rounding.
///
/// Every written length (`a`, `d`, base and tool translations, prismatic mimic offsets) moves
/// the tip by at most its own rounding; every written angle (`alpha`, `theta`, the three base
/// and tool `rpy` angles, revolute mimic offsets) turns the rest of the chain by at most its
/// rounding, which moves the tip by at most that angle times the chain's size
/// ([`DhTable::size`], prismatic travel included), since every point of the chain lies within
/// that distance of every joint. Rounding errors add (triangle inequality); a one-percent
/// margin covers the second-order terms. A mimic multiplier `m` rounded by `e` moves its joint
/// by at most `e` times the driver's range.
pub fn written_bound(table: &DhTable, precision: Precision) -> Bound {
    let size = table.size();
    let (mut position, mut orientation) = (0.0, 0.0);
    let mut lengths: Vec<f64> = Vec::with_capacity(2 * table.rows.len() + 8);
    lengths.extend(table.base.translation.vector.iter());
    lengths.extend(table.tool.translation.vector.iter());
    let mut angles = Vec::with_capacity(2 * table.rows.len() + 8);
    for r in &table.rows {
        lengths.push(r.a);
        lengths.push(r.d);
        angles.push(r.alpha);
        angles.push(r.theta);
        if r.beta != 0.0 {
            angles.push(r.beta);
        }
    }
    let range = |kind: JointKind, limits: Option<crate::table::Limits>| match (kind, limits) {
        (_, Some(l)) => l.lower.abs().max(l.upper.abs()),
        (JointKind::Revolute, None) => std::f64::consts::PI,
        (JointKind::Prismatic, None) => size,
    };
    for r in &table.rows {
        if let Some(m) = &r.mimic {
            let driver = table.rows.iter().find(|d| d.name == m.joint);
            let reach = driver.map_or(std::f64::consts::PI, |d| range(d.kind, d.limits));
            let moved = precision.relative * m.multiplier.abs() * reach;
            match r.kind {
                JointKind::Revolute => {
                    angles.push(m.offset);
                    orientation += moved;
                    position += moved * size;
                }
                JointKind::Prismatic => {
                    lengths.push(m.offset);
                    position += moved;
                }
            }
        }
    }
    for rpy in [
        crate::pose::rpy_of(&table.base.rotation.to_rotation_matrix()),
        crate::pose::rpy_of(&table.tool.rotation.to_rotation_matrix()),
    ] {
        angles.extend_from_slice(&rpy);
    }
    for v in lengths {
        position += precision.length + precision.relative * v.abs();
    }
    for a in angles {
        let e = precision.angle + precision.relative * a.abs();
        orientation += e;
        position += e * size;
    }
    Bound {
        position: 1.01 * position,
        orientation: 1.01 * orientation,
    }
}

/// Joint evaluations (rows times samples) from which [`compare_written`] runs its oracle on a
/// second thread; below, one thread does both sides (a thread costs more than the work).
pub const PIPELINE_MIN_JOINTS: usize = 100_000;
/// Joint evaluations of the oracle sent to the written side at a time.
const PIPELINE_BLOCK_JOINTS: usize = 20_000;
/// Blocks of oracle poses that may wait for the written side.
const PIPELINE_BLOCKS: usize = 4;

/// Samples drawn and evaluated by [`compare_written`]'s oracle, sent to the written side.
struct SampleBlock {
    /// Joint values of sample `k` at `q[k * n..(k + 1) * n]`.
    q: Vec<f64>,
    /// The oracle's pose at each sample.
    poses: Vec<Isometry3<f64>>,
}

impl SampleBlock {
    fn with_capacity(samples: usize, n: usize) -> SampleBlock {
        SampleBlock {
            q: Vec::with_capacity(samples * n),
            poses: Vec::with_capacity(samples),
        }
    }
}

/// Compares a `written` table (read back from what was written) with `oracle` at `samples`
/// joint values drawn from the `source` table it was written from ([`JointSampler`] with
/// `seed`, the same draws as [`crate::compare`] on `source`).
///
/// The oracle sees the source's joint values, mimic rows following their driver by the
/// source's own coupling; the written table sees the same independent values, its mimic rows
/// following their driver by the *written* coupling, so that a coupling written wrong is
/// caught. Rows are matched by position; the caller checks that both tables have the same rows.
///
/// # Errors
/// [`CoreError::JointCount`] when the tables differ in length.
pub fn compare_written<F>(
    written: &DhTable,
    source: &DhTable,
    oracle: F,
    samples: usize,
    seed: u64,
) -> Result<Deviation, CoreError>
where
    F: FnMut(&[f64]) -> Isometry3<f64> + Send,
{
    compare_written_from(written, source, oracle, samples, seed, PIPELINE_MIN_JOINTS)
}

/// [`compare_written`] with the oracle on a second thread from `pipeline_from` joint
/// evaluations (the tests compare both ways on one chain).
fn compare_written_from<F>(
    written: &DhTable,
    source: &DhTable,
    mut oracle: F,
    samples: usize,
    seed: u64,
    pipeline_from: usize,
) -> Result<Deviation, CoreError>
where
    F: FnMut(&[f64]) -> Isometry3<f64> + Send,
{
    let n = source.rows.len();
    if written.rows.len() != n {
        return Err(CoreError::JointCount {
            expected: n,
            found: written.rows.len(),
        });
    }
    // Written mimic rows follow their written driver (by name, among the written rows); resolved
    // in dependency order, at most n passes, as the sampler does.
    let follows: Vec<Option<(usize, f64, f64)>> = written
        .rows
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let m = r.mimic.as_ref()?;
            let driver = written.rows.iter().position(|d| d.name == m.joint)?;
            (driver != i).then_some((driver, m.multiplier, m.offset))
        })
        .collect();
    let sampler = JointSampler::new(&source.rows, source.size(), seed);
    let prepared = written.prepare();
    let count = samples.max(1);
    // The written side of sample `k`: the source's values in `q`, the written rows' values and
    // which of them are known in the buffers.
    let mut qw = vec![0.0; n];
    let mut done = vec![true; n];
    let mut written_pose = |q: &[f64]| -> Result<Isometry3<f64>, CoreError> {
        for (i, f) in follows.iter().enumerate() {
            qw[i] = q[i];
            done[i] = f.is_none();
        }
        for _ in 0..n {
            let mut open = false;
            for (i, f) in follows.iter().enumerate() {
                if let (Some((driver, m, o)), false) = (f, done[i]) {
                    if done[*driver] {
                        qw[i] = m * qw[*driver] + o;
                        done[i] = true;
                    } else {
                        open = true;
                    }
                }
            }
            if !open {
                break;
            }
        }
        prepared.fk(&qw)
    };
    let mut dev = Deviation::new();
    if n == 0 || n.saturating_mul(count) < pipeline_from {
        let (mut sampler, mut q) = (sampler, Vec::with_capacity(n));
        for _ in 0..count {
            sampler.next_into(&mut q);
            dev.record(pose_error(&written_pose(&q)?, &oracle(&q)));
        }
        return Ok(dev);
    }
    // A long proof: the oracle draws the samples and evaluates them on a second thread while
    // this one evaluates the written table at the same draws (sent with the oracle's poses, a
    // block at a time), their poses paired in sample order (the same figures).
    let mut sampler = sampler;
    crate::parallel::pipeline(
        PIPELINE_BLOCKS,
        move |send| {
            let block = (PIPELINE_BLOCK_JOINTS / n).max(1);
            let mut q = Vec::with_capacity(n);
            let mut drawn = SampleBlock::with_capacity(block, n);
            for k in 0..count {
                sampler.next_into(&mut q);
                drawn.poses.push(oracle(&q));
                drawn.q.extend_from_slice(&q);
                if (drawn.poses.len() == block || k + 1 == count)
                    && !send(std::mem::replace(
                        &mut drawn,
                        SampleBlock::with_capacity(block, n),
                    ))
                {
                    return;
                }
            }
        },
        |blocks| -> Result<(), CoreError> {
            for drawn in blocks {
                for (q, theirs) in drawn.q.chunks_exact(n).zip(&drawn.poses) {
                    dev.record(pose_error(&written_pose(q)?, theirs));
                }
            }
            Ok(())
        },
    )?;
    Ok(dev)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pose::from_xyz_rpy;
    use crate::table::{DhRow, Limits, Mimic};
    use crate::Convention;
    use rand::{Rng, SeedableRng};

    fn arm() -> DhTable {
        let mut rows = vec![
            DhRow::revolute("j1", 0.1, std::f64::consts::FRAC_PI_2, 0.4, 0.2),
            DhRow::revolute("j2", 0.7, 0.0, 0.0, -1.1),
            DhRow::prismatic("j3", 0.05, -std::f64::consts::FRAC_PI_2, 0.3, 0.0),
            DhRow::revolute("j4", 0.0, 0.9, 0.25, 0.4),
        ];
        rows[2].limits = Some(Limits {
            lower: -0.2,
            upper: 0.5,
        });
        rows[3].mimic = Some(Mimic {
            joint: "j2".into(),
            multiplier: -1.5,
            offset: 0.3,
        });
        DhTable {
            convention: Convention::Standard,
            base: from_xyz_rpy(
                [0.1, -0.2, 0.3],
                [0.4, std::f64::consts::FRAC_PI_2 - 1e-4, -2.0],
            ),
            tool: from_xyz_rpy([0.0, 0.05, 0.12], [3.0, -0.3, 1.0]),
            rows,
        }
    }

    /// Every value of `t` moved by up to its precision, at random.
    fn perturbed(t: &DhTable, p: Precision, rng: &mut impl Rng) -> DhTable {
        let mut t = t.clone();
        let mut e =
            |v: f64, abs: f64| v + rng.random_range(-1.0..=1.0) * (abs + p.relative * v.abs());
        for r in &mut t.rows {
            r.a = e(r.a, p.length);
            r.d = e(r.d, p.length);
            r.alpha = e(r.alpha, p.angle);
            r.theta = e(r.theta, p.angle);
            if let Some(m) = &mut r.mimic {
                m.offset = e(m.offset, p.angle);
                m.multiplier = e(m.multiplier, 0.0);
            }
        }
        for pose in [&mut t.base, &mut t.tool] {
            let (xyz, rpy) = crate::pose::to_xyz_rpy(pose);
            *pose = from_xyz_rpy(xyz.map(|v| e(v, p.length)), rpy.map(|v| e(v, p.angle)));
        }
        t
    }

    #[test]
    fn rounding_within_the_precision_stays_within_the_bound() {
        let t = arm();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for p in [
            Precision::rounded(0.5e-6, 0.5e-6),
            Precision::rounded(0.5e-3, 0.5e-3),
            Precision::rounded(0.0, 0.0),
        ] {
            let bound = written_bound(&t, p);
            let mut worst = (0.0f64, 0.0f64);
            for _ in 0..200 {
                let w = perturbed(&t, p, &mut rng);
                let source = t.prepare();
                let dev = compare_written(&w, &t, |q| source.fk(q).unwrap_or_default(), 50, 1)
                    .unwrap_or_else(|e| panic!("{e}"));
                worst.0 = worst.0.max(dev.max_position_error);
                worst.1 = worst.1.max(dev.max_orientation_error);
            }
            assert!(worst.0 <= bound.position, "{worst:?} vs {bound:?}");
            assert!(worst.1 <= bound.orientation, "{worst:?} vs {bound:?}");
            // The bound is not vacuous: the worst case found is within a factor 20 of it.
            if p.length > 0.0 {
                assert!(worst.0 > bound.position / 20.0, "{worst:?} vs {bound:?}");
            }
        }
    }

    #[test]
    fn the_oracle_on_its_own_thread_gives_the_same_figures_in_order() {
        // 60 rows (the arm's four, its mimic row included, fifteen times), 700 samples: 42 000
        // joint evaluations, several blocks of oracle poses.
        let arm = arm();
        let mut t = arm.clone();
        t.rows = (0..15)
            .flat_map(|k| {
                arm.rows.iter().map(move |r| {
                    let mut r = r.clone();
                    r.name = format!("{}_{k}", r.name);
                    if let Some(m) = &mut r.mimic {
                        m.joint = format!("{}_{k}", m.joint);
                    }
                    r
                })
            })
            .collect();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let w = perturbed(&t, Precision::rounded(0.5e-6, 0.5e-6), &mut rng);
        let source = t.prepare();
        let run = |pipeline_from: usize| {
            let mut seen = Vec::new();
            let dev = compare_written_from(
                &w,
                &t,
                |q: &[f64]| {
                    seen.push(q.to_vec());
                    source.fk(q).unwrap_or_default()
                },
                700,
                9,
                pipeline_from,
            )
            .unwrap_or_else(|e| panic!("{e}"));
            (dev, seen)
        };
        let (one, seen_one) = run(usize::MAX);
        let (two, seen_two) = run(0);
        assert_eq!(one, two);
        assert_eq!(one.samples, 700);
        assert!(one.max_position_error > 0.0);
        // The oracle saw every sample once, in the sampler's order, on either path.
        assert_eq!(seen_one, seen_two);
        let mut sampler = JointSampler::new(&t.rows, t.size(), 9);
        let mut q = Vec::new();
        for seen in &seen_one {
            sampler.next_into(&mut q);
            assert_eq!(seen, &q);
        }
    }

    #[test]
    fn a_written_coupling_that_is_wrong_is_caught() {
        let t = arm();
        let mut w = t.clone();
        if let Some(m) = &mut w.rows[3].mimic {
            m.offset += 1e-3;
        }
        let source = t.prepare();
        let dev = compare_written(&w, &t, |q| source.fk(q).unwrap_or_default(), 20, 1)
            .unwrap_or_else(|e| panic!("{e}"));
        assert!(dev.max_orientation_error > 0.9e-3, "{dev:?}");
        let same = compare_written(&t, &t, |q| source.fk(q).unwrap_or_default(), 20, 1)
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(same.max_position_error, 0.0);
    }

    #[test]
    fn tables_of_other_lengths_are_refused() {
        let t = arm();
        let mut w = t.clone();
        w.rows.pop();
        let source = t.prepare();
        assert!(compare_written(&w, &t, |q| source.fk(q).unwrap_or_default(), 5, 1).is_err());
    }
}
