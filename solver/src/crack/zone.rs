//! The process zone behind a tip that moves by the equation of motion (`algorithm.md` §7,
//! "Energy"; NairnMPM's J_tip + J_zone idea): every crack point that growth creates carries a
//! traction–separation state, and the new faces are released by a traction that falls
//! linearly from σ_c to zero over the opening δ_c = 2Γ/σ_c, so each unit of new area takes Γ
//! (the area under the law) out of the body instead of leaving it as waves.
//!
//! * Separation of a point: its two surfaces' positions (moved with their own sides' grid
//!   velocities, `motion.rs`), δ = x_above − x_below, split into opening δ_n (along the left
//!   normal, positive when open) and sliding δ_t; the effective separation
//!   s = sqrt(⟨δ_n⟩² + δ_t²) couples the modes (compression is left to contact).
//! * Law: initially rigid linear softening, σ(s) = σ_c (1 − s_max/δ_c) with s_max the largest
//!   s reached; below s_max the traction unloads along the secant to the origin,
//!   σ = σ(s_max)·s/s_max, so unloading creates no energy. The traction acts along the
//!   separation (along the opening normal while s = 0).
//! * Forces: the point's traction × its share of the crack length × thickness, spread over
//!   the nodes of its cell with the bilinear weights, applied as an equal and opposite
//!   impulse on the node's above and below fields at the force stage (momentum is conserved
//!   exactly). The impulse never exceeds the one that brings the two fields to a common
//!   velocity: a traction can stop the faces from separating but not throw them together,
//!   which is what an initially rigid law means and keeps the explicit step stable however
//!   light one field of a node is.
//! * Energy: the work of the applied force over the separation of the point's surfaces,
//!   Σ −F·Δδ (F the force of a step on the above side, Δδ the separation that step opened),
//!   summed per point: the fracture energy, booked in `dissipated` and in `energy.csv`'s
//!   `fracture` column. (The kinetic energy an impulse removes from the two lumped fields of
//!   a node is not the particles' loss: a light far-side field moves fast, and that measure
//!   booked up to twice Γ while the body lost about Γ.)
//!
//! The zone length l sets σ_c = sqrt(π E' Γ / (8 l)) (the length over which the LEFM opening
//! √r profile reaches δ_c); it is a numerical parameter of the tip law (default: a third of
//! the J domain radius, where the domain's weight is 1, so J sees the whole zone: J = J_tip +
//! J_zone).

use crate::grid::{GridGeom, Node};
use fracture_mpm::Dim2;
use fracture_mpm::fracture::contact::stick_change;
pub use fracture_mpm::fracture::zone::Zone;

use super::geometry::crosses;
use super::{CrackPoint, Cracks};

/// Which field of a node holds the material on one side: field 0 at a storage index, or
/// field 1 at a slot.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Field {
    Zero(usize),
    One(usize),
}

impl Cracks {
    /// The field of node (ix, iy) that the material at `from` reaches: field 0 when the line
    /// from → node crosses the cracks an even number of times, field 1 (if the node has one)
    /// when odd.
    pub(super) fn side_field(
        &self,
        geom: &GridGeom,
        from: [f64; 2],
        ix: usize,
        iy: usize,
        slot_of: &[u32],
    ) -> Option<Field> {
        let node = geom.pos(ix, iy);
        let mut count = 0;
        for &(ci, si) in self.segs_near(geom, from) {
            let c = &self.cracks[ci as usize];
            if crosses(from, node, c.pts[si as usize].x, c.pts[si as usize + 1].x) {
                count += 1;
            }
        }
        let idx = geom.at(ix, iy);
        if count % 2 == 0 {
            Some(Field::Zero(idx))
        } else {
            let s = *slot_of.get(idx)?;
            (s != u32::MAX).then_some(Field::One(s as usize))
        }
    }

