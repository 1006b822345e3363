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

/// `x` rounded to `decimals` decimal places: the double nearest the rounded decimal (what
/// printing `x` with that many decimals and reading the text back gives), which prints in its
/// shortest form.
///
/// Fast path: with `p = 10^decimals` exact, `k = round(x p)` is the rounded decimal's integer
/// when `x p` is far (more than two of its ulps) from a half, and `k / p`, one correctly
/// rounded division of exact operands, is the double nearest `k 10^-decimals`. Otherwise (a
/// value at a half, more than 2^51 in units of the last decimal, more than 22 decimals) it
/// goes through the decimal text.
pub fn round_decimals(x: f64, decimals: usize) -> f64 {
    if !x.is_finite() {
        return x;
    }
    match in_last_decimals(x, decimals) {
        Some(k) => k / 10f64.powi(decimals as i32),
        None => format!("{x:.decimals$}").parse().unwrap_or(x),
    }
}

/// `x` printed with `decimals` decimal places, the text of `format!("{x:.decimals$}")` (the
/// exact value rounded half to even, the sign of a negative value kept when it rounds to
/// zero), made from the rounded integer when its value is certain (as in [`round_decimals`]).
pub fn format_fixed(x: f64, decimals: usize) -> String {
    let k = match in_last_decimals(x, decimals) {
        Some(k) if decimals <= 18 => k.abs() as u64,
        _ => return format!("{x:.decimals$}"),
    };
    let unit = 10u64.pow(decimals as u32);
    let sign = if x.is_sign_negative() { "-" } else { "" };
    if decimals == 0 {
        format!("{sign}{k}")
    } else {
        format!("{sign}{}.{:0decimals$}", k / unit, k % unit)
    }
}

/// `x 10^decimals` rounded to an integer, when that integer is the one decimal rounding of
/// `x`'s exact value gives for certain: `10^decimals` is exact (at most 22 decimals), the
/// product is below [`FAST_ROUNDING_LIMIT`] and more than two of its ulps from a half.
fn in_last_decimals(x: f64, decimals: usize) -> Option<f64> {
    if !x.is_finite() || decimals > 22 {
        return None;
    }
    let y = x * 10f64.powi(decimals as i32);
    if y.abs() >= FAST_ROUNDING_LIMIT {
        return None;
    }
    let ulp = f64::from_bits(y.abs().to_bits() + 1) - y.abs();
    let from_half = ((y - y.trunc()).abs() - 0.5).abs();
    (from_half > 2.0 * ulp).then(|| y.round())
}

/// Largest value, in units of the last decimal kept, that [`round_decimals`] rounds without
/// text: 2^51, so that the rounded integer and its distance from a half are exact.
const FAST_ROUNDING_LIMIT: f64 = 2_251_799_813_685_248.0;

#[cfg(test)]
mod tests {
    use super::bound_for_print;

    /// The text route, as it was before the fast path.
    fn through_text(x: f64, decimals: usize) -> f64 {
        format!("{x:.decimals$}").parse().unwrap_or(x)
    }

    #[test]
    fn rounding_without_text_gives_the_texts_bits() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let mut values = vec![
            0.0,
            -0.0,
            0.6000000000000001,
            -1e-15,
            1e-300,
            2.5e-12,
            0.5e-12,
        ];
        for _ in 0..200_000 {
            let scale = 10f64.powi(rng.random_range(-16..16));
            values.push(rng.random_range(-1.0..1.0) * scale);
        }
        // Values at a half of the last decimal (as near as doubles get) and next to it.
        for k in 0..2000 {
            let x = (k as f64 + 0.5) * 1e-12 * if k % 2 == 0 { 1.0 } else { -1.0 };
            values.extend([x, x.next_up(), x.next_down()]);
            let y = (k as f64 * 1.37 + 0.5) * 1e-9;
            values.extend([y, y.next_up(), y.next_down()]);
        }
        for x in values {
            for d in [0, 3, 6, 9, 10, 12, 15, 17, 22, 25] {
                let (fast, text) = (super::round_decimals(x, d), through_text(x, d));
                assert_eq!(fast.to_bits(), text.to_bits(), "{x:e} to {d} decimals");
                assert_eq!(super::format_fixed(x, d), format!("{x:.d$}"), "{x:e}");
            }
        }
    }

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
