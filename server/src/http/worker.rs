//! The worker protocol (`/api/v1/worker/…`, worker token): claim (long poll), heartbeat,
//! history batches, snapshot upload, finish, the hand-back of a batch worker that must
//! stop, and the death report of a remote worker's supervisor. Every write names the claim's fence; a stale
//! one is 409 (`StoreError::Fenced`) and the worker drops the job.

use std::time::Duration;

use axum::Json;
use axum::extract::{Path, State};
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use fracture_api::jobs::{ErrorBody, JobInfo, JobStatus, SnapshotInfo};
use fracture_api::protocol::{
    Claim, ClaimRequest, CrackTipBatch, EnergyBatch, FinishRequest, Heartbeat, HeartbeatReply,
    WorkerDied, WorkerRelease,
};
use fracture_results::codec;
use serde::Deserialize;

use super::auth::WorkerToken;
use super::{blocking, job_or_404};
use crate::error::{ApiError, ApiJson, ApiQuery, RawBody};
use crate::events::JobEvent;
use crate::files::Record;
use crate::server::AppState;
use crate::store::StoreError;

/// Claim the best queued job, waiting up to `wait_seconds` (200 with the claim, 204 none).
#[utoipa::path(post, path = "/api/v1/worker/claim", tag = "worker",
    request_body(content = ClaimRequest, content_type = "application/json"),
    responses((status = 200, description = "The claim", body = Claim),
        (status = 204, description = "No job"),
        (status = 401, description = "Missing or wrong worker token", body = ErrorBody)),
    security(("bearer" = [])))]
pub(super) async fn worker_claim(
    State(st): State<AppState>,
    _: WorkerToken,
    ApiJson(req): ApiJson<ClaimRequest>,
) -> Result<Response, ApiError> {
    let wait = Duration::from_secs_f64(req.wait_seconds.clamp(0.0, 3600.0)).min(st.cfg.claim_wait);
    let deadline = tokio::time::Instant::now() + wait;
    let mut shutdown = st.shutdown.clone();
    loop {
        if st.shutting_down() {
            return Ok(StatusCode::NO_CONTENT.into_response());
        }
        let notified = st.queue_changed.notified();
        if let Some(c) = st.store.claim(&req.worker_id, st.cfg.lease).await? {
            let job = c.job;
            // The history of earlier attempts, kept up to the job's checkpoint (dropped
            // without one), and the MCAP file restarted with it (`checkpoint.rs`). A file
            // that cannot be created (a full disk) is given up, not the claim: the run's
            // rows go to the database all the same.
            let restart =
                super::checkpoint::start_claim(&st, &job.id, job.fence, &job.scene).await?;
            // A restarted job's subscribers learn where it resumes and why its progress fell
            // back: the `restart` event, then the status with the job's new message.
            if let Some(r) = &restart {
                st.hub.send(&job.id, JobEvent::Restart(r.clone()));
                st.hub.send(&job.id, JobEvent::Progress(r.progress));
            }
            // The row as the rewind left it (message and progress cleared or rewound).
            let job = st.store.get(&job.id).await?.unwrap_or(job);
            let text = job.scene.clone();
            // A scene this version cannot read still goes to the worker, which fails the
            // job with the diagnosis.
            let scene: serde_json::Value =
                blocking(move || serde_json::from_str(&text).map_err(ApiError::internal)).await?;
            tracing::info!(job = %job.id, worker = %req.worker_id, attempt = job.attempts, "claimed");
            st.announce(&job);
            return Ok(Json(Claim {
                job_id: job.id,
                fence: job.fence,
                attempt: job.attempts,
                scene,
                lease_seconds: st.cfg.lease.as_secs_f64(),
            })
            .into_response());
        }
        let now = tokio::time::Instant::now();
        if now >= deadline {
            return Ok(StatusCode::NO_CONTENT.into_response());
        }
        // Poll at least every second in case a notification was missed.
        let nap = (deadline - now).min(Duration::from_secs(1));
        tokio::select! {
            _ = notified => {}
            _ = tokio::time::sleep(nap) => {}
            _ = crate::server::until_shutdown(&mut shutdown) => {}
        }
    }
}

