//! Rigid transforms in the layouts the DH conventions and URDF use.
//!
//! All poses are `nalgebra::Isometry3<f64>` mapping child-frame coordinates into parent-frame
//! coordinates; lengths in metres, angles in radians.

use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};

/// The pose from URDF `xyz` and `rpy` (roll about x, then pitch about y, then yaw about z, all
/// about fixed axes: `R = Rz(yaw) Ry(pitch) Rx(roll)`).
pub fn from_xyz_rpy(xyz: [f64; 3], rpy: [f64; 3]) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(xyz[0], xyz[1], xyz[2]),
        UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2]),
    )
}

/// URDF `xyz` and `rpy` of a pose (the inverse of [`from_xyz_rpy`]), exact at every pitch.
///
/// With `R = Rz(yaw) Ry(pitch) Rx(roll)`, yaw is read from the first column
/// (`atan2(r10, r00)`); pitch and roll are then read from `Rz(-yaw) R = Ry(pitch) Rx(roll)`, so
/// the three angles always rebuild `R` to rounding, even at and near pitch ±pi/2 where roll and
/// yaw are not unique (there yaw takes what the first column says, 0 when it says nothing, and
/// roll takes the rest). Reading roll and yaw independently (`atan2(r21, r22)`,
/// `atan2(r10, r00)`) instead loses their split as pitch nears ±pi/2: a tool frame at a
/// rounded pitch of 1.5708 came out 0.2 rad off that way. Angles in `(-pi, pi]`, pitch in
/// `[-pi/2, pi/2]`.
pub fn to_xyz_rpy(pose: &Isometry3<f64>) -> ([f64; 3], [f64; 3]) {
    let t = pose.translation.vector;
    ([t.x, t.y, t.z], rpy_of(&pose.rotation.to_rotation_matrix()))
}

/// Roll, pitch and yaw of a rotation (see [`to_xyz_rpy`]).
pub fn rpy_of(rotation: &Rotation3<f64>) -> [f64; 3] {
    let m = rotation.matrix();
    let yaw = m[(1, 0)].atan2(m[(0, 0)]);
    let (sy, cy) = yaw.sin_cos();
    // Rows of Rz(-yaw) R = Ry(pitch) Rx(roll) = [[cp, sp sr, sp cr], [0, cr, -sr], [-sp, cp sr, cp cr]].
    let cp = cy * m[(0, 0)] + sy * m[(1, 0)];
    let pitch = (-m[(2, 0)]).atan2(cp);
    let roll = (sy * m[(0, 2)] - cy * m[(1, 2)]).atan2(cy * m[(1, 1)] - sy * m[(0, 1)]);
    [roll, pitch, yaw]
}

/// A rotation about the z axis by `angle` (radians).
pub fn rot_z(angle: f64) -> Isometry3<f64> {
    Isometry3::rotation(Vector3::z() * angle)
}

/// A rotation about the x axis by `angle` (radians).
pub fn rot_x(angle: f64) -> Isometry3<f64> {
    Isometry3::rotation(Vector3::x() * angle)
}

/// A rotation about the y axis by `angle` (radians).
pub fn rot_y(angle: f64) -> Isometry3<f64> {
    Isometry3::rotation(Vector3::y() * angle)
}

/// A translation along x by `a` (metres).
pub fn trans_x(a: f64) -> Isometry3<f64> {
    Isometry3::translation(a, 0.0, 0.0)
}

/// A translation along z by `d` (metres).
pub fn trans_z(d: f64) -> Isometry3<f64> {
    Isometry3::translation(0.0, 0.0, d)
}

/// The pose with origin `origin` and rotation columns `x`, `y = z × x`, `z` (unit, orthogonal).
pub(crate) fn from_axes(origin: Vector3<f64>, x: Vector3<f64>, z: Vector3<f64>) -> Isometry3<f64> {
    let y = z.cross(&x);
    let m = Matrix3::from_columns(&[x, y, z]);
    Isometry3::from_parts(
        Translation3::from(origin),
        UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(m)),
    )
}

