//! The crack-path picture of a run (`path.svg`): the bodies' outlines, the cracks and
//! interfaces as the scene drew them, and the x–y path of every crack tip over time,
//! coloured by time, with axes in millimetres.
//!
//! [`PathRecorder`] keeps, per tip, only the samples at which it moved (a stationary tip
//! is one point), so a run folder can draw the picture at its end without holding every
//! row; [`path_svg`] draws it.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use fracture_api::Scene;
use fracture_api::results::CrackTipRow;
use fracture_api::scene::Region;

/// Width and height of the picture's plot area (px, before margins).
const PLOT_W: f64 = 640.0;
/// Margins: left (tick labels), right (colour bar), top (title), bottom (axis labels).
const MARGIN: [f64; 4] = [64.0, 128.0, 36.0, 48.0];

/// One tip's path: `(time, x, y)` samples at which it moved.
pub type TipPath = Vec<(f64, f64, f64)>;

/// The samples of each tip at which it moved, keyed by (crack, tip).
#[derive(Debug, Clone, Default)]
pub struct PathRecorder {
    paths: BTreeMap<(u32, u32), TipPath>,
}

impl PathRecorder {
    /// An empty recorder.
    pub fn new() -> PathRecorder {
        PathRecorder::default()
    }

    /// Add rows (each tip's in time order); keeps a row when its tip moved since the last
    /// kept one, and always the first.
    pub fn extend<'a>(&mut self, rows: impl IntoIterator<Item = &'a CrackTipRow>) {
        for r in rows {
            if !(r.x.is_finite() && r.y.is_finite()) {
                continue;
            }
            let p = self.paths.entry((r.crack, r.tip)).or_default();
            match p.last_mut() {
                Some(&mut (_, x, y)) if x == r.x && y == r.y => {}
                _ => p.push((r.time, r.x, r.y)),
            }
        }
    }

    /// The paths, by (crack, tip).
    pub fn paths(&self) -> &BTreeMap<(u32, u32), TipPath> {
        &self.paths
    }
}

