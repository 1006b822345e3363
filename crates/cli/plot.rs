//! A small hand-written SVG chart of calibration residuals per pose: one panel per model
//! (before and after), one dot per measured point at its pose, the panel's RMS as a dashed
//! line and the noise floor, when known, as a dotted one.
//!
//! Written by hand rather than through a plotting crate: the chart is a few dozen elements, and
//! the output must be deterministic (no timestamps or random ids) so that it can be compared
//! between runs.

use std::fmt::Write as _;

use dh_workflows::units::LengthUnit;

/// One measured point's residual.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Residual {
    /// Pose index (0-based, in file order of first appearance).
    pub pose: usize,
    /// Euclidean distance between modelled and measured point (metres).
    pub distance: f64,
    /// Whether the point is held out for validation.
    pub validation: bool,
}

/// One panel: the residuals of one model.
#[derive(Clone, Debug, PartialEq)]
pub struct Panel {
    /// Title of the panel.
    pub label: String,
    /// The points.
    pub residuals: Vec<Residual>,
    /// RMS to draw as a dashed line (metres).
    pub rms: Option<f64>,
    /// Noise floor to draw as a dotted line (metres).
    pub floor: Option<f64>,
}

/// A chart of residual panels stacked vertically.
#[derive(Clone, Debug, PartialEq)]
pub struct ResidualChart {
    /// Title above the panels.
    pub title: String,
    /// Unit of the y axes.
    pub unit: LengthUnit,
    /// Number of poses (the x axis runs from 1 to it).
    pub poses: usize,
    /// The panels, top to bottom.
    pub panels: Vec<Panel>,
}

const WIDTH: f64 = 900.0;
const PANEL_HEIGHT: f64 = 240.0;
const LEFT: f64 = 80.0;
const RIGHT: f64 = 20.0;
const TOP: f64 = 64.0;
const GAP: f64 = 60.0;
const CALIBRATION_COLOUR: &str = "#1f77b4";
const VALIDATION_COLOUR: &str = "#ff7f0e";

/// Escapes text for XML content and attributes.
pub(crate) fn xml(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A coordinate with two decimals.
pub(crate) fn c(v: f64) -> String {
    let s = format!("{v:.2}");
    if s == "-0.00" {
        "0.00".into()
    } else {
        s
    }
}

/// A step of 1, 2 or 5 times a power of ten giving about `ticks` intervals up to `max`.
pub(crate) fn nice_step(max: f64, ticks: f64) -> f64 {
    if !(max.is_finite() && max > 0.0) {
        return 1.0;
    }
    let raw = max / ticks;
    let p = 10f64.powf(raw.log10().floor());
    let m = raw / p;
    let f = if m <= 1.0 {
        1.0
    } else if m <= 2.0 {
        2.0
    } else if m <= 5.0 {
        5.0
    } else {
        10.0
    };
    f * p
}

/// A tick label: as few decimals as the step needs.
pub(crate) fn tick_label(v: f64, step: f64) -> String {
    let decimals = if step >= 1.0 {
        0
    } else {
        (-step.log10()).ceil().max(0.0) as usize
    };
    format!("{v:.decimals$}")
}

/// The start of a chart's SVG document, `width` by `height` user units: the XML declaration,
/// the `<svg>` element, `title` as its `<title>` and centred above the chart, on white.
pub(crate) fn svg_open(width: f64, height: f64, title: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>");
    let _ = writeln!(
        s,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" viewBox=\"0 0 {} {}\" font-family=\"sans-serif\" font-size=\"12\">",
        c(width),
        c(height),
        c(width),
        c(height)
    );
    let _ = writeln!(s, "<title>{}</title>", xml(title));
    let _ = writeln!(s, "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>");
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"24\" font-size=\"15\" text-anchor=\"middle\">{}</text>",
        c(width / 2.0),
        xml(title)
    );
    s
}

