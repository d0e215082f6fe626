//! The simulation: build from a scene, step (USAVG, `algorithm.md` §2), observe.
//!
//! One step is four particle passes around three grid updates:
//! 1. P2G: mass, momentum (and, with cracks, mass-weighted displacement) per velocity field;
//!    then contact and velocity boundary conditions.
//! 2. Velocity gradient from the grid, first stress half-update (Δt/2), internal and external
//!    forces to the grid; then damping, boundary-condition force fix, contact.
//! 3. Particle update (FLIP velocity, position with the average of old and new grid
//!    velocities) and re-extrapolation of momentum with the same weights; then contact and
//!    boundary conditions.
//! 4. Velocity gradient from the re-extrapolated momenta, second stress half-update.
//!
//! The crack steps (fields, contact, crack motion, J, propagation) live in [`crate::crack`].

use fracture_api::results::{CrackTipRow, EnergyRow, FieldComponent, Snapshot, field_components};
use fracture_api::scene::{Analysis, Damping, FieldKind, ShapeFunction};
use fracture_api::{Scene, ValidScene};
use rayon::prelude::*;

use crate::crack::Cracks;
pub use crate::crack::Stage;
use crate::grid::{
    GridGeom, GridMut, Node, PAD, Reduce, STRIP, field0_columns, for_strips, visit_stencil,
};
use crate::material::Elastic;
use crate::particles::{Cold, Kin, Mech, Particles, PartsMut};
use crate::shape::{Weights2, gimp_weights_1d};

/// How many threads the solver's parallel loops use. Results are bitwise identical for any
/// choice (deterministic strip-coloured scatter).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Parallelism {
    /// One thread per core (`std::thread::available_parallelism`).
    #[default]
    AllCores,
    /// Exactly this many threads.
    Threads(std::num::NonZeroUsize),
}

impl Parallelism {
    /// Exactly `n` threads (at least one).
    pub fn threads(n: usize) -> Parallelism {
        Parallelism::Threads(std::num::NonZeroUsize::MIN.saturating_add(n.saturating_sub(1)))
    }
    /// The command line's count: 0 means one per core, `n` means `n` threads.
    pub fn from_count(n: usize) -> Parallelism {
        if n == 0 {
            Parallelism::AllCores
        } else {
            Parallelism::threads(n)
        }
    }
    /// The number of threads this means on this machine.
    pub fn resolve(self) -> usize {
        match self {
            Parallelism::AllCores => std::thread::available_parallelism().map_or(1, |n| n.get()),
            Parallelism::Threads(n) => n.get(),
        }
    }
}

impl std::fmt::Display for Parallelism {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Parallelism::AllCores => f.write_str("all"),
            Parallelism::Threads(n) => write!(f, "{n}"),
        }
    }
}

impl std::str::FromStr for Parallelism {
    type Err = String;
    /// `all` (or `0`) for one thread per core, or a thread count.
    fn from_str(s: &str) -> Result<Parallelism, String> {
        let s = s.trim();
        if s.eq_ignore_ascii_case("all") {
            return Ok(Parallelism::AllCores);
        }
        s.parse::<usize>()
            .map(Parallelism::from_count)
            .map_err(|_| format!("`{s}` is not a thread count (a whole number, or `all`)"))
    }
}

/// How the solver runs (not physics).
#[derive(Debug, Clone, Copy, Default)]
pub struct SolverConfig {
    /// Threads of the parallel loops.
    pub threads: Parallelism,
}

impl SolverConfig {
    /// One thread per core.
    pub fn all_cores() -> SolverConfig {
        SolverConfig {
            threads: Parallelism::AllCores,
        }
    }
    /// Exactly `n` threads (at least one).
    pub fn with_threads(n: usize) -> SolverConfig {
        SolverConfig {
            threads: Parallelism::threads(n),
        }
    }
}

/// Why a simulation could not be built.
#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    /// The thread pool could not be created.
    #[error("thread pool: {0}")]
    Threads(String),
}

/// Why a step failed: a numerical failure with its diagnosis.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StepError {
    /// A particle quantity became NaN or infinite.
    #[error("step {step}: {quantity} of particle {particle} at ({x:.6e}, {y:.6e}) m is not finite")]
    NonFinite {
        /// Step number.
        step: u64,
        /// Original particle index.
        particle: usize,
        /// Which quantity.
        quantity: &'static str,
        /// Particle position x (start of the step).
        x: f64,
        /// Particle position y.
        y: f64,
    },
    /// Total energy grew far beyond the energy put in.
    #[error(
        "step {step}: energy blow-up: kinetic + strain = {energy:.6e} J against {reference:.6e} J put in (initial energy + external work); reduce time.cfl or check the loads"
    )]
    EnergyBlowUp {
        /// Step number.
        step: u64,
        /// Kinetic + strain energy.
        energy: f64,
        /// Initial energy plus external work.
        reference: f64,
    },
    /// A particle reached the grid edge.
    #[error(
        "step {step}: particle {particle} reached the grid edge at ({x:.6e}, {y:.6e}) m; enlarge grid.min/grid.max"
    )]
    LeftGrid {
        /// Step number.
        step: u64,
        /// Original particle index.
        particle: usize,
        /// Position x.
        x: f64,
        /// Position y.
        y: f64,
    },
    /// A grid node needs more velocity fields than supported.
    #[error(
        "step {step}: node at ({x:.6e}, {y:.6e}) m needs {fields} velocity fields; at most {max} are supported (two cracks within a cell of each other?)"
    )]
    TooManyFields {
        /// Step number.
        step: u64,
        /// Node position x.
        x: f64,
        /// Node position y.
        y: f64,
        /// Fields needed.
        fields: u32,
        /// Fields supported.
        max: u32,
    },
}

/// What happened in one step.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepStats {
    /// Some crack tip advanced in this step.
    pub grew: bool,
    /// Active grid nodes in this step.
    pub active_nodes: usize,
}

/// How often the optional phases of a step ran: cheap counters (incremented once per phase
/// call, outside the particle and node loops) that show what a scene skips.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct WorkCounters {
    /// Steps taken.
    pub steps: u64,
    /// Crack velocity-field assignments (one per step with cracks, §3).
    pub crack_field_passes: u64,
    /// Crack-face contact passes (three per step with cracks, §4).
    pub contact_passes: u64,
    /// Crack-surface moves (one per step with cracks, §5).
    pub surface_moves: u64,
    /// Propagation checks (one per step with cracks, §7).
    pub propagation_checks: u64,
    /// J-integral evaluations (per tip, on a history sample or a growth check, §6).
    pub j_evaluations: u64,
}

/// A prescribed-velocity condition resolved to grid nodes.
#[derive(Debug, Clone)]
struct BcNodes {
    nodes: Vec<u32>,
    vx: Option<f64>,
    vy: Option<f64>,
    ramp: f64,
    start: f64,
    end: f64,
}

