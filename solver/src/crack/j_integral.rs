//! J-integral and stress intensity factors at each tip (`algorithm.md` §6; Guo & Nairn 2004):
//! the crack's J method (the domain integral of `domain.rs`, or the seed's contour with its
//! area term), the path-independence report (domain J at half and twice the radius), K_I and
//! K_II from the interaction integral for a tip at rest and from E'·J1 with Freund's A(v) and
//! the A-corrected opening ratio for a moving one (null at and above c_R), all cached per
//! sample time and rotated into the tip frame; the crack-tip rows.

use fracture_api::results::CrackTipRow;

use fracture_api::scene::{GrowthSpeed, JIntegral, Propagation};

use crate::grid::STRIP;
use crate::shape::Weights2;
use crate::tip_mechanics::{TipMedium, kinked_k};

use super::domain::ring_fits;
use super::geometry::{cross_param, crosses, dist, sub};
use super::{Cracks, View};

/// One edge of the J contour: from node, to node, outward normal.
type ContourEdge = ((usize, usize), (usize, usize), [f64; 2]);

/// J of one contour evaluation (global components).
#[derive(Debug, Clone, Copy, Default)]
struct TipJ {
    j: [f64; 2],
}

/// What one evaluation at a tip gives (global components), cached per sample time.
#[derive(Debug, Clone, Copy, serde::Serialize, serde::Deserialize)]
pub(super) struct TipEval {
    /// J by the crack's method; NaN where not defined.
    j: [f64; 2],
    /// Domain J at half and twice the radius (the path-independence report).
    j_half: [f64; 2],
    j_double: [f64; 2],
    /// (K_I, K_II) of the interaction integral.
    k_int: [f64; 2],
    /// The tip's medium (its nearest material).
    medium: TipMedium,
    /// The radius of the ring (m) J was taken on.
    #[serde(default)]
    radius: f64,
    /// For a tip on a kinked branch shorter than half the ring: the rings were centred on
    /// the kink's vertex in the parent crack's frame, and this is that frame's e1.
    #[serde(default)]
    parent_e1: Option<[f64; 2]>,
}

/// Where the J rings of a tip are centred.
#[derive(Debug, Clone, Copy)]
enum Centre {
    /// On the tip, in its own frame, with this ring radius.
    Tip(f64),
    /// On the vertex of a short kink, in the parent crack's frame (vertex, e1).
    Vertex([f64; 2], [f64; 2]),
}

/// The driving force of a tip on a short kinked branch, from the parent crack's J and K
/// measured around the kink's vertex (`algorithm.md` pitfall 15).
#[derive(Debug, Clone, Copy)]
pub(super) struct KinkDrive {
    /// The parent crack's direction at the vertex.
    pub(super) parent_e1: [f64; 2],
    /// J1 of the parent in its own frame (J/m²).
    pub(super) parent_j1: f64,
    /// (K_I, K_II) of the parent, K_I of closed faces taken as 0.
    pub(super) parent_k: [f64; 2],
}

impl KinkDrive {
    /// G of a kinked extension at θ from the parent's direction: the parent's J1 times
    /// |k(θ)|²/|K|² of Hussain, Pu & Underwood's kinked crack ([`kinked_k`]); with it
    /// (k1, k2) scaled so that (k1² + k2²)/E' is that G. None when the parent has no K.
    pub(super) fn at(&self, th: f64, e_prime: f64) -> Option<(f64, [f64; 2])> {
        let [a, b] = self.parent_k;
        let k2 = a * a + b * b;
        if !(k2.is_finite() && k2 > 0.0 && self.parent_j1.is_finite()) {
            return None;
        }
        let (ka, kb) = kinked_k(a, b, th);
        let j = self.parent_j1.max(0.0);
        let scale = (j * e_prime / k2).sqrt();
        Some((j * (ka * ka + kb * kb) / k2, [ka * scale, kb * scale]))
    }
}

