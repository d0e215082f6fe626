//! The background grid: packed per-node data, the extra crack velocity field stored only at
//! the nodes that need it, and the strip-coloured parallel traversal.
//!
//! Layout: node (ix, iy) lives at storage index `(ix + PAD)·ny + iy` (x-major, so a strip of
//! columns is one contiguous slice). Particles are sorted by cell column and grouped in strips
//! of `STRIP` columns. A particle whose cell column lies within two columns of its strip
//! writes only to nodes in storage columns `[s·STRIP, s·STRIP + STRIP + 7)`; strips of the
//! same colour (parity) are `2·STRIP` apart, so their writes never overlap. The scatter runs
//! the even strips in parallel, then the odd strips: every node receives its contributions in
//! the same order whatever the number of threads, so results are bitwise reproducible.

use crate::particles::PartsMut;

/// Cell columns per strip.
pub const STRIP: usize = 8;
/// Ghost columns on the left of the storage so write ranges never start below zero.
pub const PAD: usize = 3;

/// Data of one velocity field at one node.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Node {
    /// Mass.
    pub m: f64,
    /// Momentum after extrapolation (and boundary conditions).
    pub p: [f64; 2],
    /// Force (internal + external, boundary-condition and contact corrected).
    pub f: [f64; 2],
    /// Momentum re-extrapolated from the updated particle velocities.
    pub q: [f64; 2],
    /// Mass-weighted particle displacement Σ S m (x − X), for crack contact.
    pub u: [f64; 2],
    /// Velocity of the current gather (p/m, then q/m), 0 on empty nodes: computed once per
    /// node so the particle loops never divide by a nodal mass.
    pub v: [f64; 2],
    /// Acceleration f/m after the force stage, 0 on empty nodes.
    pub a: [f64; 2],
}

/// Geometry of the grid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridGeom {
    /// Position of node (0, 0).
    pub origin: [f64; 2],
    /// Cell size h.
    pub h: f64,
    /// 1/h.
    pub inv_h: f64,
    /// Nodes in x.
    pub nx: usize,
    /// Nodes in y.
    pub ny: usize,
    /// Number of particle strips.
    pub strips: usize,
    /// Storage columns (≥ nx + 2·PAD, whole colour chunks).
    pub cols: usize,
}

impl GridGeom {
    /// Geometry for the box `[min, max]` with cell `h`.
    pub fn new(min: [f64; 2], max: [f64; 2], h: f64) -> Self {
        let nx = ((max[0] - min[0]) / h - 1e-9).ceil() as usize + 1;
        let ny = ((max[1] - min[1]) / h - 1e-9).ceil() as usize + 1;
        let strips = (nx - 1).div_ceil(STRIP).max(1);
        let cols = 2 * STRIP * (strips.div_ceil(2) + 1) + STRIP;
        GridGeom {
            origin: min,
            h,
            inv_h: 1.0 / h,
            nx,
            ny,
            strips,
            cols,
        }
    }
    /// Storage index of node (ix, iy).
    #[inline(always)]
    pub fn index(&self, ix: usize, iy: usize) -> usize {
        (ix + PAD) * self.ny + iy
    }
    /// Node (ix, iy) of a storage index.
    #[inline(always)]
    pub fn node_of(&self, index: usize) -> (usize, usize) {
        (index / self.ny - PAD, index % self.ny)
    }
    /// Position of node (ix, iy).
    #[inline(always)]
    pub fn node_pos(&self, ix: usize, iy: usize) -> [f64; 2] {
        [
            self.origin[0] + ix as f64 * self.h,
            self.origin[1] + iy as f64 * self.h,
        ]
    }
    /// Position in cell units ξ = (x − origin)/h.
    #[inline(always)]
    pub fn xi(&self, x: [f64; 2]) -> [f64; 2] {
        [
            (x[0] - self.origin[0]) * self.inv_h,
            (x[1] - self.origin[1]) * self.inv_h,
        ]
    }
    /// The cell whose four nodes all lie on the grid and contain x, as (column, row) and
    /// x's bilinear fractions (f_x, f_y) in it; None outside.
    pub fn cell_with_fractions(&self, x: [f64; 2]) -> Option<(usize, usize, f64, f64)> {
        let xi = self.xi(x);
        let (cx, cy) = (xi[0].floor(), xi[1].floor());
        if cx < 0.0 || cy < 0.0 || cx as usize + 1 >= self.nx || cy as usize + 1 >= self.ny {
            return None;
        }
        Some((cx as usize, cy as usize, xi[0] - cx, xi[1] - cy))
    }
    /// Cell (column, row) containing x (may be out of range).
    #[inline(always)]
    pub fn cell(&self, x: [f64; 2]) -> (i64, i64) {
        let xi = self.xi(x);
        (floor_i64(xi[0]), floor_i64(xi[1]))
    }
    /// Total storage length.
    pub fn storage_len(&self) -> usize {
        self.cols * self.ny
    }
}

