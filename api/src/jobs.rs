//! Job states and the request/response types of the HTTP API (`api.md`).
//! The service extends this module; these types are the contract.

use std::collections::BTreeMap;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::results::{Progress, SnapshotSlice, Summary};
use crate::scene::Scene;
use crate::scene3::AnyScene;

/// State of a job.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, JsonSchema, utoipa::ToSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum JobStatus {
    /// Waiting for a worker.
    Queued,
    /// Claimed by a worker.
    Running,
    /// Finished normally.
    Completed,
    /// Finished with an error; see the message.
    Failed,
    /// Cancelled on request.
    Cancelled,
}

impl JobStatus {
    /// The name used in the API and the store.
    pub fn as_str(self) -> &'static str {
        match self {
            JobStatus::Queued => "queued",
            JobStatus::Running => "running",
            JobStatus::Completed => "completed",
            JobStatus::Failed => "failed",
            JobStatus::Cancelled => "cancelled",
        }
    }
    /// Parse a status name.
    pub fn parse(s: &str) -> Option<JobStatus> {
        [
            JobStatus::Queued,
            JobStatus::Running,
            JobStatus::Completed,
            JobStatus::Failed,
            JobStatus::Cancelled,
        ]
        .into_iter()
        .find(|j| j.as_str() == s)
    }
    /// Whether the job has ended.
    pub fn is_terminal(self) -> bool {
        matches!(
            self,
            JobStatus::Completed | JobStatus::Failed | JobStatus::Cancelled
        )
    }
}

/// The wrapped form of `POST /api/v1/jobs`. The scene type `S` is a 2D [`Scene`] by
/// default; the service reads the wrapper with the scene as a JSON value first and then the
/// scene by its `analysis` ([`crate::scene_any::any_scene_from_value`]), so a 3D scene gets
/// through with its field paths in errors.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct JobRequest<S = Scene> {
    /// The scene to run.
    pub scene: S,
    /// Higher runs first.
    #[serde(default)]
    pub priority: i64,
    /// Free labels, e.g. `{"sweep": "toughness"}`.
    #[serde(default)]
    pub labels: BTreeMap<String, String>,
    /// Whether a completed run of the same scene may answer (extension of `api.md`).
    #[serde(default)]
    pub cache: CacheMode,
    /// Claims before a lost worker fails the job (≥ 1; absent: the server's
    /// `--max-attempts`; extension of `api.md`).
    #[serde(default)]
    pub max_attempts: Option<u32>,
}

/// The `cache` field of a submission (extension of `api.md`): whether a completed job with
/// the same canonical scene hash and solver version answers instead of a new run.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema, utoipa::ToSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum CacheMode {
    /// Reuse a completed run of the same scene (the default).
    #[default]
    Reuse,
    /// Run the scene again even if a completed run exists.
    Force,
}

/// A job as the API returns it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema, utoipa::ToSchema)]
pub struct JobInfo {
    /// Job id.
    pub id: String,
    /// Current state.
    pub status: JobStatus,
    /// Scene name.
    pub name: String,
    /// Labels.
    pub labels: BTreeMap<String, String>,
    /// Priority.
    pub priority: i64,
    /// The scene (omitted in lists; its JSON Schema: `fracture schema`), 2D or 3D
    /// (`"analysis": "3d"`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<Object>)]
    pub scene: Option<AnyScene>,
    /// RFC 3339 UTC.
    pub created_at: String,
    /// RFC 3339 UTC.
    pub started_at: Option<String>,
    /// RFC 3339 UTC.
    pub finished_at: Option<String>,
    /// How many times a worker has claimed the job.
    pub attempts: u32,
    /// Progress of the run.
    pub progress: Option<Progress>,
    /// The run summary once finished.
    pub summary: Option<Summary>,
    /// Why the job failed or was cancelled.
    pub message: Option<String>,
    /// The sweep the job belongs to (extension of `api.md`; absent for a lone job).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sweep_id: Option<String>,
    /// The job this one reruns (`POST /api/v1/jobs/{id}/rerun`; extension of `api.md`,
    /// absent for other jobs).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rerun_of: Option<String>,
    /// The completed job whose results this one serves (a cache hit: same canonical scene
    /// hash and solver version; extension of `api.md`, absent for jobs that ran).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cached_from: Option<String>,
    /// The job's own retry budget, when it was given one (`max_attempts` of the request;
    /// absent: the server's `--max-attempts`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_attempts: Option<u32>,
}

