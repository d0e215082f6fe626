//! Jobs: submit (bare scene or `{scene, priority, labels}`, 2D or 3D), list with filters
//! (status, labels, name search) and cursors, one job, rerun, cancel, delete.

use std::collections::BTreeMap;

use axum::Json;
use axum::extract::{Path, RawQuery, State};
use axum::http::{HeaderMap, StatusCode};
use axum::response::Response;
use fracture_api::jobs::{CacheMode, ErrorBody, ErrorDetail, JobInfo, JobRequest, JobStatus};
use fracture_api::{AnyScene, any_scene_from_value, scene_any};
use serde::Deserialize;

use super::auth::ApiToken;
use super::meta::admit;
use super::{blocking, job_or_404, location, page, page_cursor, page_limit};
use crate::error::{ApiError, JsonBody, parse_json};
use crate::server::{AppState, new_job_id};
use crate::store::{ListFilter, NewJob};

/// A wrapper field path of a request error, relative to the scene document (`scene.` taken
/// off; `(document)` for the whole request).
fn wrapper_error(e: serde_path_to_error::Error<serde_json::Error>) -> ApiError {
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
}

/// The request of `POST /api/v1/jobs` in either form, with a scene of either dimension;
/// field paths of errors are relative to the scene document in both. A 2D scene is read as
/// it always was (the wrapper and its scene in one pass: the same errors); a 3D one
/// (`"analysis": "3d"`) with the wrapper's scene as a JSON value first, then the scene by
/// [`any_scene_from_value`].
fn parse_job_request(value: serde_json::Value) -> Result<JobRequest<AnyScene>, ApiError> {
    let wrapped = value
        .as_object()
        .is_some_and(|o| o.contains_key("scene") && !o.contains_key("grid"));
    if !wrapped {
        return Ok(JobRequest {
            scene: any_scene_from_value(value)?,
            priority: 0,
            labels: BTreeMap::new(),
            cache: CacheMode::Reuse,
            max_attempts: None,
        });
    }
    let three = value.get("scene").is_some_and(scene_any::is_3d);
    if !three {
        let r = serde_path_to_error::deserialize::<_, JobRequest>(value).map_err(wrapper_error)?;
        return Ok(JobRequest {
            scene: AnyScene::Two(r.scene),
            priority: r.priority,
            labels: r.labels,
            cache: r.cache,
            max_attempts: r.max_attempts,
        });
    }
    let r = serde_path_to_error::deserialize::<_, JobRequest<serde_json::Value>>(value)
        .map_err(wrapper_error)?;
    Ok(JobRequest {
        scene: any_scene_from_value(r.scene)?,
        priority: r.priority,
        labels: r.labels,
        cache: r.cache,
        max_attempts: r.max_attempts,
    })
}

/// A job's own retry budget must allow one claim (0 would never run).
pub(super) fn check_max_attempts(n: Option<u32>) -> Result<(), ApiError> {
    if n == Some(0) {
        return Err(ApiError::InvalidScene(vec![ErrorDetail {
            path: "max_attempts".into(),
            message: "0 must be at least 1 (leave it out for the server's --max-attempts)".into(),
        }]));
    }
    Ok(())
}

/// Submit a scene (bare, or wrapped as `{scene, priority, labels}`).
#[utoipa::path(post, path = "/api/v1/jobs", tag = "jobs",
    request_body(content = Object, description = "A scene, or `{\"scene\": {...}, \"priority\": 0, \"labels\": {...}}` \
        (the scene's JSON Schema: `fracture schema`; a 3D scene has `\"analysis\": \"3d\"`)",
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
    check_max_attempts(req.max_attempts)?;
    let (scene, _) = admit(&st, req.scene).await?;
    let job = NewJob {
        id: new_job_id(),
        name: scene.name().to_string(),
        scene: scene.canonical_json(),
        end_time: scene.end_time(),
        priority: req.priority,
        labels: req.labels,
        rerun_of: None,
        scene_hash: scene.hash(),
        use_cache: req.cache == CacheMode::Reuse,
        max_attempts: req.max_attempts,
    };
    let row = st.store.create_job(&job).await?;
    if let Some(src) = &row.cached_from {
        tracing::info!(job = %row.id, cached_from = %src, "cache hit: the scene has a completed run");
    } else {
        st.queue_changed.notify_waiters();
    }
    let h = location(&format!("/api/v1/jobs/{}", row.id));
    Ok((StatusCode::CREATED, h, Json(row.info(true)?)))
}

/// Query of `GET /api/v1/jobs` (read by [`ListQuery::parse`]: `label` may be repeated).
#[derive(Debug, Default, Deserialize, utoipa::IntoParams)]
#[serde(deny_unknown_fields)]
pub(super) struct ListQuery {
    /// Only jobs in this state.
    status: Option<String>,
    /// Only jobs with this label, `key:value`; repeat it for jobs with all of them
    /// (`?label=a:1&label=b:2`).
    #[param(style = Form, explode)]
    label: Vec<String>,
    /// Only jobs whose name contains this text (ASCII letters compared case-insensitively).
    q: Option<String>,
    /// Page size (default 50, at most 500).
    limit: Option<i64>,
    /// The `X-Next-Cursor` of the previous page.
    cursor: Option<String>,
}

/// The parameters [`ListQuery`] knows, for the message of an unknown one.
const LIST_PARAMETERS: &str = "`status`, `label`, `q`, `limit`, `cursor`";

