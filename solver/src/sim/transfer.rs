//! The four particle passes of a step (`algorithm.md` §2, USAVG), each written once over the
//! particle's [`Stencil`] and run strip by strip (even colour, then odd: `grid::for_strips`),
//! with their reductions merged in strip order:
//! 1. [`pass_p2g`](Simulation::pass_p2g): weights, mass, momentum and (with cracks)
//!    mass-weighted displacement to the grid.
//! 2. [`pass_forces`](Simulation::pass_forces): velocity gradient from p/m, first stress
//!    half-update, internal and external forces to the grid.
//! 3. [`pass_update`](Simulation::pass_update): FLIP velocity, position from the mid-step grid
//!    velocity, re-extrapolation of momentum with the same weights and fields (pitfall 2).
//! 4. [`pass_strain_last`](Simulation::pass_strain_last): velocity gradient from q/m, second
//!    stress half-update, positions committed.

use fracture_api::scene::ShapeFunction;

use super::Simulation;
use super::errors::{FAIL_GRID, FAIL_POSITION, FAIL_STRESS, FAIL_VELOCITY, first_fail};
use super::stencil::{Stencil, with_stencil};
use crate::grid::{GridGeom, GridMut, Reduce, STRIP, for_strips};
use crate::kernel::{Arith, Fma, Kernel, Portable, madd};
use crate::material::Elastic;
use crate::particles::PartsMut;
use crate::shape::{Cached2, CachedW2, Weights2, gimp_weights_1d};
use fracture_mpm::{Dim, Dim2};

/// Reduction of a particle pass: partial sums and the first offending particle.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Acc {
    /// Kinetic energy (pass 3) or strain energy (pass 4).
    pub(super) e: f64,
    /// External work of tractions (pass 3).
    pub(super) w: f64,
    /// A particle drifted too far from its strip: re-sort before the next scatter.
    pub(super) resort: bool,
    /// First failure: (sorted index, kind).
    pub(super) fail: Option<(usize, u8)>,
    /// Active box in node columns/rows.
    pub(super) bx: [i64; 4],
    /// Whether `bx` is set.
    pub(super) has_box: bool,
}

impl Reduce for Acc {
    fn merge(self, r: Self) -> Self {
        let bx = match (self.has_box, r.has_box) {
            (true, true) => [
                self.bx[0].min(r.bx[0]),
                self.bx[1].max(r.bx[1]),
                self.bx[2].min(r.bx[2]),
                self.bx[3].max(r.bx[3]),
            ],
            (true, false) => self.bx,
            _ => r.bx,
        };
        Acc {
            e: self.e + r.e,
            w: self.w + r.w,
            resort: self.resort || r.resort,
            fail: match (self.fail, r.fail) {
                (Some(a), Some(b)) => Some(if a.0 <= b.0 { a } else { b }),
                (a, b) => a.or(b),
            },
            bx,
            has_box: self.has_box || r.has_box,
        }
    }
}

/// Accumulate the stencil's contribution into the active box of `acc`.
#[inline(always)]
fn grow_box(acc: &mut Acc, w: &CachedW2) {
    let (bx, by) = (w[0].base as i64, w[1].base as i64);
    if acc.has_box {
        acc.bx[0] = acc.bx[0].min(bx);
        acc.bx[1] = acc.bx[1].max(bx + 2);
        acc.bx[2] = acc.bx[2].min(by);
        acc.bx[3] = acc.bx[3].max(by + 2);
    } else {
        acc.bx = [bx, bx + 2, by, by + 2];
        acc.has_box = true;
    }
}

/// L = Σ v ⊗ ∇S over the stencil, from the nodal velocities (`Node::v`) of the particle's own
/// fields (pitfall 3); unscaled (cell units), as `stress_apply` takes it.
#[inline(always)]
fn gather_l<A: Arith>(st: &mut impl Stencil) -> [[f64; 2]; 2] {
    let mut l = [[0.0; 2]; 2];
    st.each(|_, g, n| {
        l[0][0] = madd::<A>(n.v[0], g[0], l[0][0]);
        l[0][1] = madd::<A>(n.v[0], g[1], l[0][1]);
        l[1][0] = madd::<A>(n.v[1], g[0], l[1][0]);
        l[1][1] = madd::<A>(n.v[1], g[1], l[1][1]);
    });
    l
}

