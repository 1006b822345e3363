//! Length and angle units of sheets, reports and measurement files.

use serde::{Deserialize, Serialize};

/// Unit of lengths in a file or report.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum, Default)]
#[serde(rename_all = "lowercase")]
pub enum LengthUnit {
    /// Metres.
    #[default]
    M,
    /// Millimetres.
    Mm,
}

/// Unit of angles in a file or report.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum, Default)]
#[serde(rename_all = "lowercase")]
pub enum AngleUnit {
    /// Radians.
    #[default]
    Rad,
    /// Degrees.
    Deg,
}

impl LengthUnit {
    /// Metres per unit.
    pub fn metres(self) -> f64 {
        match self {
            LengthUnit::M => 1.0,
            LengthUnit::Mm => 1e-3,
        }
    }
    /// The unit's symbol.
    pub fn symbol(self) -> &'static str {
        match self {
            LengthUnit::M => "m",
            LengthUnit::Mm => "mm",
        }
    }
}

impl AngleUnit {
    /// Radians per unit.
    pub fn radians(self) -> f64 {
        match self {
            AngleUnit::Rad => 1.0,
            AngleUnit::Deg => std::f64::consts::PI / 180.0,
        }
    }
    /// The unit's symbol.
    pub fn symbol(self) -> &'static str {
        match self {
            AngleUnit::Rad => "rad",
            AngleUnit::Deg => "deg",
        }
    }
}

/// Float noise below this magnitude (metres or radians) is printed as 0: it is far below any
/// tolerance and would only make outputs differ between machines.
pub const PRINT_NOISE: f64 = 1e-13;

/// A value cleaned for printing: noise to 0, `-0` to `0`.
pub fn clean(x: f64) -> f64 {
    if x.abs() < PRINT_NOISE {
        0.0
    } else {
        x
    }
}

/// An angle cleaned for printing and wrapped to `(-pi, pi]`.
pub fn clean_angle(x: f64) -> f64 {
    use std::f64::consts::PI;
    let mut a = x.rem_euclid(2.0 * PI);
    if a > PI + PRINT_NOISE {
        a -= 2.0 * PI;
    }
    if a > PI - PRINT_NOISE {
        a = PI;
    }
    clean(a)
}
