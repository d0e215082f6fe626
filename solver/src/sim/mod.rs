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
//! This file holds the [`Simulation`] state and the step's order. The sections live in:
//! `config` (threads), `checkpoint` (the persistent state as bytes, and back), `errors` (build and step errors, first failure of a pass), `build`
//! ([`Simulation::new`]), `sort` (particles by cell), `stencil` (the 3×3 node visits of one
//! particle: field-0 fast path and generic multi-field path), `transfer` (the four particle
//! passes, each written once over a stencil), `grid_update` (nodal values, damping),
//! `boundary` (velocity conditions, loads) and `observe` (views, energies, tips, snapshots,
//! counters). The crack steps (fields, contact, crack motion, J, propagation) live in
//! [`crate::crack`].

mod boundary;
mod build;
mod checkpoint;
mod config;
mod errors;
mod grid_update;
mod observe;
mod sort;
mod transfer;

use fracture_api::Scene;
use fracture_api::scene::{Damping, ShapeFunction};

use crate::crack::Cracks;
pub use crate::crack::Stage;
use crate::grid::{GridGeom, Node};
use crate::material::Elastic;
use crate::particles::Particles;
use boundary::{BcNodes, LoadForce};
pub use checkpoint::{CHECKPOINT_FORMAT, CheckpointError, checkpoint_steps};
pub use config::{Parallelism, SolverConfig};
pub use errors::{BuildError, StepError};
pub use observe::WorkCounters;

/// What happened in one step.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepStats {
    /// Some crack tip advanced in this step.
    pub grew: bool,
    /// Active grid nodes in this step.
    pub active_nodes: usize,
}

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
    /// The energy ledger (the core's).
    ledger: fracture_mpm::Ledger,
    energy_scale: f64,
    pool: std::sync::Arc<rayon::ThreadPool>,
    load_now: Vec<[f64; 2]>,
    threads: usize,
    // Sort scratch.
    /// The sort's work arrays.
    sorter: fracture_mpm::sort::SortScratch<fracture_mpm::Dim2>,
    col_sums: Vec<f64>,
    cracks: Option<Box<Cracks>>,
    counters: WorkCounters,
    /// Every particle through the generic stencil path (tests of the fast path only).
    generic_stencil: bool,
    /// Spare grid: the next step's P2G, scattered by a fused pass 4 (`transfer.rs`).
    nodes_alt: Vec<Node>,
    /// Box of `nodes_alt` that may be non-zero.
    alt_box: Option<[usize; 4]>,
    /// Reduction of the P2G already in `nodes_alt` for the coming step.
    prefetched: Option<transfer::Acc>,
    /// Fuse pass 4 with the next P2G where possible (switch for tests and benchmarks).
    fuse: bool,
    /// Arithmetic of the particle passes (`kernel.rs`).
    kernel: crate::kernel::Kernel,
    /// Where the particle passes run (the core's host backend today).
    backend: Box<dyn fracture_mpm::Backend<fracture_mpm::Dim2>>,
}

impl Simulation {
    /// Advance one time step.
    pub fn step(&mut self) -> Result<StepStats, StepError> {
        let pool = std::sync::Arc::clone(&self.pool);
        pool.install(|| self.step_inner())
    }

