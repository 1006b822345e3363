//! Classification of two consecutive joint axes (paper §2.1, eq. 3).

use std::fmt;

use crate::{Line, Tolerance};

/// How two consecutive joint axes sit relative to each other, after applying a [`Tolerance`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Relation {
    /// Not parallel, common normal shorter than the linear tolerance.
    Intersecting,
    /// Same direction (within the angular tolerance), apart by more than the linear tolerance.
    Parallel,
    /// Opposite directions, apart by more than the linear tolerance.
    Antiparallel,
    /// One line, same or opposite direction (`antiparallel`).
    Coincident {
        /// Directions are opposite.
        antiparallel: bool,
    },
    /// Neither parallel nor intersecting: a unique common normal of non-zero length.
    Skew,
}

impl fmt::Display for Relation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Relation::Intersecting => "intersecting",
            Relation::Parallel => "parallel",
            Relation::Antiparallel => "antiparallel",
            Relation::Coincident {
                antiparallel: false,
            } => "coincident",
            Relation::Coincident { antiparallel: true } => "coincident (opposite)",
            Relation::Skew => "skew",
        })
    }
}

/// The geometry of a pair of lines and the class it falls in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairGeometry {
    /// The class under the tolerance used.
    pub relation: Relation,
    /// Angle between the directions, `[0, pi]` (radians).
    pub angle: f64,
    /// Length of the common normal (metres); for (near-)parallel lines the offset measured at
    /// the first line's point nearest the origin.
    pub distance: f64,
    /// How far the pair is from the exact class it was put in: for parallel, antiparallel and
    /// coincident pairs the angle from exact parallelism (radians); 0 otherwise.
    pub angle_deviation: f64,
    /// For intersecting and coincident pairs the distance snapped to zero (metres); 0 otherwise.
    pub distance_deviation: f64,
}

/// Classifies two lines with the dual line product (eq. 3): the real part `cos(beta)` tells
/// parallel from not, the dual part `−d sin(beta)` tells intersecting from skew. Angles are
/// compared with the angular tolerance and lengths with the linear one, never squared norms.
pub fn classify(l1: &Line, l2: &Line, tol: Tolerance) -> PairGeometry {
    // sin and cos of the angle between the directions, and the angle itself (one atan2).
    let sin = l1.direction().cross(&l2.direction()).norm();
    let angle = sin.atan2(l1.direction().dot(&l2.direction()));
    decide(
        angle,
        sin,
        tol,
        || l1.parallel_offset(l2),
        || l1.dual_dot(l2).dual,
    )
}

/// [`classify`] with the first line the z axis of the current frame (`e1 = (0, 0, 1)`,
/// `k1 = 0`), as the extraction meets every pair (§3.1): the same decisions from the same
/// values, with the products against `e1` and `k1` written out. With `u` the second line's
/// direction and `k` its moment: `|e1 × u| = sqrt(u.x² + u.y²)` (`s`, returned too),
/// `e1 · u = u.z`, the dual part of eq. (3) is `e1 · k + k1 · u = k.z`, and the parallel offset
/// is the distance of the second line's point nearest the origin from the z axis.
pub(crate) fn classify_from_z(next: &Line, tol: Tolerance) -> (PairGeometry, f64) {
    let u = next.direction();
    let sin = (u.x * u.x + u.y * u.y).sqrt();
    let angle = sin.atan2(u.z);
    let geometry = decide(
        angle,
        sin,
        tol,
        || next.point().xy().norm(),
        || next.moment().z,
    );
    (geometry, sin)
}

