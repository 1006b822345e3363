//! Fitting one sweep's joint (module docs, steps 3 and 4): a revolute joint's common axis of
//! concentric circles, a prismatic joint's common direction of parallel lines, the check that
//! the measured motion matches the commanded one (linear, sinusoidal and combined trends by
//! least squares), and the tip pose from the fitted axes. Device frame, metres, radians.

use super::*;

/// Fits `sweep`'s joint without the samples `skip` (sorted indices; see `screen`).
pub(super) fn fit_sweep(
    m: &Measurements,
    poses: &[Pose],
    sweep: &Sweep,
    index: usize,
    kind: JointKind,
    opts: &CpaOptions,
    skip: &[usize],
) -> Result<JointCpa, CpaError> {
    let groups = groups(m, poses, sweep, skip);
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

pub(super) fn fit_revolute(
    m: &Measurements,
    sweep: &Sweep,
    index: usize,
    groups: &Groups,
    opts: &CpaOptions,
) -> Result<JointCpa, CpaError> {
    let degenerate = |t: usize, e: CpaError| CpaError::Degenerate {
        joint: sweep.name.clone(),
        target: target_name(m, t),
        what: match e {
            CpaError::Degenerate { what, .. } => what,
            other => other.to_string(),
        },
    };
    // Per target: plane + geometric circle.
    let mut own = Vec::with_capacity(groups.len());
    for (t, per_pose) in groups {
        let pts: Vec<Vector3<f64>> = per_pose.iter().flat_map(|(_, p)| p.clone()).collect();
        let circle = fit_circle(&pts, CircleMethod::Geometric).map_err(|e| degenerate(*t, e))?;
        own.push(circle);
    }
    // Common axis: start from the targets' circles, weighting directions by r² · points.
    let reference = own
        .iter()
        .max_by(|a, b| {
            (a.radius * a.radius * a.points as f64)
                .total_cmp(&(b.radius * b.radius * b.points as f64))
        })
        .map_or(Vector3::z(), |c| c.normal);
    let mut normal = Vector3::zeros();
    let mut centre = Vector3::zeros();
    let mut count = 0.0;
    for c in &own {
        let sign = c.normal.dot(&reference).signum();
        normal += c.normal * sign * c.radius * c.radius * c.points as f64;
        centre += c.centre * c.points as f64;
        count += c.points as f64;
    }
    let normal = if normal.norm() > 0.0 {
        normal.normalize()
    } else {
        reference
    };
    let point_sets: Vec<Vec<Vector3<f64>>> = groups
        .iter()
        .map(|(_, pp)| pp.iter().flat_map(|(_, p)| p.clone()).collect())
        .collect();
    let mut fit = fit_coaxial(&point_sets, centre / count, normal, &own);

    // Sense: rotation about the axis must follow the commanded change.
    let k_big = own
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.radius.total_cmp(&b.1.radius))
        .map_or(0, |(k, _)| k);
    let angles = pose_angles(&groups[k_big].1, &fit);
    let mut score = 0.0;
    let mut commanded_turn = 0.0f64;
    for w in angles.windows(2) {
        let (dq, dphi) = (w[1].0 - w[0].0, w[1].1 - w[0].1);
        score += dphi.sin() * dq.sin();
        commanded_turn = commanded_turn.max(dq.sin().abs());
    }
    if commanded_turn <= opts.tolerance.angular {
        return Err(CpaError::Sense {
            joint: sweep.name.clone(),
        });
    }
    if score < 0.0 {
        fit.normal = -fit.normal;
        for h in &mut fit.heights {
            *h = -*h;
        }
    }
    let axis = Line::through(fit.point, fit.normal)?;

    // Coupled sweeps must be concentric (module docs).
    let own_rms = rms(own.iter().flat_map(|c| c.radial.iter().copied()));
    let (radial, axial) = fit.residuals(&point_sets);
    let common_rms = rms(radial.iter().copied());
    if !sweep.coupled.is_empty()
        && own.len() >= 2
        && common_rms > RIGID_RATIO * own_rms + opts.tolerance.linear
    {
        return Err(CpaError::NotRigid {
            joint: sweep.name.clone(),
            followers: sweep
                .coupled
                .iter()
                .map(|c| c.name.clone())
                .collect::<Vec<_>>()
                .join(", "),
            common: common_rms,
            own: own_rms,
        });
    }

    let targets: Vec<TargetFit> = groups
        .iter()
        .zip(&own)
        .map(|((t, _), c)| {
            let direction = c.normal * c.normal.dot(&fit.normal).signum();
            TargetFit {
                target: *t,
                name: target_name(m, *t),
                points: c.points,
                centre: c.centre,
                direction,
                radius: Some(c.radius),
                path_rms: c.circle_rms,
                plane_rms: Some(c.plane_rms),
                axis_offset: axis.distance_to_point(&c.centre),
                axis_tilt: direction
                    .cross(&fit.normal)
                    .norm()
                    .atan2(direction.dot(&fit.normal)),
            }
        })
        .collect();

    // Commanded against measured angle, per pose, targets weighted by r².
    let per_target: Vec<(f64, Vec<(f64, f64)>)> = groups
        .iter()
        .zip(&fit.radii)
        .map(|((_, pp), &r)| (r * r, pose_angles(pp, &fit)))
        .collect();
    let motion = motion_check(&per_target, JointKind::Revolute, sweep.span);

    Ok(JointCpa {
        joint: sweep.joint,
        name: sweep.name.clone(),
        kind: JointKind::Revolute,
        sweep: index,
        axis,
        points: targets.iter().map(|t| t.points).sum(),
        poses: sweep.poses,
        radius: fit.radii.iter().copied().reduce(f64::max),
        targets,
        circle_rms: common_rms,
        plane_rms: Some(rms(axial.iter().copied())),
        span: sweep.span,
        motion,
        screen: SweepScreen::default(),
    })
}

