//! A drawing of a DH table's frames: an isometric and a side view with every DH frame's x/y/z
//! axes, the joint axis lines, the common normals and the links, labelled, as the paper's CAD
//! view shows them.

use std::fmt::Write as _;

use dh_workflows::geometry::{Convention, DhTable, JointKind};
use nalgebra::{Isometry3, Point3, Vector3};

/// Panel size (SVG user units) of each view.
const PANEL: f64 = 460.0;
/// Margin inside a panel.
const MARGIN: f64 = 40.0;

/// One view: how a 3-D point (metres, base link frame) lands on the panel's plane.
#[derive(Clone, Copy)]
enum View {
    Isometric,
    Side,
}

impl View {
    fn project(self, p: &Vector3<f64>) -> (f64, f64) {
        match self {
            // Looking down the (1, 1, 1) diagonal, z up.
            View::Isometric => (
                (p.x - p.y) * 0.866_025_403_784_438_6,
                p.z - 0.5 * (p.x + p.y),
            ),
            // Looking along +y: x to the right, z up.
            View::Side => (p.x, p.z),
        }
    }
    fn title(self) -> &'static str {
        match self {
            View::Isometric => "isometric",
            View::Side => "side (x-z plane, looking along +y)",
        }
    }
}

struct Scene {
    frames: Vec<Isometry3<f64>>,
    tip: Isometry3<f64>,
    /// Standard convention: the common normal of row i runs from `normals[i].0` to `.1`.
    normals: Vec<(Vector3<f64>, Vector3<f64>)>,
    /// Joint axis lines: a point and a direction.
    axes: Vec<(Vector3<f64>, Vector3<f64>, String)>,
    size: f64,
}

