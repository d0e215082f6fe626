//! The four particle passes of a step (`algorithm.md` §2, USAVG), written once over `D: Dim`
//! and over the particle's [`Stencil`] (the fast field-0 path or the generic path through the
//! crack fields, `stencil.rs`), run strip by strip (even colour, then odd:
//! `grid::for_strips`), with their reductions merged in strip order. Every product-and-sum
//! goes through `madd` (portable or FMA kernel). The core's continuum (`step.rs`) and the 2D
//! crack solver (`fracture-solver`) both step with these passes; what the crack layer adds is
//! data: field masks and the slot map of field-1 nodes, the mass-weighted displacement of the
//! P2G, the displacement gradient of the stress updates.
//! 1. [`p2g`]: weights, mass, momentum and (with cracks) mass-weighted displacement to the
//!    grid.
//! 2. [`forces`]: velocity gradient from p/m, first stress half-update, internal and external
//!    forces to the grid.
//! 3. [`update`]: FLIP velocity, position from the mid-step grid velocity, re-extrapolation of
//!    momentum with the same weights (pitfall 2).
//! 4. [`strain`]: velocity gradient from q/m, second stress half-update, strain energy.

use fracture_api::scene::ShapeFunction;

use crate::dim::{Dim, Elastic, pack, weights};
use crate::grid::{GridGeom, GridMut, Node, Reduce, STRIP, for_strips};
use crate::math::{Arith, Fma, Kernel, Portable, madd};
use crate::particles::{Particles, PartsMut};
use crate::stencil::{Stencil, with_stencil};

/// Failure kinds of a particle pass.
pub const FAIL_VELOCITY: u8 = 1;
/// A position became non-finite.
pub const FAIL_POSITION: u8 = 2;
/// A stress became non-finite.
pub const FAIL_STRESS: u8 = 3;
/// A particle reached the grid's edge.
pub const FAIL_GRID: u8 = 4;

/// Reduction of a particle pass: partial sums and the first offending particle.
#[derive(Debug, Clone, Copy, Default)]
pub struct Acc {
    /// Kinetic energy (pass 3) or strain energy (pass 4).
    pub e: f64,
    /// External work of tractions (pass 3).
    pub w: f64,
    /// A particle drifted too far from its strip: re-sort before the next scatter.
    pub resort: bool,
    /// First failure: (sorted index, kind).
    pub fail: Option<(usize, u8)>,
    /// Active box: lowest and highest stencil base per direction (up to 3 directions).
    pub lo: [i64; 3],
    /// Highest node index touched per direction.
    pub hi: [i64; 3],
    /// Whether the box is set.
    pub has_box: bool,
}

impl Reduce for Acc {
    fn merge(self, r: Self) -> Self {
        let (lo, hi) = match (self.has_box, r.has_box) {
            (true, true) => {
                let mut lo = self.lo;
                let mut hi = self.hi;
                for k in 0..3 {
                    lo[k] = lo[k].min(r.lo[k]);
                    hi[k] = hi[k].max(r.hi[k]);
                }
                (lo, hi)
            }
            (true, false) => (self.lo, self.hi),
            _ => (r.lo, r.hi),
        };
        Acc {
            e: self.e + r.e,
            w: self.w + r.w,
            resort: self.resort || r.resort,
            fail: match (self.fail, r.fail) {
                (Some(a), Some(b)) => Some(if a.0 <= b.0 { a } else { b }),
                (a, b) => a.or(b),
            },
            lo,
            hi,
            has_box: self.has_box || r.has_box,
        }
    }
}

/// Record failure `kind` of sorted particle `i` unless an earlier one is recorded.
#[inline(always)]
fn first_fail(acc: &mut Acc, i: usize, kind: u8) {
    if acc.fail.is_none() {
        acc.fail = Some((i, kind));
    }
}

