//! A particle's stencil (`algorithm.md` §1): which nodes a transfer visits, in which order,
//! with which S and ∇S. The passes (`passes.rs`) are written once over [`Stencil`];
//! [`with_stencil!`] picks, per particle, one of two monomorphised implementations:
//!
//! - the dimension's fast path [`Dim::Fast`]: every pair in velocity field 0 (every particle of
//!   a scene without cracks, most of one with cracks). In 2D, [`Field0`]: GIMP weights, the
//!   particle's three 3-node storage columns as fixed arrays (one range check per column), the
//!   empty last column and row skipped (GIMP puts them last), ∇S computed once per particle.
//!   In 3D, [`Rows`]: the stencil rows of `Dim3::visit`.
//! - [`Fields`], the generic path: any weights, any velocity fields (the node of each pair
//!   taken from its field: field 1 through the dense slot map).
//!
//! Both visit pairs x outer (then y, then z), and the generic path only visits more pairs than
//! the fast path where those pairs add signed zeros (with GIMP, S = 0 implies ∇S = 0) to sums
//! that start at +0: the results are bitwise identical (the 2D solver's
//! `tests/stencil_paths.rs`, `tests/fields.rs` here).

use crate::dim::{Dim, Dim2, unpack};
use crate::grid::{GridGeom, GridMut, Node};
use crate::shape::Weights1;

/// The node visits of one particle's stencil: `f(S, ∇S, node)`, ∇S in cell units.
pub trait Stencil<D: Dim> {
    /// Every pair that may carry S or ∇S ≠ 0 (gathers and the re-extrapolation).
    fn each(&mut self, f: impl FnMut(f64, D::V, &mut Node<D>));
    /// The pairs with S ≠ 0 (the P2G and force scatters).
    fn each_weighted(&mut self, f: impl FnMut(f64, D::V, &mut Node<D>));
}

/// The 2D fast path: GIMP weights, every pair in field 0.
pub struct Field0<'a> {
    cols: [&'a mut [Node<Dim2>; 3]; 3],
    /// The unpacked weights, held by value (read from registers in the passes).
    w: [Weights1; 2],
    /// ∇S of every pair, `[a][b]` (computed once; dropped by the optimiser where unused).
    gr: [[[f64; 2]; 3]; 3],
    /// The last row is empty (a particle whose domain lies inside one cell row).
    last: bool,
}

impl<'a> Field0<'a> {
    /// The stencil of the cached GIMP weights `c`, all in field 0, in the strip's grid `g`.
    #[inline(always)]
    pub fn new(
        g: &'a mut GridMut<'_, Dim2>,
        geom: &GridGeom<Dim2>,
        c: &<Dim2 as Dim>::C,
    ) -> Field0<'a> {
        let w = unpack::<Dim2>(c);
        let [x, y] = &w;
        let mut gr = [[[0.0; 2]; 3]; 3];
        for a in 0..3 {
            for b in 0..3 {
                gr[a][b] = [x.ds[a] * y.s[b], x.s[a] * y.ds[b]];
            }
        }
        Field0 {
            cols: columns(g, geom, &w),
            w,
            gr,
            // Only the last row (and column) of GIMP weights can be empty (the stencil base
            // rule of `shape::weights_1d`), and there S = 0 implies S' = 0.
            last: y.s[2] == 0.0,
        }
    }
}

/// The three field-0 columns of a 2D particle's stencil as fixed-size arrays: column `a` holds
/// nodes (base_x + a, base_y … base_y + 2). All three lie in the strip's write range (the
/// stencil's base is at most two columns off the strip).
#[inline(always)]
fn columns<'g>(
    g: &'g mut GridMut<'_, Dim2>,
    geom: &GridGeom<Dim2>,
    w: &[Weights1; 2],
) -> [&'g mut [Node<Dim2>; 3]; 3] {
    let ny = geom.ny();
    let s0 = geom.at(w[0].base as usize, w[1].base as usize) - g.base;
    let (c0, rest) = g.nodes[s0..].split_at_mut(ny);
    let (c1, c2) = rest.split_at_mut(ny);
    [first3(c0), first3(c1), first3(c2)]
}

#[inline(always)]
fn first3<N>(col: &mut [N]) -> &mut [N; 3] {
    col.first_chunk_mut::<3>()
        .expect("stencil column inside the strip's write range")
}

impl Stencil<Dim2> for Field0<'_> {
    #[inline(always)]
    fn each(&mut self, mut f: impl FnMut(f64, [f64; 2], &mut Node<Dim2>)) {
        let [x, y] = &self.w;
        for (a, col) in self.cols.iter_mut().enumerate() {
            if a == 2 && x.s[2] == 0.0 {
                continue;
            }
            // A fixed 3-row loop the compiler unrolls: only the third row carries the branch.
            for (b, (n, &sy)) in col.iter_mut().zip(&y.s).enumerate() {
                if b == 2 && self.last {
                    break;
                }
                f(x.s[a] * sy, self.gr[a][b], n);
            }
        }
    }

    /// The same pairs as [`Stencil::each`]: every visited pair has S ≠ 0.
    #[inline(always)]
    fn each_weighted(&mut self, f: impl FnMut(f64, [f64; 2], &mut Node<Dim2>)) {
        self.each(f);
    }
}

