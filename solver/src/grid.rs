//! The background grid of the 2D solver: the core's grid (`fracture_mpm::grid`: packed
//! per-node data, the extra crack velocity field stored only at the nodes that need it, the
//! strip-coloured parallel traversal) in 2D, and the 2D stencil visits of the crack layer.
//!
//! Layout: node (ix, iy) lives at storage index `(ix + PAD)·ny + iy` (x-major, so a strip of
//! columns is one contiguous slice). Particles are sorted by cell column and grouped in strips
//! of `STRIP` columns. A particle whose cell column lies within two columns of its strip
//! writes only to nodes in storage columns `[s·STRIP, s·STRIP + STRIP + 7)`; strips of the
//! same colour (parity) are `2·STRIP` apart, so their writes never overlap. The scatter runs
//! the even strips in parallel, then the odd strips: every node receives its contributions in
//! the same order whatever the number of threads, so results are bitwise reproducible.

use crate::particles::PartsMut;
use fracture_mpm::Dim2;

pub use fracture_mpm::grid::{PAD, Reduce, STRIP, SplitGrid};
pub use fracture_mpm::math::floor_i64;

/// Data of one velocity field at one node (the core's node in 2D).
pub type Node = fracture_mpm::grid::Node<Dim2>;

/// Geometry of the grid (the core's in 2D; its node-pair accessors `nx`, `ny`, `at`, `pos`,
/// `node_xy`, `cell_xy` are the 2D ones).
pub type GridGeom = fracture_mpm::grid::GridGeom<Dim2>;

/// Mutable view of a contiguous range of grid storage and of the field-1 nodes inside it.
pub type GridMut<'a> = fracture_mpm::grid::GridMut<'a, Dim2>;

/// Run `f` on every strip of colour `colour` (0 even, 1 odd) in parallel (the core's
/// [`fracture_mpm::grid::for_strips`] over the 2D solver's particle views).
#[inline]
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
    fracture_mpm::grid::for_strips(geom, bounds, colour, parts, grid, f)
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
        let start = geom.at((w.x.base + a as i32) as usize, by);
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
    let ny = geom.ny();
    let s0 = geom.at(w.x.base as usize, w.y.base as usize) - g.base;
    let (c0, rest) = g.nodes[s0..].split_at_mut(ny);
    let (c1, c2) = rest.split_at_mut(ny);
    [first3(c0), first3(c1), first3(c2)]
}

#[inline(always)]
fn first3(col: &mut [Node]) -> &mut [Node; 3] {
    col.first_chunk_mut::<3>()
        .expect("stencil column inside the strip's write range")
}
