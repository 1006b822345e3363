//! The SVG chart of `cpa --plot`: per joint, the measured minus commanded motion of each pose of
//! its sweep against the commanded joint value, with the trend the analysis fitted
//! ([`MotionCheck`]: a gear ratio is a slope, an eccentric output a once-per-turn
//! sine), and the joint's circle-fit quality in its title.
//!
//! Units: revolute joints are drawn in degrees (x) and microradians (y), prismatic joints in
//! millimetres (x) and micrometres (y); the residuals come in radians and metres. Hand-written
//! and deterministic like [`crate::plot`], whose helpers it uses.

use std::fmt::Write as _;

use dh_workflows::cpa_report::{JointCpa, MotionCheck};
use dh_workflows::geometry::JointKind;

use crate::plot::{c, nice_step, significant, svg_open, tick_label, xml};

const WIDTH: f64 = 900.0;
const PANEL_HEIGHT: f64 = 200.0;
const LEFT: f64 = 90.0;
const RIGHT: f64 = 20.0;
const TOP: f64 = 64.0;
const GAP: f64 = 64.0;
const POINT_COLOUR: &str = "#1f77b4";
const TREND_COLOUR: &str = "#d62728";
/// Points along a drawn trend curve.
const CURVE_POINTS: usize = 120;

/// The fitted trend of a sweep, as a function of the commanded value (SI units), with the
/// constant the analysis removed refitted to the points (the mean residual is zero, so the
/// constant is the mean of what the trend leaves).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Trend {
    /// `k + slope · q`.
    Linear { slope: f64 },
    /// `k + amplitude · sin(q + phase)`.
    Sine { amplitude: f64, phase: f64 },
    /// Both.
    Both {
        slope: f64,
        amplitude: f64,
        phase: f64,
    },
}

impl Trend {
    /// The best trend the analysis found, with the RMS it leaves (SI units): line and sine
    /// together where fitted, else the one of the two that leaves the smaller RMS.
    fn of(m: &MotionCheck) -> Option<(Self, f64)> {
        if let Some(b) = m.combined {
            return Some((
                Self::Both {
                    slope: b.slope,
                    amplitude: b.amplitude,
                    phase: b.phase,
                },
                b.rms,
            ));
        }
        match (m.linear, m.sinusoid) {
            (Some(l), Some(s)) if s.rms < l.rms => Some((
                Self::Sine {
                    amplitude: s.amplitude,
                    phase: s.phase,
                },
                s.rms,
            )),
            (Some(l), _) => Some((Self::Linear { slope: l.slope }, l.rms)),
            (None, Some(s)) => Some((
                Self::Sine {
                    amplitude: s.amplitude,
                    phase: s.phase,
                },
                s.rms,
            )),
            (None, None) => None,
        }
    }

    /// The trend at `q` without its constant.
    fn shape(self, q: f64) -> f64 {
        match self {
            Self::Linear { slope } => slope * q,
            Self::Sine { amplitude, phase } => amplitude * (q + phase).sin(),
            Self::Both {
                slope,
                amplitude,
                phase,
            } => slope * q + amplitude * (q + phase).sin(),
        }
    }

    /// What the legend says of it.
    fn describe(self, kind: JointKind) -> String {
        let slope = |s: f64| format!("slope {}", significant(s));
        let sine = |a: f64| match kind {
            JointKind::Revolute => format!("once-per-turn {} µrad", significant(a * 1e6)),
            JointKind::Prismatic => format!("sine {} µm", significant(a * 1e6)),
        };
        match self {
            Self::Linear { slope: s } => format!("trend: {}", slope(s)),
            Self::Sine { amplitude, .. } => format!("trend: {}", sine(amplitude)),
            Self::Both {
                slope: s,
                amplitude,
                ..
            } => format!("trend: {} + {}", slope(s), sine(amplitude)),
        }
    }
}

/// Scales of one joint kind: (x per SI unit, x unit, y per SI unit, y unit).
fn scales(kind: JointKind) -> (f64, &'static str, f64, &'static str) {
    match kind {
        JointKind::Revolute => (180.0 / std::f64::consts::PI, "deg", 1e6, "µrad"),
        JointKind::Prismatic => (1e3, "mm", 1e6, "µm"),
    }
}