/// The stress half-update of one particle of material `mat` from the unscaled velocity
/// gradient `l` (Σ v ⊗ ∇S in cell units): stress, strain energy density `w` and, with cracks,
/// the displacement gradient `grad_u` accumulated. Returns whether the new stress is finite.
#[inline(always)]
fn stress_apply<A: Arith>(
    mat: &Elastic,
    stress: &mut [f64; 4],
    w: &mut f64,
    grad_u: Option<&mut [f64; 4]>,
    mut l: [[f64; 2]; 2],
    half: f64,
    inv_h: f64,
) -> bool {
    for r in &mut l {
        r[0] *= inv_h;
        r[1] *= inv_h;
    }
    *w += Dim2::stress_update::<A>(mat, stress, &[l[0][0], l[0][1], l[1][0], l[1][1]], half);
    if let Some(gu) = grad_u {
        gu[0] = madd::<A>(l[0][0], half, gu[0]);
        gu[1] = madd::<A>(l[0][1], half, gu[1]);
        gu[2] = madd::<A>(l[1][0], half, gu[2]);
        gu[3] = madd::<A>(l[1][1], half, gu[3]);
    }
    let s = *stress;
    s[0].is_finite() && s[1].is_finite() && s[2].is_finite()
}

/// What the P2G of one particle needs from the simulation (copied into each strip's loop).
#[derive(Clone, Copy)]
pub(super) struct P2gCx {
    geom: GridGeom,
    shape: ShapeFunction,
    gimp: bool,
    field0_ok: bool,
    cracks: bool,
}

impl P2gCx {
    pub(super) fn new(sim: &Simulation) -> P2gCx {
        let gimp = sim.shape == ShapeFunction::Gimp;
        P2gCx {
            geom: sim.geom,
            shape: sim.shape,
            gimp,
            field0_ok: gimp && !sim.generic_stencil,
            cracks: sim.cracks.is_some(),
        }
    }

    /// The weights of a particle at `x` of half-width `lh` (`lq`: the last half-width seen and
    /// its 1/(4l)).
    #[inline(always)]
    fn weights(&self, x: [f64; 2], lh: f64, lq: &mut (f64, f64)) -> Weights2 {
        let xi = self.geom.xi(&x);
        if self.gimp {
            if lh != lq.0 {
                *lq = (lh, 0.25 / lh);
            }
            Weights2 {
                x: gimp_weights_1d(xi[0], lh, lq.1),
                y: gimp_weights_1d(xi[1], lh, lq.1),
            }
        } else {
            Weights2::new(self.shape, xi, lh)
        }
    }
}

/// P2G of particle `i`: its weights (cached in `p.wts` for the step's later passes), mass,
/// momentum and (with cracks) mass-weighted displacement scattered to `g`. `lq` holds the
/// last half-width seen and its 1/(4l).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn p2g_particle<A: Arith>(
    cx: &P2gCx,
    p: &mut PartsMut<'_>,
    i: usize,
    first: usize,
    lq: &mut (f64, f64),
    g: &mut GridMut<'_>,
    slot_of: &[u32],
    acc: &mut Acc,
) {
    let geom = &cx.geom;
    let k = p.kin[i];
    let m = p.mech[i].m;
    // The weights the later passes will read back from the cache (`CachedW2`), used here too
    // so that all four passes see the same S and ∇S.
    let packed = CachedW2::pack(&cx.weights(k.x, p.mech[i].lh, lq));
    p.wts[i] = packed;
    let w = &packed;
    grow_box(acc, w);
    let cracks = cx.cracks;
    let (mask, disp) = if cracks {
        let x0 = p.cold[i].x0;
        (p.fmask[i], [k.x[0] - x0[0], k.x[1] - x0[1]])
    } else {
        (0, [0.0; 2])
    };
    if !(k.v[0].is_finite() && k.v[1].is_finite()) {
        first_fail(acc, first + i, FAIL_VELOCITY);
    }
    let mv = [m * k.v[0], m * k.v[1]];
    let field0 = cx.field0_ok && mask == 0;
    with_stencil!(field0, g, geom, w, mask, slot_of, |st| {
        st.each_weighted(|s, _, n| {
            n.m = madd::<A>(s, m, n.m);
            n.p[0] = madd::<A>(s, mv[0], n.p[0]);
            n.p[1] = madd::<A>(s, mv[1], n.p[1]);
            if cracks {
                let sm = s * m;
                n.u[0] = madd::<A>(sm, disp[0], n.u[0]);
                n.u[1] = madd::<A>(sm, disp[1], n.u[1]);
            }
        })
    });
}

