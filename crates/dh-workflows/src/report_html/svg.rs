//! Inline SVG plots for the report pages: a scatter plot with axes, ticks, unit labels,
//! reference lines and marked points ([`Scatter`]), and a grouped bar chart ([`Bars`]).
//! Deterministic (no random ids), every coordinate finite (a point that is not is left out and
//! counted), at most [`MAX_POINTS`] points per plot so that a page of two million samples stays
//! small.

use std::fmt::Write as _;

use super::page::esc;

/// Most points one plot draws: beyond it an evenly spaced subset is drawn (marked points
/// always), and the caption says so.
pub const MAX_POINTS: usize = 1500;

const W: f64 = 720.0;
/// Width of a plot shown two to a row (the same text size on the page).
const W_COMPACT: f64 = 460.0;
const H: f64 = 260.0;
const LEFT: f64 = 64.0;
const RIGHT: f64 = 16.0;
const TOP: f64 = 40.0;
const BOTTOM: f64 = 42.0;

/// Which kind of point: calibration, validation, or a marked one (an outlier: drawn as a red
/// ring over its dot).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A calibration sample.
    Calibration,
    /// A validation (held-out) sample.
    Validation,
}

/// One point of a scatter plot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    /// Abscissa, in the plot's x unit.
    pub x: f64,
    /// Ordinate, in the plot's y unit.
    pub y: f64,
    /// Calibration or validation.
    pub kind: Kind,
    /// Marked as an outlier.
    pub marked: bool,
}

/// A scatter plot.
pub struct Scatter<'a> {
    /// Title inside the plot (accessibility title too).
    pub title: &'a str,
    /// X axis label with its unit.
    pub x_label: &'a str,
    /// Y axis label with its unit.
    pub y_label: &'a str,
    /// The points.
    pub points: &'a [Point],
    /// Horizontal reference lines: value, label, class (`rms` dashed or `floor` dotted).
    pub lines: Vec<(f64, String, &'static str)>,
    /// Whether the y axis starts at zero (distances).
    pub y_from_zero: bool,
    /// Drawn narrower, for two plots to a row.
    pub compact: bool,
}

/// Tick positions covering `[lo, hi]` at a 1-2-5 step, about `n` of them.
fn ticks(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    let span = hi - lo;
    if !span.is_finite() || span <= 0.0 {
        return vec![lo];
    }
    let raw = span / n.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

/// A tick label: as few decimals as the step needs.
fn tick_label(v: f64, step: f64) -> String {
    let decimals = if step >= 1.0 {
        0
    } else {
        (-step.log10().floor()) as usize
    };
    super::page::fixed(v, decimals.min(9))
}

/// The range of `values` padded by 4 %, or a unit range around a single value.
fn range(values: impl Iterator<Item = f64>, from_zero: bool) -> (f64, f64) {
    let (mut lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
        (l.min(v), h.max(v))
    });
    if from_zero {
        lo = lo.min(0.0);
    }
    if !lo.is_finite() || !hi.is_finite() {
        return (0.0, 1.0);
    }
    if hi - lo <= f64::EPSILON * hi.abs().max(1.0) {
        let pad = if hi == 0.0 { 1.0 } else { hi.abs() * 0.1 };
        return (lo - pad, hi + pad);
    }
    let pad = 0.04 * (hi - lo);
    (
        if from_zero && lo >= 0.0 {
            0.0
        } else {
            lo - pad
        },
        hi + pad,
    )
}

/// The subset drawn: every marked point, and of the rest an evenly spaced `MAX_POINTS`; and
/// whether it is a subset.
fn thin(points: &[Point]) -> (Vec<Point>, bool) {
    let finite: Vec<Point> = points
        .iter()
        .filter(|p| p.x.is_finite() && p.y.is_finite())
        .copied()
        .collect();
    if finite.len() <= MAX_POINTS {
        return (finite, false);
    }
    let stride = finite.len().div_ceil(MAX_POINTS);
    let kept = finite
        .iter()
        .enumerate()
        .filter(|(i, p)| p.marked || i % stride == 0)
        .map(|(_, p)| *p)
        .collect();
    (kept, true)
}