/// What a particle pass reads besides the particles and the grid.
#[derive(Clone, Copy)]
pub struct PassCx<'a, D: Dim> {
    /// Grid geometry.
    pub geom: GridGeom<D>,
    /// Shape functions.
    pub shape: ShapeFunction,
    /// Arithmetic.
    pub kernel: Kernel,
    /// Time step (the stress half-updates use Δt/2).
    pub dt: f64,
    /// Materials by index.
    pub mats: &'a [Elastic],
    /// Tractions now, by load index.
    pub loads: &'a [D::V],
    /// Particle range of each strip.
    pub bounds: &'a [usize],
    /// Dense slot map of the field-1 nodes (empty without cracks).
    pub slot_of: &'a [u32],
    /// The P2G also scatters the mass-weighted displacement Σ S m (x − X) (crack contact).
    pub displacement: bool,
    /// The field-0 fast path may be taken (see [`PassCx::fast_ok`]).
    pub fast: bool,
}

impl<D: Dim> PassCx<'_, D> {
    /// Whether the dimension's fast stencil is exact for `shape`: the 2D path relies on GIMP's
    /// S = 0 ⇒ S' = 0; the 3D rows skip zero-weight pairs themselves.
    pub fn fast_ok(shape: ShapeFunction) -> bool {
        shape == ShapeFunction::Gimp || D::N == 3
    }
}

/// The grid storage a pass works on: field-0 nodes, field-1 nodes and their storage indices.
pub struct Grid<'a, D: Dim> {
    /// Field-0 nodes (the whole storage).
    pub nodes: &'a mut [Node<D>],
    /// Field-1 nodes, in storage order.
    pub f1: &'a mut [Node<D>],
    /// Their storage indices.
    pub f1_index: &'a [u32],
}

impl<'a, D: Dim> Grid<'a, D> {
    /// Field-0 storage only.
    pub fn single(nodes: &'a mut [Node<D>]) -> Self {
        Grid {
            nodes,
            f1: &mut [],
            f1_index: &[],
        }
    }
    fn view(&mut self) -> GridMut<'_, D> {
        GridMut {
            nodes: &mut *self.nodes,
            base: 0,
            f1: &mut *self.f1,
            f1_index: self.f1_index,
            f1_base: 0,
        }
    }
}

/// L = Σ v ⊗ ∇S over the stencil (cell units), from the nodal velocities of the particle's own
/// fields (pitfall 3).
#[inline(always)]
fn gather_l<A: Arith, D: Dim>(st: &mut impl Stencil<D>) -> D::L {
    let mut l = D::L::default();
    st.each(|_, gr, n| {
        let l = l.as_mut();
        let (v, gr) = (n.v.as_ref(), gr.as_ref());
        for r in 0..D::N {
            for k in 0..D::N {
                l[r * D::N + k] = madd::<A>(v[r], gr[k], l[r * D::N + k]);
            }
        }
    });
    l
}

/// The stress half-update of one particle from the unscaled gradient `l`: stress, strain
/// energy density `w` and, with cracks, the displacement gradient `grad_u` accumulated
/// (∇u += L·Δt/2). Returns whether the new stress is finite.
#[inline(always)]
fn stress_apply<A: Arith, D: Dim>(
    mat: &Elastic,
    stress: &mut D::S,
    w: &mut f64,
    grad_u: Option<&mut D::L>,
    mut l: D::L,
    half: f64,
    inv_h: f64,
) -> bool {
    for v in l.as_mut() {
        *v *= inv_h;
    }
    *w += D::stress_update::<A>(mat, stress, &l, half);
    if let Some(gu) = grad_u {
        for (g, lv) in gu.as_mut().iter_mut().zip(l.as_ref()) {
            *g = madd::<A>(*lv, half, *g);
        }
    }
    D::stress_finite(stress)
}

/// The force of a traction on a particle: traction × its face, (2l·h)^(N−1).
#[inline(always)]
fn face<D: Dim>(lh: f64, h: f64) -> f64 {
    let edge = 2.0 * lh * h;
    if D::N == 2 { edge } else { edge * edge }
}

