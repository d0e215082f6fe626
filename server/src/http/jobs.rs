//! Jobs: submit (bare scene or `{scene, priority, labels}`), list with filters and cursors,
//! one job, cancel, delete.

use std::collections::BTreeMap;

use axum::Json;
use axum::extract::{Path, State};
use axum::http::{HeaderMap, StatusCode};
use axum::response::Response;
use fracture_api::jobs::{ErrorBody, ErrorDetail, JobInfo, JobRequest, JobStatus};
use fracture_api::validate;
use serde::Deserialize;

use super::auth::ApiToken;
use super::meta::admit;
use super::{blocking, job_or_404, location, page, page_cursor, page_limit};
use crate::error::{ApiError, ApiQuery, JsonBody, parse_json};
use crate::server::{AppState, new_job_id};
use crate::store::{ListFilter, NewJob};

/// The request of `POST /api/v1/jobs` in either form; field paths of errors are relative to
/// the scene document in both.
fn parse_job_request(value: serde_json::Value) -> Result<JobRequest, ApiError> {
    let wrapped = value
        .as_object()
        .is_some_and(|o| o.contains_key("scene") && !o.contains_key("grid"));
    if wrapped {
        serde_path_to_error::deserialize::<_, JobRequest>(value).map_err(|e| {
            let path = e.path().to_string();
            let path = match path.strip_prefix("scene.") {
                Some(p) => p.to_string(),
                None if path == "." => "(document)".to_string(),
                None => path,
            };
            ApiError::InvalidScene(vec![ErrorDetail {
                path,
                message: e.into_inner().to_string(),
            }])
        })
    } else {
        let scene = validate::scene_from_value(value)?;
        Ok(JobRequest {
            scene,
            priority: 0,
            labels: BTreeMap::new(),
        })
    }
}

/// Submit a scene (bare, or wrapped as `{scene, priority, labels}`).
#[utoipa::path(post, path = "/api/v1/jobs", tag = "jobs",
    request_body(content = Object, description = "A scene, or `{\"scene\": {...}, \"priority\": 0, \"labels\": {...}}` \
        (the scene's JSON Schema: `fracture schema`)",
        content_type = "application/json"),
    responses(
        (status = 201, description = "The job, queued", body = JobInfo),
        (status = 400, description = "Malformed JSON", body = ErrorBody),
        (status = 401, description = "Missing or wrong API token", body = ErrorBody),
        (status = 413, description = "Body too large", body = ErrorBody),
        (status = 422, description = "Invalid scene (`invalid_scene`) or over a limit (`limit_exceeded`)", body = ErrorBody),
        (status = 503, description = "The server is shutting down", body = ErrorBody)),
    security(("bearer" = [])))]
pub(super) async fn create_job(
    State(st): State<AppState>,
    _: ApiToken,
    JsonBody(body): JsonBody,
) -> Result<(StatusCode, HeaderMap, Json<JobInfo>), ApiError> {
    if st.shutting_down() {
        return Err(ApiError::Unavailable);
    }
    let value: serde_json::Value = parse_json(&body)?;
    let req = parse_job_request(value)?;
    st.cfg.limits.check_names(None, &req.labels)?;
    let (scene, _) = admit(&st, req.scene).await?;
    let job = NewJob {
        id: new_job_id(),
        name: scene.name.clone(),
        scene: scene.canonical_json(),
        end_time: scene.time.end,
        priority: req.priority,
        labels: req.labels,
    };
    let row = st.store.create_job(&job).await?;
    st.queue_changed.notify_waiters();
    let h = location(&format!("/api/v1/jobs/{}", row.id));
    Ok((StatusCode::CREATED, h, Json(row.info(true)?)))
}

/// Query of `GET /api/v1/jobs`.
#[derive(Debug, Deserialize, utoipa::IntoParams)]
#[serde(deny_unknown_fields)]
pub(super) struct ListQuery {
    /// Only jobs in this state.
    status: Option<String>,
    /// Only jobs with this label, `key:value`.
    label: Option<String>,
    /// Page size (default 50, at most 500).
    limit: Option<i64>,
    /// The `X-Next-Cursor` of the previous page.
    cursor: Option<String>,
}

/// Jobs, newest first (next page: the `X-Next-Cursor` response header).
#[utoipa::path(get, path = "/api/v1/jobs", tag = "jobs", params(ListQuery),
    responses((status = 200, description = "Jobs without their scenes", body = Vec<JobInfo>),
        (status = 400, description = "Bad parameter", body = ErrorBody)))]
