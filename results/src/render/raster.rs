//! Nodal fields resampled to pixels: bilinear interpolation from the four nodes around each
//! pixel centre, with empty (NaN) nodes left out of the weights.
//!
//! A pixel takes the weighted mean of its valid corner nodes when their bilinear weights add
//! up to at least one half; otherwise it is background. So a pixel with no valid neighbouring
//! node is always background, a cell with all four nodes valid is plain bilinear
//! interpolation, and the edge of the material runs smoothly through partly filled cells
//! (the half-level of the interpolated occupancy) instead of stepping along node squares.

use fracture_api::results::Snapshot;

/// Bilinear weight a pixel's valid nodes must reach for the pixel to show material.
const MIN_WEIGHT: f64 = 0.5;

/// A field resampled onto the pixels of a picture.
#[derive(Debug, Clone, PartialEq)]
pub struct Raster {
    /// Pixels across.
    pub width: usize,
    /// Pixels down.
    pub height: usize,
    /// Values per pixel, row-major from the top-left pixel (+y of the body points up the
    /// picture); NaN where there is no material. For the `fringe` field this is the fringe
    /// order N, the picture's intensity is sin²(πN).
    pub values: Vec<f64>,
    origin: [f64; 2],
    cell: f64,
    /// Cells per pixel in x and y.
    step: [f64; 2],
    /// Node rows minus one: the y of the top row of nodes in cells.
    top: f64,
}