impl BcNodes {
    /// Prescribed velocity components at time t (None where free or inactive).
    fn velocity(&self, t: f64) -> [Option<f64>; 2] {
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
struct LoadForce {
    t: [f64; 2],
    ramp: f64,
}

/// Reduction of a particle pass: partial sums and the first offending particle.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Acc {
    /// Kinetic energy (pass 3) or strain energy (pass 4).
    pub e: f64,
    /// External work of tractions (pass 3).
    pub w: f64,
    /// A particle drifted too far from its strip: re-sort before the next scatter.
    pub resort: bool,
    /// First failure: (sorted index, kind).
    pub fail: Option<(usize, u8)>,
    /// Active box in node columns/rows.
    pub bx: [i64; 4],
    /// Whether `bx` is set.
    pub has_box: bool,
}

impl Reduce for Acc {
    fn merge(self, r: Self) -> Self {
        let bx = match (self.has_box, r.has_box) {
            (true, true) => [
                self.bx[0].min(r.bx[0]),
                self.bx[1].max(r.bx[1]),
                self.bx[2].min(r.bx[2]),
                self.bx[3].max(r.bx[3]),
            ],
            (true, false) => self.bx,
            _ => r.bx,
        };
        Acc {
            e: self.e + r.e,
            w: self.w + r.w,
            resort: self.resort || r.resort,
            fail: match (self.fail, r.fail) {
                (Some(a), Some(b)) => Some(if a.0 <= b.0 { a } else { b }),
                (a, b) => a.or(b),
            },
            bx,
            has_box: self.has_box || r.has_box,
        }
    }
}

const FAIL_VELOCITY: u8 = 1;
const FAIL_POSITION: u8 = 2;
const FAIL_STRESS: u8 = 3;
const FAIL_GRID: u8 = 4;

/// A running simulation.
pub struct Simulation {
    scene: Scene,
    geom: GridGeom,
    shape: ShapeFunction,
    mats: Vec<Elastic>,
    parts: Particles,
    /// Field-0 nodes (storage layout of `GridGeom`).
    nodes: Vec<Node>,
    /// Field-1 nodes, in storage order, and their storage indices.
    f1: Vec<Node>,
    f1_index: Vec<u32>,
    /// Dense map storage index → field-1 slot (u32::MAX when none); empty without cracks.
    slot_of: Vec<u32>,
    strip_bounds: Vec<usize>,
    needs_sort: bool,
    bcs: Vec<BcNodes>,
    loads: Vec<LoadForce>,
    damping: Damping,
    dt: f64,
    time: f64,
    steps: u64,
    total_steps: u64,
    /// Active box [ix0, ix1, iy0, iy1] of the last P2G (inclusive).
    active_box: [usize; 4],
    active_nodes: usize,
    m_tiny: f64,
    /// Nodes lighter than this are left empty (NaN) in snapshots.
    m_snapshot: f64,
    // Energies.
    kinetic: f64,
    strain: f64,
    external_work: f64,
    dissipated: f64,
    initial_total: f64,
    energy_scale: f64,
    work_abs: f64,
    pool: std::sync::Arc<rayon::ThreadPool>,
    load_now: Vec<[f64; 2]>,
    threads: usize,
    // Sort scratch.
    sort_keys: Vec<u32>,
    sort_count: Vec<u32>,
    sort_perm: Vec<u32>,
    scratch_kin: Vec<Kin>,
    scratch_mech: Vec<Mech>,
    scratch_stress: Vec<[f64; 4]>,
    scratch_cold: Vec<Cold>,
    scratch_grad: Vec<[f64; 4]>,
    col_sums: Vec<f64>,
    cracks: Option<Box<Cracks>>,
    counters: WorkCounters,
}

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
                w: 0.0,
                mat: mat as u32,
                load,
            });
            parts.stress.push([0.0; 4]);
            parts.cold.push(Cold {
                x0: s.x,
                id,
                body: s.body,
            });
            parts.x_next.push(s.x);
            parts.wts.push(Weights2::default());
            id += 1;
        });
        let n = parts.len();
        let m_min = parts.mech.iter().map(|m| m.m).fold(f64::INFINITY, f64::min);

        // Boundary conditions resolved to nodes.
        let bcs = scene
            .boundary_conditions
            .iter()
            .map(|bc| {
                let mut nodes = Vec::new();
                for ix in 0..geom.nx {
                    for iy in 0..geom.ny {
                        if bc.region.contains(geom.node_pos(ix, iy)) {
                            nodes.push(geom.index(ix, iy) as u32);
                        }
                    }
                }
                BcNodes {
                    nodes,
                    vx: bc.velocity.x,
                    vy: bc.velocity.y,
                    ramp: bc.ramp_time.unwrap_or(0.0),
                    start: bc.start.unwrap_or(0.0),
                    end: bc.end.unwrap_or(f64::INFINITY),
                }
            })
            .collect();
        let loads = scene
            .loads
            .iter()
            .map(|l| LoadForce {
                t: [
                    l.traction[0] * scene.thickness,
                    l.traction[1] * scene.thickness,
                ],
                ramp: l.ramp_time.unwrap_or(0.0),
            })
            .collect();

        let c_max = mats.iter().map(|m| m.c_l).fold(0.0, f64::max);
        let mass_total: f64 = parts.mech.iter().map(|m| m.m).sum();
        let storage = geom.storage_len();
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
            kinetic: 0.0,
            strain: 0.0,
            external_work: 0.0,
            dissipated: 0.0,
            initial_total: 0.0,
            energy_scale: 1e-12 * mass_total * c_max * c_max,
            work_abs: 0.0,
            pool: std::sync::Arc::new(pool),
            load_now: vec![[0.0; 2]; scene.loads.len()],
            threads,
            sort_keys: vec![0; n],
            sort_count: Vec::new(),
            sort_perm: vec![0; n],
            scratch_kin: vec![Kin::default(); n],
            scratch_mech: vec![Mech::default(); n],
            scratch_stress: vec![[0.0; 4]; n],
            scratch_cold: vec![Cold::default(); n],
            scratch_grad: if scene.cracks.is_empty() {
                Vec::new()
            } else {
                vec![[0.0; 4]; n]
            },
            col_sums: vec![0.0; geom.cols],
            parts,
            cracks: None,
            counters: WorkCounters::default(),
        };
        if !scene.cracks.is_empty() {
            sim.slot_of = vec![u32::MAX; storage];
            sim.parts.fmask = vec![0; n];
            sim.parts.grad_u = vec![[0.0; 4]; n];
            sim.cracks = Some(Box::new(Cracks::new(scene, &sim.geom, &sim.mats)));
        }
        sim.kinetic = sim.kinetic_energy();
        sim.initial_total = sim.kinetic;
        Ok(sim)
    }

    /// Replace every particle's velocity by `f(x0)` of its initial position (an API for
    /// initial conditions richer than the scene's uniform velocities, e.g. a vibration mode).
    pub fn set_velocities(&mut self, f: impl Fn([f64; 2]) -> [f64; 2]) {
        for (k, c) in self.parts.kin.iter_mut().zip(&self.parts.cold) {
            k.v = f(c.x0);
        }
        self.kinetic = self.kinetic_energy();
        self.initial_total = self.kinetic + self.strain + self.dissipated - self.external_work;
    }

    fn kinetic_energy(&self) -> f64 {
        self.parts
            .kin
            .iter()
            .zip(&self.parts.mech)
            .map(|(k, m)| 0.5 * m.m * (k.v[0] * k.v[0] + k.v[1] * k.v[1]))
            .sum()
    }

    /// Counting sort of the particles by cell (column-major), and the strip bounds.
    fn sort_particles(&mut self) -> Result<(), StepError> {
        let geom = self.geom;
        let ncx = geom.nx - 1;
        let ncy = geom.ny - 1;
        let ncells = ncx * ncy;
        for (i, k) in self.parts.kin.iter().enumerate() {
            let (cx, cy) = geom.cell(k.x);
            if cx < 1 || cy < 1 || cx as usize + 2 > ncx || cy as usize + 2 > ncy {
                return Err(StepError::LeftGrid {
                    step: self.steps,
                    particle: self.parts.cold[i].id as usize,
                    x: k.x[0],
                    y: k.x[1],
                });
            }
            self.sort_keys[i] = (cx as usize * ncy + cy as usize) as u32;
        }
        self.sort_count.clear();
        self.sort_count.resize(ncells + 1, 0);
        for &k in &self.sort_keys {
            self.sort_count[k as usize + 1] += 1;
        }
        for c in 0..ncells {
            self.sort_count[c + 1] += self.sort_count[c];
        }
        // Strip bounds: first particle with cell column ≥ s·STRIP.
        for s in 0..=geom.strips {
            let col = (s * STRIP).min(ncx);
            self.strip_bounds[s] = self.sort_count[col * ncy] as usize;
        }
        for (i, &k) in self.sort_keys.iter().enumerate() {
            let dst = &mut self.sort_count[k as usize];
            self.sort_perm[i] = *dst;
            *dst += 1;
        }
        let p = &mut self.parts;
        for (i, &d) in self.sort_perm.iter().enumerate() {
            let d = d as usize;
            self.scratch_kin[d] = p.kin[i];
            self.scratch_mech[d] = p.mech[i];
            self.scratch_stress[d] = p.stress[i];
            self.scratch_cold[d] = p.cold[i];
        }
        std::mem::swap(&mut p.kin, &mut self.scratch_kin);
        std::mem::swap(&mut p.mech, &mut self.scratch_mech);
        std::mem::swap(&mut p.stress, &mut self.scratch_stress);
        std::mem::swap(&mut p.cold, &mut self.scratch_cold);
        if !p.grad_u.is_empty() {
            for (i, &d) in self.sort_perm.iter().enumerate() {
                self.scratch_grad[d as usize] = p.grad_u[i];
            }
            std::mem::swap(&mut p.grad_u, &mut self.scratch_grad);
        }
        self.needs_sort = false;
        Ok(())
    }

    /// Advance one time step.
    pub fn step(&mut self) -> Result<StepStats, StepError> {
        let pool = std::sync::Arc::clone(&self.pool);
        pool.install(|| self.step_inner())
    }

    fn step_inner(&mut self) -> Result<StepStats, StepError> {
        if self.needs_sort {
            self.sort_particles()?;
        }
        let dt = self.dt;
        let t0 = self.time;
        let t1 = t0 + dt;
        self.reset_grid();
        self.setup_fields()?;
        for (l, out) in self.loads.iter().zip(self.load_now.iter_mut()) {
            let r = if l.ramp > 0.0 {
                (t0 / l.ramp).min(1.0)
            } else {
                1.0
            };
            *out = [l.t[0] * r, l.t[1] * r];
        }

        // Pass 1: P2G, then contact and boundary conditions on the momenta.
        let acc = self.pass_p2g();
        self.check(&acc)?;
        self.set_active_box(&acc);
        self.apply_bc_momentum(t0, false);
        self.contact(Stage::Extrapolated);
        self.nodal(Stage::Extrapolated);

        // Pass 2: first stress half-update and forces; damping, BC force fix, contact.
        let acc = self.pass_forces();
        self.check(&acc)?;
        self.grid_forces(t1);
        self.contact(Stage::Forces);
        self.nodal(Stage::Forces);

        // Pass 3: particle update and re-extrapolation; BCs and contact on the new momenta.
        let acc = self.pass_update();
        self.check(&acc)?;
        self.kinetic = acc.e;
        self.external_work += acc.w;
        self.work_abs += acc.w.abs();
        self.needs_sort |= acc.resort;
        self.apply_bc_momentum(t1, true);
        self.contact(Stage::Reextrapolated);
        self.nodal(Stage::Reextrapolated);

        // Crack surfaces move with the grid velocities (§5).
        if let Some(cr) = self.cracks.as_mut() {
            self.counters.surface_moves += 1;
            cr.move_surfaces(
                &self.geom,
                &self.nodes,
                &self.f1,
                &self.slot_of,
                self.m_tiny,
                dt,
            );
        }

        // Pass 4: second stress half-update; positions committed.
        let acc = self.pass_strain_last();
        self.check(&acc)?;
        self.strain = acc.e;

        self.time = t1;
        self.steps += 1;

        // Propagation (§7).
        let grew = self.propagate()?;

        // Energy blow-up: kinetic + strain far above everything ever put in.
        let energy = self.kinetic + self.strain;
        let reference = self.initial_total.abs() + self.work_abs + self.dissipated;
        if !energy.is_finite() || energy > 10.0 * reference + self.energy_scale {
            return Err(StepError::EnergyBlowUp {
                step: self.steps,
                energy,
                reference,
            });
        }
        Ok(StepStats {
            grew,
            active_nodes: self.active_nodes,
        })
    }

    fn check(&self, acc: &Acc) -> Result<(), StepError> {
        let Some((i, kind)) = acc.fail else {
            return Ok(());
        };
        let k = self.parts.kin[i];
        let particle = self.parts.cold[i].id as usize;
        let step = self.steps + 1;
        Err(match kind {
            FAIL_GRID => StepError::LeftGrid {
                step,
                particle,
                x: self.parts.x_next[i][0],
                y: self.parts.x_next[i][1],
            },
            _ => StepError::NonFinite {
                step,
                particle,
                quantity: match kind {
                    FAIL_VELOCITY => "velocity",
                    FAIL_POSITION => "position",
                    _ => "stress",
                },
                x: k.x[0],
                y: k.x[1],
            },
        })
    }

    /// Zero the grid where the last step wrote.
    fn reset_grid(&mut self) {
        let [x0, x1, y0, y1] = self.active_box;
        if x1 >= x0 && self.active_nodes > 0 {
            let ny = self.geom.ny;
            let start = (x0 + PAD) * ny;
            let end = (x1 + 1 + PAD) * ny;
            self.nodes[start..end]
                .par_chunks_mut(ny)
                .for_each(|col| col[y0..=y1].fill(Node::default()));
        }
        for &i in &self.f1_index {
            self.slot_of[i as usize] = u32::MAX;
        }
        self.f1.clear();
        self.f1_index.clear();
    }

    /// Crack velocity fields of every particle–node pair and the field-1 node table.
    fn setup_fields(&mut self) -> Result<(), StepError> {
        let Some(cr) = self.cracks.as_mut() else {
            return Ok(());
        };
        self.counters.crack_field_passes += 1;
        cr.assign_fields(
            &self.geom,
            self.shape,
            &self.parts.kin,
            &self.parts.mech,
            &mut self.parts.fmask,
            &mut self.f1_index,
        )
        .map_err(|(idx, fields)| {
            let (ix, iy) = self.geom.node_of(idx);
            let p = self.geom.node_pos(ix, iy);
            StepError::TooManyFields {
                step: self.steps + 1,
                x: p[0],
                y: p[1],
                fields,
                max: 2,
            }
        })?;
        self.f1.resize(self.f1_index.len(), Node::default());
        for (slot, &i) in self.f1_index.iter().enumerate() {
            self.slot_of[i as usize] = slot as u32;
        }
        Ok(())
    }

    fn set_active_box(&mut self, acc: &Acc) {
        if !acc.has_box {
            self.active_nodes = 0;
            return;
        }
        let g = self.geom;
        let b = [
            acc.bx[0].max(0) as usize,
            (acc.bx[1] as usize).min(g.nx - 1),
            acc.bx[2].max(0) as usize,
            (acc.bx[3] as usize).min(g.ny - 1),
        ];
        self.active_box = b;
        let ny = g.ny;
        let m_tiny = self.m_tiny;
        let cols = &self.nodes[(b[0] + PAD) * ny..(b[1] + 1 + PAD) * ny];
        self.active_nodes = cols
            .par_chunks(ny)
            .map(|c| c[b[2]..=b[3]].iter().filter(|n| n.m > m_tiny).count())
            .sum::<usize>()
            + self.f1.len();
    }

    /// Nodal velocity (p/m after extrapolation, q/m after re-extrapolation) or acceleration
    /// (f/m after the force stage) on every active node and field.
    fn nodal(&mut self, stage: Stage) {
        let m_tiny = self.m_tiny;
        let set = move |n: &mut Node| {
            if n.m > m_tiny {
                let inv = 1.0 / n.m;
                match stage {
                    Stage::Extrapolated => n.v = [n.p[0] * inv, n.p[1] * inv],
                    Stage::Forces => n.a = [n.f[0] * inv, n.f[1] * inv],
                    Stage::Reextrapolated => n.v = [n.q[0] * inv, n.q[1] * inv],
                }
            } else {
                n.v = [0.0; 2];
                n.a = [0.0; 2];
            }
        };
        let [x0, x1, y0, y1] = self.active_box;
        let ny = self.geom.ny;
        if self.active_nodes > 0 {
            self.nodes[(x0 + PAD) * ny..(x1 + 1 + PAD) * ny]
                .par_chunks_mut(ny)
                .for_each(|c| c[y0..=y1].iter_mut().for_each(set));
        }
        self.f1.iter_mut().for_each(set);
    }

    /// Velocity boundary conditions on the extrapolated (`reextrapolated == false`: p) or
    /// re-extrapolated (q) momenta, on every field of each constrained node.
    fn apply_bc_momentum(&mut self, t: f64, reextrapolated: bool) {
        let m_tiny = self.m_tiny;
        for bc in &self.bcs {
            let v = bc.velocity(t);
            if v[0].is_none() && v[1].is_none() {
                continue;
            }
            for &i in &bc.nodes {
                let i = i as usize;
                let slot = self.slot_of.get(i).copied().unwrap_or(u32::MAX);
                let apply = |n: &mut Node| {
                    if n.m <= m_tiny {
                        return;
                    }
                    let target = if reextrapolated { &mut n.q } else { &mut n.p };
                    for k in 0..2 {
                        if let Some(vk) = v[k] {
                            target[k] = n.m * vk;
                        }
                    }
                };
                apply(&mut self.nodes[i]);
                if slot != u32::MAX {
                    apply(&mut self.f1[slot as usize]);
                }
            }
        }
    }

    /// Damping and the boundary-condition force fix after the force pass.
    fn grid_forces(&mut self, t1: f64) {
        let dt = self.dt;
        let m_tiny = self.m_tiny;
        // Damping: a grid force against the motion (kinetic: local non-viscous; viscous:
        // mass-proportional); the work it removes is recorded as dissipated.
        let damp = self.damping.clone();
        if !matches!(damp, Damping::None) {
            let damp_node = move |n: &mut Node| -> f64 {
                if n.m <= m_tiny {
                    return 0.0;
                }
                let v = [n.p[0] / n.m, n.p[1] / n.m];
                match damp {
                    Damping::Viscous { coefficient } => {
                        let fd = [coefficient * n.p[0], coefficient * n.p[1]];
                        n.f[0] -= fd[0];
                        n.f[1] -= fd[1];
                        (fd[0] * v[0] + fd[1] * v[1]) * dt
                    }
                    Damping::Kinetic { coefficient } => {
                        let mut d = 0.0;
                        for k in 0..2 {
                            let fd = coefficient * n.f[k].abs() * v[k].signum();
                            n.f[k] -= fd;
                            d += fd * v[k] * dt;
                        }
                        d
                    }
                    Damping::None => 0.0,
                }
            };
            let [x0, x1, y0, y1] = self.active_box;
            let ny = self.geom.ny;
            let cols = &mut self.nodes[(x0 + PAD) * ny..(x1 + 1 + PAD) * ny];
            let sums = &mut self.col_sums[..x1 + 1 - x0];
            cols.par_chunks_mut(ny)
                .zip(sums.par_iter_mut())
                .for_each(|(c, s)| *s = c[y0..=y1].iter_mut().map(&damp_node).sum());
            let mut d: f64 = sums.iter().sum();
            for n in &mut self.f1 {
                d += damp_node(n);
            }
            self.dissipated += d;
        }
        // Boundary conditions: fix the force so that p + Δt f meets the prescribed velocity;
        // the reaction does work at the node's mid-step velocity.
        let mut work = 0.0;
        for bc in &self.bcs {
            let v = bc.velocity(t1);
            if v[0].is_none() && v[1].is_none() {
                continue;
            }
            for &i in &bc.nodes {
                let i = i as usize;
                let slot = self.slot_of.get(i).copied().unwrap_or(u32::MAX);
                let mut apply = |n: &mut Node| {
                    if n.m <= m_tiny {
                        return;
                    }
                    for k in 0..2 {
                        if let Some(vk) = v[k] {
                            let f_new = (n.m * vk - n.p[k]) / dt;
                            let v_mid = 0.5 * (n.p[k] / n.m + vk);
                            work += (f_new - n.f[k]) * v_mid * dt;
                            n.f[k] = f_new;
                        }
                    }
                };
                apply(&mut self.nodes[i]);
                if slot != u32::MAX {
                    apply(&mut self.f1[slot as usize]);
                }
            }
        }
        self.external_work += work;
        self.work_abs += work.abs();
    }

    fn contact(&mut self, stage: Stage) {
        if let Some(cr) = self.cracks.as_mut() {
            self.counters.contact_passes += 1;
            let d = cr.contact(
                stage,
                &mut self.nodes,
                &mut self.f1,
                &self.f1_index,
                self.m_tiny,
                self.dt,
            );
            self.dissipated += d;
        }
    }

    fn propagate(&mut self) -> Result<bool, StepError> {
        let Some(mut cr) = self.cracks.take() else {
            return Ok(false);
        };
        self.counters.propagation_checks += 1;
        let grew = cr.propagate(&self.view(), self.time);
        self.cracks = Some(cr);
        Ok(grew)
    }

    fn view(&self) -> crate::crack::View<'_> {
        crate::crack::View {
            geom: &self.geom,
            shape: self.shape,
            parts: &self.parts,
            mats: &self.mats,
            nodes: &self.nodes,
            f1: &self.f1,
            slot_of: &self.slot_of,
            strip_bounds: &self.strip_bounds,
        }
    }
}