/// Per pose: (commanded value, mean angle of the pose's points about the fitted axis).
pub(super) fn pose_angles(per_pose: &[(f64, Vec<Vector3<f64>>)], fit: &Coaxial) -> Vec<(f64, f64)> {
    let (b1, b2) = basis(&fit.normal);
    per_pose
        .iter()
        .map(|(q, pts)| {
            // Average the points' angles relative to the first one, so that no wrap splits them.
            let angle = |p: &Vector3<f64>| {
                let d = p - fit.point;
                d.dot(&b2).atan2(d.dot(&b1))
            };
            let first = angle(&pts[0]);
            let mean = pts.iter().map(|p| wrap(angle(p) - first)).sum::<f64>() / pts.len() as f64;
            (*q, first + mean)
        })
        .collect()
}

pub(super) fn fit_prismatic(
    m: &Measurements,
    sweep: &Sweep,
    index: usize,
    groups: &Groups,
) -> Result<JointCpa, CpaError> {
    // All targets translate alike: one direction from every target's centred points.
    let mut centred = Vec::new();
    let mut centroids = Vec::new();
    for (_, pp) in groups {
        let pts: Vec<Vector3<f64>> = pp.iter().flat_map(|(_, p)| p.clone()).collect();
        let c = mean(&pts);
        centred.extend(pts.iter().map(|p| p - c));
        centroids.push(c);
    }
    let (_, vectors) = principal_axes(&centred);
    let mut dir = vectors[0];
    // Sense: displacement along the direction must follow the commanded change.
    let score: f64 = groups
        .iter()
        .zip(&centroids)
        .flat_map(|((_, pp), c)| pp.iter().map(move |(q, pts)| (q, (pts[0] - c).dot(&dir))))
        .map(|(q, s)| q * s)
        .sum();
    let spread: f64 = centred.iter().map(|d| d.norm()).fold(0.0, f64::max);
    if spread == 0.0 {
        return Err(CpaError::Degenerate {
            joint: sweep.name.clone(),
            target: target_name(m, groups[0].0),
            what: "the points do not move".into(),
        });
    }
    if score < 0.0 {
        dir = -dir;
    }
    let all: Vec<Vector3<f64>> = groups
        .iter()
        .flat_map(|(_, pp)| pp.iter().flat_map(|(_, p)| p.clone()))
        .collect();
    let axis = Line::through(mean(&all), dir)?;
    let mut line_sq = Vec::new();
    let mut targets = Vec::new();
    let mut per_target = Vec::new();
    for ((t, pp), c) in groups.iter().zip(&centroids) {
        let pts: Vec<Vector3<f64>> = pp.iter().flat_map(|(_, p)| p.clone()).collect();
        let own: Vec<f64> = pts
            .iter()
            .map(|p| {
                let d = p - c;
                (d - dir * d.dot(&dir)).norm()
            })
            .collect();
        line_sq.extend(own.iter().copied());
        let (_, own_dir) = principal_axes(&pts.iter().map(|p| p - c).collect::<Vec<_>>());
        let own_dir = own_dir[0] * own_dir[0].dot(&dir).signum();
        let own_rms = rms(pts.iter().map(|p| {
            let d = p - c;
            (d - own_dir * d.dot(&own_dir)).norm()
        }));
        targets.push(TargetFit {
            target: *t,
            name: target_name(m, *t),
            points: pts.len(),
            centre: *c,
            direction: own_dir,
            radius: None,
            path_rms: own_rms,
            plane_rms: None,
            axis_offset: 0.0,
            axis_tilt: own_dir.cross(&dir).norm().atan2(own_dir.dot(&dir)),
        });
        let along: Vec<(f64, f64)> = pp
            .iter()
            .map(|(q, p)| {
                (
                    *q,
                    p.iter().map(|x| (x - c).dot(&dir)).sum::<f64>() / p.len() as f64,
                )
            })
            .collect();
        per_target.push((1.0, along));
    }
    let motion = motion_check(&per_target, JointKind::Prismatic, sweep.span);
    Ok(JointCpa {
        joint: sweep.joint,
        name: sweep.name.clone(),
        kind: JointKind::Prismatic,
        sweep: index,
        axis,
        points: all.len(),
        poses: sweep.poses,
        radius: None,
        targets,
        circle_rms: rms(line_sq.into_iter()),
        plane_rms: None,
        span: sweep.span,
        motion,
        screen: SweepScreen::default(),
    })
}