/// Escape text for SVG.
fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The picture's time colour (viridis) of `t` in [t0, t1].
fn time_colour(t: f64, t0: f64, t1: f64) -> String {
    let s = if t1 > t0 {
        ((t - t0) / (t1 - t0)).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let c = colorous::VIRIDIS.eval_continuous(s);
    format!("#{:02x}{:02x}{:02x}", c.r, c.g, c.b)
}

/// A number for SVG coordinates (two decimals).
fn n(v: f64) -> String {
    format!("{v:.2}")
}

/// The crack-path picture of `scene`'s run from its tips' paths.
pub fn path_svg(scene: &Scene, paths: &BTreeMap<(u32, u32), TipPath>) -> String {
    // The view: the bodies' bounding box (the grid box if there are none), padded by 3 %.
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    let mut grow = |p: [f64; 2]| {
        for k in 0..2 {
            if p[k].is_finite() {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
    };
    for b in &scene.bodies {
        match &b.region {
            Region::Rectangle { min, max } => {
                grow(*min);
                grow(*max);
            }
            Region::Circle { center, radius } => {
                grow([center[0] - radius, center[1] - radius]);
                grow([center[0] + radius, center[1] + radius]);
            }
            Region::Polygon { points } => points.iter().copied().for_each(&mut grow),
        }
    }
    if !(lo[0] < hi[0] && lo[1] < hi[1]) {
        lo = scene.grid.min;
        hi = scene.grid.max;
    }
    let pad = 0.03 * (hi[0] - lo[0]).max(hi[1] - lo[1]);
    let (x0, x1, y0, y1) = (lo[0] - pad, hi[0] + pad, lo[1] - pad, hi[1] + pad);
    let scale = PLOT_W / (x1 - x0).max(1e-300);
    let plot_h = ((y1 - y0) * scale).clamp(120.0, 900.0);
    let scale = scale.min(plot_h / (y1 - y0).max(1e-300));
    let plot_w = (x1 - x0) * scale;
    let [ml, mr, mt, mb] = MARGIN;
    let width = ml + plot_w + mr;
    let height = mt + plot_h + mb;
    let px = |x: f64| ml + (x - x0) * scale;
    let py = |y: f64| mt + plot_h - (y - y0) * scale;

    let mut s = String::new();
    let _ = write!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="12">"#,
        w = n(width),
        h = n(height)
    );
    let _ = write!(
        s,
        r##"<rect width="100%" height="100%" fill="#ffffff"/><text x="{}" y="22" text-anchor="middle" font-size="14">{} — crack paths</text>"##,
        n(width / 2.0),
        esc(&scene.name)
    );
    // Bodies.
    for b in &scene.bodies {
        let style = r##"fill="#eef1f5" stroke="#5b6670" stroke-width="1""##;
        match &b.region {
            Region::Rectangle { min, max } => {
                let _ = write!(
                    s,
                    r#"<rect x="{}" y="{}" width="{}" height="{}" {style}/>"#,
                    n(px(min[0])),
                    n(py(max[1])),
                    n((max[0] - min[0]) * scale),
                    n((max[1] - min[1]) * scale)
                );
            }
            Region::Circle { center, radius } => {
                let _ = write!(
                    s,
                    r#"<circle cx="{}" cy="{}" r="{}" {style}/>"#,
                    n(px(center[0])),
                    n(py(center[1])),
                    n(radius * scale)
                );
            }
            Region::Polygon { points } => {
                let pts: Vec<String> = points
                    .iter()
                    .map(|p| format!("{},{}", n(px(p[0])), n(py(p[1]))))
                    .collect();
                let _ = write!(s, r#"<polygon points="{}" {style}/>"#, pts.join(" "));
            }
        }
    }
    // Cracks and interfaces as drawn in the scene.
    let polyline = |s: &mut String, pts: &[[f64; 2]], attrs: &str| {
        let p: Vec<String> = pts
            .iter()
            .map(|q| format!("{},{}", n(px(q[0])), n(py(q[1]))))
            .collect();
        let _ = write!(
            s,
            r#"<polyline points="{}" fill="none" {attrs}/>"#,
            p.join(" ")
        );
    };
    for it in &scene.interfaces {
        polyline(
            &mut s,
            &it.points,
            r##"stroke="#b08030" stroke-width="1.5" stroke-dasharray="5 3""##,
        );
    }
    for cr in &scene.cracks {
        polyline(&mut s, &cr.points, r##"stroke="#202020" stroke-width="2""##);
    }
    // Tip paths, coloured by time.
    let (mut t0, mut t1) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in paths.values() {
        for &(t, _, _) in p {
            t0 = t0.min(t);
            t1 = t1.max(t);
        }
    }
    if !t0.is_finite() {
        (t0, t1) = (0.0, scene.time.end);
    }
    t1 = t1.max(scene.time.end.min(t1.max(t0)));
    for p in paths.values() {
        for w in p.windows(2) {
            let _ = write!(
                s,
                r#"<line x1="{}" y1="{}" x2="{}" y2="{}" stroke="{}" stroke-width="3" stroke-linecap="round"/>"#,
                n(px(w[0].1)),
                n(py(w[0].2)),
                n(px(w[1].1)),
                n(py(w[1].2)),
                time_colour(w[1].0, t0, t1)
            );
        }
        if let Some(&(t, x, y)) = p.last() {
            let _ = write!(
                s,
                r##"<circle cx="{}" cy="{}" r="3.5" fill="{}" stroke="#000" stroke-width="0.8"/>"##,
                n(px(x)),
                n(py(y)),
                time_colour(t, t0, t1)
            );
        }
    }
    // Axes in mm.
    let axis = r##"stroke="#333" stroke-width="1""##;
    let _ = write!(
        s,
        r#"<line x1="{ml}" y1="{b}" x2="{r}" y2="{b}" {axis}/><line x1="{ml}" y1="{mt}" x2="{ml}" y2="{b}" {axis}/>"#,
        b = n(mt + plot_h),
        r = n(ml + plot_w)
    );
    for (k, (a0, a1)) in [(x0, x1), (y0, y1)].into_iter().enumerate() {
        let len_px = if k == 0 { plot_w } else { plot_h };
        let step = crate::render::nice_step((a1 - a0) * 1e3, (len_px / 80.0).max(2.0)) * 1e-3;
        let mut v = (a0 / step).ceil() * step;
        while v <= a1 + 1e-12 * step.abs() {
            let label = format!("{}", (v * 1e3 * 1e6).round() / 1e6);
            if k == 0 {
                let _ = write!(
                    s,
                    r#"<line x1="{x}" y1="{b}" x2="{x}" y2="{b2}" {axis}/><text x="{x}" y="{ty}" text-anchor="middle">{label}</text>"#,
                    x = n(px(v)),
                    b = n(mt + plot_h),
                    b2 = n(mt + plot_h + 5.0),
                    ty = n(mt + plot_h + 18.0)
                );
            } else {
                let _ = write!(
                    s,
                    r#"<line x1="{l}" y1="{y}" x2="{ml}" y2="{y}" {axis}/><text x="{tx}" y="{ty}" text-anchor="end">{label}</text>"#,
                    l = n(ml - 5.0),
                    y = n(py(v)),
                    tx = n(ml - 8.0),
                    ty = n(py(v) + 4.0)
                );
            }
            v += step;
        }
    }
    let _ = write!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle">x (mm)</text><text x="16" y="{}" text-anchor="middle" transform="rotate(-90 16 {})">y (mm)</text>"#,
        n(ml + plot_w / 2.0),
        n(height - 8.0),
        n(mt + plot_h / 2.0),
        n(mt + plot_h / 2.0)
    );
    // Time colour bar (µs).
    let bx = ml + plot_w + 24.0;
    let bh = plot_h.min(240.0);
    for i in 0..32 {
        let f0 = i as f64 / 32.0;
        let _ = write!(
            s,
            r#"<rect x="{}" y="{}" width="14" height="{}" fill="{}"/>"#,
            n(bx),
            n(mt + bh * (1.0 - f0 - 1.0 / 32.0)),
            n(bh / 32.0 + 0.5),
            time_colour(t0 + f0 * (t1 - t0), t0, t1)
        );
    }
    for (f, t) in [(0.0, t0), (1.0, t1)] {
        let _ = write!(
            s,
            r#"<text x="{}" y="{}">{:.3} µs</text>"#,
            n(bx + 18.0),
            n(mt + bh * (1.0 - f) + 4.0),
            t * 1e6
        );
    }
    let _ = write!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle">time</text>"#,
        n(bx + 7.0),
        n(mt + bh + 16.0)
    );
    s.push_str("</svg>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene() -> Scene {
        serde_json::from_value(serde_json::json!({
            "name": "plate <a&b>",
            "grid": {"cell_size": 0.001, "min": [0.0, 0.0], "max": [0.1, 0.05]},
            "materials": {"m": {"model": "linear_elastic", "density": 1000.0,
                                 "youngs_modulus": 1e9, "poissons_ratio": 0.3}},
            "bodies": [{"material": "m",
                        "region": {"rectangle": {"min": [0.005, 0.005], "max": [0.045, 0.045]}}}],
            "cracks": [{"points": [[0.02, 0.0255], [0.03, 0.0255]]}],
            "time": {"end": 1e-5}
        }))
        .unwrap_or_else(|e| panic!("{e}"))
    }

    fn row(time: f64, tip: u32, x: f64) -> CrackTipRow {
        CrackTipRow {
            time,
            tip,
            x,
            y: 0.0255,
            ..CrackTipRow::default()
        }
    }

    #[test]
    fn the_recorder_keeps_only_moves() {
        let mut r = PathRecorder::new();
        let rows = [
            row(0.0, 1, 0.03),
            row(1e-6, 1, 0.03),
            row(2e-6, 1, 0.031),
            row(3e-6, 1, 0.031),
            row(4e-6, 1, 0.032),
            row(0.0, 0, 0.02),
            row(4e-6, 0, 0.02),
        ];
        r.extend(&rows);
        let p = r.paths();
        assert_eq!(p[&(0, 1)].len(), 3);
        assert_eq!(p[&(0, 0)].len(), 1);
    }

    #[test]
    fn the_picture_is_well_formed_svg_with_the_paths() {
        let mut r = PathRecorder::new();
        r.extend(&[row(0.0, 1, 0.03), row(5e-6, 1, 0.035), row(1e-5, 1, 0.04)]);
        let svg = path_svg(&scene(), r.paths());
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert!(svg.contains("plate &lt;a&amp;b&gt;"), "title escaped");
        // One body, one crack, two path segments, one end marker.
        assert_eq!(
            svg.matches("<rect x=").count() - 32,
            1,
            "body + 32 colour-bar bands"
        );
        assert_eq!(svg.matches("<polyline").count(), 1);
        assert_eq!(svg.matches(r#"stroke-width="3" stroke-linecap"#).count(), 2);
        assert!(svg.contains("x (mm)") && svg.contains("10.000 µs"));
        // Every tag closes: as many '<' as '>'.
        assert_eq!(svg.matches('<').count(), svg.matches('>').count());
    }
}
