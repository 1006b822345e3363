//! Closed-form registration of two sets of joint axis lines: the rigid motion that puts one
//! description's axes (a sheet's, in its DH frame 0) onto another's (the URDF's, in its base
//! link), used to start the fit of a free base.
//!
//! Rotation: Kabsch/Horn on the axis directions (each joint's positive sense). When all
//! directions are parallel (a planar chain) that leaves a spin about the common direction free,
//! which the lines' positions fix: seen along that direction each line is a point, and the spin
//! is the 2-D Procrustes rotation between the two point sets. Translation: the least-squares
//! point that brings every revolute axis onto its partner line (prismatic axes are directions
//! only); any direction the lines leave open (along a common direction of parallel axes) stays
//! zero, for the tool or the joint values to absorb.
//!
//! A DH table fixes each z axis up to its sign, and a sheet may count a joint the other way; the
//! candidates therefore include each single joint's direction reversed, for the fit that follows
//! to choose by the pose residual.

use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, Unit, UnitQuaternion, Vector3};

use crate::table::{Convention, DhTable, JointKind};
use crate::{CoreError, Tolerance};

/// One joint axis in some frame: a point on it (metres) and its unit direction (the sense in
/// which the joint value turns or slides).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisLine {
    /// A point on the axis (metres).
    pub point: Vector3<f64>,
    /// Unit direction.
    pub direction: Vector3<f64>,
    /// Revolute: the line's position matters. Prismatic: only its direction.
    pub revolute: bool,
}

/// The joint axes of `table` at joint values `q`, in the table's base link frame (its `base`
/// applied). Standard convention: joint `i` turns about z of frame `i − 1`; modified: of frame
/// `i`.
///
/// # Errors
/// [`CoreError::JointCount`] when `q` has the wrong length.
pub fn axis_lines(table: &DhTable, q: &[f64]) -> Result<Vec<AxisLine>, CoreError> {
    let frames = table.frames(q)?;
    let shift = match table.convention {
        Convention::Standard => 0,
        Convention::Modified => 1,
    };
    Ok(table
        .rows
        .iter()
        .enumerate()
        .filter_map(|(i, row)| {
            // The frame's origin is on its z axis in both conventions (modified frame i sits
            // after Rz(theta + q) Tz(d), which stay on the axis).
            let f = frames.get(i + shift)?;
            Some(AxisLine {
                point: f.translation.vector,
                direction: f.rotation * Vector3::z(),
                revolute: row.kind == JointKind::Revolute,
            })
        })
        .collect())
}

/// Candidate poses `X` of the source frame in the target frame with `X · source_i ≈ target_i`
/// for every axis `i` (same count, same order): first with the directions as given, then with
/// each single source direction reversed. Empty when the counts differ or there are no axes.
pub fn register_axes(
    source: &[AxisLine],
    target: &[AxisLine],
    tol: Tolerance,
) -> Vec<Isometry3<f64>> {
    if source.len() != target.len() || source.is_empty() {
        return Vec::new();
    }
    let mut signs = vec![1.0; source.len()];
    let mut out = vec![register(source, target, &signs, tol)];
    for j in 0..source.len() {
        signs[j] = -1.0;
        out.push(register(source, target, &signs, tol));
        signs[j] = 1.0;
    }
    out
}

/// One registration with source direction `j` multiplied by `signs[j]`.
fn register(
    source: &[AxisLine],
    target: &[AxisLine],
    signs: &[f64],
    tol: Tolerance,
) -> Isometry3<f64> {
    // Kabsch: the rotation R maximising sum (R s_j) . t_j is V diag(1, 1, det) U^T for
    // H = sum s_j t_j^T = U S V^T.
    let mut h = Matrix3::zeros();
    for ((s, t), &k) in source.iter().zip(target).zip(signs) {
        h += (s.direction * k) * t.direction.transpose();
    }
    let svd = h.svd(true, true);
    let mut r = match (svd.u, svd.v_t) {
        (Some(u), Some(v_t)) => {
            let v = v_t.transpose();
            let det = (v * u.transpose()).determinant();
            let fix = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, det.signum()));
            v * fix * u.transpose()
        }
        _ => Matrix3::identity(),
    };
    let common = target[0].direction;
    let planar = target
        .iter()
        .all(|t| t.direction.cross(&common).norm() <= tol.angular.sin());
    if planar {
        r = spin_about(common, &r, source, target) * r;
    }
    let rotation = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
    let translation = translation_onto_lines(&rotation, source, target, tol);
    Isometry3::from_parts(Translation3::from(translation), rotation)
}