/// The SVG document: `title` above one panel per joint of `joints`.
pub fn motion_svg(title: &str, joints: &[JointCpa]) -> String {
    let n = joints.len().max(1) as f64;
    let height = TOP + n * PANEL_HEIGHT + (n - 1.0) * GAP + 40.0;
    let plot_w = WIDTH - LEFT - RIGHT;
    let mut s = svg_open(WIDTH, height, title);
    for (k, joint) in joints.iter().enumerate() {
        let top = TOP + k as f64 * (PANEL_HEIGHT + GAP);
        panel(&mut s, joint, top, plot_w);
    }
    let _ = writeln!(s, "</svg>");
    s
}

/// One joint's panel, its top edge at `top`.
fn panel(s: &mut String, joint: &JointCpa, top: f64, plot_w: f64) {
    let (xs, x_unit, ys, y_unit) = scales(joint.kind);
    let bottom = top + PANEL_HEIGHT;
    let points: Vec<(f64, f64)> = joint
        .motion
        .poses
        .iter()
        .map(|p| (p.commanded, p.residual))
        .filter(|(q, r)| q.is_finite() && r.is_finite())
        .collect();
    let fitted = Trend::of(&joint.motion);
    let trend = fitted.map(|(t, _)| t);
    // The constant of the trend: the mean of what its shape leaves.
    let constant = match (trend, points.len()) {
        (Some(t), n) if n > 0 => {
            points.iter().map(|(q, r)| r - t.shape(*q)).sum::<f64>() / n as f64
        }
        _ => 0.0,
    };
    let (q_min, q_max) = points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), (q, _)| {
            (a.min(*q), b.max(*q))
        });
    let (q_min, q_max) = if q_min < q_max {
        (q_min, q_max)
    } else if q_min.is_finite() {
        (q_min - 1.0 / xs, q_min + 1.0 / xs)
    } else {
        (0.0, 1.0 / xs)
    };
    let curve: Vec<(f64, f64)> = match trend {
        Some(t) => (0..=CURVE_POINTS)
            .map(|i| {
                let q = q_min + (q_max - q_min) * i as f64 / CURVE_POINTS as f64;
                (q, constant + t.shape(q))
            })
            .collect(),
        None => Vec::new(),
    };
    let extent = points
        .iter()
        .chain(&curve)
        .map(|(_, r)| (r * ys).abs())
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let step = nice_step(extent, 3.0);
    let y_max = if extent > 0.0 {
        (extent / step).ceil() * step
    } else {
        step
    };
    let x = |q: f64| LEFT + (q - q_min) / (q_max - q_min) * plot_w;
    let y =
        |r: f64| top + PANEL_HEIGHT / 2.0 - (r * ys / y_max).clamp(-1.0, 1.0) * PANEL_HEIGHT / 2.0;
    let kind = match joint.kind {
        JointKind::Revolute => "revolute",
        JointKind::Prismatic => "prismatic",
    };
    let plane = joint
        .plane_rms
        .map(|p| format!(", plane RMS {} µm", significant(p * 1e6)))
        .unwrap_or_default();
    let _ = writeln!(s, "<g>");
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"{}\" font-size=\"13\">{} ({kind}, {} poses): circle RMS {} µm{plane}; motion RMS {} {y_unit}</text>",
        c(LEFT),
        c(top - 8.0),
        xml(&joint.name),
        joint.motion.poses.len(),
        significant(joint.circle_rms * 1e6),
        significant(joint.motion.rms * ys),
    );
    let _ = writeln!(
        s,
        "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#999\"/>",
        c(LEFT),
        c(top),
        c(plot_w),
        c(PANEL_HEIGHT)
    );
    let ticks = (y_max / step).round() as i64;
    for t in -ticks..=ticks {
        let v = t as f64 * step;
        let _ = writeln!(
            s,
            "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"{}\"/>",
            c(LEFT),
            c(y(v / ys)),
            c(LEFT + plot_w),
            c(y(v / ys)),
            if t == 0 { "#bbb" } else { "#eee" }
        );
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{}\" text-anchor=\"end\">{}</text>",
            c(LEFT - 6.0),
            c(y(v / ys) + 4.0),
            tick_label(v, step)
        );
    }
    let x_step = nice_step((q_max - q_min) * xs, 6.0);
    let mut v = (q_min * xs / x_step).ceil() * x_step;
    while v <= q_max * xs + 1e-9 * x_step {
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{}</text>",
            c(x(v / xs)),
            c(bottom + 16.0),
            // `+ 0.0` makes a tick of -0 read 0.
            tick_label(v + 0.0, x_step)
        );
        v += x_step;
    }
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">commanded [{x_unit}]</text>",
        c(LEFT + plot_w / 2.0),
        c(bottom + 32.0)
    );
    let _ = writeln!(
        s,
        "<text transform=\"translate({} {}) rotate(-90)\" text-anchor=\"middle\">measured − commanded [{y_unit}]</text>",
        c(LEFT - 60.0),
        c(top + PANEL_HEIGHT / 2.0)
    );
    if let Some((t, left)) = fitted {
        let path: Vec<String> = curve
            .iter()
            .map(|(q, r)| format!("{},{}", c(x(*q)), c(y(*r))))
            .collect();
        let _ = writeln!(
            s,
            "<polyline points=\"{}\" fill=\"none\" stroke=\"{TREND_COLOUR}\" stroke-width=\"1.5\"/>",
            path.join(" ")
        );
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{}\" text-anchor=\"end\" fill=\"{TREND_COLOUR}\">{}, leaves {} {y_unit} RMS</text>",
            c(LEFT + plot_w - 4.0),
            c(top + 14.0),
            xml(&t.describe(joint.kind)),
            significant(left * ys)
        );
    }
    for (q, r) in &points {
        let _ = writeln!(
            s,
            "<circle cx=\"{}\" cy=\"{}\" r=\"2.5\" fill=\"{POINT_COLOUR}\"/>",
            c(x(*q)),
            c(y(*r))
        );
    }
    let _ = writeln!(s, "</g>");
}

