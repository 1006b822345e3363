//! The proof on the artefact: how far a table written at a given precision may stray from the
//! one it was written from, and the check of what was written against the source.
//!
//! A table leaves the program as decimal text (a YAML sheet, a fixed-decimal text table, a
//! URDF). What the user receives is that text read back, not the table in memory, so the
//! self-check reads the written text back and compares *that* with the source (the URDF, the
//! input sheet, the fitted model) by forward kinematics. The bound it must meet is the source's
//! own bound (snapping, float arithmetic) plus what the written precision allows:
//! [`written_bound`].

use std::borrow::Borrow;

use nalgebra::Isometry3;

use crate::extract::Bound;
use crate::pose::pose_error;
use crate::table::{DhTable, JointKind, PreparedFk};
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
/// Joint values the oracle may draw and evaluate ahead of the written side (32 MB of them):
/// room for the oracle to run while [`compare_while_writing`]'s table is still being written.
const PIPELINE_AHEAD_JOINTS: usize = 4_000_000;

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
    compare_while_writing(source, oracle, samples, seed, || Ok(written)).map(|(_, dev)| dev)
}

/// [`compare_written`] of the table that `write` makes (renders and reads back) on the calling
/// thread while the oracle already runs: on a second thread, from [`PIPELINE_MIN_JOINTS`] joint
/// evaluations, drawing and evaluating up to some 4 million joint values ahead; once `write`
/// returns, the written side's evaluations run on every core. For a long chain, whose oracle
/// costs about as much as writing and reading back its table. Returns the written table with
/// the figures, the same as [`compare_written`]'s.
///
/// # Errors
/// `write`'s error (the oracle then stops); [`CoreError::JointCount`] when the tables differ in
/// length.
pub fn compare_while_writing<F, W, E>(
    source: &DhTable,
    oracle: F,
    samples: usize,
    seed: u64,
    write: impl FnOnce() -> Result<W, E>,
) -> Result<(W, Deviation), E>
where
    F: FnMut(&[f64]) -> Isometry3<f64> + Send,
    W: Borrow<DhTable>,
    E: From<CoreError>,
{
    compare_from(source, oracle, samples, seed, PIPELINE_MIN_JOINTS, write)
}

/// The written table as the comparison reads it: its prepared FK and how its mimic rows
/// follow their written driver. Made once, read by every thread ([`Written::side`]).
struct Written<'a> {
    prepared: PreparedFk<'a>,
    /// Per written row: `(driver, multiplier, offset)` of a mimic row.
    follows: Vec<Option<(usize, f64, f64)>>,
}

impl<'a> Written<'a> {
    /// The written table compared with a source of `n` rows.
    ///
    /// # Errors
    /// [`CoreError::JointCount`] when it has another number of rows.
    fn new(written: &'a DhTable, n: usize) -> Result<Self, CoreError> {
        if written.rows.len() != n {
            return Err(CoreError::JointCount {
                expected: n,
                found: written.rows.len(),
            });
        }
        // Written mimic rows follow their written driver (by name, among the written rows).
        let follows = written
            .rows
            .iter()
            .enumerate()
            .map(|(i, r)| {
                let m = r.mimic.as_ref()?;
                let driver = written.rows.iter().position(|d| d.name == m.joint)?;
                (driver != i).then_some((driver, m.multiplier, m.offset))
            })
            .collect();
        Ok(Written {
            prepared: written.prepare(),
            follows,
        })
    }

    /// A thread's evaluator of the written table, with its own buffers.
    fn side(&self) -> WrittenSide<'_> {
        let n = self.follows.len();
        WrittenSide {
            prepared: &self.prepared,
            follows: &self.follows,
            qw: vec![0.0; n],
            done: vec![true; n],
        }
    }
}

/// The written side of the comparison on one thread: the written table's FK at the source's
/// joint values, its mimic rows following their written driver.
struct WrittenSide<'a> {
    prepared: &'a PreparedFk<'a>,
    follows: &'a [Option<(usize, f64, f64)>],
    /// The written rows' values and which of them are known.
    qw: Vec<f64>,
    done: Vec<bool>,
}

impl WrittenSide<'_> {
    /// The written table's tip pose at the source's joint values `q`, its mimic rows resolved
    /// in dependency order (at most n passes, as the sampler does).
    fn pose(&mut self, q: &[f64]) -> Result<Isometry3<f64>, CoreError> {
        let n = self.follows.len();
        for (i, f) in self.follows.iter().enumerate() {
            self.qw[i] = q[i];
            self.done[i] = f.is_none();
        }
        for _ in 0..n {
            let mut open = false;
            for (i, f) in self.follows.iter().enumerate() {
                if let (Some((driver, m, o)), false) = (f, self.done[i]) {
                    if self.done[*driver] {
                        self.qw[i] = m * self.qw[*driver] + o;
                        self.done[i] = true;
                    } else {
                        open = true;
                    }
                }
            }
            if !open {
                break;
            }
        }
        self.prepared.fk(&self.qw)
    }
}