/// The SVG document of `chart`.
pub fn residuals_svg(chart: &ResidualChart) -> String {
    let n = chart.panels.len().max(1) as f64;
    let height = TOP + n * PANEL_HEIGHT + (n - 1.0) * GAP + 50.0;
    let plot_w = WIDTH - LEFT - RIGHT;
    let scale = 1.0 / chart.unit.metres();
    let unit = chart.unit.symbol();
    let poses = chart.poses.max(1) as f64;
    let mut s = svg_open(WIDTH, height, &chart.title);
    for (k, panel) in chart.panels.iter().enumerate() {
        let top = TOP + k as f64 * (PANEL_HEIGHT + GAP);
        let bottom = top + PANEL_HEIGHT;
        let max = panel
            .residuals
            .iter()
            .map(|r| r.distance * scale)
            .chain(panel.rms.map(|v| v * scale))
            .chain(panel.floor.map(|v| v * scale))
            .filter(|v| v.is_finite())
            .fold(0.0, f64::max);
        let step = nice_step(max, 5.0);
        let y_max = if max > 0.0 {
            (max / step).ceil() * step
        } else {
            step
        };
        let x = |pose: f64| LEFT + (pose + 0.5) / poses * plot_w;
        let y = |v: f64| bottom - (v / y_max).clamp(0.0, 1.0) * PANEL_HEIGHT;
        let _ = writeln!(s, "<g>");
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{}\" font-size=\"13\">{}</text>",
            c(LEFT),
            c(top - 8.0),
            xml(&panel.label)
        );
        let _ = writeln!(
            s,
            "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#999\"/>",
            c(LEFT),
            c(top),
            c(plot_w),
            c(PANEL_HEIGHT)
        );
        let ticks = (y_max / step).round() as usize;
        for t in 0..=ticks {
            let v = t as f64 * step;
            let _ = writeln!(
                s,
                "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"#eee\"/>",
                c(LEFT),
                c(y(v)),
                c(LEFT + plot_w),
                c(y(v))
            );
            let _ = writeln!(
                s,
                "<text x=\"{}\" y=\"{}\" text-anchor=\"end\">{}</text>",
                c(LEFT - 6.0),
                c(y(v) + 4.0),
                tick_label(v, step)
            );
        }
        let _ = writeln!(
            s,
            "<text transform=\"translate({} {}) rotate(-90)\" text-anchor=\"middle\">residual [{unit}]</text>",
            c(LEFT - 55.0),
            c(top + PANEL_HEIGHT / 2.0)
        );
        for r in &panel.residuals {
            if !r.distance.is_finite() {
                continue;
            }
            let colour = if r.validation {
                VALIDATION_COLOUR
            } else {
                CALIBRATION_COLOUR
            };
            let _ = writeln!(
                s,
                "<circle cx=\"{}\" cy=\"{}\" r=\"2.5\" fill=\"{colour}\"/>",
                c(x(r.pose as f64)),
                c(y(r.distance * scale))
            );
        }
        // The RMS label sits at the right end above its line, the floor's at the left end
        // below its own, so that the two never overlap when the fit reaches the floor.
        for (value, dash, name, left) in [
            (panel.rms, "6 4", "RMS", false),
            (panel.floor, "2 3", "noise floor", true),
        ] {
            if let Some(v) = value.filter(|v| v.is_finite()) {
                let v = v * scale;
                let _ = writeln!(
                    s,
                    "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"#333\" stroke-dasharray=\"{dash}\"/>",
                    c(LEFT),
                    c(y(v)),
                    c(LEFT + plot_w),
                    c(y(v))
                );
                let (tx, ty, anchor) = if left {
                    (LEFT + 4.0, y(v) + 14.0, "start")
                } else {
                    (LEFT + plot_w - 4.0, y(v) - 4.0, "end")
                };
                let _ = writeln!(
                    s,
                    "<text x=\"{}\" y=\"{}\" text-anchor=\"{anchor}\" fill=\"#333\">{name} {} {unit}</text>",
                    c(tx),
                    c(ty),
                    significant(v)
                );
            }
        }
        let _ = writeln!(s, "</g>");
    }
    let last = TOP + n * PANEL_HEIGHT + (n - 1.0) * GAP;
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">pose (1 to {}, in file order)</text>",
        c(LEFT + plot_w / 2.0),
        c(last + 22.0),
        chart.poses
    );
    let _ = writeln!(
        s,
        "<circle cx=\"{}\" cy=\"{}\" r=\"4\" fill=\"{CALIBRATION_COLOUR}\"/><text x=\"{}\" y=\"{}\">calibration</text>",
        c(LEFT + 4.0),
        c(last + 38.0),
        c(LEFT + 12.0),
        c(last + 42.0)
    );
    let _ = writeln!(
        s,
        "<circle cx=\"{}\" cy=\"{}\" r=\"4\" fill=\"{VALIDATION_COLOUR}\"/><text x=\"{}\" y=\"{}\">validation</text>",
        c(LEFT + 104.0),
        c(last + 38.0),
        c(LEFT + 112.0),
        c(last + 42.0)
    );
    let _ = writeln!(s, "</svg>");
    s
}

/// Four significant digits.
pub(crate) fn significant(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let decimals = (3 - v.abs().log10().floor() as i32).max(0) as usize;
    format!("{v:.decimals$}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nice_steps() {
        assert_eq!(nice_step(10.0, 5.0), 2.0);
        assert_eq!(nice_step(0.013, 5.0), 0.005);
        assert_eq!(nice_step(0.0, 5.0), 1.0);
        assert_eq!(tick_label(0.005 * 3.0, 0.005), "0.015");
        assert_eq!(significant(0.0123456), "0.01235");
    }

    #[test]
    fn titles_are_escaped_and_values_scaled() {
        let chart = ResidualChart {
            title: "a < b & \"c\"".into(),
            unit: LengthUnit::Mm,
            poses: 2,
            panels: vec![Panel {
                label: "before".into(),
                residuals: vec![
                    Residual {
                        pose: 0,
                        distance: 0.002,
                        validation: false,
                    },
                    Residual {
                        pose: 1,
                        distance: 0.004,
                        validation: true,
                    },
                ],
                rms: Some(0.003),
                floor: None,
            }],
        };
        let svg = residuals_svg(&chart);
        assert!(svg.contains("a &lt; b &amp; &quot;c&quot;"), "{svg}");
        assert!(svg.contains("RMS 3.000 mm"), "{svg}");
        assert_eq!(svg.matches("<circle").count(), 4);
    }
}
