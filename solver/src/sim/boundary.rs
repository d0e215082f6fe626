//! Boundary conditions and loads (`algorithm.md` §2): prescribed velocities resolved to grid
//! nodes and imposed on the momenta (after P2G and after re-extrapolation) and, through the
//! force, after the force pass (the reaction's work counts as external work); traction loads
//! ramped to the start of the step for the particle passes.

use fracture_api::Scene;

use super::Simulation;
use crate::grid::GridGeom;
use fracture_mpm::Dim2;
use fracture_mpm::gridops;

/// A prescribed-velocity condition resolved to grid nodes (the core's, `fracture_mpm::bc`).
pub(super) type BcNodes = fracture_mpm::state::BcNodes<Dim2>;

/// The scene's velocity conditions, each with the grid nodes inside its region.
pub(super) fn resolve_bcs(scene: &Scene, geom: &GridGeom) -> Vec<BcNodes> {
    fracture_mpm::scenes::bc_specs_2d(scene)
        .into_iter()
        .map(|s| BcNodes::new(s, geom))
        .collect()
}

/// A traction load: traction × thickness (N/m) and its ramp time.
#[derive(Debug, Clone, Copy)]
pub(super) struct LoadForce {
    t: [f64; 2],
    ramp: f64,
}

impl LoadForce {
    /// The scene's traction loads, in scene order (a particle's `Mech::load` is 1 + index).
    pub(super) fn resolve(scene: &Scene) -> Vec<LoadForce> {
        scene
            .loads
            .iter()
            .map(|l| LoadForce {
                t: [
                    l.traction[0] * scene.thickness,
                    l.traction[1] * scene.thickness,
                ],
                ramp: l.ramp_time.unwrap_or(0.0),
            })
            .collect()
    }
}

impl Simulation {
    /// The loads' ramped force per unit edge length at time `t0` (the start of the step),
    /// read by the force and update passes.
    pub(super) fn ramp_loads(&mut self, t0: f64) {
        let geom = self.geom;
        for bc in &mut self.bcs {
            bc.follow(t0, &geom);
        }
        for (l, out) in self.loads.iter().zip(self.load_now.iter_mut()) {
            let r = if l.ramp > 0.0 {
                (t0 / l.ramp).min(1.0)
            } else {
                1.0
            };
            *out = [l.t[0] * r, l.t[1] * r];
        }
    }

    /// Velocity boundary conditions on the extrapolated (`reextrapolated == false`: p) or
    /// re-extrapolated (q) momenta, on every field of each constrained node.
    pub(super) fn apply_bc_momentum(&mut self, t: f64, reextrapolated: bool) {
        let m_tiny = self.m_tiny;
        for bc in &self.bcs {
            let v = bc.velocity(t);
            if v[..2].iter().all(Option::is_none) {
                continue;
            }
            gridops::hold_momentum::<Dim2>(
                &mut self.nodes,
                &mut self.f1,
                &self.slot_of,
                &bc.nodes,
                &v[..2],
                reextrapolated,
                m_tiny,
            );
        }
    }

    /// Boundary conditions after the force pass: fix the force so that p + Δt f meets the
    /// prescribed velocity; the reaction does work at the node's mid-step velocity.
    pub(super) fn bc_force_fix(&mut self, t1: f64) {
        let dt = self.dt;
        let m_tiny = self.m_tiny;
        let mut work = 0.0;
        for bc in &self.bcs {
            let v = bc.velocity(t1);
            if v[..2].iter().all(Option::is_none) {
                continue;
            }
            gridops::hold_force::<Dim2>(
                &mut self.nodes,
                &mut self.f1,
                &self.slot_of,
                &bc.nodes,
                &v[..2],
                m_tiny,
                dt,
                &mut work,
            );
        }
        self.ledger.external_work += work;
        self.ledger.work_abs += work.abs();
    }
}