/// J of a tip in its own frame (e1 ahead along the crack, e2 to its left), with K.
#[derive(Debug, Clone, Copy)]
pub(super) struct TipFrameJ {
    pub(super) tip: [f64; 2],
    pub(super) e1: [f64; 2],
    pub(super) e2: [f64; 2],
    pub(super) j1: f64,
    pub(super) j2: f64,
    /// (J1, J2) of the domain at half and twice the radius.
    pub(super) j_half: [f64; 2],
    pub(super) j_double: [f64; 2],
    /// (K_I, K_II) of the interaction integral.
    pub(super) k_int: [f64; 2],
    /// The tip's medium (its nearest material).
    pub(super) medium: TipMedium,
    /// Set for a tip on a kinked branch shorter than half its ring: J1 and K above are then
    /// the kinked tip's, from the parent's field at the vertex.
    pub(super) kink: Option<KinkDrive>,
}

impl Cracks {
    /// Dynamic J (global components) at tip `t` of crack `ci`: contour plus area term.
    fn compute_j(&self, ci: usize, t: usize, v: &View<'_>) -> TipJ {
        let g = v.geom;
        let h = g.h;
        let c = &self.cracks[ci];
        let (tip, _) = c.tip_frame(t, h);
        let n = match c.j_method {
            JIntegral::Contour { cells } => i64::from(cells.max(1)),
            JIntegral::Domain { radius } => (radius / h).round().max(1.0) as i64,
        };
        let xi = g.xi(&tip);
        let (c0, r0) = (xi[0].round() as i64, xi[1].round() as i64);
        // Window of nodes around the contour.
        let (wx0, wy0) = (c0 - n - 1, r0 - n - 1);
        let wn = (2 * n + 3) as usize;
        if wx0 < 0 || wy0 < 0 || wx0 as usize + wn > g.nx() || wy0 as usize + wn > g.ny() {
            // The contour leaves the grid: J is not defined (null in the output), never 0.
            return TipJ { j: [f64::NAN; 2] };
        }
        let (wx0, wy0) = (wx0 as usize, wy0 as usize);
        const NV: usize = 9;
        let mut mass = vec![0.0f64; wn * wn];
        let mut vals = vec![0.0f64; wn * wn * NV];
        let mut area = [0.0f64; 2];
        let box_lo = [(c0 - n) as f64, (r0 - n) as f64];
        let box_hi = [(c0 + n) as f64, (r0 + n) as f64];
        let p = v.parts;
        let s_lo = ((wx0 as i64 - 5).max(0) as usize) / STRIP;
        let s_hi = ((wx0 + wn + 5) / STRIP).min(g.strips - 1);
        let range = v.strip_bounds[s_lo]..v.strip_bounds[s_hi + 1];
        let has_mask = !p.fmask.is_empty();
        for i in range {
            let k = p.kin[i];
            let pxi = g.xi(&k.x);
            if pxi[0] < wx0 as f64 - 2.0
                || pxi[1] < wy0 as f64 - 2.0
                || pxi[0] > (wx0 + wn) as f64 + 1.0
                || pxi[1] > (wy0 + wn) as f64 + 1.0
            {
                continue;
            }
            let m = p.mech[i];
            let s = p.stress[i];
            let gu = p.grad_u[i];
            let rho = m.m / m.vol;
            let ke = 0.5 * rho * (k.v[0] * k.v[0] + k.v[1] * k.v[1]);
            let pv = [s[0], s[1], s[2], gu[0], gu[1], gu[2], gu[3], p.wden[i], ke];
            let w = Weights2::new(v.shape, pxi, m.lh);
            let mask = if has_mask { p.fmask[i] } else { 0 };
            let inside = pxi[0] > box_lo[0]
                && pxi[0] < box_hi[0]
                && pxi[1] > box_lo[1]
                && pxi[1] < box_hi[1];
            // Nodal values of the window (field-0 pairs only: each node its own side).
            for a in 0..3 {
                for b in 0..3 {
                    let sh = w.s(a, b);
                    if sh <= 0.0 {
                        continue;
                    }
                    let ix = (w.x.base + a as i32) as usize;
                    let iy = (w.y.base + b as i32) as usize;
                    let field = ((mask >> (3 * a + b)) & 1) as u8;
                    if field == 0 && ix >= wx0 && iy >= wy0 && ix < wx0 + wn && iy < wy0 + wn {
                        let wk = (ix - wx0) * wn + (iy - wy0);
                        mass[wk] += sh * m.m;
                        for q in 0..NV {
                            vals[wk * NV + q] += sh * m.m * pv[q];
                        }
                    }
                }
            }
            if inside {
                let (acc, gv) = v.own_field_rates(&w, mask);
                // ∫_A ρ [ü_i ∂u_i/∂x_k − u̇_i ∂u̇_i/∂x_k] dA, per unit thickness.
                let da = m.vol / self.thickness * rho;
                for kk in 0..2 {
                    area[kk] += da
                        * (acc[0] * gu[kk] + acc[1] * gu[2 + kk]
                            - k.v[0] * gv[0][kk]
                            - k.v[1] * gv[1][kk]);
                }
            }
        }
        // Contour integrand at a window node with outward normal nrm.
        let integrand = |ix: usize, iy: usize, nrm: [f64; 2]| -> [f64; 2] {
            let wk = (ix - wx0) * wn + (iy - wy0);
            let m = mass[wk];
            if m <= 0.0 {
                return [0.0; 2];
            }
            let q = |k: usize| vals[wk * NV + k] / m;
            let (sxx, syy, sxy) = (q(0), q(1), q(2));
            let gu = [q(3), q(4), q(5), q(6)];
            let e = q(7) + q(8);
            let tr = [sxx * nrm[0] + sxy * nrm[1], sxy * nrm[0] + syy * nrm[1]];
            [
                e * nrm[0] - (tr[0] * gu[0] + tr[1] * gu[2]),
                e * nrm[1] - (tr[0] * gu[1] + tr[1] * gu[3]),
            ]
        };
        // Walk the square counter-clockwise: bottom, right, top, left edges.
        let (cx0, cx1) = ((c0 - n) as usize, (c0 + n) as usize);
        let (cy0, cy1) = ((r0 - n) as usize, (r0 + n) as usize);
        let mut edges: Vec<ContourEdge> = Vec::new();
        for ix in cx0..cx1 {
            edges.push(((ix, cy0), (ix + 1, cy0), [0.0, -1.0]));
        }
        for iy in cy0..cy1 {
            edges.push(((cx1, iy), (cx1, iy + 1), [1.0, 0.0]));
        }
        for ix in (cx0 + 1..=cx1).rev() {
            edges.push(((ix, cy1), (ix - 1, cy1), [0.0, 1.0]));
        }
        for iy in (cy0 + 1..=cy1).rev() {
            edges.push(((cx0, iy), (cx0, iy - 1), [-1.0, 0.0]));
        }
        let mut j = area;
        for (pn, qn, nrm) in edges {
            let (pp, qp) = (g.pos(pn.0, pn.1), g.pos(qn.0, qn.1));
            let fp = integrand(pn.0, pn.1, nrm);
            let fq = integrand(qn.0, qn.1, nrm);
            let cut = c
                .pts
                .windows(2)
                .find(|w| crosses(pp, qp, w[0].x, w[1].x))
                .map(|w| cross_param(pp, qp, w[0].x, w[1].x));
            for r in 0..2 {
                j[r] += match cut {
                    // Each face of the crack uses its own side's values up to the crossing.
                    Some(tc) => h * (tc * fp[r] + (1.0 - tc) * fq[r]),
                    None => 0.5 * h * (fp[r] + fq[r]),
                };
            }
        }
        TipJ { j }
    }

