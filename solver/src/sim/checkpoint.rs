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
//! Format: postcard (serde; f64 as its exact bits) of a [`Header`] — magic, format version,
//! solver version, the scene's hash, the particle count and the SHA-256 of the state — then
//! the state. A checkpoint of another scene, another solver version or format, or whose
//! bytes do not match their digest is refused ([`CheckpointError`]), never used.
//!
//! Completeness is guarded by `tests/checkpoint.rs`: runs restored mid-way must match
//! uninterrupted runs bit for bit (particles, crack points, tips, energies) on a growing
//! crack with a process zone, a cohesive interface and a plain scene. State structs derive
//! serde, so a new field is in checkpoints unless it is marked `#[serde(skip)]`; a new
//! field of [`Simulation`] itself must be added to `State` below.

use fracture_api::ValidScene;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use super::{Simulation, SolverConfig, WorkCounters};
use crate::crack::Cracks;
use crate::particles::Particles;

/// First bytes of every solver checkpoint.
pub const CHECKPOINT_MAGIC: [u8; 8] = *b"MPMFSIM\0";

/// Version of the checkpoint layout; bumped whenever the persisted state changes shape.
pub const CHECKPOINT_FORMAT: u32 = 3;

/// Why a checkpoint was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CheckpointError {
    /// Not a checkpoint, truncated, or its bytes do not match their digest.
    #[error("not a usable checkpoint: {0}")]
    Corrupt(String),
    /// Written by another solver version or checkpoint format.
    #[error(
        "checkpoint of solver {found_version} (format {found_format}); this is solver {version} \
         (format {format})"
    )]
    Version {
        /// The solver version that wrote it.
        found_version: String,
        /// Its format.
        found_format: u32,
        /// This solver's version.
        version: String,
        /// This solver's format.
        format: u32,
    },
    /// Written for another scene.
    #[error("checkpoint of another scene (scene hash {found}, this scene's is {expected})")]
    Scene {
        /// The hash the checkpoint names.
        found: String,
        /// This scene's hash.
        expected: String,
    },
    /// The state does not fit the scene (particle count, grid, cracks).
    #[error("checkpoint state does not fit the scene: {0}")]
    Mismatch(String),
    /// The scene could not be built.
    #[error("cannot build the scene: {0}")]
    Build(String),
}

/// What precedes the state.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Header {
    magic: [u8; 8],
    format: u32,
    solver_version: String,
    scene_hash: String,
    particles: u64,
    steps: u64,
    digest: [u8; 32],
}

/// The persistent state (see the module docs).
#[derive(Serialize, Deserialize)]
struct State {
    parts: Particles,
    cracks: Option<Box<Cracks>>,
    needs_sort: bool,
    strip_bounds: Vec<usize>,
    time: f64,
    steps: u64,
    kinetic: f64,
    strain: f64,
    external_work: f64,
    dissipated: f64,
    initial_total: f64,
    work_abs: f64,
    counters: WorkCounters,
}

/// Borrowed form of [`State`] for writing (same field order and types).
#[derive(Serialize)]
struct StateRef<'a> {
    parts: &'a Particles,
    cracks: &'a Option<Box<Cracks>>,
    needs_sort: bool,
    strip_bounds: &'a [usize],
    time: f64,
    steps: u64,
    kinetic: f64,
    strain: f64,
    external_work: f64,
    dissipated: f64,
    initial_total: f64,
    work_abs: f64,
    counters: WorkCounters,
}

/// The step count a checkpoint was taken at, read from its header (checked like
/// [`Simulation::restore`] checks it, but without the state).
pub fn checkpoint_steps(bytes: &[u8]) -> Result<u64, CheckpointError> {
    let (h, _) = postcard::take_from_bytes::<Header>(bytes)
        .map_err(|e| CheckpointError::Corrupt(e.to_string()))?;
    if h.magic != CHECKPOINT_MAGIC {
        return Err(CheckpointError::Corrupt("no checkpoint magic".into()));
    }
    Ok(h.steps)
}

