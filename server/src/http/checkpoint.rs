//! Checkpoints of running jobs over the worker protocol (`docs/service.md`, "Checkpoints"):
//! upload (`PUT …/checkpoint`), download on claim (`GET`, 404 when none), refusal (`DELETE`:
//! the worker could not use it, the job starts over), all fenced; and what a claim does with
//! a job's checkpoint before it answers ([`start_claim`]): the history of earlier attempts
//! is kept up to the checkpoint's cursor (everything is dropped without one) and the job's
//! MCAP file is rebuilt from what was kept, so a resumed run's history ends up as an
//! uninterrupted run's.

use axum::body::Body;
use axum::extract::{Path, State};
use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};
use fracture_api::AnyScene;
use fracture_api::jobs::ErrorBody;
use serde::Deserialize;

use super::auth::WorkerToken;
use super::blocking;
use crate::checkpoints::{self, Found};
use crate::error::{ApiError, ApiQuery, RawBody};
use crate::files::Record;
use crate::server::AppState;
use crate::store::{HistoryCursor, Restart};

/// Query of a checkpoint upload: the claim and where the checkpoint stands.
#[derive(Debug, Deserialize, utoipa::IntoParams)]
#[serde(deny_unknown_fields)]
pub(super) struct PutQuery {
    /// Fencing token of the claim.
    fence: i64,
    /// Steps taken.
    step: u64,
    /// Simulated time (s); rows sampled at or before it were sent before the checkpoint.
    time: f64,
    /// Snapshots taken (indices below this were sent before the checkpoint).
    snapshots: u32,
}

/// Query of a checkpoint download or refusal.
#[derive(Debug, Deserialize, utoipa::IntoParams)]
#[serde(deny_unknown_fields)]
pub(super) struct FenceQuery {
    /// Fencing token of the claim.
    fence: i64,
}

/// Store the job's checkpoint (replacing the previous one; a full disk keeps it).
#[utoipa::path(put, path = "/api/v1/worker/jobs/{id}/checkpoint", tag = "worker",
    params(("id" = String, Path, description = "Job id"), PutQuery),
    request_body(content = Vec<u8>, description = "The worker's checkpoint", content_type = "application/octet-stream"),
    responses((status = 204, description = "Stored"),
        (status = 400, description = "A bad cursor", body = ErrorBody),
        (status = 401, description = "Missing or wrong worker token", body = ErrorBody),
        (status = 409, description = "Stale fencing token", body = ErrorBody),
        (status = 507, description = "No room: the previous checkpoint stays", body = ErrorBody)),
    security(("bearer" = [])))]
pub(super) async fn put_checkpoint(
    State(st): State<AppState>,
    _: WorkerToken,
    Path(id): Path<String>,
    ApiQuery(q): ApiQuery<PutQuery>,
    RawBody(body): RawBody,
) -> Result<StatusCode, ApiError> {
    if !q.time.is_finite() || q.time < 0.0 || body.is_empty() {
        return Err(ApiError::BadRequest(
            "a checkpoint needs a finite time ≥ 0 and a body".into(),
        ));
    }
    let _g = checkpoints::LOCK.lock().await;
    // Fenced while the lock is held: a claim after this one waits for the file.
    st.store.heartbeat(&id, q.fence, st.cfg.lease, None).await?;
    let dir = st.files.dir(&id);
    let at = HistoryCursor {
        step: q.step,
        time: q.time,
        snapshots: q.snapshots,
    };
    let n = body.len();
    let t0 = std::time::Instant::now();
    blocking(move || checkpoints::write(&dir, q.fence, at, &body).map_err(|e| ApiError::io(&e)))
        .await?;
    tracing::info!(job = %id, step = q.step, bytes = n,
        write_ms = t0.elapsed().as_secs_f64() * 1e3, "checkpoint stored");
    Ok(StatusCode::NO_CONTENT)
}