    /// Process-zone tractions at the force stage (see the module doc): returns the energy
    /// they removed in this step (J, the scene's thickness).
    pub fn zone_forces(
        &mut self,
        geom: &GridGeom,
        nodes: &mut [Node],
        f1: &mut [Node],
        slot_of: &[u32],
        dt: f64,
    ) -> f64 {
        if !self
            .cracks
            .iter()
            .any(|c| c.pts.iter().any(|p| p.zone.is_some() || p.bond.is_some()))
        {
            return 0.0;
        }
        let thickness = self.thickness;
        let mut total = 0.0;
        for ci in 0..self.cracks.len() {
            let n = self.cracks[ci].pts.len();
            for k in 0..n {
                let c = &self.cracks[ci];
                if c.pts[k].bond.is_some() {
                    total += self.bond_force(ci, k, geom, nodes, f1, slot_of, dt);
                    continue;
                }
                let Some(mut zone) = c.pts[k].zone else {
                    continue;
                };
                let is_tip = (k == 0 && c.tips[0].active) || (k == n - 1 && c.tips[1].active);
                if is_tip || n < 2 || (zone.failed() && zone.last.is_none()) {
                    continue;
                }
                let pt: CrackPoint = c.pts[k];
                // Length share: half of each neighbouring segment (only the one towards the
                // grown side for the scene's tip point).
                let [back, fore] = c.neighbour_lengths(k, |p| p.x);
                let share = match zone.side {
                    1 => 0.5 * fore,
                    -1 => 0.5 * back,
                    _ => 0.5 * (back + fore),
                };
                let nrm = c.local_normal(k); // above → below
                let up = [-nrm[0], -nrm[1]]; // left normal, towards the above side
                let tan = [nrm[1], -nrm[0]]; // along the crack, pa → pb
                let d = [pt.above[0] - pt.below[0], pt.above[1] - pt.below[1]];
                // Work of last step's force over the separation it saw open since.
                if let Some((f, d0)) = zone.last.take() {
                    let w = -(f[0] * (d[0] - d0[0]) + f[1] * (d[1] - d0[1]));
                    zone.book(w);
                    total += w;
                }
                zone.capacity = zone.toughness * share * thickness;
                let dn = (d[0] * up[0] + d[1] * up[1]).max(0.0);
                let dtn = d[0] * tan[0] + d[1] * tan[1];
                let s = dn.hypot(dtn);
                let s_next = if zone.prev_separation.is_finite() {
                    s + (s - zone.prev_separation)
                } else {
                    s
                };
                zone.prev_separation = s;
                let sigma = zone.traction(s, s_next);
                if sigma <= 0.0 || share <= 0.0 {
                    self.cracks[ci].pts[k].zone = Some(zone);
                    continue;
                }
                // Direction of the separation (the opening normal while closed).
                let dir = if s > 1e-12 * self.h {
                    [
                        (dn * up[0] + dtn * tan[0]) / s,
                        (dn * up[1] + dtn * tan[1]) / s,
                    ]
                } else {
                    up
                };
                // Impulse on the above side: pulls it back along −dir.
                // A point that opens by a good part of δ_c in one step (a fast-sliding mode II
                // face) would take far more than its Γ·area in that step at the start-of-step
                // traction: cap the force so the step's expected work, over the separation
                // the last step's rate predicts, stays within what the point has left.
                let left = (zone.capacity - zone.positive_work).max(0.0);
                let expected = (s_next - s).max(0.0) * share * thickness;
                let sigma = if expected > 0.0 {
                    sigma.min(left / expected)
                } else {
                    sigma
                };
                let magnitude = sigma * share * thickness * dt;
                let Some(applied) =
                    self.push_pairs(geom, nodes, f1, slot_of, pt.x, nrm, dt, |w, stick| {
                        // The traction pulls the above field along −dir; at most as far as
                        // the stick change goes in that direction.
                        let reach = -(stick[0] * dir[0] + stick[1] * dir[1]);
                        let j = (magnitude * w).min(reach.max(0.0));
                        [-j * dir[0], -j * dir[1]]
                    })
                else {
                    self.cracks[ci].pts[k].zone = Some(zone);
                    continue;
                };
                zone.last = Some((applied, d));
                self.cracks[ci].pts[k].zone = Some(zone);
            }
        }
        self.zone_work += total;
        total
    }

    /// Apply a point's traction at the force stage: on each node of the point's cell where
    /// both sides' fields are present, the impulse `impulse(w, stick)` on the above field and
    /// its opposite on the below field, with w the node's share of the point (bilinear
    /// weights over the two-field nodes) and `stick` the change of the above field's momentum
    /// that would make the two move together. Returns the force applied on the above side
    /// (N), or None when no node of the cell has both sides.
    #[allow(clippy::too_many_arguments)]
    fn push_pairs(
        &self,
        geom: &GridGeom,
        nodes: &mut [Node],
        f1: &mut [Node],
        slot_of: &[u32],
        x: [f64; 2],
        nrm: [f64; 2],
        dt: f64,
        impulse: impl Fn(f64, [f64; 2]) -> [f64; 2],
    ) -> Option<[f64; 2]> {
        let pairs = self.cell_pairs(geom, slot_of, x, nrm)?;
        let wsum: f64 = pairs
            .iter()
            .flatten()
            .map(|p| p.0)
            .filter(|&w| w > 0.0)
            .sum();
        if wsum <= 0.0 {
            return None;
        }
        let mut applied = [0.0; 2];
        for (w, fa, fb) in pairs.into_iter().flatten() {
            if w <= 0.0 {
                continue;
            }
            let Some((na, nb)) = pair_mut(nodes, f1, fa, fb) else {
                continue;
            };
            // Force-stage momenta and the stick change of the above field.
            let pa_ = [na.p[0] + dt * na.f[0], na.p[1] + dt * na.f[1]];
            let pb_ = [nb.p[0] + dt * nb.f[0], nb.p[1] + dt * nb.f[1]];
            let stick = stick_change::<Dim2>(na.m, &pa_, nb.m, &pb_);
            let imp = impulse(w / wsum, stick);
            for q in 0..2 {
                na.f[q] += imp[q] / dt;
                nb.f[q] -= imp[q] / dt;
                applied[q] += imp[q] / dt;
            }
        }
        Some(applied)
    }

