//! Parameter sweeps (an extension of `api.md`, see `docs/service.md`): create (every
//! combination built and admitted before any job is stored), list, get, cancel, delete.

use std::collections::BTreeMap;

use axum::Json;
use axum::extract::{Path, State};
use axum::http::{HeaderMap, StatusCode};
use axum::response::Response;
use fracture_api::any_scene_from_value;
use fracture_api::jobs::CacheMode;
use fracture_api::jobs::{ErrorBody, ErrorDetail, JobStatus};
use fracture_api::sweep::{self, SweepInfo, SweepJob, SweepParameter, SweepRequest};
use serde::Deserialize;

use super::auth::ApiToken;
use super::{blocking, location, page, page_cursor, page_limit};
use crate::config::Limits;
use crate::error::{ApiError, ApiQuery, JsonBody, parse_json};
use crate::server::{AppState, new_job_id};
use crate::store::{JobRow, NewJob, NewSweep, NewSweepJob, StoreError, SweepRow};

/// Details of a sweep error are capped so a large grid of bad values stays readable.
const MAX_SWEEP_DETAILS: usize = 20;

/// A sweep as the API shows it; `full` adds the base scene and the jobs.
fn sweep_info(row: &SweepRow, jobs: &[JobRow], full: bool) -> Result<SweepInfo, StoreError> {
    let statuses: Vec<JobStatus> = jobs.iter().map(|j| j.status).collect();
    let mut counts: BTreeMap<String, u64> = [
        JobStatus::Queued,
        JobStatus::Running,
        JobStatus::Completed,
        JobStatus::Failed,
        JobStatus::Cancelled,
    ]
    .iter()
    .map(|s| (s.as_str().to_string(), 0))
    .collect();
    for s in &statuses {
        *counts.entry(s.as_str().to_string()).or_default() += 1;
    }
    let fraction = |j: &JobRow| -> f64 {
        if j.status.is_terminal() {
            1.0
        } else {
            j.progress.map_or(0.0, |p| p.fraction.clamp(0.0, 1.0))
        }
    };
    let progress = if jobs.is_empty() {
        0.0
    } else {
        jobs.iter().map(fraction).sum::<f64>() / jobs.len() as f64
    };
    Ok(SweepInfo {
        id: row.id.clone(),
        name: row.name.clone(),
        created_at: row.created_at.clone(),
        priority: row.priority,
        labels: row.labels.clone(),
        parameters: row.parameters.clone(),
        max_concurrent: row.max_concurrent,
        status: sweep::overall_status(&statuses).to_string(),
        total: jobs.len() as u64,
        counts,
        progress,
        scene: full.then(|| row.scene_value()).transpose()?,
        jobs: full
            .then(|| jobs.iter().map(sweep_job).collect())
            .transpose()?,
    })
}

/// One job of a sweep; a job row of a sweep without its place in it is corrupt.
fn sweep_job(j: &JobRow) -> Result<SweepJob, StoreError> {
    let missing = |c: &str| StoreError::Corrupt(format!("sweep job `{}` has no `{c}`", j.id));
    Ok(SweepJob {
        id: j.id.clone(),
        index: j.sweep_index.ok_or_else(|| missing("sweep_index"))?,
        label: j
            .sweep_label
            .clone()
            .ok_or_else(|| missing("sweep_label"))?,
        values: j
            .sweep_values
            .clone()
            .ok_or_else(|| missing("sweep_values"))?,
        name: j.name.clone(),
        status: j.status,
        progress: j.progress,
        started_at: j.started_at.clone(),
        finished_at: j.finished_at.clone(),
        message: j.message.clone(),
        summary: j.summary.clone(),
        cached_from: j.cached_from.clone(),
    })
}

async fn sweep_or_404(st: &AppState, id: &str) -> Result<SweepRow, ApiError> {
    st.store
        .sweep(id)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("no sweep with id `{id}`")))
}

fn invalid_sweep(mut details: Vec<ErrorDetail>, message: String) -> ApiError {
    let extra = details.len().saturating_sub(MAX_SWEEP_DETAILS);
    details.truncate(MAX_SWEEP_DETAILS);
    if extra > 0 {
        details.push(ErrorDetail {
            path: "parameters".into(),
            message: format!("… and {extra} more problems"),
        });
    }
    ApiError::InvalidSweep { message, details }
}

