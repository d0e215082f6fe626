//! Field snapshots rendered as PNG images: a perceptual colour map (viridis for magnitudes,
//! a diverging map centred on zero for signed quantities, a dark-field isochromatic picture
//! `I ∝ sin²(πN)` for `fringe`), a colour scale bar with its range, and the cracks on top.

use fracture_api::results::Snapshot;
use fracture_api::scene::FieldKind;

/// Why a field could not be rendered.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The snapshot has no such component or field.
    #[error("the snapshot has no field or component named `{0}`")]
    UnknownField(String),
    /// PNG encoding failed.
    #[error("png encoding failed: {0}")]
    Encode(String),
}

/// The component a field kind renders by default.
pub fn default_component(kind: FieldKind) -> &'static str {
    match kind {
        FieldKind::Stress => "sxx",
        FieldKind::Strain => "exx",
        FieldKind::Velocity => "speed",
        FieldKind::Displacement => "ux",
        FieldKind::Fringe => "fringe",
        FieldKind::Material => "material",
    }
}

/// Resolve a URL field name (component or kind) to a component of the snapshot.
pub fn resolve<'a>(
    snap: &'a Snapshot,
    field: &str,
) -> Option<&'a fracture_api::results::FieldComponent> {
    snap.component(field).or_else(|| {
        FieldKind::from_name(field).and_then(|k| {
            snap.component(default_component(k)).or_else(|| {
                fracture_api::results::field_components(k)
                    .iter()
                    .find_map(|c| snap.component(c))
            })
        })
    })
}

#[derive(Clone, Copy, PartialEq)]
enum Map {
    Sequential,
    Diverging,
    Fringe,
    Categorical,
}

fn map_for(name: &str) -> Map {
    match name {
        "speed" | "von_mises" | "mises" | "magnitude" => Map::Sequential,
        "fringe" => Map::Fringe,
        "material" => Map::Categorical,
        _ => Map::Diverging,
    }
}

const EMPTY: [u8; 3] = [38, 38, 44];
const BG: [u8; 3] = [255, 255, 255];
const INK: [u8; 3] = [20, 20, 20];

struct Canvas {
    w: usize,
    h: usize,
    px: Vec<u8>,
}

impl Canvas {
    fn new(w: usize, h: usize) -> Canvas {
        let mut px = vec![0u8; w * h * 3];
        for p in px.chunks_exact_mut(3) {
            p.copy_from_slice(&BG);
        }
        Canvas { w, h, px }
    }
    fn set(&mut self, x: i64, y: i64, c: [u8; 3]) {
        if x >= 0 && y >= 0 && (x as usize) < self.w && (y as usize) < self.h {
            let i = (y as usize * self.w + x as usize) * 3;
            self.px[i..i + 3].copy_from_slice(&c);
        }
    }
    fn line(&mut self, (x0, y0): (f64, f64), (x1, y1): (f64, f64), c: [u8; 3], r: i64) {
        let n = ((x1 - x0).abs().max((y1 - y0).abs()).ceil() as usize).clamp(1, 100_000);
        for i in 0..=n {
            let t = i as f64 / n as f64;
            let x = (x0 + t * (x1 - x0)).round() as i64;
            let y = (y0 + t * (y1 - y0)).round() as i64;
            for dy in -r..=r {
                for dx in -r..=r {
                    self.set(x + dx, y + dy, c);
                }
            }
        }
    }
    fn text(&mut self, x: i64, y: i64, s: &str, scale: i64) {
        let mut cx = x;
        for ch in s.chars() {
            let g = glyph(ch);
            for (row, bits) in g.iter().enumerate() {
                for col in 0..3 {
                    if bits & (0b100 >> col) != 0 {
                        for sy in 0..scale {
                            for sx in 0..scale {
                                self.set(cx + col * scale + sx, y + row as i64 * scale + sy, INK);
                            }
                        }
                    }
                }
            }
            cx += 4 * scale;
        }
    }
}

/// A 3×5 pixel font for numbers.
fn glyph(c: char) -> [u8; 5] {
    match c {
        '0' => [0b111, 0b101, 0b101, 0b101, 0b111],
        '1' => [0b010, 0b110, 0b010, 0b010, 0b111],
        '2' => [0b111, 0b001, 0b111, 0b100, 0b111],
        '3' => [0b111, 0b001, 0b111, 0b001, 0b111],
        '4' => [0b101, 0b101, 0b111, 0b001, 0b001],
        '5' => [0b111, 0b100, 0b111, 0b001, 0b111],
        '6' => [0b111, 0b100, 0b111, 0b101, 0b111],
        '7' => [0b111, 0b001, 0b010, 0b010, 0b010],
        '8' => [0b111, 0b101, 0b111, 0b101, 0b111],
        '9' => [0b111, 0b101, 0b111, 0b001, 0b111],
        '.' => [0b000, 0b000, 0b000, 0b000, 0b010],
        '-' => [0b000, 0b000, 0b111, 0b000, 0b000],
        '+' => [0b000, 0b010, 0b111, 0b010, 0b000],
        'e' => [0b000, 0b111, 0b111, 0b100, 0b111],
        _ => [0; 5],
    }
}

fn colour(map: Map, t: f64) -> [u8; 3] {
    let t = t.clamp(0.0, 1.0);
    match map {
        Map::Sequential => colorous::VIRIDIS.eval_continuous(t).as_array(),
        Map::Diverging => colorous::RED_BLUE.eval_continuous(1.0 - t).as_array(),
        Map::Fringe => {
            let g = (255.0 * t).round() as u8;
            [g, g, g]
        }
        Map::Categorical => colorous::TABLEAU10[(t * 1000.0) as usize % 10].as_array(),
    }
}

