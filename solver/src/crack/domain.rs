//! The equivalent domain integral for J and the interaction integral for K (`algorithm.md`
//! §6; Li, Shih & Needleman 1985, Moran & Shih 1987; Yau, Wang & Corten 1980).
//!
//! Over a ring around the tip with the weight q = 1 for r ≤ R/2, falling smoothly to 0 at
//! r = R (R a physical radius, so a finer grid puts more cells in the same ring), summed over
//! the particles (dA = particle area, every particle with its own velocity field's values):
//!
//! J_k = Σ dA {[σ_ij ∂u_i/∂x_k − (W + ½ρ|u̇|²) δ_jk] ∂q/∂x_j + ρ[ü_i ∂u_i/∂x_k − u̇_i ∂u̇_i/∂x_k] q}
//!       − Σ_faces q t_i ∂u_i/∂x_k ds,
//!
//! the last term over the two-field nodes where the crack faces carry a contact force (the
//! force-stage contact force of each side, with that side's nodal ∂u/∂x); ü and ∂u̇/∂x come
//! from the particle's own field's nodes (f/m and the re-extrapolated q/m). The area term is
//! taken over A − A_ε ([`INERTIA_EXCLUSION_CELLS`], weight w), and along the tip's direction
//! e1 the kinetic pair is integrated by parts ([`kinetic_along_tip`]) where the ring's crack
//! runs along e1 ([`BY_PARTS_STRAIGHTNESS_DEG`]):
//! ∫ −½ρ|u̇|² ∂q/∂x1 − w q ρ u̇·∂u̇/∂x1 dA = ∫ ½ρ|u̇|² [(w − 1) ∂q/∂x1 + q ∂w/∂x1] dA.
//!
//! The interaction integral with the auxiliary Williams fields of unit K in the tip frame
//! (x1 ahead), M = Σ dA {[σ_ij ∂u^a_i/∂x1 + σ^a_ij ∂u_i/∂x1 − σ^a_ij ε_ij δ_1j] ∂q/∂x_j +
//! ρ ü_i ∂u^a_i/∂x1 q}, gives K = E'·M/2 for each mode.
//!
//! A ring that leaves the grid or the material (a point of its outer circle on a node
//! without mass) gives NaN: the result is flagged, never a silent 0.

use std::collections::BTreeMap;

use crate::grid::STRIP;
use crate::shape::Weights2;
use crate::tip_mechanics::{Mode, TipMedium, williams, williams_du_dx1};

use super::{Cracks, View};
pub(super) use fracture_mpm::fracture::domain::{
    BY_PARTS_STRAIGHTNESS_DEG, INERTIA_EXCLUSION_CELLS, inertia_weight, inertia_weight_dr,
    kinetic_along_tip, ring,
};

/// What one pass over the particles around a tip gives.
#[derive(Debug, Clone, Copy)]
pub(super) struct DomainResult {
    /// J (global x, y) for each requested radius; NaN where the ring is not inside the body.
    pub(super) j: [[f64; 2]; 3],
    /// (K_I, K_II) from the interaction integral at the first radius; NaN if not defined.
    pub(super) k: [f64; 2],
}

/// Whether the ring of outer radius `r` around `tip` lies inside the grid and the material:
/// each of 32 points of its outer circle falls within the grid next to a node that carries
/// mass in some field.
pub(super) fn ring_fits(v: &View<'_>, tip: [f64; 2], r: f64) -> bool {
    let g = v.geom;
    if !(r.is_finite() && r > 0.0) {
        return false;
    }
    (0..32).all(|i| {
        let a = f64::from(i) * std::f64::consts::PI / 16.0;
        let xi = g.xi(&[tip[0] + r * a.cos(), tip[1] + r * a.sin()]);
        let (ix, iy) = (xi[0].round(), xi[1].round());
        if ix < 1.0 || iy < 1.0 || ix + 1.0 >= g.nx() as f64 || iy + 1.0 >= g.ny() as f64 {
            return false;
        }
        let (ix, iy) = (ix as usize, iy as usize);
        v.node(ix, iy, 0).is_some_and(|n| n.m > 0.0) || v.node(ix, iy, 1).is_some_and(|n| n.m > 0.0)
    })
}

/// Face-term accumulator of one two-field node: Σ S m ∂u/∂x and Σ S m per field.
#[derive(Debug, Clone, Copy, Default)]
struct FaceNode {
    gu: [[f64; 4]; 2],
    m: [f64; 2],
}