/// Position error (metres) and orientation error (radians, the angle of `a⁻¹ b`) between two
/// poses.
pub fn pose_error(a: &Isometry3<f64>, b: &Isometry3<f64>) -> (f64, f64) {
    let dp = (a.translation.vector - b.translation.vector).norm();
    let dr = a.rotation.angle_to(&b.rotation);
    (dp, dr)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn rpy_is_fixed_axis_roll_pitch_yaw() {
        let (r, p, y) = (0.3, -0.4, 1.2);
        let pose = from_xyz_rpy([1.0, 2.0, 3.0], [r, p, y]);
        let want = Rotation3::from_axis_angle(&Vector3::z_axis(), y)
            * Rotation3::from_axis_angle(&Vector3::y_axis(), p)
            * Rotation3::from_axis_angle(&Vector3::x_axis(), r);
        assert_relative_eq!(pose.rotation.to_rotation_matrix(), want, epsilon = 1e-15);
        let (xyz, rpy) = to_xyz_rpy(&pose);
        assert_relative_eq!(
            Vector3::from(xyz),
            Vector3::new(1.0, 2.0, 3.0),
            epsilon = 1e-15
        );
        assert_relative_eq!(Vector3::from(rpy), Vector3::new(r, p, y), epsilon = 1e-14);
    }

    /// The largest entry of `R(rpy_of(R)) - R`.
    fn rebuild_error(r: &Rotation3<f64>) -> f64 {
        let rpy = rpy_of(r);
        let back = from_xyz_rpy([0.0; 3], rpy).rotation.to_rotation_matrix();
        (back.matrix() - r.matrix()).abs().max()
    }

    #[test]
    fn rpy_rebuilds_the_rotation_approaching_both_poles() {
        // Pitch ±pi/2 exactly, then 1e-1 .. 1e-16 rad away, from both sides, with roll and yaw
        // spread over the circle: the split of roll and yaw is what used to be lost.
        let mut worst: f64 = 0.0;
        for pole in [FRAC_PI_2, -FRAC_PI_2] {
            for k in 0..=16 {
                let away = if k == 16 { 0.0 } else { 10f64.powi(-(k + 1)) };
                for side in [-1.0, 1.0] {
                    let p = pole + side * away;
                    for i in 0..12 {
                        for j in 0..12 {
                            let (r, y) = (-3.0 + 0.51 * i as f64, -3.1 + 0.53 * j as f64);
                            let rot = Rotation3::from_euler_angles(r, p, y);
                            worst = worst.max(rebuild_error(&rot));
                        }
                    }
                }
            }
        }
        assert!(worst < 2e-15, "worst entry error {worst:e}");
    }

    #[test]
    #[allow(clippy::approx_constant)] // the rounded values real URDFs hold, on purpose
    fn rpy_rebuilds_random_rotations_and_the_rounded_pitch_of_real_urdfs() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut worst: f64 = 0.0;
        for _ in 0..100_000 {
            let q = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            ));
            worst = worst.max(rebuild_error(&q.to_rotation_matrix()));
        }
        // URDF angles rounded to 1.5708, composed: the case that printed a tool 0.2 rad off.
        for (r, p, y) in [
            (1.5708, 1.5708, 0.0),
            (0.0, 1.5708, -1.5708),
            (3.1416, -1.5708, 1.5708),
        ] {
            let rot =
                Rotation3::from_euler_angles(r, p, y) * Rotation3::from_euler_angles(0.3, 0.0, 0.0);
            worst = worst.max(rebuild_error(&rot));
        }
        assert!(worst < 2e-15, "worst entry error {worst:e}");
    }

    #[test]
    fn rpy_at_the_poles_is_in_range_and_exact() {
        for p in [FRAC_PI_2, -FRAC_PI_2] {
            let rot = Rotation3::from_euler_angles(0.7, p, -0.2);
            let [r, pp, y] = rpy_of(&rot);
            assert!(r.abs() <= std::f64::consts::PI && y.abs() <= std::f64::consts::PI);
            assert!((pp - p).abs() < 1e-15, "{pp} vs {p}");
            assert!(rebuild_error(&rot) < 1e-15);
        }
    }
}