pub(super) async fn list_jobs(
    State(st): State<AppState>,
    ApiQuery(q): ApiQuery<ListQuery>,
) -> Result<Response, ApiError> {
    let status = match q.status.as_deref() {
        None | Some("") => None,
        Some(s) => Some(JobStatus::parse(s).ok_or_else(|| {
            ApiError::BadRequest(format!(
                "unknown status `{s}` (queued, running, completed, failed, cancelled)"
            ))
        })?),
    };
    let label = match q.label.as_deref() {
        None | Some("") => None,
        Some(l) => {
            let (k, v) = l
                .split_once(':')
                .ok_or_else(|| ApiError::BadRequest("label must be `key:value`".into()))?;
            Some((k.to_string(), v.to_string()))
        }
    };
    let limit = page_limit(q.limit)?;
    let before_seq = page_cursor(q.cursor.as_deref())?;
    let rows = st
        .store
        .list(&ListFilter {
            status,
            label,
            limit,
            before_seq,
        })
        .await?;
    let jobs = rows
        .iter()
        .map(|r| r.info(false))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(page(jobs, limit, rows.last().map(|r| r.seq)))
}

/// One job with its scene, progress and summary (and, beyond `api.md`, `worker`: the
/// worker holding its lease, `null` when none).
#[utoipa::path(get, path = "/api/v1/jobs/{id}", tag = "jobs",
    params(("id" = String, Path, description = "Job id")),
    responses((status = 200, description = "The job, with `worker`", body = JobInfo),
        (status = 404, description = "Unknown id", body = ErrorBody)))]
pub(super) async fn get_job(
    State(st): State<AppState>,
    Path(id): Path<String>,
) -> Result<Json<serde_json::Value>, ApiError> {
    let job = job_or_404(&st, &id).await?;
    let mut v = serde_json::to_value(job.info(true)?).map_err(ApiError::internal)?;
    if let Some(o) = v.as_object_mut() {
        o.insert("worker".into(), job.worker_id.clone().into());
    }
    Ok(Json(v))
}

/// Cancel a job: a queued job at once, a running one within a second or two.
#[utoipa::path(post, path = "/api/v1/jobs/{id}/cancel", tag = "jobs",
    params(("id" = String, Path, description = "Job id")),
    responses((status = 200, description = "The job after the request", body = JobInfo),
        (status = 401, description = "Missing or wrong API token", body = ErrorBody),
        (status = 404, description = "Unknown id", body = ErrorBody)),
    security(("bearer" = [])))]
pub(super) async fn cancel_job(
    State(st): State<AppState>,
    _: ApiToken,
    Path(id): Path<String>,
) -> Result<Json<JobInfo>, ApiError> {
    let before = job_or_404(&st, &id).await?;
    let after = st
        .store
        .cancel(&id)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("no job with id `{id}`")))?;
    if before.status != after.status {
        st.announce(&after);
    }
    Ok(Json(after.info(false)?))
}

/// Delete a finished job and its files.
#[utoipa::path(delete, path = "/api/v1/jobs/{id}", tag = "jobs",
    params(("id" = String, Path, description = "Job id")),
    responses((status = 204, description = "Deleted"),
        (status = 401, description = "Missing or wrong API token", body = ErrorBody),
        (status = 404, description = "Unknown id", body = ErrorBody),
        (status = 409, description = "The job has not finished", body = ErrorBody)),
    security(("bearer" = [])))]
pub(super) async fn delete_job(
    State(st): State<AppState>,
    _: ApiToken,
    Path(id): Path<String>,
) -> Result<StatusCode, ApiError> {
    let job = job_or_404(&st, &id).await?;
    if !job.status.is_terminal() {
        return Err(ApiError::Conflict(format!(
            "job `{id}` is {}; cancel it first",
            job.status.as_str()
        )));
    }
    if !st.store.delete(&id).await? {
        return Err(ApiError::Conflict(format!(
            "job `{id}` could not be deleted"
        )));
    }
    // The row is gone (committed): the job is deleted. A folder that cannot be removed now
    // is an orphan removed at the next start (`JobFiles::remove_orphans`).
    let files = st.files.clone();
    blocking(move || {
        if let Err(e) = files.delete(&id) {
            tracing::warn!(job = %id, error = %e, "cannot remove the results folder; removed at the next start");
        }
        Ok(())
    })
    .await?;
    Ok(StatusCode::NO_CONTENT)
}