/// Residuals per pose from per-target (weight, [(commanded, measured)]) series. Revolute values
/// are angles (compared modulo a turn); prismatic ones lengths.
pub(super) fn motion_check(
    per_target: &[(f64, Vec<(f64, f64)>)],
    kind: JointKind,
    span: f64,
) -> MotionCheck {
    let diff = |a: f64| match kind {
        JointKind::Revolute => wrap(a),
        JointKind::Prismatic => a,
    };
    // Per target: measured − commanded, about its first pose, then mean removed.
    let mut by_pose: Vec<(f64, f64, f64)> = Vec::new(); // (commanded, Σ w·residual, Σ w)
    for (w, series) in per_target {
        let Some(&(q0, m0)) = series.first() else {
            continue;
        };
        let rel: Vec<(f64, f64)> = series
            .iter()
            .map(|&(q, mv)| (q, diff(mv - m0 - (q - q0))))
            .collect();
        let mean = rel.iter().map(|r| r.1).sum::<f64>() / rel.len() as f64;
        for (q, r) in rel {
            match by_pose.iter_mut().find(|p| p.0 == q) {
                Some(p) => {
                    p.1 += w * (r - mean);
                    p.2 += w;
                }
                None => by_pose.push((q, w * (r - mean), *w)),
            }
        }
    }
    let mut poses: Vec<PoseResidual> = by_pose
        .iter()
        .filter(|p| p.2 > 0.0)
        .map(|p| PoseResidual {
            commanded: p.0,
            residual: p.1 / p.2,
        })
        .collect();
    let mean = poses.iter().map(|p| p.residual).sum::<f64>() / poses.len().max(1) as f64;
    for p in &mut poses {
        p.residual -= mean;
    }
    let q: Vec<f64> = poses.iter().map(|p| p.commanded).collect();
    let e: Vec<f64> = poses.iter().map(|p| p.residual).collect();
    let n = poses.len();
    let linear = (n >= 3)
        .then(|| least_squares(&q, &e, &[Basis::One, Basis::Q]))
        .flatten()
        .map(|(c, rms)| LinearTrend { slope: c[1], rms });
    let revolute = kind == JointKind::Revolute;
    let sinusoid = (revolute && n >= 4)
        .then(|| least_squares(&q, &e, &[Basis::One, Basis::Cos, Basis::Sin]))
        .flatten()
        .map(|(c, rms)| SinusoidTrend {
            amplitude: c[1].hypot(c[2]),
            phase: c[1].atan2(c[2]),
            rms,
        });
    let combined = (revolute && n >= 5 && span >= PI)
        .then(|| least_squares(&q, &e, &[Basis::One, Basis::Q, Basis::Cos, Basis::Sin]))
        .flatten()
        .map(|(c, rms)| CombinedTrend {
            slope: c[1],
            amplitude: c[2].hypot(c[3]),
            phase: c[2].atan2(c[3]),
            rms,
        });
    MotionCheck {
        rms: rms(e.iter().copied()),
        poses,
        linear,
        sinusoid,
        combined,
    }
}

