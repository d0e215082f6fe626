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

/// `POST /api/v1/worker/jobs/{id}/died`: sent by the supervisor of a remote worker
/// (`fracture worker`) when its worker process died while it held the job, so the server
/// releases the job at once (not after its lease) with the cause in its message.
#[derive(Debug, Clone, Serialize, Deserialize, utoipa::ToSchema)]
pub struct WorkerDied {
    /// Fencing token of the claim the dead process held.
    pub fence: i64,
    /// How the process ended and its last output ([`exit_cause`]).
    pub cause: String,
}

/// `POST /api/v1/worker/jobs/{id}/release`: a worker hands its job back (a batch worker
/// told to stop before its time limit, e.g. Slurm's `--signal`): the job returns to the
/// queue without counting the attempt, for another worker to run (from its checkpoint,
/// where one was stored).
#[derive(Debug, Clone, Serialize, Deserialize, utoipa::ToSchema)]
pub struct WorkerRelease {
    /// Fencing token of the claim handed back.
    pub fence: i64,
    /// Why, for the job's message (e.g. `SIGUSR1 from the scheduler`).
    #[serde(default)]
    pub reason: String,
    /// Who hands it back: the worker id and, where known, host and scheduler job.
    #[serde(default)]
    pub worker: String,
}

/// Lines of a worker's stderr kept for the message of the job it held when it died.
pub const STDERR_TAIL: usize = 8;

/// Why a worker process ended, for people: the signal or exit status, what it usually
/// means, and the last lines of its stderr (`tail`).
pub fn exit_cause(status: &std::process::ExitStatus, tail: &[String]) -> String {
    #[cfg(unix)]
    let how = {
        use std::os::unix::process::ExitStatusExt;
        match (status.signal(), status.code()) {
            (Some(9), _) => "killed by signal 9 (SIGKILL: e.g. the out-of-memory killer)".into(),
            (Some(6), _) => "aborted (signal 6, SIGABRT: e.g. a failed memory allocation)".into(),
            (Some(7), _) => {
                "killed by signal 7 (SIGBUS: e.g. a full or vanished file system)".into()
            }
            (Some(11), _) => "killed by signal 11 (SIGSEGV)".into(),
            (Some(15), _) => "stopped by signal 15 (SIGTERM)".into(),
            (Some(sig), _) => format!("killed by signal {sig}"),
            (None, Some(code)) => format!("exited with status {code}"),
            (None, None) => "ended".into(),
        }
    };
    #[cfg(not(unix))]
    let how = format!("exited ({status})");
    // The log lines worth showing: without the colour codes of the log prefix, short.
    let lines: Vec<String> = tail
        .iter()
        .map(|l| {
            let l: String = l.chars().filter(|c| *c != '\u{1b}').collect();
            let l = l.trim();
            if l.chars().count() > 300 {
                format!("{}…", l.chars().take(300).collect::<String>())
            } else {
                l.to_string()
            }
        })
        .filter(|l| !l.is_empty())
        .collect();
    if lines.is_empty() {
        how
    } else {
        format!("{how}; its last output: {}", lines.join(" | "))
    }
}

/// Whether a worker's exit cause shows that it ran out of memory (a failed allocation
/// under its cap): the job would fail the same way again, so it is failed at once.
pub fn ran_out_of_memory(cause: &str) -> bool {
    [
        "memory allocation of",
        "out of memory",
        "Cannot allocate memory",
    ]
    .iter()
    .any(|m| cause.contains(m))
}
