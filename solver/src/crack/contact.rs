//! Crack-face contact (`algorithm.md` §4, pitfall 4): at every node with two fields, the
//! stick change Δp, the overlap and approach tests, frictionless and Coulomb sliding and the
//! stick law, applied as ±Δp at the chosen momentum stage so momentum is conserved exactly;
//! returns the frictional work for the energy balance.

use fracture_api::scene::ContactLaw;

use crate::grid::Node;

use super::Cracks;
use super::geometry::norm;

/// The momentum stage at which contact is applied (`algorithm.md` §4, pitfall 4).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// After P2G (momentum p).
    Extrapolated,
    /// After the force update (p + Δt f; forces adjusted by ±Δp/Δt).
    Forces,
    /// After re-extrapolation (momentum q).
    Reextrapolated,
}

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
            let big_m = a.m + b.m;
            // Stick change: both fields at the centre-of-mass velocity.
            let d = [
                (a.m * pb[0] - b.m * pa[0]) / big_m,
                (a.m * pb[1] - b.m * pa[1]) / big_m,
            ];
            let n = info.normal;
            let dn = d[0] * n[0] + d[1] * n[1];
            let node_index = f1_index[s] as usize;
            let law = &self.cracks[info.crack as usize].contact;
            let applied = match law {
                ContactLaw::Stick => d,
                _ => {
                    // Separation from the fields' mass-weighted displacements.
                    let ua = [a.u[0] / a.m, a.u[1] / a.m];
                    let ub = [b.u[0] / b.m, b.u[1] / b.m];
                    let sep = (ub[0] - ua[0]) * n[0] + (ub[1] - ua[1]) * n[1];
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
                    let normal = if approaching {
                        [dn * n[0], dn * n[1]]
                    } else {
                        [0.0, 0.0]
                    };
                    if friction > 0.0 {
                        let t = [d[0] - dn * n[0], d[1] - dn * n[1]];
                        let tl = norm(t);
                        let capacity = if stage == Stage::Forces {
                            -dn
                        } else {
                            held.max(-dn)
                        };
                        let limit = friction * capacity.max(0.0);
                        if tl > limit {
                            [normal[0] + limit * t[0] / tl, normal[1] + limit * t[1] / tl]
                        } else {
                            [normal[0] + t[0], normal[1] + t[1]]
                        }
                    } else {
                        normal
                    }
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
