//! The ranges of the numeric options, one parser per option: a finite number (or count) within
//! a stated range, the error naming the range, so `--sigma 1e200` reads "expected a length in
//! (0, 1000], found 1e200". The command line uses them as its value parsers (clap prefixes the
//! option), the Python package for the keyword arguments of the same names. README.md ("Bad
//! input") lists them.

use crate::text::escape;

/// A finite number in `[lo, hi]` (or `(lo, hi]` when `open_low`), for a value parser.
fn ranged(s: &str, what: &str, lo: f64, hi: f64, open_low: bool) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("expected {what}, found '{}'", escape(s)))?;
    let low_ok = if open_low { v > lo } else { v >= lo };
    if v.is_finite() && low_ok && v <= hi {
        return Ok(v);
    }
    let open = if open_low { '(' } else { '[' };
    Err(format!(
        "expected {what} in {open}{lo}, {hi}], found {}",
        escape(s.trim())
    ))
}

/// An integer in `[lo, hi]`, for a value parser.
fn counted(s: &str, what: &str, lo: usize, hi: usize) -> Result<usize, String> {
    let v: usize = s
        .trim()
        .parse()
        .map_err(|_| format!("expected {what}, found '{}'", escape(s)))?;
    if (lo..=hi).contains(&v) {
        Ok(v)
    } else {
        Err(format!(
            "expected {what} in [{lo}, {hi}], found {}",
            s.trim()
        ))
    }
}

/// Largest linear tolerance (metres): a common normal of 10 cm is a link, not rounding.
pub const MAX_LINEAR_TOL: f64 = 0.1;
/// Largest angular tolerance (radians, 5.7°): beyond it every pair of a real arm would snap.
pub const MAX_ANGULAR_TOL: f64 = 0.1;

/// `--linear-tol`: metres in `[0, 0.1]`.
pub fn linear_tol(s: &str) -> Result<f64, String> {
    ranged(s, "a length in metres", 0.0, MAX_LINEAR_TOL, false)
}

/// `--angular-tol`: radians in `[0, 0.1]`.
pub fn angular_tol(s: &str) -> Result<f64, String> {
    ranged(s, "an angle in radians", 0.0, MAX_ANGULAR_TOL, false)
}

/// `--sigma`: a standard deviation in the files' length unit, in `(0, 1000]` (1 m in mm, 1 km
/// in m: far above any measuring device, far below overflow when squared).
pub fn sigma(s: &str) -> Result<f64, String> {
    ranged(s, "a length", 0.0, 1000.0, true)
}

/// `--noise`: metres in `[0, 1]`.
pub fn noise(s: &str) -> Result<f64, String> {
    ranged(s, "a length in metres", 0.0, 1.0, false)
}

/// `simulate --orientation-noise`: radians in `(0, 1]`.
pub fn orientation_noise(s: &str) -> Result<f64, String> {
    ranged(s, "an angle in radians", 0.0, 1.0, true)
}

/// `compensate --max-change`: radians (metres for prismatic joints) in `(0, 1]`.
pub fn max_change(s: &str) -> Result<f64, String> {
    ranged(s, "radians (metres for prismatic joints)", 0.0, 1.0, true)
}

/// `--validation`: a fraction in `[0, 0.9]`.
pub fn fraction(s: &str) -> Result<f64, String> {
    ranged(s, "a fraction", 0.0, 0.9, false)
}

/// `--arc`: radians in `(0, 2 pi]`.
pub fn arc(s: &str) -> Result<f64, String> {
    ranged(s, "an angle in radians", 0.0, std::f64::consts::TAU, true)
}

/// A joint value of `--q` (radians, or metres for a prismatic joint): `[-100, 100]`.
pub fn joint_value(s: &str) -> Result<f64, String> {
    ranged(s, "a joint value", -100.0, 100.0, false)
}

/// A bound of `--random-errors` (metres, then radians): `[0, 1]`.
pub fn random_error(s: &str) -> Result<f64, String> {
    ranged(s, "a length (m) or angle (rad)", 0.0, 1.0, false)
}

/// `--random-errors LENGTH,ANGLE`: exactly two numbers, each as [`random_error`].
pub fn random_errors(s: &str) -> Result<(f64, f64), String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    match parts.as_slice() {
        [l, a] => Ok((random_error(l)?, random_error(a)?)),
        _ => Err(format!(
            "expected LENGTH,ANGLE (two numbers, e.g. 0.001,0.002), found {} value(s)",
            parts.len()
        )),
    }
}

/// Largest `--samples` of `extract`'s self-check.
pub const MAX_SAMPLES: usize = 1_000_000;
/// `--samples`: `[1, 1 000 000]`.
pub fn samples(s: &str) -> Result<usize, String> {
    counted(s, "a number of samples", 1, MAX_SAMPLES)
}

/// Largest `--poses` of `simulate` (times targets and repeats: at most [`MAX_SIM_SAMPLES`]).
pub const MAX_POSES: usize = 1_000_000;
/// Largest number of simulated samples (poses x targets x repeats).
pub const MAX_SIM_SAMPLES: usize = 2_000_000;
/// `--poses`: `[1, 1 000 000]`.
pub fn poses(s: &str) -> Result<usize, String> {
    counted(s, "a number of poses", 1, MAX_POSES)
}

/// `--targets` (simulate) and `--repeats`: `[1, 1000]`.
pub fn small_count(s: &str) -> Result<usize, String> {
    counted(s, "a count", 1, 1000)
}

/// `--folds`: `[2, 100]`.
pub fn folds(s: &str) -> Result<usize, String> {
    counted(s, "a number of folds", 2, 100)
}

/// `--max-effects`: `[0, 100]`.
pub fn max_effects(s: &str) -> Result<usize, String> {
    counted(s, "a number of effects", 0, 100)
}

/// A significance level: `(0, 0.5]`.
pub fn alpha(s: &str) -> Result<f64, String> {
    ranged(s, "a significance level", 0.0, 0.5, true)
}

/// A gravity component (m/s²): `[-100, 100]`.
pub fn gravity(s: &str) -> Result<f64, String> {
    ranged(s, "an acceleration in m/s²", -100.0, 100.0, false)
}

/// A payload value (kg, or m for the centre): `[-1000, 1000]`.
pub fn payload(s: &str) -> Result<f64, String> {
    ranged(s, "a mass (kg) or position (m)", -1000.0, 1000.0, false)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parsers_name_the_range() {
        assert_eq!(sigma("0.5"), Ok(0.5));
        assert!(sigma("1e200").unwrap_err().contains("(0, 1000]"));
        assert!(sigma("0").is_err());
        assert!(sigma("nan").is_err());
        assert!(angular_tol("4").unwrap_err().contains("[0, 0.1]"));
        assert_eq!(angular_tol("0"), Ok(0.0));
        assert!(joint_value("nan").is_err());
        assert!(joint_value("inf").is_err());
        assert_eq!(joint_value("-1.5"), Ok(-1.5));
        assert!(folds("0").unwrap_err().contains("[2, 100]"));
        assert!(samples("1000000000").is_err());
        assert!(poses("100000000").is_err());
        assert_eq!(poses("100"), Ok(100));
    }
}
