//! The ranges of the numeric options, one parser per option: a finite number (or count) within
//! a stated range, the error naming the range, so `--sigma 1e200` reads "expected a length in
//! [1e-9, 1000], found 1e200". The command line uses them as its value parsers (clap prefixes the
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
        "expected {what} in {open}{}, {}], found {}",
        bound(lo),
        bound(hi),
        escape(s.trim())
    ))
}

/// A range's end as a reader writes it: `1e-9`, not `0.000000001`.
fn bound(v: f64) -> String {
    if v != 0.0 && !(1e-3..1e6).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
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

/// Smallest standard deviation of a measurement (metres for a length, radians for an angle):
/// a nanometre is below every measuring device's noise, and a chi-square of residuals over it
/// stays finite (a sigma of 1e-300 made it infinite and the verdict "complete"). The option's
/// value in the files' length unit, the CSV columns `sigma`, `sx`, `sy`, `sz` (in metres once
/// converted) and `sigma_rot` are held to it: [`dh_calib::MIN_SIGMA`].
pub const MIN_SIGMA: f64 = dh_calib::MIN_SIGMA;

/// Largest `--sigma`, in the files' length unit (1 m in mm, 1 km in m: far above any measuring
/// device, far below overflow when squared).
pub const MAX_SIGMA: f64 = 1000.0;

/// `--sigma`: a standard deviation in the files' length unit, in `[1e-9, 1000]`.
pub fn sigma(s: &str) -> Result<f64, String> {
    ranged(s, "a length", MIN_SIGMA, MAX_SIGMA, false)
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

/// Largest `--samples` of any proof (`extract`, `convert`, `to-urdf`, `batch`), whatever the
/// chain: a 6-joint arm may use it (6e6 joint evaluations), a longer chain is held to
/// [`max_samples`].
pub const MAX_SAMPLES: usize = 1_000_000;
/// Fewest samples of a proof: the zero pose (always the first sample). Zero samples would
/// prove nothing and report a PASS.
pub const MIN_SAMPLES: usize = 1;
/// Most joint evaluations (samples x joints) one proof may cost: the budget of `extract`'s
/// default sample count ([`crate::extract::default_samples`]).
pub const MAX_PROOF_EVALUATIONS: usize = 10_000_000;
/// Fewest samples [`max_samples`] allows, however long the chain (a 10^6-joint chain still gets
/// 10 samples).
const FLOOR_OF_MAX_SAMPLES: usize = 10;

/// `--samples`: `[1, 1 000 000]` (a chain of `n` joints is then held to [`max_samples`] by
/// [`check_samples`]).
pub fn samples(s: &str) -> Result<usize, String> {
    counted(s, "a number of samples", MIN_SAMPLES, MAX_SAMPLES)
}

/// The most samples a proof of a chain of `joints` joints may take: [`MAX_PROOF_EVALUATIONS`]
/// over the joint count, within `[10, MAX_SAMPLES]`.
pub fn max_samples(joints: usize) -> usize {
    (MAX_PROOF_EVALUATIONS / joints.max(1)).clamp(FLOOR_OF_MAX_SAMPLES, MAX_SAMPLES)
}

/// The library's check of a proof's sample count (every proof calls it, so Python and Rust
/// callers get the command line's range): `samples` in `[1, max_samples(joints)]`.
///
/// # Errors
/// The message names the range, and the joint count when it narrows it.
pub fn check_samples(samples: usize, joints: usize) -> Result<usize, String> {
    let most = max_samples(joints);
    if (MIN_SAMPLES..=most).contains(&samples) {
        return Ok(samples);
    }
    let why = if most < MAX_SAMPLES {
        format!(
            " for a chain of {joints} joints (at most {MAX_PROOF_EVALUATIONS:.0e} joint \
             evaluations in all)"
        )
    } else {
        String::new()
    };
    Err(format!(
        "expected a number of samples in [{MIN_SAMPLES}, {most}]{why}, found {samples}"
    ))
}

/// A sampler's `--seed`: an integer in `[0, 2^64 - 1]` (the command line's `u64`), for the
/// Python package (clap parses the option itself).
pub fn seed(s: &str) -> Result<u64, String> {
    s.trim().parse().map_err(|_| {
        format!(
            "expected an integer in [0, {}], found '{}'",
            u64::MAX,
            escape(s)
        )
    })
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
        assert!(sigma("1e200").unwrap_err().contains("[1e-9, 1000]"));
        assert!(sigma("0").is_err());
        assert!(sigma("nan").is_err());
        assert!(angular_tol("4").unwrap_err().contains("[0, 0.1]"));
        assert_eq!(angular_tol("0"), Ok(0.0));
        assert!(joint_value("nan").is_err());
        assert!(joint_value("inf").is_err());
        assert_eq!(joint_value("-1.5"), Ok(-1.5));
        assert!(folds("0").unwrap_err().contains("[2, 100]"));
        assert!(samples("1000000000").is_err());
        assert!(samples("0").unwrap_err().contains("[1, 1000000]"));
        assert!(poses("100000000").is_err());
        assert_eq!(poses("100"), Ok(100));
    }

    #[test]
    fn sigma_has_a_physical_lower_bound() {
        assert_eq!(sigma("1e-9"), Ok(1e-9));
        for tiny in ["1e-300", "5e-324", "9.99e-10", "0"] {
            let e = sigma(tiny).unwrap_err();
            assert!(e.contains("in [1e-9, 1000]"), "{tiny}: {e}");
        }
        assert!(sigma("1000.0001").is_err());
    }

    #[test]
    fn every_proof_is_held_to_ten_million_joint_evaluations() {
        assert_eq!(check_samples(1000, 6), Ok(1000));
        assert_eq!(check_samples(1_000_000, 6), Ok(1_000_000));
        assert!(check_samples(0, 6)
            .unwrap_err()
            .contains("[1, 1000000], found 0"));
        // 10 000 joints: 1000 samples; 100 000 joints: 100; a million joints still 10.
        assert_eq!(max_samples(10_000), 1000);
        assert_eq!(max_samples(100_000), 100);
        assert_eq!(max_samples(1_000_000), 10);
        assert_eq!(max_samples(0), MAX_SAMPLES);
        let e = check_samples(1001, 10_000).unwrap_err();
        assert!(
            e.contains("in [1, 1000] for a chain of 10000 joints (at most 1e7 joint evaluations in all), found 1001"),
            "{e}"
        );
        // The default of extract stays within it for every length.
        for n in [1, 6, 10_000, 12_345, 100_000, 5_000_000] {
            let d = crate::extract::default_samples(n);
            assert_eq!(check_samples(d, n), Ok(d), "{n}");
        }
    }

    #[test]
    fn seeds_are_unsigned_integers() {
        assert_eq!(seed("7"), Ok(7));
        assert!(seed("-1").unwrap_err().contains("found '-1'"));
        assert!(seed("1.5").is_err());
    }
}