/// The field mask of particle `i` (zero without cracks).
#[inline(always)]
fn mask_of<D: Dim>(p: &PartsMut<'_, D>, has_mask: bool, i: usize) -> D::Mask {
    if has_mask {
        p.fmask[i]
    } else {
        D::Mask::default()
    }
}

/// Run `f` on every strip (even colour, then odd) and merge in strip order.
fn strips<D, F>(cx: &PassCx<'_, D>, parts: &mut Particles<D>, grid: &mut Grid<'_, D>, f: &F) -> Acc
where
    D: Dim,
    F: Fn(usize, usize, PartsMut<'_, D>, GridMut<'_, D>) -> Acc + Sync,
{
    let mut out = Acc::default();
    let bounds = cx.bounds;
    for colour in 0..2 {
        let a: Acc = for_strips(
            &cx.geom,
            bounds,
            colour,
            PartsMut::new(parts),
            grid.view(),
            &|s, p, g| f(s, bounds[s], p, g),
        );
        out = if colour == 0 { a } else { out.merge(a) };
    }
    out
}

macro_rules! by_kernel {
    ($kernel:expr, $f:ident ( $($arg:expr),* )) => {
        match $kernel {
            Kernel::Portable => $f::<Portable, D>($($arg),*),
            Kernel::Fma => $f::<Fma, D>($($arg),*),
        }
    };
}

/// What the P2G of one particle reads (copied into each strip's loop).
#[derive(Clone, Copy)]
struct P2gCx<D: Dim> {
    geom: GridGeom<D>,
    shape: ShapeFunction,
    fast: bool,
    displacement: bool,
}

/// P2G of particle `i`: its weights (cached for the step's later passes), mass, momentum and
/// (with cracks) mass-weighted displacement scattered to `g`. `lq` holds the last half-width
/// seen and its 1/(4l).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn p2g_particle<A: Arith, D: Dim, const DISP: bool>(
    cx: &P2gCx<D>,
    p: &mut PartsMut<'_, D>,
    i: usize,
    first: usize,
    lq: &mut (f64, f64),
    g: &mut GridMut<'_, D>,
    slot_of: &[u32],
    acc: &mut Acc,
) {
    let geom = &cx.geom;
    let k = p.kin[i];
    let m = p.mech[i].m;
    let lh = p.mech[i].lh;
    if cx.shape == ShapeFunction::Gimp && lh != lq.0 {
        *lq = (lh, 0.25 / lh);
    }
    let xi = geom.xi(&k.x);
    // The weights the later passes read back from the cache, used here too so that all four
    // passes see the same S and ∇S.
    let c = pack::<D>(&weights::<D>(cx.shape, &xi, lh, lq.1));
    p.wts[i] = c;
    // Active box: the stencil's base .. base + 2 per direction.
    for (d, w) in c.as_ref().iter().enumerate() {
        let b = i64::from(w.base);
        if acc.has_box {
            acc.lo[d] = acc.lo[d].min(b);
            acc.hi[d] = acc.hi[d].max(b + 2);
        } else {
            acc.lo[d] = b;
            acc.hi[d] = b + 2;
        }
    }
    acc.has_box = true;
    let (mask, disp) = if DISP {
        let x0 = p.cold[i].x0;
        let mut u = D::V::default();
        for d in 0..D::N {
            u.as_mut()[d] = k.x.as_ref()[d] - x0.as_ref()[d];
        }
        (p.fmask[i], u)
    } else {
        (D::Mask::default(), D::V::default())
    };
    let v = k.v.as_ref();
    if !v.iter().all(|x| x.is_finite()) {
        first_fail(acc, first + i, FAIL_VELOCITY);
    }
    let mut mv = D::V::default();
    for d in 0..D::N {
        mv.as_mut()[d] = m * v[d];
    }
    let fast = cx.fast && mask.into() == 0;
    with_stencil!(D, fast, g, geom, &c, mask, slot_of, |st| {
        st.each_weighted(|s, _, n| {
            n.m = madd::<A>(s, m, n.m);
            let (np, mv) = (n.p.as_mut(), mv.as_ref());
            for d in 0..D::N {
                np[d] = madd::<A>(s, mv[d], np[d]);
            }
            if DISP {
                let sm = s * m;
                let (nu, du) = (n.u.as_mut(), disp.as_ref());
                for d in 0..D::N {
                    nu[d] = madd::<A>(sm, du[d], nu[d]);
                }
            }
        })
    });
}

