//! Field snapshots rendered as PNG images that hold up at the resolution a reader looks at.
//!
//! * The nodal field is resampled to pixels finer than the grid ([`RenderOptions`]: pixels
//!   per cell or picture width; by default at least 4 pixels per cell), bilinearly from the
//!   four nodes around each pixel centre, empty (NaN) nodes left out ([`raster`]).
//! * Isochromatics: the fringe order N (or the stresses, with [`RenderOptions::fringe_per_pa`])
//!   is interpolated first and the dark-field intensity I = sin²(πN) taken per pixel after, so
//!   fringes are resolved between the nodes instead of aliasing into noise where N changes by
//!   more than half a fringe per cell. Where N still changes by more than one fringe per
//!   pixel, [`RenderReport::aliased`] is set and the legend says so.
//! * Colour maps: viridis for magnitudes, a diverging map centred on zero for signed
//!   quantities, categorical colours for `material` (nearest node, never interpolated).
//! * Legend: the quantity and its unit with an SI prefix chosen for the range (`σxx (MPa)`,
//!   `|v| (m/s)`, `fringe order N`), tick values on the colour bar, a length scale bar, the
//!   time, and the sampling; text in an embedded 5×7 font of our own, no font files.
//! * Cracks are drawn on top, light with a dark outline so they show on any map.
//!
//! (About 750 lines: the options, the report, the field lookup and the pixel loop are one
//! pipeline read top to bottom; the canvas, font, legend and raster parts are submodules.)

mod canvas;
mod font;
mod legend;
pub mod raster;

use canvas::{Canvas, plain};
use fracture_api::results::{FieldComponent, Snapshot};
use fracture_api::scene::FieldKind;
pub(crate) use legend::nice_step;
use legend::{Layout, Quantity, notes};
use raster::{Raster, Source};

/// Why a field could not be rendered.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The snapshot has no such component or field.
    #[error("the snapshot has no field or component named `{0}`")]
    UnknownField(String),
    /// The options ask for an impossible or too large picture.
    #[error("bad render options: {0}")]
    BadOptions(String),
    /// PNG encoding failed.
    #[error("png encoding failed: {0}")]
    Encode(String),
}

/// The most pixels the field area of one picture may have (about 6000 × 6000).
pub const MAX_PLOT_PIXELS: u64 = 36_000_000;
/// Pixels per cell when nothing is asked: at least this many, more for small grids.
pub const MIN_DEFAULT_PX_PER_CELL: f64 = 4.0;
/// A fringe order changing by more than this between adjacent pixels is aliased.
pub const ALIAS_FRINGES_PER_PIXEL: f64 = 1.0;

/// How to render a field picture. `Default` gives the automatic size (at least
/// [`MIN_DEFAULT_PX_PER_CELL`] pixels per cell, about 960 pixels on the long side for small
/// grids), the data range, cracks and the legend.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderOptions {
    /// Pixels per cell (node spacing), > 0. Takes precedence over `width`.
    pub px_per_cell: Option<f64>,
    /// Width of the field area in pixels (the legend comes on top), when `px_per_cell` is
    /// not given.
    pub width: Option<u32>,
    /// Fixed colour range in SI units (Pa, m/s, m, …) instead of the data range, e.g. to
    /// compare the snapshots of a series; for signed maps the larger magnitude is used
    /// symmetrically. Ignored for fringes and materials.
    pub range: Option<[f64; 2]>,
    /// Fringes per pascal of σ1 − σ2 (h/f_σ, thickness over the material fringe constant).
    /// When given and the snapshot holds `sxx`, `syy`, `sxy`, the fringe order is computed per
    /// pixel from the interpolated stresses; otherwise the nodal `fringe` order is
    /// interpolated.
    pub fringe_per_pa: Option<f64>,
    /// Draw the cracks.
    pub cracks: bool,
    /// Draw the legend (title, colour bar, length scale, notes); without it the PNG is the
    /// field area alone.
    pub legend: bool,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            px_per_cell: None,
            width: None,
            range: None,
            fringe_per_pa: None,
            cracks: true,
            legend: true,
        }
    }
}