    /// The tip's medium (its nearest material in the scene's 2D state).
    fn medium(&self, v: &View<'_>, x: [f64; 2]) -> TipMedium {
        self.media[self.nearest_material(v, x)]
    }

    /// Where tip `t`'s rings go for a ring of radius `radius`: on a kinked branch of length
    /// s (`TipState::kink_at`) shorter than R/2, the vertex in the parent's frame (the
    /// kinked-crack solution drives the tip, pitfall 15); between R/2 and R, on the tip with
    /// the radius s, so that the vertex stays out of the ring; otherwise on the tip.
    ///
    /// Open: on the pure-shear plate the branches stall for ~60 µs once they pass R/2 (the
    /// ring of radius s reads J1 ≈ 0.05 Γ) and then grow in bursts. Keeping the vertex until
    /// R removed the stall but arrested Kalthoff–Winkler's crack after 12.7 mm (1 mm cells;
    /// 80–90 mm with this rule), so the rule stays until one passes both (`docs/kinks.md`).
    fn centre(&self, ci: usize, t: usize, radius: f64) -> Centre {
        let c = &self.cracks[ci];
        let Some(at) = c.tips[t].kink_at else {
            return Centre::Tip(radius);
        };
        let s = c.tips[t].advance - at;
        if s.is_nan() || s <= 0.0 || s >= radius {
            return Centre::Tip(radius);
        }
        if s >= 0.5 * radius {
            return Centre::Tip(s);
        }
        let n = c.pts.len();
        let at_k = |i: usize| {
            if t == 0 {
                c.pts[i].x
            } else {
                c.pts[n - 1 - i].x
            }
        };
        // The vertex: the point whose path length from the tip is nearest s; the parent's
        // direction: the chord from the point R/2 further back to it.
        let (mut acc, mut vertex, mut best) = (0.0, None, f64::INFINITY);
        let mut parent = None;
        for i in 1..n {
            acc += dist(at_k(i - 1), at_k(i));
            match vertex {
                None => {
                    if (acc - s).abs() < best {
                        best = (acc - s).abs();
                    } else {
                        vertex = Some((i - 1, acc - dist(at_k(i - 1), at_k(i))));
                    }
                }
                Some((_, sv)) => {
                    if acc - sv >= 0.5 * radius {
                        parent = Some(i);
                        break;
                    }
                }
            }
        }
        let Some((iv, _)) = vertex else {
            return Centre::Tip(radius);
        };
        let xv = at_k(iv);
        let xp = at_k(parent.unwrap_or(n - 1));
        let d = sub(xv, xp);
        let l = d[0].hypot(d[1]);
        if iv == 0 || l.is_nan() || l <= 0.0 {
            return Centre::Tip(radius);
        }
        Centre::Vertex(xv, [d[0] / l, d[1] / l])
    }

