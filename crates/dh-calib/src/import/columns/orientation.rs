//! The orientation of a 6-DoF device (a tracker's 6-DoF probe, an optical marker body) in the
//! user's own export: which columns hold it, as a quaternion or as roll, pitch and yaw, and its
//! standard deviation.
//!
//! # Frames and units
//! The orientation is the rotation of the target frame in the device frame, as the canonical
//! CSV's `qw`, `qx`, `qy`, `qz` hold it ([`crate::csv`]):
//!
//! - a quaternion: four columns named in the order `qw, qx, qy, qz` (scalar first, Hamilton
//!   convention; an export that puts the scalar last names its columns in this order all the
//!   same), normalised when its norm is within [`QUATERNION_NORM_TOLERANCE`](crate::csv::QUATERNION_NORM_TOLERANCE) of 1, refused
//!   beyond;
//! - roll, pitch, yaw: three columns in the map's angle unit
//!   ([`ColumnMap::angle_scale`](super::ColumnMap::angle_scale)), URDF's fixed-axis convention
//!   `R = Rz(yaw) · Ry(pitch) · Rx(roll)`, each within a turn;
//! - `sigma_rot`: the standard deviation of each component of the rotation vector, in the
//!   map's angle unit too (written in radians), > 0 and at most a radian.
//!
//! A row whose rotation cells are all empty is a point; one with some empty is refused.

use nalgebra::UnitQuaternion;

use super::ColumnRef;
use crate::csv::{number, unit_quaternion, DataError};
use crate::data::Orientation;

/// Largest `sigma_rot` (radians), as the canonical reader takes it: a standard deviation of a
/// radian says nothing.
const MAX_SIGMA_ROT: f64 = 1.0;

/// Largest roll, pitch or yaw (radians): a turn, so that exports in `[0, 360)` degrees read
/// and degrees read as radians (beyond 6.28) do not.
const MAX_RPY: f64 = std::f64::consts::TAU;

/// The columns of the measured rotation.
#[derive(Clone, Debug, PartialEq)]
pub enum RotationColumns {
    /// `qw`, `qx`, `qy`, `qz`, in this order.
    Quaternion([ColumnRef; 4]),
    /// Roll, pitch, yaw, in this order (the map's angle unit).
    Rpy([ColumnRef; 3]),
}

/// Where a 6-DoF device's orientation is (see the [module docs](self)).
#[derive(Clone, Debug, PartialEq)]
pub struct OrientationMap {
    /// The rotation's columns.
    pub rotation: RotationColumns,
    /// The column of its standard deviation per axis (the map's angle unit).
    pub sigma: ColumnRef,
}

/// An [`OrientationMap`] with its columns found in the file (0-based).
pub(super) struct Resolved {
    rotation: Vec<usize>,
    quaternion: bool,
    sigma: usize,
}

impl OrientationMap {
    /// Finds the columns with `resolve` (a column number or header name to its index).
    pub(super) fn resolve(
        &self,
        resolve: &impl Fn(&ColumnRef) -> Result<usize, DataError>,
    ) -> Result<Resolved, DataError> {
        let (refs, quaternion): (&[ColumnRef], bool) = match &self.rotation {
            RotationColumns::Quaternion(c) => (c, true),
            RotationColumns::Rpy(c) => (c, false),
        };
        Ok(Resolved {
            rotation: refs.iter().map(resolve).collect::<Result<_, _>>()?,
            quaternion,
            sigma: resolve(&self.sigma)?,
        })
    }
}

impl Resolved {
    /// Each column with its role, for the check that no column has two.
    pub(super) fn roles(&self) -> Vec<(usize, String)> {
        let names: &[&str] = if self.quaternion {
            &["qw", "qx", "qy", "qz"]
        } else {
            &["roll", "pitch", "yaw"]
        };
        let mut out: Vec<(usize, String)> = self
            .rotation
            .iter()
            .zip(names)
            .map(|(&c, n)| (c, format!("orientation {n}")))
            .collect();
        out.push((self.sigma, "sigma_rot".into()));
        out
    }