    /// The cohesive traction of interface point k of crack ci (`cohesive.rs`) at the force
    /// stage; returns the work booked for its last step (J).
    #[allow(clippy::too_many_arguments)]
    fn bond_force(
        &mut self,
        ci: usize,
        k: usize,
        geom: &GridGeom,
        nodes: &mut [Node],
        f1: &mut [Node],
        slot_of: &[u32],
        dt: f64,
    ) -> f64 {
        let c = &self.cracks[ci];
        let pt: CrackPoint = c.pts[k];
        let Some(mut bond) = pt.bond else {
            return 0.0;
        };
        let [back, fore] = c.neighbour_lengths(k, |p| p.x0);
        bond.share = 0.5 * (back + fore);
        let nrm = c.local_normal(k); // above → below
        let up = [-nrm[0], -nrm[1]];
        let tan = [nrm[1], -nrm[0]];
        let d = [pt.above[0] - pt.below[0], pt.above[1] - pt.below[1]];
        // Work of last step's force over the separation the surfaces opened since. (The
        // impulses' work at the fields' end-of-step velocities is zero wherever they stick the
        // two fields, which they do at most nodes: the faces open through the particles'
        // motion, which the surfaces follow.)
        let mut w = 0.0;
        if let Some((f, d0)) = bond.last.take() {
            w = -(f[0] * (d[0] - d0[0]) + f[1] * (d[1] - d0[1]));
            bond.work += w;
        }
        let dn = d[0] * up[0] + d[1] * up[1];
        let dtn = d[0] * tan[0] + d[1] * tan[1];
        let traction = bond.traction(dn, dtn);
        let area_dt = bond.share * self.thickness * dt;
        // None: rigid (the undamaged linear law); a zero traction (failed, or closed after
        // damage) applies nothing.
        if area_dt > 0.0 && traction != Some([0.0; 2]) {
            let caps = [bond.strength[0] * area_dt, bond.strength[1] * area_dt];
            // Rigid: whether a pair needed more than the strength (the bond engages).
            let saturated = std::cell::Cell::new(false);
            let applied = self.push_pairs(geom, nodes, f1, slot_of, pt.x, nrm, dt, |wf, stick| {
                let s = [
                    stick[0] * up[0] + stick[1] * up[1],
                    stick[0] * tan[0] + stick[1] * tan[1],
                ];
                // Impulse components (normal, tangential) on the above side, signed. Rigid:
                // whatever keeps the fields together, up to the strengths (the normal part
                // only in tension).
                let want = match traction {
                    Some(t) => [-t[0] * area_dt, -t[1] * area_dt],
                    None => [-caps[0], s[1].signum() * caps[1]],
                };
                let mut j = [0.0; 2];
                for q in 0..2 {
                    let wq = want[q] * wf;
                    // Only against the separating motion, and never past the stick change.
                    if wq * s[q] > 0.0 {
                        j[q] = wq.signum() * wq.abs().min(s[q].abs());
                        if traction.is_none() && wq.abs() < s[q].abs() {
                            saturated.set(true);
                        }
                    }
                }
                [j[0] * up[0] + j[1] * tan[0], j[0] * up[1] + j[1] * tan[1]]
            });
            if saturated.get() {
                // Loaded to the strength: from the next step the law runs from here.
                bond.engaged = true;
            }
            // A rigid bond is a constraint: it does no work (the surfaces' drift under it is
            // not an opening), so nothing is booked for it.
            if let (Some(a), Some(_)) = (applied, traction) {
                bond.last = Some((a, d));
            }
        }
        self.cracks[ci].pts[k].bond = Some(bond);
        w
    }
}

/// The two fields of a node pair, above first, when both hold mass.
fn pair_mut<'a>(
    nodes: &'a mut [Node],
    f1: &'a mut [Node],
    fa: Field,
    fb: Field,
) -> Option<(&'a mut Node, &'a mut Node)> {
    let (na, nb) = match (fa, fb) {
        (Field::Zero(i), Field::One(s)) => (&mut nodes[i], &mut f1[s]),
        (Field::One(s), Field::Zero(i)) => (&mut f1[s], &mut nodes[i]),
        _ => return None,
    };
    (na.m > 0.0 && nb.m > 0.0).then_some((na, nb))
}

