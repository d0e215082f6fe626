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
//! The step sequence is the core's (`fracture_mpm::Simulation<Dim2, CrackLayer>`, written
//! once for both dimensions); the crack steps (fields, contact, zone and cohesive forces,
//! crack motion, propagation) enter it as the hooks of a layer (`layer.rs`, code in
//! [`crate::crack`]). This module holds the 2D [`Simulation`]: `build` (from a validated
//! scene), `checkpoint` (the core's state as bytes), `config` (threads), `errors` (build and
//! step errors in 2D terms), `layer` and `observe` (views, energies, tips, snapshots,
//! counters).

mod build;
mod checkpoint;
mod config;
mod errors;
mod layer;
mod observe;

use fracture_api::Scene;
use fracture_mpm::Dim2;

pub use crate::crack::Stage;
pub use checkpoint::{CHECKPOINT_FORMAT, CheckpointError, checkpoint_steps};
pub use config::{Parallelism, SolverConfig};
pub use errors::{BuildError, StepError};
pub use fracture_mpm::{PassTimes, WorkCounters};
pub use layer::CrackLayer;

/// What happened in one step.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepStats {
    /// Some crack tip advanced in this step.
    pub grew: bool,
    /// Active grid nodes in this step.
    pub active_nodes: usize,
}

/// A running simulation: the core's 2D simulation with the crack layer on its step, and the
/// scene it was built from.
pub struct Simulation {
    scene: Scene,
    /// Nodes lighter than this are left empty (NaN) in snapshots.
    m_snapshot: f64,
    /// The step, its state (the checkpoint) and its working memory.
    core: fracture_mpm::Simulation<Dim2, CrackLayer>,
}

impl Simulation {
    /// Advance one time step.
    pub fn step(&mut self) -> Result<StepStats, StepError> {
        let s = self.core.step()?;
        Ok(StepStats {
            grew: s.grew,
            active_nodes: s.active_nodes,
        })
    }

    /// Send every particle through the generic multi-field stencil instead of the field-0
    /// fast path (`fracture_mpm::stencil`). The two give bitwise identical results; this
    /// switch exists for the test that proves it (`tests/stencil_paths.rs`), not for users.
    #[doc(hidden)]
    pub fn force_generic_stencil(&mut self, on: bool) {
        self.core.model.generic_stencil = on;
    }

    /// Fuse the last stress half-update with the next step's P2G where no re-sort and no
    /// crack falls between (on by default; bitwise identical either way: `tests/fused_step.rs`).
    /// A switch for that test and for benchmarks.
    #[doc(hidden)]
    pub fn set_fused_step(&mut self, on: bool) {
        self.core.set_fused_step(on);
    }

    /// The arithmetic of the particle passes: [`Kernel::Portable`](crate::kernel::Kernel) (the
    /// same bits on every CPU) or [`Kernel::Fma`](crate::kernel::Kernel) (fused multiply-add,
    /// last-bit differences, `kernel.rs`); by default the portable one. Returns the
    /// kernel in use: the portable one where `kernel` is not available on this CPU.
    pub fn set_kernel(&mut self, kernel: crate::kernel::Kernel) -> crate::kernel::Kernel {
        self.core.set_kernel(kernel)
    }

    /// The arithmetic of the particle passes.
    pub fn kernel(&self) -> crate::kernel::Kernel {
        self.core.model.kernel
    }
}