/// One problem in an error body.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema, utoipa::ToSchema)]
pub struct ErrorDetail {
    /// JSON path of the offending field, e.g. `materials.plate.poissons_ratio`.
    pub path: String,
    /// What is wrong with it.
    pub message: String,
}

/// The body of every API error.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema, utoipa::ToSchema)]
pub struct ErrorBody {
    /// Kind of error, e.g. `invalid_scene`, `not_found`.
    pub error: String,
    /// Human-readable explanation.
    pub message: String,
    /// Per-field problems.
    #[serde(default)]
    pub details: Vec<ErrorDetail>,
}

/// `GET /api/v1/health`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema, utoipa::ToSchema)]
pub struct HealthInfo {
    /// `"ok"`.
    pub status: String,
    /// Local worker processes the server supervises.
    pub workers: u64,
    /// Jobs waiting for a worker.
    pub queued: u64,
    /// Jobs being run.
    pub running: u64,
}

/// `POST /api/v1/scenes/validate` for a valid scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema, utoipa::ToSchema)]
pub struct ValidateResponse {
    /// Always `true` (an invalid scene gets 422).
    pub valid: bool,
    /// Number of particles.
    pub particles: u64,
    /// Grid nodes of the box.
    pub grid_nodes: u64,
    /// Δt (s).
    pub time_step: f64,
    /// Time steps to reach the end time.
    pub steps: u64,
}

/// One entry of `GET /api/v1/jobs/{id}/snapshots`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema, utoipa::ToSchema)]
pub struct SnapshotInfo {
    /// Index of the snapshot in its run.
    pub index: u32,
    /// Simulated time (s).
    pub time: f64,
    /// Field kinds recorded (each renders as `{kind}.png` with its default component).
    pub fields: Vec<String>,
    /// Component names (each renders as `{component}.png`).
    pub components: Vec<String>,
    /// The plane of a 3D run this snapshot samples (extension of `api.md`; absent for 2D
    /// runs): `{normal, at, node_at, axes}`, the picture's x and y being `axes`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<Object>)]
    pub slice: Option<SnapshotSlice>,
}

/// One built-in example scene (`GET /api/v1/scenes`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema, utoipa::ToSchema)]
pub struct SceneEntry {
    /// File name without `.json`.
    pub name: String,
    /// The scene's description.
    pub description: String,
    /// The scene document.
    #[schema(value_type = Object)]
    pub scene: serde_json::Value,
    /// Particles of a run of the scene (validation's count; 0 when the scene does not
    /// validate). Extension of `api.md`.
    #[serde(default)]
    pub particles: u64,
    /// Time steps to the scene's end time (0 when it does not validate).
    #[serde(default)]
    pub steps: u64,
    /// The work of a run: particles × steps (`fracture_api::cost::particle_steps`).
    #[serde(default)]
    pub particle_steps: u64,
    /// Estimated wall time of the time loop (s): `particle_steps` over
    /// `estimate_particle_steps_per_second`; absent when the scene does not validate.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub estimated_wall_seconds: Option<f64>,
    /// The throughput the estimate assumes (particle-steps per second).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub estimate_particle_steps_per_second: Option<f64>,
    /// Where that throughput comes from: `measured` (the mean of this server's completed
    /// runs) or `nominal` (the documented single-thread figure of `docs/performance.md`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub estimate_basis: Option<String>,
}

/// The `status` event of a job's event stream (also sent first to a late subscriber).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema, utoipa::ToSchema)]
pub struct StatusEvent {
    /// Job id.
    pub id: String,
    /// Current state.
    pub status: JobStatus,
    /// Claims so far.
    pub attempts: u32,
    /// Why the job failed or was cancelled.
    pub message: Option<String>,
    /// The run summary once finished.
    pub summary: Option<Summary>,
}
