//! Poses and sweeps (module docs, steps 1 and 2): consecutive samples with the same joint values
//! are one pose; maximal runs of poses in which the same joints change in the same proportion
//! are a sweep; a sweep's points are grouped per target and pose for the fits.

use super::*;

/// A set of consecutive samples at one joint configuration.
pub(super) struct Pose {
    pub(super) q: Vec<f64>,
    pub(super) samples: Vec<usize>,
}

pub(super) fn group_poses(m: &Measurements, unchanged: f64) -> Vec<Pose> {
    let mut poses: Vec<Pose> = Vec::new();
    for (i, s) in m.samples.iter().enumerate() {
        match poses.last_mut() {
            Some(p)
                if p.q
                    .iter()
                    .zip(s.q.iter())
                    .all(|(a, b)| (a - b).abs() <= unchanged) =>
            {
                p.samples.push(i);
            }
            _ => poses.push(Pose {
                q: s.q.to_vec(),
                samples: vec![i],
            }),
        }
    }
    poses
}

/// The joints that change from pose `a` to pose `b`.
pub(super) fn changed(a: &Pose, b: &Pose, unchanged: f64) -> Vec<usize> {
    (0..a.q.len())
        .filter(|&j| (b.q[j] - a.q[j]).abs() > unchanged)
        .collect()
}

pub(super) fn find_sweeps(m: &Measurements, poses: &[Pose], opts: &CpaOptions) -> Vec<Sweep> {
    let tol = opts.unchanged;
    let mut sweeps = Vec::new();
    let mut start = 0;
    while start + 1 < poses.len() {
        let set = changed(&poses[start], &poses[start + 1], tol);
        let Some(&lead) = set.first() else {
            start += 1;
            continue;
        };
        let step = |i: usize, j: usize| poses[i + 1].q[j] - poses[i].q[j];
        let ratios: Vec<(usize, f64)> = set[1..]
            .iter()
            .map(|&f| (f, step(start, f) / step(start, lead)))
            .collect();
        let mut end = start + 1;
        while end + 1 < poses.len() {
            let same_set = changed(&poses[end], &poses[end + 1], tol) == set;
            // Each value may be off by `tol`, so a difference by twice that.
            let proportional = ratios
                .iter()
                .all(|&(f, k)| (step(end, f) - k * step(end, lead)).abs() <= 2.0 * tol);
            if !(same_set && proportional) {
                break;
            }
            end += 1;
        }
        let count = end - start + 1;
        if count >= opts.min_poses {
            let run = &poses[start..=end];
            let samples: Vec<usize> = run.iter().flat_map(|p| p.samples.clone()).collect();
            let values = run.iter().map(|p| p.q[lead]);
            let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            });
            // Fit the ratio over the whole run rather than the first step alone.
            let coupled = ratios
                .iter()
                .map(|&(f, _)| {
                    let (mut num, mut den) = (0.0, 0.0);
                    for i in start..end {
                        num += step(i, f) * step(i, lead);
                        den += step(i, lead) * step(i, lead);
                    }
                    Coupled {
                        joint: f,
                        name: m.joint_names[f].clone(),
                        ratio: num / den,
                    }
                })
                .collect();
            let first = samples.first().map_or(0, |&i| m.samples[i].line);
            let last = samples.last().map_or(0, |&i| m.samples[i].line);
            sweeps.push(Sweep {
                joint: lead,
                name: m.joint_names[lead].clone(),
                coupled,
                samples,
                poses: count,
                start: run[0].q.clone(),
                span: hi - lo,
                lines: (first, last),
                used: false,
            });
        }
        start = end;
    }
    sweeps
}

pub(super) fn describe(sweeps: &[Sweep], kinds: &[JointKind]) -> String {
    if sweeps.is_empty() {
        return "none".into();
    }
    let mut out = String::new();
    for (i, s) in sweeps.iter().enumerate() {
        if i > 0 {
            out.push_str("; ");
        }
        let _ = write!(out, "{}", s.name);
        for c in &s.coupled {
            let _ = write!(out, " with {} (x{})", c.name, c.ratio);
        }
        let _ = match kinds[s.joint] {
            JointKind::Revolute => {
                write!(out, ": {} poses, {:.1} deg", s.poses, s.span.to_degrees())
            }
            JointKind::Prismatic => write!(out, ": {} poses, {:.4} m", s.poses, s.span),
        };
    }
    out
}

/// Groups of one sweep: per target, (target index, per pose: (commanded lead value, points)).
pub(super) type Groups = Vec<(usize, Vec<(f64, Vec<Vector3<f64>>)>)>;

/// The sweep's points per target and pose, without the samples `skip` (sorted indices).
pub(super) fn groups(m: &Measurements, poses: &[Pose], sweep: &Sweep, skip: &[usize]) -> Groups {
    let mut out: Groups = Vec::new();
    let in_sweep =
        |i: &usize| sweep.samples.binary_search(i).is_ok() && skip.binary_search(i).is_err();
    for pose in poses {
        let members: Vec<usize> = pose.samples.iter().copied().filter(in_sweep).collect();
        if members.is_empty() {
            continue;
        }
        let q = pose.q[sweep.joint];
        for i in members {
            let s = &m.samples[i];
            let slot = match out.iter().position(|(t, _)| *t == s.target) {
                Some(k) => k,
                None => {
                    out.push((s.target, Vec::new()));
                    out.len() - 1
                }
            };
            let per_pose = &mut out[slot].1;
            match per_pose.last_mut() {
                Some((last_q, pts)) if *last_q == q => pts.push(s.point),
                _ => per_pose.push((q, vec![s.point])),
            }
        }
    }
    // A target seen at fewer than three poses fits no circle: leave it out.
    out.retain(|(_, per_pose)| per_pose.len() >= 3);
    out
}

pub(super) fn target_name(m: &Measurements, t: usize) -> String {
    m.targets.get(t).cloned().unwrap_or_else(|| t.to_string())
}
