//! The worker's checkpoint of a job: the solver's checkpoint
//! ([`fracture_solver::Simulation::checkpoint`]) with the run loop's own cursors (next history
//! and snapshot sample, snapshots taken, the step last sampled, the counters of the
//! summary), checked by this build's commit and the scene's hash, postcard-encoded and
//! zstd-compressed. See `docs/service.md`, "Checkpoints".

use std::time::Duration;

use serde::{Deserialize, Serialize};

/// First bytes of a worker checkpoint (after decompression).
const MAGIC: [u8; 8] = *b"MPMFRUN\0";
/// Version of the envelope layout.
const FORMAT: u32 = 1;

/// When a running job writes checkpoints.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CheckpointPolicy {
    /// Every this many steps (at the first history sample after they have passed).
    pub steps: Option<u64>,
    /// Every this much wall time (at the first history sample after it has passed).
    pub every: Option<Duration>,
}

impl CheckpointPolicy {
    /// No checkpoints (local runs).
    pub fn none() -> Self {
        CheckpointPolicy::default()
    }
    /// Whether any checkpoint is written.
    pub fn enabled(&self) -> bool {
        self.steps.is_some() || self.every.is_some()
    }
    /// Whether one is due `steps` steps and `elapsed` wall time after the last.
    pub(crate) fn due(&self, steps: u64, elapsed: Duration) -> bool {
        self.steps.is_some_and(|n| steps >= n.max(1)) || self.every.is_some_and(|d| elapsed >= d)
    }
}

/// The run loop's position, restored with the solver state.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LoopCursor {
    /// Index of the next history sample.
    pub history_next: u64,
    /// Index of the next snapshot sample time.
    pub snapshot_next: u64,
    /// Snapshots taken so far (the next snapshot's index).
    pub snapshots: u32,
    /// Step count at the last history sample.
    pub sampled_at: Option<u64>,
    /// Σ active nodes over the steps so far (the summary's mean).
    pub active_sum: f64,
    /// Steps so far, for the mean.
    pub active_steps: u64,
    /// Wall time of the attempts before (s).
    pub wall_seconds: f64,
}

/// Where a checkpoint was taken: what the server keeps of the run's history with it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CheckpointAt {
    /// Steps taken.
    pub step: u64,
    /// Simulated time (s): history rows at later times are not covered by it.
    pub time: f64,
    /// Snapshots taken (indices below this are covered).
    pub snapshots: u32,
}

#[derive(Serialize, Deserialize)]
struct Envelope {
    magic: [u8; 8],
    format: u32,
    commit: Option<String>,
    scene_hash: String,
    step: u64,
    time: f64,
    cursor: LoopCursor,
    solver: Vec<u8>,
}

/// Encode a checkpoint.
pub(crate) fn encode(
    scene_hash: &str,
    step: u64,
    time: f64,
    cursor: LoopCursor,
    solver: Vec<u8>,
) -> Result<Vec<u8>, String> {
    let env = Envelope {
        magic: MAGIC,
        format: FORMAT,
        commit: crate::provenance::SOLVER_COMMIT.map(String::from),
        scene_hash: scene_hash.to_string(),
        step,
        time,
        cursor,
        solver,
    };
    let raw = postcard::to_allocvec(&env).map_err(|e| e.to_string())?;
    zstd::bulk::compress(&raw, 3).map_err(|e| e.to_string())
}

/// A decoded checkpoint: the loop's cursor, its position and the solver's bytes.
#[derive(Debug)]
pub(crate) struct Decoded {
    pub(crate) cursor: LoopCursor,
    pub(crate) at: CheckpointAt,
    pub(crate) solver: Vec<u8>,
}

/// Largest decompressed checkpoint accepted (a bound against a corrupt size field).
const MAX_RAW: usize = 1 << 34;

/// Decode a checkpoint of `scene_hash` written by this build; the reason otherwise.
pub(crate) fn decode(bytes: &[u8], scene_hash: &str) -> Result<Decoded, String> {
    let size = zstd::zstd_safe::get_frame_content_size(bytes)
        .ok()
        .flatten()
        .ok_or("not a compressed checkpoint")?;
    if size as usize > MAX_RAW {
        return Err(format!("implausible size {size}"));
    }
    let raw = zstd::bulk::decompress(bytes, size as usize).map_err(|e| e.to_string())?;
    let env: Envelope = postcard::from_bytes(&raw).map_err(|e| format!("unreadable: {e}"))?;
    if env.magic != MAGIC || env.format != FORMAT {
        return Err(format!("not a checkpoint of format {FORMAT}"));
    }
    let here = crate::provenance::SOLVER_COMMIT;
    if env.commit.as_deref() != here {
        return Err(format!(
            "written by build {}, this is build {}",
            env.commit.as_deref().unwrap_or("(unknown)"),
            here.unwrap_or("(unknown)")
        ));
    }
    if env.scene_hash != scene_hash {
        return Err(format!(
            "of scene {}, this job's scene is {scene_hash}",
            env.scene_hash
        ));
    }
    Ok(Decoded {
        cursor: env.cursor,
        at: CheckpointAt {
            step: env.step,
            time: env.time,
            snapshots: env.cursor.snapshots,
        },
        solver: env.solver,
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    fn cursor() -> LoopCursor {
        LoopCursor {
            history_next: 3,
            snapshot_next: 1,
            snapshots: 1,
            sampled_at: Some(7),
            active_sum: 0.1 + 0.2,
            active_steps: 7,
            wall_seconds: 1.5,
        }
    }

    #[test]
    fn round_trip_and_refusals() {
        let b = encode("abc", 7, 1e-6 / 3.0, cursor(), vec![1, 2, 3]).unwrap();
        let d = decode(&b, "abc").unwrap();
        assert_eq!(d.cursor, cursor());
        assert_eq!(d.at.time.to_bits(), (1e-6f64 / 3.0).to_bits());
        assert_eq!(d.solver, vec![1, 2, 3]);
        assert!(decode(&b, "other").unwrap_err().contains("scene"));
        assert!(decode(&b[..b.len() / 2], "abc").is_err());
        assert!(decode(b"garbage", "abc").is_err());
    }

    #[test]
    fn policy() {
        let p = CheckpointPolicy {
            steps: Some(10),
            every: None,
        };
        assert!(!p.due(9, Duration::from_secs(1000)) && p.due(10, Duration::ZERO));
        assert!(!CheckpointPolicy::none().enabled());
    }
}
