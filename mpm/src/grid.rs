//! The background grid of any dimension: geometry, packed nodes, and the strip-coloured
//! parallel traversal (the 2D solver's scheme, with a "column" now an x-plane of nodes).
//!
//! Layout: node (ix, iy[, iz]) lives at storage index `(ix + PAD)·stride + iy·nz + iz`
//! (x-major; `stride` = the nodes of one x-plane), so a strip of x-planes is one contiguous
//! slice. Particles are sorted by cell (x, then y, then z) and grouped in strips of `STRIP`
//! cell planes. A particle whose cell plane lies within two planes of its strip writes only
//! to storage planes `[s·STRIP, s·STRIP + STRIP + 7)`; strips of the same colour (parity) are
//! `2·STRIP` apart, so their writes never overlap. The scatter runs the even strips in
//! parallel, then the odd strips: every node receives its contributions in the same order
//! whatever the number of threads, so results are bitwise reproducible.

use crate::dim::{Dim, Dim2};
use crate::math::floor_i64;

/// Cell planes per strip.
pub const STRIP: usize = 8;
/// Ghost planes before the storage's first x-plane so write ranges never start below zero.
pub const PAD: usize = 3;

/// Data of one velocity field at one node.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Node<D: Dim> {
    /// Mass.
    pub m: f64,
    /// Momentum after extrapolation (and boundary conditions).
    pub p: D::V,
    /// Force (internal + external, boundary-condition corrected).
    pub f: D::V,
    /// Momentum re-extrapolated from the updated particle velocities.
    pub q: D::V,
    /// Mass-weighted particle displacement Σ S m (x − X), for crack contact (zero where no
    /// crack needs it).
    pub u: D::V,
    /// Velocity of the current gather (p/m, then q/m), 0 on empty nodes.
    pub v: D::V,
    /// Acceleration f/m after the force stage, 0 on empty nodes.
    pub a: D::V,
}

/// Geometry of the grid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridGeom<D: Dim> {
    /// Position of node 0.
    pub origin: D::V,
    /// Cell size h.
    pub h: f64,
    /// 1/h.
    pub inv_h: f64,
    /// Nodes per direction.
    pub n: D::U,
    /// Storage strides per direction (x: the nodes of one x-plane; last: 1).
    pub strides: D::U,
    /// Number of particle strips.
    pub strips: usize,
    /// Storage x-planes (≥ nx + 2·PAD, whole colour chunks).
    pub cols: usize,
}

impl<D: Dim> GridGeom<D> {
    /// Geometry for the box `[min, max]` with cell `h`.
    pub fn new(min: D::V, max: D::V, h: f64) -> Self {
        let mut n = D::U::default();
        for k in 0..D::N {
            n.as_mut()[k] = ((max.as_ref()[k] - min.as_ref()[k]) / h - 1e-9).ceil() as usize + 1;
        }
        let mut strides = D::U::default();
        let mut s = 1;
        for k in (0..D::N).rev() {
            strides.as_mut()[k] = s;
            s *= n.as_ref()[k];
        }
        let nx = n.as_ref()[0];
        let strips = (nx - 1).div_ceil(STRIP).max(1);
        let cols = 2 * STRIP * (strips.div_ceil(2) + 1) + STRIP;
        GridGeom {
            origin: min,
            h,
            inv_h: 1.0 / h,
            n,
            strides,
            strips,
            cols,
        }
    }
    /// Nodes of one x-plane.
    #[inline(always)]
    pub fn plane(&self) -> usize {
        self.strides.as_ref()[0]
    }
    /// Storage index of node `i`.
    #[inline(always)]
    pub fn index(&self, i: &D::U) -> usize {
        let mut k = PAD * self.plane();
        for d in 0..D::N {
            k += i.as_ref()[d] * self.strides.as_ref()[d];
        }
        k
    }
    /// Storage index of the first node of a stencil whose bases are `base` (≥ 0).
    #[inline(always)]
    pub fn index_i32(&self, base: impl Fn(usize) -> i32) -> usize {
        let mut k = PAD * self.plane();
        for d in 0..D::N {
            k += base(d) as usize * self.strides.as_ref()[d];
        }
        k
    }
    /// Node of a storage index.
    pub fn node_of(&self, index: usize) -> D::U {
        let mut i = D::U::default();
        let mut r = index - PAD * self.plane();
        for d in 0..D::N {
            let s = self.strides.as_ref()[d];
            i.as_mut()[d] = r / s;
            r %= s;
        }
        i
    }
    /// Position of node `i`.
    #[inline(always)]
    pub fn node_pos(&self, i: &D::U) -> D::V {
        let mut p = D::V::default();
        for d in 0..D::N {
            p.as_mut()[d] = self.origin.as_ref()[d] + i.as_ref()[d] as f64 * self.h;
        }
        p
    }
    /// Position in cell units ξ = (x − origin)/h.
    #[inline(always)]
    pub fn xi(&self, x: &D::V) -> D::V {
        let mut xi = D::V::default();
        for d in 0..D::N {
            xi.as_mut()[d] = (x.as_ref()[d] - self.origin.as_ref()[d]) * self.inv_h;
        }
        xi
    }
    /// Cell containing x per direction (may be out of range).
    #[inline(always)]
    pub fn cell(&self, x: &D::V) -> [i64; 3] {
        let xi = self.xi(x);
        let mut c = [0i64; 3];
        for d in 0..D::N {
            c[d] = floor_i64(xi.as_ref()[d]);
        }
        c
    }
    /// Total storage length.
    pub fn storage_len(&self) -> usize {
        self.cols * self.plane()
    }
    /// Number of grid nodes.
    pub fn node_count(&self) -> usize {
        self.n.as_ref().iter().product()
    }
}

