//! The units a CSV may be written in ([`LengthUnit`], [`AngleUnit`]; values are converted to
//! metres and radians on reading) and the reader's settings ([`CsvOptions`]).

use super::*;

/// Unit of lengths in a file: point coordinates, standard deviations and prismatic joints.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum LengthUnit {
    /// Metres (the canonical unit).
    #[default]
    Metre,
    /// Millimetres.
    Millimetre,
}

impl LengthUnit {
    /// `value` (in this unit) in metres; millimetres are divided by 1000, which rounds
    /// correctly (`7 mm` is the double nearest `0.007 m`).
    pub fn to_metres(self, value: f64) -> f64 {
        match self {
            LengthUnit::Metre => value,
            LengthUnit::Millimetre => value / 1000.0,
        }
    }
}

impl fmt::Display for LengthUnit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            LengthUnit::Metre => "m",
            LengthUnit::Millimetre => "mm",
        })
    }
}

impl FromStr for LengthUnit {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "m" => Ok(LengthUnit::Metre),
            "mm" => Ok(LengthUnit::Millimetre),
            other => Err(format!("expected length unit 'm' or 'mm', found '{other}'")),
        }
    }
}

/// Unit of revolute joint values in a file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum AngleUnit {
    /// Radians (the canonical unit).
    #[default]
    Radian,
    /// Degrees.
    Degree,
}

impl AngleUnit {
    /// `value` (in this unit) in radians.
    pub fn to_radians(self, value: f64) -> f64 {
        match self {
            AngleUnit::Radian => value,
            AngleUnit::Degree => value.to_radians(),
        }
    }
}

impl fmt::Display for AngleUnit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            AngleUnit::Radian => "rad",
            AngleUnit::Degree => "deg",
        })
    }
}

impl FromStr for AngleUnit {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "rad" => Ok(AngleUnit::Radian),
            "deg" => Ok(AngleUnit::Degree),
            other => Err(format!(
                "expected angle unit 'rad' or 'deg', found '{other}'"
            )),
        }
    }
}

/// Units of a measurement file; values are converted to metres and radians on reading.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct CsvOptions {
    /// Unit of `x`, `y`, `z`, of `sigma`/`sx`/`sy`/`sz` and of prismatic joint columns.
    pub length_unit: LengthUnit,
    /// Unit of revolute joint columns.
    pub angle_unit: AngleUnit,
    /// Names of the prismatic joints (their columns are lengths, not angles); every other joint
    /// column is an angle.
    pub prismatic: Vec<String>,
}
