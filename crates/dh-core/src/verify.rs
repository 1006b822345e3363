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
    rng: ChaCha8Rng,
    emitted: usize,
}

impl JointSampler {
    /// A sampler for `rows` with `seed`; `size` (metres) bounds unlimited prismatic joints.
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
        for (i, r) in rows.iter().enumerate() {
            if let Some(m) = &r.mimic {
                if let Some(driver) = rows.iter().position(|d| d.name == m.joint) {
                    // A driver that itself follows another, or a cycle, is resolved below by
                    // drawing in dependency order; a cycle falls back to own limits.
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
        Self {
            draws,
            rng: ChaCha8Rng::seed_from_u64(seed),
            emitted: 0,
        }
    }

    /// Writes the next sample into `q` (one value per row). The first sample is the zero pose
    /// (mimic offsets applied).
    pub fn next_into(&mut self, q: &mut Vec<f64>) {
        let n = self.draws.len();
        q.clear();
        q.resize(n, f64::NAN);
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
        // Followers: at most n passes resolve any chain of drivers; what is left is a cycle.
        for _ in 0..n {
            let mut open = false;
            for i in 0..n {
                if let Draw::Follows {
                    driver,
                    multiplier,
                    offset,
                } = self.draws[i]
                {
                    if q[i].is_nan() {
                        if q[driver].is_nan() {
                            open = true;
                        } else {
                            q[i] = multiplier * q[driver] + offset;
                        }
                    }
                }
            }
            if !open {
                break;
            }
        }
        for v in q.iter_mut().filter(|v| v.is_nan()) {
            *v = 0.0;
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
    let mut dev = Deviation {
        samples: 0,
        max_position_error: 0.0,
        max_orientation_error: 0.0,
    };
    for _ in 0..samples.max(1) {
        sampler.next_into(&mut q);
        let (dp, dr) = pose_error(&prepared.fk(&q)?, &oracle(&q));
        // NaN must never pass as "small": max() would drop it.
        dev.max_position_error = if dp.is_nan() {
            f64::INFINITY
        } else {
            dev.max_position_error.max(dp)
        };
        dev.max_orientation_error = if dr.is_nan() {
            f64::INFINITY
        } else {
            dev.max_orientation_error.max(dr)
        };
        dev.samples += 1;
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