/// A validator field path in dot form (`cracks[0].propagation` → `cracks.0.propagation`:
/// deserialization errors use brackets, the checks dots).
fn dotted(path: &str) -> String {
    path.replace("].", ".").replace('[', ".").replace(']', "")
}

/// The parameter of a sweep a field path belongs to: the longest parameter path equal to
/// it, below it, or above it (an unknown key a parameter added is reported at its parent).
fn responsible<'a>(params: &'a [SweepParameter], field: &str) -> Option<(usize, &'a str)> {
    let field = dotted(field);
    let field = field.as_str();
    params
        .iter()
        .enumerate()
        .filter(|(_, p)| {
            field == p.path
                || field.starts_with(&format!("{}.", p.path))
                || p.path.starts_with(&format!("{field}."))
        })
        .max_by_key(|(_, p)| p.path.len())
        .map(|(i, p)| (i, p.path.as_str()))
}

/// What every job of a sweep shares.
struct SweepBase<'a> {
    scene: &'a serde_json::Value,
    params: &'a [SweepParameter],
    limits: &'a Limits,
    sweep_id: &'a str,
    name: &'a str,
    priority: i64,
    labels: &'a BTreeMap<String, String>,
}

/// Every job of a sweep: each combination built from the base scene and admitted
/// ([`Limits::admit_any`], 2D or 3D: the cheap limits, validation, the exact limits). Any invalid
/// combination refuses the whole sweep with one detail per problem. CPU-bound: run it off
/// the async threads.
fn build_sweep_jobs(b: &SweepBase<'_>) -> Result<Vec<NewSweepJob>, ApiError> {
    let params = b.params;
    let names = sweep::short_names(params);
    let mut jobs = Vec::new();
    let mut problems: Vec<ErrorDetail> = Vec::new();
    let mut first_problem: Option<String> = None;
    for combo in sweep::combinations(params) {
        let label = sweep::label(&names, params, &combo);
        let mut doc = b.scene.clone();
        let mut values = serde_json::Map::new();
        for (p, &i) in params.iter().zip(&combo) {
            let v = p.values.get(i).cloned().unwrap_or(serde_json::Value::Null);
            values.insert(p.path.clone(), v.clone());
            sweep::set_path(&mut doc, &p.path, v)
                .map_err(|e| ApiError::BadRequest(e.to_string()))?;
        }
        let checked = any_scene_from_value(doc)
            .map_err(ApiError::from)
            .and_then(|scene| b.limits.admit_any(&scene).map(|_| scene));
        let scene = match checked {
            Ok(scene) => scene,
            Err(e) => {
                let details = match e {
                    ApiError::InvalidScene(d) | ApiError::LimitExceeded { details: d, .. } => d,
                    other => return Err(other),
                };
                for d in details {
                    let blame = match responsible(params, &d.path) {
                        Some((i, path)) => format!(
                            "parameter `{path}` = {}",
                            params[i]
                                .values
                                .get(combo[i])
                                .map(|v| v.to_string())
                                .unwrap_or_default()
                        ),
                        None => format!("combination `{label}`"),
                    };
                    let message = format!("with {blame} ({label}): {}", d.message);
                    if first_problem.is_none() {
                        first_problem = Some(format!(
                            "the sweep's combination `{label}` is not a valid scene: {blame}: {}: {}",
                            d.path, d.message
                        ));
                    }
                    problems.push(ErrorDetail {
                        path: d.path,
                        message,
                    });
                }
                continue;
            }
        };
        let mut labels = b.labels.clone();
        labels.insert("sweep".into(), b.sweep_id.to_string());
        for (n, (p, &i)) in names.iter().zip(params.iter().zip(&combo)) {
            labels.insert(
                n.clone(),
                p.values.get(i).map(sweep::value_text).unwrap_or_default(),
            );
        }
        jobs.push(NewSweepJob {
            job: NewJob {
                id: new_job_id(),
                name: format!("{} ({label})", b.name),
                scene: scene.canonical_json(),
                end_time: scene.end_time(),
                priority: b.priority,
                labels,
                rerun_of: None,
                scene_hash: scene.hash(),
                use_cache: true,
                max_attempts: None,
            },
            label,
            values: serde_json::Value::Object(values).to_string(),
        });
    }
    if let Some(message) = first_problem {
        return Err(invalid_sweep(problems, message));
    }
    Ok(jobs)
}

