//! Checkpoints: the state of a [`Simulation`] that persists from one step to the next, as
//! bytes ([`Simulation::checkpoint`]), and a simulation rebuilt from them
//! ([`Simulation::restore`]) that steps on bitwise identically to the one that wrote them.
//!
//! What is in one: every particle array but the step's scratch (`Particles` with its
//! `#[serde(skip)]` fields left out: weights and end-of-step positions, recomputed by the
//! next P2G), the particle order and strip bounds of the last sort (a re-sort would change
//! the order of sums), the crack set (`Cracks`: crack points with their zone and cohesive
//! states, tip states with their growth histories, filters and cached J, interface fronts,
//! the per-node contact impulses that carry into the next step, the energy ledgers), and
//! the simulation's time, step count, energy ledger and work counters.
//!
//! What is not: what the scene gives (materials, boundary conditions, the crack laws; taken
//! from a fresh [`Simulation::new`]), scratch, and the grid of the last step. The grid is
//! rebuilt by every step; a P2G done ahead by a fused step (`transfer.rs`) is simply done
//! again by the restored simulation's first step (bitwise the same: `tests/fused_step.rs`).
//! Views that read the last step's grid (J of a tip whose value is not cached, snapshots)
//! are therefore only meaningful after the restored simulation's first step; the worker
//! checkpoints right after it sampled, so it never asks.
//!
//! Format: the core's (`fracture_mpm::checkpoint`): postcard (serde; f64 as its exact bits)
//! of a header — magic, format version, solver version, the scene's hash, the particle count,
//! the step count and the SHA-256 of the state — then the core's `State<Dim2, CrackLayer>`
//! (particles, cracks, sort state, time, steps, ledger, counters). A checkpoint of another
//! scene, another solver version or format, or whose bytes do not match their digest is
//! refused ([`CheckpointError`]), never used. The bytes are those the 2D solver wrote before
//! its step moved onto the core (`tests/state_hashes.rs` hashes them).
//!
//! Completeness is guarded by `tests/checkpoint.rs`: runs restored mid-way must match
//! uninterrupted runs bit for bit (particles, crack points, tips, energies) on a growing
//! crack with a process zone, a cohesive interface and a plain scene. State structs derive
//! serde, so a new field is in checkpoints unless it is marked `#[serde(skip)]`.

use fracture_api::ValidScene;

use super::{Simulation, SolverConfig};

pub use fracture_mpm::checkpoint::{CheckpointError, checkpoint_steps};

/// Version of the checkpoint layout; bumped whenever the persisted state changes shape.
pub const CHECKPOINT_FORMAT: u32 = fracture_mpm::checkpoint::FORMAT;

impl Simulation {
    /// The state that persists across steps, as bytes (module docs: what is in it and the
    /// format). Taking one does not change the simulation.
    pub fn checkpoint(&self) -> Vec<u8> {
        self.core.checkpoint()
    }

    /// A simulation of `scene` in the state of a checkpoint taken by
    /// [`Simulation::checkpoint`] (of this scene, by this solver version); it steps on
    /// bitwise identically to the one that took it, with any thread count.
    pub fn restore(
        valid: &ValidScene,
        config: SolverConfig,
        bytes: &[u8],
    ) -> Result<Simulation, CheckpointError> {
        let mut sim =
            Simulation::new(valid, config).map_err(|e| CheckpointError::Build(e.to_string()))?;
        sim.core.restore(bytes)?;
        Ok(sim)
    }
}