impl ListQuery {
    /// Decode the query string. As with the other query types (`deny_unknown_fields`), an
    /// unknown parameter, a repeated one other than `label` and a malformed value are 400s.
    fn parse(raw: Option<&str>) -> Result<ListQuery, ApiError> {
        let raw = raw.unwrap_or("");
        let uri: axum::http::Uri = format!("/?{raw}")
            .parse()
            .map_err(|e| ApiError::BadRequest(format!("bad query string: {e}")))?;
        let axum::extract::Query(pairs) =
            axum::extract::Query::<Vec<(String, String)>>::try_from_uri(&uri).map_err(|e| {
                ApiError::BadRequest(format!("bad query string: {}", e.body_text()))
            })?;
        let mut q = ListQuery::default();
        // The message serde gave before (`bad query string: …`), now with the parameter in
        // `details[].path`.
        fn query_error(key: &str, what: String) -> ApiError {
            ApiError::BadParameter {
                message: format!("bad query string: {what}"),
                details: vec![fracture_api::jobs::ErrorDetail {
                    path: key.to_string(),
                    message: what,
                }],
            }
        }
        fn once(slot: &mut Option<String>, key: &str, v: String) -> Result<(), ApiError> {
            if slot.replace(v).is_some() {
                return Err(query_error(key, format!("duplicate field `{key}`")));
            }
            Ok(())
        }
        let mut limit = None;
        for (k, v) in pairs {
            match k.as_str() {
                "status" => once(&mut q.status, &k, v)?,
                "q" => once(&mut q.q, &k, v)?,
                "cursor" => once(&mut q.cursor, &k, v)?,
                "limit" => once(&mut limit, &k, v)?,
                "label" => q.label.push(v),
                _ => {
                    return Err(query_error(
                        &k,
                        format!("unknown field `{k}`, expected one of {LIST_PARAMETERS}"),
                    ));
                }
            }
        }
        if let Some(l) = limit {
            q.limit = Some(l.trim().parse::<i64>().map_err(|_| {
                ApiError::bad_parameter("limit", format!("`{l}` is not a whole number"))
            })?);
        }
        Ok(q)
    }
}

/// Jobs, newest first (next page: the `X-Next-Cursor` response header). Filters combine
/// with AND.
#[utoipa::path(get, path = "/api/v1/jobs", tag = "jobs", params(ListQuery),
    responses((status = 200, description = "Jobs without their scenes", body = Vec<JobInfo>),
        (status = 400, description = "Bad or unknown parameter", body = ErrorBody)))]
pub(super) async fn list_jobs(
    State(st): State<AppState>,
    RawQuery(raw): RawQuery,
) -> Result<Response, ApiError> {
    let q = ListQuery::parse(raw.as_deref())?;
    let status = match q.status.as_deref() {
        None | Some("") => None,
        Some(s) => Some(JobStatus::parse(s).ok_or_else(|| {
            ApiError::BadRequest(format!(
                "unknown status `{s}` (queued, running, completed, failed, cancelled)"
            ))
        })?),
    };
    let mut labels = Vec::new();
    for l in q.label.iter().filter(|l| !l.is_empty()) {
        let (k, v) = l
            .split_once(':')
            .ok_or_else(|| ApiError::BadRequest("label must be `key:value`".into()))?;
        labels.push((k.to_string(), v.to_string()));
    }
    let name_contains = q.q.clone().filter(|t| !t.is_empty());
    let limit = page_limit(q.limit)?;
    let before_seq = page_cursor(q.cursor.as_deref())?;
    let rows = st
        .store
        .list(&ListFilter {
            status,
            labels,
            name_contains,
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

/// Run a job's scene again: a new queued job with the same scene, name, labels and priority,
/// whose `rerun_of` is the original's id. The scene is admitted again under this server's
/// current limits (422 if it no longer fits them).
#[utoipa::path(post, path = "/api/v1/jobs/{id}/rerun", tag = "jobs",
    params(("id" = String, Path, description = "Id of the job to run again")),
    responses((status = 201, description = "The new job, queued, with `rerun_of`", body = JobInfo),
        (status = 401, description = "Missing or wrong API token", body = ErrorBody),
        (status = 403, description = "A cross-site request", body = ErrorBody),
        (status = 404, description = "Unknown id", body = ErrorBody),
        (status = 422, description = "The scene is over a limit of this server", body = ErrorBody),
        (status = 503, description = "The server is shutting down", body = ErrorBody)),
    security(("bearer" = [])))]
pub(super) async fn rerun_job(
    State(st): State<AppState>,
    _: ApiToken,
    Path(id): Path<String>,
) -> Result<(StatusCode, HeaderMap, Json<JobInfo>), ApiError> {
    if st.shutting_down() {
        return Err(ApiError::Unavailable);
    }
    let orig = job_or_404(&st, &id).await?;
    let value: serde_json::Value = serde_json::from_str(&orig.scene).map_err(ApiError::internal)?;
    let scene = any_scene_from_value(value)?;
    let (scene, _) = admit(&st, scene).await?;
    let job = NewJob {
        id: new_job_id(),
        name: orig.name.clone(),
        scene: scene.canonical_json(),
        end_time: scene.end_time(),
        priority: orig.priority,
        labels: orig.labels.clone(),
        rerun_of: Some(orig.id.clone()),
        scene_hash: scene.hash(),
        // A rerun is asked for by name: it always runs.
        use_cache: false,
        max_attempts: orig.max_attempts,
    };
    let row = st.store.create_job(&job).await?;
    st.queue_changed.notify_waiters();
    let h = location(&format!("/api/v1/jobs/{}", row.id));
    Ok((StatusCode::CREATED, h, Json(row.info(true)?)))
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