/// Render one field of a snapshot as a PNG.
pub fn render_png(snap: &Snapshot, field: &str) -> Result<Vec<u8>, RenderError> {
    let comp = resolve(snap, field).ok_or_else(|| RenderError::UnknownField(field.to_string()))?;
    let map = map_for(&comp.name);
    let nx = snap.nx.max(1) as usize;
    let ny = snap.ny.max(1) as usize;
    let vals = &comp.values;
    let finite = vals.iter().copied().filter(|v| v.is_finite());
    let (mut lo, mut hi) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v as f64), b.max(v as f64))
    });
    if !lo.is_finite() {
        lo = 0.0;
        hi = 0.0;
    }
    match map {
        Map::Diverging => {
            let m = lo.abs().max(hi.abs());
            lo = -m;
            hi = m;
        }
        Map::Fringe => {
            lo = 0.0;
            hi = 1.0;
        }
        _ => {}
    }
    let span = if hi > lo { hi - lo } else { 1.0 };
    // Scale small grids up so the picture is readable; cap the size of large ones.
    let scale = (480 / nx.max(ny)).clamp(1, 16);
    let (pw, ph) = (nx * scale, ny * scale);
    let margin = 10usize;
    let bar_w = 16usize;
    let label_w = 70usize;
    let w = margin + pw + margin + bar_w + 6 + label_w;
    let h = (margin + ph + margin).max(90);
    let mut c = Canvas::new(w, h);
    for iy in 0..ny {
        for ix in 0..nx {
            let v = vals.get(iy * nx + ix).copied().unwrap_or(f32::NAN);
            let rgb = if !v.is_finite() {
                EMPTY
            } else {
                let v = v as f64;
                let t = match map {
                    Map::Fringe => (std::f64::consts::PI * v).sin().powi(2),
                    Map::Categorical => v,
                    _ => (v - lo) / span,
                };
                if map == Map::Categorical {
                    colorous::TABLEAU10[(v.max(0.0) as usize) % 10].as_array()
                } else {
                    colour(map, t)
                }
            };
            // Row 0 is the bottom of the body: flip so +y points up.
            let py0 = margin + (ny - 1 - iy) * scale;
            let px0 = margin + ix * scale;
            for dy in 0..scale {
                for dx in 0..scale {
                    c.set((px0 + dx) as i64, (py0 + dy) as i64, rgb);
                }
            }
        }
    }
    // Cracks: node (ix, iy) is at origin + (ix, iy)·h; its pixel is that node's square.
    let h_cell = if snap.cell_size > 0.0 {
        snap.cell_size
    } else {
        1.0
    };
    let to_px = |p: &[f64; 2]| {
        let fx = (p[0] - snap.origin[0]) / h_cell;
        let fy = (p[1] - snap.origin[1]) / h_cell;
        (
            margin as f64 + (fx + 0.5) * scale as f64,
            margin as f64 + (ny as f64 - 0.5 - fy) * scale as f64,
        )
    };
    let crack_colour = if map == Map::Fringe {
        [255, 200, 0]
    } else {
        [0, 0, 0]
    };
    for crack in &snap.cracks {
        for seg in crack.windows(2) {
            c.line(to_px(&seg[0]), to_px(&seg[1]), crack_colour, 1);
        }
    }
    // Scale bar with its range.
    let bx = margin + pw + margin;
    let bh = ph.max(60);
    for y in 0..bh {
        let t = 1.0 - y as f64 / (bh.max(2) - 1) as f64;
        let rgb = match map {
            Map::Fringe => colour(map, t),
            Map::Categorical => colorous::TABLEAU10[(t * 9.0).round() as usize % 10].as_array(),
            _ => colour(map, t),
        };
        for x in 0..bar_w {
            c.set((bx + x) as i64, (margin + y) as i64, rgb);
        }
    }
    let (top, bottom) = match map {
        Map::Fringe => ("1".to_string(), "0".to_string()),
        _ => (format!("{hi:.2e}"), format!("{lo:.2e}")),
    };
    let tx = (bx + bar_w + 6) as i64;
    c.text(tx, margin as i64, &top, 2);
    c.text(tx, (margin + bh) as i64 - 10, &bottom, 2);
    if map == Map::Diverging {
        c.text(tx, (margin + bh / 2) as i64 - 5, "0", 2);
    }
    encode(&c)
}

fn encode(c: &Canvas) -> Result<Vec<u8>, RenderError> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, c.w as u32, c.h as u32);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc
            .write_header()
            .map_err(|e| RenderError::Encode(e.to_string()))?;
        w.write_image_data(&c.px)
            .map_err(|e| RenderError::Encode(e.to_string()))?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use fracture_api::results::FieldComponent;

    #[test]
    fn renders_signed_and_fringe_fields() {
        let nx = 21;
        let ny = 11;
        let vals: Vec<f32> = (0..nx * ny)
            .map(|i| if i == 5 { f32::NAN } else { i as f32 - 100.0 })
            .collect();
        let snap = Snapshot {
            index: 0,
            time: 0.0,
            nx,
            ny,
            origin: [0.0, 0.0],
            cell_size: 0.001,
            fields: vec!["stress".into(), "fringe".into()],
            components: vec![
                FieldComponent {
                    name: "sxx".into(),
                    values: vals.clone(),
                },
                FieldComponent {
                    name: "fringe".into(),
                    values: vals.iter().map(|v| v.abs() / 50.0).collect(),
                },
            ],
            cracks: vec![vec![[0.0, 0.005], [0.01, 0.005]]],
        };
        for f in ["sxx", "stress", "fringe"] {
            let png = render_png(&snap, f).expect("renders");
            assert_eq!(&png[1..4], b"PNG");
        }
        assert!(matches!(
            render_png(&snap, "vx"),
            Err(RenderError::UnknownField(_))
        ));
    }
}