/// Pass 1: weights (cached for the step), mass, momentum and (with `cx.displacement`)
/// mass-weighted displacement to the grid.
pub fn p2g<D: Dim>(cx: &PassCx<'_, D>, parts: &mut Particles<D>, grid: &mut Grid<'_, D>) -> Acc {
    by_kernel!(cx.kernel, p2g_k(cx, parts, grid))
}

fn p2g_k<A: Arith, D: Dim>(
    cx: &PassCx<'_, D>,
    parts: &mut Particles<D>,
    grid: &mut Grid<'_, D>,
) -> Acc {
    let pc = P2gCx {
        geom: cx.geom,
        shape: cx.shape,
        fast: cx.fast,
        displacement: cx.displacement,
    };
    let slot_of = cx.slot_of;
    strips(cx, parts, grid, &|_s, first, mut p, mut g| {
        A::run(|| {
            // Locals, not the closure's captured references: read through those, the values
            // are reloaded after every node store (the compiler cannot rule out aliasing).
            #[allow(clippy::redundant_locals)]
            let pc = pc;
            let mut acc = Acc::default();
            p.assert_lengths();
            let mut lq = (f64::NAN, f64::NAN);
            // The displacement scatter chosen once per strip, not per node.
            if pc.displacement {
                for i in 0..p.len() {
                    let (lq, g) = (&mut lq, &mut g);
                    p2g_particle::<A, D, true>(&pc, &mut p, i, first, lq, g, slot_of, &mut acc);
                }
            } else {
                for i in 0..p.len() {
                    let (lq, g) = (&mut lq, &mut g);
                    p2g_particle::<A, D, false>(&pc, &mut p, i, first, lq, g, slot_of, &mut acc);
                }
            }
            acc
        })
    })
}

/// Pass 2: velocity gradient from p/m, first stress half-update (and ∇u with cracks), forces
/// to the grid.
pub fn forces<D: Dim>(cx: &PassCx<'_, D>, parts: &mut Particles<D>, grid: &mut Grid<'_, D>) -> Acc {
    by_kernel!(cx.kernel, forces_k(cx, parts, grid))
}

fn forces_k<A: Arith, D: Dim>(
    cx: &PassCx<'_, D>,
    parts: &mut Particles<D>,
    grid: &mut Grid<'_, D>,
) -> Acc {
    let geom = cx.geom;
    let fast_ok = cx.fast;
    let half = 0.5 * cx.dt;
    let inv_h = 1.0 / geom.h;
    let h = geom.h;
    let (mats, loads, slot_of) = (cx.mats, cx.loads, cx.slot_of);
    strips(cx, parts, grid, &|_s, first, p, mut g| {
        A::run(|| {
            // Locals, not captured references (see `p2g_k`).
            let (geom, fast_ok, half, inv_h, h) = (geom, fast_ok, half, inv_h, h);
            let mut acc = Acc::default();
            p.assert_lengths();
            let has_mask = !p.fmask.is_empty();
            for i in 0..p.len() {
                let mech = p.mech[i];
                let mask = mask_of(&p, has_mask, i);
                // External force: traction × the particle's face.
                let loaded = mech.load > 0;
                let mut fext = D::V::default();
                if loaded {
                    let t = loads[mech.load as usize - 1];
                    let a = face::<D>(mech.lh, h);
                    for d in 0..D::N {
                        fext.as_mut()[d] = t.as_ref()[d] * a;
                    }
                }
                let vs = mech.vol * inv_h;
                let fast = fast_ok && mask.into() == 0;
                let c = p.wts[i];
                with_stencil!(D, fast, &mut g, &geom, &c, mask, slot_of, |st| {
                    let l = gather_l::<A, D>(&mut st);
                    let mat = &mats[mech.mat as usize];
                    let gu = p.grad_u.get_mut(i);
                    let (stress, w) = (&mut p.stress[i], &mut p.wden[i]);
                    if !stress_apply::<A, D>(mat, stress, w, gu, l, half, inv_h) {
                        first_fail(&mut acc, first + i, FAIL_STRESS);
                    }
                    let s = p.stress[i];
                    let nvs = -vs;
                    st.each_weighted(|sh, gr, n| {
                        // f = −V σ·∇S (the sums inside the parentheses of −V(σ·∇S)).
                        let sg = D::stress_dot::<A>(&s, gr.as_ref());
                        let (nf, sg, fe) = (n.f.as_mut(), sg.as_ref(), fext.as_ref());
                        // Without a load S·0 = +0 would change nothing (sums start at +0 and
                        // never become −0), so the unloaded particle skips it.
                        if loaded {
                            for d in 0..D::N {
                                nf[d] += madd::<A>(sh, fe[d], nvs * sg[d]);
                            }
                        } else {
                            for d in 0..D::N {
                                nf[d] = madd::<A>(nvs, sg[d], nf[d]);
                            }
                        }
                    });
                });
            }
            acc
        })
    })
}