/// Extend the lease and report progress; the reply says whether to cancel.
#[utoipa::path(post, path = "/api/v1/worker/jobs/{id}/heartbeat", tag = "worker",
    params(("id" = String, Path, description = "Job id")),
    request_body(content = Heartbeat, content_type = "application/json"),
    responses((status = 200, description = "Whether to cancel, and the lease", body = HeartbeatReply),
        (status = 401, description = "Missing or wrong worker token", body = ErrorBody),
        (status = 409, description = "Stale fencing token: drop the job", body = ErrorBody)),
    security(("bearer" = [])))]
pub(super) async fn worker_heartbeat(
    State(st): State<AppState>,
    _: WorkerToken,
    Path(id): Path<String>,
    ApiJson(hb): ApiJson<Heartbeat>,
) -> Result<Json<HeartbeatReply>, ApiError> {
    let cancel = st
        .store
        .heartbeat(&id, hb.fence, st.cfg.lease, hb.progress.as_ref())
        .await?;
    if let Some(p) = hb.progress {
        st.hub.send(&id, JobEvent::Progress(p));
    }
    Ok(Json(HeartbeatReply {
        cancel,
        lease_seconds: st.cfg.lease.as_secs_f64(),
    }))
}

/// Append a record to the job's MCAP file (off the async threads). Called after the rows
/// are committed: a failed file write gives the file up (`JobFiles::write`) but not the
/// request, so the worker does not resend rows the database already holds.
async fn write_file(st: &AppState, id: &str, fence: i64, rec: Record) -> Result<(), ApiError> {
    let files = st.files.clone();
    let id = id.to_string();
    blocking(move || {
        let _ = files.write(&id, fence, rec);
        Ok(())
    })
    .await
}

/// Append energy rows.
#[utoipa::path(post, path = "/api/v1/worker/jobs/{id}/energy", tag = "worker",
    params(("id" = String, Path, description = "Job id")),
    request_body(content = EnergyBatch, content_type = "application/json"),
    responses((status = 204, description = "Stored"),
        (status = 401, description = "Missing or wrong worker token", body = ErrorBody),
        (status = 409, description = "Stale fencing token", body = ErrorBody)),
    security(("bearer" = [])))]
pub(super) async fn worker_energy(
    State(st): State<AppState>,
    _: WorkerToken,
    Path(id): Path<String>,
    ApiJson(b): ApiJson<EnergyBatch>,
) -> Result<StatusCode, ApiError> {
    let rows = b.rows;
    st.store
        .append_energy(&id, b.fence, st.cfg.lease, &rows)
        .await?;
    write_file(&st, &id, b.fence, Record::Energy(rows.clone())).await?;
    st.hub.send(&id, JobEvent::Energy(rows));
    Ok(StatusCode::NO_CONTENT)
}

/// Append crack-tip rows.
#[utoipa::path(post, path = "/api/v1/worker/jobs/{id}/crack-tips", tag = "worker",
    params(("id" = String, Path, description = "Job id")),
    request_body(content = CrackTipBatch, content_type = "application/json"),
    responses((status = 204, description = "Stored"),
        (status = 401, description = "Missing or wrong worker token", body = ErrorBody),
        (status = 409, description = "Stale fencing token", body = ErrorBody)),
    security(("bearer" = [])))]
pub(super) async fn worker_crack_tips(
    State(st): State<AppState>,
    _: WorkerToken,
    Path(id): Path<String>,
    ApiJson(b): ApiJson<CrackTipBatch>,
) -> Result<StatusCode, ApiError> {
    let rows = b.rows;
    st.store
        .append_crack_tips(&id, b.fence, st.cfg.lease, &rows)
        .await?;
    write_file(&st, &id, b.fence, Record::CrackTips(rows.clone())).await?;
    st.hub.send(&id, JobEvent::CrackTips(rows));
    Ok(StatusCode::NO_CONTENT)
}