impl Simulation {
    /// Run `f` on every strip (even colour, then odd) and merge the results in strip order.
    fn strips<F>(&mut self, f: &F) -> Acc
    where
        F: Fn(usize, usize, PartsMut<'_>, GridMut<'_>) -> Acc + Sync,
    {
        let geom = self.geom;
        let mut out = Acc::default();
        for colour in 0..2 {
            let grid = GridMut {
                nodes: &mut self.nodes,
                base: 0,
                f1: &mut self.f1,
                f1_index: &self.f1_index,
                f1_base: 0,
            };
            let parts = PartsMut::new(&mut self.parts);
            let bounds = &self.strip_bounds;
            let a: Acc = for_strips(&geom, bounds, colour, parts, grid, &|s, p, g| {
                f(s, bounds[s], p, g)
            });
            out = if colour == 0 { a } else { out.merge(a) };
        }
        out
    }

    /// Pass 1: P2G of mass, momentum and (with cracks) mass-weighted displacement.
    pub(super) fn pass_p2g(&mut self) -> Acc {
        match self.kernel {
            Kernel::Portable => self.pass_p2g_k::<Portable>(),
            Kernel::Fma => self.pass_p2g_k::<Fma>(),
        }
    }

    fn pass_p2g_k<A: Arith>(&mut self) -> Acc {
        let cx = P2gCx::new(self);
        let slot_of = std::mem::take(&mut self.slot_of);
        let acc = self.strips(&|_s, first, mut p, mut g| {
            A::run(|| {
                // Locals, not the closure's captured references: read through those, the
                // values are reloaded after every node store (the compiler cannot rule out
                // aliasing), which costs the passes up to 8 % of their instructions.
                #[allow(clippy::redundant_locals)]
                let cx = cx;
                let mut acc = Acc::default();
                p.assert_lengths();
                // 1/(4l) of the last particle size seen (all particles of a body share it).
                let mut lq = (f64::NAN, f64::NAN);
                for i in 0..p.len() {
                    p2g_particle::<A>(&cx, &mut p, i, first, &mut lq, &mut g, &slot_of, &mut acc);
                }
                acc
            })
        });
        self.slot_of = slot_of;
        acc
    }

    /// Pass 2: velocity gradient from p/m, first stress half-update, forces to the grid.
    pub(super) fn pass_forces(&mut self) -> Acc {
        match self.kernel {
            Kernel::Portable => self.pass_forces_k::<Portable>(),
            Kernel::Fma => self.pass_forces_k::<Fma>(),
        }
    }