/// Accumulate the stencil's contribution into the active box of `acc`.
#[inline(always)]
fn grow_box(acc: &mut Acc, w: &Weights2) {
    let (bx, by) = (w.x.base as i64, w.y.base as i64);
    if acc.has_box {
        acc.bx[0] = acc.bx[0].min(bx);
        acc.bx[1] = acc.bx[1].max(bx + 2);
        acc.bx[2] = acc.bx[2].min(by);
        acc.bx[3] = acc.bx[3].max(by + 2);
    } else {
        acc.bx = [bx, bx + 2, by, by + 2];
        acc.has_box = true;
    }
}

#[inline(always)]
fn first_fail(acc: &mut Acc, i: usize, kind: u8) {
    if acc.fail.is_none() {
        acc.fail = Some((i, kind));
    }
}

/// Velocity gradient of particle `i` from the nodal velocities (`Node::v`) of its own fields
/// (pitfall 3), then a stress half-update over `half` with the strain energy density and, with
/// cracks, the displacement gradient accumulated. Returns whether the new stress is finite.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn stress_half_update(
    p: &mut PartsMut<'_>,
    g: &mut GridMut<'_>,
    i: usize,
    geom: &GridGeom,
    slot_of: &[u32],
    mats: &[Elastic],
    half: f64,
    inv_h: f64,
) -> bool {
    let w = p.wts[i];
    let has_mask = !p.fmask.is_empty();
    let mask = if has_mask { p.fmask[i] } else { 0 };
    // L_ij = Σ_nodes v_i ∂S/∂x_j.
    let mut l = [[0.0; 2]; 2];
    visit_stencil(g, geom, &w, mask, slot_of, |a, b, n| {
        let gr = w.g(a, b);
        l[0][0] += n.v[0] * gr[0];
        l[0][1] += n.v[0] * gr[1];
        l[1][0] += n.v[1] * gr[0];
        l[1][1] += n.v[1] * gr[1];
    });
    let mech = &mut p.mech[i];
    let grad_u = p.grad_u.get_mut(i);
    stress_apply(
        &mats[mech.mat as usize],
        &mut p.stress[i],
        &mut mech.w,
        grad_u,
        l,
        half,
        inv_h,
    )
}

