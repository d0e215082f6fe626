//! The figure of the accuracy ladder: one log–log panel per problem, |error| against the
//! cost, one curve per setting family, the Pareto front dashed with ringed points. Drawn with
//! [`crate::report::svg`].

use fracture_verify::Problem;

use super::accuracy::{Cost, Family, Row, pareto};
use crate::report::svg::{
    Frame, Marker, Scale, Stroke, Svg, TickStyle, decade_label, legend_entry, text, vertical_text,
};

const PANEL_W: f64 = 400.0;
const PANEL_H: f64 = 290.0;
const COLS: usize = 3;
const MARGIN_L: f64 = 62.0;
const MARGIN_R: f64 = 14.0;
const MARGIN_T: f64 = 30.0;
const MARGIN_B: f64 = 44.0;
const LEGEND_H: f64 = 28.0;
const FRONT: Stroke = Stroke::new("black").dashed();

fn colour(f: Family) -> &'static str {
    match f {
        Family::Resolution => "#1f77b4",
        Family::Linear => "#ff7f0e",
        Family::Ppc => "#2ca02c",
        Family::Cfl => "#d62728",
        Family::Contour => "#9467bd",
    }
}

/// |error| floored at 1e-6 so that an exact answer stays on the log axis.
fn err(r: &Row) -> f64 {
    r.error.abs().max(1e-6)
}

/// The plot as an SVG document.
pub fn accuracy_plot(rows: &[Row], cost: Cost) -> String {
    let problems: Vec<Problem> = Problem::ALL
        .into_iter()
        .filter(|p| rows.iter().any(|r| r.problem == p.name()))
        .collect();
    let nrows = problems.len().div_ceil(COLS).max(1);
    let (w, h) = (COLS as f64 * PANEL_W, nrows as f64 * PANEL_H + LEGEND_H);
    let mut svg = Svg::new(w, h, 11);
    let mut lx = 10.0;
    for f in Family::ALL {
        let c = colour(f);
        let dot = Marker::Dot { r: 3.0, colour: c };
        let entry = legend_entry(lx, 14.0, Stroke::new(c).width(2.0), Some(dot), f.name());
        svg.add(entry);
        lx += 100.0;
    }
    let ring = Marker::Ring {
        r: 5.0,
        colour: "black",
    };
    svg.add(legend_entry(lx, 14.0, FRONT, Some(ring), "Pareto front"));
    for (k, p) in problems.iter().enumerate() {
        let ox = (k % COLS) as f64 * PANEL_W;
        let oy = LEGEND_H + (k / COLS) as f64 * PANEL_H;
        panel(&mut svg, rows, *p, cost, ox, oy);
    }
    svg.finish()
}

