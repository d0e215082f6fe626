//! Crack-face contact (`algorithm.md` §4, pitfall 4): at every node with two fields, the
//! stick change Δp, the overlap and approach tests, frictionless and Coulomb sliding and the
//! stick law, applied as ±Δp at the chosen momentum stage so momentum is conserved exactly;
//! returns the frictional work for the energy balance. The same algebra joins a body with a
//! contact law to the others (`Body::contact`, slots marked [`BODY_CONTACT`]), with the
//! struck body's surface normal from the nodal masses ([`Cracks::body_normals`]).

use fracture_api::scene::ContactLaw;
use fracture_mpm::Dim2;
use fracture_mpm::fracture::contact::{coulomb_change, stick_change};

use crate::grid::Node;

use super::Cracks;
use super::fields::BODY_CONTACT;
use super::geometry::norm;

/// The momentum stage at which contact is applied (`algorithm.md` §4, pitfall 4): the
/// core's grid stages.
pub use fracture_mpm::gridops::Stage;

impl Cracks {
    /// Crack-face contact at every node with two fields (§4). Returns the frictional work.
    pub fn contact(
        &mut self,
        stage: Stage,
        nodes: &mut [Node],
        f1: &mut [Node],
        f1_index: &[u32],
        _m_tiny: f64,
        dt: f64,
    ) -> f64 {
        let mut friction_work = 0.0;
        if stage == Stage::Forces {
            self.face_force.clear();
            self.face_force.resize(self.slots.len(), [0.0; 2]);
        }
        if stage == Stage::Extrapolated && self.contact_bodies.contains(&true) {
            self.body_normals(nodes, f1, f1_index);
        }
        for (s, info) in self.slots.iter().enumerate() {
            let n0 = &mut nodes[f1_index[s] as usize];
            let n1 = &mut f1[s];
            if n0.m <= 0.0 || n1.m <= 0.0 {
                continue;
            }
            let (a, b) = if info.above_is_f1 { (n1, n0) } else { (n0, n1) };
            let mom = |nd: &Node| match stage {
                Stage::Extrapolated => nd.p,
                Stage::Forces => [nd.p[0] + dt * nd.f[0], nd.p[1] + dt * nd.f[1]],
                Stage::Reextrapolated => nd.q,
            };
            let (pa, pb) = (mom(a), mom(b));
            // Stick change: both fields at the centre-of-mass velocity.
            let d = stick_change::<Dim2>(a.m, &pa, b.m, &pb);
            let n = info.normal;
            let dn = d[0] * n[0] + d[1] * n[1];
            let node_index = f1_index[s] as usize;
            let body = info.crack == BODY_CONTACT;
            let law = if body {
                &self.body_contact
            } else {
                &self.cracks[info.crack as usize].contact
            };
            let applied = match law {
                ContactLaw::Stick => d,
                _ => {
                    // Separation from the fields' mass-weighted displacements. Two bodies do
                    // not start together, so their displacements say nothing of a gap: at a
                    // node both reach they are in contact while they approach (Bardenhagen
                    // et al. 2000), which starts it up to about a cell early.
                    let sep = if body {
                        -1.0
                    } else {
                        let ua = [a.u[0] / a.m, a.u[1] / a.m];
                        let ub = [b.u[0] / b.m, b.u[1] / b.m];
                        (ub[0] - ua[0]) * n[0] + (ub[1] - ua[1]) * n[1]
                    };
                    let approaching = dn < 0.0;
                    if stage == Stage::Forces {
                        self.normal_impulse[node_index] =
                            if sep < 0.0 && approaching { -dn } else { 0.0 };
                    }
                    let held = self.normal_impulse[node_index];
                    let friction = match law {
                        ContactLaw::Coulomb { friction } => *friction,
                        _ => 0.0,
                    };
                    // In contact: overlapping and approaching; or, for friction at the
                    // extrapolation stages, overlapping and still pressed by the normal force
                    // of the last force stage (a static contact does not approach).
                    let pressed = stage != Stage::Forces && friction > 0.0 && held > 0.0;
                    if !(sep < 0.0 && (approaching || pressed)) {
                        continue;
                    }
                    let capacity = if stage == Stage::Forces {
                        -dn
                    } else {
                        held.max(-dn)
                    };
                    coulomb_change::<Dim2>(&d, &n, approaching, friction, capacity)
                }
            };
            if stage == Stage::Forces && matches!(law, ContactLaw::Coulomb { .. }) {
                // Frictional work: kinetic energy the tangential impulse removes beyond what
                // the normal impulse alone removes.
                let ke = |da: [f64; 2]| {
                    let qa = [pa[0] + da[0], pa[1] + da[1]];
                    let qb = [pb[0] - da[0], pb[1] - da[1]];
                    0.5 * (qa[0] * qa[0] + qa[1] * qa[1]) / a.m
                        + 0.5 * (qb[0] * qb[0] + qb[1] * qb[1]) / b.m
                };
                let w = ke([dn * n[0], dn * n[1]]) - ke(applied);
                friction_work += w.max(0.0);
            }
            match stage {
                Stage::Extrapolated => {
                    for k in 0..2 {
                        a.p[k] += applied[k];
                        b.p[k] -= applied[k];
                    }
                }
                Stage::Forces => {
                    for k in 0..2 {
                        a.f[k] += applied[k] / dt;
                        b.f[k] -= applied[k] / dt;
                    }
                    self.face_force[s] = [applied[0] / dt, applied[1] / dt];
                }
                Stage::Reextrapolated => {
                    for k in 0..2 {
                        a.q[k] += applied[k];
                        b.q[k] -= applied[k];
                    }
                }
            }
        }
        friction_work
    }
}