/// Pass 3: FLIP particle update and re-extrapolation of the new momenta with the same weights
/// and fields (pitfall 2). The position is committed here.
pub fn update<D: Dim>(cx: &PassCx<'_, D>, parts: &mut Particles<D>, grid: &mut Grid<'_, D>) -> Acc {
    by_kernel!(cx.kernel, update_k(cx, parts, grid))
}

fn update_k<A: Arith, D: Dim>(
    cx: &PassCx<'_, D>,
    parts: &mut Particles<D>,
    grid: &mut Grid<'_, D>,
) -> Acc {
    let geom = cx.geom;
    let fast_ok = cx.fast;
    let dt = cx.dt;
    let h = geom.h;
    let (loads, slot_of) = (cx.loads, cx.slot_of);
    // Cells per direction (a particle must stay one cell inside the grid).
    let mut ncell = [0i64; 3];
    for d in 0..D::N {
        ncell[d] = (geom.n.as_ref()[d] - 1) as i64;
    }
    strips(cx, parts, grid, &|s, first, p, mut g| {
        A::run(|| {
            // Locals, not captured references (see `p2g_k`).
            let (geom, fast_ok, dt, h, ncell) = (geom, fast_ok, dt, h, ncell);
            let hdt = 0.5 * dt;
            let mut acc = Acc::default();
            p.assert_lengths();
            let has_mask = !p.fmask.is_empty();
            let lo = (s * STRIP) as i64 - 1;
            let hi = ((s + 1) * STRIP) as i64;
            for i in 0..p.len() {
                let k = p.kin[i];
                let mech = p.mech[i];
                let c = p.wts[i];
                let mask = mask_of(&p, has_mask, i);
                let fast = fast_ok && mask.into() == 0;
                with_stencil!(D, fast, &mut g, &geom, &c, mask, slot_of, |st| {
                    let mut acc_p = D::V::default();
                    let mut vbar = D::V::default();
                    st.each(|sh, _, n| {
                        let (ap, vb) = (acc_p.as_mut(), vbar.as_mut());
                        for d in 0..D::N {
                            let an = sh * n.a.as_ref()[d];
                            ap[d] += an;
                            // (v_old + v_new)/2 = p/m + Δt/2 · f/m
                            vb[d] += madd::<A>(sh, n.v.as_ref()[d], hdt * an);
                        }
                    });
                    let mut v = D::V::default();
                    let mut xn = D::V::default();
                    for d in 0..D::N {
                        v.as_mut()[d] = madd::<A>(dt, acc_p.as_ref()[d], k.v.as_ref()[d]);
                        xn.as_mut()[d] = madd::<A>(dt, vbar.as_ref()[d], k.x.as_ref()[d]);
                    }
                    let v_ok = v.as_ref().iter().all(|x| x.is_finite());
                    let x_ok = xn.as_ref().iter().all(|x| x.is_finite());
                    if !v_ok {
                        first_fail(&mut acc, first + i, FAIL_VELOCITY);
                    } else if !x_ok {
                        first_fail(&mut acc, first + i, FAIL_POSITION);
                    } else {
                        // Truncation (not floor): negative ξ gives 0 and is caught as < 1 too.
                        let xi = geom.xi(&xn);
                        let mut cell = [0i64; 3];
                        let mut out = false;
                        for d in 0..D::N {
                            let x = xi.as_ref()[d];
                            cell[d] = x as i64;
                            out |= x < 1.0 || cell[d] + 1 >= ncell[d];
                        }
                        if out {
                            first_fail(&mut acc, first + i, FAIL_GRID);
                        }
                        if cell[0] < lo || cell[0] > hi {
                            acc.resort = true;
                        }
                    }
                    p.kin[i].v = v;
                    // Nothing between this pass and the last stress update reads the position
                    // (that pass and the fused P2G use the cached weights). A non-finite one is
                    // not written, so the step's error names the last good one.
                    if x_ok {
                        p.kin[i].x = xn;
                    }
                    let mut v2 = 0.0;
                    for d in 0..D::N {
                        v2 += v.as_ref()[d] * v.as_ref()[d];
                    }
                    acc.e += 0.5 * mech.m * v2;
                    if mech.load > 0 {
                        let t = loads[mech.load as usize - 1];
                        let a = face::<D>(mech.lh, h);
                        // Work on the grid: F · v̄ Δt with v̄ the mid-step grid velocity at the
                        // particle (the velocity that moves it).
                        let mut tv = 0.0;
                        for d in 0..D::N {
                            tv += t.as_ref()[d] * vbar.as_ref()[d];
                        }
                        acc.w += a * tv * dt;
                    }
                    // Re-extrapolate momentum with the same weights and fields (pitfall 2).
                    let mut mv = D::V::default();
                    for d in 0..D::N {
                        mv.as_mut()[d] = mech.m * v.as_ref()[d];
                    }
                    st.each(|sh, _, n| {
                        let q = n.q.as_mut();
                        for d in 0..D::N {
                            q[d] = madd::<A>(sh, mv.as_ref()[d], q[d]);
                        }
                    });
                });
            }
            acc
        })
    })
}

