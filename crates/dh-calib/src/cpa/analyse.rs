//! The analysis itself ([`analyse`], module docs steps 1 to 5): input checks, the sweeps found
//! (`sweeps`), each joint fitted (`joint_fit`), and the axes' DH extraction.

use super::*;

/// Runs circle-point analysis on a measurement set (see the [module docs](crate::cpa)).
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
        joints.push(fit_screened(m, &poses, &sweeps[c], c, kinds[j], opts)?);
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
