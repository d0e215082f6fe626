//! Building a simulation from a validated scene: the core's continuum of it (particles on the
//! seeding lattice, `fracture_api::lattice`, uniform GIMP half-widths, `algorithm.md` §1;
//! materials, boundary conditions and loads resolved to nodes, the grid, scratch sized up
//! front) and the crack layer (§3) when the scene has cracks.

use fracture_api::ValidScene;
use fracture_mpm::scenes::spec_2d;

use super::{BuildError, CrackLayer, Simulation, SolverConfig};
use crate::crack::Cracks;
use crate::grid::GridGeom;

impl Simulation {
    /// Build a simulation from a scene (validated here too): the core's 2D continuum of the
    /// scene (`fracture_mpm::scenes::spec_2d`: particles on the lattice, materials, conditions,
    /// loads, time step) with the crack layer of its cracks, interfaces and contact bodies.
    pub fn new(valid: &ValidScene, config: SolverConfig) -> Result<Simulation, BuildError> {
        let scene = valid.scene();
        let spec = spec_2d(valid, config.threads.resolve());
        let parts = &spec.particles;
        let m_min = parts.mech.iter().map(|m| m.m).fold(f64::INFINITY, f64::min);
        // Two velocity fields per node: cracks, or bodies that meet through a contact law.
        let multi_field =
            !scene.cracks.is_empty() || scene.bodies.iter().any(|b| b.contact.is_some());
        let geom = GridGeom::new(spec.min, spec.max, spec.h);
        let layer = CrackLayer(
            multi_field.then(|| Box::new(Cracks::new(scene, &geom, &spec.materials, spec.dt))),
        );
        // The portable kernel by default: every stored result and test reproduces bit for
        // bit; the FMA build is chosen with `set_kernel` or `fracture bench --kernel`.
        let core = fracture_mpm::Simulation::with_layer(spec, layer, Box::new(fracture_mpm::Cpu))?;
        Ok(Simulation {
            scene: scene.clone(),
            m_snapshot: 1e-9 * m_min,
            core,
        })
    }

    /// Replace every particle's velocity by `f(x0)` of its initial position (an API for
    /// initial conditions richer than the scene's uniform velocities, e.g. a vibration mode).
    pub fn set_velocities(&mut self, f: impl Fn([f64; 2]) -> [f64; 2]) {
        self.core.set_velocities(|x0| f(*x0));
    }
}