/// The class of a pair from its angle `angle` (radians, `[0, pi]`) and `sin = sin(angle)`; the
/// parallel offset (metres) and the dual part of eq. (3) (metres) are computed only when needed.
fn decide(
    angle: f64,
    sin: f64,
    tol: Tolerance,
    offset: impl FnOnce() -> f64,
    dual: impl FnOnce() -> f64,
) -> PairGeometry {
    let from_parallel = angle.min(std::f64::consts::PI - angle);
    let anti = angle > std::f64::consts::FRAC_PI_2;
    if from_parallel <= tol.angular {
        let offset = offset();
        let coincident = offset <= tol.linear;
        return PairGeometry {
            relation: match (coincident, anti) {
                (true, a) => Relation::Coincident { antiparallel: a },
                (false, false) => Relation::Parallel,
                (false, true) => Relation::Antiparallel,
            },
            angle,
            distance: offset,
            angle_deviation: from_parallel,
            distance_deviation: if coincident { offset } else { 0.0 },
        };
    }
    let distance = (dual() / sin).abs();
    if distance <= tol.linear {
        PairGeometry {
            relation: Relation::Intersecting,
            angle,
            distance,
            angle_deviation: 0.0,
            distance_deviation: distance,
        }
    } else {
        PairGeometry {
            relation: Relation::Skew,
            angle,
            distance,
            angle_deviation: 0.0,
            distance_deviation: 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    /// What hand-written URDFs say for pi/2: 3.7e-6 rad off, on purpose.
    #[allow(clippy::approx_constant)]
    const ROUNDED_HALF_PI: f64 = 1.5708;
    use super::*;
    use nalgebra::Vector3;

    fn line(p: [f64; 3], d: [f64; 3]) -> Line {
        Line::through(Vector3::from(p), Vector3::from(d)).unwrap()
    }

    #[test]
    fn the_five_classes() {
        let tol = Tolerance::default();
        let z = line([0.0; 3], [0.0, 0.0, 1.0]);
        let cases = [
            (
                line([0.0, 0.0, 1.0], [1.0, 0.0, 0.0]),
                Relation::Intersecting,
            ),
            (line([0.5, 0.0, 0.0], [0.0, 0.0, 1.0]), Relation::Parallel),
            (
                line([0.5, 0.0, 0.0], [0.0, 0.0, -1.0]),
                Relation::Antiparallel,
            ),
            (
                line([0.0, 0.0, 3.0], [0.0, 0.0, 2.0]),
                Relation::Coincident {
                    antiparallel: false,
                },
            ),
            (
                line([0.0, 0.0, 3.0], [0.0, 0.0, -2.0]),
                Relation::Coincident { antiparallel: true },
            ),
            (line([0.0, 0.3, 0.0], [1.0, 0.0, 0.0]), Relation::Skew),
        ];
        for (l, want) in cases {
            assert_eq!(classify(&z, &l, tol).relation, want, "{l:?}");
        }
    }

    #[test]
    fn rounded_half_pi_is_parallel_at_default_but_not_exact_tolerance() {
        // rpy 1.5708 puts a y axis 3.7e-6 rad off the z axis it was meant to be.
        let tilt = ROUNDED_HALF_PI - std::f64::consts::FRAC_PI_2;
        let z = line([0.0; 3], [0.0, 0.0, 1.0]);
        let l = line([0.425, 0.0, 0.0], [0.0, tilt.sin(), tilt.cos()]);
        let g = classify(&z, &l, Tolerance::default());
        assert_eq!(g.relation, Relation::Parallel);
        assert!((g.angle_deviation - tilt.abs()).abs() < 1e-12);
        assert_eq!(classify(&z, &l, Tolerance::EXACT).relation, Relation::Skew);
    }

    #[test]
    fn distance_of_skew_lines_is_a_length() {
        let z = line([0.0; 3], [0.0, 0.0, 1.0]);
        let l = line([0.0, 0.3, 0.0], [1.0, 0.0, 1.0]);
        let g = classify(&z, &l, Tolerance::default());
        assert_eq!(g.relation, Relation::Skew);
        assert!((g.distance - 0.3).abs() < 1e-15);
        assert!((g.angle - std::f64::consts::FRAC_PI_4).abs() < 1e-15);
    }

    #[test]
    fn from_z_is_classify_with_the_z_axis() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(12);
        let z = Line::z_axis();
        let mut v = || -> Vector3<f64> {
            Vector3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            )
        };
        for k in 0..20_000 {
            let (p, mut d) = (v(), v());
            // Exactly and nearly parallel, and exactly and nearly intersecting, pairs too.
            match k % 4 {
                1 => d.x *= 1e-5,
                2 => d = Vector3::new(0.0, 0.0, d.z.signum()),
                _ => {}
            }
            let p = if k % 8 == 3 {
                Vector3::new(0.0, 0.0, p.z) + d * 1e-7
            } else {
                p
            };
            let l = line(p.into(), d.into());
            for tol in [
                Tolerance::default(),
                Tolerance::EXACT,
                Tolerance::new(0.3, 0.2).unwrap(),
            ] {
                let want = classify(&z, &l, tol);
                let (got, sin) = classify_from_z(&l, tol);
                assert_eq!(got, want, "{l:?}");
                assert_eq!(sin, z.direction().cross(&l.direction()).norm());
            }
        }
    }
}
