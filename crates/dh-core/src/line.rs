//! Plücker lines and the dual line product (paper §2).

use nalgebra::{Isometry3, Vector3};

use crate::CoreError;

/// A directed line in Plücker coordinates `s = (e, k)`: unit direction `e` and moment
/// `k = c × e` for any point `c` on the line (paper eq. 1). Units: `k` in metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Line {
    e: Vector3<f64>,
    k: Vector3<f64>,
}

/// The dual number `cos(beta) + ε (−d sin(beta))` returned by the dual line product (eq. 3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DualNumber {
    /// Real part: `e1 · e2 = cos(beta)`.
    pub real: f64,
    /// Dual part: `e1 · k2 + k1 · e2 = −d sin(beta)`, with `d` measured along
    /// `(e1 × e2) / |e1 × e2|` from line 1 to line 2 (ERRATA: eq. 3).
    pub dual: f64,
}

impl Line {
    /// The line through `point` along `direction` (any non-zero length; it is normalised).
    ///
    /// # Errors
    /// [`CoreError::NonFinite`] for a NaN or infinite coordinate, [`CoreError::ZeroDirection`]
    /// for a zero direction.
    pub fn through(point: Vector3<f64>, direction: Vector3<f64>) -> Result<Self, CoreError> {
        check_finite("line point", &point)?;
        check_finite("line direction", &direction)?;
        let norm = direction.norm();
        if norm == 0.0 || !norm.is_finite() {
            return Err(CoreError::ZeroDirection {
                what: "line".into(),
            });
        }
        let e = direction / norm;
        Ok(Self {
            e,
            k: point.cross(&e),
        })
    }

    /// The z axis of a frame, as a line in that frame's own coordinates.
    pub fn z_axis() -> Self {
        Self {
            e: Vector3::z(),
            k: Vector3::zeros(),
        }
    }

    /// Unit direction `e`.
    pub fn direction(&self) -> Vector3<f64> {
        self.e
    }

    /// Moment `k = c × e` (metres).
    pub fn moment(&self) -> Vector3<f64> {
        self.k
    }

    /// The point of the line closest to the origin, `e × k` (metres).
    pub fn point(&self) -> Vector3<f64> {
        self.e.cross(&self.k)
    }

    /// The point of the line closest to `p` (metres).
    pub fn foot_of(&self, p: &Vector3<f64>) -> Vector3<f64> {
        let c = self.point();
        c + self.e * (p - c).dot(&self.e)
    }

    /// Distance from `p` to the line (metres).
    pub fn distance_to_point(&self, p: &Vector3<f64>) -> f64 {
        (p - self.foot_of(p)).norm()
    }

    /// The same line seen from another frame: `iso` maps this line's frame into the new one.
    pub fn transformed(&self, iso: &Isometry3<f64>) -> Self {
        let e = iso.rotation * self.e;
        let c = iso * nalgebra::Point3::from(self.point());
        Self {
            e,
            k: c.coords.cross(&e),
        }
    }

    /// The dual line product `ŝ1 · ŝ2 = e1·e2 + ε (e1·k2 + k1·e2)` (eq. 3).
    pub fn dual_dot(&self, other: &Line) -> DualNumber {
        DualNumber {
            real: self.e.dot(&other.e),
            dual: self.e.dot(&other.k) + self.k.dot(&other.e),
        }
    }

    /// Angle `beta` between the two directions, in `[0, pi]` (radians), computed from both
    /// `|e1 × e2|` and `e1 · e2` so that it stays accurate near 0 and pi.
    pub fn angle_to(&self, other: &Line) -> f64 {
        self.e.cross(&other.e).norm().atan2(self.e.dot(&other.e))
    }

    /// The closest points `(p1, p2)` on this line and on `other` (metres), by eq. (14) and
    /// (15) with the UNIT common normal `n = (e1 × e2) / sin(beta)` (ERRATA: the paper prints the
    /// unnormalised `e1 × e2`). Works for intersecting lines too, where `p1 = p2` is the
    /// intersection point: this replaces eq. (4) and the origin shift of eq. (5)-(10), whose
    /// denominator vanishes when the plane of the two lines contains the origin.
    ///
    /// Returns `None` for exactly parallel lines, which have no unique common normal.
    pub fn closest_points(&self, other: &Line) -> Option<(Vector3<f64>, Vector3<f64>)> {
        let cross = self.e.cross(&other.e);
        let sin = cross.norm();
        if sin == 0.0 {
            return None;
        }
        let n = cross / sin;
        let cos = self.e.dot(&other.e);
        let (k1n, k2n) = (self.k.dot(&n), other.k.dot(&n));
        let p1 = self.e * ((k2n - cos * k1n) / sin) + self.e.cross(&self.k);
        let p2 = other.e * ((-k1n + cos * k2n) / sin) + other.e.cross(&other.k);
        Some((p1, p2))
    }