/// The stress half-update of one particle of material `mat` from the unscaled velocity
/// gradient `l` (Σ v ⊗ ∇S in cell units): stress, strain energy density `w` and, with cracks,
/// the displacement gradient `grad_u` accumulated. Returns whether the new stress is finite.
#[inline(always)]
fn stress_apply(
    mat: &Elastic,
    stress: &mut [f64; 4],
    w: &mut f64,
    grad_u: Option<&mut [f64; 4]>,
    mut l: [[f64; 2]; 2],
    half: f64,
    inv_h: f64,
) -> bool {
    for r in &mut l {
        r[0] *= inv_h;
        r[1] *= inv_h;
    }
    *w += mat.update(stress, l, half);
    if let Some(gu) = grad_u {
        gu[0] += l[0][0] * half;
        gu[1] += l[0][1] * half;
        gu[2] += l[1][0] * half;
        gu[3] += l[1][1] * half;
    }
    let s = *stress;
    s[0].is_finite() && s[1].is_finite() && s[2].is_finite()
}

// The field-0 fast path. A particle whose pairs are all in field 0 (every particle of a scene
// without cracks) with GIMP weights writes to three contiguous 3-node columns. The kernels
// below do the same arithmetic in the same node order as the `visit_stencil` path, so the
// results are bitwise identical; they only drop the per-node tests. The generic path skips
// pairs with S = 0 in P2G and in the force scatter: with GIMP, S = 0 implies ∇S = 0, so such
// a pair only adds signed zeros, which leave a sum that starts at +0 unchanged. (With linear
// weights a node on the particle's cell line has S = 0 but ∇S ≠ 0, hence GIMP only.)