/// The rotation about `u` (unit) that best brings the revolute source lines, rotated by `r` and
/// seen along `u`, onto the target lines (2-D Procrustes about the centroids).
fn spin_about(
    u: Vector3<f64>,
    r: &Matrix3<f64>,
    source: &[AxisLine],
    target: &[AxisLine],
) -> Matrix3<f64> {
    let flat = |p: Vector3<f64>| p - u * u.dot(&p);
    let pairs: Vec<(Vector3<f64>, Vector3<f64>)> = source
        .iter()
        .zip(target)
        .filter(|(s, _)| s.revolute)
        .map(|(s, t)| (flat(r * s.point), flat(t.point)))
        .collect();
    if pairs.len() < 2 {
        return Matrix3::identity();
    }
    let count = pairs.len() as f64;
    let ca = pairs.iter().map(|p| p.0).sum::<Vector3<f64>>() / count;
    let cb = pairs.iter().map(|p| p.1).sum::<Vector3<f64>>() / count;
    let (mut sin, mut cos) = (0.0, 0.0);
    for (a, b) in &pairs {
        let (a, b) = (a - ca, b - cb);
        sin += u.dot(&a.cross(&b));
        cos += a.dot(&b);
    }
    let angle = sin.atan2(cos);
    *Rotation3::from_axis_angle(&Unit::new_unchecked(u), angle).matrix()
}

/// The translation `t` minimising the distances of `R p_j + t` from the target revolute lines:
/// `(sum P_j) t = sum P_j (q_j − R p_j)` with `P_j = I − d_j d_j^T`. Directions the lines leave
/// open (eigenvalues of `sum P_j` below the angular tolerance's share) get no translation.
fn translation_onto_lines(
    rotation: &UnitQuaternion<f64>,
    source: &[AxisLine],
    target: &[AxisLine],
    tol: Tolerance,
) -> Vector3<f64> {
    let mut m = Matrix3::zeros();
    let mut rhs = Vector3::zeros();
    let mut count = 0.0;
    for (s, t) in source.iter().zip(target).filter(|(s, _)| s.revolute) {
        let p = Matrix3::identity() - t.direction * t.direction.transpose();
        m += p;
        rhs += p * (t.point - rotation * s.point);
        count += 1.0;
    }
    // A direction of sum P_j is observable when some line is tilted from it by more than the
    // angular tolerance (its eigenvalue is a sum of sin^2 of those tilts).
    let open = count * tol.angular.sin().powi(2);
    m.svd(true, true)
        .solve(&rhs, open)
        .unwrap_or_else(|_| Vector3::zeros())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::table::DhRow;
    use approx::assert_relative_eq;

    fn table(rows: Vec<DhRow>, convention: Convention, base: Isometry3<f64>) -> DhTable {
        DhTable {
            convention,
            base,
            tool: Isometry3::identity(),
            rows,
        }
    }

    fn moved() -> Isometry3<f64> {
        Isometry3::new(Vector3::new(0.3, -0.7, 0.2), Vector3::new(0.4, -1.1, 2.5))
    }

    /// A spatial arm seen from a moved base: the first candidate is that base, exactly.
    #[test]
    fn spatial_axes_register_exactly() {
        let rows = vec![
            DhRow::revolute("a", 0.1, 1.2, 0.3, 0.2),
            DhRow::revolute("b", 0.4, -0.5, 0.0, 0.1),
            DhRow::prismatic("c", 0.0, 0.9, 0.1, 0.0),
            DhRow::revolute("d", 0.2, std::f64::consts::FRAC_PI_2, 0.05, 0.0),
        ];
        for convention in [Convention::Standard, Convention::Modified] {
            let sheet = table(rows.clone(), convention, Isometry3::identity());
            let urdf = table(rows.clone(), convention, moved());
            let q = [0.0; 4];
            let found = register_axes(
                &axis_lines(&sheet, &q).unwrap(),
                &axis_lines(&urdf, &q).unwrap(),
                Tolerance::default(),
            );
            assert_eq!(found.len(), 5);
            assert_relative_eq!(
                found[0].to_homogeneous(),
                moved().to_homogeneous(),
                epsilon = 1e-12
            );
        }
    }

    /// All axes parallel and antiparallel (a planar arm with a flipped joint): the spin about
    /// the common direction comes from the lines' positions; the shift along it is left open.
    #[test]
    fn planar_axes_register_up_to_the_open_shift() {
        let pi = std::f64::consts::PI;
        let rows = vec![
            DhRow::revolute("a", 0.3, pi, 0.1, 0.4),
            DhRow::revolute("b", 0.25, 0.0, 0.2, -0.3),
            DhRow::revolute("c", 0.15, 0.0, 0.0, 0.0),
        ];
        let sheet = table(rows.clone(), Convention::Standard, Isometry3::identity());
        let urdf = table(rows, Convention::Standard, moved());
        let q = [0.0; 3];
        let source = axis_lines(&sheet, &q).unwrap();
        let target = axis_lines(&urdf, &q).unwrap();
        let x = register_axes(&source, &target, Tolerance::default())[0];
        for (s, t) in source.iter().zip(&target) {
            let p = x * nalgebra::Point3::from(s.point);
            let off = (p.coords - t.point) - t.direction * t.direction.dot(&(p.coords - t.point));
            assert!(off.norm() < 1e-12, "{off}");
            assert_relative_eq!(x.rotation * s.direction, t.direction, epsilon = 1e-12);
        }
        // The open shift is along the common direction only.
        let rest = moved().inverse() * x;
        assert_relative_eq!(rest.rotation.angle(), 0.0, epsilon = 1e-12);
        assert!(rest.translation.vector.xy().norm() < 1e-12);
    }
}