/// Pass 4: velocity gradient from the re-extrapolated momenta, second stress half-update (and
/// ∇u with cracks), strain energy summed.
pub fn strain<D: Dim>(cx: &PassCx<'_, D>, parts: &mut Particles<D>, grid: &mut Grid<'_, D>) -> Acc {
    by_kernel!(cx.kernel, strain_k(cx, parts, grid))
}

fn strain_k<A: Arith, D: Dim>(
    cx: &PassCx<'_, D>,
    parts: &mut Particles<D>,
    grid: &mut Grid<'_, D>,
) -> Acc {
    let geom = cx.geom;
    let fast_ok = cx.fast;
    let half = 0.5 * cx.dt;
    let inv_h = 1.0 / geom.h;
    let (mats, slot_of) = (cx.mats, cx.slot_of);
    strips(cx, parts, grid, &|_s, first, p, mut g| {
        A::run(|| {
            // Locals, not captured references (see `p2g_k`).
            let (geom, fast_ok, half, inv_h) = (geom, fast_ok, half, inv_h);
            let mut acc = Acc::default();
            p.assert_lengths();
            let has_mask = !p.fmask.is_empty();
            for i in 0..p.len() {
                let mech = p.mech[i];
                let mask = mask_of(&p, has_mask, i);
                let fast = fast_ok && mask.into() == 0;
                let c = p.wts[i];
                let ok = with_stencil!(D, fast, &mut g, &geom, &c, mask, slot_of, |st| {
                    let l = gather_l::<A, D>(&mut st);
                    let mat = &mats[mech.mat as usize];
                    let gu = p.grad_u.get_mut(i);
                    stress_apply::<A, D>(mat, &mut p.stress[i], &mut p.wden[i], gu, l, half, inv_h)
                });
                if !ok {
                    first_fail(&mut acc, first + i, FAIL_STRESS);
                }
                acc.e += mech.vol * p.wden[i];
            }
            acc
        })
    })
}