    fn pass_forces_k<A: Arith>(&mut self) -> Acc {
        let geom = self.geom;
        let field0_ok = self.shape == ShapeFunction::Gimp && !self.generic_stencil;
        let half = 0.5 * self.dt;
        let inv_h = 1.0 / geom.h;
        let h = geom.h;
        let slot_of = std::mem::take(&mut self.slot_of);
        let mats = std::mem::take(&mut self.mats);
        let loads = std::mem::take(&mut self.load_now);
        let acc = self.strips(&|_s, first, p, mut g| {
            A::run(|| {
                // Locals, not captured references (see `pass_p2g`).
                let (field0_ok, half, inv_h, h) = (field0_ok, half, inv_h, h);
                let mut acc = Acc::default();
                p.assert_lengths();
                let has_mask = !p.fmask.is_empty();
                for i in 0..p.len() {
                    let mech = p.mech[i];
                    let mask = if has_mask { p.fmask[i] } else { 0 };
                    // External force: traction × edge length (2l = h/ppc) × thickness.
                    let loaded = mech.load > 0;
                    let fext = if loaded {
                        let t = loads[mech.load as usize - 1];
                        let edge = 2.0 * mech.lh * h;
                        [t[0] * edge, t[1] * edge]
                    } else {
                        [0.0; 2]
                    };
                    let vs = mech.vol * inv_h;
                    let field0 = field0_ok && mask == 0;
                    let wi = p.wts[i];
                    with_stencil!(field0, &mut g, &geom, &wi, mask, &slot_of, |st| {
                        let l = gather_l::<A>(&mut st);
                        let mat = &mats[mech.mat as usize];
                        let gu = p.grad_u.get_mut(i);
                        let (stress, w) = (&mut p.stress[i], &mut p.wden[i]);
                        if !stress_apply::<A>(mat, stress, w, gu, l, half, inv_h) {
                            first_fail(&mut acc, first + i, FAIL_STRESS);
                        }
                        let s = p.stress[i];
                        let nvs = -vs;
                        st.each_weighted(|sh, gr, n| {
                            // f = −V σ·∇S (the sums inside the parentheses of −V(σ·∇S)).
                            let sg = [
                                madd::<A>(s[0], gr[0], s[2] * gr[1]),
                                madd::<A>(s[2], gr[0], s[1] * gr[1]),
                            ];
                            // Without a load S·0 = +0 would change nothing (sums start at +0 and
                            // never become −0), so the unloaded particle skips it.
                            if loaded {
                                n.f[0] += madd::<A>(sh, fext[0], nvs * sg[0]);
                                n.f[1] += madd::<A>(sh, fext[1], nvs * sg[1]);
                            } else {
                                n.f[0] = madd::<A>(nvs, sg[0], n.f[0]);
                                n.f[1] = madd::<A>(nvs, sg[1], n.f[1]);
                            }
                        });
                    });
                }
                acc
            })
        });
        self.slot_of = slot_of;
        self.mats = mats;
        self.load_now = loads;
        acc
    }

    /// Pass 3: FLIP particle update and re-extrapolation of the new momenta with the same
    /// weights and fields.
    pub(super) fn pass_update(&mut self) -> Acc {
        match self.kernel {
            Kernel::Portable => self.pass_update_k::<Portable>(),
            Kernel::Fma => self.pass_update_k::<Fma>(),
        }
    }

    fn pass_update_k<A: Arith>(&mut self) -> Acc {
        let geom = self.geom;
        let field0_ok = self.shape == ShapeFunction::Gimp && !self.generic_stencil;
        let dt = self.dt;
        let h = geom.h;
        let slot_of = std::mem::take(&mut self.slot_of);
        let loads = std::mem::take(&mut self.load_now);
        let (ncx, ncy) = ((geom.nx() - 1) as i64, (geom.ny() - 1) as i64);
        let acc = self.strips(&|s, first, p, mut g| {
            A::run(|| {
                // Locals, not captured references (see `pass_p2g`).
                let (field0_ok, dt, h) = (field0_ok, dt, h);
                let hdt = 0.5 * dt;
                let mut acc = Acc::default();
                p.assert_lengths();
                let has_mask = !p.fmask.is_empty();
                let lo = (s * STRIP) as i64 - 1;
                let hi = ((s + 1) * STRIP) as i64;
                for i in 0..p.len() {
                    let k = p.kin[i];
                    let mech = p.mech[i];
                    let w = &p.wts[i];
                    let mask = if has_mask { p.fmask[i] } else { 0 };
                    let field0 = field0_ok && mask == 0;
                    with_stencil!(field0, &mut g, &geom, w, mask, &slot_of, |st| {
                        let mut acc_p = [0.0; 2];
                        let mut vbar = [0.0; 2];
                        st.each(|sh, _, n| {
                            for c in 0..2 {
                                let an = sh * n.a[c];
                                acc_p[c] += an;
                                // (v_old + v_new)/2 = p/m + Δt/2 · f/m
                                vbar[c] += madd::<A>(sh, n.v[c], hdt * an);
                            }
                        });
                        let v_old = k.v;
                        let v = [
                            madd::<A>(dt, acc_p[0], v_old[0]),
                            madd::<A>(dt, acc_p[1], v_old[1]),
                        ];
                        let xn = [
                            madd::<A>(dt, vbar[0], k.x[0]),
                            madd::<A>(dt, vbar[1], k.x[1]),
                        ];
                        if !(v[0].is_finite() && v[1].is_finite()) {
                            first_fail(&mut acc, first + i, FAIL_VELOCITY);
                        } else if !(xn[0].is_finite() && xn[1].is_finite()) {
                            first_fail(&mut acc, first + i, FAIL_POSITION);
                        } else {
                            // Truncation (not floor): negative ξ gives 0 and is caught as < 1 too.
                            let xi = geom.xi(&xn);
                            let (cx, cy) = (xi[0] as i64, xi[1] as i64);
                            if xi[0] < 1.0 || xi[1] < 1.0 || cx + 1 >= ncx || cy + 1 >= ncy {
                                first_fail(&mut acc, first + i, FAIL_GRID);
                            }
                            if cx < lo || cx > hi {
                                acc.resort = true;
                            }
                        }
                        p.kin[i].v = v;
                        // The position is committed here: nothing between this pass and the
                        // last stress update reads it (that pass and the fused P2G use the
                        // cached weights and, for the P2G, this new position). A non-finite
                        // one is not written, so the step's error names the last good one.
                        if xn[0].is_finite() && xn[1].is_finite() {
                            p.kin[i].x = xn;
                        }
                        acc.e += 0.5 * mech.m * (v[0] * v[0] + v[1] * v[1]);
                        if mech.load > 0 {
                            let t = loads[mech.load as usize - 1];
                            let edge = 2.0 * mech.lh * h;
                            // Work on the grid: F · v̄ Δt with v̄ the mid-step grid velocity at the
                            // particle (the velocity that moves it), consistent with the grid's
                            // energy.
                            acc.w += edge * (t[0] * vbar[0] + t[1] * vbar[1]) * dt;
                        }
                        // Re-extrapolate momentum with the same weights and fields (pitfall 2).
                        let mv = [mech.m * v[0], mech.m * v[1]];
                        st.each(|sh, _, n| {
                            n.q[0] = madd::<A>(sh, mv[0], n.q[0]);
                            n.q[1] = madd::<A>(sh, mv[1], n.q[1]);
                        });
                    });
                }
                acc
            })
        });
        self.slot_of = slot_of;
        self.load_now = loads;
        acc
    }

