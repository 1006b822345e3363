//! The outlier screen of a sweep (module docs, step 3): points a lost beam, a reflection or a
//! mistyped row put far off their target's circle are left out of the circle, the axis and
//! the motion check, and named.
//!
//! The procedure is `calibrate`'s ([`crate::outliers`]), on the circles instead of the model:
//! fit the sweep's kept points (all of them first); take every point's distance from its
//! target's fitted path (a circle: in its plane and across it, two components; a prismatic
//! joint's line: across it, two components too); standardise it by the scale `s`, the larger
//! of the known noise (the samples' own `sigma`, the largest axis) and the robust estimate
//! `sqrt(median d² / median χ²₂)` of the kept points; leave out the points with
//! `P(χ²₂ > (d/s)²) < level / N` ([`crate::outliers::threshold_in`], a Bonferroni bound over
//! the sweep's `N` points); refit and repeat until the set left out no longer changes. Unlike
//! `calibrate`'s hundreds of points, a sweep's circle has a handful, and a point a metre off
//! pulls the first fit away from every point of its target: so each round leaves out only the
//! farthest point beyond the bound (and gives back those left out that the new fit puts
//! within it), the backward deletion of the single worst point.
//!
//! The result is sound when the set settled within [`MAX_ROUNDS`] and at most
//! [`MAX_LEFT_OUT`] of the sweep's points were left out: more would be a sweep that is not a
//! circle (an unmodelled motion, a wrong joint), which no screen should hide.

use std::collections::BTreeSet;

use super::*;
use crate::outliers::{threshold_in, DEFAULT_LEVEL, MAX_ROUNDS, MIN_SCALE};

/// Largest fraction of a sweep's points the screen may leave out for the result to be sound.
pub const MAX_LEFT_OUT: f64 = 0.25;

/// Median of the chi-square distribution with 2 degrees of freedom, `2 ln 2`.
const CHI2_2_MEDIAN: f64 = 2.0 * std::f64::consts::LN_2;

/// One point left out of a sweep's fit.
#[derive(Clone, Debug, PartialEq)]
pub struct LeftOut {
    /// Index into the measurements' samples.
    pub sample: usize,
    /// 1-based line of the sample in its file (0 when generated).
    pub line: usize,
    /// Target name.
    pub target: String,
    /// Distance from the target's path fitted without the points left out (metres).
    pub distance: f64,
    /// The same in units of the scale ([`SweepScreen::scale`]).
    pub sigmas: f64,
}

/// What the screen of one sweep found.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepScreen {
    /// Points of the sweep (every target's).
    pub points: usize,
    /// The scale of the distances (metres): known noise or robust estimate, the larger.
    pub scale: f64,
    /// Threshold on `distance / scale`.
    pub threshold: f64,
    /// The points left out, in file order.
    pub left_out: Vec<LeftOut>,
    /// Fit-and-screen rounds run.
    pub rounds: usize,
    /// `false` when [`MAX_ROUNDS`] ended the screen before its set settled.
    pub converged: bool,
}

impl Default for SweepScreen {
    /// No screen run: nothing left out, sound.
    fn default() -> Self {
        SweepScreen {
            points: 0,
            scale: 0.0,
            threshold: 0.0,
            left_out: Vec::new(),
            rounds: 0,
            converged: true,
        }
    }
}

impl SweepScreen {
    /// Whether the fit can be trusted (see the module docs): the screen settled and left out
    /// at most [`MAX_LEFT_OUT`] of the points.
    pub fn sound(&self) -> bool {
        self.converged && self.left_out.len() as f64 <= MAX_LEFT_OUT * self.points as f64
    }

    /// The sample indices left out, sorted.
    pub fn samples(&self) -> Vec<usize> {
        self.left_out.iter().map(|o| o.sample).collect()
    }
}

