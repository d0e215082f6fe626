//! The figures of the page: tip speed against time per sweep (SVG, drawn with
//! `crate::report::svg`) and the isochromatic fringe pictures (PNG) with their table.

use std::fmt::Write as _;

use fracture_api::scene::WaveSpeeds;

use super::measure::FRINGE_TIMES;
use super::report::Report;
use super::sweeps::Sweep;
use crate::report::svg::{
    Frame, PALETTE, Scale, Stroke, Svg, TickStyle, legend_entry, text, vertical_text,
};
use crate::report::{markdown_header, markdown_row, write_file};

impl Report<'_> {
    /// The fringe pictures of the toughness and friction sweeps: one PNG per run and time, in
    /// a table of runs against [`FRINGE_TIMES`].
    pub(super) fn fringes(&self, md: &mut String, sw: &Sweep) -> anyhow::Result<()> {
        if !matches!(
            sw.id.as_str(),
            "toughness" | "friction" | "toughness-fine" | "friction-fine"
        ) {
            return Ok(());
        }
        let _ = writeln!(
            md,
            "\nIsochromatic fringes (dark field, I ∝ sin²(πN), N = t(σ₁ − σ₂)/f_σ):\n"
        );
        let mut header = vec!["run".to_string()];
        header.extend(FRINGE_TIMES.iter().map(|t| format!("{:.0} µs", t * 1e6)));
        md.push_str(&markdown_header(&header));
        for v in &sw.runs {
            let Some(m) = self.get(sw, v) else { continue };
            let mut row = vec![(sw.legend)(v)];
            for t in FRINGE_TIMES {
                match m.fringes.iter().find(|s| (s.time - t).abs() < 0.25e-6) {
                    Some(s) => {
                        let name = format!(
                            "fringe-{}-v{}-j{}-mu{}-{:.0}us.png",
                            sw.id,
                            v.v,
                            v.j_ic,
                            v.mu,
                            t * 1e6
                        );
                        let png = fracture_results::render::render_png(s, "fringe")?;
                        write_file(self.figs, &name, &png)?;
                        row.push(format!("![](rosakis/{name})"));
                    }
                    None => row.push("–".into()),
                }
            }
            md.push_str(&markdown_row(&row));
        }
        Ok(())
    }
}

/// Font size (px) of a title centred on a figure `width` px wide: 14, or smaller (down to 9)
/// so that the title fits, at ~0.56 em per character of a sans-serif font.
fn title_size(title: &str, width: f64) -> u32 {
    let chars = title.chars().count().max(1) as f64;
    ((width - 16.0) / (0.56 * chars)).floor().clamp(9.0, 14.0) as u32
}

/// Speed against time, one line per run, with the wave speeds as dashed reference lines and
/// the legend to the right of the plot.
pub(super) fn speed_plot(
    title: &str,
    series: &[(String, Vec<[f64; 2]>)],
    s: &WaveSpeeds,
    t_end_us: f64,
) -> String {
    const W: f64 = 720.0;
    const H: f64 = 420.0;
    const L: f64 = 64.0;
    const R: f64 = 170.0;
    const T: f64 = 36.0;
    const B: f64 = 48.0;
    let vmax = 1.08 * s.c_l;
    let frame = Frame {
        left: L,
        top: T,
        width: W - L - R,
        height: H - T - B,
        x: Scale::linear(0.0, t_end_us).clamped(),
        y: Scale::linear(0.0, vmax).clamped(),
    };
    let mut svg = Svg::new(W, H, 12);
    svg.add(
        text(W / 2.0, 20.0, title)
            .middle()
            .size(title_size(title, W)),
    );
    svg.add(frame.axes("#333"));
    let mark = TickStyle::Mark {
        len: 5.0,
        colour: "#333",
    };
    frame.x_ticks(&mut svg, 10.0, mark, 18.0, |t| format!("{t:.0}"));
    frame.y_ticks(&mut svg, 500.0, mark, 8.0, |v| format!("{v:.0}"));
    svg.add(text((L + W - R) / 2.0, H - 10.0, "time after impact (µs)").middle());
    svg.add(vertical_text(
        16.0,
        (T + H - B) / 2.0,
        "crack-tip speed (m/s)",
    ));
    for (name, val, dy) in [
        ("c_R", s.c_r, 14.0),
        ("c_S", s.c_s, -4.0),
        ("√2·c_S", 2f64.sqrt() * s.c_s, -4.0),
        ("c_L", s.c_l, -4.0),
    ] {
        let label = format!("{name} {val:.0}");
        svg.add(frame.y_reference(val, Stroke::new("#999").dashed(), &label, dy));
    }
    for (i, (name, pts)) in series.iter().enumerate() {
        let c = PALETTE[i % PALETTE.len()];
        if let Some(curve) = frame.path(pts, Stroke::new(c).width(1.6)) {
            svg.add(curve);
        }
        let y = T + 14.0 + 18.0 * i as f64;
        svg.add(legend_entry(
            W - R + 10.0,
            y,
            Stroke::new(c).width(2.0),
            None,
            name,
        ));
    }
    svg.finish()
}

#[cfg(test)]
mod tests {
    use super::title_size;

    /// A short title keeps 14 px; a long one shrinks so its estimated width fits the figure,
    /// and none goes below 9 px.
    #[test]
    fn titles_fit_the_figure() {
        assert_eq!(title_size("Toughness", 720.0), 14);
        let long = "J domain radius on the reduced scene (J_Ic = 25 J/m², 0.5 mm cells, equation of motion, 30 µs)";
        let s = title_size(long, 720.0);
        assert!(
            s < 14 && 0.56 * f64::from(s) * long.chars().count() as f64 <= 704.0,
            "{s}"
        );
        assert_eq!(title_size(&"x".repeat(400), 720.0), 9);
    }
}