    /// Pass 4: velocity gradient from the re-extrapolated momenta, second stress half-update,
    /// positions committed, strain energy summed. Fused with the next step's P2G
    /// ([`pass_strain_last_p2g`](Simulation::pass_strain_last_p2g)) when nothing can fall
    /// between the two.
    pub(super) fn pass_strain_last(&mut self) -> Acc {
        if self.can_fuse() {
            let (acc, next) = self.pass_strain_last_p2g();
            self.prefetched = Some(next);
            return acc;
        }
        self.pass_strain_last_alone()
    }

    /// Whether pass 4 may run fused with the next step's P2G: no crack (the next step's
    /// velocity fields depend on the committed positions and the crack's motion), no re-sort
    /// due (it reorders the particles before the next P2G), fusion not switched off.
    /// Observers between the steps see the same particles and the same grid (`nodes`): the
    /// next step's P2G goes to the spare grid `nodes_alt`, swapped in when that step starts.
    fn can_fuse(&self) -> bool {
        self.fuse && self.cracks.is_none() && !self.needs_sort
    }

    /// Pass 4 fused with pass 1 of the next step: per particle, the second stress half-update
    /// from the current grid, the position committed, then the new weights and the P2G into
    /// the spare grid. Per node the P2G sums run in the same particle and strip order as an
    /// unfused P2G, so the results are bitwise identical (`tests/fused_step.rs`). Returns the
    /// reduction of pass 4 and that of the next step's P2G.
    pub(super) fn pass_strain_last_p2g(&mut self) -> (Acc, Acc) {
        match self.kernel {
            Kernel::Portable => self.pass_strain_last_p2g_k::<Portable>(),
            Kernel::Fma => self.pass_strain_last_p2g_k::<Fma>(),
        }
    }

