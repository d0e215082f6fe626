//! The 3×3 stencil of one particle (`algorithm.md` §1): which nodes a transfer visits, in
//! which order, with which S and ∇S. The passes of `transfer.rs` are written once over the
//! [`Stencil`] trait; [`with_stencil!`] picks, per particle, one of two monomorphised
//! implementations:
//!
//! - [`Field0`], the fast path: GIMP weights and every pair in field 0 (every particle of a
//!   scene without cracks, most of one with cracks). The particle writes its three 3-node
//!   storage columns directly (`grid::field0_columns`: one range check per column), skips the
//!   stencil's empty last column and row (`shape::gimp_weights_1d` puts them last), and
//!   computes ∇S once per particle.
//! - [`Fields`], the generic path: any weights, any velocity fields (the node of each pair
//!   taken from its field through `grid::visit_stencil`).
//!
//! Both visit nodes column by column (a, then b), and the generic path only visits more pairs
//! than the fast path where those pairs add signed zeros (with GIMP, S = 0 implies ∇S = 0), to
//! sums that start at +0: results are bitwise identical (`tests/stencil_paths.rs`).

use crate::grid::{GridGeom, GridMut, Node, field0_columns, visit_stencil};
use crate::shape::{Cached2, CachedW2, Weights2};

/// The node visits of one particle's stencil. `f(S, ∇S, node)`, ∇S in cell units
/// (`Weights2::g`), in the order a (x) then b (y).
pub(super) trait Stencil {
    /// Every pair that may carry S or ∇S ≠ 0 (gathers and the re-extrapolation).
    fn each(&mut self, f: impl FnMut(f64, [f64; 2], &mut Node));
    /// The pairs with S ≠ 0 (the P2G and force scatters). The generic path tests S = 0; with
    /// linear weights that drops the force of a node with S = 0 but ∇S ≠ 0.
    fn each_weighted(&mut self, f: impl FnMut(f64, [f64; 2], &mut Node));
}

/// The field-0 fast path: GIMP weights, every pair in field 0.
pub(super) struct Field0<'a> {
    cols: [&'a mut [Node; 3]; 3],
    /// The unpacked weights, held by value: the passes read them from registers, not from a
    /// `Weights2` stored on the stack for the generic path's indexed reads.
    w: Weights2,
    /// ∇S of every pair, `[a][b]` (computed once; dropped by the optimiser where unused).
    gr: [[[f64; 2]; 3]; 3],
    /// The last row is empty (a particle whose domain lies inside one cell row).
    last: bool,
}

impl<'a> Field0<'a> {
    /// The stencil of the cached GIMP weights `c` all in field 0, in the strip's grid `g`.
    #[inline(always)]
    pub(super) fn new(g: &'a mut GridMut<'_>, geom: &GridGeom, c: &CachedW2) -> Field0<'a> {
        let w = c.unpack();
        let mut gr = [[[0.0; 2]; 3]; 3];
        for a in 0..3 {
            for b in 0..3 {
                gr[a][b] = w.g(a, b);
            }
        }
        Field0 {
            cols: field0_columns(g, geom, &w),
            w,
            gr,
            // Only the last row (and column) of GIMP weights can be empty (the stencil base rule
            // of `shape::gimp_weights_1d`), and there S = 0 implies S' = 0.
            last: w.y.s[2] == 0.0,
        }
    }
}

impl Stencil for Field0<'_> {
    #[inline(always)]
    fn each(&mut self, mut f: impl FnMut(f64, [f64; 2], &mut Node)) {
        let w = &self.w;
        for (a, col) in self.cols.iter_mut().enumerate() {
            if a == 2 && w.x.s[2] == 0.0 {
                continue;
            }
            // A fixed 3-row loop the compiler unrolls: only the third row carries the branch.
            for (b, (n, &sy)) in col.iter_mut().zip(&w.y.s).enumerate() {
                if b == 2 && self.last {
                    break;
                }
                f(w.x.s[a] * sy, self.gr[a][b], n);
            }
        }
    }

    /// The same pairs as [`Stencil::each`]: every visited pair has S ≠ 0.
    #[inline(always)]
    fn each_weighted(&mut self, f: impl FnMut(f64, [f64; 2], &mut Node)) {
        self.each(f);
    }
}

/// The generic path: any weights, the node of each pair from its velocity field.
pub(super) struct Fields<'a, 'g> {
    g: &'a mut GridMut<'g>,
    geom: &'a GridGeom,
    w: Weights2,
    mask: u16,
    slot_of: &'a [u32],
}

impl<'a, 'g> Fields<'a, 'g> {
    /// The stencil of the cached weights `c` with field mask `mask` (bit 3a + b set: pair
    /// (a, b) in field 1, through the dense slot map `slot_of`).
    #[inline(always)]
    pub(super) fn new(
        g: &'a mut GridMut<'g>,
        geom: &'a GridGeom,
        c: &CachedW2,
        mask: u16,
        slot_of: &'a [u32],
    ) -> Fields<'a, 'g> {
        Fields {
            g,
            geom,
            w: c.unpack(),
            mask,
            slot_of,
        }
    }
}

impl Stencil for Fields<'_, '_> {
    #[inline(always)]
    fn each(&mut self, mut f: impl FnMut(f64, [f64; 2], &mut Node)) {
        let w = &self.w;
        visit_stencil(self.g, self.geom, w, self.mask, self.slot_of, |a, b, n| {
            f(w.s(a, b), w.g(a, b), n)
        });
    }

    #[inline(always)]
    fn each_weighted(&mut self, mut f: impl FnMut(f64, [f64; 2], &mut Node)) {
        let w = &self.w;
        visit_stencil(self.g, self.geom, w, self.mask, self.slot_of, |a, b, n| {
            let s = w.s(a, b);
            if s != 0.0 {
                f(s, w.g(a, b), n);
            }
        });
    }
}

/// `with_stencil!(field0, g, geom, c, mask, slot_of, |st| body)`: run `body` with `st` bound
/// to the stencil of the particle's cached weights `c` (a `&CachedW2`, which each path unpacks
/// itself), a [`Field0`] when `field0` holds (GIMP weights, `mask == 0`) and a [`Fields`]
/// otherwise. The body is written once and compiled once per stencil type (a closure cannot
/// be generic), so each path runs its own monomorphised copy.
macro_rules! with_stencil {
    ($field0:expr, $g:expr, $geom:expr, $c:expr, $mask:expr, $slot_of:expr, |$st:ident| $body:expr) => {
        if $field0 {
            let mut $st = $crate::sim::stencil::Field0::new($g, $geom, $c);
            $body
        } else {
            let mut $st = $crate::sim::stencil::Fields::new($g, $geom, $c, $mask, $slot_of);
            $body
        }
    };
}
pub(super) use with_stencil;