    /// Evaluate tip `t` of crack `ci` now (uncached).
    fn evaluate(&self, ci: usize, t: usize, v: &View<'_>) -> TipEval {
        let (tip, e1) = self.cracks[ci].tip_frame(t, self.h);
        let medium = self.medium(v, tip);
        let h = self.h;
        let (radius, contour) = match self.cracks[ci].j_method {
            JIntegral::Domain { radius } => (radius, false),
            // The contour's K and path-independence report come from the domain integral at
            // the default radius, or the largest smaller ring (down to two cells) that fits in
            // the material (its own J stays the contour's).
            JIntegral::Contour { .. } => {
                let radius = [JIntegral::DEFAULT_RADIUS_CELLS, 4.0, 3.0, 2.0]
                    .map(|c| c * h)
                    .into_iter()
                    .find(|&r| ring_fits(v, tip, r))
                    .unwrap_or(2.0 * h);
                (radius, true)
            }
        };
        let (frame, radius, parent_e1) = match (contour, self.centre(ci, t, radius)) {
            (false, Centre::Vertex(x, e)) => ((x, e), radius, Some(e)),
            (false, Centre::Tip(r)) => ((tip, e1), r, None),
            (true, _) => ((tip, e1), radius, None),
        };
        let d = self.domain_integrals(ci, frame, v, [radius, 0.5 * radius, 2.0 * radius], &medium);
        let j = if contour {
            self.compute_j(ci, t, v).j
        } else {
            d.j[0]
        };
        TipEval {
            j,
            j_half: d.j[1],
            j_double: d.j[2],
            k_int: d.k,
            medium,
            radius,
            parent_e1,
        }
    }

    fn tip_eval(&mut self, ci: usize, t: usize, v: &View<'_>, time: f64) -> TipEval {
        if let Some((tc, e)) = self.cracks[ci].tips[t].cached_j
            && tc == time
        {
            return e;
        }
        let e = self.evaluate(ci, t, v);
        self.j_evaluations += 1;
        self.cracks[ci].tips[t].cached_j = Some((time, e));
        e
    }