    /// Whether the two lines lie in one plane: the dual part of eq. (3) vanishes,
    /// `e1·k2 + e2·k1 = 0` (ERRATA: eq. 4 prints a minus sign). `linear` is the largest common
    /// normal (metres) still counted as zero.
    pub fn is_coplanar_with(&self, other: &Line, linear: f64) -> bool {
        let sin = self.e.cross(&other.e).norm();
        let dual = self.dual_dot(other).dual;
        // |dual| = d sin(beta): compare a length with a length.
        dual.abs() <= linear * sin || sin == 0.0 && self.parallel_offset(other) <= linear
    }

    /// Distance between the two lines measured perpendicular to this line's direction at the
    /// point of this line nearest the origin: the offset of (nearly) parallel lines (metres).
    pub fn parallel_offset(&self, other: &Line) -> f64 {
        let v = other.point() - self.point();
        (v - self.e * v.dot(&self.e)).norm()
    }
}

impl approx::AbsDiffEq for Line {
    type Epsilon = f64;
    fn default_epsilon() -> f64 {
        f64::EPSILON
    }
    fn abs_diff_eq(&self, other: &Self, epsilon: f64) -> bool {
        self.e.abs_diff_eq(&other.e, epsilon) && self.k.abs_diff_eq(&other.k, epsilon)
    }
}

impl approx::RelativeEq for Line {
    fn default_max_relative() -> f64 {
        f64::EPSILON
    }
    fn relative_eq(&self, other: &Self, epsilon: f64, max_relative: f64) -> bool {
        self.e.relative_eq(&other.e, epsilon, max_relative)
            && self.k.relative_eq(&other.k, epsilon, max_relative)
    }
}

