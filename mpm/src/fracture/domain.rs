//! The domain weights of the J integral (`algorithm.md` §6): the ring's q and ∂q/∂r, the
//! weight of the inertial area term near the tip, the kinetic term along the tip direction.
//! Dimension-free radial functions: a 2D ring and a 3D front's tube take the same ones.

/// Radius ε of the disk around the tip, in cells (at most half the ring), left out of the
/// inertial area term ∫ ρ(ü·∂u/∂x_k − u̇·∂u̇/∂x_k) q dA (Nishioka and Atluri's J′ over
/// A − A_ε, ε → 0; here with h). Its integrand vanishes at a steadily running tip
/// (u̇ = −v ∂u/∂x1) and is integrable at a stationary one; the discrete one within a few cells
/// of a moving tip is the tip's passage through the grid. In the reduced Rosakis scene
/// (J_Ic = 25 J/m², 1 and 0.5 mm) it swung a running tip's J1 by ±300 J/m²; with the disk
/// left out, no sample fell below −0.1 Γ. Freund's stationary crack (0.5 mm, rings 3 and
/// 6 mm): J1 within 4 % of K²(1 − ν²)/E at every sample.
///
/// **An open regularisation in cells (issue 34, pitfall 13).** It shrinks with h, so the
/// J it gives converges to Moran & Shih's as h → 0, but at a given h it is part of what a fast
/// tip receives: on Freund's step wave with growth (Γ reached 2.25 µs after the wave,
/// 0.5 mm cells, ring 3.75 mm, `fracture run`, 2026-12-05) J1 over Freund's (1 − v/c_R)G* while
/// the tip ran at 0.8–0.9 c_R was 1.86 with 3 cells, 1.36 with 1 and 0.96 with none (1.03 at
/// 0.25 mm), 0.93 with 3 cells and the process zone off: the zone inside the disk is what
/// the excess comes from (the zone's length, 1.25–3.75 mm, changed it by under 10 %). In the
/// study's longer window (`docs/growth.md`, last third at 0.85–0.9 c_R) it was 2.53 with the
/// disk and 1.93 without. Without the disk, Kalthoff–Winkler, the pure-shear plate, the
/// damped DCB (+2.3 % at the end) and the 0.4 c_R strip (−1.6 %) still pass their tests, but a
/// tip held at the speed cap on the Rosakis bond read 411 / 341 / 109 J/m² on rings of 1.5 / 3 /
/// 6 mm (888 / 978 / 818 with it) and the reduced Rosakis toughness sweep (1 mm, 30 µs) grew
/// 19.4 / 18.5 / 20.7 mm at J_Ic = 25 / 100 / 250 J/m², no longer falling with J_Ic: at the cap
/// the near-tip inertia is not resolved, and the disk hides it. It stays until the cap itself
/// goes (`propagation::WALL_FRACTION`).
///
/// The disk's edge is a smooth step ([`inertia_weight`]), not a cut: with a cut, every
/// particle that crosses r = ε as the tip runs switches its whole inertial term on or off
/// (J1 of a tip at c_R swung with the period of a cell crossing).
pub const INERTIA_EXCLUSION_CELLS: f64 = 3.0;

/// Half-width of the smooth edge of the inertial disk, as a fraction of ε: the weight rises
/// from 0 at (1 − w)ε to 1 at (1 + w)ε (2 to 4 cells for ε = 3 cells).
pub const INERTIA_EDGE: f64 = 1.0 / 3.0;

/// Weight of the inertial area term at distance r from the tip for a disk of radius `eps`:
/// 0 inside (1 − w)ε, 1 outside (1 + w)ε, and the C¹ step 3s² − 2s³ between
/// (w = [`INERTIA_EDGE`]). As ε → 0 it tends to the integral over A − A_ε, like the cut.
#[inline]
pub fn inertia_weight(r: f64, eps: f64) -> f64 {
    let a = eps * (1.0 - INERTIA_EDGE);
    let b = eps * (1.0 + INERTIA_EDGE);
    if r <= a {
        0.0
    } else if r >= b {
        1.0
    } else {
        let s = (r - a) / (b - a);
        s * s * (3.0 - 2.0 * s)
    }
}