impl Scatter<'_> {
    /// The SVG, and a note for the caption when only a subset is drawn, points are not
    /// finite, or outliers lie beyond the axis (empty otherwise).
    pub fn render(&self) -> (String, String) {
        let (points, thinned) = thin(self.points);
        let left_out = self.points.len()
            - self
                .points
                .iter()
                .filter(|p| p.x.is_finite() && p.y.is_finite())
                .count();
        let w = if self.compact { W_COMPACT } else { W };
        let (x0, x1) = range(points.iter().map(|p| p.x), false);
        let lines: Vec<&(f64, String, &str)> =
            self.lines.iter().filter(|l| l.0.is_finite()).collect();
        // The axis covers the unmarked points; marked points far beyond them (an outlier of
        // 80 sigma) sit on the top edge with their value, so that the rest stays readable.
        let unmarked_top = points
            .iter()
            .filter(|p| !p.marked)
            .map(|p| p.y)
            .chain(lines.iter().map(|l| l.0))
            .fold(f64::NEG_INFINITY, f64::max);
        let beyond =
            |y: f64| unmarked_top.is_finite() && unmarked_top > 0.0 && y > 2.0 * unmarked_top;
        let (y0, y1) = range(
            points
                .iter()
                .filter(|p| !(p.marked && beyond(p.y)))
                .map(|p| p.y)
                .chain(lines.iter().map(|l| l.0)),
            self.y_from_zero,
        );
        let px = |x: f64| LEFT + (x - x0) / (x1 - x0) * (w - LEFT - RIGHT);
        let py = |y: f64| (H - BOTTOM - (y - y0) / (y1 - y0) * (H - TOP - BOTTOM)).max(TOP);
        let mut s = String::with_capacity(points.len() * 16 + 2048);
        let _ = write!(
            s,
            "<svg viewBox=\"0 0 {w} {H}\" role=\"img\" aria-label=\"{t}\"><title>{t}</title>",
            t = esc(self.title)
        );
        let _ = write!(
            s,
            "<text x=\"{LEFT}\" y=\"14\" font-weight=\"600\">{}</text>",
            esc(self.title)
        );
        // Grid and tick labels.
        let yt = ticks(y0, y1, 5);
        let ystep = if yt.len() > 1 { yt[1] - yt[0] } else { y1 - y0 };
        for t in &yt {
            let y = py(*t);
            let _ = write!(
                s,
                "<line class=\"grid\" x1=\"{LEFT}\" y1=\"{y:.1}\" x2=\"{:.1}\" y2=\"{y:.1}\"/><text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{}</text>",
                w - RIGHT,
                LEFT - 6.0,
                y + 4.0,
                tick_label(*t, ystep)
            );
        }
        let xt = ticks(x0, x1, if self.compact { 5 } else { 8 });
        let xstep = if xt.len() > 1 { xt[1] - xt[0] } else { x1 - x0 };
        for t in &xt {
            let x = px(*t);
            let _ = write!(
                s,
                "<line class=\"grid\" x1=\"{x:.1}\" y1=\"{TOP}\" x2=\"{x:.1}\" y2=\"{:.1}\"/><text x=\"{x:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{}</text>",
                H - BOTTOM,
                H - BOTTOM + 14.0,
                tick_label(*t, xstep)
            );
        }
        let _ = write!(
            s,
            "<line class=\"axis\" x1=\"{LEFT}\" y1=\"{TOP}\" x2=\"{LEFT}\" y2=\"{b:.1}\"/><line class=\"axis\" x1=\"{LEFT}\" y1=\"{b:.1}\" x2=\"{:.1}\" y2=\"{b:.1}\"/>",
            w - RIGHT,
            b = H - BOTTOM
        );
        let _ = write!(
            s,
            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{}</text>",
            (LEFT + w - RIGHT) / 2.0,
            H - 6.0,
            esc(self.x_label)
        );
        let _ = write!(
            s,
            "<text transform=\"translate(14 {:.1}) rotate(-90)\" text-anchor=\"middle\">{}</text>",
            (TOP + H - BOTTOM) / 2.0,
            esc(self.y_label)
        );
        // Points: calibration first, validation over them, rings over both.
        for kind in [Kind::Calibration, Kind::Validation] {
            let class = match kind {
                Kind::Calibration => "cal",
                Kind::Validation => "val",
            };
            let mut d = String::new();
            for p in points.iter().filter(|p| p.kind == kind) {
                let _ = write!(d, "M{:.0} {:.0}h0", px(p.x), py(p.y));
            }
            if !d.is_empty() {
                let _ = write!(s, "<path class=\"{class}\" d=\"{d}\"/>");
            }
        }
        let mut clipped = 0;
        if points.iter().any(|p| p.marked) {
            s.push_str("<g class=\"out\">");
            for p in points.iter().filter(|p| p.marked) {
                let (x, y) = (px(p.x), py(p.y));
                let _ = write!(s, "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"5\"/>");
                if beyond(p.y) {
                    clipped += 1;
                    let (tx, anchor) = if x > w - RIGHT - 60.0 {
                        (x - 7.0, "end")
                    } else {
                        (x + 7.0, "start")
                    };
                    let _ = write!(
                        s,
                        "<text class=\"outv\" x=\"{tx:.1}\" y=\"{:.1}\" text-anchor=\"{anchor}\">\u{2191} {}</text>",
                        y + 4.0,
                        super::page::fixed(p.y, 3)
                    );
                }
            }
            s.push_str("</g>");
        }
        for (v, label, class) in lines {
            let y = py(*v);
            // RMS labels at the right end, the floor's at the left, so that they never overlap.
            let (lx, anchor) = if *class == "floor" {
                (LEFT + 4.0, "start")
            } else {
                (w - RIGHT - 4.0, "end")
            };
            let _ = write!(
                s,
                "<line class=\"{class}\" x1=\"{LEFT}\" y1=\"{y:.1}\" x2=\"{:.1}\" y2=\"{y:.1}\"/><text x=\"{lx:.1}\" y=\"{:.1}\" text-anchor=\"{anchor}\">{}</text>",
                w - RIGHT,
                y - 4.0,
                esc(label)
            );
        }
        // Legend, on its own line under the title.
        let has_val = points.iter().any(|p| p.kind == Kind::Validation);
        let has_out = points.iter().any(|p| p.marked);
        let mut lx = LEFT + 4.0;
        for (show, class, label) in [
            (true, "cal", "calibration"),
            (has_val, "val", "validation"),
            (has_out, "out", "outlier"),
        ] {
            if show {
                let mark = if class == "out" {
                    format!("<circle class=\"out\" cx=\"{lx:.1}\" cy=\"27\" r=\"4\"/>")
                } else {
                    format!("<path class=\"{class} key\" d=\"M{lx:.1} 27h0\"/>")
                };
                let _ = write!(
                    s,
                    "{mark}<text x=\"{:.1}\" y=\"31\">{label}</text>",
                    lx + 8.0
                );
                lx += 90.0;
            }
        }
        s.push_str("</svg>");
        let mut note = String::new();
        if thinned {
            let _ = write!(
                note,
                "{} of {} points drawn, evenly spaced (every outlier drawn). ",
                points.len(),
                self.points.len()
            );
        }
        if left_out > 0 {
            let _ = write!(note, "{left_out} points not finite, not drawn. ");
        }
        if clipped > 0 {
            let _ = write!(
                note,
                "{clipped} outlier(s) beyond the axis, drawn on its top edge with their value. "
            );
        }
        (s, note)
    }
}