pub(crate) fn check_finite(what: &str, v: &Vector3<f64>) -> Result<(), CoreError> {
    match v.iter().find(|x| !x.is_finite()) {
        Some(&value) => Err(CoreError::NonFinite {
            what: what.into(),
            value,
        }),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// Brute-force closest points by the textbook normal equations, independent of Plücker
    /// coordinates.
    fn brute_closest(
        p: Vector3<f64>,
        u: Vector3<f64>,
        q: Vector3<f64>,
        v: Vector3<f64>,
    ) -> (Vector3<f64>, Vector3<f64>) {
        let (u, v) = (u.normalize(), v.normalize());
        let w = p - q;
        let b = u.dot(&v);
        let (d, e) = (u.dot(&w), v.dot(&w));
        let den = 1.0 - b * b;
        let t = (b * e - d) / den;
        let s = (e - b * d) / den;
        (p + u * t, q + v * s)
    }

    #[test]
    fn moment_is_independent_of_the_point_chosen() {
        let d = Vector3::new(1.0, 2.0, -0.5);
        let a = Line::through(Vector3::new(0.3, -1.0, 2.0), d).unwrap();
        let b = Line::through(Vector3::new(0.3, -1.0, 2.0) + 3.7 * d, d).unwrap();
        assert_relative_eq!(a, b, epsilon = 1e-14);
    }

    #[test]
    fn dual_product_gives_cos_and_minus_d_sin_eq3() {
        // Line 1: x axis. Line 2: through (0, 0, 2) along (0, 1, 1)/√2. Common normal along z,
        // e1 × e2 = (0,-1,1)/√2 × ... : check the sign convention of the ERRATA.
        let l1 = Line::through(Vector3::zeros(), Vector3::x()).unwrap();
        let l2 = Line::through(Vector3::new(0.0, 0.0, 2.0), Vector3::new(0.0, 1.0, 0.0)).unwrap();
        let dn = l1.dual_dot(&l2);
        let beta = std::f64::consts::FRAC_PI_2;
        assert_relative_eq!(dn.real, beta.cos(), epsilon = 1e-15);
        // e1 × e2 = z: line 2 sits at d = +2 along it, so the dual part is −2 sin(beta).
        assert_relative_eq!(dn.dual, -2.0 * beta.sin(), epsilon = 1e-15);
    }

    #[test]
    fn eq4_as_printed_is_wrong_and_the_dual_part_decides_coplanarity() {
        // Two intersecting lines off the origin.
        let p = Vector3::new(1.0, 2.0, 3.0);
        let l1 = Line::through(p, Vector3::new(1.0, 0.0, 0.0)).unwrap();
        let l2 = Line::through(p, Vector3::new(0.0, 1.0, 1.0)).unwrap();
        let printed = l1.e.dot(&l2.k) - l2.e.dot(&l1.k);
        let corrected = l1.e.dot(&l2.k) + l2.e.dot(&l1.k);
        assert!(printed.abs() > 1e-3, "printed eq. 4 should not vanish here");
        assert!(corrected.abs() < 1e-14);
        assert!(l1.is_coplanar_with(&l2, 1e-9));
    }

    #[test]
    fn eq4_intersection_point_matches_closest_points_off_origin_plane() {
        let p = Vector3::new(1.0, 2.0, 3.0);
        let l1 = Line::through(p, Vector3::new(1.0, 0.2, 0.0)).unwrap();
        let l2 = Line::through(p, Vector3::new(0.0, 1.0, 1.0)).unwrap();
        // eq. (4): p = (k1 × k2) / (e2 · k1), valid when the plane misses the origin.
        let eq4 = l1.k.cross(&l2.k) / l2.e.dot(&l1.k);
        assert_relative_eq!(eq4, p, epsilon = 1e-12);
        let (p1, p2) = l1.closest_points(&l2).unwrap();
        assert_relative_eq!(p1, p, epsilon = 1e-12);
        assert_relative_eq!(p2, p, epsilon = 1e-12);
    }

    #[test]
    fn eq4_denominator_vanishes_when_the_plane_holds_the_origin() {
        // Both lines lie in the plane z = 0 which contains the origin.
        let p = Vector3::new(1.0, 1.0, 0.0);
        let l1 = Line::through(p, Vector3::x()).unwrap();
        let l2 = Line::through(p, Vector3::y()).unwrap();
        assert_eq!(l2.e.dot(&l1.k), 0.0);
        let (p1, _) = l1.closest_points(&l2).unwrap();
        assert_relative_eq!(p1, p, epsilon = 1e-15);
    }

    #[test]
    fn eq14_15_need_the_unit_normal() {
        let l1 = Line::through(Vector3::new(0.1, 0.2, 0.3), Vector3::new(1.0, 0.0, 0.2)).unwrap();
        let l2 = Line::through(Vector3::new(-0.4, 1.0, 0.8), Vector3::new(0.3, 0.5, 1.0)).unwrap();
        let (p1, p2) = l1.closest_points(&l2).unwrap();
        let (b1, b2) = brute_closest(
            Vector3::new(0.1, 0.2, 0.3),
            Vector3::new(1.0, 0.0, 0.2),
            Vector3::new(-0.4, 1.0, 0.8),
            Vector3::new(0.3, 0.5, 1.0),
        );
        assert_relative_eq!(p1, b1, epsilon = 1e-12);
        assert_relative_eq!(p2, b2, epsilon = 1e-12);
        // With the unnormalised n of the printed paper the foot points move.
        let n = l1.e.cross(&l2.e);
        let (sin, cos) = (n.norm(), l1.e.dot(&l2.e));
        let wrong = l1.e * ((l2.k.dot(&n) - cos * l1.k.dot(&n)) / sin) + l1.e.cross(&l1.k);
        assert!((wrong - b1).norm() > 1e-3);
    }

    #[test]
    fn transformed_line_keeps_its_points() {
        let iso = Isometry3::new(Vector3::new(0.5, -1.0, 2.0), Vector3::new(0.3, -0.2, 1.1));
        let c = Vector3::new(0.3, 0.1, -0.7);
        let d = Vector3::new(0.0, 1.0, 1.0);
        let l = Line::through(c, d).unwrap().transformed(&iso);
        let c2 = (iso * nalgebra::Point3::from(c)).coords;
        assert!(l.distance_to_point(&c2) < 1e-14);
        assert_relative_eq!(l.direction(), iso.rotation * d.normalize(), epsilon = 1e-15);
    }

    #[test]
    fn zero_and_nan_directions_are_errors() {
        assert!(matches!(
            Line::through(Vector3::zeros(), Vector3::zeros()),
            Err(CoreError::ZeroDirection { .. })
        ));
        assert!(matches!(
            Line::through(Vector3::new(f64::NAN, 0.0, 0.0), Vector3::x()),
            Err(CoreError::NonFinite { .. })
        ));
    }
}