    fn pass_strain_last_p2g_k<A: Arith>(&mut self) -> (Acc, Acc) {
        debug_assert!(self.cracks.is_none());
        let cx = P2gCx::new(self);
        let geom = self.geom;
        let field0_ok = cx.field0_ok;
        let half = 0.5 * self.dt;
        let inv_h = 1.0 / geom.h;
        let slot_of = std::mem::take(&mut self.slot_of);
        let mats = std::mem::take(&mut self.mats);
        self.zero_alt();
        let mut next = std::mem::take(&mut self.nodes_alt);
        let f = |_s: usize,
                 first: usize,
                 mut p: PartsMut<'_>,
                 mut gc: GridMut<'_>,
                 mut gn: GridMut<'_>| {
            A::run(|| {
                // Locals, not captured references (see `pass_p2g`).
                let (cx, field0_ok, half, inv_h) = (cx, field0_ok, half, inv_h);
                let mut acc = Acc::default();
                let mut acc_next = Acc::default();
                p.assert_lengths();
                let mut lq = (f64::NAN, f64::NAN);
                for i in 0..p.len() {
                    let mech = p.mech[i];
                    let wi = p.wts[i];
                    let ok = with_stencil!(field0_ok, &mut gc, &geom, &wi, 0, &slot_of, |st| {
                        let l = gather_l::<A>(&mut st);
                        let mat = &mats[mech.mat as usize];
                        stress_apply::<A>(
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
                    p2g_particle::<A>(
                        &cx,
                        &mut p,
                        i,
                        first,
                        &mut lq,
                        &mut gn,
                        &slot_of,
                        &mut acc_next,
                    );
                }
                (acc, acc_next)
            })
        };
        let mut out = (Acc::default(), Acc::default());
        for colour in 0..2 {
            let cur = GridMut {
                nodes: &mut self.nodes,
                base: 0,
                f1: &mut self.f1,
                f1_index: &self.f1_index,
                f1_base: 0,
            };
            let nxt = GridMut {
                nodes: &mut next,
                base: 0,
                f1: &mut [],
                f1_index: &[],
                f1_base: 0,
            };
            let parts = PartsMut::new(&mut self.parts);
            let bounds = &self.strip_bounds;
            let a: (Acc, Acc) = for_strips(
                &geom,
                bounds,
                colour,
                parts,
                (cur, nxt),
                &|s, p, (gc, gn)| f(s, bounds[s], p, gc, gn),
            );
            out = if colour == 0 { a } else { out.merge(a) };
        }
        self.nodes_alt = next;
        self.alt_box = self.box_of(&out.1);
        self.slot_of = slot_of;
        self.mats = mats;
        out
    }

    /// Pass 4 alone (see [`pass_strain_last`](Simulation::pass_strain_last)).
    fn pass_strain_last_alone(&mut self) -> Acc {
        match self.kernel {
            Kernel::Portable => self.pass_strain_last_alone_k::<Portable>(),
            Kernel::Fma => self.pass_strain_last_alone_k::<Fma>(),
        }
    }

    fn pass_strain_last_alone_k<A: Arith>(&mut self) -> Acc {
        let geom = self.geom;
        let field0_ok = self.shape == ShapeFunction::Gimp && !self.generic_stencil;
        let half = 0.5 * self.dt;
        let inv_h = 1.0 / geom.h;
        let slot_of = std::mem::take(&mut self.slot_of);
        let mats = std::mem::take(&mut self.mats);
        let acc = self.strips(&|_s, first, p, mut g| {
            A::run(|| {
                // Locals, not captured references (see `pass_p2g`).
                let (field0_ok, half, inv_h) = (field0_ok, half, inv_h);
                let mut acc = Acc::default();
                p.assert_lengths();
                let has_mask = !p.fmask.is_empty();
                for i in 0..p.len() {
                    let mech = p.mech[i];
                    let mask = if has_mask { p.fmask[i] } else { 0 };
                    let field0 = field0_ok && mask == 0;
                    let wi = p.wts[i];
                    let ok = with_stencil!(field0, &mut g, &geom, &wi, mask, &slot_of, |st| {
                        let l = gather_l::<A>(&mut st);
                        let mat = &mats[mech.mat as usize];
                        let gu = p.grad_u.get_mut(i);
                        stress_apply::<A>(mat, &mut p.stress[i], &mut p.wden[i], gu, l, half, inv_h)
                    });
                    if !ok {
                        first_fail(&mut acc, first + i, FAIL_STRESS);
                    }
                    acc.e += mech.vol * p.wden[i];
                }
                acc
            })
        });
        self.slot_of = slot_of;
        self.mats = mats;
        acc
    }
}
