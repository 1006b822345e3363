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

/// URDF `xyz` and `rpy` of a pose (the inverse of [`from_xyz_rpy`]). At pitch ±pi/2 the roll
/// and yaw are not unique; the one nalgebra chooses is returned.
pub fn to_xyz_rpy(pose: &Isometry3<f64>) -> ([f64; 3], [f64; 3]) {
    let t = pose.translation.vector;
    let (r, p, y) = pose.rotation.euler_angles();
    ([t.x, t.y, t.z], [r, p, y])
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
}