    /// The orientation of the row at `line` (`None` when its rotation cells are all empty),
    /// `cell` giving a cell by column index, `name` a column's name for messages,
    /// `angle_scale` the radians per unit of roll, pitch, yaw and `sigma_rot`.
    ///
    /// # Errors
    /// A [`DataError`] naming the line and column: some rotation cells empty, a cell that is
    /// not a finite number, a quaternion that is not a unit one, an angle beyond a turn, a
    /// standard deviation that is empty, not positive or above a radian.
    pub(super) fn cells<'a>(
        &self,
        line: usize,
        cell: &impl Fn(usize) -> &'a str,
        name: &impl Fn(usize) -> String,
        angle_scale: f64,
    ) -> Result<Option<Orientation>, DataError> {
        let empty: Vec<bool> = self.rotation.iter().map(|&c| cell(c).is_empty()).collect();
        if empty.iter().all(|e| *e) {
            return Ok(None);
        }
        let names = || {
            self.rotation
                .iter()
                .map(|&c| format!("'{}'", name(c)))
                .collect::<Vec<_>>()
                .join(", ")
        };
        if let Some(k) = empty.iter().position(|e| *e) {
            return Err(DataError::Format {
                line,
                expected: format!("all of the orientation columns {} or none", names()),
                found: format!("an empty '{}'", name(self.rotation[k])),
            });
        }
        let mut v = Vec::with_capacity(self.rotation.len());
        for &c in &self.rotation {
            v.push(number(cell(c), line, &name(c))?);
        }
        let rotation = if self.quaternion {
            unit_quaternion([v[0], v[1], v[2], v[3]], line, &names())?
        } else {
            let mut rpy = [0.0; 3];
            for ((slot, value), &c) in rpy.iter_mut().zip(&v).zip(&self.rotation) {
                *slot = value * angle_scale;
                if slot.abs() > MAX_RPY {
                    return Err(DataError::Format {
                        line,
                        expected: format!(
                            "an angle within a turn in column '{}' (is the angle unit right?)",
                            name(c)
                        ),
                        found: format!("'{}'", cell(c)),
                    });
                }
            }
            UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2])
        };
        let s = self.sigma;
        if cell(s).is_empty() {
            return Err(DataError::Format {
                line,
                expected: format!(
                    "a standard deviation in column '{}' for an orientation",
                    name(s)
                ),
                found: "an empty cell".into(),
            });
        }
        let sigma = number(cell(s), line, &name(s))? * angle_scale;
        // 0 passes (a rounded export): the reader floors it with a warning.
        if !(0.0..=MAX_SIGMA_ROT).contains(&sigma) {
            return Err(DataError::Format {
                line,
                expected: format!(
                    "a standard deviation >= 0 and <= {MAX_SIGMA_ROT} rad in column '{}'",
                    name(s)
                ),
                found: format!("'{}'", cell(s)),
            });
        }
        Ok(Some(Orientation { rotation, sigma }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::csv::{parse_measurements, write_measurements, CsvOptions};
    use crate::import::columns::{parse, ColumnMap};

    /// Two joints in degrees, a point in millimetres, its sigma, then the orientation from
    /// column 7 on.
    fn map(rotation: RotationColumns, sigma: usize) -> ColumnMap {
        ColumnMap {
            time: None,
            joints: ColumnRef::parse_list("1-2").unwrap(),
            joint_names: vec![],
            point: [
                ColumnRef::Number(3),
                ColumnRef::Number(4),
                ColumnRef::Number(5),
            ],
            target: None,
            sigma: Some(ColumnRef::Number(6)),
            sigma_axes: None,
            skip_incomplete: false,
            config: None,
            set: None,
            session: None,
            orientation: Some(OrientationMap {
                rotation,
                sigma: ColumnRef::Number(sigma),
            }),
            delimiter: None,
            header: true,
            length_scale: 1e-3,
            angle_scale: std::f64::consts::PI / 180.0,
            prismatic: vec![],
        }
    }

    fn quaternion_map() -> ColumnMap {
        // The export puts the scalar last: the map names it first all the same.
        let c = ColumnRef::parse_list("w,x4,y4,z4").unwrap();
        map(RotationColumns::Quaternion(c.try_into().unwrap()), 11)
    }

    /// What the canonical reader reads back from the import's CSV.
    fn round_trip(m: &crate::data::Measurements) -> crate::data::Measurements {
        let text = write_measurements(m);
        assert!(text.contains(",qw,qx,qy,qz,sigma_rot\n"), "{text}");
        parse_measurements(&text, &m.joint_names, &CsvOptions::default()).unwrap()
    }

    #[test]
    fn quaternion_columns_in_any_order_read_back_through_the_canonical_csv() {
        // 0.8 + 0.6 i: a turn of 2·atan2(0.6, 0.8) = 73.74 degrees about x.
        let text = "a;b;x;y;z;s;x4;y4;z4;w;sr\n\
                    10;20;1000;2000;3000;0.02;0.6;0;0;0.8;0.005\n\
                    0;0;1;2;3;0.02;;;;;\n";
        let (m, _) = parse(text, &quaternion_map()).unwrap();
        let o = m.samples[0].orientation.as_ref().unwrap();
        let want = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(0.8, 0.6, 0.0, 0.0));
        assert!(o.rotation.angle_to(&want) < 1e-15);
        // 0.005 degrees in radians.
        assert!((o.sigma - 0.005_f64.to_radians()).abs() < 1e-18);
        assert!(m.samples[1].orientation.is_none());
        let back = round_trip(&m);
        let b = back.samples[0].orientation.as_ref().unwrap();
        assert!(b.rotation.angle_to(&o.rotation) < 1e-12);
        assert!((b.sigma - o.sigma).abs() <= 1e-12 * o.sigma);
        assert!((back.samples[0].point - m.samples[0].point).norm() < 1e-12);
        assert!(back.samples[1].orientation.is_none());
    }

    #[test]
    fn roll_pitch_yaw_in_degrees_read_as_the_urdf_rotation() {
        let c = ColumnRef::parse_list("7-9").unwrap();
        let rpy = map(RotationColumns::Rpy(c.try_into().unwrap()), 10);
        let text = "a,b,x,y,z,s,r,p,yw,sr\n0,0,1,2,3,0.02,30,-20,350,0.01\n";
        let (m, _) = parse(text, &rpy).unwrap();
        let o = m.samples[0].orientation.as_ref().unwrap();
        let want =
            UnitQuaternion::from_axis_angle(&nalgebra::Vector3::z_axis(), 350f64.to_radians())
                * UnitQuaternion::from_axis_angle(
                    &nalgebra::Vector3::y_axis(),
                    -20f64.to_radians(),
                )
                * UnitQuaternion::from_axis_angle(&nalgebra::Vector3::x_axis(), 30f64.to_radians());
        assert!(o.rotation.angle_to(&want) < 1e-14);
        let back = round_trip(&m);
        let b = back.samples[0].orientation.as_ref().unwrap();
        assert!(b.rotation.angle_to(&want) < 1e-12);
        assert!((b.sigma - 0.01_f64.to_radians()).abs() < 1e-15);
    }

    #[test]
    fn bad_orientation_cells_name_the_line_and_column() {
        let q = quaternion_map();
        for (row, message) in [
            (
                "0;0;1;2;3;0.02;0.6;0;;0.8;0.005",
                "line 3: expected all of the orientation columns 'w', 'x4', 'y4', 'z4' or none, found an empty 'z4'",
            ),
            ("0;0;1;2;3;0.02;0.6;0;0;0.9;0.005", "line 3: expected a unit quaternion in columns 'w', 'x4', 'y4', 'z4'"),
            ("0;0;1;2;3;0.02;0.6;0;0;0.8;", "line 3: expected a standard deviation in column 'sr' for an orientation"),
            ("0;0;1;2;3;0.02;0.6;0;0;0.8;-1", "line 3: expected a standard deviation >= 0 and <= 1 rad in column 'sr'"),
            ("0;0;1;2;3;;0.6;0;0;0.8;0.005", "line 3: expected a standard deviation in column 's' for a row with an orientation"),
            ("0;0;1;2;3;0.02;0.6;nan;0;0.8;0.005", "line 3"),
        ] {
            let text = format!("a;b;x;y;z;s;x4;y4;z4;w;sr\n0;0;1;2;3;0.02;;;;;\n{row}\n");
            let e = parse(&text, &q).unwrap_err().to_string();
            assert!(e.contains(message), "{row}: {e}");
        }
        let mut rad = map(
            RotationColumns::Rpy(ColumnRef::parse_list("7-9").unwrap().try_into().unwrap()),
            10,
        );
        rad.angle_scale = 1.0;
        let e = parse("a,b,x,y,z,s,r,p,yw,sr\n0,0,1,2,3,0.02,30,0,0,0.01\n", &rad)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(
                "line 2: expected an angle within a turn in column 'r' (is the angle unit right?)"
            ),
            "{e}"
        );
        let mut no_sigma = quaternion_map();
        no_sigma.sigma = None;
        let e = parse(
            "a;b;x;y;z;s;x4;y4;z4;w;sr\n0;0;1;2;3;0.02;0;0;0;1;0.1\n",
            &no_sigma,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("a sigma column with orientation columns"), "{e}");
    }
}