impl Cracks {
    /// For each node of the cell of `x` (in the order (0,0), (0,1), (1,0), (1,1)): its
    /// bilinear weight of `x` (possibly 0) and the above and below sides' fields, where both
    /// are present and differ (a two-field node across the line of normal `nrm`); None
    /// outside the grid. At most 4 entries: no allocation per point and step.
    fn cell_pairs(
        &self,
        geom: &GridGeom,
        slot_of: &[u32],
        x: [f64; 2],
        nrm: [f64; 2],
    ) -> Option<[Option<(f64, Field, Field)>; 4]> {
        let eps = 1e-3 * self.h;
        let (cx, cy, fx, fy) = geom.cell_with_fractions(x)?;
        let from_above = [x[0] - eps * nrm[0], x[1] - eps * nrm[1]];
        let from_below = [x[0] + eps * nrm[0], x[1] + eps * nrm[1]];
        let mut pairs: [Option<(f64, Field, Field)>; 4] = [None; 4];
        let mut k = 0;
        for (a, wa) in [(0, 1.0 - fx), (1, fx)] {
            for (b, wb) in [(0, 1.0 - fy), (1, fy)] {
                let (ix, iy) = (cx + a, cy + b);
                let fa = self.side_field(geom, from_above, ix, iy, slot_of);
                let fb = self.side_field(geom, from_below, ix, iy, slot_of);
                if let (Some(fa), Some(fb)) = (fa, fb)
                    && fa != fb
                {
                    pairs[k] = Some((wa * wb, fa, fb));
                }
                k += 1;
            }
        }
        Some(pairs)
    }
}

impl Cracks {
    /// Hold the re-extrapolated momenta of the rigid bonded points (the linear law not yet
    /// loaded to its strength, `Bond::engaged`): on each of their node pairs, the change
    /// that makes the two fields move together, the opening part only against separating
    /// motion (compression is contact's). Without it the MUSL re-extrapolation gives the two
    /// fields of a rigid bond the relative velocity of their particles' FLIP updates, which
    /// the second stress half-update and the surfaces then follow as if the faces were free.
    /// A constraint: no work is booked for it. (Holding the engaged points as well was
    /// tried: their traction-limited steps then gained energy, −8.6 % / −2.8 % of the work
    /// on the DCB at 1 / 0.5 mm, against −0.6 % / −0.1 % holding only the rigid ones.)
    pub fn bond_hold(
        &mut self,
        geom: &GridGeom,
        nodes: &mut [Node],
        f1: &mut [Node],
        slot_of: &[u32],
    ) {
        for ci in 0..self.cracks.len() {
            if !self.cracks[ci].interface {
                continue;
            }
            for k in 0..self.cracks[ci].pts.len() {
                let pt = self.cracks[ci].pts[k];
                let Some(bond) = pt.bond else { continue };
                if bond.failed || bond.engaged {
                    continue;
                }
                let nrm = self.cracks[ci].local_normal(k);
                let up = [-nrm[0], -nrm[1]];
                let tan = [nrm[1], -nrm[0]];
                self.hold_pairs(geom, nodes, f1, slot_of, pt.x, nrm, |stick| {
                    let s = [
                        stick[0] * up[0] + stick[1] * up[1],
                        stick[0] * tan[0] + stick[1] * tan[1],
                    ];
                    // Separating: the above field moves away from the below one along up
                    // (stick pulls it back: s[0] < 0); sliding either way.
                    let jn = s[0].min(0.0);
                    let jt = s[1];
                    [jn * up[0] + jt * tan[0], jn * up[1] + jt * tan[1]]
                });
            }
        }
    }

    /// On each node of the cell of `x` where both sides' fields are present, the momentum
    /// change `change(stick)` on the above field and its opposite on the below one, with
    /// `stick` the change of the above field's momentum that makes the two move together
    /// (momenta, not forces: the re-extrapolated stage).
    #[allow(clippy::too_many_arguments)]
    fn hold_pairs(
        &self,
        geom: &GridGeom,
        nodes: &mut [Node],
        f1: &mut [Node],
        slot_of: &[u32],
        x: [f64; 2],
        nrm: [f64; 2],
        change: impl Fn([f64; 2]) -> [f64; 2],
    ) {
        let Some(pairs) = self.cell_pairs(geom, slot_of, x, nrm) else {
            return;
        };
        // Every node of the cell, a zero bilinear weight included: a constraint.
        for (_, fa, fb) in pairs.into_iter().flatten() {
            let Some((na, nb)) = pair_mut(nodes, f1, fa, fb) else {
                continue;
            };
            // The re-extrapolated momenta are `q`.
            let stick = stick_change::<Dim2>(na.m, &na.q, nb.m, &nb.q);
            let c = change(stick);
            for k in 0..2 {
                na.q[k] += c[k];
                nb.q[k] -= c[k];
            }
        }
    }
}