impl Simulation {
    /// The state that persists across steps, as bytes (module docs: what is in it and the
    /// format). Taking one does not change the simulation.
    pub fn checkpoint(&self) -> Vec<u8> {
        let state = StateRef {
            parts: &self.parts,
            cracks: &self.cracks,
            needs_sort: self.needs_sort,
            strip_bounds: &self.strip_bounds,
            time: self.time,
            steps: self.steps,
            kinetic: self.ledger.kinetic,
            strain: self.ledger.strain,
            external_work: self.ledger.external_work,
            dissipated: self.ledger.dissipated,
            initial_total: self.ledger.initial_total,
            work_abs: self.ledger.work_abs,
            counters: self.counters,
        };
        // Serializing plain data into a Vec cannot fail (no maps with non-string keys, no
        // IO); an empty state would be refused on restore rather than used.
        let body = postcard::to_allocvec(&state).unwrap_or_default();
        let header = Header {
            magic: CHECKPOINT_MAGIC,
            format: CHECKPOINT_FORMAT,
            solver_version: fracture_api::SOLVER_VERSION.to_string(),
            scene_hash: self.scene.hash(),
            particles: self.parts.len() as u64,
            steps: self.steps,
            digest: Sha256::digest(&body).into(),
        };
        let mut out = postcard::to_allocvec(&header).unwrap_or_default();
        out.extend_from_slice(&body);
        out
    }

    /// A simulation of `scene` in the state of a checkpoint taken by
    /// [`Simulation::checkpoint`] (of this scene, by this solver version); it steps on
    /// bitwise identically to the one that took it, with any thread count.
    pub fn restore(
        valid: &ValidScene,
        config: SolverConfig,
        bytes: &[u8],
    ) -> Result<Simulation, CheckpointError> {
        let (h, body) = postcard::take_from_bytes::<Header>(bytes)
            .map_err(|e| CheckpointError::Corrupt(format!("header: {e}")))?;
        if h.magic != CHECKPOINT_MAGIC {
            return Err(CheckpointError::Corrupt("no checkpoint magic".into()));
        }
        if h.format != CHECKPOINT_FORMAT || h.solver_version != fracture_api::SOLVER_VERSION {
            return Err(CheckpointError::Version {
                found_version: h.solver_version,
                found_format: h.format,
                version: fracture_api::SOLVER_VERSION.to_string(),
                format: CHECKPOINT_FORMAT,
            });
        }
        let expected = valid.scene().hash();
        if h.scene_hash != expected {
            return Err(CheckpointError::Scene {
                found: h.scene_hash,
                expected,
            });
        }
        let digest: [u8; 32] = Sha256::digest(body).into();
        if digest != h.digest {
            return Err(CheckpointError::Corrupt(
                "the state does not match its digest".into(),
            ));
        }
        let st: State = postcard::from_bytes(body)
            .map_err(|e| CheckpointError::Corrupt(format!("state: {e}")))?;
        let mut sim =
            Simulation::new(valid, config).map_err(|e| CheckpointError::Build(e.to_string()))?;

        let n = sim.parts.len();
        let p = &st.parts;
        let cracked = sim.cracks.is_some();
        let opt_len = |len: usize| len == if cracked { n } else { 0 };
        if h.particles != n as u64
            || p.len() != n
            || p.mech.len() != n
            || p.stress.len() != n
            || p.cold.len() != n
            || !opt_len(p.grad_u.len())
            || !opt_len(p.fmask.len())
        {
            return Err(CheckpointError::Mismatch(format!(
                "particle arrays of {} particles, the scene has {n}",
                p.len()
            )));
        }
        if st.strip_bounds.len() != sim.strip_bounds.len()
            || st.strip_bounds.windows(2).any(|w| w[0] > w[1])
            || st.strip_bounds.last().is_some_and(|&b| b > n)
        {
            return Err(CheckpointError::Mismatch(
                "strip bounds of another grid".into(),
            ));
        }
        if st.steps != h.steps {
            return Err(CheckpointError::Corrupt("step counts disagree".into()));
        }
        match (st.cracks, sim.cracks.as_deref()) {
            (Some(mut c), Some(fresh)) => {
                c.adopt_scene(fresh).map_err(CheckpointError::Mismatch)?;
                sim.cracks = Some(c);
            }
            (None, None) => {}
            _ => {
                return Err(CheckpointError::Mismatch(
                    "cracks in one of the checkpoint and the scene only".into(),
                ));
            }
        }
        // Particles, with the step's scratch sized as `new` sizes it.
        let mut parts = st.parts;
        parts.wts = std::mem::take(&mut sim.parts.wts);
        sim.parts = parts;
        sim.needs_sort = st.needs_sort;
        sim.strip_bounds = st.strip_bounds;
        sim.time = st.time;
        sim.steps = st.steps;
        sim.ledger.kinetic = st.kinetic;
        sim.ledger.strain = st.strain;
        sim.ledger.external_work = st.external_work;
        sim.ledger.dissipated = st.dissipated;
        sim.ledger.initial_total = st.initial_total;
        sim.ledger.work_abs = st.work_abs;
        sim.counters = st.counters;
        Ok(sim)
    }
}