/// Largest angle (degrees) between e1 and a crack segment inside the ring for which the
/// kinetic pair along e1 is summed by parts ([`kinetic_along_tip`]): its identity drops the
/// faces' ∮ w q ½ρ|u̇|² n1 ds, which vanishes only on faces along e1. A ring holding a kink,
/// a curve or another crack takes the pair as written. (Kalthoff–Winkler's notch under its
/// 70° kink, faces at 70° to e1 with the struck side's kinetic energy ~10⁶ J/m³ below them,
/// summed by parts read J1 down to −45,000 J/m² while the ring of half the radius read
/// +80,000, and the crack stopped after 3.4 mm.) On the reduced Rosakis bond the tip's e1
/// tilts up to ~2.5° from the segments behind it as the sheared faces move.
pub const BY_PARTS_STRAIGHTNESS_DEG: f64 = 5.0;

/// d/dr of [`inertia_weight`]: 6s(1 − s)/(b − a) on the smooth edge (a, b), 0 elsewhere.
#[inline]
pub fn inertia_weight_dr(r: f64, eps: f64) -> f64 {
    let a = eps * (1.0 - INERTIA_EDGE);
    let b = eps * (1.0 + INERTIA_EDGE);
    if r <= a || r >= b {
        0.0
    } else {
        let s = (r - a) / (b - a);
        6.0 * s * (1.0 - s) / (b - a)
    }
}

/// The kinetic pair of J along the tip's direction e1 at one particle, integrated by parts:
/// ke·[(w − 1) ∂q/∂x1 + q ∂w/∂x1] for kinetic energy density ke = ½ρ|u̇|², with w the
/// inertial weight, `dw_dr` its radial derivative and `dir1` = e1·(x − x_tip)/r.
///
/// With ρ uniform, −½ρ|u̇|² ∂q/∂x1 − w q ρ u̇·∂u̇/∂x1 = −ke ∂q/∂x1 − w q ∂ke/∂x1, and
/// −∫ w q ∂ke/∂x1 dA = ∫ ke ∂(wq)/∂x1 dA: no outer boundary term (q = 0), none on faces
/// along e1 (n1 = 0) and none at the tip (w = 0). The pair is then the kinetic energy carried
/// across the disk's smooth edge, ke weighted by ∂w/∂x1 at 2h–4h from the tip (and where the
/// edge overlaps the ring, ke (w − 1) ∂q/∂x1): it needs no ∂u̇/∂x, and it no longer grows with
/// the ring. Written as before, the two halves cancel only if u̇ (the particle's FLIP
/// velocity) were the field whose gradient ∂u̇/∂x (the grid's) is; they are not, and the
/// mismatch is summed over the whole ring. In the reduced Rosakis scene (J_Ic = 25 J/m², the
/// equation of motion, a tip near c_R, kinetic terms of ~1,000 J/m² against J ≈ Γ) rings of
/// 12 cells read J1 below −0.1 Γ in 24 % of the running samples at 1 mm and 19 % at 0.5 mm,
/// rings of 8 cells at 0.5 mm in 2.7 %; integrated by parts 0 %, 4.3 % and 0 %
/// (`fracture run`, 2026-12-03). Along e2 the faces carry the pair (n2 = ±1), so J2 keeps
/// the pair as written. A material boundary crossing the ring across e1 (∂ρ/∂x1 ≠ 0) would
/// add ½|u̇|² ∂ρ/∂x1, which this form leaves out.
#[inline]
pub fn kinetic_along_tip(ke: f64, q: f64, dq1: f64, w: f64, dw_dr: f64, dir1: f64) -> f64 {
    ke * ((w - 1.0) * dq1 + q * dw_dr * dir1)
}

/// The ring weight q(r) and dq/dr for an outer radius `big_r`: q = 1 inside R/2, then the
/// smooth step q = 1 − 3s² + 2s³, s = (r − R/2)/(R/2), to 0 at R. Its gradient is continuous
/// (0 at both edges of the ring), so the particle sum, a point quadrature with a few particles
/// across the ring, does not see a jump of ∂q at the ring's edges.
#[inline]
pub fn ring(r: f64, big_r: f64) -> (f64, f64) {
    let r_in = 0.5 * big_r;
    if r <= r_in {
        (1.0, 0.0)
    } else if r < big_r {
        let w = big_r - r_in;
        let s = (r - r_in) / w;
        (1.0 - s * s * (3.0 - 2.0 * s), -6.0 * s * (1.0 - s) / w)
    } else {
        (0.0, 0.0)
    }
}
