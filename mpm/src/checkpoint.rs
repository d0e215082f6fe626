//! Checkpoints of the core: the [`State`] as bytes and back. A checkpoint is
//! the state — particles, sort order and strip bounds, time, steps, energy ledger — and
//! nothing else: the model is rebuilt from the scene, scratch by the next step.
//!
//! Format: postcard (f64 as its exact bits) of a header (magic, format, solver version, the
//! dimension, the scene's hash, particle count, steps, the SHA-256 of the state), then the
//! state. A checkpoint of another scene, version, dimension or whose bytes do not match
//! their digest is refused, never used.

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::dim::Dim;
use crate::state::State;
use crate::step::Simulation;

/// First bytes of every core checkpoint.
pub const MAGIC: [u8; 8] = *b"MPMCORE\0";
/// Layout version of the state.
pub const FORMAT: u32 = 2;

/// Why a checkpoint was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CheckpointError {
    /// Not a checkpoint, truncated, or its bytes do not match their digest.
    #[error("not a usable checkpoint: {0}")]
    Corrupt(String),
    /// Written by another version, format or dimension.
    #[error("checkpoint of {0}; this is {1}")]
    Version(String, String),
    /// Written for another scene.
    #[error("checkpoint of another scene (scene hash {found}, this scene's is {expected})")]
    Scene {
        /// The hash the checkpoint names.
        found: String,
        /// This scene's hash.
        expected: String,
    },
    /// The state does not fit the scene.
    #[error("checkpoint state does not fit the scene: {0}")]
    Mismatch(String),
}

#[derive(Serialize, Deserialize)]
struct Header {
    magic: [u8; 8],
    format: u32,
    version: String,
    dims: u32,
    scene_hash: String,
    particles: u64,
    steps: u64,
    digest: [u8; 32],
}

fn identity(format: u32, version: &str, dims: u32) -> String {
    format!("solver {version}, format {format}, {dims}D")
}

impl<D: Dim> Simulation<D> {
    /// The state as bytes. Taking one does not change the simulation.
    pub fn checkpoint(&self) -> Vec<u8> {
        // Serializing plain data into a Vec cannot fail; an empty body would be refused on
        // restore rather than used.
        let body = postcard::to_allocvec(&self.state).unwrap_or_default();
        let header = Header {
            magic: MAGIC,
            format: FORMAT,
            version: fracture_api::SOLVER_VERSION.to_string(),
            dims: D::N as u32,
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
    /// into this freshly built simulation; it then steps on bitwise identically.
    pub fn restore(&mut self, bytes: &[u8]) -> Result<(), CheckpointError> {
        let (h, body) = postcard::take_from_bytes::<Header>(bytes)
            .map_err(|e| CheckpointError::Corrupt(format!("header: {e}")))?;
        if h.magic != MAGIC {
            return Err(CheckpointError::Corrupt("no checkpoint magic".into()));
        }
        let version = fracture_api::SOLVER_VERSION;
        if h.format != FORMAT || h.version != version || h.dims != D::N as u32 {
            return Err(CheckpointError::Version(
                identity(h.format, &h.version, h.dims),
                identity(FORMAT, version, D::N as u32),
            ));
        }
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
        let mut st: State<D> = postcard::from_bytes(body)
            .map_err(|e| CheckpointError::Corrupt(format!("state: {e}")))?;
        let n = self.state.parts.len();
        let p = &st.parts;
        if h.particles != n as u64
            || p.len() != n
            || p.mech.len() != n
            || p.stress.len() != n
            || p.cold.len() != n
            || p.wden.len() != n
        {
            return Err(CheckpointError::Mismatch(format!(
                "{} particles, the scene has {n}",
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
        st.parts.wts = std::mem::take(&mut self.state.parts.wts);
        self.state = st;
        // The next step does its own P2G (a fresh simulation has none done ahead anyway).
        self.scratch.prefetched = None;
        Ok(())
    }
}
