//! Building a simulation from a validated scene: particles on the seeding lattice
//! (`fracture_api::lattice`, uniform GIMP half-widths, `algorithm.md` §1), materials, boundary
//! conditions and loads resolved to nodes, the grid, scratch sized up front (no allocation per
//! step), and the crack state (§3) when the scene has cracks.

use fracture_api::ValidScene;
use fracture_api::scene::Analysis;

use super::boundary::{LoadForce, resolve_bcs};
use super::{BuildError, Simulation, SolverConfig, WorkCounters};
use crate::crack::Cracks;
use crate::grid::{GridGeom, Node};
use crate::material::Elastic;
use crate::particles::{Cold, Kin, Mech, Particles};

impl Simulation {
    /// Build a simulation from a scene (validated here too).
    pub fn new(valid: &ValidScene, config: SolverConfig) -> Result<Simulation, BuildError> {
        let (scene, size) = (valid.scene(), valid.size());
        let threads = config.threads.resolve();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| BuildError::Threads(e.to_string()))?;
        let g = &scene.grid;
        let geom = GridGeom::new(g.min, g.max, g.cell_size);
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
            parts.kin.push(Kin {
                x: s.x,
                v: body.initial_velocity,
            });
            parts.mech.push(Mech {
                m: mats[mat].rho * vol,
                vol,
                lh: 0.5 / s.ppc as f64,
                mat: mat as u32,
                load,
            });
            parts.stress.push([0.0; 4]);
            parts.cold.push(Cold {
                x0: s.x,
                id,
                body: s.body,
            });
            parts.wden.push(0.0);
            parts.wts.push(crate::shape::CachedW2::default());
            id += 1;
        });
        let n = parts.len();
        let m_min = parts.mech.iter().map(|m| m.m).fold(f64::INFINITY, f64::min);

        // Boundary conditions resolved to nodes.
        let bcs = resolve_bcs(scene, &geom);
        let loads = LoadForce::resolve(scene);

        let c_max = mats.iter().map(|m| m.c_l).fold(0.0, f64::max);
        let mass_total: f64 = parts.mech.iter().map(|m| m.m).sum();
        let storage = geom.storage_len();
        // Two velocity fields per node: cracks, or bodies that meet through a contact law.
        let multi_field =
            !scene.cracks.is_empty() || scene.bodies.iter().any(|b| b.contact.is_some());
        let mut sim = Simulation {
            scene: scene.clone(),
            geom,
            shape: g.shape_function,
            mats,
            nodes: vec![Node::default(); storage],
            f1: Vec::new(),
            f1_index: Vec::new(),
            slot_of: Vec::new(),
            strip_bounds: vec![0; geom.strips + 1],
            needs_sort: true,
            bcs,
            loads,
            damping: scene.damping.clone(),
            dt: size.time_step,
            time: 0.0,
            steps: 0,
            total_steps: size.steps,
            active_box: [0, 0, 0, 0],
            active_nodes: 0,
            // Gathers must use every node with mass: skipping light nodes breaks Σ∇S = 0 and
            // strains a rigidly moving body.
            m_tiny: f64::MIN_POSITIVE,
            m_snapshot: 1e-9 * m_min,
            ledger: fracture_mpm::Ledger::default(),
            energy_scale: 1e-12 * mass_total * c_max * c_max,
            pool: std::sync::Arc::new(pool),
            load_now: vec![[0.0; 2]; scene.loads.len()],
            threads,
            sorter: Default::default(),
            col_sums: vec![0.0; geom.cols],
            parts,
            cracks: None,
            counters: WorkCounters::default(),
            generic_stencil: false,
            nodes_alt: Vec::new(),
            alt_box: None,
            prefetched: None,
            fuse: true,
            // The portable kernel by default: every stored result and test reproduces bit for
            // bit; the FMA build is chosen with `set_kernel` or `fracture bench --kernel`.
            kernel: crate::kernel::Kernel::Portable,
            backend: Box::new(fracture_mpm::Cpu),
        };
        if multi_field {
            sim.slot_of = vec![u32::MAX; storage];
            sim.parts.fmask = vec![0; n];
            sim.parts.grad_u = vec![[0.0; 4]; n];
            sim.cracks = Some(Box::new(Cracks::new(scene, &sim.geom, &sim.mats, sim.dt)));
        }
        sim.ledger.kinetic = sim.kinetic_energy();
        sim.ledger.initial_total = sim.ledger.kinetic;
        Ok(sim)
    }

    /// Replace every particle's velocity by `f(x0)` of its initial position (an API for
    /// initial conditions richer than the scene's uniform velocities, e.g. a vibration mode).
    pub fn set_velocities(&mut self, f: impl Fn([f64; 2]) -> [f64; 2]) {
        for (k, c) in self.parts.kin.iter_mut().zip(&self.parts.cold) {
            k.v = f(c.x0);
        }
        // A P2G done ahead by the last fused step used the old velocities.
        self.prefetched = None;
        self.ledger.kinetic = self.kinetic_energy();
        self.ledger.initial_total =
            self.ledger.kinetic + self.ledger.strain + self.ledger.dissipated
                - self.ledger.external_work;
    }

    fn kinetic_energy(&self) -> f64 {
        self.parts
            .kin
            .iter()
            .zip(&self.parts.mech)
            .map(|(k, m)| 0.5 * m.m * (k.v[0] * k.v[0] + k.v[1] * k.v[1]))
            .sum()
    }
}