/// Fits `sweep`'s joint with its outliers left out (see the module docs).
///
/// # Errors
/// As the fits of the joint ([`CpaError::Degenerate`], [`CpaError::NotRigid`],
/// [`CpaError::Sense`]).
pub(super) fn fit_screened(
    m: &Measurements,
    poses: &[Pose],
    sweep: &Sweep,
    index: usize,
    kind: JointKind,
    opts: &CpaOptions,
) -> Result<JointCpa, CpaError> {
    let in_sweep: Vec<usize> = sweep.samples.clone();
    let known = in_sweep
        .iter()
        .filter_map(|&i| m.samples[i].sigma.map(|s| s.max()))
        .fold(0.0f64, f64::max);
    let limit = threshold_in(in_sweep.len(), DEFAULT_LEVEL, 2.0);
    // One point more per round at most: a sweep's few points are all pulled by a gross
    // outlier in the first fit, which leaves it still the farthest.
    let most_rounds = MAX_ROUNDS + in_sweep.len() / 4;
    let mut left: BTreeSet<usize> = BTreeSet::new();
    let mut rounds = 0;
    loop {
        rounds += 1;
        let skip: Vec<usize> = left.iter().copied().collect();
        let mut joint = fit_sweep(m, poses, sweep, index, kind, opts, &skip)?;
        // Each point's distance from its target's path (none for a target the fit dropped).
        let distances: Vec<(usize, Option<f64>)> = in_sweep
            .iter()
            .map(|&i| {
                let s = &m.samples[i];
                let t = joint.targets.iter().find(|t| t.target == s.target);
                (i, t.map(|t| path_distance(t, &s.point)))
            })
            .collect();
        let mut kept: Vec<f64> = distances
            .iter()
            .filter(|(i, _)| !left.contains(i))
            .filter_map(|(_, d)| d.map(|d| d * d))
            .collect();
        kept.sort_by(f64::total_cmp);
        let median = kept.get(kept.len() / 2).copied().unwrap_or(0.0);
        let scale = known.max((median / CHI2_2_MEDIAN).sqrt()).max(MIN_SCALE);
        let beyond = |d: &Option<f64>| d.is_none_or(|d| d / scale > limit);
        // Points left out stay out while beyond the bound; the farthest kept one joins them.
        let mut next: BTreeSet<usize> = distances
            .iter()
            .filter(|(i, d)| left.contains(i) && beyond(d))
            .map(|(i, _)| *i)
            .collect();
        // Among the targets with a kept point beyond the bound, the point farthest from the
        // path fitted to its target's other points (its deleted distance): a gross outlier
        // pulls its target's whole fit, so that its clean points can be farther from that fit
        // than it is, but never from a fit without it.
        let mut worst: Option<(usize, f64)> = None;
        for (i, d) in &distances {
            if left.contains(i) || !beyond(d) {
                continue;
            }
            let target = m.samples[*i].target;
            let own: Vec<usize> = in_sweep
                .iter()
                .copied()
                .filter(|k| !left.contains(k) && m.samples[*k].target == target)
                .collect();
            for &k in &own {
                let others: Vec<Vector3<f64>> = own
                    .iter()
                    .filter(|&&o| o != k)
                    .map(|&o| m.samples[o].point)
                    .collect();
                if let Some(dk) = deleted_distance(&others, &m.samples[k].point, kind) {
                    if worst.is_none_or(|(_, w)| dk > w) {
                        worst = Some((k, dk));
                    }
                }
            }
        }
        if let Some((i, _)) = worst {
            next.insert(i);
        }
        let settled = next == left;
        if settled || rounds >= most_rounds {
            joint.screen = SweepScreen {
                points: in_sweep.len(),
                scale,
                threshold: limit,
                left_out: distances
                    .iter()
                    .filter(|(i, _)| left.contains(i))
                    .map(|&(i, d)| LeftOut {
                        sample: i,
                        line: m.samples[i].line,
                        target: target_name(m, m.samples[i].target),
                        distance: d.unwrap_or(f64::INFINITY),
                        sigmas: d.map_or(f64::INFINITY, |d| d / scale),
                    })
                    .collect(),
                rounds,
                converged: settled,
            };
            return Ok(joint);
        }
        left = next;
    }
}

/// The distance (metres) of `point` from the path fitted to `others`, its target's other
/// points: a circle for a revolute joint, a line (principal axis) for a prismatic one; `None`
/// when they fit none.
fn deleted_distance(others: &[Vector3<f64>], point: &Vector3<f64>, kind: JointKind) -> Option<f64> {
    let fit = match kind {
        JointKind::Revolute => {
            let c = fit_circle(others, CircleMethod::Geometric).ok()?;
            (c.centre, c.normal, Some(c.radius))
        }
        JointKind::Prismatic => {
            if others.len() < 2 {
                return None;
            }
            let c = mean(others);
            let centred: Vec<Vector3<f64>> = others.iter().map(|p| p - c).collect();
            let (_, vectors) = principal_axes(&centred);
            (c, vectors[0], None)
        }
    };
    let v = point - fit.0;
    let along = v.dot(&fit.1);
    let across = (v - fit.1 * along).norm();
    Some(match fit.2 {
        Some(r) => (across - r).hypot(along),
        None => across,
    })
}

/// A point's distance (metres) from a target's fitted path: its circle (radius and plane),
/// or for a prismatic joint its line through the centre along the direction.
fn path_distance(t: &TargetFit, p: &Vector3<f64>) -> f64 {
    let v = p - t.centre;
    let along = v.dot(&t.direction);
    let across = (v - t.direction * along).norm();
    match t.radius {
        Some(r) => (across - r).hypot(along),
        None => across,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_distance_has_its_in_plane_and_axial_parts() {
        let t = TargetFit {
            target: 0,
            name: "t".into(),
            points: 3,
            centre: Vector3::new(1.0, 0.0, 0.0),
            direction: Vector3::z(),
            radius: Some(0.5),
            path_rms: 0.0,
            plane_rms: Some(0.0),
            axis_offset: 0.0,
            axis_tilt: 0.0,
        };
        let d = path_distance(&t, &Vector3::new(1.0, 0.8, 0.4));
        assert!((d - 0.5).abs() < 1e-15, "{d}");
        let line = TargetFit { radius: None, ..t };
        let d = path_distance(&line, &Vector3::new(1.0, 0.3, 7.0));
        assert!((d - 0.3).abs() < 1e-15, "{d}");
    }
}
