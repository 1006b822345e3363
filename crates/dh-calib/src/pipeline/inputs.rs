//! Preparing the measurements of a calibration: a separate validation set merged in as
//! validation samples ([`merge_validation`], sessions matched by name), a subset of the targets
//! kept ([`keep_targets`]), and the check that the calibration samples can determine their own
//! unknowns ([`enough_samples`]).

use std::collections::HashMap;

use super::PipelineError;
use crate::data::{Measurements, Split};

/// Name of the session of a validation set without sessions when the calibration data names its
/// sessions (or the other way round).
pub const UNNAMED_VALIDATION: &str = "validation";

/// Matches the sessions of `extra` (a validation set) to those of `data` by name, adding the
/// new ones to `data.sessions`; returns `data`'s index of each of `extra`'s sessions. When
/// neither names sessions, everything stays in one session. When only one of them does, the
/// other's samples are one session of their own (`"1"` for the calibration data,
/// [`UNNAMED_VALIDATION`] for the validation set), whose frame is then estimated apart.
pub fn merge_sessions(data: &mut Measurements, extra: &Measurements) -> Vec<usize> {
    if data.sessions.is_empty() && extra.sessions.is_empty() {
        return vec![0];
    }
    if data.sessions.is_empty() {
        data.sessions.push(data.session_name(0));
    }
    let names: Vec<String> = if extra.sessions.is_empty() {
        vec![UNNAMED_VALIDATION.to_string()]
    } else {
        extra.sessions.clone()
    };
    names
        .into_iter()
        .map(|n| match data.sessions.iter().position(|s| *s == n) {
            Some(i) => i,
            None => {
                data.sessions.push(n);
                data.sessions.len() - 1
            }
        })
        .collect()
}

/// Appends `extra`'s samples to `data` as validation samples, targets and sessions matched by
/// name (see [`merge_sessions`]). Both must have the same joint columns.
pub fn merge_validation(data: &mut Measurements, extra: Measurements) {
    let mut index: HashMap<String, usize> = data
        .targets
        .iter()
        .enumerate()
        .map(|(i, t)| (t.clone(), i))
        .collect();
    let sessions = merge_sessions(data, &extra);
    for mut s in extra.samples {
        s.session = sessions.get(s.session).copied().unwrap_or(0);
        let name = extra.targets.get(s.target).cloned().unwrap_or_default();
        let next = data.targets.len();
        let k = *index.entry(name.clone()).or_insert_with(|| {
            data.targets.push(name);
            next
        });
        s.target = k;
        s.split = Split::Validation;
        data.samples.push(s);
    }
}

/// Keeps the samples of the targets named in `keep` and renumbers the targets.
///
/// # Errors
/// [`PipelineError::UnknownTarget`] for a name the data does not have.
pub fn keep_targets(data: &mut Measurements, keep: &[String]) -> Result<(), PipelineError> {
    if let Some(k) = keep.iter().find(|k| !data.targets.contains(k)) {
        return Err(PipelineError::UnknownTarget {
            target: k.clone(),
            targets: data.targets.clone(),
        });
    }
    let old = std::mem::take(&mut data.targets);
    let mut map = vec![None; old.len()];
    for (i, t) in old.iter().enumerate() {
        if keep.contains(t) {
            map[i] = Some(data.targets.len());
            data.targets.push(t.clone());
        }
    }
    data.samples
        .retain_mut(|s| match map.get(s.target).copied().flatten() {
            Some(k) => {
                s.target = k;
                true
            }
            None => false,
        });
    Ok(())
}

/// Refuses, before any fitting, point data that cannot determine its own unknowns: every step
/// estimates each target's position (3 parameters) and the device frame (6), and each sample
/// gives 3 coordinates, so fewer than `targets + 3` calibration samples fit nothing.
///
/// # Errors
/// [`PipelineError::TooFewSamples`].
pub fn enough_samples(data: &Measurements) -> Result<(), PipelineError> {
    // The distinct targets of the calibration samples, marked by index (one outside the set's
    // list, which `prepare` refuses later, counted apart), without a list of millions.
    let mut marked = vec![false; data.targets.len()];
    let mut beyond = std::collections::BTreeSet::new();
    let mut found = 0;
    for s in data
        .samples
        .iter()
        .filter(|s| s.split == Split::Calibration)
    {
        found += 1;
        match marked.get_mut(s.target) {
            Some(m) => *m = true,
            None => {
                beyond.insert(s.target);
            }
        }
    }
    let targets = marked.iter().filter(|m| **m).count() + beyond.len();
    let needed = targets + 3;
    if found < needed {
        return Err(PipelineError::TooFewSamples {
            needed,
            targets,
            found,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::Sample;
    use nalgebra::Vector3;

    /// The count asks for 3 calibration samples more than their distinct targets: validation
    /// samples are not counted, and a target index beyond the set's list counts once.
    #[test]
    fn enough_samples_counts_the_distinct_targets_of_the_calibration_samples() {
        let sample = |target: usize, split: Split| Sample {
            target,
            split,
            ..Sample::test_point(&[0.0; 6], Vector3::zeros(), 2)
        };
        let mut data = Measurements::test_ur5(vec![
            sample(0, Split::Calibration),
            sample(0, Split::Calibration),
            sample(7, Split::Calibration),
            sample(7, Split::Calibration),
            sample(0, Split::Validation),
        ]);
        // Targets 0 and 7 (beyond the list of one): 5 needed, 4 found.
        let Err(PipelineError::TooFewSamples {
            needed,
            targets,
            found,
        }) = enough_samples(&data)
        else {
            panic!("expected too few samples");
        };
        assert_eq!((needed, targets, found), (5, 2, 4));
        data.samples.push(sample(7, Split::Calibration));
        assert!(enough_samples(&data).is_ok());
    }
}