/// Whether stencil column `a` of GIMP weights `w` is empty (S and S' both zero): skipped,
/// as in `visit_stencil`.
#[inline(always)]
fn empty_column(w: &Weights2, a: usize) -> bool {
    // GIMP: only the last column can be empty (the stencil base rule of `shape::gimp_1d`),
    // and S = 0 implies S' = 0.
    a == 2 && w.x.s[2] == 0.0
}

/// Whether the last stencil row of GIMP weights `w` is empty (a particle whose domain lies
/// inside one cell row): row `b` is skipped, as in `visit_stencil`, when `b == 2` and this
/// holds. The kernels test `b == 2 && last` inside their fixed 3-row loops, which the
/// compiler unrolls, so only the third row carries the branch.
#[inline(always)]
fn last_row_empty(w: &Weights2) -> bool {
    w.y.s[2] == 0.0
}

/// ∇S (cell units) of the 3×3 stencil, `[a][b]` as `Weights2::g`.
#[inline(always)]
fn stencil_grads(w: &Weights2) -> [[[f64; 2]; 3]; 3] {
    let mut g = [[[0.0; 2]; 3]; 3];
    for a in 0..3 {
        for b in 0..3 {
            g[a][b] = [w.x.ds[a] * w.y.s[b], w.x.s[a] * w.y.ds[b]];
        }
    }
    g
}