/// Pass 4 fused with pass 1 of the next step (only without cracks: the next step's fields
/// depend on the crack's motion): per particle, the second stress half-update from the
/// current grid `cur`, then the new weights and the P2G into `next` (zeroed by the caller
/// where it was written). Per node the P2G sums run in the same particle and strip order as an
/// unfused P2G, so the results are bitwise identical (`tests/fused.rs`). Returns the
/// reductions of pass 4 and of the next step's P2G.
pub fn strain_p2g<D: Dim>(
    cx: &PassCx<'_, D>,
    parts: &mut Particles<D>,
    cur: &mut Grid<'_, D>,
    next: &mut [Node<D>],
) -> (Acc, Acc) {
    by_kernel!(cx.kernel, strain_p2g_k(cx, parts, cur, next))
}

fn strain_p2g_k<A: Arith, D: Dim>(
    cx: &PassCx<'_, D>,
    parts: &mut Particles<D>,
    cur: &mut Grid<'_, D>,
    next: &mut [Node<D>],
) -> (Acc, Acc) {
    debug_assert!(parts.fmask.is_empty(), "the fused pass runs without cracks");
    let pc = P2gCx {
        geom: cx.geom,
        shape: cx.shape,
        fast: cx.fast,
        displacement: false,
    };
    let geom = cx.geom;
    let fast = cx.fast;
    let half = 0.5 * cx.dt;
    let inv_h = 1.0 / geom.h;
    let (mats, slot_of) = (cx.mats, cx.slot_of);
    let f = |_s: usize,
             first: usize,
             mut p: PartsMut<'_, D>,
             (mut gc, mut gn): (GridMut<'_, D>, GridMut<'_, D>)| {
        A::run(|| {
            // Locals, not captured references (see `p2g_k`).
            let (pc, geom, fast, half, inv_h) = (pc, geom, fast, half, inv_h);
            let mut acc = Acc::default();
            let mut acc_next = Acc::default();
            p.assert_lengths();
            let mut lq = (f64::NAN, f64::NAN);
            let zero = D::Mask::default();
            for i in 0..p.len() {
                let mech = p.mech[i];
                let c = p.wts[i];
                let ok = with_stencil!(D, fast, &mut gc, &geom, &c, zero, slot_of, |st| {
                    let l = gather_l::<A, D>(&mut st);
                    let mat = &mats[mech.mat as usize];
                    stress_apply::<A, D>(
                        mat,
                        &mut p.stress[i],
                        &mut p.wden[i],
                        None,
                        l,
                        half,
                        inv_h,
                    )
                });
                if !ok {
                    first_fail(&mut acc, first + i, FAIL_STRESS);
                }
                acc.e += mech.vol * p.wden[i];
                let (lq, gn) = (&mut lq, &mut gn);
                p2g_particle::<A, D, false>(&pc, &mut p, i, first, lq, gn, slot_of, &mut acc_next);
            }
            (acc, acc_next)
        })
    };
    let bounds = cx.bounds;
    let mut out = (Acc::default(), Acc::default());
    for colour in 0..2 {
        let nxt = GridMut::single(&mut *next);
        let parts = PartsMut::new(parts);
        let a: (Acc, Acc) = for_strips(
            &geom,
            bounds,
            colour,
            parts,
            (cur.view(), nxt),
            &|s, p, g| f(s, bounds[s], p, g),
        );
        out = if colour == 0 { a } else { out.merge(a) };
    }
    out
}
