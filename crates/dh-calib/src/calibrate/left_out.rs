//! The points an outlier screen left out, kept beside a session so that a fit with an effect
//! the screen's model lacked can judge them again (issue 33 §4): a clean pose that only an
//! unmodelled effect put far off is the best evidence for that effect, and must not be lost
//! while the effect is judged.
//!
//! Each left-out sample is prepared as the session's own are (its place in the whole file's
//! sequence: a pose left out was still visited), and carries its per-axis scale as the screen
//! standardised it (the known noise when the screen's scale was known, else the screen's
//! robust scale). A point is *explained* by a fit when its standardised position residual
//! `‖r / s‖` there is within the screen's threshold of its split (the point's own judgement,
//! against that fit).

use std::collections::HashMap;

use super::*;
use crate::outliers::{OutlierReport, ScaleSource};

/// The samples an outlier screen left out, prepared for the session's model.
pub(crate) struct LeftOut {
    /// The left-out calibration samples (`cal`) and validation samples (`val`), in file order.
    pub(crate) prep: Prepared,
    /// The pose of each of `prep.cal` (numbered from 0: samples sharing `config` share one;
    /// a sample without one is a pose of its own).
    pub(crate) cal_poses: Vec<usize>,
    /// Per-axis scale of each of `prep.cal` (metres).
    pub(crate) cal_scales: Vec<Vector3<f64>>,
    /// Per-axis scale of each of `prep.val` (metres).
    pub(crate) val_scales: Vec<Vector3<f64>>,
    /// The held-out group of each of `prep.val`: that of the kept validation samples of its
    /// pose (same `config`) when there are some, else one of its own per pose, numbered after
    /// the session's groups.
    pub(crate) val_groups: Vec<usize>,
    /// The screen's threshold on `‖r / s‖` for calibration points.
    pub(crate) threshold: f64,
    /// The screen's threshold for validation points.
    pub(crate) validation_threshold: f64,
}

impl LeftOut {
    /// The samples of `data` that `scan` left out, prepared as a session of `data` without
    /// them prepares its own (`directions`: some effect reads the direction of motion);
    /// `kept_val_groups` are the held-out groups of the kept validation samples, in file
    /// order. `None` when nothing was left out (or the points were kept in the fit), or when
    /// no validation point and calibration points of fewer than `min_poses` poses were (no
    /// use for them then: a pose of its own is no structure).
    ///
    /// # Errors
    /// Those of [`prepare`].
    pub(crate) fn new(
        tree: &DhTree,
        data: &Measurements,
        options: &CalibrationOptions,
        scan: Option<&OutlierReport>,
        directions: bool,
        (kept_val_groups, min_poses): (&[usize], usize),
    ) -> Result<Option<LeftOut>, CalibError> {
        let Some(scan) = scan.filter(|s| !s.left_out().is_empty()) else {
            return Ok(None);
        };
        // Needed for a left-out validation point (with a validation split, which every
        // validation sample makes) or for left-out calibration points of several poses.
        let mut poses = std::collections::BTreeSet::new();
        for o in scan.outliers.iter().filter(|o| !o.validation) {
            poses.insert(
                o.config
                    .clone()
                    .unwrap_or_else(|| format!("\0{}", o.sample)),
            );
        }
        if poses.len() < min_poses && scan.outliers.iter().all(|o| !o.validation) {
            return Ok(None);
        }
        let left = scan.left_out();
        let full = sequence_of(&rows_of(tree, data)?, data);
        let sequence = kept_sequence(&full, data, |i, _| left.contains(&i));
        let subset = data.filtered(|i, _| left.contains(&i));
        let prep = prepare(tree, &subset, Some(&sequence), directions)?;
        let scale = |i: usize| -> Vector3<f64> {
            let known = match options.sigma {
                Some(v) => Some(Vector3::repeat(v)),
                None => data.samples[i].sigma.filter(|v| v.iter().all(|a| *a > 0.0)),
            };
            match (scan.source, known) {
                (ScaleSource::Known, Some(s)) => s,
                _ => Vector3::repeat(scan.scale),
            }
        };
        let is_val = |i: usize| data.samples[i].split == crate::data::Split::Validation;
        let cal_samples: Vec<usize> = left.iter().copied().filter(|&i| !is_val(i)).collect();
        let val_samples: Vec<usize> = left.iter().copied().filter(|&i| is_val(i)).collect();
        // The kept validation samples' groups, by pose.
        let config = |i: usize| data.samples[i].config.as_deref().map(str::to_string);
        let mut by_pose: HashMap<String, usize> = HashMap::new();
        let kept_val = (0..data.samples.len()).filter(|&i| is_val(i) && !left.contains(&i));
        for (i, &g) in kept_val.zip(kept_val_groups) {
            if let Some(c) = config(i) {
                by_pose.entry(c).or_insert(g);
            }
        }
        let mut next = kept_val_groups.iter().max().map_or(0, |g| g + 1);
        let mut own: HashMap<String, usize> = HashMap::new();
        let val_groups = val_samples
            .iter()
            .map(|&i| {
                let key = config(i).unwrap_or_else(|| format!("\0{i}"));
                if let Some(&g) = by_pose.get(&key) {
                    return g;
                }
                *own.entry(key).or_insert_with(|| {
                    next += 1;
                    next - 1
                })
            })
            .collect();
        let mut poses: HashMap<String, usize> = HashMap::new();
        let cal_poses = cal_samples
            .iter()
            .map(|&i| {
                let key = config(i).unwrap_or_else(|| format!("\0{i}"));
                let next = poses.len();
                *poses.entry(key).or_insert(next)
            })
            .collect();
        Ok(Some(LeftOut {
            cal_scales: cal_samples.iter().map(|&i| scale(i)).collect(),
            val_scales: val_samples.iter().map(|&i| scale(i)).collect(),
            cal_poses,
            val_groups,
            prep,
            threshold: scan.threshold,
            validation_threshold: scan.validation_threshold,
        }))
    }

    /// The left-out validation points that the fit at `before` or the one at `after` explains
    /// (see the module docs), with their held-out errors at both (as [`HeldOut::weighed`]) and
    /// their groups: `(before, after, groups)`. The two fits' figures are over the same points,
    /// chosen by the same rule for both, so that a paired comparison stays paired and neither
    /// fit is favoured by the choice (a point neither explains, a lost beam, stays out of both).
    pub(crate) fn explained_validation(
        &self,
        model: &Model,
        before: &[f64],
        after: &[f64],
    ) -> (Vec<f64>, Vec<f64>, Vec<usize>) {
        let val = &self.prep.val;
        if val.is_empty() {
            return (Vec::new(), Vec::new(), Vec::new());
        }
        let at: Vec<usize> = (0..val.len()).collect();
        let explained = |x: &[f64]| -> Vec<bool> {
            residual_vectors(model, x, val)
                .iter()
                .zip(&self.val_scales)
                .map(|(r, s)| r.component_div(s).norm() <= self.validation_threshold)
                .collect()
        };
        let (eb, ea) = (explained(before), explained(after));
        let keep: Vec<usize> = at.iter().copied().filter(|&i| eb[i] || ea[i]).collect();
        if keep.is_empty() {
            return (Vec::new(), Vec::new(), Vec::new());
        }
        let hb = held_at(model, before, val, &keep).weighed();
        let ha = held_at(model, after, val, &keep).weighed();
        let groups = keep.iter().map(|&i| self.val_groups[i]).collect();
        (hb, ha, groups)
    }
}
