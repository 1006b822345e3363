//! `calibration.conf`, where a Universal Robots controller keeps each arm's factory
//! calibration: INI-like sections (`[mounting]`), `key = value` lines, arrays written
//! `[ a, b, c, d, e, f ]` (possibly over several lines), `#` or `;` comments. The four keys read
//! are `[mounting]`'s `delta_theta`, `delta_a`, `delta_d`, `delta_alpha` (radians, metres, one
//! number per joint, standard DH); every other key and section is ignored.

use anyhow::Result;

use crate::error::hinted;

/// The four keys read, in the order of [`Deltas::row`].
const KEYS: [&str; 4] = ["delta_theta", "delta_a", "delta_d", "delta_alpha"];

/// Largest delta accepted (metres or radians): real ones reach about ten metres (the `d` of
/// nearly parallel axes); beyond this the file is not a calibration.
const MAX_DELTA: f64 = 1e6;

/// Per-joint standard DH deltas (metres, radians).
#[derive(Clone, Debug, PartialEq)]
pub struct Deltas {
    theta: Vec<f64>,
    a: Vec<f64>,
    d: Vec<f64>,
    alpha: Vec<f64>,
}

impl Deltas {
    /// Deltas from four arrays of one length.
    ///
    /// # Errors
    /// Arrays of different lengths, an empty array, a number that is not finite or beyond
    /// 1e6.
    pub fn new(theta: Vec<f64>, a: Vec<f64>, d: Vec<f64>, alpha: Vec<f64>) -> Result<Deltas> {
        let n = theta.len();
        for (key, v) in KEYS.iter().zip([&theta, &a, &d, &alpha]) {
            if v.len() != n || n == 0 {
                anyhow::bail!(
                    "{key}: expected as many numbers as delta_theta ({n}, at least 1), found {}",
                    v.len()
                );
            }
            if let Some(x) = v.iter().find(|x| !x.is_finite() || x.abs() > MAX_DELTA) {
                anyhow::bail!("{key}: expected finite numbers within {MAX_DELTA:e}, found {x}");
            }
        }
        Ok(Deltas { theta, a, d, alpha })
    }

    /// Number of joints.
    pub fn len(&self) -> usize {
        self.theta.len()
    }

    /// Whether there are no joints (never, for deltas built by [`Deltas::new`]).
    pub fn is_empty(&self) -> bool {
        self.theta.is_empty()
    }

    /// Joint `k`'s `[delta_theta, delta_a, delta_d, delta_alpha]`; zeros beyond the last.
    pub fn row(&self, k: usize) -> [f64; 4] {
        let at = |v: &Vec<f64>| v.get(k).copied().unwrap_or(0.0);
        [at(&self.theta), at(&self.a), at(&self.d), at(&self.alpha)]
    }
}

/// A `calibration.conf` read: its deltas and the other keys of `[mounting]` (ignored).
#[derive(Clone, Debug, PartialEq)]
pub struct CalibrationConf {
    /// The deltas.
    pub deltas: Deltas,
    /// The other keys of `[mounting]`, in file order (`joint_checksum`, ...).
    pub ignored: Vec<String>,
}

impl CalibrationConf {
    /// Reads `text`; `origin` names the file in messages.
    ///
    /// # Errors
    /// No `[mounting]` section; one of the four keys missing or given twice; a value that is
    /// not an array of numbers (naming the line); arrays of different lengths.
    pub fn parse(text: &str, origin: &str) -> Result<CalibrationConf> {
        let text = text.trim_start_matches('\u{feff}');
        let mut section = String::new();
        let mut seen_mounting = false;
        let mut found: [Option<(Vec<f64>, usize)>; 4] = [None, None, None, None];
        let mut ignored = Vec::new();
        let mut lines = text.lines().enumerate();
        while let Some((k, raw)) = lines.next() {
            let line_no = k + 1;
            let line = raw.trim();
            if line.is_empty() || line.starts_with('#') || line.starts_with(';') {
                continue;
            }
            if let Some(name) = line
                .strip_prefix('[')
                .and_then(|l| l.strip_suffix(']'))
                .filter(|_| !line.contains('='))
            {
                section = name.trim().to_owned();
                seen_mounting |= section == "mounting";
                continue;
            }
            let Some((key, value)) = line.split_once('=') else {
                anyhow::bail!("{origin}: line {line_no}: expected 'key = value' or '[section]', found '{line}'");
            };
            let (key, mut value) = (key.trim(), value.trim().to_owned());
            // An array may go on over the next lines until its ']'.
            if value.starts_with('[') {
                while !value.contains(']') {
                    let Some((_, more)) = lines.next() else {
                        anyhow::bail!("{origin}: line {line_no}: {key}: expected ']' closing the array, found the end of the file");
                    };
                    value.push(' ');
                    value.push_str(more.trim());
                }
            }
            if section != "mounting" {
                continue;
            }
            let Some(slot) = KEYS.iter().position(|k| *k == key) else {
                ignored.push(key.to_owned());
                continue;
            };
            let Some(entry) = found.get_mut(slot) else {
                continue;
            };
            if let Some((_, first)) = entry {
                anyhow::bail!("{origin}: line {line_no}: {key}: expected it once in [mounting], found it again (first at line {first})");
            }
            let numbers = array(&value)
                .map_err(|m| anyhow::anyhow!("{origin}: line {line_no}: {key}: {m}"))?;
            *entry = Some((numbers, line_no));
        }
        if !seen_mounting {
            return Err(hinted(
                format!("{origin}: expected a [mounting] section, found none"),
                "a UR controller's calibration.conf holds delta_theta, delta_a, delta_d and delta_alpha under [mounting]",
            ));
        }
        let [theta, a, d, alpha] = found;
        let take = |v: Option<(Vec<f64>, usize)>, key: &str| {
            v.map(|(x, _)| x).ok_or_else(|| {
                hinted(
                    format!("{origin}: [mounting]: expected '{key} = [ ... ]', found none"),
                    "the four keys delta_theta, delta_a, delta_d, delta_alpha are all needed",
                )
            })
        };
        let [k_theta, k_a, k_d, k_alpha] = KEYS;
        let deltas = Deltas::new(
            take(theta, k_theta)?,
            take(a, k_a)?,
            take(d, k_d)?,
            take(alpha, k_alpha)?,
        )
        .map_err(|e| anyhow::anyhow!("{origin}: [mounting]: {e}"))?;
        Ok(CalibrationConf { deltas, ignored })
    }
}

/// `[ a, b, c ]` as numbers.
fn array(value: &str) -> Result<Vec<f64>, String> {
    let inner = value
        .strip_prefix('[')
        .and_then(|v| v.strip_suffix(']'))
        .ok_or_else(|| format!("expected an array '[ a, b, ... ]', found '{value}'"))?;
    inner
        .split(',')
        .map(str::trim)
        .filter(|t| !t.is_empty())
        .map(|t| {
            t.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| format!("expected finite numbers, found '{t}'"))
        })
        .collect()
}