/// The job's checkpoint, for the claim holding it (404 when it has none).
#[utoipa::path(get, path = "/api/v1/worker/jobs/{id}/checkpoint", tag = "worker",
    params(("id" = String, Path, description = "Job id"), FenceQuery),
    responses((status = 200, description = "The worker's checkpoint", content_type = "application/octet-stream"),
        (status = 401, description = "Missing or wrong worker token", body = ErrorBody),
        (status = 404, description = "No checkpoint", body = ErrorBody),
        (status = 409, description = "Stale fencing token", body = ErrorBody)),
    security(("bearer" = [])))]
pub(super) async fn get_checkpoint(
    State(st): State<AppState>,
    _: WorkerToken,
    Path(id): Path<String>,
    ApiQuery(q): ApiQuery<FenceQuery>,
) -> Result<Response, ApiError> {
    let _g = checkpoints::LOCK.lock().await;
    st.store.heartbeat(&id, q.fence, st.cfg.lease, None).await?;
    let dir = st.files.dir(&id);
    match blocking(move || checkpoints::read(&dir).map_err(|e| ApiError::io(&e))).await? {
        Found::None => Err(ApiError::NotFound("this job has no checkpoint".into())),
        // The claim kept the history to its cursor: the worker must refuse it (DELETE).
        Found::Corrupt(why) => Err(ApiError::internal(format!("corrupt checkpoint: {why}"))),
        Found::Some(_, bytes) => Ok((
            [(header::CONTENT_TYPE, "application/octet-stream")],
            Body::from(bytes),
        )
            .into_response()),
    }
}

/// The worker cannot use the job's checkpoint (corrupt, another build): it is removed, the
/// job's history is dropped and its MCAP file restarted; the run starts over from step 0.
#[utoipa::path(delete, path = "/api/v1/worker/jobs/{id}/checkpoint", tag = "worker",
    params(("id" = String, Path, description = "Job id"), FenceQuery),
    responses((status = 204, description = "Removed; the history starts over"),
        (status = 401, description = "Missing or wrong worker token", body = ErrorBody),
        (status = 409, description = "Stale fencing token", body = ErrorBody)),
    security(("bearer" = [])))]
pub(super) async fn delete_checkpoint(
    State(st): State<AppState>,
    _: WorkerToken,
    Path(id): Path<String>,
    ApiQuery(q): ApiQuery<FenceQuery>,
) -> Result<StatusCode, ApiError> {
    let _g = checkpoints::LOCK.lock().await;
    st.store.heartbeat(&id, q.fence, st.cfg.lease, None).await?;
    let dir = st.files.dir(&id);
    blocking(move || checkpoints::remove(&dir).map_err(|e| ApiError::io(&e))).await?;
    st.store
        .rewind_history(&id, q.fence, st.cfg.lease, None)
        .await?;
    let job = st
        .store
        .get(&id)
        .await?
        .ok_or_else(|| ApiError::NotFound("no such job".into()))?;
    restart_file(&st, &id, q.fence, &job.scene, None).await?;
    tracing::warn!(job = %id, "checkpoint refused by the worker; the run starts over");
    Ok(StatusCode::NO_CONTENT)
}

/// A claim under `fence` starts: keep the history its checkpoint covers (none without
/// one; a corrupt checkpoint is removed), and open its MCAP file with that history.
pub(super) async fn start_claim(
    st: &AppState,
    id: &str,
    fence: i64,
    scene: &str,
) -> Result<Option<Restart>, ApiError> {
    let _g = checkpoints::LOCK.lock().await;
    let dir = st.files.dir(id);
    let found = blocking(move || checkpoints::read(&dir).map_err(|e| ApiError::io(&e))).await;
    let keep = match found {
        Ok(Found::Some(at, _)) => Some(at),
        Ok(Found::None) => None,
        Ok(Found::Corrupt(why)) => {
            tracing::warn!(job = %id, reason = %why, "corrupt checkpoint removed; the run starts over");
            let dir = st.files.dir(id);
            let _ = blocking(move || checkpoints::remove(&dir).map_err(|e| ApiError::io(&e))).await;
            None
        }
        Err(e) => {
            tracing::warn!(job = %id, error = %e, "checkpoint unreadable; the run starts over");
            None
        }
    };
    let restart = st
        .store
        .rewind_history(id, fence, st.cfg.lease, keep)
        .await?;
    restart_file(st, id, fence, scene, keep).await?;
    if let Some(k) = keep {
        tracing::info!(job = %id, step = k.step, "resuming from its checkpoint");
    }
    if let Some(r) = &restart {
        tracing::info!(job = %id, attempt = r.attempt, "{}", r.message);
    }
    Ok(restart)
}