/// Σ v ⊗ ∇S over the field-0 columns (unscaled, as in `stress_half_update`).
#[inline(always)]
fn gather_l(cols: &[&mut [Node; 3]; 3], w: &Weights2, gr: &[[[f64; 2]; 3]; 3]) -> [[f64; 2]; 2] {
    let mut l = [[0.0; 2]; 2];
    let last = last_row_empty(w);
    for a in 0..3 {
        if empty_column(w, a) {
            continue;
        }
        for b in 0..3 {
            if b == 2 && last {
                break;
            }
            let (v, g) = (cols[a][b].v, gr[a][b]);
            l[0][0] += v[0] * g[0];
            l[0][1] += v[0] * g[1];
            l[1][0] += v[1] * g[0];
            l[1][1] += v[1] * g[1];
        }
    }
    l
}

impl Simulation {
    /// Run `f` on every strip (even colour, then odd) and merge the results in strip order.
    fn strips<F>(&mut self, f: &F) -> Acc
    where
        F: Fn(usize, usize, PartsMut<'_>, GridMut<'_>) -> Acc + Sync,
    {
        let geom = self.geom;
        let mut out = Acc::default();
        for colour in 0..2 {
            let grid = GridMut {
                nodes: &mut self.nodes,
                base: 0,
                f1: &mut self.f1,
                f1_index: &self.f1_index,
                f1_base: 0,
            };
            let parts = PartsMut::new(&mut self.parts);
            let bounds = &self.strip_bounds;
            let a: Acc = for_strips(&geom, bounds, colour, parts, grid, &|s, p, g| {
                f(s, bounds[s], p, g)
            });
            out = if colour == 0 { a } else { out.merge(a) };
        }
        out
    }

    /// Pass 1: P2G of mass, momentum and (with cracks) mass-weighted displacement.
    fn pass_p2g(&mut self) -> Acc {
        let geom = self.geom;
        let shape = self.shape;
        let gimp = shape == ShapeFunction::Gimp;
        let cracks = self.cracks.is_some();
        let slot_of = std::mem::take(&mut self.slot_of);
        let acc = self.strips(&|_s, first, p, mut g| {
            let mut acc = Acc::default();
            p.assert_lengths();
            // 1/(4l) of the last particle size seen (all particles of a body share it).
            let (mut l_last, mut q_last) = (f64::NAN, f64::NAN);
            for i in 0..p.len() {
                let k = p.kin[i];
                let m = p.mech[i].m;
                let lh = p.mech[i].lh;
                let xi = geom.xi(k.x);
                if gimp {
                    if lh != l_last {
                        (l_last, q_last) = (lh, 0.25 / lh);
                    }
                    let wt = &mut p.wts[i];
                    wt.x = gimp_weights_1d(xi[0], lh, q_last);
                    wt.y = gimp_weights_1d(xi[1], lh, q_last);
                } else {
                    p.wts[i] = Weights2::new(shape, xi, lh);
                }
                let w = &p.wts[i];
                grow_box(&mut acc, w);
                let (mask, disp) = if cracks {
                    let x0 = p.cold[i].x0;
                    (p.fmask[i], [k.x[0] - x0[0], k.x[1] - x0[1]])
                } else {
                    (0, [0.0; 2])
                };
                if !(k.v[0].is_finite() && k.v[1].is_finite()) {
                    first_fail(&mut acc, first + i, FAIL_VELOCITY);
                }
                let mv = [m * k.v[0], m * k.v[1]];
                if gimp && mask == 0 {
                    let cols = field0_columns(&mut g, &geom, w);
                    let last = last_row_empty(w);
                    for (a, col) in cols.into_iter().enumerate() {
                        if empty_column(w, a) {
                            continue;
                        }
                        for (b, (n, &sy)) in col.iter_mut().zip(&w.y.s).enumerate() {
                            if b == 2 && last {
                                break;
                            }
                            let s = w.x.s[a] * sy;
                            n.m += s * m;
                            n.p[0] += s * mv[0];
                            n.p[1] += s * mv[1];
                            if cracks {
                                n.u[0] += s * m * disp[0];
                                n.u[1] += s * m * disp[1];
                            }
                        }
                    }
                    continue;
                }
                visit_stencil(&mut g, &geom, w, mask, &slot_of, |a, b, n| {
                    let s = w.s(a, b);
                    if s == 0.0 {
                        return;
                    }
                    n.m += s * m;
                    n.p[0] += s * mv[0];
                    n.p[1] += s * mv[1];
                    if cracks {
                        n.u[0] += s * m * disp[0];
                        n.u[1] += s * m * disp[1];
                    }
                });
            }
            acc
        });
        self.slot_of = slot_of;
        acc
    }

    /// Pass 2: velocity gradient from p/m, first stress half-update, forces to the grid.
    fn pass_forces(&mut self) -> Acc {
        let geom = self.geom;
        let gimp = self.shape == ShapeFunction::Gimp;
        let half = 0.5 * self.dt;
        let inv_h = 1.0 / geom.h;
        let h = geom.h;
        let slot_of = std::mem::take(&mut self.slot_of);
        let mats = std::mem::take(&mut self.mats);
        let loads = std::mem::take(&mut self.load_now);
        let acc = self.strips(&|_s, first, mut p, mut g| {
            let mut acc = Acc::default();
            p.assert_lengths();
            let has_mask = !p.fmask.is_empty();
            for i in 0..p.len() {
                let mech = p.mech[i];
                let mask = if has_mask { p.fmask[i] } else { 0 };
                // External force: traction × edge length (2l = h/ppc) × thickness.
                let fext = if mech.load > 0 {
                    let t = loads[mech.load as usize - 1];
                    let edge = 2.0 * mech.lh * h;
                    [t[0] * edge, t[1] * edge]
                } else {
                    [0.0; 2]
                };
                let vs = mech.vol * inv_h;
                if gimp && mask == 0 {
                    let w = &p.wts[i];
                    let gr = stencil_grads(w);
                    let cols = field0_columns(&mut g, &geom, w);
                    let l = gather_l(&cols, w, &gr);
                    let mat = &mats[mech.mat as usize];
                    let s = &mut p.stress[i];
                    let gu = p.grad_u.get_mut(i);
                    if !stress_apply(mat, s, &mut p.mech[i].w, gu, l, half, inv_h) {
                        first_fail(&mut acc, first + i, FAIL_STRESS);
                    }
                    let s = *s;
                    let last = last_row_empty(w);
                    for (a, col) in cols.into_iter().enumerate() {
                        if empty_column(w, a) {
                            continue;
                        }
                        for (b, n) in col.iter_mut().enumerate() {
                            if b == 2 && last {
                                break;
                            }
                            let g = gr[a][b];
                            let fi = [
                                -vs * (s[0] * g[0] + s[2] * g[1]),
                                -vs * (s[2] * g[0] + s[1] * g[1]),
                            ];
                            // Without a load the generic path adds S·0 = +0, which changes
                            // nothing here (see the fast-path note).
                            if mech.load > 0 {
                                let sh = w.x.s[a] * w.y.s[b];
                                n.f[0] += fi[0] + sh * fext[0];
                                n.f[1] += fi[1] + sh * fext[1];
                            } else {
                                n.f[0] += fi[0];
                                n.f[1] += fi[1];
                            }
                        }
                    }
                    continue;
                }
                if !stress_half_update(&mut p, &mut g, i, &geom, &slot_of, &mats, half, inv_h) {
                    first_fail(&mut acc, first + i, FAIL_STRESS);
                }
                let s = p.stress[i];
                let w = p.wts[i];
                visit_stencil(&mut g, &geom, &w, mask, &slot_of, |a, b, n| {
                    let sh = w.s(a, b);
                    if sh == 0.0 {
                        return;
                    }
                    let gr = w.g(a, b);
                    n.f[0] += -vs * (s[0] * gr[0] + s[2] * gr[1]) + sh * fext[0];
                    n.f[1] += -vs * (s[2] * gr[0] + s[1] * gr[1]) + sh * fext[1];
                });
            }
            acc
        });
        self.slot_of = slot_of;
        self.mats = mats;
        self.load_now = loads;
        acc
    }