pub use fracture_mpm::math::floor_i64;

/// Mutable view of a contiguous range of grid storage and of the field-1 nodes inside it.
pub struct GridMut<'a> {
    /// Field-0 nodes of storage indices `[base, base + nodes.len())`.
    pub nodes: &'a mut [Node],
    /// Storage index of `nodes[0]`.
    pub base: usize,
    /// Field-1 nodes whose storage index lies in the range, in storage order.
    pub f1: &'a mut [Node],
    /// Their storage indices (same length as `f1`).
    pub f1_index: &'a [u32],
    /// Slot number of `f1[0]` in the whole field-1 table.
    pub f1_base: usize,
}

impl<'a> GridMut<'a> {
    /// Split at storage index `at` (absolute).
    pub fn split_at(self, at: usize) -> (GridMut<'a>, GridMut<'a>) {
        let cut = at.clamp(self.base, self.base + self.nodes.len()) - self.base;
        let (n0, n1) = self.nodes.split_at_mut(cut);
        let k = self.f1_index.partition_point(|&i| (i as usize) < at);
        let (f0, f1) = self.f1.split_at_mut(k);
        let (i0, i1) = self.f1_index.split_at(k);
        (
            GridMut {
                nodes: n0,
                base: self.base,
                f1: f0,
                f1_index: i0,
                f1_base: self.f1_base,
            },
            GridMut {
                nodes: n1,
                base: self.base + cut,
                f1,
                f1_index: i1,
                f1_base: self.f1_base + k,
            },
        )
    }

    /// The node of field `field` at storage index `index` (which must be in range; field-1
    /// nodes are looked up through the dense slot map `slot_of`).
    #[inline(always)]
    pub fn node(&mut self, index: usize, field: u8, slot_of: &[u32]) -> &mut Node {
        if field == 0 {
            &mut self.nodes[index - self.base]
        } else {
            let slot = slot_of[index] as usize;
            &mut self.f1[slot - self.f1_base]
        }
    }
}

/// Visit the 3×3 stencil of a particle with weights `w`: `f(a, b, node)` for each pair, the
/// node taken from the pair's velocity field. Pairs all in field 0 (every pair of a scene
/// without cracks) take a fast path over contiguous column slices.
#[inline(always)]
pub fn visit_stencil(
    g: &mut GridMut<'_>,
    geom: &GridGeom,
    w: &crate::shape::Weights2,
    mask: u16,
    slot_of: &[u32],
    mut f: impl FnMut(usize, usize, &mut Node),
) {
    let by = w.y.base as usize;
    for a in 0..3 {
        if w.x.s[a] == 0.0 && w.x.ds[a] == 0.0 {
            continue;
        }
        let start = geom.index((w.x.base + a as i32) as usize, by);
        if mask & (0b111 << (3 * a)) == 0 {
            let s0 = start - g.base;
            let col = &mut g.nodes[s0..s0 + 3];
            for (b, n) in col.iter_mut().enumerate() {
                f(a, b, n);
            }
        } else {
            for b in 0..3 {
                let field = ((mask >> (3 * a + b)) & 1) as u8;
                f(a, b, g.node(start + b, field, slot_of));
            }
        }
    }
}

/// The three field-0 columns of a particle's 3×3 stencil as fixed-size arrays: column `a`
/// holds nodes (base_x + a, base_y … base_y + 2). One range check per column and none per
/// node, for the particles whose pairs are all in field 0. All three columns always lie in
/// the strip's write range (the stencil's base is at most two columns off the strip).
#[inline(always)]
pub fn field0_columns<'g>(
    g: &'g mut GridMut<'_>,
    geom: &GridGeom,
    w: &crate::shape::Weights2,
) -> [&'g mut [Node; 3]; 3] {
    let ny = geom.ny;
    let s0 = geom.index(w.x.base as usize, w.y.base as usize) - g.base;
    let (c0, rest) = g.nodes[s0..].split_at_mut(ny);
    let (c1, c2) = rest.split_at_mut(ny);
    [first3(c0), first3(c1), first3(c2)]
}