/// Where a raster's values come from.
pub(super) enum Source<'a> {
    /// One nodal component, bilinearly interpolated.
    Linear(&'a [f32]),
    /// One nodal component, value of the nearest valid node (categorical fields).
    Nearest(&'a [f32]),
    /// The fringe order from interpolated stresses: N = c·2·sqrt(((σxx − σyy)/2)² + σxy²).
    FringeFromStress {
        sxx: &'a [f32],
        syy: &'a [f32],
        sxy: &'a [f32],
        per_pa: f64,
    },
}

impl Raster {
    /// Resample `source` (nodal values of `snap`) onto `width × height` pixels spanning the
    /// nodes from the first to the last in each direction.
    pub(super) fn build(snap: &Snapshot, source: &Source, width: usize, height: usize) -> Raster {
        let nx = snap.nx.max(1) as usize;
        let ny = snap.ny.max(1) as usize;
        let cells = [(nx - 1).max(1) as f64, (ny - 1).max(1) as f64];
        let step = [cells[0] / width as f64, cells[1] / height as f64];
        let cell = if snap.cell_size > 0.0 {
            snap.cell_size
        } else {
            1.0
        };
        let mut r = Raster {
            width,
            height,
            values: vec![f64::NAN; width * height],
            origin: snap.origin,
            cell,
            step,
            top: (ny - 1) as f64,
        };
        for j in 0..height {
            for i in 0..width {
                let (fx, fy) = r.node_coords(i, j);
                let c = Corners::new(nx, ny, fx, fy);
                r.values[j * width + i] = match source {
                    Source::Linear(v) => c.linear(v),
                    Source::Nearest(v) => c.nearest(v),
                    Source::FringeFromStress {
                        sxx,
                        syy,
                        sxy,
                        per_pa,
                    } => {
                        let (a, b, s) = (c.linear(sxx), c.linear(syy), c.linear(sxy));
                        per_pa * 2.0 * (0.5 * (a - b)).hypot(s)
                    }
                };
            }
        }
        r
    }

    /// The value at pixel (i, j) (NaN: background).
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.values[j * self.width + i]
    }

    /// The body position (m) of the centre of pixel (i, j).
    pub fn position(&self, i: usize, j: usize) -> [f64; 2] {
        let (fx, fy) = self.node_coords(i, j);
        [
            self.origin[0] + fx * self.cell,
            self.origin[1] + fy * self.cell,
        ]
    }

    /// Continuous pixel coordinates (x right, y down; pixel (i, j) spans [i, i+1) × [j, j+1))
    /// of a body position (m).
    pub fn to_pixel(&self, p: [f64; 2]) -> (f64, f64) {
        let fx = (p[0] - self.origin[0]) / self.cell;
        let fy = (p[1] - self.origin[1]) / self.cell;
        (fx / self.step[0], (self.top - fy) / self.step[1])
    }

    /// Pixels per cell (node spacing) in x.
    pub fn px_per_cell(&self) -> f64 {
        1.0 / self.step[0]
    }

    /// Node coordinates (in cells from node (0, 0)) of the centre of pixel (i, j).
    fn node_coords(&self, i: usize, j: usize) -> (f64, f64) {
        (
            (i as f64 + 0.5) * self.step[0],
            self.top - (j as f64 + 0.5) * self.step[1],
        )
    }

    /// The largest change between horizontally or vertically adjacent material pixels, how
    /// many adjacent pairs change by more than `limit`, and the box (m: x0, y0, x1, y1)
    /// around those pairs.
    pub(super) fn max_step(&self, limit: f64) -> (f64, u64, Option<[f64; 4]>) {
        let mut max = 0.0f64;
        let mut over = 0u64;
        let mut bbox: Option<[f64; 4]> = None;
        for j in 0..self.height {
            for i in 0..self.width {
                let v = self.get(i, j);
                let right = (i + 1 < self.width).then(|| self.get(i + 1, j));
                let down = (j + 1 < self.height).then(|| self.get(i, j + 1));
                for d in [right, down].into_iter().flatten().map(|w| (v - w).abs()) {
                    if !d.is_finite() {
                        continue;
                    }
                    max = max.max(d);
                    if d > limit {
                        over += 1;
                        let [x, y] = self.position(i, j);
                        let b = bbox.get_or_insert([x, y, x, y]);
                        *b = [b[0].min(x), b[1].min(y), b[2].max(x), b[3].max(y)];
                    }
                }
            }
        }
        (max, over, bbox)
    }

    /// The smallest and largest finite values.
    pub(super) fn range(&self) -> Option<[f64; 2]> {
        let (lo, hi) = self
            .values
            .iter()
            .filter(|v| v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        lo.is_finite().then_some([lo, hi])
    }
}

/// The four nodes around a point and their bilinear weights.
struct Corners {
    idx: [usize; 4],
    w: [f64; 4],
}

impl Corners {
    fn new(nx: usize, ny: usize, fx: f64, fy: f64) -> Corners {
        let axis = |n: usize, f: f64| -> (usize, usize, f64) {
            if n < 2 {
                return (0, 0, 0.0);
            }
            let i0 = (f.floor().max(0.0) as usize).min(n - 2);
            (i0, i0 + 1, (f - i0 as f64).clamp(0.0, 1.0))
        };
        let (x0, x1, tx) = axis(nx, fx);
        let (y0, y1, ty) = axis(ny, fy);
        Corners {
            idx: [y0 * nx + x0, y0 * nx + x1, y1 * nx + x0, y1 * nx + x1],
            w: [
                (1.0 - tx) * (1.0 - ty),
                tx * (1.0 - ty),
                (1.0 - tx) * ty,
                tx * ty,
            ],
        }
    }

    fn linear(&self, v: &[f32]) -> f64 {
        let (mut sum, mut wsum) = (0.0, 0.0);
        for k in 0..4 {
            let x = v.get(self.idx[k]).copied().unwrap_or(f32::NAN);
            if x.is_finite() {
                sum += self.w[k] * x as f64;
                wsum += self.w[k];
            }
        }
        if wsum >= MIN_WEIGHT - 1e-12 {
            sum / wsum
        } else {
            f64::NAN
        }
    }

    fn nearest(&self, v: &[f32]) -> f64 {
        let (mut best, mut bw, mut wsum) = (f64::NAN, -1.0, 0.0);
        for k in 0..4 {
            let x = v.get(self.idx[k]).copied().unwrap_or(f32::NAN);
            if x.is_finite() {
                wsum += self.w[k];
                if self.w[k] > bw {
                    bw = self.w[k];
                    best = x as f64;
                }
            }
        }
        if wsum >= MIN_WEIGHT - 1e-12 {
            best
        } else {
            f64::NAN
        }
    }
}