/// A grouped bar chart: one group per label, one bar per series (a missing value draws no bar
/// and `n/a` under the group).
pub struct Bars<'a> {
    /// Title inside the chart.
    pub title: &'a str,
    /// Y axis label with its unit.
    pub y_label: &'a str,
    /// The series' names and classes (`bar-cal`, `bar-val`).
    pub series: &'a [(&'a str, &'static str)],
    /// Group label and one value per series.
    pub groups: &'a [(String, Vec<Option<f64>>)],
}

impl Bars<'_> {
    /// The SVG.
    pub fn render(&self) -> String {
        let values = self
            .groups
            .iter()
            .flat_map(|g| g.1.iter().flatten().copied())
            .filter(|v| v.is_finite());
        let (_, y1) = range(values, true);
        let y0 = 0.0;
        let py = |y: f64| H - BOTTOM - (y - y0) / (y1 - y0) * (H - TOP - BOTTOM);
        let mut s = String::new();
        let _ = write!(
            s,
            "<svg viewBox=\"0 0 {W} {H}\" role=\"img\" aria-label=\"{t}\"><title>{t}</title><text x=\"{LEFT}\" y=\"16\" font-weight=\"600\">{t}</text>",
            t = esc(self.title)
        );
        let yt = ticks(y0, y1, 5);
        let ystep = if yt.len() > 1 { yt[1] - yt[0] } else { y1 - y0 };
        for t in &yt {
            let y = py(*t);
            let _ = write!(
                s,
                "<line class=\"grid\" x1=\"{LEFT}\" y1=\"{y:.1}\" x2=\"{:.1}\" y2=\"{y:.1}\"/><text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{}</text>",
                W - RIGHT,
                LEFT - 6.0,
                y + 4.0,
                tick_label(*t, ystep)
            );
        }
        let _ = write!(
            s,
            "<line class=\"axis\" x1=\"{LEFT}\" y1=\"{b:.1}\" x2=\"{:.1}\" y2=\"{b:.1}\"/><text transform=\"translate(14 {:.1}) rotate(-90)\" text-anchor=\"middle\">{}</text>",
            W - RIGHT,
            (TOP + H - BOTTOM) / 2.0,
            esc(self.y_label),
            b = H - BOTTOM
        );
        let n = self.groups.len().max(1) as f64;
        let group_w = (W - LEFT - RIGHT) / n;
        let k = self.series.len().max(1) as f64;
        let bar_w = (group_w * 0.7 / k).min(48.0);
        for (g, (label, vals)) in self.groups.iter().enumerate() {
            let gx = LEFT + g as f64 * group_w + group_w / 2.0;
            let start = gx - bar_w * k / 2.0;
            for (i, v) in vals.iter().enumerate() {
                let class = self.series.get(i).map_or("bar-cal", |s| s.1);
                let x = start + i as f64 * bar_w;
                match v.filter(|v| v.is_finite()) {
                    Some(v) => {
                        let top = py(v);
                        let _ = write!(
                            s,
                            "<rect class=\"{class}\" x=\"{x:.1}\" y=\"{top:.1}\" width=\"{:.1}\" height=\"{:.1}\"><title>{}: {}</title></rect><text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{}</text>",
                            bar_w - 2.0,
                            (H - BOTTOM - top).max(0.0),
                            esc(label),
                            super::page::fixed(v, 3),
                            x + (bar_w - 2.0) / 2.0,
                            top - 3.0,
                            super::page::fixed(v, 3)
                        );
                    }
                    None => {
                        let _ = write!(
                            s,
                            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\" class=\"muted\">n/a</text>",
                            x + (bar_w - 2.0) / 2.0,
                            H - BOTTOM - 3.0
                        );
                    }
                }
            }
            let _ = write!(
                s,
                "<text x=\"{gx:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{}</text>",
                H - BOTTOM + 14.0,
                esc(label)
            );
        }
        let mut lx = W - RIGHT - 220.0;
        for (name, class) in self.series {
            let _ = write!(
                s,
                "<rect class=\"{class}\" x=\"{lx:.1}\" y=\"6\" width=\"10\" height=\"10\"/><text x=\"{:.1}\" y=\"15\">{}</text>",
                lx + 14.0,
                esc(name)
            );
            lx += 110.0;
        }
        s.push_str("</svg>");
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round_and_cover_the_range() {
        assert_eq!(
            ticks(0.0, 1.0, 5),
            vec![0.0, 0.2, 0.4, 0.6000000000000001, 0.8, 1.0]
        );
        assert_eq!(ticks(3.0, 3.0, 5), vec![3.0]);
        assert_eq!(tick_label(0.25, 0.05), "0.25");
        assert_eq!(tick_label(40.0, 20.0), "40");
    }

    #[test]
    fn many_points_are_thinned_but_outliers_kept() {
        let points: Vec<Point> = (0..10_000)
            .map(|i| Point {
                x: i as f64,
                y: f64::from(i % 7),
                kind: Kind::Calibration,
                marked: i == 4_999,
            })
            .collect();
        let (kept, thinned) = thin(&points);
        assert!(thinned);
        assert!(kept.len() <= MAX_POINTS + 1);
        assert!(kept.iter().any(|p| p.marked && p.x == 4_999.0));
    }

    #[test]
    fn non_finite_points_are_left_out_and_counted() {
        let points = [
            Point {
                x: 0.0,
                y: f64::NAN,
                kind: Kind::Calibration,
                marked: false,
            },
            Point {
                x: 1.0,
                y: 2.0,
                kind: Kind::Validation,
                marked: false,
            },
        ];
        let (svg, note) = Scatter {
            title: "t",
            x_label: "x",
            y_label: "y",
            points: &points,
            lines: vec![(f64::INFINITY, "rms".into(), "rms")],
            y_from_zero: true,
            compact: false,
        }
        .render();
        assert!(!svg.contains("NaN") && !svg.contains("inf"));
        assert!(note.contains("1 points not finite"));
    }
}