/// The 2D grid's node-pair accessors (the crack layer of the 2D solver addresses nodes as
/// (column, row)).
impl GridGeom<Dim2> {
    /// Nodes in x.
    #[inline(always)]
    pub fn nx(&self) -> usize {
        self.n[0]
    }
    /// Nodes in y.
    #[inline(always)]
    pub fn ny(&self) -> usize {
        self.n[1]
    }
    /// Storage index of node (ix, iy): `(ix + PAD)·ny + iy`.
    #[inline(always)]
    pub fn at(&self, ix: usize, iy: usize) -> usize {
        (ix + PAD) * self.n[1] + iy
    }
    /// Node (ix, iy) of a storage index.
    #[inline(always)]
    pub fn node_xy(&self, index: usize) -> (usize, usize) {
        (index / self.n[1] - PAD, index % self.n[1])
    }
    /// Position of node (ix, iy).
    #[inline(always)]
    pub fn pos(&self, ix: usize, iy: usize) -> [f64; 2] {
        [
            self.origin[0] + ix as f64 * self.h,
            self.origin[1] + iy as f64 * self.h,
        ]
    }
    /// Cell (column, row) containing x (may be out of range).
    #[inline(always)]
    pub fn cell_xy(&self, x: [f64; 2]) -> (i64, i64) {
        let xi = self.xi(&x);
        (floor_i64(xi[0]), floor_i64(xi[1]))
    }
    /// The cell whose four nodes all lie on the grid and contain x, as (column, row) and
    /// x's bilinear fractions (f_x, f_y) in it; None outside.
    pub fn cell_with_fractions(&self, x: [f64; 2]) -> Option<(usize, usize, f64, f64)> {
        let xi = self.xi(&x);
        let (cx, cy) = (xi[0].floor(), xi[1].floor());
        if cx < 0.0 || cy < 0.0 || cx as usize + 1 >= self.n[0] || cy as usize + 1 >= self.n[1] {
            return None;
        }
        Some((cx as usize, cy as usize, xi[0] - cx, xi[1] - cy))
    }
}

/// Mutable view of a contiguous range of grid storage and of the extra-field nodes inside it
/// (the second velocity field at nodes a crack cuts; empty without cracks).
pub struct GridMut<'a, D: Dim> {
    /// Field-0 nodes of storage indices `[base, base + nodes.len())`.
    pub nodes: &'a mut [Node<D>],
    /// Storage index of `nodes[0]`.
    pub base: usize,
    /// Field-1 nodes whose storage index lies in the range, in storage order.
    pub f1: &'a mut [Node<D>],
    /// Their storage indices (same length as `f1`).
    pub f1_index: &'a [u32],
    /// Slot number of `f1[0]` in the whole field-1 table.
    pub f1_base: usize,
}

impl<'a, D: Dim> GridMut<'a, D> {
    /// A view of the whole storage `nodes` with no field-1 nodes.
    pub fn single(nodes: &'a mut [Node<D>]) -> Self {
        GridMut {
            nodes,
            base: 0,
            f1: &mut [],
            f1_index: &[],
            f1_base: 0,
        }
    }