#[inline(always)]
fn first3(col: &mut [Node]) -> &mut [Node; 3] {
    col.first_chunk_mut::<3>()
        .expect("stencil column inside the strip's write range")
}

/// Grid storage that the strip traversal splits at storage indices: one grid, or two with
/// the same layout split together (the fused step's current grid, read, and the next step's
/// grid, written: `sim/transfer.rs`).
pub trait SplitGrid: Send + Sized {
    /// Split at storage index `at` (absolute).
    fn split_grid(self, at: usize) -> (Self, Self);
}

impl SplitGrid for GridMut<'_> {
    #[inline]
    fn split_grid(self, at: usize) -> (Self, Self) {
        self.split_at(at)
    }
}

impl SplitGrid for (GridMut<'_>, GridMut<'_>) {
    #[inline]
    fn split_grid(self, at: usize) -> (Self, Self) {
        let (a0, a1) = self.0.split_at(at);
        let (b0, b1) = self.1.split_at(at);
        ((a0, b0), (a1, b1))
    }
}

/// Something combined across strips in a fixed order (deterministic reductions).
pub trait Reduce: Default + Send {
    /// Combine the result of a left (earlier) range with a right (later) one.
    fn merge(self, right: Self) -> Self;
}

impl Reduce for () {
    fn merge(self, _: Self) -> Self {}
}

impl<A: Reduce, B: Reduce> Reduce for (A, B) {
    fn merge(self, r: Self) -> Self {
        (self.0.merge(r.0), self.1.merge(r.1))
    }
}

/// Run `f` on every strip of colour `colour` (0 even, 1 odd) in parallel, each with mutable
/// views of its particles and of the grid columns it may write. `bounds[s]..bounds[s+1]` is the
/// particle range of strip `s`. Results are merged in strip order.
pub fn for_strips<R, G, F>(
    geom: &GridGeom,
    bounds: &[usize],
    colour: usize,
    parts: PartsMut<'_>,
    grid: G,
    f: &F,
) -> R
where
    R: Reduce,
    G: SplitGrid,
    F: Fn(usize, PartsMut<'_>, G) -> R + Sync,
{
    let n = geom.strips.saturating_sub(colour).div_ceil(2);
    if n == 0 {
        return R::default();
    }
    // Drop the storage before this colour's first chunk.
    let (_, grid) = grid.split_grid(colour * STRIP * geom.ny);
    recurse(geom, bounds, colour, 0, n, parts, 0, grid, f)
}

#[allow(clippy::too_many_arguments)]
fn recurse<R, G, F>(
    geom: &GridGeom,
    bounds: &[usize],
    colour: usize,
    k0: usize,
    k1: usize,
    parts: PartsMut<'_>,
    pbase: usize,
    grid: G,
    f: &F,
) -> R
where
    R: Reduce,
    G: SplitGrid,
    F: Fn(usize, PartsMut<'_>, G) -> R + Sync,
{
    if k1 - k0 == 1 {
        let s = 2 * k0 + colour;
        let (_, rest) = parts.split_at(bounds[s] - pbase);
        let (mine, _) = rest.split_at(bounds[s + 1] - bounds[s]);
        let end = (colour * STRIP + 2 * (k0 + 1) * STRIP) * geom.ny;
        let (chunk, _) = grid.split_grid(end);
        return f(s, mine, chunk);
    }
    let mid = (k0 + k1) / 2;
    let pcut = bounds[2 * mid + colour] - pbase;
    let gcut = (colour * STRIP + 2 * mid * STRIP) * geom.ny;
    let (pl, pr) = parts.split_at(pcut);
    let (gl, gr) = grid.split_grid(gcut);
    let (a, b) = rayon::join(
        || recurse(geom, bounds, colour, k0, mid, pl, pbase, gl, f),
        || recurse(geom, bounds, colour, mid, k1, pr, pbase + pcut, gr, f),
    );
    a.merge(b)
}