/// The checks of a sweep request that need no scene: parameters present, each with values,
/// the combination count within `max_sweep_jobs`, every path leading into the base scene.
fn check_parameters(req: &SweepRequest, limits: &Limits) -> Result<(), ApiError> {
    let params = &req.parameters.0;
    if params.is_empty() {
        return Err(invalid_sweep(
            vec![ErrorDetail {
                path: "parameters".into(),
                message: "name at least one parameter, e.g. {\"cracks.0.propagation.toughness\": [25, 100]}".into(),
            }],
            "the sweep has no parameters".into(),
        ));
    }
    if let Some(p) = params.iter().find(|p| p.values.is_empty()) {
        return Err(invalid_sweep(
            vec![ErrorDetail {
                path: format!("parameters.{}", p.path),
                message: "the list of values is empty".into(),
            }],
            format!("parameter `{}` has no values", p.path),
        ));
    }
    let count = sweep::combination_count(params);
    let limit = limits.max_sweep_jobs;
    if count > limit {
        let sizes: Vec<String> = params.iter().map(|p| p.values.len().to_string()).collect();
        let message = format!(
            "the sweep has {count} combinations ({}), more than this server's limit max_sweep_jobs = {limit}",
            sizes.join(" × ")
        );
        return Err(ApiError::LimitExceeded {
            details: vec![ErrorDetail {
                path: "parameters".into(),
                message: message.clone(),
            }],
            message,
        });
    }
    let path_errors: Vec<ErrorDetail> = params
        .iter()
        .filter_map(|p| {
            let mut probe = req.scene.clone();
            let v = p.values.first().cloned().unwrap_or(serde_json::Value::Null);
            sweep::set_path(&mut probe, &p.path, v).err()
        })
        .map(|e| ErrorDetail {
            path: format!("parameters.{}", e.path),
            message: e.reason,
        })
        .collect();
    if let Some(first) = path_errors.first() {
        let message = format!("{}: {}", first.path, first.message);
        return Err(invalid_sweep(path_errors, message));
    }
    if !req.scene.is_object() {
        return Err(invalid_sweep(
            vec![ErrorDetail {
                path: "scene".into(),
                message: "the base scene must be a JSON object".into(),
            }],
            "the base scene must be a JSON object".into(),
        ));
    }
    Ok(())
}

/// Create a sweep: one job per combination of the parameter values (every combination is
/// validated before any job is queued).
#[utoipa::path(post, path = "/api/v1/sweeps", tag = "sweeps",
    request_body(content = Object, description = "`{\"scene\": {...}, \"parameters\": {\"cracks.0.propagation.toughness\": [25, 100, 250], ...}, \"name\": \"...\", \"priority\": 0, \"labels\": {...}}` \
        (the scene's JSON Schema: `fracture schema`; parameters keep the order written)",
        content_type = "application/json"),
    responses(
        (status = 201, description = "The sweep with its queued jobs", body = SweepInfo),
        (status = 400, description = "Malformed JSON", body = ErrorBody),
        (status = 401, description = "Missing or wrong API token", body = ErrorBody),
        (status = 413, description = "Body too large", body = ErrorBody),
        (status = 422, description = "`invalid_sweep` (a path or a combination is not valid; details name the field path, the message the parameter and value) or `limit_exceeded` (too many combinations, or a combination over a scene limit)", body = ErrorBody),
        (status = 503, description = "The server is shutting down", body = ErrorBody)),
    security(("bearer" = [])))]
