//! The paper's own check, made stronger: forward kinematics of a DH table against an independent
//! oracle (the URDF's own transform of the tip link) at many joint values, not one.

use nalgebra::Isometry3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::pose::pose_error;
use crate::table::{DhRow, DhTable, JointKind};
use crate::CoreError;

/// The largest deviations found over a set of joint values.
#[derive(Clone, Debug, PartialEq)]
pub struct Deviation {
    /// Joint-value samples compared (the zero pose is always the first).
    pub samples: usize,
    /// Largest tip position deviation (metres).
    pub max_position_error: f64,
    /// Largest tip orientation deviation (radians).
    pub max_orientation_error: f64,
}

impl Deviation {
    /// No sample yet.
    pub fn new() -> Deviation {
        Deviation {
            samples: 0,
            max_position_error: 0.0,
            max_orientation_error: 0.0,
        }
    }

    /// Counts one sample's position and orientation errors (metres, radians). A NaN counts as
    /// infinite: it must never pass as "small", and `max` would drop it.
    pub fn record(&mut self, (dp, dr): (f64, f64)) {
        let worse = |max: f64, e: f64| {
            if e.is_nan() {
                f64::INFINITY
            } else {
                max.max(e)
            }
        };
        self.max_position_error = worse(self.max_position_error, dp);
        self.max_orientation_error = worse(self.max_orientation_error, dr);
        self.samples += 1;
    }

    /// Counts the samples of `other` too: the figures of both sets of samples together, the
    /// same whatever the order in which sets are merged.
    pub fn merge(&mut self, other: &Deviation) {
        self.max_position_error = self.max_position_error.max(other.max_position_error);
        self.max_orientation_error = self.max_orientation_error.max(other.max_orientation_error);
        self.samples += other.samples;
    }
}

impl Default for Deviation {
    fn default() -> Self {
        Deviation::new()
    }
}

/// How one row's value is drawn.
#[derive(Clone, Copy, Debug)]
enum Draw {
    Uniform {
        lower: f64,
        upper: f64,
    },
    Follows {
        driver: usize,
        multiplier: f64,
        offset: f64,
    },
}

/// Draws joint values for a table's rows: uniform within each joint's limits (continuous
/// joints, and joints whose limits are equal, over `[−pi, pi]`; unlimited prismatic joints over
/// `±size` of the chain), mimic rows
/// from their driver (`q = m q_driver + offset`) when the driver is a row too, else within their
/// own limits. Deterministic for a given seed.
#[derive(Clone, Debug)]
pub struct JointSampler {
    draws: Vec<Draw>,
    /// The following rows, each after its driver: one pass resolves every chain of drivers.
    order: Vec<usize>,
    rng: ChaCha8Rng,
    emitted: usize,
}

