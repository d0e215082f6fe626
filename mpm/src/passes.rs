//! The four particle passes of a step (`algorithm.md` §2, USAVG), written once over `D: Dim`
//! and run strip by strip (even colour, then odd: `grid::for_strips`), with their reductions
//! merged in strip order. The arithmetic (every product-and-sum through `madd`, the order of
//! the sums, the f32-cached weights) is the 2D solver's, so that for `Dim2` the passes give
//! its bits.
//! 1. [`p2g`]: weights, mass and momentum to the grid.
//! 2. [`forces`]: velocity gradient from p/m, first stress half-update, internal and external
//!    forces to the grid.
//! 3. [`update`]: FLIP velocity, position from the mid-step grid velocity, re-extrapolation of
//!    momentum with the same weights (pitfall 2).
//! 4. [`strain`]: velocity gradient from q/m, second stress half-update, strain energy.

use fracture_api::scene::ShapeFunction;

use crate::dim::{Dim, Elastic, pack, unpack, weights};
use crate::grid::{GridGeom, GridMut, Reduce, STRIP, for_strips};
use crate::math::{Arith, Fma, Kernel, Portable, madd};
use crate::particles::PartsMut;
use crate::state::{Model, Scratch, State};

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

/// A particle's stencil in a strip's grid: the unpacked weights and the storage offset of
/// its first node in the strip's slice (unpacked once per particle and pass).
struct Sten<D: Dim> {
    w: D::W,
    start: usize,
}

impl<D: Dim> Sten<D> {
    #[inline(always)]
    fn new(g: &GridMut<'_, D>, geom: &GridGeom<D>, c: &D::C) -> Self {
        let w = unpack::<D>(c);
        let start = geom.index_i32(|d| w.as_ref()[d].base) - g.base;
        Sten { w, start }
    }
}

/// Visit the stencil `st` in the strip's grid `g`: `f(S, ∇S, node)`.
#[inline(always)]
fn each<D: Dim>(
    g: &mut GridMut<'_, D>,
    geom: &GridGeom<D>,
    st: &Sten<D>,
    weighted: bool,
    f: impl FnMut(f64, D::V, &mut crate::grid::Node<D>),
) {
    D::visit(&st.w, &geom.strides, weighted, &mut g.nodes[st.start..], f);
}

