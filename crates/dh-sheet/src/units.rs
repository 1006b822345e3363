//! Length and angle units of sheets, reports and measurement files.

use serde::{Deserialize, Serialize};

/// Unit of lengths in a file or report.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum LengthUnit {
    /// Metres.
    #[default]
    M,
    /// Millimetres.
    Mm,
}

/// Unit of angles in a file or report.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
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

impl LengthUnit {
    /// Decimals kept when printing a length in this unit: a picometre.
    pub fn decimals(self) -> usize {
        match self {
            LengthUnit::M => 12,
            LengthUnit::Mm => 9,
        }
    }
    /// `metres` in this unit, rounded to a picometre so that outputs show `0.6`, not
    /// `0.6000000000000001`.
    pub fn from_si(self, metres: f64) -> f64 {
        round_decimals(clean(metres) / self.metres(), self.decimals())
    }
}

impl AngleUnit {
    /// Decimals kept when printing an angle in this unit (1e-12 rad).
    pub fn decimals(self) -> usize {
        match self {
            AngleUnit::Rad => 12,
            AngleUnit::Deg => 10,
        }
    }
    /// `radians` (wrapped to (-pi, pi]) in this unit, rounded like [`LengthUnit::from_si`];
    /// within 1e-12 rad of a multiple of 45° it is that multiple exactly, so that pi/2 prints
    /// as `1.5707963267948966` (or `90`), the value readers recognise.
    pub fn from_si(self, radians: f64) -> f64 {
        let a = clean_angle(radians);
        let eighths = (a / std::f64::consts::FRAC_PI_4).round();
        if (a - eighths * std::f64::consts::FRAC_PI_4).abs() < PRINT_NOISE * 10.0 {
            return match self {
                AngleUnit::Rad => eighths * std::f64::consts::FRAC_PI_4,
                AngleUnit::Deg => eighths * 45.0,
            };
        }
        round_decimals(a / self.radians(), self.decimals())
    }
    /// `radians` in this unit without wrapping (joint limits may exceed pi).
    pub fn from_si_unwrapped(self, radians: f64) -> f64 {
        round_decimals(clean(radians) / self.radians(), self.decimals())
    }
}

/// A bound for printing: `x` rounded *up* to two significant digits, so that the printed
/// figure is still a bound and does not carry the last bits of floating-point rounding.
pub fn bound_for_print(x: f64) -> f64 {
    if !x.is_finite() || x <= 0.0 {
        return x;
    }
    let text = format!("{x:.1e}");
    let shown: f64 = text.parse().unwrap_or(x);
    if shown >= x {
        return shown;
    }
    // One unit up in the second digit: 1.2e-13 -> 1.3e-13, 9.9e-13 -> 1.0e-12.
    let exponent = x.log10().floor();
    let step = 10f64.powf(exponent - 1.0);
    match format!("{:.1e}", shown + step).parse() {
        Ok(up) if up >= x => up,
        _ => x,
    }
}

/// `x` rounded to `decimals` decimal places (through decimal text, so the result is the double
/// nearest the rounded decimal and prints in its shortest form).
pub fn round_decimals(x: f64, decimals: usize) -> f64 {
    if !x.is_finite() {
        return x;
    }
    format!("{x:.decimals$}").parse().unwrap_or(x)
}

#[cfg(test)]
mod tests {
    use super::bound_for_print;

    #[test]
    fn bounds_round_up_to_two_digits() {
        assert_eq!(bound_for_print(1.0159893229154544e-13), 1.1e-13);
        assert_eq!(bound_for_print(1.0182097689647047e-13), 1.1e-13);
        assert_eq!(bound_for_print(9.96e-13), 1.0e-12);
        assert_eq!(bound_for_print(9.94e-13), 1.0e-12);
        assert_eq!(bound_for_print(2.5e-6), 2.5e-6);
        assert_eq!(bound_for_print(0.0), 0.0);
        for x in [3.3333e-9, 7.77e-14, 1.000001e-5, 4.4e-300] {
            assert!(bound_for_print(x) >= x, "{x}");
        }
    }
}
