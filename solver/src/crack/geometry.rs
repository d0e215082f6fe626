//! Crack geometry (`algorithm.md` §3): vector helpers, the orientation (side) test with its
//! tie rule, the segment crossing test, segment normals, and the broad phase that registers
//! each crack segment in the cells near it.

use crate::grid::GridGeom;

use super::Cracks;

#[inline(always)]
pub(super) fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}
#[inline(always)]
pub(super) fn norm(a: [f64; 2]) -> f64 {
    a[0].hypot(a[1])
}
#[inline(always)]
pub(super) fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    norm(sub(a, b))
}
/// Orientation of c relative to the directed line a → b: ≥ 0 counts as left (tie rule).
#[inline(always)]
pub(super) fn left(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> bool {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) >= 0.0
}

/// [`left`] with the direction d = b − a computed once (`sub(b, a)`): the same operations on
/// the same values, so the same answer to the bit.
#[inline(always)]
pub(super) fn left_d(a: [f64; 2], d: [f64; 2], c: [f64; 2]) -> bool {
    d[0] * (c[1] - a[1]) - d[1] * (c[0] - a[0]) >= 0.0
}

/// Whether segment p → q crosses crack segment a → b (tie rule: on-line counts as left).
#[inline(always)]
pub fn crosses(p: [f64; 2], q: [f64; 2], a: [f64; 2], b: [f64; 2]) -> bool {
    left(a, b, p) != left(a, b, q) && left(p, q, a) != left(p, q, b)
}

/// Parameter t ∈ [0, 1] along p → q where it meets the line a → b.
pub(super) fn cross_param(p: [f64; 2], q: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let r = sub(q, p);
    let s = sub(b, a);
    let den = r[0] * s[1] - r[1] * s[0];
    if den.abs() < 1e-300 {
        return 0.5;
    }
    let ap = sub(a, p);
    ((ap[0] * s[1] - ap[1] * s[0]) / den).clamp(0.0, 1.0)
}

/// Unit normal of a → b pointing from above (left) to below (right).
pub(super) fn seg_normal(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    let d = sub(b, a);
    let l = norm(d).max(1e-300);
    [d[1] / l, -d[0] / l]
}

impl Cracks {
    /// Rebuild the per-cell segment lists (segments' boxes grown by 3h). Returns the box of
    /// the cells holding a segment in cell units, `[ξx_lo, ξx_hi, ξy_lo, ξy_hi]` (a point
    /// outside `[lo, hi)` has no segment near it: [`segs_near`](Cracks::segs_near) returns
    /// none), or None when no cell holds one.
    pub(super) fn build_broad_phase(&mut self, geom: &GridGeom) -> Option<[f64; 4]> {
        let (ncx, ncy) = (self.ncx, self.ncy);
        self.cell_start.clear();
        self.cell_start.resize(ncx * ncy + 1, 0);
        let margin = 3.0 * self.h;
        let cells_of = |a: [f64; 2], b: [f64; 2]| {
            let lo = geom.xi(&[a[0].min(b[0]) - margin, a[1].min(b[1]) - margin]);
            let hi = geom.xi(&[a[0].max(b[0]) + margin, a[1].max(b[1]) + margin]);
            let cx0 = (lo[0].floor().max(0.0) as usize).min(ncx - 1);
            let cx1 = (hi[0].floor().max(0.0) as usize).min(ncx - 1);
            let cy0 = (lo[1].floor().max(0.0) as usize).min(ncy - 1);
            let cy1 = (hi[1].floor().max(0.0) as usize).min(ncy - 1);
            (cx0, cx1, cy0, cy1)
        };
        for c in &self.cracks {
            for w in c.pts.windows(2) {
                let (x0, x1, y0, y1) = cells_of(w[0].x, w[1].x);
                for cx in x0..=x1 {
                    for cy in y0..=y1 {
                        self.cell_start[cx * ncy + cy + 1] += 1;
                    }
                }
            }
        }
        for i in 0..ncx * ncy {
            self.cell_start[i + 1] += self.cell_start[i];
        }
        let total = self.cell_start[ncx * ncy] as usize;
        self.cell_segs.clear();
        self.cell_segs.resize(total, (0, 0));
        let mut fill = self.cell_start.clone();
        let mut bx: Option<[usize; 4]> = None;
        for (ci, c) in self.cracks.iter().enumerate() {
            for (si, w) in c.pts.windows(2).enumerate() {
                let (x0, x1, y0, y1) = cells_of(w[0].x, w[1].x);
                bx = Some(match bx {
                    None => [x0, x1, y0, y1],
                    Some(b) => [b[0].min(x0), b[1].max(x1), b[2].min(y0), b[3].max(y1)],
                });
                for cx in x0..=x1 {
                    for cy in y0..=y1 {
                        let k = &mut fill[cx * ncy + cy];
                        self.cell_segs[*k as usize] = (ci as u32, si as u32);
                        *k += 1;
                    }
                }
            }
        }
        // Cell c holds the points with floor(ξ) = c, ξ ∈ [c, c + 1).
        bx.map(|b| [b[0], b[1] + 1, b[2], b[3] + 1].map(|c| c as f64))
    }

    /// Segments registered in the cell containing `x`.
    pub(super) fn segs_near(&self, geom: &GridGeom, x: [f64; 2]) -> &[(u32, u32)] {
        let (cx, cy) = geom.cell_xy(x);
        if cx < 0 || cy < 0 || cx as usize >= self.ncx || cy as usize >= self.ncy {
            return &[];
        }
        let c = cx as usize * self.ncy + cy as usize;
        &self.cell_segs[self.cell_start[c] as usize..self.cell_start[c + 1] as usize]
    }
}
