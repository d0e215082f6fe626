//! Building a simulation from a validated scene: particles on the seeding lattice
//! (`fracture_api::lattice`, uniform GIMP half-widths, `algorithm.md` §1), materials, boundary
//! conditions and loads resolved to nodes, the grid, scratch sized up front (no allocation per
//! step), and the crack state (§3) when the scene has cracks.

use fracture_api::ValidScene;
use fracture_api::scene::Analysis;
use fracture_mpm::{Dim2, LoadSpec, Spec};

use super::{BuildError, CrackLayer, Simulation, SolverConfig};
use crate::crack::Cracks;
use crate::grid::GridGeom;
use crate::material::Elastic;
use crate::particles::{Cold, Kin, Mech, Particles};

impl Simulation {
    /// Build a simulation from a scene (validated here too).
    pub fn new(valid: &ValidScene, config: SolverConfig) -> Result<Simulation, BuildError> {
        let (scene, size) = (valid.scene(), valid.size());
        let g = &scene.grid;
        let h = g.cell_size;
        let analysis = if scene.analysis == Analysis::PlaneStress {
            Analysis::PlaneStress
        } else {
            Analysis::PlaneStrain
        };
        let names: Vec<&String> = scene.materials.keys().collect();
        let mats: Vec<Elastic> = scene
            .materials
            .values()
            .map(|m| Elastic::new(m, analysis))
            .collect();

        // Particles on the lattice.
        let mut parts = Particles::default();
        let mut id = 0u32;
        fracture_api::lattice::for_each_seed(scene, |s| {
            let body = &scene.bodies[s.body as usize];
            let mat = names.iter().position(|n| **n == body.material).unwrap_or(0);
            let sub = h / s.ppc as f64;
            let vol = sub * sub * scene.thickness;
            let load = scene
                .loads
                .iter()
                .position(|l| l.region.contains(s.x))
                .map_or(0, |i| i as u32 + 1);
            parts.push(
                Kin {
                    x: s.x,
                    v: body.initial_velocity,
                },
                Mech {
                    m: mats[mat].rho * vol,
                    vol,
                    lh: 0.5 / s.ppc as f64,
                    mat: mat as u32,
                    load,
                },
                Cold {
                    x0: s.x,
                    id,
                    body: s.body,
                },
            );
            id += 1;
        });
        let m_min = parts.mech.iter().map(|m| m.m).fold(f64::INFINITY, f64::min);

        // Two velocity fields per node: cracks, or bodies that meet through a contact law.
        let multi_field =
            !scene.cracks.is_empty() || scene.bodies.iter().any(|b| b.contact.is_some());
        let geom = GridGeom::new(g.min, g.max, h);
        let layer = CrackLayer(
            multi_field.then(|| Box::new(Cracks::new(scene, &geom, &mats, size.time_step))),
        );
        let spec = Spec::<Dim2> {
            min: g.min,
            max: g.max,
            h,
            shape: g.shape_function,
            materials: mats,
            particles: parts,
            bcs: fracture_mpm::scenes::bc_specs_2d(scene),
            // Traction × thickness: force per unit edge length (N/m).
            loads: scene
                .loads
                .iter()
                .map(|l| LoadSpec {
                    traction: [
                        l.traction[0] * scene.thickness,
                        l.traction[1] * scene.thickness,
                    ],
                    ramp: l.ramp_time.unwrap_or(0.0),
                })
                .collect(),
            damping: scene.damping.clone(),
            dt: size.time_step,
            total_steps: size.steps,
            threads: config.threads.resolve(),
            scene_hash: scene.hash(),
        };
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