    /// Split at storage index `at` (absolute).
    pub fn split_at(self, at: usize) -> (GridMut<'a, D>, GridMut<'a, D>) {
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
    pub fn node(&mut self, index: usize, field: u8, slot_of: &[u32]) -> &mut Node<D> {
        if field == 0 {
            &mut self.nodes[index - self.base]
        } else {
            let slot = slot_of[index] as usize;
            &mut self.f1[slot - self.f1_base]
        }
    }
}

/// Grid storage that the strip traversal splits at storage indices: one grid, or two of the
/// same layout split together (the fused last pass reads the current grid and scatters the
/// next step's P2G into the spare one).
pub trait SplitGrid: Send + Sized {
    /// Split at storage index `at` (absolute).
    fn split_grid(self, at: usize) -> (Self, Self);
}

impl<D: Dim> SplitGrid for GridMut<'_, D> {
    fn split_grid(self, at: usize) -> (Self, Self) {
        self.split_at(at)
    }
}

impl<D: Dim> SplitGrid for (GridMut<'_, D>, GridMut<'_, D>) {
    fn split_grid(self, at: usize) -> (Self, Self) {
        let (a0, a1) = self.0.split_at(at);
        let (b0, b1) = self.1.split_at(at);
        ((a0, b0), (a1, b1))
    }
}

impl Reduce for () {
    fn merge(self, _: Self) -> Self {}
}

impl<A: Reduce, B: Reduce> Reduce for (A, B) {
    fn merge(self, r: Self) -> Self {
        (self.0.merge(r.0), self.1.merge(r.1))
    }
}

/// Something combined across strips in a fixed order (deterministic reductions).
pub trait Reduce: Default + Send {
    /// Combine the result of a left (earlier) range with a right (later) one.
    fn merge(self, right: Self) -> Self;
}

/// A particle range that the strip traversal splits (the particle arrays of a pass).
pub trait SplitParts: Send + Sized {
    /// Split at particle `i` (relative to the view).
    fn split_at(self, i: usize) -> (Self, Self);
}

/// Run `f` on every strip of colour `colour` (0 even, 1 odd) in parallel, each with mutable
/// views of its particles and of the grid planes it may write. `bounds[s]..bounds[s+1]` is
/// the particle range of strip `s`. Results are merged in strip order (the same binary tree
/// as the 2D solver's, so sums are bitwise the same).
pub fn for_strips<D, P, G, R, F>(
    geom: &GridGeom<D>,
    bounds: &[usize],
    colour: usize,
    parts: P,
    grid: G,
    f: &F,
) -> R
where
    D: Dim,
    P: SplitParts,
    G: SplitGrid,
    R: Reduce,
    F: Fn(usize, P, G) -> R + Sync,
{
    let n = geom.strips.saturating_sub(colour).div_ceil(2);
    if n == 0 {
        return R::default();
    }
    let (_, grid) = grid.split_grid(colour * STRIP * geom.plane());
    recurse(geom, bounds, colour, 0, n, parts, 0, grid, f)
}

#[allow(clippy::too_many_arguments)]
fn recurse<D, P, G, R, F>(
    geom: &GridGeom<D>,
    bounds: &[usize],
    colour: usize,
    k0: usize,
    k1: usize,
    parts: P,
    pbase: usize,
    grid: G,
    f: &F,
) -> R
where
    D: Dim,
    P: SplitParts,
    G: SplitGrid,
    R: Reduce,
    F: Fn(usize, P, G) -> R + Sync,
{
    let plane = geom.plane();
    if k1 - k0 == 1 {
        let s = 2 * k0 + colour;
        let (_, rest) = parts.split_at(bounds[s] - pbase);
        let (mine, _) = rest.split_at(bounds[s + 1] - bounds[s]);
        let end = (colour * STRIP + 2 * (k0 + 1) * STRIP) * plane;
        let (chunk, _) = grid.split_grid(end);
        return f(s, mine, chunk);
    }
    let mid = (k0 + k1) / 2;
    let pcut = bounds[2 * mid + colour] - pbase;
    let gcut = (colour * STRIP + 2 * mid * STRIP) * plane;
    let (pl, pr) = parts.split_at(pcut);
    let (gl, gr) = grid.split_grid(gcut);
    let (a, b) = rayon::join(
        || recurse(geom, bounds, colour, k0, mid, pl, pbase, gl, f),
        || recurse(geom, bounds, colour, mid, k1, pr, pbase + pcut, gr, f),
    );
    a.merge(b)
}
