//! Geometric fits: a circle through 3D points ([`fit_circle`]: SVD plane (Shakarji 1998), Kåsa's
//! algebraic circle (1976), then orthogonal-distance Levenberg-Marquardt (Gander, Golub and
//! Strebel 1994)), concentric circles about one common axis, and the small vector helpers
//! they share. Metres.

use super::*;

/// How a circle is fitted in its plane.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CircleMethod {
    /// Kåsa's algebraic fit: linear least squares on `x² + y² + D x + E y + F = 0`. Fast and
    /// closed-form, but it shrinks circles fitted to short noisy arcs.
    Kasa,
    /// Geometric fit: least squares of the orthogonal distances to the circle
    /// (Levenberg-Marquardt from the Kåsa fit; Gander, Golub & Strebel 1994).
    Geometric,
}

/// A circle in space fitted to points.
#[derive(Clone, Debug, PartialEq)]
pub struct Circle {
    /// Centre (metres, the points' frame).
    pub centre: Vector3<f64>,
    /// Unit normal of the plane (sign arbitrary: the SVD's).
    pub normal: Vector3<f64>,
    /// Radius (metres).
    pub radius: f64,
    /// RMS in-plane distance of the points from the circle (metres).
    pub circle_rms: f64,
    /// RMS distance of the points from the plane (metres).
    pub plane_rms: f64,
    /// Number of points.
    pub points: usize,
    /// Each point's in-plane radial residual, distance from the centre minus radius (metres).
    pub radial: Vec<f64>,
}

/// Fits a plane by SVD and then a circle in it by `method` (see [`CircleMethod`]).
///
/// # Errors
/// [`CpaError::Degenerate`] (with empty joint and target names) for fewer than three points,
/// non-finite coordinates, or points on a line or at one place.
pub fn fit_circle(points: &[Vector3<f64>], method: CircleMethod) -> Result<Circle, CpaError> {
    let degenerate = |what: &str| CpaError::Degenerate {
        joint: String::new(),
        target: String::new(),
        what: what.into(),
    };
    if points.len() < 3 {
        return Err(degenerate("a circle needs at least three points"));
    }
    if points.iter().any(|p| !p.iter().all(|c| c.is_finite())) {
        return Err(degenerate("a point has a non-finite coordinate"));
    }
    let c = mean(points);
    let centred: Vec<Vector3<f64>> = points.iter().map(|p| p - c).collect();
    let (values, vectors) = principal_axes(&centred);
    // Collinear points (second singular value at rounding level of the first) span no plane.
    if values[1] <= values[0] * 1e3 * f64::EPSILON {
        return Err(degenerate(
            "the points lie on a line, so they fit no circle",
        ));
    }
    let (e1, e2, normal) = (vectors[0], vectors[1], vectors[2]);
    let plane_rms = rms(centred.iter().map(|d| d.dot(&normal)));
    let xy: Vec<Vector2<f64>> = centred
        .iter()
        .map(|d| Vector2::new(d.dot(&e1), d.dot(&e2)))
        .collect();
    let (mut centre2, mut radius) =
        kasa(&xy).ok_or_else(|| degenerate("the points fit no circle (algebraic fit singular)"))?;
    if method == CircleMethod::Geometric {
        (centre2, radius) = geometric_circle(&xy, centre2, radius);
    }
    let radial: Vec<f64> = xy.iter().map(|p| (p - centre2).norm() - radius).collect();
    Ok(Circle {
        centre: c + e1 * centre2.x + e2 * centre2.y,
        normal,
        radius,
        circle_rms: rms(radial.iter().copied()),
        plane_rms,
        points: points.len(),
        radial,
    })
}

/// Kåsa's fit: minimise Σ (x² + y² + D x + E y + F)² (linear), centre `(−D/2, −E/2)`.
pub(super) fn kasa(xy: &[Vector2<f64>]) -> Option<(Vector2<f64>, f64)> {
    let a = DMatrix::from_fn(xy.len(), 3, |i, j| match j {
        0 => xy[i].x,
        1 => xy[i].y,
        _ => 1.0,
    });
    let b = DVector::from_fn(xy.len(), |i, _| -xy[i].norm_squared());
    let svd = a.svd(true, true);
    let max = svd.singular_values.max();
    if svd.singular_values.min() <= max * 1e3 * f64::EPSILON {
        return None;
    }
    let x = svd.solve(&b, 0.0).ok()?;
    let centre = Vector2::new(-x[0] / 2.0, -x[1] / 2.0);
    let r2 = centre.norm_squared() - x[2];
    (r2 > 0.0 && r2.is_finite()).then(|| (centre, r2.sqrt()))
}