/// What a render produced, besides the image.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderReport {
    /// The snapshot component rendered (`fringe`, `sxx`, …).
    pub component: String,
    /// Quantity and unit as in the legend, e.g. `σxx (MPa)`.
    pub label: String,
    /// Size of the whole PNG.
    pub width: u32,
    /// Size of the whole PNG.
    pub height: u32,
    /// The field area inside the PNG: x, y of its top-left pixel, width, height.
    pub plot: [u32; 4],
    /// Pixels per cell actually used.
    pub px_per_cell: f64,
    /// The colour range in SI units (fringes: [0, largest N]).
    pub range: [f64; 2],
    /// For fringe pictures: the largest change of N between adjacent pixels.
    pub max_fringes_per_pixel: Option<f64>,
    /// Adjacent pixel pairs whose fringe order differs by more than
    /// [`ALIAS_FRINGES_PER_PIXEL`].
    pub aliased_pairs: u64,
    /// The fringe order changes by more than one fringe per pixel somewhere: those fringes
    /// are not resolved (more pixels per cell, or a finer grid, would resolve them). Near a
    /// crack tip, where the grid's N jumps by many fringes per cell, this is expected; see
    /// `aliased_box` for where.
    pub aliased: bool,
    /// The box (m: x0, y0, x1, y1) around the aliased pixel pairs.
    pub aliased_box: Option<[f64; 4]>,
}

/// A rendered picture.
#[derive(Debug, Clone)]
pub struct Rendered {
    /// The PNG file.
    pub png: Vec<u8>,
    /// What was drawn.
    pub report: RenderReport,
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
pub fn resolve<'a>(snap: &'a Snapshot, field: &str) -> Option<&'a FieldComponent> {
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

/// Render one field of a snapshot as a PNG with the default options.
pub fn render_png(snap: &Snapshot, field: &str) -> Result<Vec<u8>, RenderError> {
    render_png_with(snap, field, &RenderOptions::default()).map(|r| r.png)
}

/// Render one field of a snapshot as a PNG, with its report.
pub fn render_png_with(
    snap: &Snapshot,
    field: &str,
    opts: &RenderOptions,
) -> Result<Rendered, RenderError> {
    let (name, raster) = rasterize(snap, field, opts)?;
    let map = map_for(&name);
    let q = Quantity::of(&name);
    let data_range = raster.range().unwrap_or([0.0, 0.0]);
    let range = match map {
        Map::Fringe => [0.0, data_range[1].max(0.0)],
        Map::Categorical => data_range,
        Map::Diverging => {
            let [lo, hi] = opts.range.unwrap_or(data_range);
            let m = lo.abs().max(hi.abs());
            [-m, m]
        }
        Map::Sequential => opts.range.unwrap_or(data_range),
    };
    let (max_step, aliased_pairs, aliased_box) = if map == Map::Fringe {
        let (m, n, b) = raster.max_step(ALIAS_FRINGES_PER_PIXEL);
        (Some(m), n, b)
    } else {
        (None, 0, None)
    };
    let aliased = aliased_pairs > 0;
    let label = q.label(range);
    let notes = notes(snap, &raster, max_step, aliased_box);
    let layout = Layout::new(&raster, opts.legend, snap, &label, map, range, &q, &notes);
    let mut c = Canvas::new(layout.w, layout.h, BG);
    let (x0, y0) = (layout.plot[0] as i64, layout.plot[1] as i64);
    paint_field(&mut c, &raster, map, range, (x0, y0));
    if opts.cracks {
        draw_cracks(&mut c, snap, &raster, map, (x0, y0));
    }
    if opts.legend {
        layout.draw(&mut c, &label, map, range, &q, &notes, snap, &raster);
    }
    let report = RenderReport {
        component: name,
        label: plain(&label),
        width: layout.w as u32,
        height: layout.h as u32,
        plot: layout.plot,
        px_per_cell: raster.px_per_cell(),
        range,
        max_fringes_per_pixel: max_step,
        aliased_pairs,
        aliased,
        aliased_box,
    };
    Ok(Rendered {
        png: encode(&c)?,
        report,
    })
}

/// Resample a field of a snapshot to the pixels of its picture (without drawing): the
/// component rendered and its per-pixel values (for `fringe`: the fringe order N).
pub fn rasterize(
    snap: &Snapshot,
    field: &str,
    opts: &RenderOptions,
) -> Result<(String, Raster), RenderError> {
    let stresses = (
        snap.component("sxx"),
        snap.component("syy"),
        snap.component("sxy"),
    );
    let wants_fringe = field == "fringe" || FieldKind::from_name(field) == Some(FieldKind::Fringe);
    let (name, source) = match (wants_fringe, opts.fringe_per_pa, stresses) {
        (true, Some(per_pa), (Some(a), Some(b), Some(s))) => {
            if !(per_pa.is_finite() && per_pa > 0.0) {
                return Err(RenderError::BadOptions(format!(
                    "fringe_per_pa must be a positive number, not {per_pa}"
                )));
            }
            (
                "fringe".to_string(),
                Source::FringeFromStress {
                    sxx: &a.values,
                    syy: &b.values,
                    sxy: &s.values,
                    per_pa,
                },
            )
        }
        _ => {
            let comp =
                resolve(snap, field).ok_or_else(|| RenderError::UnknownField(field.to_string()))?;
            let src = if map_for(&comp.name) == Map::Categorical {
                Source::Nearest(&comp.values)
            } else {
                Source::Linear(&comp.values)
            };
            (comp.name.clone(), src)
        }
    };
    let (w, h) = plot_size(snap, opts)?;
    Ok((name, Raster::build(snap, &source, w, h)))
}