    /// Pass 3: FLIP particle update and re-extrapolation of the new momenta with the same
    /// weights and fields.
    fn pass_update(&mut self) -> Acc {
        let geom = self.geom;
        let gimp = self.shape == ShapeFunction::Gimp;
        let dt = self.dt;
        let h = geom.h;
        let slot_of = std::mem::take(&mut self.slot_of);
        let loads = std::mem::take(&mut self.load_now);
        let (ncx, ncy) = ((geom.nx - 1) as i64, (geom.ny - 1) as i64);
        let acc = self.strips(&|s, first, p, mut g| {
            let mut acc = Acc::default();
            p.assert_lengths();
            let has_mask = !p.fmask.is_empty();
            let lo = (s * STRIP) as i64 - 1;
            let hi = ((s + 1) * STRIP) as i64;
            for i in 0..p.len() {
                let k = p.kin[i];
                let mech = p.mech[i];
                let w = &p.wts[i];
                let mask = if has_mask { p.fmask[i] } else { 0 };
                let fast = gimp && mask == 0;
                let mut acc_p = [0.0; 2];
                let mut vbar = [0.0; 2];
                let mut gather = |sh: f64, n: &Node| {
                    for c in 0..2 {
                        let an = sh * n.a[c];
                        acc_p[c] += an;
                        // (v_old + v_new)/2 = p/m + Δt/2 · f/m
                        vbar[c] += sh * n.v[c] + 0.5 * dt * an;
                    }
                };
                let last = last_row_empty(w);
                if fast {
                    let cols = field0_columns(&mut g, &geom, w);
                    for (a, col) in cols.iter().enumerate() {
                        if empty_column(w, a) {
                            continue;
                        }
                        for (b, (n, &sy)) in col.iter().zip(&w.y.s).enumerate() {
                            if b == 2 && last {
                                break;
                            }
                            gather(w.x.s[a] * sy, n);
                        }
                    }
                } else {
                    visit_stencil(&mut g, &geom, w, mask, &slot_of, |a, b, n| {
                        gather(w.s(a, b), n)
                    });
                }
                let v_old = k.v;
                let v = [v_old[0] + dt * acc_p[0], v_old[1] + dt * acc_p[1]];
                let xn = [k.x[0] + dt * vbar[0], k.x[1] + dt * vbar[1]];
                if !(v[0].is_finite() && v[1].is_finite()) {
                    first_fail(&mut acc, first + i, FAIL_VELOCITY);
                } else if !(xn[0].is_finite() && xn[1].is_finite()) {
                    first_fail(&mut acc, first + i, FAIL_POSITION);
                } else {
                    // Truncation (not floor): negative ξ gives 0 and is caught as < 1 too.
                    let xi = geom.xi(xn);
                    let (cx, cy) = (xi[0] as i64, xi[1] as i64);
                    if xi[0] < 1.0 || xi[1] < 1.0 || cx + 1 >= ncx || cy + 1 >= ncy {
                        first_fail(&mut acc, first + i, FAIL_GRID);
                    }
                    if cx < lo || cx > hi {
                        acc.resort = true;
                    }
                }
                p.kin[i].v = v;
                p.x_next[i] = xn;
                acc.e += 0.5 * mech.m * (v[0] * v[0] + v[1] * v[1]);
                if mech.load > 0 {
                    let t = loads[mech.load as usize - 1];
                    let edge = 2.0 * mech.lh * h;
                    // Work on the grid: F · v̄ Δt with v̄ the mid-step grid velocity at the
                    // particle (the velocity that moves it), consistent with the grid's energy.
                    acc.w += edge * (t[0] * vbar[0] + t[1] * vbar[1]) * dt;
                }
                // Re-extrapolate momentum with the same weights and fields (pitfall 2).
                let mv = [mech.m * v[0], mech.m * v[1]];
                if fast {
                    let cols = field0_columns(&mut g, &geom, w);
                    for (a, col) in cols.into_iter().enumerate() {
                        if empty_column(w, a) {
                            continue;
                        }
                        for (b, (n, &sy)) in col.iter_mut().zip(&w.y.s).enumerate() {
                            if b == 2 && last {
                                break;
                            }
                            let sh = w.x.s[a] * sy;
                            n.q[0] += sh * mv[0];
                            n.q[1] += sh * mv[1];
                        }
                    }
                } else {
                    visit_stencil(&mut g, &geom, w, mask, &slot_of, |a, b, n| {
                        let sh = w.s(a, b);
                        n.q[0] += sh * mv[0];
                        n.q[1] += sh * mv[1];
                    });
                }
            }
            acc
        });
        self.slot_of = slot_of;
        self.load_now = loads;
        acc
    }

