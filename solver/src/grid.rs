//! The background grid of the 2D solver: the core's grid (`fracture_mpm::grid`: packed
//! per-node data, the extra crack velocity field stored only at the nodes that need it, the
//! strip-coloured parallel traversal) in 2D. The stencil visits of the passes, field 0 and
//! the crack fields, are the core's (`fracture_mpm::stencil`).
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