/// [`compare_while_writing`] with the oracle on a second thread from `pipeline_from` joint
/// evaluations (the tests compare both ways on one chain).
fn compare_from<F, W, E>(
    source: &DhTable,
    mut oracle: F,
    samples: usize,
    seed: u64,
    pipeline_from: usize,
    write: impl FnOnce() -> Result<W, E>,
) -> Result<(W, Deviation), E>
where
    F: FnMut(&[f64]) -> Isometry3<f64> + Send,
    W: Borrow<DhTable>,
    E: From<CoreError>,
{
    let n = source.rows.len();
    let mut sampler = JointSampler::new(&source.rows, source.size(), seed);
    let count = samples.max(1);
    if n == 0 || n.saturating_mul(count) < pipeline_from {
        let written = write()?;
        let w = Written::new(written.borrow(), n)?;
        let mut side = w.side();
        let (mut dev, mut q) = (Deviation::new(), Vec::with_capacity(n));
        for _ in 0..count {
            sampler.next_into(&mut q);
            dev.record(pose_error(&side.pose(&q)?, &oracle(&q)));
        }
        return Ok((written, dev));
    }
    // A long proof: the oracle draws the samples and evaluates them on a second thread while
    // this one writes the table, then evaluates the written table at the same draws (sent with
    // the oracle's poses, a block at a time) on every core. The figures are maxima over the
    // samples: the same whichever thread takes which block.
    let block = (PIPELINE_BLOCK_JOINTS / n).max(1);
    let ahead = (PIPELINE_AHEAD_JOINTS / (block * n)).max(1);
    crate::parallel::pipeline(
        ahead,
        move |send| {
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
        |blocks| -> Result<(W, Deviation), E> {
            let written = write()?;
            let w = Written::new(written.borrow(), n)?;
            let parts = crate::parallel::on_each_core(|| -> Result<Deviation, CoreError> {
                let mut side = w.side();
                let mut dev = Deviation::new();
                for drawn in blocks {
                    for (q, theirs) in drawn.q.chunks_exact(n).zip(&drawn.poses) {
                        dev.record(pose_error(&side.pose(q)?, theirs));
                    }
                }
                Ok(dev)
            });
            let mut dev = Deviation::new();
            for part in parts {
                dev.merge(&part?);
            }
            Ok((written, dev))
        },
    )
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

    /// 60 rows: the arm's four, its mimic row included, fifteen times.
    fn long_arm() -> DhTable {
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
        t
    }

    #[test]
    fn while_writing_the_writers_error_or_a_wrong_length_is_the_answer() {
        let t = long_arm();
        let source = t.prepare();
        let oracle = |q: &[f64]| source.fk(q).unwrap_or_default();
        for pipeline_from in [0, usize::MAX] {
            // The writer's own error (one the comparison cannot give: 1 row expected).
            let theirs = || CoreError::JointCount {
                expected: 1,
                found: 2,
            };
            let failed: Result<(&DhTable, Deviation), CoreError> =
                compare_from(&t, oracle, 700, 9, pipeline_from, || Err(theirs()));
            assert_eq!(failed.err(), Some(theirs()));
            let mut short = t.clone();
            short.rows.pop();
            let r = compare_from(&t, oracle, 700, 9, pipeline_from, || {
                Ok::<_, CoreError>(&short)
            });
            assert!(
                matches!(
                    r,
                    Err(CoreError::JointCount {
                        expected: 60,
                        found: 59
                    })
                ),
                "{r:?}"
            );
        }
        // A table written off its source, owned by the writer, on the pipeline: it comes back
        // with the figures compare_written gives on one thread, and they are not zero.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(8);
        let off = perturbed(&t, Precision::rounded(0.5e-6, 0.5e-6), &mut rng);
        let (w, dev) = compare_from(&t, oracle, 700, 9, 0, || Ok::<_, CoreError>(off.clone()))
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(w, off);
        assert!(dev.max_position_error > 0.0 && dev.max_orientation_error > 0.0);
        assert_eq!(Some(dev), compare_written(&off, &t, oracle, 700, 9).ok());
    }

    #[test]
    fn the_oracle_on_its_own_thread_gives_the_same_figures_in_order() {
        // 60 rows, 700 samples: 42 000 joint evaluations, several blocks of oracle poses.
        let t = long_arm();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let w = perturbed(&t, Precision::rounded(0.5e-6, 0.5e-6), &mut rng);
        let source = t.prepare();
        let run = |pipeline_from: usize| {
            let mut seen = Vec::new();
            let (_, dev) = compare_from(
                &t,
                |q: &[f64]| {
                    seen.push(q.to_vec());
                    source.fk(q).unwrap_or_default()
                },
                700,
                9,
                pipeline_from,
                || Ok::<_, CoreError>(&w),
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
