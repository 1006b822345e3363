//! Comparing the measured axes with a nominal model's: each joint's document, the nominal axes
//! at `q = 0`, the angle and distance between consecutive axis pairs (radians, metres), and the
//! proof that the axes reproduce the measured points.

use super::*;

/// `[max position, max orientation]` difference between `table`'s FK and the measured axes'.
pub(super) fn against_axes(table: &DhTable, result: &CpaResult, qs: &[Vec<f64>]) -> [f64; 2] {
    let mut worst = [0.0f64; 2];
    for q in qs {
        let Ok(fk) = table.fk(q) else { continue };
        let mut t = Isometry3::identity();
        for (ax, &qi) in result.axes.iter().zip(q) {
            let e = ax.line.direction();
            t *= match ax.kind {
                JointKind::Revolute => {
                    let c = ax.line.point();
                    Isometry3::translation(c.x, c.y, c.z)
                        * Isometry3::rotation(e * qi)
                        * Isometry3::translation(-c.x, -c.y, -c.z)
                }
                JointKind::Prismatic => Isometry3::translation(e.x * qi, e.y * qi, e.z * qi),
            };
        }
        let (dp, dr) = dh_core::pose::pose_error(&fk, &(t * result.tip));
        worst = [worst[0].max(dp), worst[1].max(dr)];
    }
    worst
}

pub(super) fn arr(v: &nalgebra::Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

pub(super) fn joint_doc(j: &JointCpa) -> JointCpaDoc {
    let m = &j.motion;
    JointCpaDoc {
        name: j.name.clone(),
        kind: match j.kind {
            JointKind::Revolute => "revolute",
            JointKind::Prismatic => "prismatic",
        },
        poses: j.poses,
        points: j.points,
        radius: j.radius,
        circle_rms: j.circle_rms,
        plane_rms: j.plane_rms,
        span: j.span,
        axis: AxisDoc {
            point: arr(&j.axis.point()),
            direction: arr(&j.axis.direction()),
        },
        motion: MotionDoc {
            rms: m.rms,
            slope: m.linear.map(|l| l.slope),
            linear_rms: m.linear.map(|l| l.rms),
            sinusoid_amplitude: m.sinusoid.map(|s| s.amplitude),
            sinusoid_rms: m.sinusoid.map(|s| s.rms),
            poses: m.poses.iter().map(|p| [p.commanded, p.residual]).collect(),
        },
        targets: j
            .targets
            .iter()
            .map(|t| TargetCircleDoc {
                name: t.name.clone(),
                points: t.points,
                radius: t.radius,
                path_rms: t.path_rms,
                plane_rms: t.plane_rms,
                axis_offset: t.axis_offset,
                axis_tilt: t.axis_tilt,
            })
            .collect(),
        screen: ScreenDoc {
            scale: j.screen.scale,
            threshold: j.screen.threshold,
            left_out: j
                .screen
                .left_out
                .iter()
                .map(|o| LeftOutDoc {
                    line: o.line,
                    target: o.target.clone(),
                    distance: o.distance,
                    sigmas: o.sigmas,
                })
                .collect(),
            sound: j.screen.sound(),
        },
    }
}

/// The joint axes of `table` at `q = 0`, in its base link frame.
pub(super) fn nominal_axes(table: &DhTable) -> Result<Vec<Line>> {
    let zeros = vec![0.0; table.rows.len()];
    let frames = table.frames(&zeros)?;
    let offset = match table.convention {
        Convention::Standard => 0,
        Convention::Modified => 1,
    };
    (0..table.rows.len())
        .map(|i| {
            let f = frames
                .get(i + offset)
                .ok_or_else(|| anyhow::anyhow!("the table has no frame {}", i + offset))?;
            Ok(Line::through(
                f.translation.vector,
                f.rotation * nalgebra::Vector3::z(),
            )?)
        })
        .collect()
}

/// Whether two axes at `angle` (radians, `[0, pi]`) are within 5 degrees of parallel.
pub(super) fn near_parallel(angle: f64) -> bool {
    angle.min(std::f64::consts::PI - angle) < NEAR_PARALLEL
}

/// Per axis, the point where a DH frame would sit on it: on the first, the point nearest the
/// origin; on a later one, the foot of the common normal with the previous axis, or for a
/// (nearly) parallel pair the foot of the previous axis's point. Offsets of parallel axes are
/// measured there, where the arm is, rather than near a far-away origin.
pub(super) fn anchors(axes: &[&Line]) -> Vec<nalgebra::Vector3<f64>> {
    let mut out: Vec<nalgebra::Vector3<f64>> = Vec::with_capacity(axes.len());
    for (i, a) in axes.iter().enumerate() {
        let p = match (i, out.last()) {
            (0, _) | (_, None) => a.point(),
            (_, Some(prev)) => {
                let b = axes[i - 1];
                if near_parallel(b.angle_to(a)) {
                    a.foot_of(prev)
                } else {
                    b.closest_points(a)
                        .map_or_else(|| a.foot_of(prev), |(_, q)| q)
                }
            }
        };
        out.push(p);
    }
    out
}

pub(super) fn pair_comparison(
    nominal: &DhTable,
    cpa: &CpaResult,
) -> Result<Vec<PairComparisonDoc>> {
    let tol = Tolerance::default();
    let nominal_axes = nominal_axes(nominal)?;
    // The rows the data measured, in chain order, nominal and measured side by side.
    let mut both: Vec<(&str, &Line, &Line)> = Vec::new();
    for (row, n) in nominal.rows.iter().zip(&nominal_axes) {
        if let Some(m) = cpa.axes.iter().find(|a| a.name == row.name) {
            both.push((&row.name, n, &m.line));
        }
    }
    let n_axes: Vec<&Line> = both.iter().map(|b| b.1).collect();
    let m_axes: Vec<&Line> = both.iter().map(|b| b.2).collect();
    let (n_at, m_at) = (anchors(&n_axes), anchors(&m_axes));
    let mut out = Vec::new();
    for i in 1..both.len() {
        let n = classify(n_axes[i - 1], n_axes[i], tol);
        let m = classify(m_axes[i - 1], m_axes[i], tol);
        // The common normal of nearly parallel measured axes lies anywhere along them; their
        // offset at the arm is what can be compared.
        let (nd, md) = if near_parallel(n.angle) && near_parallel(m.angle) {
            (
                n_axes[i].distance_to_point(&n_at[i - 1]),
                m_axes[i].distance_to_point(&m_at[i - 1]),
            )
        } else {
            (n.distance, m.distance)
        };
        out.push(PairComparisonDoc {
            joints: [both[i - 1].0.to_string(), both[i].0.to_string()],
            nominal_angle: n.angle,
            measured_angle: m.angle,
            nominal_distance: nd,
            measured_distance: md,
        });
    }
    Ok(out)
}