impl Cracks {
    /// The contact normal of every body-contact slot, from field 0 into the contact bodies:
    /// −∇m₀, the surface of the struck or supporting body (field 0), unless its nodal mass
    /// gradient is under a quarter of the contact bodies' ∇m₁ (a corner of field 0's body),
    /// then ∇m₁. Gradients by central differences of the nodal masses (a contact body has
    /// mass only at its slots, so a neighbour without a slot holds none of it). Not the
    /// contact body's own gradient, nor the difference of the two: near a sliding body's
    /// front corner its gradient turns towards its side face, and the frictionless block of
    /// `tests/body_contact.rs` (sliding at 2 m/s on a plate) struck the plate's surface
    /// nodes there: it kept 0 % of its speed after 20 µs with the body's normal, 81 % with
    /// the difference, 85 % with the larger of the two, and 100.00 % with this one.
    pub(super) fn body_normals(&mut self, nodes: &[Node], f1: &[Node], f1_index: &[u32]) {
        let ny = self.ncy + 1;
        let m1 = |idx: usize| {
            f1_index
                .binary_search(&(idx as u32))
                .map_or(0.0, |s| f1[s].m)
        };
        let m0 = |idx: usize| nodes.get(idx).map_or(0.0, |n| n.m);
        for (s, info) in self.slots.iter_mut().enumerate() {
            if info.crack != BODY_CONTACT {
                continue;
            }
            let i = f1_index[s] as usize;
            let iy = i % ny;
            // Storage has padding columns on both sides, so i ± ny is in range.
            let (xl, xr) = (i.saturating_sub(ny), i + ny);
            let (yd, yu) = (
                if iy > 0 { i - 1 } else { i },
                if iy + 1 < ny { i + 1 } else { i },
            );
            let g1 = [m1(xr) - m1(xl), m1(yu) - m1(yd)];
            let g0 = [m0(xr) - m0(xl), m0(yu) - m0(yd)];
            // ∇m₁ points into the contact body, −∇m₀ out of field 0's body: both from 0 to 1.
            // The struck body's surface unless it has next to none here (a corner of it).
            let n = if norm(g0) > 0.25 * norm(g1) {
                [-g0[0], -g0[1]]
            } else {
                g1
            };
            let l = norm(n);
            if l > 0.0 {
                info.normal = [n[0] / l, n[1] / l];
            }
        }
    }
}