fn scene(table: &DhTable, q: &[f64]) -> Option<Scene> {
    let std = table.to_convention(Convention::Standard);
    let frames = std.frames(q).ok()?;
    let tip = std.fk(q).ok()?;
    let mut normals = Vec::new();
    let mut axes = Vec::new();
    for (i, row) in std.rows.iter().enumerate() {
        let f = &frames[i];
        let z = f.rotation * Vector3::z();
        let d = row.d
            + if row.kind == JointKind::Prismatic {
                q[i]
            } else {
                0.0
            };
        let foot = f.translation.vector + z * d;
        normals.push((foot, frames[i + 1].translation.vector));
        axes.push((f.translation.vector, z, row.name.clone()));
    }
    let pts: Vec<Vector3<f64>> = frames
        .iter()
        .map(|f| f.translation.vector)
        .chain([tip.translation.vector])
        .collect();
    let mut lo = pts[0];
    let mut hi = pts[0];
    for p in &pts {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let size = (hi - lo).norm().max(0.05);
    Some(Scene {
        frames,
        tip,
        normals,
        axes,
        size,
    })
}

/// Labels placed so that none overlaps another: each tries spots around its anchor, then
/// further below, and takes the first free one (greedy, in drawing order).
#[derive(Default)]
struct Labels {
    /// Boxes taken: (left, top, right, bottom) in SVG units.
    taken: Vec<(f64, f64, f64, f64)>,
}

impl Labels {
    /// Width of `text` at the drawing's 11-unit font (bold a little wider).
    fn width(text: &str, bold: bool) -> f64 {
        text.chars().count() as f64 * if bold { 7.0 } else { 6.2 }
    }

    /// Where the baseline of `text` goes for an anchor at `(x, y)`.
    fn place(&mut self, x: f64, y: f64, text: &str, bold: bool) -> (f64, f64) {
        let (w, h) = (Self::width(text, bold), 12.0);
        let free = |l: f64, b: f64, taken: &[(f64, f64, f64, f64)]| {
            let (t, r) = (b - h + 2.0, l + w);
            taken
                .iter()
                .all(|&(l2, t2, r2, b2)| r <= l2 || l >= r2 || b + 1.0 <= t2 || t >= b2 + 1.0)
        };
        let mut spots = vec![
            (x + 4.0, y - 4.0),
            (x + 4.0, y + 12.0),
            (x - w - 4.0, y - 4.0),
            (x - w - 4.0, y + 12.0),
        ];
        for k in 1..=12 {
            let down = 12.0 * k as f64;
            spots.push((x + 4.0, y - 4.0 + down));
            spots.push((x + 4.0, y - 4.0 - down));
        }
        let spot = spots
            .iter()
            .copied()
            .find(|&(l, b)| free(l, b, &self.taken))
            .unwrap_or((x + 4.0, y - 4.0));
        self.taken
            .push((spot.0, spot.1 - h + 2.0, spot.0 + w, spot.1));
        spot
    }
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The SVG document of `table`'s frames at joint values `q` (one per row; radians or metres).
/// Returns `None` when `q` does not fit the table.
pub fn frames_svg(table: &DhTable, q: &[f64], title: &str) -> Option<String> {
    let sc = scene(table, q)?;
    let arrow = sc.size / 10.0;
    let axis_half = sc.size / 5.0;
    let mut s = String::new();
    let width = 2.0 * PANEL;
    let _ = writeln!(
        s,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width}\" height=\"{}\" viewBox=\"0 0 {width} {}\" font-family=\"sans-serif\" font-size=\"11\">",
        PANEL + 30.0,
        PANEL + 30.0
    );
    let _ = writeln!(s, "<title>{}</title>", esc(title));
    let _ = writeln!(s, "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>");
    let _ = writeln!(s, "<text x=\"10\" y=\"18\" font-size=\"13\">{} — DH frames (x red, y green, z blue), joint axes dashed, common normals orange</text>", esc(title));
    for (k, view) in [View::Isometric, View::Side].into_iter().enumerate() {
        // Everything this view draws, to fit it into the panel.
        let mut pts: Vec<Vector3<f64>> = Vec::new();
        for f in sc.frames.iter().chain([&sc.tip]) {
            let o = f.translation.vector;
            pts.push(o);
            for a in [Vector3::x(), Vector3::y(), Vector3::z()] {
                pts.push(o + f.rotation * a * arrow);
            }
        }
        for (p, z, _) in &sc.axes {
            pts.push(p + z * axis_half);
            pts.push(p - z * axis_half);
        }
        let uv: Vec<(f64, f64)> = pts.iter().map(|p| view.project(p)).collect();
        let (mut u0, mut u1, mut v0, mut v1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for (u, v) in &uv {
            u0 = u0.min(*u);
            u1 = u1.max(*u);
            v0 = v0.min(*v);
            v1 = v1.max(*v);
        }
        let scale = (PANEL - 2.0 * MARGIN) / (u1 - u0).max(v1 - v0).max(1e-9);
        let ox = k as f64 * PANEL + MARGIN + 0.5 * ((PANEL - 2.0 * MARGIN) - (u1 - u0) * scale);
        let oy = 30.0 + MARGIN + 0.5 * ((PANEL - 2.0 * MARGIN) + (v1 - v0) * scale);
        let at = |p: &Vector3<f64>| {
            let (u, v) = view.project(p);
            (ox + (u - u0) * scale, oy - (v - v0) * scale)
        };
        let _ = writeln!(s, "<g id=\"view-{k}\">");
        let mut labels = Labels::default();
        let _ = writeln!(
            s,
            "<rect x=\"{}\" y=\"30\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#ccc\"/>",
            k as f64 * PANEL + 4.0,
            PANEL - 8.0,
            PANEL - 4.0
        );
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"46\" fill=\"#555\">{}</text>",
            k as f64 * PANEL + 12.0,
            view.title()
        );
        for (p, z, name) in &sc.axes {
            let (a, b) = (at(&(p - z * axis_half)), at(&(p + z * axis_half)));
            let _ = writeln!(s, "<line x1=\"{:.2}\" y1=\"{:.2}\" x2=\"{:.2}\" y2=\"{:.2}\" stroke=\"#888\" stroke-dasharray=\"6 4\"><title>axis of {}</title></line>", a.0, a.1, b.0, b.1, esc(name));
        }
        let path: Vec<String> = sc
            .frames
            .iter()
            .map(|f| f.translation.vector)
            .chain([sc.tip.translation.vector])
            .map(|p| {
                let (x, y) = at(&p);
                format!("{x:.2},{y:.2}")
            })
            .collect();
        let _ = writeln!(s, "<polyline points=\"{}\" fill=\"none\" stroke=\"#333\" stroke-width=\"1.5\" stroke-opacity=\"0.35\"/>", path.join(" "));
        for (i, (a, b)) in sc.normals.iter().enumerate() {
            let (a, b) = (at(a), at(b));
            let _ = writeln!(s, "<line x1=\"{:.2}\" y1=\"{:.2}\" x2=\"{:.2}\" y2=\"{:.2}\" stroke=\"orange\" stroke-width=\"2.5\"><title>common normal of row {}</title></line>", a.0, a.1, b.0, b.1, i + 1);
        }
        // Frames whose origins land on one spot share one label ("F1 F2", "F7 tool").
        let mut spots: Vec<((f64, f64), String, &Isometry3<f64>)> = Vec::new();
        let named = sc
            .frames
            .iter()
            .enumerate()
            .map(|(i, f)| (format!("F{i}"), f))
            .chain([("tool".to_string(), &sc.tip)]);
        for (label, f) in named {
            let o = at(&f.translation.vector);
            for (a, colour) in [
                (Vector3::x(), "red"),
                (Vector3::y(), "green"),
                (Vector3::z(), "blue"),
            ] {
                let e = at(&(f * Point3::from(a * arrow)).coords);
                let _ = writeln!(s, "<line x1=\"{:.2}\" y1=\"{:.2}\" x2=\"{:.2}\" y2=\"{:.2}\" stroke=\"{colour}\" stroke-width=\"1.6\"/>", o.0, o.1, e.0, e.1);
            }
            let _ = writeln!(
                s,
                "<circle cx=\"{:.2}\" cy=\"{:.2}\" r=\"2.5\" fill=\"black\"/>",
                o.0, o.1
            );
            match spots
                .iter_mut()
                .find(|(p, _, _)| (p.0 - o.0).hypot(p.1 - o.1) < 3.0)
            {
                Some((_, text, _)) => {
                    text.push(' ');
                    text.push_str(&label);
                }
                None => spots.push((o, label, f)),
            }
        }
        for (o, text, _) in &spots {
            let (x, y) = labels.place(o.0, o.1, text, true);
            let _ = writeln!(
                s,
                "<text x=\"{x:.2}\" y=\"{y:.2}\" font-weight=\"bold\">{}</text>",
                esc(text)
            );
        }
        // Axis names after the frame labels, each at the upper end of its axis.
        for (p, z, name) in &sc.axes {
            let b = at(&(p + z * axis_half));
            let (x, y) = labels.place(b.0, b.1 + 4.0, name, false);
            let _ = writeln!(
                s,
                "<text x=\"{x:.2}\" y=\"{y:.2}\" fill=\"#666\">{}</text>",
                esc(name)
            );
        }
        let _ = writeln!(s, "</g>");
    }
    let _ = writeln!(s, "</svg>");
    Some(s)
}
