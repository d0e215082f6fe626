//! A hand-written SVG of the accuracy ladder: one log–log panel per problem, |error| against
//! wall time, one curve per setting family, the Pareto front dashed with ringed points.

use std::fmt::Write;

use fracture_verify::Problem;

use super::accuracy::{Cost, Family, Row, pareto};

const PANEL_W: f64 = 400.0;
const PANEL_H: f64 = 290.0;
const COLS: usize = 3;
const MARGIN_L: f64 = 62.0;
const MARGIN_R: f64 = 14.0;
const MARGIN_T: f64 = 30.0;
const MARGIN_B: f64 = 44.0;

fn colour(f: Family) -> &'static str {
    match f {
        Family::Resolution => "#1f77b4",
        Family::Linear => "#ff7f0e",
        Family::Ppc => "#2ca02c",
        Family::Cfl => "#d62728",
        Family::Contour => "#9467bd",
    }
}

/// Escape text for SVG/XML content.
pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// Decades covering [lo, hi] (log10), at least one decade wide.
fn decades(lo: f64, hi: f64) -> (f64, f64) {
    let (mut a, mut b) = (lo.log10().floor(), hi.log10().ceil());
    if b <= a {
        a -= 0.5;
        b += 0.5;
    }
    (a, b)
}

/// The plot as an SVG document.
pub fn accuracy_plot(rows: &[Row], cost: Cost) -> String {
    let problems: Vec<Problem> = Problem::ALL
        .into_iter()
        .filter(|p| rows.iter().any(|r| r.problem == p.name()))
        .collect();
    let nrows = problems.len().div_ceil(COLS).max(1);
    let legend_h = 28.0;
    let (w, h) = (COLS as f64 * PANEL_W, nrows as f64 * PANEL_H + legend_h);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="11">"#
    );
    let _ = writeln!(s, r#"<rect width="{w}" height="{h}" fill="white"/>"#);
    // Legend.
    let mut lx = 10.0;
    for f in Family::ALL {
        let _ = writeln!(
            s,
            r#"<line x1="{lx}" y1="14" x2="{}" y2="14" stroke="{}" stroke-width="2"/><circle cx="{}" cy="14" r="3" fill="{}"/><text x="{}" y="18">{}</text>"#,
            lx + 20.0,
            colour(f),
            lx + 10.0,
            colour(f),
            lx + 24.0,
            f.name()
        );
        lx += 100.0;
    }
    let _ = writeln!(
        s,
        r#"<line x1="{lx}" y1="14" x2="{}" y2="14" stroke="black" stroke-dasharray="4 3"/><circle cx="{}" cy="14" r="5" fill="none" stroke="black"/><text x="{}" y="18">Pareto front</text>"#,
        lx + 20.0,
        lx + 10.0,
        lx + 24.0
    );
    for (k, p) in problems.iter().enumerate() {
        let ox = (k % COLS) as f64 * PANEL_W;
        let oy = legend_h + (k / COLS) as f64 * PANEL_H;
        let rs: Vec<&Row> = rows
            .iter()
            .filter(|r| r.problem == p.name() && r.error.is_finite() && cost.of(r) > 0.0)
            .collect();
        let pw = PANEL_W - MARGIN_L - MARGIN_R;
        let ph = PANEL_H - MARGIN_T - MARGIN_B;
        let _ = writeln!(
            s,
            r#"<text x="{}" y="{}" font-weight="bold">{}</text>"#,
            ox + MARGIN_L,
            oy + 18.0,
            escape(&format!("{} ({})", p.name(), p.reference_name()))
        );
        let _ = writeln!(
            s,
            r##"<rect x="{}" y="{}" width="{pw}" height="{ph}" fill="none" stroke="#888"/>"##,
            ox + MARGIN_L,
            oy + MARGIN_T
        );
        if rs.is_empty() {
            continue;
        }
        // |error| floor at 1e-6 so an exact answer stays on the log axis.
        let err = |r: &Row| r.error.abs().max(1e-6);
        let (tx0, tx1) = decades(
            rs.iter().map(|r| cost.of(r)).fold(f64::INFINITY, f64::min),
            rs.iter().map(|r| cost.of(r)).fold(0.0, f64::max),
        );
        let (ey0, ey1) = decades(
            rs.iter().map(|r| err(r)).fold(f64::INFINITY, f64::min),
            rs.iter().map(|r| err(r)).fold(0.0, f64::max),
        );
        let px = |t: f64| ox + MARGIN_L + (t.log10() - tx0) / (tx1 - tx0) * pw;
        let py = |e: f64| oy + MARGIN_T + ph - (e.log10() - ey0) / (ey1 - ey0) * ph;
        // Decade ticks and grid.
        let mut d = tx0;
        while d <= tx1 + 1e-9 {
            let x = px(10f64.powf(d));
            let _ = writeln!(
                s,
                r##"<line x1="{x}" y1="{}" x2="{x}" y2="{}" stroke="#ddd"/><text x="{x}" y="{}" text-anchor="middle">{}</text>"##,
                oy + MARGIN_T,
                oy + MARGIN_T + ph,
                oy + MARGIN_T + ph + 14.0,
                tick(d, "s")
            );
            d += 1.0;
        }
        let mut d = ey0;
        while d <= ey1 + 1e-9 {
            let y = py(10f64.powf(d));
            let _ = writeln!(
                s,
                r##"<line x1="{}" y1="{y}" x2="{}" y2="{y}" stroke="#ddd"/><text x="{}" y="{}" text-anchor="end">{}</text>"##,
                ox + MARGIN_L,
                ox + MARGIN_L + pw,
                ox + MARGIN_L - 4.0,
                y + 4.0,
                tick(d + 2.0, "%")
            );
            d += 1.0;
        }
        let _ = writeln!(
            s,
            r#"<text x="{}" y="{}" text-anchor="middle">{}</text><text transform="translate({},{}) rotate(-90)" text-anchor="middle">|error|</text>"#,
            ox + MARGIN_L + 0.5 * pw,
            oy + PANEL_H - 12.0,
            cost.label(),
            ox + 14.0,
            oy + MARGIN_T + 0.5 * ph
        );
        // One curve per family, ordered by wall time.
        for f in Family::ALL {
            let mut pts: Vec<&&Row> = rs.iter().filter(|r| r.family == f.name()).collect();
            if pts.is_empty() {
                continue;
            }
            pts.sort_by(|a, b| cost.of(a).total_cmp(&cost.of(b)));
            let path: Vec<String> = pts
                .iter()
                .map(|r| format!("{:.1},{:.1}", px(cost.of(r)), py(err(r))))
                .collect();
            let _ = writeln!(
                s,
                r#"<polyline points="{}" fill="none" stroke="{}" stroke-width="1.5"/>"#,
                path.join(" "),
                colour(f)
            );
            for r in pts {
                let _ = writeln!(
                    s,
                    r#"<circle cx="{:.1}" cy="{:.1}" r="3" fill="{}"><title>{}</title></circle>"#,
                    px(cost.of(r)),
                    py(err(r)),
                    colour(f),
                    escape(&format!(
                        "{} h={:e} ppc={} cfl={} {} contour={}: {:+.3} % in {:.2} s wall, {:.2} s CPU",
                        r.family,
                        r.cell_size,
                        r.ppc,
                        r.cfl,
                        r.shape,
                        r.contour,
                        100.0 * r.error,
                        r.wall_seconds,
                        r.cpu_seconds
                    ))
                );
            }
        }
        let front = pareto(&rs, cost);
        let path: Vec<String> = front
            .iter()
            .map(|&i| format!("{:.1},{:.1}", px(cost.of(rs[i])), py(err(rs[i]))))
            .collect();
        let _ = writeln!(
            s,
            r#"<polyline points="{}" fill="none" stroke="black" stroke-dasharray="4 3"/>"#,
            path.join(" ")
        );
        for &i in &front {
            let _ = writeln!(
                s,
                r#"<circle cx="{:.1}" cy="{:.1}" r="5.5" fill="none" stroke="black"/>"#,
                px(cost.of(rs[i])),
                py(err(rs[i]))
            );
        }
    }
    s.push_str("</svg>\n");
    s
}

/// A decade tick label: 10^d with a unit (percent ticks pass d + 2).
fn tick(d: f64, unit: &str) -> String {
    let v = 10f64.powf(d);
    if (-3.0..=3.0).contains(&d) {
        let decimals = (-d).max(0.0) as usize;
        format!("{v:.decimals$} {unit}")
    } else {
        format!("1e{d:.0} {unit}")
    }
}