    /// Pass 4: velocity gradient from the re-extrapolated momenta, second stress half-update,
    /// positions committed, strain energy summed.
    fn pass_strain_last(&mut self) -> Acc {
        let geom = self.geom;
        let gimp = self.shape == ShapeFunction::Gimp;
        let half = 0.5 * self.dt;
        let inv_h = 1.0 / geom.h;
        let slot_of = std::mem::take(&mut self.slot_of);
        let mats = std::mem::take(&mut self.mats);
        let acc = self.strips(&|_s, first, mut p, mut g| {
            let mut acc = Acc::default();
            p.assert_lengths();
            let has_mask = !p.fmask.is_empty();
            for i in 0..p.len() {
                let mech = p.mech[i];
                let mask = if has_mask { p.fmask[i] } else { 0 };
                let ok = if gimp && mask == 0 {
                    let w = &p.wts[i];
                    let gr = stencil_grads(w);
                    let cols = field0_columns(&mut g, &geom, w);
                    let l = gather_l(&cols, w, &gr);
                    let mat = &mats[mech.mat as usize];
                    let gu = p.grad_u.get_mut(i);
                    stress_apply(mat, &mut p.stress[i], &mut p.mech[i].w, gu, l, half, inv_h)
                } else {
                    stress_half_update(&mut p, &mut g, i, &geom, &slot_of, &mats, half, inv_h)
                };
                if !ok {
                    first_fail(&mut acc, first + i, FAIL_STRESS);
                }
                let wnew = p.mech[i].w;
                acc.e += mech.vol * wnew;
                p.kin[i].x = p.x_next[i];
            }
            acc
        });
        self.slot_of = slot_of;
        self.mats = mats;
        acc
    }
}
/// Read-only views.
impl Simulation {
    /// The scene.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }
    /// Simulated time (s).
    pub fn time(&self) -> f64 {
        self.time
    }
    /// Steps taken.
    pub fn steps_taken(&self) -> u64 {
        self.steps
    }
    /// Δt (s).
    pub fn time_step(&self) -> f64 {
        self.dt
    }
    /// End time (s).
    pub fn end_time(&self) -> f64 {
        self.scene.time.end
    }
    /// Steps to reach the end time.
    pub fn total_steps(&self) -> u64 {
        self.total_steps
    }
    /// Whether the end time is reached.
    pub fn is_finished(&self) -> bool {
        self.steps >= self.total_steps
    }
    /// Number of particles.
    pub fn particle_count(&self) -> usize {
        self.parts.len()
    }
    /// Nodes of the grid box.
    pub fn grid_node_count(&self) -> usize {
        self.geom.nx * self.geom.ny
    }
    /// Nodes (and extra crack fields) touched by particles in the last step.
    pub fn active_node_count(&self) -> usize {
        self.active_nodes
    }
    /// Threads in use.
    pub fn threads(&self) -> usize {
        self.threads
    }
    /// Grid geometry.
    pub fn grid(&self) -> &GridGeom {
        &self.geom
    }
    /// The particles (sorted by cell; `cold[i].id` is the creation index).
    pub fn particles(&self) -> &Particles {
        &self.parts
    }

    /// Energies now (J per the scene's thickness).
    pub fn energy(&self) -> EnergyRow {
        EnergyRow {
            time: self.time,
            kinetic: self.kinetic,
            strain: self.strain,
            external_work: self.external_work,
            dissipated: self.dissipated,
            total_error: self.kinetic + self.strain + self.dissipated
                - self.external_work
                - self.initial_total,
        }
    }

    /// One row per crack tip now (J and K computed here, on demand).
    pub fn crack_tips(&mut self) -> Vec<CrackTipRow> {
        let Some(mut cr) = self.cracks.take() else {
            return Vec::new();
        };
        let rows = cr.tip_rows(&self.view(), self.time);
        self.cracks = Some(cr);
        rows
    }

    /// The cracks, if the scene has any.
    pub fn cracks(&self) -> Option<&Cracks> {
        self.cracks.as_deref()
    }

    /// How often the optional (crack) phases have run so far.
    pub fn work_counters(&self) -> WorkCounters {
        WorkCounters {
            steps: self.steps,
            j_evaluations: self.cracks.as_ref().map_or(0, |c| c.j_evaluations()),
            ..self.counters
        }
    }

    /// Fields sampled at the grid nodes now: mass-weighted averages of particle values
    /// (NaN where no particle reaches a node).
    pub fn snapshot(&self, index: u32, fields: &[FieldKind]) -> Snapshot {
        let g = self.geom;
        let mut names: Vec<&'static str> = Vec::new();
        for f in fields {
            for c in field_components(*f) {
                if !names.contains(c) {
                    names.push(c);
                }
            }
        }
        let nn = g.nx * g.ny;
        let nc = names.len();
        let mut mass = vec![0.0f64; nn];
        let mut acc = vec![0.0f64; nn * nc];
        let thickness = self.scene.thickness;
        let fringe_c = self.scene.output.fringe_constant.unwrap_or(f64::NAN);
        let p = &self.parts;
        let mut vals = vec![0.0f64; nc];
        for i in 0..p.len() {
            let k = p.kin[i];
            let s = p.stress[i];
            // Small strain from the stress through the compliance (exact for linear
            // elasticity): ε = [σ − ν(tr σ − σ)]/E per axis, γ = σxy/μ.
            let mt = &self.mats[p.mech[i].mat as usize];
            let e = [
                (s[0] - mt.nu * (s[1] + s[3])) / mt.e,
                (s[1] - mt.nu * (s[0] + s[3])) / mt.e,
                s[2] / mt.c66,
            ];
            for (c, name) in names.iter().enumerate() {
                vals[c] = match *name {
                    "sxx" => s[0],
                    "syy" => s[1],
                    "sxy" => s[2],
                    "exx" => e[0],
                    "eyy" => e[1],
                    "exy" => 0.5 * e[2],
                    "vx" => k.v[0],
                    "vy" => k.v[1],
                    "speed" => k.v[0].hypot(k.v[1]),
                    "ux" => k.x[0] - p.cold[i].x0[0],
                    "uy" => k.x[1] - p.cold[i].x0[1],
                    // N = h(σ1 − σ2)/f_σ, σ1 − σ2 = 2·sqrt(((σxx − σyy)/2)² + σxy²).
                    "fringe" => thickness * 2.0 * (0.5 * (s[0] - s[1])).hypot(s[2]) / fringe_c,
                    "material" => p.mech[i].mat as f64,
                    _ => 0.0,
                };
            }
            let w = Weights2::new(self.shape, g.xi(k.x), p.mech[i].lh);
            for a in 0..3 {
                for b in 0..3 {
                    let sh = w.s(a, b);
                    if sh == 0.0 {
                        continue;
                    }
                    let ix = (w.x.base + a as i32) as usize;
                    let iy = (w.y.base + b as i32) as usize;
                    if ix >= g.nx || iy >= g.ny {
                        continue;
                    }
                    let n = iy * g.nx + ix;
                    let sm = sh * p.mech[i].m;
                    mass[n] += sm;
                    for c in 0..nc {
                        acc[n * nc + c] += sm * vals[c];
                    }
                }
            }
        }
        let components = names
            .iter()
            .enumerate()
            .map(|(c, name)| FieldComponent {
                name: (*name).to_string(),
                values: (0..nn)
                    .map(|n| {
                        if mass[n] > self.m_snapshot {
                            (acc[n * nc + c] / mass[n]) as f32
                        } else {
                            f32::NAN
                        }
                    })
                    .collect(),
            })
            .collect();
        Snapshot {
            index,
            time: self.time,
            nx: g.nx as u32,
            ny: g.ny as u32,
            origin: g.origin,
            cell_size: g.h,
            fields: fields.iter().map(|f| f.name().to_string()).collect(),
            components,
            cracks: self.cracks.as_ref().map(|c| c.lines()).unwrap_or_default(),
        }
    }
}