/// Query of the snapshot upload.
#[derive(Debug, Deserialize, utoipa::IntoParams)]
#[serde(deny_unknown_fields)]
pub(super) struct FenceQuery {
    /// Fencing token of the claim.
    fence: i64,
}

/// Upload a snapshot (binary body, see `codec`).
#[utoipa::path(post, path = "/api/v1/worker/jobs/{id}/snapshots", tag = "worker",
    params(("id" = String, Path, description = "Job id"), FenceQuery),
    request_body(content = Vec<u8>, description = "Encoded snapshot", content_type = "application/octet-stream"),
    responses((status = 204, description = "Stored"),
        (status = 400, description = "Not a snapshot", body = ErrorBody),
        (status = 401, description = "Missing or wrong worker token", body = ErrorBody),
        (status = 409, description = "Stale fencing token", body = ErrorBody)),
    security(("bearer" = [])))]
pub(super) async fn worker_snapshot(
    State(st): State<AppState>,
    _: WorkerToken,
    Path(id): Path<String>,
    ApiQuery(q): ApiQuery<FenceQuery>,
    RawBody(body): RawBody,
) -> Result<StatusCode, ApiError> {
    let (snap, body) = blocking(move || {
        let snap =
            codec::decode_snapshot(&body).map_err(|e| ApiError::BadRequest(e.to_string()))?;
        Ok((snap, body))
    })
    .await?;
    st.store
        .put_snapshot(&id, q.fence, st.cfg.lease, &snap, &body)
        .await?;
    let info = SnapshotInfo {
        index: snap.index,
        time: snap.time,
        fields: snap.fields.clone(),
        components: snap.components.iter().map(|c| c.name.clone()).collect(),
        slice: snap.slice.clone(),
    };
    write_file(&st, &id, q.fence, Record::Snapshot(Box::new(snap))).await?;
    st.hub.send(&id, JobEvent::Snapshot(info));
    Ok(StatusCode::NO_CONTENT)
}

/// Finish the run with its summary.
#[utoipa::path(post, path = "/api/v1/worker/jobs/{id}/finish", tag = "worker",
    params(("id" = String, Path, description = "Job id")),
    request_body(content = FinishRequest, content_type = "application/json"),
    responses((status = 200, description = "The job", body = JobInfo),
        (status = 401, description = "Missing or wrong worker token", body = ErrorBody),
        (status = 409, description = "Stale fencing token", body = ErrorBody)),
    security(("bearer" = [])))]
pub(super) async fn worker_finish(
    State(st): State<AppState>,
    _: WorkerToken,
    Path(id): Path<String>,
    ApiJson(f): ApiJson<FinishRequest>,
) -> Result<Json<JobInfo>, ApiError> {
    // Close the file first so a client that sees the final status gets a complete MCAP.
    let current = job_or_404(&st, &id).await?;
    if current.fence != f.fence || current.status != JobStatus::Running {
        return Err(StoreError::Fenced.into());
    }
    let files = st.files.clone();
    let id2 = id.clone();
    blocking(move || {
        // A file that cannot be finished is given up (`JobFiles::finish`); the run's record
        // is the database.
        let _ = files.finish(&id2);
        Ok(())
    })
    .await?;
    let mut summary = f.summary;
    // `summary.tips` from every stored row: a worker that resumed from a checkpoint saw only
    // the rows since it (the rows are the record; the summary is a function of them).
    if let Ok(scene) = serde_json::from_str::<fracture_api::Scene>(&current.scene)
        && !(scene.cracks.is_empty() && scene.interfaces.is_empty())
    {
        let rows = st.store.crack_tips(&id, None).await?;
        let (tips, references) = fracture_api::tips::summarize(&scene, &rows);
        summary.tips = tips;
        summary.references = references;
    }
    let row = st.store.finish(&id, f.fence, &summary).await?;
    // The run is over: nothing will resume from its checkpoint.
    super::checkpoint::remove_after_finish(&st, &id).await;
    tracing::info!(job = %id, status = row.status.as_str(), "finished");
    st.announce(&row);
    st.queue_changed.notify_waiters();
    Ok(Json(row.info(false)?))
}