#[cfg(test)]
mod tests {
    use super::*;
    use dh_workflows::cpa_report::{LinearTrend, PoseResidual, SweepScreen};
    use dh_workflows::geometry::Line;

    fn joint(poses: Vec<PoseResidual>, linear: Option<LinearTrend>) -> JointCpa {
        JointCpa {
            joint: 0,
            name: "j<1>".into(),
            kind: JointKind::Revolute,
            sweep: 0,
            axis: Line::z_axis(),
            targets: Vec::new(),
            points: poses.len(),
            poses: poses.len(),
            radius: Some(0.3),
            circle_rms: 12e-6,
            plane_rms: Some(4e-6),
            span: 1.0,
            motion: MotionCheck {
                rms: 5e-5,
                poses,
                linear,
                sinusoid: None,
                combined: None,
            },
            screen: SweepScreen::default(),
        }
    }

    #[test]
    fn a_sweep_is_drawn_with_its_trend_in_microradians_and_degrees() {
        // A gear-ratio error of 1e-4: residual = 1e-4 q, mean removed.
        let qs = [-0.5, 0.0, 0.5, 1.0];
        let poses: Vec<PoseResidual> = qs
            .iter()
            .map(|&q| PoseResidual {
                commanded: q,
                residual: 1e-4 * (q - 0.25),
            })
            .collect();
        let svg = motion_svg(
            "cpa of d.csv",
            &[joint(
                poses,
                Some(LinearTrend {
                    slope: 1e-4,
                    rms: 0.0,
                }),
            )],
        );
        assert!(svg.contains("j&lt;1&gt; (revolute, 4 poses): circle RMS 12.00 µm, plane RMS 4.000 µm; motion RMS 50.00 µrad"), "{svg}");
        assert!(
            svg.contains("trend: slope 0.0001000, leaves 0 µrad RMS"),
            "{svg}"
        );
        assert_eq!(svg.matches("<circle").count(), 4);
        assert_eq!(svg.matches("<polyline").count(), 1);
        assert!(svg.contains("commanded [deg]"));
        // The trend passes through the points: its constant is refitted. The first point
        // (q = -0.5, residual -75 µrad) and the curve's first vertex coincide.
        let first_point = svg
            .split("<circle cx=\"")
            .nth(1)
            .and_then(|t| t.split('"').nth(2))
            .expect("a point");
        let first_vertex = svg
            .split("points=\"")
            .nth(1)
            .and_then(|t| t.split(' ').next())
            .and_then(|v| v.split(',').nth(1))
            .expect("a vertex");
        assert_eq!(first_point, first_vertex, "{svg}");
        assert!(!svg.contains("NaN") && !svg.contains("inf"));
    }

    #[test]
    fn a_sweep_without_a_trend_or_spread_still_draws() {
        let poses = vec![PoseResidual {
            commanded: 0.3,
            residual: 0.0,
        }];
        let svg = motion_svg("t", &[joint(poses, None)]);
        assert_eq!(svg.matches("<circle").count(), 1);
        assert_eq!(svg.matches("<polyline").count(), 0);
        assert!(!svg.contains("NaN") && !svg.contains("inf"));
    }
}