pub(super) async fn create_sweep(
    State(st): State<AppState>,
    _: ApiToken,
    JsonBody(body): JsonBody,
) -> Result<(StatusCode, HeaderMap, Json<SweepInfo>), ApiError> {
    if st.shutting_down() {
        return Err(ApiError::Unavailable);
    }
    // Malformed JSON is a 400; the typed parse reads the text again so that the
    // parameters keep the client's order (`serde_json::Value` sorts object keys).
    let _: serde_json::Value = parse_json(&body)?;
    let mut de = serde_json::Deserializer::from_slice(&body);
    let req: SweepRequest = serde_path_to_error::deserialize(&mut de).map_err(|e| {
        let path = e.path().to_string();
        let msg = e.into_inner().to_string();
        invalid_sweep(
            vec![ErrorDetail {
                path: path.clone(),
                message: msg.clone(),
            }],
            format!("the sweep request is not valid: {path}: {msg}"),
        )
    })?;
    st.cfg
        .limits
        .check_names(req.name.as_deref(), &req.labels)?;
    check_parameters(&req, &st.cfg.limits)?;
    if req.max_concurrent == Some(0) {
        return Err(invalid_sweep(
            vec![ErrorDetail {
                path: "max_concurrent".into(),
                message: "0 must be at least 1 (leave it out for no limit)".into(),
            }],
            "the sweep request is not valid: max_concurrent: 0 must be at least 1".into(),
        ));
    }
    if req.max_attempts == Some(0) {
        return Err(invalid_sweep(
            vec![ErrorDetail {
                path: "max_attempts".into(),
                message: "0 must be at least 1 (leave it out for the server's --max-attempts)"
                    .into(),
            }],
            "the sweep request is not valid: max_attempts: 0 must be at least 1".into(),
        ));
    }
    // Build and admit every combination before storing anything.
    let sweep_id = new_job_id();
    let base_name = req
        .scene
        .get("name")
        .and_then(|n| n.as_str())
        .unwrap_or("untitled")
        .to_string();
    let (req, jobs) = {
        let limits = st.cfg.limits.clone();
        let (sweep_id, base_name) = (sweep_id.clone(), base_name.clone());
        blocking(move || {
            let jobs = build_sweep_jobs(&SweepBase {
                scene: &req.scene,
                params: &req.parameters.0,
                limits: &limits,
                sweep_id: &sweep_id,
                name: &base_name,
                priority: req.priority,
                labels: &req.labels,
            })?;
            Ok((req, jobs))
        })
        .await?
    };
    let use_cache = req.cache == CacheMode::Reuse;
    let jobs: Vec<NewSweepJob> = jobs
        .into_iter()
        .map(|mut j| {
            j.job.use_cache = use_cache;
            j.job.max_attempts = req.max_attempts;
            j
        })
        .collect();
    let new = NewSweep {
        id: sweep_id,
        name: req
            .name
            .filter(|n| !n.trim().is_empty())
            .unwrap_or(base_name),
        scene: req.scene.to_string(),
        parameters: req.parameters.0,
        priority: req.priority,
        labels: req.labels,
        max_concurrent: req.max_concurrent,
    };
    let row = st.store.create_sweep(&new, &jobs).await?;
    st.queue_changed.notify_waiters();
    let stored = st.store.sweep_jobs(&row.id).await?;
    tracing::info!(sweep = %row.id, jobs = stored.len(), "sweep created");
    let h = location(&format!("/api/v1/sweeps/{}", row.id));
    Ok((
        StatusCode::CREATED,
        h,
        Json(sweep_info(&row, &stored, true)?),
    ))
}

/// Query of `GET /api/v1/sweeps`.
#[derive(Debug, Deserialize, utoipa::IntoParams)]
#[serde(deny_unknown_fields)]
pub(super) struct SweepListQuery {
    /// Page size (default 50, at most 500).
    limit: Option<i64>,
    /// The `X-Next-Cursor` of the previous page.
    cursor: Option<String>,
}

/// Sweeps, newest first, with their job counts and progress (next page: the
/// `X-Next-Cursor` response header).
#[utoipa::path(get, path = "/api/v1/sweeps", tag = "sweeps", params(SweepListQuery),
    responses((status = 200, description = "Sweeps without scene and jobs", body = Vec<SweepInfo>),
        (status = 400, description = "Bad parameter", body = ErrorBody)))]