/// Geometric circle fit in the plane: minimise Σ (|p − c| − r)² by Levenberg-Marquardt.
pub(super) fn geometric_circle(
    xy: &[Vector2<f64>],
    c0: Vector2<f64>,
    r0: f64,
) -> (Vector2<f64>, f64) {
    let eval = |x: &DVector<f64>| {
        let c = Vector2::new(x[0], x[1]);
        let mut r = DVector::zeros(xy.len());
        let mut j = DMatrix::zeros(xy.len(), 3);
        for (i, p) in xy.iter().enumerate() {
            let d = p - c;
            let dist = d.norm();
            r[i] = dist - x[2];
            if dist > 0.0 {
                j[(i, 0)] = -d.x / dist;
                j[(i, 1)] = -d.y / dist;
            }
            j[(i, 2)] = -1.0;
        }
        (r, j)
    };
    let x = levenberg_marquardt(DVector::from_vec(vec![c0.x, c0.y, r0]), eval, |x, dx| {
        x + dx
    });
    (Vector2::new(x[0], x[1]), x[2])
}

/// Concentric circles about one axis: a point on the axis, the axis direction, and per group a
/// radius and a position of its plane along the axis.
pub(super) struct Coaxial {
    pub(super) point: Vector3<f64>,
    pub(super) normal: Vector3<f64>,
    pub(super) radii: Vec<f64>,
    pub(super) heights: Vec<f64>,
}

impl Coaxial {
    /// Radial and axial residuals of every point.
    pub(super) fn residuals(&self, groups: &[Vec<Vector3<f64>>]) -> (Vec<f64>, Vec<f64>) {
        let mut radial = Vec::new();
        let mut axial = Vec::new();
        for (k, pts) in groups.iter().enumerate() {
            for p in pts {
                let d = p - self.point;
                let z = d.dot(&self.normal);
                radial.push((d - self.normal * z).norm() - self.radii[k]);
                axial.push(z - self.heights[k]);
            }
        }
        (radial, axial)
    }
}

/// Fits concentric circles sharing one axis to the point groups (each point's squared
/// orthogonal distance to its circle, split into radial and axial parts), by Levenberg-Marquardt
/// started from `point`, `normal` and the groups' own circles.
pub(super) fn fit_coaxial(
    groups: &[Vec<Vector3<f64>>],
    point: Vector3<f64>,
    normal: Vector3<f64>,
    own: &[Circle],
) -> Coaxial {
    let k = groups.len();
    // State: point (3), normal (3), radii (k), heights (k).
    let mut x0 = Vec::with_capacity(6 + 2 * k);
    x0.extend(point.iter());
    x0.extend(normal.iter());
    x0.extend(own.iter().map(|c| c.radius));
    x0.extend(own.iter().map(|c| (c.centre - point).dot(&normal)));
    let unpack = |x: &DVector<f64>| {
        let a = Vector3::new(x[0], x[1], x[2]);
        let n = Vector3::new(x[3], x[4], x[5]);
        (a, n)
    };
    let m: usize = groups.iter().map(Vec::len).sum();
    let eval = |x: &DVector<f64>| {
        let (a, n) = unpack(x);
        let (b1, b2) = basis(&n);
        let mut r = DVector::zeros(2 * m);
        let mut j = DMatrix::zeros(2 * m, 4 + 2 * k);
        let mut row = 0;
        for (g, pts) in groups.iter().enumerate() {
            for p in pts {
                let d = p - a;
                let z = d.dot(&n);
                let rho = (d - n * z).norm();
                let (d1, d2) = (d.dot(&b1), d.dot(&b2));
                // Axial residual: local parameters (tilt along b1, b2; shift along b1, b2).
                r[row] = z - x[6 + k + g];
                j[(row, 0)] = d1;
                j[(row, 1)] = d2;
                j[(row, 4 + k + g)] = -1.0;
                // Radial residual.
                r[row + 1] = rho - x[6 + g];
                if rho > 0.0 {
                    j[(row + 1, 0)] = -z * d1 / rho;
                    j[(row + 1, 1)] = -z * d2 / rho;
                    j[(row + 1, 2)] = -d1 / rho;
                    j[(row + 1, 3)] = -d2 / rho;
                }
                j[(row + 1, 4 + g)] = -1.0;
                row += 2;
            }
        }
        (r, j)
    };
    let update = |x: &DVector<f64>, dx: &DVector<f64>| {
        let (a, n) = unpack(x);
        let (b1, b2) = basis(&n);
        let n2 = (n + b1 * dx[0] + b2 * dx[1]).normalize();
        let a2 = a + b1 * dx[2] + b2 * dx[3];
        let mut y = x.clone();
        y.fixed_rows_mut::<3>(0).copy_from(&a2);
        y.fixed_rows_mut::<3>(3).copy_from(&n2);
        for i in 0..2 * k {
            y[6 + i] += dx[4 + i];
        }
        y
    };
    let x = levenberg_marquardt(DVector::from_vec(x0), eval, update);
    let (a, n) = unpack(&x);
    Coaxial {
        point: a,
        normal: n,
        radii: (0..k).map(|g| x[6 + g]).collect(),
        heights: (0..k).map(|g| x[6 + k + g]).collect(),
    }
}