/// L = Σ v ⊗ ∇S over the stencil (cell units), from the nodal velocities.
#[inline(always)]
fn gather_l<A: Arith, D: Dim>(g: &mut GridMut<'_, D>, geom: &GridGeom<D>, st: &Sten<D>) -> D::L {
    let mut l = D::L::default();
    each(g, geom, st, false, |_, gr, n| {
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

/// The stress half-update of one particle from the unscaled gradient `l`. Returns whether
/// the new stress is finite.
#[inline(always)]
fn stress_apply<A: Arith, D: Dim>(
    mat: &Elastic,
    stress: &mut D::S,
    w: &mut f64,
    mut l: D::L,
    half: f64,
    inv_h: f64,
) -> bool {
    for v in l.as_mut() {
        *v *= inv_h;
    }
    *w += D::stress_update::<A>(mat, stress, &l, half);
    D::stress_finite(stress)
}

/// The force of a traction on a particle: traction × its face, (2l·h)^(N−1).
#[inline(always)]
fn face<D: Dim>(lh: f64, h: f64) -> f64 {
    let edge = 2.0 * lh * h;
    if D::N == 2 { edge } else { edge * edge }
}

/// Run `f` on every strip (even colour, then odd) and merge in strip order.
fn strips<D, F>(model: &Model<D>, st: &mut State<D>, sc: &mut Scratch<D>, f: &F) -> Acc
where
    D: Dim,
    F: Fn(usize, usize, PartsMut<'_, D>, GridMut<'_, D>) -> Acc + Sync,
{
    let geom = model.geom;
    let mut out = Acc::default();
    let bounds = &st.strip_bounds;
    for colour in 0..2 {
        let grid = GridMut::single(&mut sc.nodes);
        let parts = PartsMut::new(&mut st.parts);
        let a: Acc = for_strips(&geom, bounds, colour, parts, grid, &|s, p, g| {
            f(s, bounds[s], p, g)
        });
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

/// Pass 1: weights (cached for the step), mass and momentum to the grid.
pub fn p2g<D: Dim>(model: &Model<D>, st: &mut State<D>, sc: &mut Scratch<D>) -> Acc {
    by_kernel!(model.kernel, p2g_k(model, st, sc))
}

/// P2G of particle `i`: its weights (cached for the step's later passes), mass and
/// momentum scattered to `g`. `lq` holds the last half-width seen and its 1/(4l).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn p2g_particle<A: Arith, D: Dim>(
    geom: &GridGeom<D>,
    shape: ShapeFunction,
    p: &mut PartsMut<'_, D>,
    i: usize,
    first: usize,
    lq: &mut (f64, f64),
    g: &mut GridMut<'_, D>,
    acc: &mut Acc,
) {
    let k = p.kin[i];
    let m = p.mech[i].m;
    let lh = p.mech[i].lh;
    if shape == ShapeFunction::Gimp && lh != lq.0 {
        *lq = (lh, 0.25 / lh);
    }
    let xi = geom.xi(&k.x);
    let c = pack::<D>(&weights::<D>(shape, &xi, lh, lq.1));
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
    let v = k.v.as_ref();
    if !v.iter().all(|x| x.is_finite()) {
        first_fail(acc, first + i, FAIL_VELOCITY);
    }
    let mut mv = D::V::default();
    for d in 0..D::N {
        mv.as_mut()[d] = m * v[d];
    }
    let st = Sten::new(g, geom, &c);
    each(g, geom, &st, true, |s, _, n| {
        n.m = madd::<A>(s, m, n.m);
        let (np, mv) = (n.p.as_mut(), mv.as_ref());
        for d in 0..D::N {
            np[d] = madd::<A>(s, mv[d], np[d]);
        }
    });
}

fn p2g_k<A: Arith, D: Dim>(model: &Model<D>, st: &mut State<D>, sc: &mut Scratch<D>) -> Acc {
    let geom = model.geom;
    let shape = model.shape;
    strips(model, st, sc, &|_s, first, mut p, mut g| {
        A::run(|| {
            let (geom, shape) = (geom, shape);
            let mut acc = Acc::default();
            p.assert_lengths();
            let mut lq = (f64::NAN, f64::NAN);
            for i in 0..p.len() {
                p2g_particle::<A, D>(&geom, shape, &mut p, i, first, &mut lq, &mut g, &mut acc);
            }
            acc
        })
    })
}

/// Pass 2: velocity gradient from p/m, first stress half-update, forces to the grid.
pub fn forces<D: Dim>(model: &Model<D>, st: &mut State<D>, sc: &mut Scratch<D>) -> Acc {
    let loads = std::mem::take(&mut sc.load_now);
    let acc = by_kernel!(model.kernel, forces_k(model, st, sc, &loads));
    sc.load_now = loads;
    acc
}

fn forces_k<A: Arith, D: Dim>(
    model: &Model<D>,
    st: &mut State<D>,
    sc: &mut Scratch<D>,
    loads: &[D::V],
) -> Acc {
    let geom = model.geom;
    let half = 0.5 * model.dt;
    let inv_h = 1.0 / geom.h;
    let h = geom.h;
    let mats = &model.mats;
    strips(model, st, sc, &|_s, first, p, mut g| {
        A::run(|| {
            let (geom, half, inv_h, h) = (geom, half, inv_h, h);
            let mut acc = Acc::default();
            p.assert_lengths();
            for i in 0..p.len() {
                let mech = p.mech[i];
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
                let c = p.wts[i];
                let st = Sten::new(&g, &geom, &c);
                let l = gather_l::<A, D>(&mut g, &geom, &st);
                let mat = &mats[mech.mat as usize];
                if !stress_apply::<A, D>(mat, &mut p.stress[i], &mut p.wden[i], l, half, inv_h) {
                    first_fail(&mut acc, first + i, FAIL_STRESS);
                }
                let s = p.stress[i];
                let nvs = -vs;
                each(&mut g, &geom, &st, true, |sh, gr, n| {
                    // f = −V σ·∇S.
                    let sg = D::stress_dot::<A>(&s, gr.as_ref());
                    let (nf, sg, fe) = (n.f.as_mut(), sg.as_ref(), fext.as_ref());
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
            }
            acc
        })
    })
}

/// Pass 3: FLIP particle update and re-extrapolation of the new momenta.
pub fn update<D: Dim>(model: &Model<D>, st: &mut State<D>, sc: &mut Scratch<D>) -> Acc {
    let loads = std::mem::take(&mut sc.load_now);
    let acc = by_kernel!(model.kernel, update_k(model, st, sc, &loads));
    sc.load_now = loads;
    acc
}

fn update_k<A: Arith, D: Dim>(
    model: &Model<D>,
    st: &mut State<D>,
    sc: &mut Scratch<D>,
    loads: &[D::V],
) -> Acc {
    let geom = model.geom;
    let dt = model.dt;
    let h = geom.h;
    strips(model, st, sc, &|s, first, p, mut g| {
        A::run(|| {
            let (dt, h) = (dt, h);
            let hdt = 0.5 * dt;
            let mut acc = Acc::default();
            p.assert_lengths();
            let lo = (s * STRIP) as i64 - 1;
            let hi = ((s + 1) * STRIP) as i64;
            for i in 0..p.len() {
                let k = p.kin[i];
                let mech = p.mech[i];
                let c = p.wts[i];
                let mut acc_p = D::V::default();
                let mut vbar = D::V::default();
                let st = Sten::new(&g, &geom, &c);
                each(&mut g, &geom, &st, false, |sh, _, n| {
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
                    let mut out = false;
                    for d in 0..D::N {
                        let x = xi.as_ref()[d];
                        let nc = (geom.n.as_ref()[d] - 1) as i64;
                        if x < 1.0 || x as i64 + 1 >= nc {
                            out = true;
                        }
                    }
                    if out {
                        first_fail(&mut acc, first + i, FAIL_GRID);
                    }
                    let cx = xi.as_ref()[0] as i64;
                    if cx < lo || cx > hi {
                        acc.resort = true;
                    }
                }
                p.kin[i].v = v;
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
                    // Work on the grid: F · v̄ Δt with v̄ the mid-step velocity at the particle.
                    let mut tv = 0.0;
                    for d in 0..D::N {
                        tv += t.as_ref()[d] * vbar.as_ref()[d];
                    }
                    acc.w += a * tv * dt;
                }
                // Re-extrapolate momentum with the same weights (pitfall 2).
                let mut mv = D::V::default();
                for d in 0..D::N {
                    mv.as_mut()[d] = mech.m * v.as_ref()[d];
                }
                each(&mut g, &geom, &st, false, |sh, _, n| {
                    let q = n.q.as_mut();
                    for d in 0..D::N {
                        q[d] = madd::<A>(sh, mv.as_ref()[d], q[d]);
                    }
                });
            }
            acc
        })
    })
}

/// Pass 4: velocity gradient from the re-extrapolated momenta, second stress half-update,
/// strain energy summed.
pub fn strain<D: Dim>(model: &Model<D>, st: &mut State<D>, sc: &mut Scratch<D>) -> Acc {
    by_kernel!(model.kernel, strain_k(model, st, sc))
}

fn strain_k<A: Arith, D: Dim>(model: &Model<D>, st: &mut State<D>, sc: &mut Scratch<D>) -> Acc {
    let geom = model.geom;
    let half = 0.5 * model.dt;
    let inv_h = 1.0 / geom.h;
    let mats = &model.mats;
    strips(model, st, sc, &|_s, first, p, mut g| {
        A::run(|| {
            let (half, inv_h) = (half, inv_h);
            let mut acc = Acc::default();
            p.assert_lengths();
            for i in 0..p.len() {
                let mech = p.mech[i];
                let c = p.wts[i];
                let st = Sten::new(&g, &geom, &c);
                let l = gather_l::<A, D>(&mut g, &geom, &st);
                let mat = &mats[mech.mat as usize];
                if !stress_apply::<A, D>(mat, &mut p.stress[i], &mut p.wden[i], l, half, inv_h) {
                    first_fail(&mut acc, first + i, FAIL_STRESS);
                }
                acc.e += mech.vol * p.wden[i];
            }
            acc
        })
    })
}

/// Pass 4 fused with pass 1 of the next step: per particle, the second stress half-update
/// from the current grid, then the new weights and the P2G into the spare grid
/// (`Scratch::nodes_alt`, zeroed where it was written). Per node the P2G sums run in the
/// same particle and strip order as an unfused P2G, so the results are bitwise identical
/// (`tests/fused.rs`). Returns the reductions of pass 4 and of the next step's P2G.
pub fn strain_p2g<D: Dim>(model: &Model<D>, st: &mut State<D>, sc: &mut Scratch<D>) -> (Acc, Acc) {
    by_kernel!(model.kernel, strain_p2g_k(model, st, sc))
}

fn strain_p2g_k<A: Arith, D: Dim>(
    model: &Model<D>,
    st: &mut State<D>,
    sc: &mut Scratch<D>,
) -> (Acc, Acc) {
    let geom = model.geom;
    let shape = model.shape;
    let half = 0.5 * model.dt;
    let inv_h = 1.0 / geom.h;
    let mats = &model.mats;
    let f = |_s: usize,
             first: usize,
             mut p: PartsMut<'_, D>,
             (mut gc, mut gn): (GridMut<'_, D>, GridMut<'_, D>)| {
        A::run(|| {
            let (geom, shape, half, inv_h) = (geom, shape, half, inv_h);
            let mut acc = Acc::default();
            let mut next = Acc::default();
            p.assert_lengths();
            let mut lq = (f64::NAN, f64::NAN);
            for i in 0..p.len() {
                let mech = p.mech[i];
                let c = p.wts[i];
                let st = Sten::new(&gc, &geom, &c);
                let l = gather_l::<A, D>(&mut gc, &geom, &st);
                let mat = &mats[mech.mat as usize];
                if !stress_apply::<A, D>(mat, &mut p.stress[i], &mut p.wden[i], l, half, inv_h) {
                    first_fail(&mut acc, first + i, FAIL_STRESS);
                }
                acc.e += mech.vol * p.wden[i];
                p2g_particle::<A, D>(&geom, shape, &mut p, i, first, &mut lq, &mut gn, &mut next);
            }
            (acc, next)
        })
    };
    let bounds = &st.strip_bounds;
    let mut out = (Acc::default(), Acc::default());
    for colour in 0..2 {
        let cur = GridMut::single(&mut sc.nodes);
        let nxt = GridMut::single(&mut sc.nodes_alt);
        let parts = PartsMut::new(&mut st.parts);
        let a: (Acc, Acc) = for_strips(&geom, bounds, colour, parts, (cur, nxt), &|s, p, g| {
            f(s, bounds[s], p, g)
        });
        out = if colour == 0 { a } else { out.merge(a) };
    }
    out
}