pub(super) async fn list_sweeps(
    State(st): State<AppState>,
    ApiQuery(q): ApiQuery<SweepListQuery>,
) -> Result<Response, ApiError> {
    let limit = page_limit(q.limit)?;
    let before = page_cursor(q.cursor.as_deref())?;
    let rows = st.store.sweeps(limit, before).await?;
    let mut out = Vec::with_capacity(rows.len());
    for r in &rows {
        let jobs = st.store.sweep_jobs(&r.id).await?;
        out.push(sweep_info(r, &jobs, false)?);
    }
    Ok(page(out, limit, rows.last().map(|r| r.seq)))
}

/// One sweep with its base scene and every job's id, parameter values, label, status and
/// progress.
#[utoipa::path(get, path = "/api/v1/sweeps/{id}", tag = "sweeps",
    params(("id" = String, Path, description = "Sweep id")),
    responses((status = 200, description = "The sweep", body = SweepInfo),
        (status = 404, description = "Unknown id", body = ErrorBody)))]
pub(super) async fn get_sweep(
    State(st): State<AppState>,
    Path(id): Path<String>,
) -> Result<Json<SweepInfo>, ApiError> {
    let row = sweep_or_404(&st, &id).await?;
    let jobs = st.store.sweep_jobs(&id).await?;
    Ok(Json(sweep_info(&row, &jobs, true)?))
}

/// Cancel every unfinished job of a sweep (queued at once, running within a second or two).
#[utoipa::path(post, path = "/api/v1/sweeps/{id}/cancel", tag = "sweeps",
    params(("id" = String, Path, description = "Sweep id")),
    responses((status = 200, description = "The sweep after the request", body = SweepInfo),
        (status = 401, description = "Missing or wrong API token", body = ErrorBody),
        (status = 404, description = "Unknown id", body = ErrorBody)),
    security(("bearer" = [])))]
pub(super) async fn cancel_sweep(
    State(st): State<AppState>,
    _: ApiToken,
    Path(id): Path<String>,
) -> Result<Json<SweepInfo>, ApiError> {
    let row = sweep_or_404(&st, &id).await?;
    for job in st.store.sweep_jobs(&id).await? {
        if job.status.is_terminal() {
            continue;
        }
        if let Some(after) = st.store.cancel(&job.id).await?
            && after.status != job.status
        {
            st.announce(&after);
        }
    }
    let jobs = st.store.sweep_jobs(&id).await?;
    Ok(Json(sweep_info(&row, &jobs, true)?))
}

/// Delete a finished sweep with its jobs and their files (409 while a job is unfinished).
#[utoipa::path(delete, path = "/api/v1/sweeps/{id}", tag = "sweeps",
    params(("id" = String, Path, description = "Sweep id")),
    responses((status = 204, description = "Deleted"),
        (status = 401, description = "Missing or wrong API token", body = ErrorBody),
        (status = 404, description = "Unknown id", body = ErrorBody),
        (status = 409, description = "A job of the sweep has not finished", body = ErrorBody)),
    security(("bearer" = [])))]
pub(super) async fn delete_sweep(
    State(st): State<AppState>,
    _: ApiToken,
    Path(id): Path<String>,
) -> Result<StatusCode, ApiError> {
    sweep_or_404(&st, &id).await?;
    let jobs = st.store.sweep_jobs(&id).await?;
    if let Some(j) = jobs.iter().find(|j| !j.status.is_terminal()) {
        return Err(ApiError::Conflict(format!(
            "job `{}` of sweep `{id}` is {}; cancel the sweep first",
            j.id,
            j.status.as_str()
        )));
    }
    // The sweep and its jobs go in one transaction; their folders after it committed (a
    // folder that cannot be removed now is removed at the next start).
    let ids = st.store.delete_sweep(&id).await?;
    let files = st.files.clone();
    blocking(move || {
        for jid in ids {
            if let Err(e) = files.delete(&jid) {
                tracing::warn!(job = %jid, error = %e, "cannot remove the results folder; removed at the next start");
            }
        }
        Ok(())
    })
    .await?;
    Ok(StatusCode::NO_CONTENT)
}