/// Levenberg-Marquardt iterations of a solver setting, not a geometric decision: enough for
/// the small well-started problems here, which converge in a handful.
pub(super) const LM_MAX_ITERATIONS: usize = 200;

/// Minimises |r(x)|² with Marquardt's scaled damping. `eval` gives residuals and the Jacobian
/// with respect to a local step; `update` applies a step (for manifold parameters such as a unit
/// vector). Stops when a step no longer lowers the cost by more than rounding.
pub(super) fn levenberg_marquardt(
    mut x: DVector<f64>,
    eval: impl Fn(&DVector<f64>) -> (DVector<f64>, DMatrix<f64>),
    update: impl Fn(&DVector<f64>, &DVector<f64>) -> DVector<f64>,
) -> DVector<f64> {
    let (mut r, mut j) = eval(&x);
    let mut cost = r.norm_squared();
    let mut lambda = 1e-3;
    for _ in 0..LM_MAX_ITERATIONS {
        let jt = j.transpose();
        let jtj = &jt * &j;
        let g = &jt * &r;
        let max_diag = jtj.diagonal().max();
        if max_diag <= 0.0 || !max_diag.is_finite() {
            break;
        }
        let mut improved = false;
        while lambda < 1e16 {
            let mut a = jtj.clone();
            for i in 0..a.nrows() {
                // Floor the scaling so that parameters without effect stay put.
                a[(i, i)] += lambda * jtj[(i, i)].max(max_diag * f64::EPSILON);
            }
            let Some(chol) = a.cholesky() else {
                lambda *= 10.0;
                continue;
            };
            let dx = -chol.solve(&g);
            let candidate = update(&x, &dx);
            let (r2, j2) = eval(&candidate);
            let cost2 = r2.norm_squared();
            if cost2.is_finite() && cost2 < cost {
                let gain = cost - cost2;
                x = candidate;
                (r, j, cost) = (r2, j2, cost2);
                lambda = (lambda / 10.0).max(1e-12);
                improved = gain > cost * 16.0 * f64::EPSILON;
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    x
}

/// Singular values (descending) and the matching unit vectors of the scatter of `centred`.
pub(super) fn principal_axes(centred: &[Vector3<f64>]) -> ([f64; 3], [Vector3<f64>; 3]) {
    let scatter = centred
        .iter()
        .fold(Matrix3::zeros(), |acc, d| acc + d * d.transpose());
    let eig = scatter.symmetric_eigen();
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let values = order.map(|i| eig.eigenvalues[i].max(0.0).sqrt());
    let vectors = order.map(|i| eig.eigenvectors.column(i).into_owned());
    (values, vectors)
}

/// Two unit vectors completing `n` to a right-handed frame `(b1, b2, n)`.
pub(super) fn basis(n: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let b1 = perpendicular(n);
    (b1, n.cross(&b1))
}

/// A unit vector perpendicular to the unit vector `n`: from the world x axis, or y when x is
/// too close to `n` (the rule `dh_core::extract` uses for frame 0).
pub(super) fn perpendicular(n: &Vector3<f64>) -> Vector3<f64> {
    let pick = |v: Vector3<f64>| v - n * v.dot(n);
    let x = pick(Vector3::x());
    if x.norm() >= FRAC_1_SQRT_2 {
        x.normalize()
    } else {
        pick(Vector3::y()).normalize()
    }
}

pub(super) fn mean(points: &[Vector3<f64>]) -> Vector3<f64> {
    points.iter().sum::<Vector3<f64>>() / points.len().max(1) as f64
}

pub(super) fn rms(values: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v * v, n + 1));
    if n == 0 {
        0.0
    } else {
        (sum / n as f64).sqrt()
    }
}

/// `a` wrapped into `(−pi, pi]`.
pub(super) fn wrap(a: f64) -> f64 {
    let w = a - TAU * (a / TAU).round();
    if w <= -PI {
        w + TAU
    } else {
        w
    }
}