impl Cracks {
    /// Domain J at `radii` and the interaction-integral K at `radii[0]` of crack `ci` for
    /// rings centred at `tip` with the frame e1 (ahead): a tip's own frame, or the vertex of
    /// a short kink with the parent crack's frame (`j_integral.rs`).
    pub(super) fn domain_integrals(
        &self,
        ci: usize,
        (tip, e1): ([f64; 2], [f64; 2]),
        v: &View<'_>,
        radii: [f64; 3],
        medium: &TipMedium,
    ) -> DomainResult {
        let g = v.geom;
        let h = g.h;
        let e2 = [-e1[1], e1[0]];
        let r_max = radii.iter().fold(0.0_f64, |a, &b| a.max(b));
        let nan = [f64::NAN; 2];

        let ok = radii.map(|r| ring_fits(v, tip, r));
        if !ok.iter().any(|&o| o) {
            return DomainResult {
                j: [nan; 3],
                k: nan,
            };
        }

        // Whether every crack segment reaching into each ring lies along e1 (within
        // `BY_PARTS_STRAIGHTNESS_DEG`): then the kinetic pair is summed by parts.
        let sin_tol = BY_PARTS_STRAIGHTNESS_DEG.to_radians().sin();
        let straight = radii.map(|big_r| {
            self.cracks.iter().enumerate().all(|(cj, other)| {
                other.pts.windows(2).all(|s| {
                    let (a, b) = (s[0].x, s[1].x);
                    let d = [b[0] - a[0], b[1] - a[1]];
                    let l = d[0].hypot(d[1]);
                    // The segment's closest point to the tip.
                    let u = if l > 0.0 {
                        (((tip[0] - a[0]) * d[0] + (tip[1] - a[1]) * d[1]) / (l * l))
                            .clamp(0.0, 1.0)
                    } else {
                        0.0
                    };
                    let c = [a[0] + u * d[0] - tip[0], a[1] + u * d[1] - tip[1]];
                    if c[0].hypot(c[1]) >= big_r {
                        return true;
                    }
                    cj == ci && (l == 0.0 || (d[0] * e1[1] - d[1] * e1[0]).abs() <= sin_tol * l)
                })
            })
        });
        let p = v.parts;
        let xi_tip = g.xi(&tip);
        let reach = r_max / h + 3.0;
        let s_lo = ((xi_tip[0] - reach).max(0.0) as usize) / STRIP;
        let s_hi = (((xi_tip[0] + reach).max(0.0) as usize) / STRIP).min(g.strips - 1);
        let range = v.strip_bounds[s_lo]..v.strip_bounds[s_hi + 1];
        let has_mask = !p.fmask.is_empty();
        let faces = !self.face_force.is_empty();
        let mut face_nodes: BTreeMap<u32, (usize, FaceNode)> = BTreeMap::new();

        let mut j = [[0.0_f64; 2]; 3];
        let mut m_int = [0.0_f64; 2];
        // Particles up to 2h beyond the ring feed the face term's nodal gradients.
        let r_feed = r_max + 2.0 * h;
        // hypot(d) ≥ max(|d₀|, |d₁|) up to libm's error (under an ulp, far inside the 1e-9
        // margin): a particle this far along either axis fails `r < r_feed` without the call.
        let r_box = r_feed * (1.0 + 1e-9);
        // The disk left out of the inertial area term, per radius (`INERTIA_EXCLUSION_CELLS`).
        let eps = radii.map(|big_r| (INERTIA_EXCLUSION_CELLS * h).min(0.5 * big_r));
        for i in range {
            let k = p.kin[i];
            let d = [k.x[0] - tip[0], k.x[1] - tip[1]];
            if d[0].abs().max(d[1].abs()) > r_box {
                continue;
            }
            let r = d[0].hypot(d[1]);
            if r >= r_feed || r <= 0.0 {
                continue;
            }
            let m = p.mech[i];
            let s = p.stress[i];
            let gu = p.grad_u[i];
            let pxi = g.xi(&k.x);
            let w = Weights2::new(v.shape, pxi, m.lh);
            let mask = if has_mask { p.fmask[i] } else { 0 };
            let (acc, gv) = v.own_field_rates(&w, mask);
            // The face term's nodal ∂u/∂x of each side at the two-field nodes with a contact
            // force.
            if faces {
                for a in 0..3 {
                    for b in 0..3 {
                        let sh = w.s(a, b);
                        if sh <= 0.0 {
                            continue;
                        }
                        let ix = (w.x.base + a as i32) as usize;
                        let iy = (w.y.base + b as i32) as usize;
                        let idx = g.at(ix, iy);
                        if let Some(&slot) = v.slot_of.get(idx)
                            && slot != u32::MAX
                            && self
                                .face_force
                                .get(slot as usize)
                                .is_some_and(|f| f[0] != 0.0 || f[1] != 0.0)
                        {
                            let f = ((mask >> (3 * a + b)) & 1) as usize;
                            let e = face_nodes.entry(slot).or_insert((idx, FaceNode::default()));
                            e.1.m[f] += sh * m.m;
                            for q in 0..4 {
                                e.1.gu[f][q] += sh * m.m * gu[q];
                            }
                        }
                    }
                }
            }
            if r >= r_max {
                continue;
            }
            let rho = m.m / m.vol;
            let da = m.vol / self.thickness;
            let ke = 0.5 * rho * (k.v[0] * k.v[0] + k.v[1] * k.v[1]);
            let wden = p.wden[i];
            let sig = [[s[0], s[2]], [s[2], s[1]]];
            // ∂u_i/∂x_k = gu[2i + k].
            let gmat = [[gu[0], gu[1]], [gu[2], gu[3]]];
            let dir = [d[0] / r, d[1] / r];
            for (kr, &big_r) in radii.iter().enumerate() {
                if !ok[kr] {
                    continue;
                }
                let (q, dq_dr) = ring(r, big_r);
                if q == 0.0 && dq_dr == 0.0 {
                    continue;
                }
                let dq = [dq_dr * dir[0], dq_dr * dir[1]];
                // The inertial area term's weight over A − A_ε (smooth edge).
                let wi = inertia_weight(r, eps[kr]);
                for kk in 0..2 {
                    let mut term = 0.0;
                    for jj in 0..2 {
                        let mut sg = 0.0;
                        for ii in 0..2 {
                            sg += sig[ii][jj] * gmat[ii][kk];
                        }
                        if jj == kk {
                            sg -= wden;
                        }
                        term += sg * dq[jj];
                    }
                    let inertial = wi * rho * (acc[0] * gmat[0][kk] + acc[1] * gmat[1][kk]);
                    j[kr][kk] += da * (term + inertial * q);
                }
                if !straight[kr] {
                    // The pair as written: −ke ∂q/∂x_k − w q ρ u̇·∂u̇/∂x_k.
                    for kk in 0..2 {
                        let v_dv = k.v[0] * gv[0][kk] + k.v[1] * gv[1][kk];
                        j[kr][kk] += da * (-ke * dq[kk] - wi * q * rho * v_dv);
                    }
                } else {
                    // The kinetic pair in the tip frame: along e1 integrated by parts
                    // (`kinetic_along_tip`), along e2 as written, −ke ∂q/∂x2 − w q ρ u̇·∂u̇/∂x2.
                    let along = |a: [f64; 2], e: [f64; 2]| a[0] * e[0] + a[1] * e[1];
                    let k1 = kinetic_along_tip(
                        ke,
                        q,
                        along(dq, e1),
                        wi,
                        inertia_weight_dr(r, eps[kr]),
                        along(dir, e1),
                    );
                    let v_dv2 = k.v[0] * along(gv[0], e2) + k.v[1] * along(gv[1], e2);
                    let k2 = -ke * along(dq, e2) - wi * q * rho * v_dv2;
                    for kk in 0..2 {
                        j[kr][kk] += da * (k1 * e1[kk] + k2 * e2[kk]);
                    }
                }
                if kr == 0 {
                    // Interaction integral in the tip frame.
                    let rot =
                        |a: [f64; 2]| [a[0] * e1[0] + a[1] * e1[1], a[0] * e2[0] + a[1] * e2[1]];
                    let xl = rot(d);
                    let dql = rot(dq);
                    let al = rot(acc);
                    // σ' = R σ Rᵀ and G' = R G Rᵀ with R's rows e1, e2.
                    let rm = [e1, e2];
                    let mut sl = [[0.0; 2]; 2];
                    let mut gl = [[0.0; 2]; 2];
                    for a in 0..2 {
                        for b in 0..2 {
                            for c1 in 0..2 {
                                for c2 in 0..2 {
                                    sl[a][b] += rm[a][c1] * sig[c1][c2] * rm[b][c2];
                                    gl[a][b] += rm[a][c1] * gmat[c1][c2] * rm[b][c2];
                                }
                            }
                        }
                    }
                    let eps = [gl[0][0], gl[1][1], 0.5 * (gl[0][1] + gl[1][0])];
                    let th = xl[1].atan2(xl[0]);
                    for (mi, mode) in [Mode::I, Mode::II].into_iter().enumerate() {
                        let (_, sa) = williams(mode, r, th, medium);
                        let du = williams_du_dx1(mode, xl, medium);
                        let sa_m = [[sa[0], sa[2]], [sa[2], sa[1]]];
                        let w12 = sa[0] * eps[0] + sa[1] * eps[1] + 2.0 * sa[2] * eps[2];
                        let mut term = 0.0;
                        for jj in 0..2 {
                            let mut v_j = 0.0;
                            for ii in 0..2 {
                                v_j += sl[ii][jj] * du[ii] + sa_m[ii][jj] * gl[ii][0];
                            }
                            if jj == 0 {
                                v_j -= w12;
                            }
                            term += v_j * dql[jj];
                        }
                        let inertial = rho * (al[0] * du[0] + al[1] * du[1]);
                        m_int[mi] += da * (term + inertial * q);
                    }
                }
            }
        }

        // Crack-face traction term −Σ q t_i ∂u_i/∂x_k ds: the contact force on each side's
        // material (per the scene's thickness) with that side's nodal ∂u/∂x.
        for (slot, (idx, fnode)) in &face_nodes {
            let (ix, iy) = g.node_xy(*idx);
            let x = g.pos(ix, iy);
            let r = (x[0] - tip[0]).hypot(x[1] - tip[1]);
            let Some(info) = self.slots.get(*slot as usize) else {
                continue;
            };
            if info.crack == super::fields::BODY_CONTACT {
                continue;
            }
            let f_above = self.face_force[*slot as usize];
            let above = usize::from(info.above_is_f1);
            for side in 0..2 {
                if fnode.m[side] <= 0.0 {
                    continue;
                }
                let f = if side == above {
                    f_above
                } else {
                    [-f_above[0], -f_above[1]]
                };
                let gsum = fnode.gu[side];
                let gm = |q: usize| gsum[q] / fnode.m[side];
                for (kr, &big_r) in radii.iter().enumerate() {
                    if !ok[kr] {
                        continue;
                    }
                    let (q, _) = ring(r, big_r);
                    if q == 0.0 {
                        continue;
                    }
                    for kk in 0..2 {
                        j[kr][kk] -= q * (f[0] * gm(kk) + f[1] * gm(2 + kk)) / self.thickness;
                    }
                }
            }
        }

        let mut out = DomainResult {
            j: [nan; 3],
            k: nan,
        };
        for kr in 0..3 {
            if ok[kr] {
                out.j[kr] = j[kr];
            }
        }
        if ok[0] {
            out.k = [
                0.5 * medium.e_prime * m_int[0],
                0.5 * medium.e_prime * m_int[1],
            ];
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::{inertia_weight, inertia_weight_dr, kinetic_along_tip, ring};

    /// The kinetic pair integrated by parts equals the pair as written for a smooth field:
    /// ∫ −ke ∂q/∂x1 − w q ∂ke/∂x1 dA = ∫ ke [(w − 1) ∂q/∂x1 + q ∂w/∂x1] dA over the disk
    /// (midpoint rule, 1,200² points), for ke = (1 − x1/R + x1²/R²)(1 + 2 x2²/R²) — larger
    /// behind the tip than ahead, like a crack's wake — on rings where the disk's edge lies
    /// inside the plateau (R = 12 cells) and where it overlaps the ring (R = 6 cells).
    #[test]
    fn kinetic_pair_by_parts_matches_the_pair_as_written() {
        let h: f64 = 1.0;
        for big_r in [12.0 * h, 6.0 * h] {
            let eps = (3.0 * h).min(0.5 * big_r);
            let ke = |x: f64, y: f64| {
                (1.0 - x / big_r + x * x / (big_r * big_r)) * (1.0 + 2.0 * y * y / (big_r * big_r))
            };
            let dke_dx = |x: f64, y: f64| {
                (-1.0 / big_r + 2.0 * x / (big_r * big_r)) * (1.0 + 2.0 * y * y / (big_r * big_r))
            };
            let n = 1200;
            let d = 2.0 * big_r / n as f64;
            let (mut written, mut by_parts) = (0.0, 0.0);
            for i in 0..n {
                for k in 0..n {
                    let x = -big_r + (i as f64 + 0.5) * d;
                    let y = -big_r + (k as f64 + 0.5) * d;
                    let r = x.hypot(y);
                    if r >= big_r {
                        continue;
                    }
                    let (q, dq_dr) = ring(r, big_r);
                    let (w, dw) = (inertia_weight(r, eps), inertia_weight_dr(r, eps));
                    let dir1 = x / r;
                    let dq1 = dq_dr * dir1;
                    written += (-ke(x, y) * dq1 - w * q * dke_dx(x, y)) * d * d;
                    by_parts += kinetic_along_tip(ke(x, y), q, dq1, w, dw, dir1) * d * d;
                }
            }
            assert!(
                written.abs() > 1.0,
                "R = {big_r}: the test field gives no pair ({written})"
            );
            assert!(
                (by_parts / written - 1.0).abs() < 1e-3,
                "R = {big_r}: by parts {by_parts} vs as written {written}"
            );
        }
    }

    /// d/dr of the inertial weight is its derivative (central differences).
    #[test]
    fn inertia_weight_dr_is_the_derivative() {
        let eps = 3.0;
        for i in 1..60 {
            let r = 0.1 * i as f64;
            let fd = (inertia_weight(r + 1e-6, eps) - inertia_weight(r - 1e-6, eps)) / 2e-6;
            assert!((inertia_weight_dr(r, eps) - fd).abs() < 1e-6, "r {r}");
        }
    }
}