#[derive(Clone, Copy)]
pub(super) enum Basis {
    One,
    Q,
    Cos,
    Sin,
}

/// Least squares of `e` on the basis functions of `q`: coefficients and residual RMS; `None`
/// when the design is rank-deficient.
pub(super) fn least_squares(q: &[f64], e: &[f64], basis: &[Basis]) -> Option<(Vec<f64>, f64)> {
    let a = DMatrix::from_fn(q.len(), basis.len(), |i, j| match basis[j] {
        Basis::One => 1.0,
        Basis::Q => q[i],
        Basis::Cos => q[i].cos(),
        Basis::Sin => q[i].sin(),
    });
    let b = DVector::from_column_slice(e);
    let svd = a.clone().svd(true, true);
    let max = svd.singular_values.max();
    // Rank: singular values below the rounding level of the largest one are zero.
    let tiny = max * f64::EPSILON * (q.len().max(basis.len()) as f64);
    if svd.singular_values.iter().any(|&s| s <= tiny) {
        return None;
    }
    let x = svd.solve(&b, tiny).ok()?;
    let r = &b - &a * &x;
    Some((x.iter().copied().collect(), rms(r.iter().copied())))
}

/// The tip pose at the last joint's sweep configuration with the last joint at zero (module
/// docs).
pub(super) fn tip_pose(
    m: &Measurements,
    poses: &[Pose],
    sweep: &Sweep,
    joint: &JointCpa,
) -> Result<Isometry3<f64>, CpaError> {
    let z = joint.axis.direction();
    match joint.kind {
        JointKind::Prismatic => {
            let origin = joint.axis.point();
            Ok(frame(origin, perpendicular(&z), z))
        }
        JointKind::Revolute => {
            let groups = groups(m, poses, sweep, &joint.screen.samples());
            let far = joint.targets.iter().enumerate().max_by(|a, b| {
                a.1.radius
                    .unwrap_or(0.0)
                    .total_cmp(&b.1.radius.unwrap_or(0.0))
            });
            let Some((k, target)) = far else {
                return Ok(frame(joint.axis.point(), perpendicular(&z), z));
            };
            let centre = joint.axis.foot_of(&target.centre);
            // The target's angle at q_n = 0: mean of (measured angle − commanded) over the poses.
            let fit = Coaxial {
                point: centre,
                normal: z,
                radii: Vec::new(),
                heights: Vec::new(),
            };
            let angles = pose_angles(&groups[k].1, &fit);
            let Some(&(q0, a0)) = angles.first() else {
                return Ok(frame(centre, perpendicular(&z), z));
            };
            let offset = a0 - q0
                + angles
                    .iter()
                    .map(|(q, a)| wrap(a - q - (a0 - q0)))
                    .sum::<f64>()
                    / angles.len() as f64;
            let (b1, b2) = basis(&z);
            let x = b1 * offset.cos() + b2 * offset.sin();
            Ok(frame(centre, x, z))
        }
    }
}

/// The pose with origin `origin`, x axis `x`, z axis `z` (unit, orthogonal).
pub(super) fn frame(origin: Vector3<f64>, x: Vector3<f64>, z: Vector3<f64>) -> Isometry3<f64> {
    let y = z.cross(&x);
    let r = Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[x, y, z]));
    Isometry3::from_parts(
        Translation3::from(origin),
        UnitQuaternion::from_rotation_matrix(&r),
    )
}

/// The motion of joints `0..axes.len()` at serial values `theta`, as one rigid transform
/// (product of exponentials about the axes at `q = 0`).
pub(super) fn chain_motion(axes: &[(JointKind, Line)], theta: &[f64]) -> Isometry3<f64> {
    let mut t = Isometry3::identity();
    for ((kind, line), &th) in axes.iter().zip(theta) {
        let e = line.direction();
        let step = match kind {
            JointKind::Prismatic => Isometry3::translation(e.x * th, e.y * th, e.z * th),
            JointKind::Revolute => {
                let r = UnitQuaternion::from_axis_angle(&Unit::new_unchecked(e), th);
                let c = line.point();
                Isometry3::from_parts(Translation3::from(c - r * c), r)
            }
        };
        t *= step;
    }
    t
}
