//! The analysis itself ([`analyse`], module docs steps 1, 2 and 5): input checks, grouping
//! samples into poses, finding sweeps (one joint, or coupled joints in a fixed proportion) and
//! the per-target point groups each sweep fits.

use super::*;

/// Runs circle-point analysis on a measurement set (see the [module docs](self)).
///
/// Frames: points, axes and the DH base are in the measuring device's frame; metres and
/// radians.
///
/// # Errors
/// [`CpaError::NoSamples`], [`CpaError::JointCount`], [`CpaError::NonFinite`] and
/// [`CpaError::InvalidOption`] for bad input; [`CpaError::NotSwept`] when some joint has no sweep of at least
/// [`CpaOptions::min_poses`] poses; [`CpaError::Degenerate`] when a sweep's points fit no circle
/// or line; [`CpaError::NotRigid`] for a coupled sweep that is not a rotation about the lead
/// axis; [`CpaError::Sense`] when the sense of rotation cannot be told; [`CpaError::Core`] from
/// the DH extraction.
pub fn analyse(m: &Measurements, opts: &CpaOptions) -> Result<CpaResult, CpaError> {
    check_input(m, opts)?;
    if m.session_count() > 1 {
        // Circles fitted across sessions would mix device frames.
        return Err(CpaError::InvalidOption {
            option: "session",
            expected: "one measurement session (circles are fitted in one device frame); give a nominal model to calibrate several sessions",
            found: format!("{} sessions ({})", m.session_count(), m.sessions.join(", ")),
        });
    }
    let kinds: Vec<JointKind> = m
        .joint_names
        .iter()
        .map(|n| {
            if opts.prismatic.contains(n) {
                JointKind::Prismatic
            } else {
                JointKind::Revolute
            }
        })
        .collect();
    let poses = group_poses(m, opts.unchanged);
    let mut sweeps = find_sweeps(m, &poses, opts);

    // One sweep per joint: most poses, then largest span.
    let n = m.joint_names.len();
    let mut chosen: Vec<Option<usize>> = vec![None; n];
    for (i, s) in sweeps.iter().enumerate() {
        let better = match chosen[s.joint] {
            None => true,
            Some(c) => (s.poses, s.span) > (sweeps[c].poses, sweeps[c].span),
        };
        if better {
            chosen[s.joint] = Some(i);
        }
    }
    let missing: Vec<String> = (0..n)
        .filter(|&j| chosen[j].is_none())
        .map(|j| m.joint_names[j].clone())
        .collect();
    if !missing.is_empty() {
        return Err(CpaError::NotSwept {
            missing,
            found: describe(&sweeps, &kinds),
        });
    }
    let chosen: Vec<usize> = chosen.into_iter().flatten().collect();
    for &c in &chosen {
        sweeps[c].used = true;
    }

    let mut joints = Vec::with_capacity(n);
    for (j, &c) in chosen.iter().enumerate() {
        joints.push(fit_sweep(m, &poses, &sweeps[c], c, kinds[j], opts)?);
    }

    // Serial joint variables: a follower of a used coupled sweep is q_f − k q_lead.
    let mut coupling: Vec<Option<(usize, f64)>> = vec![None; n];
    for &c in &chosen {
        for f in &sweeps[c].coupled {
            coupling[f.joint] = Some((sweeps[c].joint, f.ratio));
        }
    }
    let serial = |q: &[f64]| -> Vec<f64> {
        q.iter()
            .enumerate()
            .map(|(j, &v)| match coupling[j] {
                Some((lead, k)) => v - k * q[lead],
                None => v,
            })
            .collect()
    };

    // Axes at q = 0, base to tip.
    let mut zero: Vec<(JointKind, Line)> = Vec::with_capacity(n);
    for (j, joint) in joints.iter().enumerate() {
        let theta = serial(&sweeps[chosen[j]].start);
        let back = chain_motion(&zero, &theta).inverse();
        zero.push((joint.kind, joint.axis.transformed(&back)));
    }
    let last = n - 1;
    let tip_at_sweep = tip_pose(m, &poses, &sweeps[chosen[last]], &joints[last])?;
    let theta = serial(&sweeps[chosen[last]].start);
    let tip = chain_motion(&zero[..last], &theta).inverse() * tip_at_sweep;

    let axes: Vec<JointAxis> = zero
        .iter()
        .zip(&m.joint_names)
        .map(|((kind, line), name)| JointAxis {
            name: name.clone(),
            kind: *kind,
            line: *line,
            limits: None,
            mimic: None,
        })
        .collect();
    let snapped = extract(&axes, &tip, opts.tolerance, opts.convention)?;
    let extraction = measured_parallels(snapped, &axes, &tip, opts)?;
    Ok(CpaResult {
        sweeps,
        joints,
        axes,
        tip,
        extraction,
    })
}

