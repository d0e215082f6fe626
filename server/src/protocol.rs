//! The worker protocol (`/api/v1/worker/…`): what a worker sends and what it gets back.
//!
//! Every request about a job carries the job's fencing token (`fence`, raised on every
//! claim): a worker whose lease was lost gets 409 and must drop the job.

use fracture_api::results::{CrackTipRow, EnergyRow, Progress, Summary};
use serde::{Deserialize, Deserializer, Serialize};

/// `POST /api/v1/worker/claim`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ClaimRequest {
    /// Who asks (for the job record and the logs).
    pub worker_id: String,
    /// Longest time to wait for a job (s), capped by the server.
    #[serde(default)]
    pub wait_seconds: f64,
}

/// A claimed job (200 from claim; 204 means no job within the wait).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Claim {
    /// Job id.
    pub job_id: String,
    /// Fencing token of this claim.
    pub fence: i64,
    /// Attempt number (1 for the first claim).
    pub attempt: u32,
    /// The scene, as JSON.
    pub scene: serde_json::Value,
    /// How long the lease lasts without a heartbeat (s).
    pub lease_seconds: f64,
}

/// `POST /api/v1/worker/jobs/{id}/heartbeat`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Heartbeat {
    /// Fencing token.
    pub fence: i64,
    /// Latest progress, if any.
    #[serde(default)]
    pub progress: Option<Progress>,
}

/// Reply to a heartbeat.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct HeartbeatReply {
    /// The job was cancelled: stop it and finish with a cancelled summary.
    pub cancel: bool,
    /// The lease now lasts this long (s).
    pub lease_seconds: f64,
}

/// `POST /api/v1/worker/jobs/{id}/energy`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct EnergyBatch {
    /// Fencing token.
    pub fence: i64,
    /// Rows in time order.
    pub rows: Vec<WireEnergy>,
}

/// `POST /api/v1/worker/jobs/{id}/crack-tips`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CrackTipBatch {
    /// Fencing token.
    pub fence: i64,
    /// Rows in time order.
    pub rows: Vec<WireCrackTip>,
}

/// `POST /api/v1/worker/jobs/{id}/finish`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FinishRequest {
    /// Fencing token.
    pub fence: i64,
    /// The run summary.
    pub summary: Summary,
}

fn nan_if_null<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// An energy row on the wire: JSON writes NaN as `null`, which reads back as NaN here.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[allow(missing_docs)]
pub struct WireEnergy {
    #[serde(deserialize_with = "nan_if_null")]
    pub time: f64,
    #[serde(deserialize_with = "nan_if_null")]
    pub kinetic: f64,
    #[serde(deserialize_with = "nan_if_null")]
    pub strain: f64,
    #[serde(deserialize_with = "nan_if_null")]
    pub external_work: f64,
    #[serde(deserialize_with = "nan_if_null")]
    pub dissipated: f64,
    #[serde(deserialize_with = "nan_if_null")]
    pub total_error: f64,
}

impl From<&EnergyRow> for WireEnergy {
    fn from(r: &EnergyRow) -> Self {
        WireEnergy {
            time: r.time,
            kinetic: r.kinetic,
            strain: r.strain,
            external_work: r.external_work,
            dissipated: r.dissipated,
            total_error: r.total_error,
        }
    }
}

impl From<WireEnergy> for EnergyRow {
    fn from(r: WireEnergy) -> Self {
        EnergyRow {
            time: r.time,
            kinetic: r.kinetic,
            strain: r.strain,
            external_work: r.external_work,
            dissipated: r.dissipated,
            total_error: r.total_error,
        }
    }
}

/// A crack-tip row on the wire (NaN-tolerant like [`WireEnergy`]).
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[allow(missing_docs)]
pub struct WireCrackTip {
    #[serde(deserialize_with = "nan_if_null")]
    pub time: f64,
    pub crack: u32,
    pub tip: u32,
    #[serde(deserialize_with = "nan_if_null")]
    pub x: f64,
    #[serde(deserialize_with = "nan_if_null")]
    pub y: f64,
    #[serde(deserialize_with = "nan_if_null")]
    pub length: f64,
    #[serde(deserialize_with = "nan_if_null")]
    pub speed: f64,
    #[serde(deserialize_with = "nan_if_null")]
    pub j1: f64,
    #[serde(deserialize_with = "nan_if_null")]
    pub j2: f64,
    #[serde(deserialize_with = "nan_if_null")]
    pub k1: f64,
    #[serde(deserialize_with = "nan_if_null")]
    pub k2: f64,
    pub growing: bool,
}

impl From<&CrackTipRow> for WireCrackTip {
    fn from(r: &CrackTipRow) -> Self {
        WireCrackTip {
            time: r.time,
            crack: r.crack,
            tip: r.tip,
            x: r.x,
            y: r.y,
            length: r.length,
            speed: r.speed,
            j1: r.j1,
            j2: r.j2,
            k1: r.k1,
            k2: r.k2,
            growing: r.growing,
        }
    }
}

impl From<WireCrackTip> for CrackTipRow {
    fn from(r: WireCrackTip) -> Self {
        CrackTipRow {
            time: r.time,
            crack: r.crack,
            tip: r.tip,
            x: r.x,
            y: r.y,
            length: r.length,
            speed: r.speed,
            j1: r.j1,
            j2: r.j2,
            k1: r.k1,
            k2: r.k2,
            growing: r.growing,
        }
    }
}
