//! The legend of a field picture: the quantity and its unit with an SI prefix, the colour
//! bar and its ticks, the length scale bar, the title and the notes (sampling, aliasing).

use super::canvas::{Canvas, text_height, text_width};
use super::raster::Raster;
use super::{BAR_W, GAP, INK, MARGIN, Map, TEXT_SCALE, WARN, value_colour};
use fracture_api::results::Snapshot;

/// A quantity's name in the legend, its unit, and how values scale to it.
pub(super) struct Quantity {
    name: &'static str,
    unit: Unit,
    /// Raw component name, for components not known here.
    raw: String,
}

#[derive(Clone, Copy, PartialEq)]
enum Unit {
    Pascal,
    MetrePerSecond,
    Metre,
    Strain,
    Fringe,
    None,
}

impl Quantity {
    pub(super) fn of(name: &str) -> Quantity {
        let (n, unit) = match name {
            "sxx" => ("σ_xx", Unit::Pascal),
            "syy" => ("σ_yy", Unit::Pascal),
            "sxy" => ("σ_xy", Unit::Pascal),
            "szz" => ("σ_zz", Unit::Pascal),
            "von_mises" | "mises" => ("σ_vM", Unit::Pascal),
            "pressure" => ("p", Unit::Pascal),
            "exx" => ("ε_xx", Unit::Strain),
            "eyy" => ("ε_yy", Unit::Strain),
            "exy" => ("ε_xy", Unit::Strain),
            "vx" => ("v_x", Unit::MetrePerSecond),
            "vy" => ("v_y", Unit::MetrePerSecond),
            "speed" => ("|v|", Unit::MetrePerSecond),
            "ux" => ("u_x", Unit::Metre),
            "uy" => ("u_y", Unit::Metre),
            // 3D runs' slices
            "syz" => ("σ_yz", Unit::Pascal),
            "sxz" => ("σ_xz", Unit::Pascal),
            "ezz" => ("ε_zz", Unit::Strain),
            "eyz" => ("ε_yz", Unit::Strain),
            "exz" => ("ε_xz", Unit::Strain),
            "vz" => ("v_z", Unit::MetrePerSecond),
            "uz" => ("u_z", Unit::Metre),
            "fringe" => ("fringe order N", Unit::Fringe),
            "material" => ("material", Unit::None),
            _ => ("", Unit::None),
        };
        Quantity {
            name: n,
            unit,
            raw: name.replace('_', " "),
        }
    }

    /// The power of ten (a multiple of 3) values are shown in, for a colour range.
    fn exponent(&self, range: [f64; 2]) -> i32 {
        let m = range[0].abs().max(range[1].abs());
        let e = if m > 0.0 && m.is_finite() {
            (m.log10().floor() as i32).div_euclid(3) * 3
        } else {
            0
        };
        match self.unit {
            Unit::Pascal => e.clamp(-3, 9),
            Unit::MetrePerSecond | Unit::Metre => e.clamp(-9, 0),
            Unit::Strain => e.clamp(-9, 0),
            Unit::Fringe | Unit::None => 0,
        }
    }

    pub(super) fn label(&self, range: [f64; 2]) -> String {
        let e = self.exponent(range);
        let unit = match self.unit {
            Unit::Pascal => format!("{}Pa", prefix(e)),
            Unit::MetrePerSecond => format!("{}m/s", prefix(e)),
            Unit::Metre => format!("{}m", prefix(e)),
            Unit::Strain if e == 0 => "-".to_string(),
            Unit::Strain => format!("×1e{e}"),
            Unit::Fringe | Unit::None => String::new(),
        };
        let name = if self.name.is_empty() {
            self.raw.as_str()
        } else {
            self.name
        };
        if unit.is_empty() {
            name.to_string()
        } else {
            format!("{name} ({unit})")
        }
    }
}

fn prefix(e: i32) -> &'static str {
    match e {
        9 => "G",
        6 => "M",
        3 => "k",
        -3 => "m",
        -6 => "µ",
        -9 => "n",
        _ => "",
    }
}

/// A value with an SI prefix and unit, e.g. `10 mm`, `12.5 µs`.
fn si(v: f64, unit: &str) -> String {
    let e = if v != 0.0 && v.is_finite() {
        ((v.abs().log10().floor() as i32).div_euclid(3) * 3).clamp(-9, 0)
    } else {
        0
    };
    let x = v / 10f64.powi(e);
    format!("{} {}{unit}", trim_number(x, 3), prefix(e))
}