    /// J and K at tip `t` of crack `ci` in the tip frame.
    pub(super) fn tip_frame_j(
        &mut self,
        ci: usize,
        t: usize,
        v: &View<'_>,
        time: f64,
    ) -> TipFrameJ {
        let e = self.tip_eval(ci, t, v, time);
        let (tip, e1) = self.cracks[ci].tip_frame(t, self.h);
        let e2 = [-e1[1], e1[0]];
        if let Some(p1) = e.parent_e1 {
            // A short kinked branch: the parent's J1 and K at the vertex (its frame), and the
            // kinked tip's G and (k1, k2) at the branch's angle θ from them.
            let p2 = [-p1[1], p1[0]];
            let pj = |j: [f64; 2]| j[0] * p1[0] + j[1] * p1[1];
            let drive = KinkDrive {
                parent_e1: p1,
                parent_j1: pj(e.j),
                parent_k: [e.k_int[0].max(0.0), e.k_int[1]],
            };
            let th = (e1[0] * p2[0] + e1[1] * p2[1]).atan2(e1[0] * p1[0] + e1[1] * p1[1]);
            let ep = e.medium.e_prime;
            let (g, k) = drive.at(th, ep).unwrap_or((f64::NAN, [f64::NAN; 2]));
            let scaled = |j: [f64; 2]| {
                let jp = pj(j);
                if drive.parent_j1 > 0.0 {
                    g * jp / drive.parent_j1
                } else {
                    f64::NAN
                }
            };
            return TipFrameJ {
                tip,
                e1,
                e2,
                j1: g,
                j2: -2.0 * k[0] * k[1] / ep,
                j_half: [scaled(e.j_half), f64::NAN],
                j_double: [scaled(e.j_double), f64::NAN],
                k_int: k,
                medium: e.medium,
                kink: Some(drive),
            };
        }
        let frame = |j: [f64; 2]| [j[0] * e1[0] + j[1] * e1[1], j[0] * e2[0] + j[1] * e2[1]];
        let [mut j1, j2] = frame(e.j);
        let [mut j1_half, j2_half] = frame(e.j_half);
        let [mut j1_double, j2_double] = frame(e.j_double);
        // A tip grown by the equation of motion drags a process zone (`zone.rs`): its J1 is
        // the far field's energy release rate J_tip + J_zone, the zone counted whole whatever
        // part of it each ring's weight holds (`zone_outside_domain`).
        if matches!(
            self.cracks[ci].propagation,
            Propagation::EnergyRelease {
                speed: GrowthSpeed::EquationOfMotion,
                ..
            }
        ) {
            let r = e.radius;
            j1 += self.zone_outside_domain(ci, t, e1, r);
            j1_half += self.zone_outside_domain(ci, t, e1, 0.5 * r);
            j1_double += self.zone_outside_domain(ci, t, e1, 2.0 * r);
        }
        TipFrameJ {
            tip,
            e1,
            e2,
            j1,
            j2,
            j_half: [j1_half, j2_half],
            j_double: [j1_double, j2_double],
            k_int: e.k_int,
            medium: e.medium,
            kink: None,
        }
    }
}

// K (§6) from J and the crack opening, and the crack-tip rows.
impl Cracks {
    /// Opening (δ_n, δ_t) in the tip frame, about 2h behind tip `t`: left face − right face.
    fn tip_opening(&self, ci: usize, t: usize) -> [f64; 2] {
        let c = &self.cracks[ci];
        let (_, e1) = c.tip_frame(t, self.h);
        let e2 = [-e1[1], e1[0]];
        let n = c.pts.len();
        let order: Box<dyn Iterator<Item = usize>> = if t == 0 {
            Box::new(0..n)
        } else {
            Box::new((0..n).rev())
        };
        let mut prev: Option<[f64; 2]> = None;
        let mut s = 0.0;
        let mut at = if t == 0 { n - 1 } else { 0 };
        for k in order {
            if let Some(p) = prev {
                s += dist(p, c.pts[k].x);
            }
            prev = Some(c.pts[k].x);
            if s >= 2.0 * self.h {
                at = k;
                break;
            }
        }
        let p = c.pts[at];
        let cod = if t == 1 {
            sub(p.above, p.below)
        } else {
            sub(p.below, p.above)
        };
        [
            cod[0] * e2[0] + cod[1] * e2[1],
            cod[0] * e1[0] + cod[1] * e1[1],
        ]
    }

