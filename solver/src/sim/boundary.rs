//! Boundary conditions and loads (`algorithm.md` §2): prescribed velocities resolved to grid
//! nodes and imposed on the momenta (after P2G and after re-extrapolation) and, through the
//! force, after the force pass (the reaction's work counts as external work); traction loads
//! ramped to the start of the step for the particle passes.

use fracture_api::Scene;
use fracture_api::scene::Region;

use super::Simulation;
use crate::grid::GridGeom;
use fracture_mpm::Dim2;
use fracture_mpm::gridops;

/// A prescribed-velocity condition resolved to grid nodes.
#[derive(Debug, Clone)]
pub(super) struct BcNodes {
    nodes: Vec<u32>,
    vx: Option<f64>,
    vy: Option<f64>,
    ramp: f64,
    start: f64,
    end: f64,
    /// The scene's region, for a moving condition (None: fixed, `nodes` resolved once).
    moving: Option<Region>,
    /// The displacement the nodes of a moving condition were last resolved for.
    shift: [f64; 2],
}

/// The node storage indices inside `region` translated by `shift` (only the nodes in its
/// translated bounding box are tested).
fn nodes_in(region: &Region, shift: [f64; 2], geom: &GridGeom) -> Vec<u32> {
    let (lo, hi) = region.bounds();
    let (lo, hi) = (
        [lo[0] + shift[0], lo[1] + shift[1]],
        [hi[0] + shift[0], hi[1] + shift[1]],
    );
    let (a, b) = (geom.xi(&lo), geom.xi(&hi));
    // One node of margin each side: `contains` decides, not the rounding of ξ.
    let range = |lo: f64, hi: f64, n: usize| -> (usize, usize) {
        let first = (lo.ceil() - 1.0).max(0.0);
        let last = (hi.floor() + 1.0).min(n as f64 - 1.0);
        if !(first.is_finite() && last.is_finite()) || last < first {
            return (1, 0);
        }
        (first as usize, last as usize)
    };
    let (x0, x1) = range(a[0], b[0], geom.nx());
    let (y0, y1) = range(a[1], b[1], geom.ny());
    let mut nodes = Vec::new();
    for ix in x0..=x1 {
        for iy in y0..=y1 {
            let p = geom.pos(ix, iy);
            if region.contains([p[0] - shift[0], p[1] - shift[1]]) {
                nodes.push(geom.at(ix, iy) as u32);
            }
        }
    }
    nodes
}

impl BcNodes {
    /// The scene's velocity conditions, each with the grid nodes inside its region.
    pub(super) fn resolve(scene: &Scene, geom: &GridGeom) -> Vec<BcNodes> {
        scene
            .boundary_conditions
            .iter()
            .map(|bc| BcNodes {
                nodes: nodes_in(&bc.region, [0.0; 2], geom),
                vx: bc.velocity.x,
                vy: bc.velocity.y,
                ramp: bc.ramp_time.unwrap_or(0.0),
                start: bc.start.unwrap_or(0.0),
                end: bc.end.unwrap_or(f64::INFINITY),
                moving: bc.moving.then(|| bc.region.clone()),
                shift: [0.0; 2],
            })
            .collect()
    }

    /// The displacement of the prescribed components from 0 to `t`: ∫ v(τ) dτ over the
    /// active interval, with the ramp v·min(τ/ramp, 1) that [`BcNodes::velocity`] applies
    /// (in closed form, so a resumed run resolves the same nodes).
    fn displacement(&self, t: f64) -> [f64; 2] {
        let (a, b) = (self.start, t.min(self.end));
        if b <= a {
            return [0.0; 2];
        }
        // F(τ) = ∫_0^τ min(s/R, 1) ds.
        let r = self.ramp;
        let big_f = |tau: f64| {
            if r <= 0.0 {
                tau
            } else if tau <= r {
                tau * tau / (2.0 * r)
            } else {
                0.5 * r + (tau - r)
            }
        };
        let d = big_f(b) - big_f(a);
        [self.vx.unwrap_or(0.0) * d, self.vy.unwrap_or(0.0) * d]
    }

    /// A moving condition: resolve its nodes for the displacement at `t` (when it moved
    /// since the last time).
    pub(super) fn follow(&mut self, t: f64, geom: &GridGeom) {
        let Some(region) = &self.moving else {
            return;
        };
        let d = self.displacement(t);
        // The face a node stands for is the nearest one: a node half a cell behind the
        // moved face is released, one less than half a cell ahead is driven (resolving the
        // region at the displacement itself lags the face by half a cell on average: the
        // 1D strip then took 2.6 % / 4.6 % too little momentum at 0.5 / 0.25 mm).
        let len = d[0].hypot(d[1]);
        let shift = if len > 0.0 {
            let k = 1.0 + 0.5 * geom.h / len;
            [d[0] * k, d[1] * k]
        } else {
            d
        };
        if shift != self.shift {
            self.nodes = nodes_in(region, shift, geom);
            self.shift = shift;
        }
    }

    /// Prescribed velocity components at time t (None where free or inactive).
    pub(super) fn velocity(&self, t: f64) -> [Option<f64>; 2] {
        if t < self.start || t > self.end {
            return [None, None];
        }
        let r = if self.ramp > 0.0 {
            (t / self.ramp).min(1.0)
        } else {
            1.0
        };
        [self.vx.map(|v| v * r), self.vy.map(|v| v * r)]
    }
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
            if v[0].is_none() && v[1].is_none() {
                continue;
            }
            gridops::hold_momentum::<Dim2>(
                &mut self.nodes,
                &mut self.f1,
                &self.slot_of,
                &bc.nodes,
                &v,
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
            if v[0].is_none() && v[1].is_none() {
                continue;
            }
            gridops::hold_force::<Dim2>(
                &mut self.nodes,
                &mut self.f1,
                &self.slot_of,
                &bc.nodes,
                &v,
                m_tiny,
                dt,
                &mut work,
            );
        }
        self.ledger.external_work += work;
        self.ledger.work_abs += work.abs();
    }
}