/// The field area's size in pixels for these options.
fn plot_size(snap: &Snapshot, opts: &RenderOptions) -> Result<(usize, usize), RenderError> {
    let cx = (snap.nx.max(2) - 1) as f64;
    let cy = (snap.ny.max(2) - 1) as f64;
    let ppc = match (opts.px_per_cell, opts.width) {
        (Some(p), _) => {
            if !(p.is_finite() && p > 0.0) {
                return Err(RenderError::BadOptions(format!(
                    "px_per_cell must be a positive number, not {p}"
                )));
            }
            p
        }
        (None, Some(w)) => {
            if w == 0 {
                return Err(RenderError::BadOptions("width must be at least 1".into()));
            }
            w as f64 / cx
        }
        (None, None) => {
            // Small grids get ~960 px on the long side, large ones 4 px per cell, all
            // within the pixel budget.
            let auto = (960.0 / cx.max(cy))
                .ceil()
                .clamp(MIN_DEFAULT_PX_PER_CELL, 32.0);
            auto.min((MAX_PLOT_PIXELS as f64 / (cx * cy)).sqrt())
        }
    };
    let w = (cx * ppc).round().max(1.0);
    let h = (cy * ppc).round().max(1.0);
    if w * h > MAX_PLOT_PIXELS as f64 {
        return Err(RenderError::BadOptions(format!(
            "{w} × {h} pixels is more than the {MAX_PLOT_PIXELS} allowed; ask for fewer pixels \
             per cell"
        )));
    }
    Ok((w as usize, h as usize))
}

#[derive(Clone, Copy, PartialEq, Debug)]
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

const BG: [u8; 3] = [255, 255, 255];
const INK: [u8; 3] = [20, 20, 20];
const WARN: [u8; 3] = [200, 0, 0];
/// No material: a light checkerboard, unlike any colour of the maps (black..white included).
const EMPTY: [[u8; 3]; 2] = [[205, 205, 210], [232, 232, 236]];
const CRACK_CORE: [[u8; 3]; 2] = [[255, 170, 0], [255, 255, 255]];
const CRACK_EDGE: [u8; 3] = [0, 0, 0];
const TEXT_SCALE: i64 = 2;
const MARGIN: i64 = 12;
const BAR_W: i64 = 18;
const GAP: i64 = 14;

fn colour(map: Map, t: f64) -> [u8; 3] {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
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

/// The colour of a value: dark-field intensity for fringe orders, position in the range
/// otherwise.
fn value_colour(map: Map, range: [f64; 2], v: f64) -> [u8; 3] {
    match map {
        Map::Fringe => colour(map, (std::f64::consts::PI * v).sin().powi(2)),
        Map::Categorical => colorous::TABLEAU10[(v.max(0.0) as usize) % 10].as_array(),
        _ => {
            let span = range[1] - range[0];
            let t = if span > 0.0 {
                (v - range[0]) / span
            } else {
                0.5
            };
            colour(map, t)
        }
    }
}

fn paint_field(c: &mut Canvas, r: &Raster, map: Map, range: [f64; 2], (x0, y0): (i64, i64)) {
    for j in 0..r.height {
        for i in 0..r.width {
            let v = r.get(i, j);
            let rgb = if v.is_finite() {
                value_colour(map, range, v)
            } else {
                EMPTY[((i / 8) + (j / 8)) % 2]
            };
            c.set(x0 + i as i64, y0 + j as i64, rgb);
        }
    }
}

fn draw_cracks(c: &mut Canvas, snap: &Snapshot, r: &Raster, map: Map, (x0, y0): (i64, i64)) {
    let to_px = |p: &[f64; 2]| {
        let (x, y) = r.to_pixel(*p);
        (x0 as f64 + x, y0 as f64 + y)
    };
    let width = (r.px_per_cell() / 6.0).round().clamp(1.0, 3.0) as i64;
    let core = CRACK_CORE[usize::from(map != Map::Fringe)];
    for pass in 0..2 {
        for crack in &snap.cracks {
            for seg in crack.windows(2) {
                let (a, b) = (to_px(&seg[0]), to_px(&seg[1]));
                if pass == 0 {
                    c.line(a, b, CRACK_EDGE, width + 1);
                } else {
                    c.line(a, b, core, width);
                }
            }
        }
    }
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
mod tests;