    /// K by the crack-opening ratio (the seed's and NairnMPM's method, kept for comparison):
    /// |K| from E'·J1 = A_I K_I² + A_II K_II², the mode ratio from the opening (δ_n, δ_t) about
    /// 2h behind the tip, which for a moving tip scales as (A_I K_I, A_II K_II) (Freund);
    /// NaN at and above c_R.
    pub(super) fn cod_k(
        &self,
        ci: usize,
        t: usize,
        j1: f64,
        speed: f64,
        medium: &TipMedium,
    ) -> [f64; 2] {
        let Some((ai, aii)) = medium.moving_factors(speed) else {
            return [f64::NAN; 2];
        };
        if !j1.is_finite() {
            return [f64::NAN; 2];
        }
        if j1 <= 0.0 {
            return [0.0; 2];
        }
        let [dn, dt] = self.tip_opening(ci, t);
        let (pn, pt) = (dn / ai, dt / aii);
        let r = pn.hypot(pt);
        let (c, s) = if r > 1e-12 * self.h {
            (pn / r, pt / r)
        } else {
            (1.0, 0.0)
        };
        let k = (medium.e_prime * j1 / (ai * c * c + aii * s * s)).sqrt();
        [k * c, k * s]
    }

    /// K of a tip: the interaction integral for a tip at rest (speed 0 over the speed
    /// window); for a moving tip the crack-opening K of [`Self::cod_k`] (the static auxiliary
    /// fields do not hold for a moving tip); NaN at and above c_R.
    pub(super) fn tip_k(&self, ci: usize, t: usize, tf: &TipFrameJ, speed: f64) -> [f64; 2] {
        if speed == 0.0 || tf.kink.is_some() {
            tf.k_int
        } else {
            self.cod_k(ci, t, tf.j1, speed, &tf.medium)
        }
    }

    /// Crack-tip rows now.
    pub fn tip_rows(&mut self, v: &View<'_>, time: f64) -> Vec<CrackTipRow> {
        let mut rows = Vec::new();
        for ci in 0..self.cracks.len() {
            for t in 0..2 {
                if !self.cracks[ci].tips[t].active {
                    continue;
                }
                let tf = self.tip_frame_j(ci, t, v, time);
                let (tip, j1, j2) = (tf.tip, tf.j1, tf.j2);
                let c = &self.cracks[ci];
                let speed = self.tip_speed(&c.tips[t], time);
                let [k1, k2] = self.tip_k(ci, t, &tf, speed);
                let [k1_cod, k2_cod] = self.cod_k(ci, t, j1, speed, &tf.medium);
                let c = &self.cracks[ci];
                rows.push(CrackTipRow {
                    time,
                    crack: ci as u32,
                    tip: t as u32,
                    x: tip[0],
                    y: tip[1],
                    length: c.length(),
                    speed,
                    j1,
                    j2,
                    k1,
                    k2,
                    growing: c.tips[t].grew,
                    j1_half: tf.j_half[0],
                    j2_half: tf.j_half[1],
                    j1_double: tf.j_double[0],
                    j2_double: tf.j_double[1],
                    k1_cod,
                    k2_cod,
                    zone_x: f64::NAN,
                    zone_y: f64::NAN,
                    connected_x: f64::NAN,
                    connected_y: f64::NAN,
                    zone_connected_x: f64::NAN,
                    zone_connected_y: f64::NAN,
                });
            }
        }
        rows.extend(self.interface_rows(time));
        rows
    }

    pub(super) fn nearest_material(&self, v: &View<'_>, x: [f64; 2]) -> usize {
        if v.mats.len() == 1 {
            return 0;
        }
        let p = v.parts;
        let mut best = (f64::INFINITY, 0usize);
        for (k, m) in p.kin.iter().zip(&p.mech) {
            let d = dist(k.x, x);
            if d < best.0 {
                best = (d, m.mat as usize);
            }
        }
        best.1
    }
}