impl JointSampler {
    /// A sampler for `rows` with `seed`; `size` (metres) bounds unlimited prismatic joints.
    /// Linear in the number of rows: drivers are found by name once, and the rows that follow
    /// others are put in dependency order once; rows of a mimic cycle are drawn within their
    /// own limits.
    pub fn new(rows: &[DhRow], size: f64, seed: u64) -> Self {
        // A joint whose limits allow no motion is drawn as if unlimited: the table must be
        // right at every value, and a frozen joint would leave its row unchecked.
        let own = |r: &DhRow| match (r.limits.filter(|l| l.lower != l.upper), r.kind) {
            (Some(l), _) => Draw::Uniform {
                lower: l.lower.min(l.upper),
                upper: l.upper.max(l.lower),
            },
            (None, JointKind::Revolute) => Draw::Uniform {
                lower: -std::f64::consts::PI,
                upper: std::f64::consts::PI,
            },
            (None, JointKind::Prismatic) => Draw::Uniform {
                lower: -size,
                upper: size,
            },
        };
        let mut draws: Vec<Draw> = rows.iter().map(own).collect();
        let mut index: std::collections::HashMap<&str, usize> =
            std::collections::HashMap::with_capacity(rows.len());
        for (i, r) in rows.iter().enumerate() {
            index.entry(r.name.as_str()).or_insert(i);
        }
        for (i, r) in rows.iter().enumerate() {
            if let Some(m) = &r.mimic {
                if let Some(&driver) = index.get(m.joint.as_str()) {
                    if driver != i {
                        draws[i] = Draw::Follows {
                            driver,
                            multiplier: m.multiplier,
                            offset: m.offset,
                        };
                    }
                }
            }
        }
        // Dependency order, walking each chain of drivers once (0 unseen, 1 on the walk,
        // 2 placed).
        let mut state = vec![0u8; rows.len()];
        let mut order = Vec::new();
        for start in 0..rows.len() {
            let mut walk = Vec::new();
            let mut k = start;
            while state[k] == 0 {
                let Draw::Follows { driver, .. } = draws[k] else {
                    break;
                };
                state[k] = 1;
                walk.push(k);
                k = driver;
            }
            let mut placed = walk.clone();
            if state[k] == 1 {
                // A cycle: its rows move on their own; those leading into it follow them.
                let from = walk.iter().position(|&w| w == k).unwrap_or(0);
                for &c in &walk[from..] {
                    draws[c] = own(&rows[c]);
                }
                placed.truncate(from);
            }
            order.extend(placed.iter().rev());
            for w in walk {
                state[w] = 2;
            }
        }
        Self {
            draws,
            order,
            rng: ChaCha8Rng::seed_from_u64(seed),
            emitted: 0,
        }
    }

    /// Writes the next sample into `q` (one value per row). The first sample is the zero pose
    /// (mimic offsets applied).
    pub fn next_into(&mut self, q: &mut Vec<f64>) {
        let n = self.draws.len();
        q.clear();
        q.resize(n, 0.0);
        let zero = self.emitted == 0;
        self.emitted += 1;
        for (i, draw) in self.draws.iter().enumerate() {
            if let Draw::Uniform { lower, upper } = *draw {
                q[i] = if zero {
                    0.0_f64.clamp(lower, upper)
                } else if upper > lower {
                    self.rng.random_range(lower..=upper)
                } else {
                    lower
                };
            }
        }
        for &i in &self.order {
            if let Draw::Follows {
                driver,
                multiplier,
                offset,
            } = self.draws[i]
            {
                q[i] = multiplier * q[driver] + offset;
            }
        }
    }
}