/// The panel of problem `p` with its top-left corner at (ox, oy).
fn panel(svg: &mut Svg, rows: &[Row], p: Problem, cost: Cost, ox: f64, oy: f64) {
    let rs: Vec<&Row> = rows
        .iter()
        .filter(|r| r.problem == p.name() && r.error.is_finite() && cost.of(r) > 0.0)
        .collect();
    let pw = PANEL_W - MARGIN_L - MARGIN_R;
    let ph = PANEL_H - MARGIN_T - MARGIN_B;
    let (left, top) = (ox + MARGIN_L, oy + MARGIN_T);
    let title = format!("{} ({})", p.name(), p.reference_name());
    svg.add(text(left, oy + 18.0, &title).bold());
    let min_max = |f: &dyn Fn(&Row) -> f64| {
        (
            rs.iter().map(|r| f(r)).fold(f64::INFINITY, f64::min),
            rs.iter().map(|r| f(r)).fold(0.0, f64::max),
        )
    };
    let (t0, t1) = min_max(&|r| cost.of(r));
    let (e0, e1) = min_max(&err);
    let frame = Frame {
        left,
        top,
        width: pw,
        height: ph,
        x: Scale::log_covering(t0, t1),
        y: Scale::log_covering(e0, e1),
    };
    svg.add(frame.outline("#888"));
    if rs.is_empty() {
        return;
    }
    let grid = TickStyle::Grid("#ddd");
    frame.x_ticks(svg, 1.0, grid, 14.0, |d| decade_label(d, "s"));
    // |error| is a fraction; its ticks are labelled in percent.
    frame.y_ticks(svg, 1.0, grid, 4.0, |d| decade_label(d + 2.0, "%"));
    svg.add(format_args!(
        "{}{}",
        text(left + 0.5 * pw, oy + PANEL_H - 12.0, cost.label()).middle(),
        vertical_text(ox + 14.0, top + 0.5 * ph, "|error|")
    ));
    // One curve per family, ordered by cost.
    let at = |r: &Row| [cost.of(r), err(r)];
    for f in Family::ALL {
        let mut pts: Vec<&Row> = rs
            .iter()
            .copied()
            .filter(|r| r.family == f.name())
            .collect();
        if pts.is_empty() {
            continue;
        }
        pts.sort_by(|a, b| cost.of(a).total_cmp(&cost.of(b)));
        let line: Vec<[f64; 2]> = pts.iter().map(|r| at(r)).collect();
        svg.add(frame.polyline(&line, Stroke::new(colour(f)).width(1.5)));
        let dot = Marker::Dot {
            r: 3.0,
            colour: colour(f),
        };
        for r in pts {
            let title = format!(
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
            );
            svg.add(frame.marker(at(r), dot, Some(&title)));
        }
    }
    let front: Vec<[f64; 2]> = pareto(&rs, cost).into_iter().map(|i| at(rs[i])).collect();
    svg.add(frame.polyline(&front, FRONT));
    let ring = Marker::Ring {
        r: 5.5,
        colour: "black",
    };
    for p in front {
        svg.add(frame.marker(p, ring, None));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three rungs of every family for two problems; one rung failed, one exact.
    fn rows() -> Vec<Row> {
        let mut out = Vec::new();
        for p in [Problem::CenterCrack, Problem::VibratingBar] {
            for (fi, f) in Family::ALL.into_iter().enumerate() {
                for k in 0..3 {
                    let error = match (fi, k) {
                        (1, 2) => 0.0,
                        (2, 1) => f64::NAN,
                        _ => 0.3 / (1.0 + (fi * 3 + k * 7) as f64),
                    };
                    out.push(Row {
                        problem: p.name(),
                        family: f.name(),
                        cell_size: 0.004 / f64::from(1 << k),
                        cells_across: 2.0 * f64::from(1 << k),
                        ppc: 2,
                        cfl: 0.5,
                        shape: "gimp",
                        contour: 2,
                        particles: 1000,
                        steps: 100,
                        wall_seconds: 0.01 * 3f64.powi((k + fi) as i32),
                        cpu_seconds: 0.02,
                        value: 1.0 + error,
                        reference: 1.0,
                        error,
                        worst: error,
                        failure: String::new(),
                    });
                }
            }
        }
        out
    }

    /// One panel per problem with a curve per family and the front; the CPU cost (the same
    /// for every run) still gets a one-decade axis.
    #[test]
    fn one_panel_per_problem() {
        for cost in [Cost::Wall, Cost::Cpu] {
            let svg = accuracy_plot(&rows(), cost);
            assert!(svg.starts_with("<svg ") && svg.ends_with("</svg>\n"));
            assert_eq!(svg.matches(r#"font-weight="bold""#).count(), 2);
            assert_eq!(
                svg.matches("<polyline").count(),
                2 * (Family::ALL.len() + 1)
            );
            assert!(!svg.contains("NaN") && !svg.contains("inf\""), "{svg}");
        }
        let empty = accuracy_plot(&[], Cost::Wall);
        assert!(!empty.contains("<polyline"));
    }
}
