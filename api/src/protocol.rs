//! The worker protocol (`/api/v1/worker/…`): what a worker sends and what it gets back.
//!
//! Every request about a job carries the job's fencing token (`fence`, raised on every
//! claim): a worker whose lease was lost gets 409 and must drop the job. History rows travel
//! as the real rows: NaN as `null` ([`crate::nan`]).

use serde::{Deserialize, Serialize};

use crate::results::{CrackTipRow, EnergyRow, Progress, Summary};

/// `POST /api/v1/worker/claim`.
#[derive(Debug, Clone, Serialize, Deserialize, utoipa::ToSchema)]
pub struct ClaimRequest {
    /// Who asks (for the job record and the logs).
    pub worker_id: String,
    /// Longest time to wait for a job (s), capped by the server.
    #[serde(default)]
    pub wait_seconds: f64,
}

/// A claimed job (200 from claim; 204 means no job within the wait).
#[derive(Debug, Clone, Serialize, Deserialize, utoipa::ToSchema)]
pub struct Claim {
    /// Job id.
    pub job_id: String,
    /// Fencing token of this claim.
    pub fence: i64,
    /// Attempt number (1 for the first claim).
    pub attempt: u32,
    /// The scene, as JSON.
    #[schema(value_type = Object)]
    pub scene: serde_json::Value,
    /// How long the lease lasts without a heartbeat (s).
    pub lease_seconds: f64,
}

/// `POST /api/v1/worker/jobs/{id}/heartbeat`.
#[derive(Debug, Clone, Serialize, Deserialize, utoipa::ToSchema)]
pub struct Heartbeat {
    /// Fencing token.
    pub fence: i64,
    /// Latest progress, if any.
    #[serde(default)]
    pub progress: Option<Progress>,
}

/// Reply to a heartbeat.
#[derive(Debug, Clone, Serialize, Deserialize, utoipa::ToSchema)]
pub struct HeartbeatReply {
    /// The job was cancelled: stop it and finish with a cancelled summary.
    pub cancel: bool,
    /// The lease now lasts this long (s).
    pub lease_seconds: f64,
}

/// `POST /api/v1/worker/jobs/{id}/energy`.
#[derive(Debug, Clone, Serialize, Deserialize, utoipa::ToSchema)]
pub struct EnergyBatch {
    /// Fencing token.
    pub fence: i64,
    /// Rows in time order.
    pub rows: Vec<EnergyRow>,
}

/// `POST /api/v1/worker/jobs/{id}/crack-tips`.
#[derive(Debug, Clone, Serialize, Deserialize, utoipa::ToSchema)]
pub struct CrackTipBatch {
    /// Fencing token.
    pub fence: i64,
    /// Rows in time order.
    pub rows: Vec<CrackTipRow>,
}

/// `POST /api/v1/worker/jobs/{id}/finish`.
#[derive(Debug, Clone, Serialize, Deserialize, utoipa::ToSchema)]
pub struct FinishRequest {
    /// Fencing token.
    pub fence: i64,
    /// The run summary.
    pub summary: Summary,
}