/// Nearly parallel measured axes are the measurement, not noise to snap away: when the
/// extraction snapped a pair that is not exactly parallel, the table is extracted again without
/// angular snapping (only the linear tolerance decides) and every pair within
/// [`ModelOptions::DEFAULT_HAYATI_THRESHOLD`](crate::model::ModelOptions) of parallel is
/// written in the Hayati-Mirmirani form ([`dh_core::DhTable::hayati_form`]): a small `beta`
/// and bounded lengths, the placement `calibrate` estimates. The ill-conditioned warnings of
/// the pairs so written are dropped: their rows are no longer ill conditioned.
pub(super) fn measured_parallels(
    snapped: Extraction,
    axes: &[JointAxis],
    tip: &Isometry3<f64>,
    opts: &CpaOptions,
) -> Result<Extraction, CpaError> {
    let tilted_snap = snapped.warnings.iter().any(
        |w| matches!(w, Warning::SnappedParallel { angle_deviation, .. } if *angle_deviation > 0.0),
    );
    if !tilted_snap {
        return Ok(snapped);
    }
    let threshold = crate::model::ModelOptions::DEFAULT_HAYATI_THRESHOLD;
    let exact_tol = Tolerance::new(opts.tolerance.linear, EXACT_ANGLE)?;
    let mut exact = extract(axes, tip, exact_tol, opts.convention)?;
    exact.table = exact.table.hayati_form(threshold);
    exact.warnings.retain(
        |w| !matches!(w, Warning::IllConditioned { angle_from_parallel, .. } if *angle_from_parallel <= threshold),
    );
    Ok(exact)
}

/// Angular tolerance (radians) of the extraction that keeps measured near-parallel pairs as
/// they are: far below any measurement, so only exactly parallel axes snap.
pub(super) const EXACT_ANGLE: f64 = 1e-12;

pub(super) fn check_input(m: &Measurements, opts: &CpaOptions) -> Result<(), CpaError> {
    if m.samples.is_empty() || m.joint_names.is_empty() {
        return Err(CpaError::NoSamples);
    }
    for s in &m.samples {
        if s.q.len() != m.joint_names.len() {
            return Err(CpaError::JointCount {
                line: s.line,
                expected: m.joint_names.len(),
                found: s.q.len(),
            });
        }
        if let Some(&value) = s.q.iter().chain(s.point.iter()).find(|v| !v.is_finite()) {
            return Err(CpaError::NonFinite {
                line: s.line,
                value,
            });
        }
    }
    if !opts.unchanged.is_finite() || opts.unchanged < 0.0 {
        return Err(CpaError::InvalidOption {
            option: "unchanged",
            expected: "a finite value >= 0",
            found: opts.unchanged.to_string(),
        });
    }
    if opts.min_poses < 3 {
        return Err(CpaError::InvalidOption {
            option: "min_poses",
            expected: "at least 3",
            found: opts.min_poses.to_string(),
        });
    }
    Ok(())
}

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
                    .zip(&s.q)
                    .all(|(a, b)| (a - b).abs() <= unchanged) =>
            {
                p.samples.push(i);
            }
            _ => poses.push(Pose {
                q: s.q.clone(),
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

pub(super) fn groups(m: &Measurements, poses: &[Pose], sweep: &Sweep) -> Groups {
    let mut out: Groups = Vec::new();
    let in_sweep = |i: &usize| sweep.samples.binary_search(i).is_ok();
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

pub(super) fn fit_sweep(
    m: &Measurements,
    poses: &[Pose],
    sweep: &Sweep,
    index: usize,
    kind: JointKind,
    opts: &CpaOptions,
) -> Result<JointCpa, CpaError> {
    let groups = groups(m, poses, sweep);
    if groups.is_empty() {
        return Err(CpaError::Degenerate {
            joint: sweep.name.clone(),
            target: m.targets.join(", "),
            what: "no target was measured at three or more poses of the sweep".into(),
        });
    }
    match kind {
        JointKind::Revolute => fit_revolute(m, sweep, index, &groups, opts),
        JointKind::Prismatic => fit_prismatic(m, sweep, index, &groups),
    }
}
