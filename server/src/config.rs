//! Run-time configuration of the service: queue timing and the limits that keep one request
//! from exhausting the machine.

use std::time::Duration;

use fracture_api::jobs::ErrorDetail;
use fracture_api::{RunSize, Scene};

use crate::error::ApiError;

/// Limits on what one request may ask for.
#[derive(Debug, Clone)]
pub struct Limits {
    /// Most particles a scene may have.
    pub max_particles: u64,
    /// Most time steps a scene may take.
    pub max_steps: u64,
    /// Most snapshot volume: number of snapshots × grid nodes.
    pub max_snapshot_volume: u64,
    /// Largest request body of the public API (bytes).
    pub max_body_bytes: usize,
    /// Largest request body of the worker API (bytes; snapshots are large).
    pub max_worker_body_bytes: usize,
    /// Most jobs (parameter combinations) one sweep may create.
    pub max_sweep_jobs: u64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_particles: 4_000_000,
            max_steps: 5_000_000,
            max_snapshot_volume: 400_000_000,
            max_body_bytes: 4 << 20,
            max_worker_body_bytes: 512 << 20,
            max_sweep_jobs: 100,
        }
    }
}

impl Limits {
    /// Check a valid scene's size against the limits: 422 naming each exceeded limit.
    pub fn check(&self, scene: &Scene, size: &RunSize) -> Result<(), ApiError> {
        let mut details = Vec::new();
        if size.particles > self.max_particles {
            details.push(ErrorDetail {
                path: "bodies".into(),
                message: format!(
                    "the scene has {} particles, more than this server's limit max_particles = {}",
                    size.particles, self.max_particles
                ),
            });
        }
        if size.steps > self.max_steps {
            details.push(ErrorDetail {
                path: "time.end".into(),
                message: format!(
                    "the run takes {} time steps, more than this server's limit max_steps = {}",
                    size.steps, self.max_steps
                ),
            });
        }
        let snapshots = snapshot_count(scene);
        let volume = snapshots.saturating_mul(size.grid_nodes);
        if volume > self.max_snapshot_volume {
            details.push(ErrorDetail {
                path: "output.snapshot_interval".into(),
                message: format!(
                    "{snapshots} snapshots × {} grid nodes = {volume}, more than this server's \
                     limit max_snapshot_volume = {}",
                    size.grid_nodes, self.max_snapshot_volume
                ),
            });
        }
        if details.is_empty() {
            Ok(())
        } else {
            let names: Vec<&str> = details
                .iter()
                .map(|d| match d.path.as_str() {
                    "bodies" => "max_particles",
                    "time.end" => "max_steps",
                    _ => "max_snapshot_volume",
                })
                .collect();
            Err(ApiError::LimitExceeded {
                message: format!(
                    "the scene exceeds this server's limits: {}",
                    names.join(", ")
                ),
                details,
            })
        }
    }
}

/// How many snapshots a run of this scene writes.
pub fn snapshot_count(scene: &Scene) -> u64 {
    let dt = scene.output.snapshot_interval;
    if dt > 0.0 && dt.is_finite() && scene.time.end.is_finite() {
        let n = (scene.time.end / dt).floor();
        if (0.0..1e15).contains(&n) {
            n as u64 + 1
        } else {
            u64::MAX
        }
    } else {
        0
    }
}

/// Configuration of the service (what `fracture serve` turns its flags into).
#[derive(Debug, Clone)]
pub struct Config {
    /// Token required for submit, cancel and delete; `None`: open.
    pub api_token: Option<String>,
    /// Token workers present on `/api/v1/worker/…`.
    pub worker_token: String,
    /// How long a claim or heartbeat holds a job.
    pub lease: Duration,
    /// Claims after which an expiring lease fails the job instead of re-queueing it.
    pub max_attempts: u32,
    /// Longest a claim request waits for a job.
    pub claim_wait: Duration,
    /// Request limits.
    pub limits: Limits,
    /// Local worker processes the server supervises (for `/health`).
    pub local_workers: usize,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            api_token: None,
            worker_token: String::new(),
            lease: Duration::from_secs(30),
            max_attempts: 3,
            claim_wait: Duration::from_secs(20),
            limits: Limits::default(),
            local_workers: 0,
        }
    }
}