/// `x` with at most `sig` significant digits, trailing zeros dropped.
fn trim_number(x: f64, sig: i32) -> String {
    if x == 0.0 || !x.is_finite() {
        return "0".into();
    }
    let d = (sig - 1 - x.abs().log10().floor() as i32).clamp(0, 9) as usize;
    let s = format!("{x:.d$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Round step sizes 1, 2, 5 × 10^k giving about `target` steps over `span`.
pub(crate) fn nice_step(span: f64, target: f64) -> f64 {
    if span <= 0.0 || !span.is_finite() {
        return 1.0;
    }
    let raw = span / target;
    let p = 10f64.powf(raw.log10().floor());
    let m = raw / p;
    let n = if m < 1.5 {
        1.0
    } else if m < 3.5 {
        2.0
    } else if m < 7.5 {
        5.0
    } else {
        10.0
    };
    n * p
}

/// Ticks of the colour bar: (value in SI units, label).
fn ticks(map: Map, range: [f64; 2], q: &Quantity) -> Vec<(f64, String)> {
    let (lo, hi) = (range[0], range[1]);
    if map == Map::Categorical {
        let (a, b) = (lo.max(0.0).round() as i64, hi.max(0.0).round() as i64);
        let step = ((b - a) / 8 + 1).max(1);
        return (a..=b)
            .step_by(step as usize)
            .map(|k| (k as f64, k.to_string()))
            .collect();
    }
    let scale = 10f64.powi(q.exponent(range));
    let (dlo, dhi) = (lo / scale, hi / scale);
    let mut step = nice_step(dhi - dlo, 5.0);
    if map == Map::Fringe {
        step = step.max(1.0).round();
    }
    if dhi <= dlo {
        return vec![(lo, trim_number(dlo, 3))];
    }
    let decimals = (-step.log10().floor()).clamp(0.0, 9.0) as usize;
    let first = (dlo / step - 1e-9).ceil() as i64;
    let last = (dhi / step + 1e-9).floor() as i64;
    (first..=last)
        .map(|k| {
            let v = k as f64 * step;
            let mut s = format!("{v:.decimals$}");
            if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
                s.remove(0);
            }
            (v * scale, s)
        })
        .collect()
}

/// The notes under the picture: sampling, and the aliasing warning for fringes.
pub(super) fn notes(
    snap: &Snapshot,
    r: &Raster,
    max_step: Option<f64>,
    aliased: Option<[f64; 4]>,
) -> Vec<(String, bool)> {
    let mut out = vec![(
        format!(
            "{} px/cell, bilinear from {}x{} nodes, cell {}",
            trim_number(r.px_per_cell(), 3),
            snap.nx,
            snap.ny,
            si(snap.cell_size, "m")
        ),
        false,
    )];
    if let Some(m) = max_step {
        if let Some(b) = aliased {
            out.push((
                format!(
                    "WARNING: aliased, N changes {} fringes/px (>1) in x {}..{}, y {}..{}",
                    trim_number(m, 2),
                    si(b[0], "m"),
                    si(b[2], "m"),
                    si(b[1], "m"),
                    si(b[3], "m"),
                ),
                true,
            ));
        } else {
            out.push((
                format!(
                    "dark field I = sin²(πN), max {} fringe/px",
                    trim_number(m, 2)
                ),
                false,
            ));
        }
    }
    out
}

/// Where everything goes.
pub(super) struct Layout {
    pub w: usize,
    pub h: usize,
    pub plot: [u32; 4],
    bar: [i64; 4],
    tick_x: i64,
    notes_y: i64,
}

impl Layout {
    #[allow(clippy::too_many_arguments)]
    pub(super) fn new(
        r: &Raster,
        legend: bool,
        snap: &Snapshot,
        label: &str,
        map: Map,
        range: [f64; 2],
        q: &Quantity,
        notes: &[(String, bool)],
    ) -> Layout {
        let (pw, ph) = (r.width as i64, r.height as i64);
        if !legend {
            return Layout {
                w: r.width,
                h: r.height,
                plot: [0, 0, r.width as u32, r.height as u32],
                bar: [0; 4],
                tick_x: 0,
                notes_y: 0,
            };
        }
        let line = text_height(TEXT_SCALE) + 6;
        let title = title(snap, label);
        let tick_w = ticks(map, range, q)
            .iter()
            .map(|(_, s)| text_width(s, TEXT_SCALE))
            .max()
            .unwrap_or(0);
        let notes_w = notes
            .iter()
            .map(|(s, _)| text_width(s, TEXT_SCALE))
            .max()
            .unwrap_or(0);
        let py = MARGIN + line;
        let bar_h = ph.max(160);
        let bar = [MARGIN + pw + GAP, py, BAR_W, bar_h];
        let tick_x = bar[0] + BAR_W + 10;
        let content_w = (tick_x + tick_w).max(MARGIN + text_width(&title, TEXT_SCALE));
        let notes_y = py + bar_h.max(ph) + 10 + line; // one line for the length scale
        let w = (content_w.max(MARGIN + notes_w) + MARGIN) as usize;
        let h = (notes_y + notes.len().max(1) as i64 * line + MARGIN) as usize;
        Layout {
            w,
            h,
            plot: [MARGIN as u32, py as u32, pw as u32, ph as u32],
            bar,
            tick_x,
            notes_y,
        }
    }

    #[allow(clippy::too_many_arguments)]
    pub(super) fn draw(
        &self,
        c: &mut Canvas,
        label: &str,
        map: Map,
        range: [f64; 2],
        q: &Quantity,
        notes: &[(String, bool)],
        snap: &Snapshot,
        r: &Raster,
    ) {
        let line = text_height(TEXT_SCALE) + 6;
        c.text(MARGIN, MARGIN, &title(snap, label), TEXT_SCALE, INK);
        // Colour bar, value increasing upwards.
        let [bx, by, bw, bh] = self.bar;
        let at = |v: f64| -> f64 {
            let span = range[1] - range[0];
            if span > 0.0 {
                by as f64 + (bh - 1) as f64 * (1.0 - (v - range[0]) / span)
            } else {
                (by + bh / 2) as f64
            }
        };
        for y in 0..bh {
            let t = 1.0 - y as f64 / (bh - 1).max(1) as f64;
            let v = range[0] + t * (range[1] - range[0]);
            let rgb = match map {
                Map::Categorical => {
                    colorous::TABLEAU10[(v.max(0.0).round() as usize) % 10].as_array()
                }
                _ => value_colour(map, range, v),
            };
            c.rect(bx, by + y, bw, 1, rgb);
        }
        c.rect(bx - 1, by - 1, bw + 2, 1, INK);
        c.rect(bx - 1, by + bh, bw + 2, 1, INK);
        c.rect(bx - 1, by - 1, 1, bh + 2, INK);
        c.rect(bx + bw, by - 1, 1, bh + 2, INK);
        let th = 7 * TEXT_SCALE;
        for (v, s) in ticks(map, range, q) {
            let y = at(v).round() as i64;
            c.rect(bx + bw, y, 6, 1, INK);
            let ty = (y - th / 2).clamp(by - th / 2, by + bh - th / 2);
            c.text(self.tick_x, ty, &s, TEXT_SCALE, INK);
        }
        // Length scale bar under the field.
        let [px, py, pw, ph] = self.plot.map(|v| v as i64);
        let body_w = pw as f64 / r.px_per_cell() * snap.cell_size.max(f64::MIN_POSITIVE);
        let len = nice_step(body_w, 4.0);
        let len_px = (len / body_w * pw as f64).round() as i64;
        let sy = py + ph.max(bh) + 10;
        c.rect(px, sy + 4, len_px, 4, INK);
        c.rect(px, sy, 2, 12, INK);
        c.rect(px + len_px - 2, sy, 2, 12, INK);
        c.text(px + len_px + 8, sy, &si(len, "m"), TEXT_SCALE, INK);
        for (k, (s, warn)) in notes.iter().enumerate() {
            let col = if *warn { WARN } else { INK };
            c.text(MARGIN, self.notes_y + k as i64 * line, s, TEXT_SCALE, col);
        }
    }
}

/// The picture's title: the quantity, the time and the snapshot's index, and for a 3D run's
/// slice its plane (`z = 2 mm`: the picture's axes are the other two).
pub(super) fn title(snap: &Snapshot, label: &str) -> String {
    let plane = snap
        .slice
        .as_ref()
        .map(|s| format!("   {} = {}", s.normal, si(s.at, "m")))
        .unwrap_or_default();
    format!(
        "{label}   t = {}   #{}{plane}",
        si(snap.time, "s"),
        snap.index
    )
}