/// Open the job's MCAP file afresh under `fence` and write into it the history kept from
/// earlier attempts (in time order: rows up to each snapshot's time, then the snapshot).
async fn restart_file(
    st: &AppState,
    id: &str,
    fence: i64,
    scene: &str,
    kept: Option<HistoryCursor>,
) -> Result<(), ApiError> {
    let (energy, tips, snaps) = if kept.is_some() {
        let energy = st.store.energy(id, None).await?;
        let tips = st.store.crack_tips(id, None).await?;
        let mut snaps = Vec::new();
        for info in st.store.snapshots(id).await? {
            if let Some(s) = st.store.snapshot(id, info.index).await? {
                snaps.push(s);
            }
        }
        (energy, tips, snaps)
    } else {
        Default::default()
    };
    let files = st.files.clone();
    let (id, text) = (id.to_string(), scene.to_string());
    blocking(move || {
        // The file records the scene when this version can read it; a file that cannot be
        // written is given up (`JobFiles`), not the claim.
        let typed: Option<AnyScene> = serde_json::from_str(&text).ok();
        if files.start(&id, fence, typed.as_ref()).is_err() {
            return Ok(());
        }
        let (mut e, mut t) = (0, 0);
        let upto = |time: f64, rows_e: &mut usize, rows_t: &mut usize| {
            let e1 = *rows_e
                + energy[*rows_e..]
                    .iter()
                    .take_while(|r| r.time <= time)
                    .count();
            let t1 = *rows_t
                + tips[*rows_t..]
                    .iter()
                    .take_while(|r| r.time <= time)
                    .count();
            let r = (energy[*rows_e..e1].to_vec(), tips[*rows_t..t1].to_vec());
            (*rows_e, *rows_t) = (e1, t1);
            r
        };
        for s in snaps {
            let (re, rt) = upto(s.time, &mut e, &mut t);
            write_rows(&files, &id, fence, re, rt);
            let _ = files.write(&id, fence, Record::Snapshot(Box::new(s)));
        }
        let (re, rt) = upto(f64::INFINITY, &mut e, &mut t);
        write_rows(&files, &id, fence, re, rt);
        Ok(())
    })
    .await
}

/// Rows into the job's MCAP file (a failed write gives the file up: `JobFiles::write`).
fn write_rows(
    files: &crate::files::JobFiles,
    id: &str,
    fence: i64,
    energy: Vec<fracture_api::results::EnergyRow>,
    tips: Vec<fracture_api::results::CrackTipRow>,
) {
    if !energy.is_empty() {
        let _ = files.write(id, fence, Record::Energy(energy));
    }
    if !tips.is_empty() {
        let _ = files.write(id, fence, Record::CrackTips(tips));
    }
}

/// Remove a finished job's checkpoint (its run is over; a failure only leaves a file that
/// the job's deletion removes).
pub(super) async fn remove_after_finish(st: &AppState, id: &str) {
    let _g = checkpoints::LOCK.lock().await;
    let dir = st.files.dir(id);
    if let Err(e) = blocking(move || checkpoints::remove(&dir).map_err(|e| ApiError::io(&e))).await
    {
        tracing::warn!(job = %id, error = %e, "could not remove the checkpoint of a finished job");
    }
}