    fn step_inner(&mut self) -> Result<StepStats, StepError> {
        // This step's P2G, when the last step's fused pass 4 did it (`transfer.rs`).
        let prefetched = self.take_prefetched_p2g();
        if prefetched.is_none() && self.needs_sort {
            self.sort_particles()?;
        }
        let dt = self.dt;
        let t0 = self.time;
        let t1 = t0 + dt;
        if prefetched.is_none() {
            self.reset_grid();
            self.setup_fields()?;
        }
        self.ramp_loads(t0);

        // Pass 1: P2G, then contact and boundary conditions on the momenta.
        let acc = match prefetched {
            Some(acc) => acc,
            None => self.pass_p2g(),
        };
        self.check(&acc)?;
        self.set_active_box(&acc);
        self.apply_bc_momentum(t0, false);
        self.contact(Stage::Extrapolated);
        self.nodal(Stage::Extrapolated);

        // Pass 2: first stress half-update and forces; damping, BC force fix, contact.
        let acc = self.pass_forces();
        self.check(&acc)?;
        self.damp_forces();
        self.bc_force_fix(t1);
        self.zone_forces();
        self.contact(Stage::Forces);
        self.nodal(Stage::Forces);

        // Pass 3: particle update and re-extrapolation; BCs and contact on the new momenta.
        let acc = self.pass_update();
        self.check(&acc)?;
        self.ledger.kinetic = acc.e;
        self.ledger.external_work += acc.w;
        self.ledger.work_abs += acc.w.abs();
        self.needs_sort |= acc.resort;
        self.apply_bc_momentum(t1, true);
        self.bond_hold();
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
        self.ledger.strain = acc.e;

        self.time = t1;
        self.steps += 1;

        // Propagation (§7).
        let grew = self.propagate()?;

        // Energy blow-up: kinetic + strain far above everything ever put in.
        let energy = self.ledger.kinetic + self.ledger.strain;
        let reference =
            self.ledger.initial_total.abs() + self.ledger.work_abs + self.ledger.dissipated;
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

    /// Send every particle through the generic multi-field stencil instead of the field-0
    /// fast path (`stencil.rs`). The two give bitwise identical results; this switch exists
    /// for the test that proves it (`tests/stencil_paths.rs`), not for users.
    #[doc(hidden)]
    pub fn force_generic_stencil(&mut self, on: bool) {
        self.generic_stencil = on;
    }

    /// Fuse the last stress half-update with the next step's P2G where no re-sort and no
    /// crack falls between (on by default; bitwise identical either way: `tests/fused_step.rs`).
    /// A switch for that test and for benchmarks.
    #[doc(hidden)]
    pub fn set_fused_step(&mut self, on: bool) {
        self.fuse = on;
    }

    /// The arithmetic of the particle passes: [`Kernel::Portable`](crate::kernel::Kernel) (the
    /// same bits on every CPU) or [`Kernel::Fma`](crate::kernel::Kernel) (fused multiply-add,
    /// last-bit differences, `kernel.rs`); by default the portable one. Returns the
    /// kernel in use: the portable one where `kernel` is not available on this CPU.
    pub fn set_kernel(&mut self, kernel: crate::kernel::Kernel) -> crate::kernel::Kernel {
        self.kernel = if kernel.available() {
            kernel
        } else {
            crate::kernel::Kernel::Portable
        };
        // A P2G done ahead by the last fused step used the other arithmetic.
        self.prefetched = None;
        self.kernel
    }

    /// The arithmetic of the particle passes.
    pub fn kernel(&self) -> crate::kernel::Kernel {
        self.kernel
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
            self.ledger.dissipated += d;
        }
    }

    /// Process-zone tractions behind tips grown by the equation of motion (`crack/zone.rs`),
    /// before the force-stage contact; their work is dissipated (fracture energy).
    fn zone_forces(&mut self) {
        if let Some(cr) = self.cracks.as_mut() {
            let w = cr.zone_forces(
                &self.geom,
                &mut self.nodes,
                &mut self.f1,
                &self.slot_of,
                self.dt,
            );
            self.ledger.dissipated += w;
        }
    }

    /// Rigid bonded interface points hold their re-extrapolated momenta together
    /// (`crack/zone.rs`, `Cracks::bond_hold`).
    fn bond_hold(&mut self) {
        if let Some(cr) = self.cracks.as_mut() {
            cr.bond_hold(&self.geom, &mut self.nodes, &mut self.f1, &self.slot_of);
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
            viscous_damping: match self.damping {
                Damping::Viscous { coefficient } => coefficient,
                _ => 0.0,
            },
            m_tiny: self.m_tiny,
        }
    }
}