/// Longest exit cause kept in a job's message (characters).
const MAX_CAUSE_CHARS: usize = 4000;

/// A remote worker's supervisor reports that its worker process died while it held this
/// claim: the job is released at once, by the rules of a local worker's death (re-queued;
/// failed past the attempt limit, or at once when the cause shows it ran out of memory;
/// cancelled if that was asked), with the cause in its message.
#[utoipa::path(post, path = "/api/v1/worker/jobs/{id}/died", tag = "worker",
    params(("id" = String, Path, description = "Job id")),
    request_body(content = WorkerDied, content_type = "application/json"),
    responses((status = 200, description = "The released job", body = JobInfo),
        (status = 401, description = "Missing or wrong worker token", body = ErrorBody),
        (status = 409, description = "Stale fencing token: the job was already released or finished", body = ErrorBody)),
    security(("bearer" = [])))]
pub(super) async fn worker_died(
    State(st): State<AppState>,
    _: WorkerToken,
    Path(id): Path<String>,
    ApiJson(d): ApiJson<WorkerDied>,
) -> Result<Json<JobInfo>, ApiError> {
    let cause: String = if d.cause.chars().count() > MAX_CAUSE_CHARS {
        format!(
            "{}…",
            d.cause.chars().take(MAX_CAUSE_CHARS).collect::<String>()
        )
    } else {
        d.cause
    };
    let cause = if cause.trim().is_empty() {
        "its process ended (no cause given)".to_string()
    } else {
        cause
    };
    let rows = crate::service::release_dead(
        &st,
        crate::service::DeadWorker::Claim(&id, d.fence),
        &format!("{} (reported by its supervisor)", cause.trim()),
    )
    .await?;
    let row = rows.into_iter().next().ok_or(StoreError::Fenced)?;
    Ok(Json(row.info(false)?))
}

/// Longest reason or worker name kept in a handed-back job's message (characters).
const MAX_RELEASE_CHARS: usize = 500;

/// A worker hands its claim back (a batch worker told to stop before its time limit, e.g.
/// by Slurm's `--signal`): the job returns to the queue without counting the attempt (or
/// ends cancelled if that was asked), for another worker to run.
#[utoipa::path(post, path = "/api/v1/worker/jobs/{id}/release", tag = "worker",
    params(("id" = String, Path, description = "Job id")),
    request_body(content = WorkerRelease, content_type = "application/json"),
    responses((status = 200, description = "The job, queued again", body = JobInfo),
        (status = 401, description = "Missing or wrong worker token", body = ErrorBody),
        (status = 409, description = "Stale fencing token: the job was already released or finished", body = ErrorBody)),
    security(("bearer" = [])))]
pub(super) async fn worker_release(
    State(st): State<AppState>,
    _: WorkerToken,
    Path(id): Path<String>,
    ApiJson(r): ApiJson<WorkerRelease>,
) -> Result<Json<JobInfo>, ApiError> {
    let cut = |s: &str| -> String {
        let s = s.trim();
        if s.chars().count() > MAX_RELEASE_CHARS {
            format!("{}…", s.chars().take(MAX_RELEASE_CHARS).collect::<String>())
        } else {
            s.to_string()
        }
    };
    let (reason, worker) = (cut(&r.reason), cut(&r.worker));
    let mut message = "handed back by its worker".to_string();
    if !worker.is_empty() {
        message.push_str(&format!(" {worker}"));
    }
    if !reason.is_empty() {
        message.push_str(&format!(" ({reason})"));
    }
    message.push_str("; re-queued without counting the attempt");
    let row = st.store.hand_back(&id, r.fence, &message).await?;
    tracing::info!(job = %id, status = row.status.as_str(), worker = %worker, "handed back");
    if row.status.is_terminal() {
        let files = st.files.clone();
        let id = id.clone();
        let _ = tokio::task::spawn_blocking(move || files.finish(&id)).await;
    }
    st.announce(&row);
    st.queue_changed.notify_waiters();
    Ok(Json(row.info(false)?))
}