/// Compares `table` with `oracle` (a function from the same joint values to the tip link's pose
/// in the base link frame) at `samples` joint values drawn by [`JointSampler`] with `seed`.
///
/// # Errors
/// [`CoreError::JointCount`] never in practice (the sampler draws one value per row).
pub fn compare<F>(
    table: &DhTable,
    mut oracle: F,
    samples: usize,
    seed: u64,
) -> Result<Deviation, CoreError>
where
    F: FnMut(&[f64]) -> Isometry3<f64>,
{
    let mut sampler = JointSampler::new(&table.rows, table.size(), seed);
    let mut q = Vec::with_capacity(table.rows.len());
    let prepared = table.prepare();
    let mut dev = Deviation::new();
    for _ in 0..samples.max(1) {
        sampler.next_into(&mut q);
        dev.record(pose_error(&prepared.fk(&q)?, &oracle(&q)));
    }
    Ok(dev)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::table::{Convention, Mimic};

    #[test]
    fn mimic_rows_follow_their_driver_and_zero_comes_first() {
        let mut rows = vec![
            DhRow::revolute("a", 0.1, 0.0, 0.0, 0.0),
            DhRow::revolute("b", 0.1, 0.0, 0.0, 0.0),
        ];
        rows[1].mimic = Some(Mimic {
            joint: "a".into(),
            multiplier: -2.0,
            offset: 0.5,
        });
        let mut s = JointSampler::new(&rows, 1.0, 7);
        let mut q = Vec::new();
        s.next_into(&mut q);
        assert_eq!(q, vec![0.0, 0.5]);
        for _ in 0..100 {
            s.next_into(&mut q);
            assert!((q[1] - (-2.0 * q[0] + 0.5)).abs() < 1e-15);
            assert!(q[0].abs() <= std::f64::consts::PI);
        }
    }

    fn chain_of_followers(n: usize) -> Vec<DhRow> {
        // Row i follows row i + 1 (q_i = 0.5 q_{i+1} + 0.001); the last moves on its own: the
        // drivers come after their followers, the worst order for repeated passes.
        (0..n)
            .map(|i| {
                let mut r = DhRow::revolute(&format!("j{i}"), 0.1, 0.0, 0.0, 0.0);
                if i + 1 < n {
                    r.mimic = Some(Mimic {
                        joint: format!("j{}", i + 1),
                        multiplier: 0.5,
                        offset: 0.001,
                    });
                }
                r
            })
            .collect()
    }

    #[test]
    fn a_long_chain_of_mimics_is_resolved_in_one_pass() {
        let rows = chain_of_followers(4000);
        let mut s = JointSampler::new(&rows, 1.0, 11);
        let mut q = Vec::new();
        s.next_into(&mut q);
        assert_eq!(q[3999], 0.0, "the zero pose first");
        for _ in 0..20 {
            s.next_into(&mut q);
            assert_ne!(q[3999], 0.0);
            for i in 0..3999 {
                assert_eq!(q[i], 0.5 * q[i + 1] + 0.001, "row {i}");
            }
        }
    }

    #[test]
    fn mimic_cycles_move_on_their_own() {
        let mut rows = chain_of_followers(3);
        // j2 follows j0: j0 -> j1 -> j2 -> j0.
        rows[2].mimic = Some(Mimic {
            joint: "j0".into(),
            multiplier: 1.0,
            offset: 0.0,
        });
        let mut extra = DhRow::revolute("k", 0.1, 0.0, 0.0, 0.0);
        extra.mimic = Some(Mimic {
            joint: "j1".into(),
            multiplier: 2.0,
            offset: 0.0,
        });
        rows.push(extra);
        let mut s = JointSampler::new(&rows, 1.0, 5);
        let mut q = Vec::new();
        s.next_into(&mut q);
        let mut moved = [false; 3];
        for _ in 0..20 {
            s.next_into(&mut q);
            for (m, v) in moved.iter_mut().zip(&q) {
                *m |= *v != 0.0;
            }
            // A row leading into the cycle still follows its driver.
            assert_eq!(q[3], 2.0 * q[1]);
        }
        assert_eq!(moved, [true; 3]);
    }

    #[test]
    fn a_frozen_joint_is_moved_all_the_same() {
        let mut rows = vec![DhRow::revolute("a", 0.1, 0.0, 0.0, 0.0)];
        rows[0].limits = Some(crate::Limits {
            lower: 0.0,
            upper: 0.0,
        });
        let mut s = JointSampler::new(&rows, 1.0, 3);
        let mut q = Vec::new();
        let mut largest: f64 = 0.0;
        for _ in 0..50 {
            s.next_into(&mut q);
            largest = largest.max(q[0].abs());
        }
        assert!(largest > 1.0, "{largest}");
    }

    #[test]
    fn a_wrong_oracle_is_caught() {
        let table = DhTable {
            convention: Convention::Standard,
            base: Isometry3::identity(),
            tool: Isometry3::identity(),
            rows: vec![DhRow::revolute("a", 1.0, 0.0, 0.0, 0.0)],
        };
        let dev = compare(
            &table,
            |q| Isometry3::translation(q[0].cos(), q[0].sin() + 1e-3, 0.0),
            50,
            1,
        )
        .unwrap();
        assert!(dev.max_position_error > 9e-4);
        let nan = compare(&table, |_| Isometry3::translation(f64::NAN, 0.0, 0.0), 5, 1).unwrap();
        assert!(nan.max_position_error.is_infinite());
    }
}