/// The fast path of any dimension through [`Dim::visit`] (3D: rows of three nodes behind one
/// range check, 2 or 3 nodes per direction by the empty-last rule).
pub struct Rows<'a, D: Dim> {
    nodes: &'a mut [Node<D>],
    w: D::W,
    strides: D::U,
}

impl<'a, D: Dim> Rows<'a, D> {
    /// The stencil of the cached weights `c`, all in field 0, in the strip's grid `g`.
    #[inline(always)]
    pub fn new(g: &'a mut GridMut<'_, D>, geom: &GridGeom<D>, c: &D::C) -> Rows<'a, D> {
        let w = unpack::<D>(c);
        let start = geom.index_i32(|d| w.as_ref()[d].base) - g.base;
        Rows {
            nodes: &mut g.nodes[start..],
            w,
            strides: geom.strides,
        }
    }
}

impl<D: Dim> Stencil<D> for Rows<'_, D> {
    #[inline(always)]
    fn each(&mut self, f: impl FnMut(f64, D::V, &mut Node<D>)) {
        D::visit(&self.w, &self.strides, false, self.nodes, f);
    }
    #[inline(always)]
    fn each_weighted(&mut self, f: impl FnMut(f64, D::V, &mut Node<D>)) {
        D::visit(&self.w, &self.strides, true, self.nodes, f);
    }
}

/// The generic path: any weights, the node of each pair from its velocity field.
pub struct Fields<'a, 'g, D: Dim> {
    g: &'a mut GridMut<'g, D>,
    w: D::W,
    /// Storage index of the stencil's first node.
    start: usize,
    strides: D::U,
    mask: u32,
    slot_of: &'a [u32],
}

impl<'a, 'g, D: Dim> Fields<'a, 'g, D> {
    /// The stencil of the cached weights `c` with field mask `mask` (bit k set: pair k, x
    /// outer, in field 1, through the dense slot map `slot_of`).
    #[inline(always)]
    pub fn new(
        g: &'a mut GridMut<'g, D>,
        geom: &GridGeom<D>,
        c: &D::C,
        mask: D::Mask,
        slot_of: &'a [u32],
    ) -> Fields<'a, 'g, D> {
        let w = unpack::<D>(c);
        Fields {
            g,
            start: geom.index_i32(|d| w.as_ref()[d].base),
            w,
            strides: geom.strides,
            mask: mask.into(),
            slot_of,
        }
    }

    /// Every pair of the stencil but those of an empty x-plane: `f(S, ∇S, node)` with S and
    /// ∇S the products of the 1D weights in direction order (∇S_d with S'_d in place of
    /// S_d), the node from the pair's field.
    #[inline(always)]
    fn visit(&mut self, weighted: bool, mut f: impl FnMut(f64, D::V, &mut Node<D>)) {
        let w = self.w.as_ref();
        let per_plane = D::STENCIL / 3;
        for a in 0..3 {
            if w[0].s[a] == 0.0 && w[0].ds[a] == 0.0 {
                continue;
            }
            for r in 0..per_plane {
                let k = a * per_plane + r;
                // Digits of the pair in the other directions (last fastest).
                let mut digit = [a, 0, 0];
                let mut rest = r;
                for d in (1..D::N).rev() {
                    digit[d] = rest % 3;
                    rest /= 3;
                }
                let mut s = w[0].s[a];
                for d in 1..D::N {
                    s *= w[d].s[digit[d]];
                }
                if weighted && s == 0.0 {
                    continue;
                }
                let mut g = D::V::default();
                for (d, gd) in g.as_mut().iter_mut().enumerate() {
                    let mut p = if d == 0 { w[0].ds[a] } else { w[0].s[a] };
                    for e in 1..D::N {
                        p *= if e == d {
                            w[e].ds[digit[e]]
                        } else {
                            w[e].s[digit[e]]
                        };
                    }
                    *gd = p;
                }
                let mut index = self.start;
                for d in 0..D::N {
                    index += digit[d] * self.strides.as_ref()[d];
                }
                let field = ((self.mask >> k) & 1) as u8;
                f(s, g, self.g.node(index, field, self.slot_of));
            }
        }
    }
}

impl<D: Dim> Stencil<D> for Fields<'_, '_, D> {
    #[inline(always)]
    fn each(&mut self, f: impl FnMut(f64, D::V, &mut Node<D>)) {
        self.visit(false, f);
    }
    #[inline(always)]
    fn each_weighted(&mut self, f: impl FnMut(f64, D::V, &mut Node<D>)) {
        self.visit(true, f);
    }
}

/// `with_stencil!(D, fast, g, geom, c, mask, slot_of, |st| body)`: run `body` with `st` bound
/// to the stencil of the particle's cached weights `c` (a `&D::C`): the dimension's fast path
/// [`Dim::fast`] when `fast` holds (GIMP weights, `mask` zero), [`Fields`] otherwise. The body
/// is written once and compiled once per stencil type (a closure cannot be generic).
#[macro_export]
macro_rules! with_stencil {
    ($d:ty, $fast:expr, $g:expr, $geom:expr, $c:expr, $mask:expr, $slot_of:expr, |$st:ident| $body:expr) => {
        if $fast {
            let mut $st = <$d as $crate::dim::Dim>::fast($g, $geom, $c);
            $body
        } else {
            let mut $st = $crate::stencil::Fields::<$d>::new($g, $geom, $c, $mask, $slot_of);
            $body
        }
    };
}
pub use with_stencil;
