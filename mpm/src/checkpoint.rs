//! Checkpoints: the [`State`] as bytes and back, for both dimensions and any layer. A
//! checkpoint is the state — particles, the layer's state (the cracks), sort order and strip
//! bounds, time, steps, energy ledger, counters — and nothing else: the model is rebuilt from
//! the scene, scratch by the next step. A P2G done ahead by a fused step is simply done again
//! by the restored simulation's first step (bitwise the same: `tests/fused.rs`).
//!
//! Format: postcard (f64 as its exact bits) of a header — the dimension's magic, the format,
//! the solver version, the scene's hash, the particle count, the step count and the SHA-256
//! of the state — then the state in its field order. A 2D checkpoint is byte for byte what the
//! 2D solver wrote before its step moved onto this core (format 3). A checkpoint of another
//! scene, version, format or dimension, or whose bytes do not match their digest, is refused,
//! never used.

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::dim::Dim;
use crate::layer::Layer;
use crate::state::State;
use crate::step::Simulation;

/// First bytes of a 2D checkpoint.
pub const MAGIC_2D: [u8; 8] = *b"MPMFSIM\0";
/// First bytes of a 3D checkpoint.
pub const MAGIC_3D: [u8; 8] = *b"MPMFS3D\0";
/// First bytes of the 3D checkpoints of format 2 (refused with their format named).
const MAGIC_3D_FORMAT_2: [u8; 8] = *b"MPMCORE\0";
/// Version of the checkpoint layout; bumped whenever the persisted state changes shape.
pub const FORMAT: u32 = 3;

/// The magic of a dimension's checkpoints.
pub fn magic(dims: usize) -> [u8; 8] {
    if dims == 3 { MAGIC_3D } else { MAGIC_2D }
}

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
    /// The state does not fit the scene (dimension, particle count, grid, cracks).
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

/// The first fields of every header this solver ever wrote.
#[derive(Deserialize)]
struct Prefix {
    magic: [u8; 8],
    format: u32,
    solver_version: String,
}

/// The header of `bytes`, checked for the magic of dimension `dims`, this format and this
/// solver version; and the state's bytes after it.
fn header(bytes: &[u8], dims: usize) -> Result<(Header, &[u8]), CheckpointError> {
    let (p, _) = postcard::take_from_bytes::<Prefix>(bytes)
        .map_err(|e| CheckpointError::Corrupt(format!("header: {e}")))?;
    let found_dims = match p.magic {
        MAGIC_2D => 2,
        MAGIC_3D | MAGIC_3D_FORMAT_2 => 3,
        _ => return Err(CheckpointError::Corrupt("no checkpoint magic".into())),
    };
    let version = fracture_api::SOLVER_VERSION;
    if p.format != FORMAT || p.magic == MAGIC_3D_FORMAT_2 || p.solver_version != version {
        return Err(CheckpointError::Version {
            found_version: p.solver_version,
            found_format: p.format,
            version: version.to_string(),
            format: FORMAT,
        });
    }
    if dims != found_dims {
        return Err(CheckpointError::Mismatch(format!(
            "a {found_dims}D checkpoint; this scene is {dims}D"
        )));
    }
    postcard::take_from_bytes::<Header>(bytes)
        .map_err(|e| CheckpointError::Corrupt(format!("header: {e}")))
}

/// The step count a checkpoint of this format was taken at, read from its header (its
/// magic checked; the version, scene and state are checked by [`Simulation::restore`]).
pub fn checkpoint_steps(bytes: &[u8]) -> Result<u64, CheckpointError> {
    let (h, _) = postcard::take_from_bytes::<Header>(bytes)
        .map_err(|e| CheckpointError::Corrupt(e.to_string()))?;
    if h.magic != MAGIC_2D && h.magic != MAGIC_3D {
        return Err(CheckpointError::Corrupt("no checkpoint magic".into()));
    }
    Ok(h.steps)
}

impl<D: Dim, L: Layer<D>> Simulation<D, L> {
    /// The state as bytes (module docs: what is in it and the format). Taking one does not
    /// change the simulation.
    pub fn checkpoint(&self) -> Vec<u8> {
        // Serializing plain data into a Vec cannot fail (no maps with non-string keys, no
        // IO); an empty body would be refused on restore rather than used.
        let body = postcard::to_allocvec(&self.state).unwrap_or_default();
        let header = Header {
            magic: magic(D::N),
            format: FORMAT,
            solver_version: fracture_api::SOLVER_VERSION.to_string(),
            scene_hash: self.model.scene_hash.clone(),
            particles: self.state.parts.len() as u64,
            steps: self.state.steps,
            digest: Sha256::digest(&body).into(),
        };
        let mut out = postcard::to_allocvec(&header).unwrap_or_default();
        out.extend_from_slice(&body);
        out
    }

    /// Put the state of a checkpoint taken by [`Simulation::checkpoint`] of the same scene
    /// into this freshly built simulation; it then steps on bitwise identically, with any
    /// thread count.
    pub fn restore(&mut self, bytes: &[u8]) -> Result<(), CheckpointError> {
        let (h, body) = header(bytes, D::N)?;
        if h.scene_hash != self.model.scene_hash {
            return Err(CheckpointError::Scene {
                found: h.scene_hash,
                expected: self.model.scene_hash.clone(),
            });
        }
        let digest: [u8; 32] = Sha256::digest(body).into();
        if digest != h.digest {
            return Err(CheckpointError::Corrupt(
                "the state does not match its digest".into(),
            ));
        }
        let st: State<D, L> = postcard::from_bytes(body)
            .map_err(|e| CheckpointError::Corrupt(format!("state: {e}")))?;
        let fresh = &self.state.parts;
        let n = fresh.len();
        let p = &st.parts;
        if h.particles != n as u64
            || p.len() != n
            || p.mech.len() != n
            || p.stress.len() != n
            || p.cold.len() != n
            || p.wden.len() != n
            || p.grad_u.len() != fresh.grad_u.len()
            || p.fmask.len() != fresh.fmask.len()
        {
            return Err(CheckpointError::Mismatch(format!(
                "particle arrays of {} particles, the scene has {n}",
                p.len()
            )));
        }
        if st.strip_bounds.len() != self.state.strip_bounds.len()
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
        let State {
            mut parts,
            layer,
            needs_sort,
            strip_bounds,
            time,
            steps,
            ledger,
            counters,
        } = st;
        self.state
            .layer
            .adopt(layer)
            .map_err(CheckpointError::Mismatch)?;
        // The particles, with the step's scratch sized as a fresh build sizes it.
        parts.wts = std::mem::take(&mut self.state.parts.wts);
        let s = &mut self.state;
        s.parts = parts;
        s.needs_sort = needs_sort;
        s.strip_bounds = strip_bounds;
        s.time = time;
        s.steps = steps;
        s.ledger = ledger;
        s.counters = counters;
        // The next step does its own P2G (a fresh simulation has none done ahead anyway).
        self.scratch.prefetched = None;
        Ok(())
    }
}
