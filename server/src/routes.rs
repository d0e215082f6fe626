//! The HTTP API (`api.md`): public routes, worker routes, OpenAPI, docs and the dashboard.

use std::collections::BTreeMap;
use std::convert::Infallible;
use std::time::Duration;

use axum::extract::{DefaultBodyLimit, Path, Query, State};
use axum::http::{HeaderMap, HeaderValue, StatusCode, Uri, header};
use axum::response::sse::{Event, KeepAlive, Sse};
use axum::response::{IntoResponse, Response};
use axum::{Extension, Json, Router};
use fracture_api::jobs::{
    ErrorBody, HealthInfo, JobInfo, JobRequest, JobStatus, SceneEntry, SnapshotInfo,
    ValidateResponse,
};
use fracture_api::results::{CRACK_TIPS_CSV_HEADER, CrackTipRow, ENERGY_CSV_HEADER, EnergyRow};
use fracture_api::{Scene, validate};
use futures::Stream;
use serde::Deserialize;
use tokio::sync::broadcast::error::RecvError;
use utoipa::OpenApi;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;
use utoipa_swagger_ui::SwaggerUi;

use crate::error::{ApiError, ApiJson, BodyLimit, RawBody, parse_json};
use crate::events::JobEvent;
use crate::files::Record;
use crate::server::{AppState, new_job_id};
use crate::store::{JobRow, ListFilter, NewJob, NewSweep, NewSweepJob, StoreError, SweepRow};
use fracture_api::protocol::{
    Claim, ClaimRequest, CrackTipBatch, EnergyBatch, FinishRequest, Heartbeat, HeartbeatReply,
};
use fracture_api::sweep::{self, SweepInfo, SweepJob, SweepParameter, SweepRequest};
use fracture_results::codec;
use fracture_results::render;

impl From<StoreError> for ApiError {
    fn from(e: StoreError) -> Self {
        match e {
            StoreError::Fenced => ApiError::Conflict(e.to_string()),
            StoreError::Db(d) => ApiError::Database(d),
            other => ApiError::internal(other),
        }
    }
}

#[derive(OpenApi)]
#[openapi(
    info(
        title = "mpm-fracture",
        description = "Dynamic fracture with the material point method: submit scenes, follow \
                       runs, read crack-tip histories, energies and field snapshots."
    ),
    tags(
        (name = "jobs", description = "Submit and follow simulation jobs"),
        (name = "sweeps", description = "Parameter sweeps: one job per combination of values"),
        (name = "results", description = "What a run produced"),
        (name = "scenes", description = "Example scenes and validation"),
        (name = "service", description = "Health"),
        (name = "worker", description = "Worker protocol (worker token)")
    ),
    components(schemas(ErrorDoc, SweepInfo, SweepJob, SweepParameter)),
    modifiers(&BearerAuth)
)]
struct ApiDoc;

/// Declares the `bearer` security scheme the token-protected routes name.
struct BearerAuth;

impl utoipa::Modify for BearerAuth {
    fn modify(&self, openapi: &mut utoipa::openapi::OpenApi) {
        use utoipa::openapi::security::{Http, HttpAuthScheme, SecurityScheme};
        let components = openapi.components.get_or_insert_with(Default::default);
        components.add_security_scheme(
            "bearer",
            SecurityScheme::Http(Http::new(HttpAuthScheme::Bearer)),
        );
    }
}

/// The error body (`{"error","message","details"}`).
#[derive(utoipa::ToSchema)]
#[allow(dead_code)]
struct ErrorDoc {
    /// Kind, e.g. `invalid_scene`, `not_found`, `unauthorized`.
    error: String,
    /// Explanation.
    message: String,
    /// Per-field problems: `[{"path", "message"}]`.
    details: Vec<serde_json::Value>,
}

/// The router of the whole service over `state`.
pub fn app(state: AppState) -> Router {
    let limits = state.cfg.limits.clone();
    let public = OpenApiRouter::with_openapi(ApiDoc::openapi())
        .routes(routes!(health))
        .routes(routes!(list_scenes))
        .routes(routes!(validate_scene))
        .routes(routes!(create_job, list_jobs))
        .routes(routes!(get_job, delete_job))
        .routes(routes!(cancel_job))
        .routes(routes!(get_crack_tips))
        .routes(routes!(get_energy))
        .routes(routes!(list_snapshots))
        .routes(routes!(snapshot_png))
        .routes(routes!(fields_mcap))
        .routes(routes!(job_events))
        .routes(routes!(create_sweep, list_sweeps))
        .routes(routes!(get_sweep, delete_sweep))
        .routes(routes!(cancel_sweep))
        .layer(DefaultBodyLimit::max(limits.max_body_bytes))
        .layer(Extension(BodyLimit(limits.max_body_bytes)));
    let worker = OpenApiRouter::new()
        .routes(routes!(worker_claim))
        .routes(routes!(worker_heartbeat))
        .routes(routes!(worker_energy))
        .routes(routes!(worker_crack_tips))
        .routes(routes!(worker_snapshot))
        .routes(routes!(worker_finish))
        .layer(DefaultBodyLimit::max(limits.max_worker_body_bytes))
        .layer(Extension(BodyLimit(limits.max_worker_body_bytes)));
    let (router, api) = public.merge(worker).split_for_parts();
    router
        .merge(SwaggerUi::new("/api/v1/docs").url("/api/v1/openapi.json", api))
        .fallback(static_files)
        .layer(tower_http::trace::TraceLayer::new_for_http())
        .layer(tower_http::compression::CompressionLayer::new())
        .with_state(state)
}

// ---------------------------------------------------------------------------------------
// Auth

fn bearer(headers: &HeaderMap) -> Option<&str> {
    headers
        .get(header::AUTHORIZATION)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| {
            v.strip_prefix("Bearer ")
                .or_else(|| v.strip_prefix("bearer "))
        })
        .map(str::trim)
}

fn same(a: &str, b: &str) -> bool {
    // Length leaks, content does not: compare every byte.
    a.len() == b.len()
        && a.bytes()
            .zip(b.bytes())
            .fold(0u8, |acc, (x, y)| acc | (x ^ y))
            == 0
}

fn require_api_token(st: &AppState, headers: &HeaderMap) -> Result<(), ApiError> {
    match &st.cfg.api_token {
        None => Ok(()),
        Some(t) => match bearer(headers) {
            Some(given) if same(given, t) => Ok(()),
            Some(_) => Err(ApiError::Unauthorized("wrong API token".into())),
            None => Err(ApiError::Unauthorized(
                "this server requires an API token: send `Authorization: Bearer <token>`".into(),
            )),
        },
    }
}

fn require_worker_token(st: &AppState, headers: &HeaderMap) -> Result<(), ApiError> {
    match bearer(headers) {
        Some(given) if same(given, &st.cfg.worker_token) => Ok(()),
        Some(_) => Err(ApiError::Unauthorized("wrong worker token".into())),
        None => Err(ApiError::Unauthorized(
            "worker routes need `Authorization: Bearer <worker token>`".into(),
        )),
    }
}

async fn job_or_404(st: &AppState, id: &str) -> Result<crate::store::JobRow, ApiError> {
    st.store
        .get(id)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("no job with id `{id}`")))
}

// ---------------------------------------------------------------------------------------
// Service and scenes

/// Health of the service.
#[utoipa::path(get, path = "/api/v1/health", tag = "service",
    responses((status = 200, description = "`{status, workers, queued, running}`", body = Object)))]
async fn health(State(st): State<AppState>) -> Result<Json<HealthInfo>, ApiError> {
    let (queued, running) = st.store.counts().await?;
    Ok(Json(HealthInfo {
        status: "ok".into(),
        workers: st.cfg.local_workers as u64,
        queued,
        running,
    }))
}

/// The built-in example scenes.
#[utoipa::path(get, path = "/api/v1/scenes", tag = "scenes",
    responses((status = 200, description = "`[{name, description, scene}]`", body = Vec<Object>)))]
async fn list_scenes() -> Json<Vec<SceneEntry>> {
    Json(crate::assets::scenes())
}

fn check_scene(st: &AppState, scene: &Scene) -> Result<fracture_api::RunSize, ApiError> {
    let size = validate::validate(scene)?;
    st.cfg.limits.check(scene, &size)?;
    Ok(size)
}

/// Validate a scene and report the size of its run.
#[utoipa::path(post, path = "/api/v1/scenes/validate", tag = "scenes",
    request_body(content = Object, description = "A scene", content_type = "application/json"),
    responses(
        (status = 200, description = "`{valid, particles, grid_nodes, time_step, steps}`", body = Object),
        (status = 400, description = "Malformed JSON", body = ErrorDoc),
        (status = 413, description = "Body too large", body = ErrorDoc),
        (status = 422, description = "Invalid scene or over a limit", body = ErrorDoc)))]
async fn validate_scene(
    State(st): State<AppState>,
    RawBody(body): RawBody,
) -> Result<Json<ValidateResponse>, ApiError> {
    let value: serde_json::Value = parse_json(&body)?;
    let scene = validate::scene_from_value(value)?;
    let size = check_scene(&st, &scene)?;
    Ok(Json(ValidateResponse {
        valid: true,
        particles: size.particles,
        grid_nodes: size.grid_nodes,
        time_step: size.time_step,
        steps: size.steps,
    }))
}

// ---------------------------------------------------------------------------------------
// Jobs

fn parse_job_request(value: serde_json::Value) -> Result<JobRequest, ApiError> {
    let wrapped = value
        .as_object()
        .is_some_and(|o| o.contains_key("scene") && !o.contains_key("grid"));
    if wrapped {
        serde_path_to_error::deserialize::<_, JobRequest>(value).map_err(|e| {
            // Paths are relative to the scene document in both request forms.
            let path = e.path().to_string();
            let path = match path.strip_prefix("scene.") {
                Some(p) => p.to_string(),
                None if path == "." => "(document)".to_string(),
                None => path,
            };
            ApiError::InvalidScene(vec![fracture_api::jobs::ErrorDetail {
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
    request_body(content = Object, description = "A scene, or `{\"scene\": {...}, \"priority\": 0, \"labels\": {...}}`",
        content_type = "application/json"),
    responses(
        (status = 201, description = "The job, queued", body = Object),
        (status = 400, description = "Malformed JSON", body = ErrorDoc),
        (status = 401, description = "Missing or wrong API token", body = ErrorDoc),
        (status = 413, description = "Body too large", body = ErrorDoc),
        (status = 422, description = "Invalid scene or over a limit", body = ErrorDoc)),
    security(("bearer" = [])))]
async fn create_job(
    State(st): State<AppState>,
    headers: HeaderMap,
    RawBody(body): RawBody,
) -> Result<(StatusCode, HeaderMap, Json<JobInfo>), ApiError> {
    require_api_token(&st, &headers)?;
    if st.shutting_down() {
        return Err(ApiError::Unavailable);
    }
    let value: serde_json::Value = parse_json(&body)?;
    let req = parse_job_request(value)?;
    check_scene(&st, &req.scene)?;
    let job = NewJob {
        id: new_job_id(),
        name: req.scene.name.clone(),
        scene: req.scene.canonical_json(),
        end_time: req.scene.time.end,
        priority: req.priority,
        labels: req.labels,
    };
    let row = st.store.create_job(&job).await?;
    st.queue_changed.notify_waiters();
    let mut h = HeaderMap::new();
    if let Ok(v) = HeaderValue::from_str(&format!("/api/v1/jobs/{}", row.id)) {
        h.insert(header::LOCATION, v);
    }
    Ok((StatusCode::CREATED, h, Json(row.info(true))))
}

/// Query of `GET /api/v1/jobs`.
#[derive(Debug, Deserialize, utoipa::IntoParams)]
struct ListQuery {
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
    responses((status = 200, description = "Jobs without their scenes", body = Vec<Object>),
        (status = 400, description = "Bad parameter", body = ErrorDoc)))]
async fn list_jobs(
    State(st): State<AppState>,
    Query(q): Query<ListQuery>,
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
    let limit = q.limit.unwrap_or(50);
    if !(1..=500).contains(&limit) {
        return Err(ApiError::BadRequest("limit must be in 1..=500".into()));
    }
    let before_seq = match q.cursor.as_deref() {
        None | Some("") => None,
        Some(c) => Some(
            c.parse::<i64>()
                .map_err(|_| ApiError::BadRequest(format!("bad cursor `{c}`")))?,
        ),
    };
    let rows = st
        .store
        .list(&ListFilter {
            status,
            label,
            limit,
            before_seq,
        })
        .await?;
    let next = (rows.len() as i64 == limit)
        .then(|| rows.last().map(|r| r.seq))
        .flatten();
    let jobs: Vec<JobInfo> = rows.iter().map(|r| r.info(false)).collect();
    let mut resp = Json(jobs).into_response();
    if let Some(n) = next
        && let Ok(v) = HeaderValue::from_str(&n.to_string())
    {
        resp.headers_mut().insert("x-next-cursor", v);
    }
    Ok(resp)
}

/// One job with its scene, progress and summary.
#[utoipa::path(get, path = "/api/v1/jobs/{id}", tag = "jobs",
    params(("id" = String, Path, description = "Job id")),
    responses((status = 200, description = "The job", body = Object),
        (status = 404, description = "Unknown id", body = ErrorDoc)))]
async fn get_job(
    State(st): State<AppState>,
    Path(id): Path<String>,
) -> Result<Json<serde_json::Value>, ApiError> {
    let job = job_or_404(&st, &id).await?;
    let mut v = serde_json::to_value(job.info(true)).map_err(ApiError::internal)?;
    if let Some(o) = v.as_object_mut() {
        // Extension of api.md: which worker holds the lease (null when none).
        o.insert("worker".into(), job.worker_id.clone().into());
    }
    Ok(Json(v))
}

/// Cancel a job: a queued job at once, a running one within a second or two.
#[utoipa::path(post, path = "/api/v1/jobs/{id}/cancel", tag = "jobs",
    params(("id" = String, Path, description = "Job id")),
    responses((status = 200, description = "The job after the request", body = Object),
        (status = 401, description = "Missing or wrong API token", body = ErrorDoc),
        (status = 404, description = "Unknown id", body = ErrorDoc)),
    security(("bearer" = [])))]
async fn cancel_job(
    State(st): State<AppState>,
    headers: HeaderMap,
    Path(id): Path<String>,
) -> Result<Json<JobInfo>, ApiError> {
    require_api_token(&st, &headers)?;
    let before = job_or_404(&st, &id).await?;
    let after = st
        .store
        .cancel(&id)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("no job with id `{id}`")))?;
    if before.status != after.status {
        st.announce(&after);
    }
    Ok(Json(after.info(false)))
}

/// Delete a finished job and its files.
#[utoipa::path(delete, path = "/api/v1/jobs/{id}", tag = "jobs",
    params(("id" = String, Path, description = "Job id")),
    responses((status = 204, description = "Deleted"),
        (status = 401, description = "Missing or wrong API token", body = ErrorDoc),
        (status = 404, description = "Unknown id", body = ErrorDoc),
        (status = 409, description = "The job has not finished", body = ErrorDoc)),
    security(("bearer" = [])))]
async fn delete_job(
    State(st): State<AppState>,
    headers: HeaderMap,
    Path(id): Path<String>,
) -> Result<StatusCode, ApiError> {
    require_api_token(&st, &headers)?;
    let job = job_or_404(&st, &id).await?;
    if !job.status().is_terminal() {
        return Err(ApiError::Conflict(format!(
            "job `{id}` is {}; cancel it first",
            job.status
        )));
    }
    if !st.store.delete(&id).await? {
        return Err(ApiError::Conflict(format!(
            "job `{id}` could not be deleted"
        )));
    }
    let files = st.files.clone();
    let id2 = id.clone();
    tokio::task::spawn_blocking(move || files.delete(&id2))
        .await
        .map_err(ApiError::internal)?
        .map_err(ApiError::internal)?;
    Ok(StatusCode::NO_CONTENT)
}

/// Query of the history routes.
#[derive(Debug, Deserialize, utoipa::IntoParams)]
struct SinceQuery {
    /// Only rows with `time` greater than this (s).
    since: Option<f64>,
}

fn wants_csv(headers: &HeaderMap) -> bool {
    headers
        .get(header::ACCEPT)
        .and_then(|v| v.to_str().ok())
        .is_some_and(|a| a.contains("text/csv"))
}

fn csv_response(header_line: &str, lines: impl Iterator<Item = String>) -> Response {
    let mut body = String::from(header_line);
    body.push('\n');
    for l in lines {
        body.push_str(&l);
        body.push('\n');
    }
    ([(header::CONTENT_TYPE, "text/csv; charset=utf-8")], body).into_response()
}

/// Crack-tip history (`crack_tips.csv` rows), JSON or CSV (`Accept: text/csv`).
#[utoipa::path(get, path = "/api/v1/jobs/{id}/crack-tips", tag = "results",
    params(("id" = String, Path, description = "Job id"), SinceQuery),
    responses((status = 200, description = "`[{time, crack, tip, x, y, length, speed, j1, j2, k1, k2, growing}]`", body = Vec<Object>),
        (status = 404, description = "Unknown id", body = ErrorDoc)))]
async fn get_crack_tips(
    State(st): State<AppState>,
    Path(id): Path<String>,
    Query(q): Query<SinceQuery>,
    headers: HeaderMap,
) -> Result<Response, ApiError> {
    job_or_404(&st, &id).await?;
    let rows = st.store.crack_tips(&id, q.since).await?;
    if wants_csv(&headers) {
        Ok(csv_response(
            CRACK_TIPS_CSV_HEADER,
            rows.iter().map(CrackTipRow::to_csv),
        ))
    } else {
        Ok(Json(rows).into_response())
    }
}

/// Energy history (`energy.csv` rows), JSON or CSV (`Accept: text/csv`).
#[utoipa::path(get, path = "/api/v1/jobs/{id}/energy", tag = "results",
    params(("id" = String, Path, description = "Job id"), SinceQuery),
    responses((status = 200, description = "`[{time, kinetic, strain, external_work, dissipated, total_error}]`", body = Vec<Object>),
        (status = 404, description = "Unknown id", body = ErrorDoc)))]
async fn get_energy(
    State(st): State<AppState>,
    Path(id): Path<String>,
    Query(q): Query<SinceQuery>,
    headers: HeaderMap,
) -> Result<Response, ApiError> {
    job_or_404(&st, &id).await?;
    let rows = st.store.energy(&id, q.since).await?;
    if wants_csv(&headers) {
        Ok(csv_response(
            ENERGY_CSV_HEADER,
            rows.iter().map(EnergyRow::to_csv),
        ))
    } else {
        Ok(Json(rows).into_response())
    }
}

/// The job's field snapshots so far.
#[utoipa::path(get, path = "/api/v1/jobs/{id}/snapshots", tag = "results",
    params(("id" = String, Path, description = "Job id")),
    responses((status = 200, description = "`[{index, time, fields, components}]`", body = Vec<Object>),
        (status = 404, description = "Unknown id", body = ErrorDoc)))]
async fn list_snapshots(
    State(st): State<AppState>,
    Path(id): Path<String>,
) -> Result<Json<Vec<SnapshotInfo>>, ApiError> {
    job_or_404(&st, &id).await?;
    Ok(Json(st.store.snapshots(&id).await?))
}

/// A snapshot field as a PNG: `{field}` is a component (`sxx`, `vx`, `speed`, `fringe`, …)
/// or a field kind (`stress`, `velocity`, …) for its default component.
#[utoipa::path(get, path = "/api/v1/jobs/{id}/snapshots/{index}/{file}", tag = "results",
    params(("id" = String, Path, description = "Job id"),
        ("index" = u32, Path, description = "Snapshot index"),
        ("file" = String, Path, description = "`{field}.png`")),
    responses((status = 200, description = "The image", content_type = "image/png"),
        (status = 404, description = "Unknown job, snapshot or field", body = ErrorDoc)))]
async fn snapshot_png(
    State(st): State<AppState>,
    Path((id, index, file)): Path<(String, String, String)>,
) -> Result<Response, ApiError> {
    let field = file
        .strip_suffix(".png")
        .ok_or_else(|| ApiError::NotFound(format!("`{file}`: only `{{field}}.png` is served")))?
        .to_string();
    let index: u32 = index
        .parse()
        .map_err(|_| ApiError::NotFound(format!("no snapshot `{index}`")))?;
    job_or_404(&st, &id).await?;
    let snap = st
        .store
        .snapshot(&id, index)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("job `{id}` has no snapshot {index}")))?;
    let png = tokio::task::spawn_blocking(move || render::render_png(&snap, &field))
        .await
        .map_err(ApiError::internal)?
        .map_err(|e| match e {
            render::RenderError::UnknownField(_) => ApiError::NotFound(e.to_string()),
            other => ApiError::internal(other),
        })?;
    Ok(([(header::CONTENT_TYPE, "image/png")], png).into_response())
}

/// The job's MCAP file (while running: what has been written so far).
#[utoipa::path(get, path = "/api/v1/jobs/{id}/fields.mcap", tag = "results",
    params(("id" = String, Path, description = "Job id")),
    responses((status = 200, description = "MCAP", content_type = "application/octet-stream"),
        (status = 404, description = "Unknown id, or no file yet", body = ErrorDoc)))]
async fn fields_mcap(
    State(st): State<AppState>,
    Path(id): Path<String>,
) -> Result<Response, ApiError> {
    job_or_404(&st, &id).await?;
    let path = st.files.mcap_path(&id);
    match tokio::fs::read(&path).await {
        Ok(bytes) => Ok((
            [
                (header::CONTENT_TYPE, "application/octet-stream".to_string()),
                (
                    header::CONTENT_DISPOSITION,
                    format!("attachment; filename=\"{id}-fields.mcap\""),
                ),
            ],
            bytes,
        )
            .into_response()),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Err(ApiError::NotFound(format!(
            "job `{id}` has no MCAP file yet"
        ))),
        Err(e) => Err(ApiError::internal(e)),
    }
}

fn sse(ev: &JobEvent) -> Event {
    Event::default().event(ev.name()).data(ev.data())
}

/// Server-Sent Events of a job: `progress`, `energy`, `crack_tip`, `snapshot`, `status`.
/// A subscriber first gets the current `status` (and `progress`); the stream ends after a
/// terminal `status`.
#[utoipa::path(get, path = "/api/v1/jobs/{id}/events", tag = "jobs",
    params(("id" = String, Path, description = "Job id")),
    responses((status = 200, description = "text/event-stream", content_type = "text/event-stream"),
        (status = 404, description = "Unknown id", body = ErrorDoc)))]
async fn job_events(
    State(st): State<AppState>,
    Path(id): Path<String>,
) -> Result<Sse<impl Stream<Item = Result<Event, Infallible>>>, ApiError> {
    job_or_404(&st, &id).await?;
    // Subscribe before reading the state so no change falls between the two.
    let rx = st.hub.subscribe(&id);
    let job = job_or_404(&st, &id).await?;
    // Current state first: progress, then status (so a terminal status stays the last event).
    let mut first = Vec::new();
    if let Some(p) = job.progress() {
        first.push(sse(&JobEvent::Progress(p)));
    }
    first.push(sse(&JobEvent::Status(job.status_event())));
    let done = job.status().is_terminal();
    let shutdown = st.shutdown.clone();
    let live = futures::stream::unfold((rx, shutdown, done), |(mut rx, mut sd, done)| async move {
        if done {
            return None;
        }
        loop {
            let next = tokio::select! {
                r = rx.recv() => Some(r),
                _ = crate::server::until_shutdown(&mut sd) => None,
            };
            match next {
                None | Some(Err(RecvError::Closed)) => return None,
                Some(Err(RecvError::Lagged(_))) => continue,
                Some(Ok(ev)) => {
                    let term = matches!(&ev, JobEvent::Status(s) if s.status.is_terminal());
                    return Some((Ok(sse(&ev)), (rx, sd, term)));
                }
            }
        }
    });
    use futures::StreamExt;
    let stream = futures::stream::iter(first.into_iter().map(Ok)).chain(live);
    Ok(Sse::new(stream).keep_alive(KeepAlive::new().interval(Duration::from_secs(10))))
}

// ---------------------------------------------------------------------------------------
// Sweeps (extension of api.md, see docs/service.md)

/// Details of a sweep error are capped so a large grid of bad values stays readable.
const MAX_SWEEP_DETAILS: usize = 20;

fn sweep_info(row: &SweepRow, jobs: &[JobRow], full: bool) -> SweepInfo {
    let statuses: Vec<JobStatus> = jobs.iter().map(JobRow::status).collect();
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
        if j.status().is_terminal() {
            1.0
        } else {
            j.progress()
                .map(|p| p.fraction.clamp(0.0, 1.0))
                .unwrap_or(0.0)
        }
    };
    let progress = if jobs.is_empty() {
        0.0
    } else {
        jobs.iter().map(fraction).sum::<f64>() / jobs.len() as f64
    };
    SweepInfo {
        id: row.id.clone(),
        name: row.name.clone(),
        created_at: row.created_at.clone(),
        priority: row.priority,
        labels: serde_json::from_str(&row.labels).unwrap_or_default(),
        parameters: serde_json::from_str(&row.parameters).unwrap_or_default(),
        status: sweep::overall_status(&statuses).to_string(),
        total: jobs.len() as u64,
        counts,
        progress,
        scene: if full {
            serde_json::from_str(&row.scene).ok()
        } else {
            None
        },
        jobs: full.then(|| {
            jobs.iter()
                .map(|j| SweepJob {
                    id: j.id.clone(),
                    index: j.sweep_index.unwrap_or(0).max(0) as u32,
                    label: j.sweep_label.clone().unwrap_or_default(),
                    values: j
                        .sweep_values
                        .as_deref()
                        .and_then(|v| serde_json::from_str(v).ok())
                        .unwrap_or_default(),
                    name: j.name.clone(),
                    status: j.status(),
                    progress: j.progress(),
                    started_at: j.started_at.clone(),
                    finished_at: j.finished_at.clone(),
                    message: j.message.clone(),
                    summary: j
                        .summary
                        .as_deref()
                        .and_then(|s| serde_json::from_str(s).ok()),
                })
                .collect()
        }),
    }
}

async fn sweep_or_404(st: &AppState, id: &str) -> Result<SweepRow, ApiError> {
    st.store
        .sweep(id)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("no sweep with id `{id}`")))
}

fn invalid_sweep(mut details: Vec<fracture_api::jobs::ErrorDetail>, message: String) -> ApiError {
    let extra = details.len().saturating_sub(MAX_SWEEP_DETAILS);
    details.truncate(MAX_SWEEP_DETAILS);
    if extra > 0 {
        details.push(fracture_api::jobs::ErrorDetail {
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

/// Every job of a sweep: each combination built from the base scene and validated (scene
/// validation and this server's limits). Any invalid combination refuses the whole sweep
/// with one detail per problem. CPU-bound (validation counts particles): run it off the
/// async threads.
fn build_sweep_jobs(
    scene: &serde_json::Value,
    params: &[SweepParameter],
    limits: &crate::config::Limits,
    sweep_id: &str,
    base_name: &str,
    priority: i64,
    labels: &BTreeMap<String, String>,
) -> Result<Vec<NewSweepJob>, ApiError> {
    use fracture_api::jobs::ErrorDetail;
    let names = sweep::short_names(params);
    let mut jobs = Vec::new();
    let mut problems: Vec<ErrorDetail> = Vec::new();
    let mut first_problem: Option<String> = None;
    for combo in sweep::combinations(params) {
        let label = sweep::label(&names, params, &combo);
        let mut doc = scene.clone();
        let mut values = serde_json::Map::new();
        for (p, &i) in params.iter().zip(&combo) {
            let v = p.values.get(i).cloned().unwrap_or(serde_json::Value::Null);
            values.insert(p.path.clone(), v.clone());
            sweep::set_path(&mut doc, &p.path, v)
                .map_err(|e| ApiError::BadRequest(e.to_string()))?;
        }
        let checked = validate::scene_from_value(doc)
            .map_err(ApiError::from)
            .and_then(|scene| {
                validate::validate(&scene)
                    .map_err(ApiError::from)
                    .and_then(|size| limits.check(&scene, &size))
                    .map(|_| scene)
            });
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
        let mut labels = labels.clone();
        labels.insert("sweep".into(), sweep_id.to_string());
        for (n, (p, &i)) in names.iter().zip(params.iter().zip(&combo)) {
            labels.insert(
                n.clone(),
                p.values.get(i).map(sweep::value_text).unwrap_or_default(),
            );
        }
        jobs.push(NewSweepJob {
            job: NewJob {
                id: new_job_id(),
                name: format!("{base_name} ({label})"),
                scene: scene.canonical_json(),
                end_time: scene.time.end,
                priority,
                labels,
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

/// Create a sweep: one job per combination of the parameter values (every combination is
/// validated before any job is queued).
#[utoipa::path(post, path = "/api/v1/sweeps", tag = "sweeps",
    request_body(content = Object, description = "`{\"scene\": {...}, \"parameters\": {\"cracks.0.propagation.toughness\": [25, 100, 250], ...}, \"name\": \"...\", \"priority\": 0, \"labels\": {...}}`",
        content_type = "application/json"),
    responses(
        (status = 201, description = "The sweep with its queued jobs", body = SweepInfo),
        (status = 400, description = "Malformed JSON", body = ErrorDoc),
        (status = 401, description = "Missing or wrong API token", body = ErrorDoc),
        (status = 413, description = "Body too large", body = ErrorDoc),
        (status = 422, description = "`invalid_sweep` (a path or a combination is not valid; details name the field path, the message the parameter and value) or `limit_exceeded` (too many combinations, or a combination over a scene limit)", body = ErrorDoc)),
    security(("bearer" = [])))]
async fn create_sweep(
    State(st): State<AppState>,
    headers: HeaderMap,
    RawBody(body): RawBody,
) -> Result<(StatusCode, HeaderMap, Json<SweepInfo>), ApiError> {
    use fracture_api::jobs::ErrorDetail;
    require_api_token(&st, &headers)?;
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
    let params = req.parameters.0;
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
    let count = sweep::combination_count(&params);
    let limit = st.cfg.limits.max_sweep_jobs;
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
    // Every path must lead into the base scene.
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
    // Build and validate every combination before storing anything.
    let sweep_id = new_job_id();
    let base_name = req
        .scene
        .get("name")
        .and_then(|n| n.as_str())
        .unwrap_or("untitled")
        .to_string();
    let jobs = {
        let (scene, params, limits) = (req.scene.clone(), params.clone(), st.cfg.limits.clone());
        let (sweep_id, base_name, labels) =
            (sweep_id.clone(), base_name.clone(), req.labels.clone());
        let priority = req.priority;
        tokio::task::spawn_blocking(move || {
            build_sweep_jobs(
                &scene, &params, &limits, &sweep_id, &base_name, priority, &labels,
            )
        })
        .await
        .map_err(ApiError::internal)??
    };
    let new = NewSweep {
        id: sweep_id,
        name: req
            .name
            .filter(|n| !n.trim().is_empty())
            .unwrap_or(base_name),
        scene: req.scene.to_string(),
        parameters: serde_json::to_string(&params).map_err(ApiError::internal)?,
        priority: req.priority,
        labels: req.labels,
    };
    let row = st.store.create_sweep(&new, &jobs).await?;
    st.queue_changed.notify_waiters();
    let stored = st.store.sweep_jobs(&row.id).await?;
    tracing::info!(sweep = %row.id, jobs = stored.len(), "sweep created");
    let mut h = HeaderMap::new();
    if let Ok(v) = HeaderValue::from_str(&format!("/api/v1/sweeps/{}", row.id)) {
        h.insert(header::LOCATION, v);
    }
    Ok((
        StatusCode::CREATED,
        h,
        Json(sweep_info(&row, &stored, true)),
    ))
}

/// Query of `GET /api/v1/sweeps`.
#[derive(Debug, Deserialize, utoipa::IntoParams)]
struct SweepListQuery {
    /// Page size (default 50, at most 500).
    limit: Option<i64>,
    /// The `X-Next-Cursor` of the previous page.
    cursor: Option<String>,
}

/// Sweeps, newest first, with their job counts and progress (next page: the
/// `X-Next-Cursor` response header).
#[utoipa::path(get, path = "/api/v1/sweeps", tag = "sweeps", params(SweepListQuery),
    responses((status = 200, description = "Sweeps without scene and jobs", body = Vec<SweepInfo>),
        (status = 400, description = "Bad parameter", body = ErrorDoc)))]
async fn list_sweeps(
    State(st): State<AppState>,
    Query(q): Query<SweepListQuery>,
) -> Result<Response, ApiError> {
    let limit = q.limit.unwrap_or(50);
    if !(1..=500).contains(&limit) {
        return Err(ApiError::BadRequest("limit must be in 1..=500".into()));
    }
    let before = match q.cursor.as_deref() {
        None | Some("") => None,
        Some(c) => Some(
            c.parse::<i64>()
                .map_err(|_| ApiError::BadRequest(format!("bad cursor `{c}`")))?,
        ),
    };
    let rows = st.store.sweeps(limit, before).await?;
    let mut out = Vec::with_capacity(rows.len());
    for r in &rows {
        let jobs = st.store.sweep_jobs(&r.id).await?;
        out.push(sweep_info(r, &jobs, false));
    }
    let next = (rows.len() as i64 == limit)
        .then(|| rows.last().map(|r| r.seq))
        .flatten();
    let mut resp = Json(out).into_response();
    if let Some(n) = next
        && let Ok(v) = HeaderValue::from_str(&n.to_string())
    {
        resp.headers_mut().insert("x-next-cursor", v);
    }
    Ok(resp)
}

/// One sweep with its base scene and every job's id, parameter values, label, status and
/// progress.
#[utoipa::path(get, path = "/api/v1/sweeps/{id}", tag = "sweeps",
    params(("id" = String, Path, description = "Sweep id")),
    responses((status = 200, description = "The sweep", body = SweepInfo),
        (status = 404, description = "Unknown id", body = ErrorDoc)))]
async fn get_sweep(
    State(st): State<AppState>,
    Path(id): Path<String>,
) -> Result<Json<SweepInfo>, ApiError> {
    let row = sweep_or_404(&st, &id).await?;
    let jobs = st.store.sweep_jobs(&id).await?;
    Ok(Json(sweep_info(&row, &jobs, true)))
}

/// Cancel every unfinished job of a sweep (queued at once, running within a second or two).
#[utoipa::path(post, path = "/api/v1/sweeps/{id}/cancel", tag = "sweeps",
    params(("id" = String, Path, description = "Sweep id")),
    responses((status = 200, description = "The sweep after the request", body = SweepInfo),
        (status = 401, description = "Missing or wrong API token", body = ErrorDoc),
        (status = 404, description = "Unknown id", body = ErrorDoc)),
    security(("bearer" = [])))]
async fn cancel_sweep(
    State(st): State<AppState>,
    headers: HeaderMap,
    Path(id): Path<String>,
) -> Result<Json<SweepInfo>, ApiError> {
    require_api_token(&st, &headers)?;
    let row = sweep_or_404(&st, &id).await?;
    for job in st.store.sweep_jobs(&id).await? {
        if job.status().is_terminal() {
            continue;
        }
        if let Some(after) = st.store.cancel(&job.id).await?
            && after.status != job.status
        {
            st.announce(&after);
        }
    }
    let jobs = st.store.sweep_jobs(&id).await?;
    Ok(Json(sweep_info(&row, &jobs, true)))
}

/// Delete a finished sweep with its jobs and their files (409 while a job is unfinished).
#[utoipa::path(delete, path = "/api/v1/sweeps/{id}", tag = "sweeps",
    params(("id" = String, Path, description = "Sweep id")),
    responses((status = 204, description = "Deleted"),
        (status = 401, description = "Missing or wrong API token", body = ErrorDoc),
        (status = 404, description = "Unknown id", body = ErrorDoc),
        (status = 409, description = "A job of the sweep has not finished", body = ErrorDoc)),
    security(("bearer" = [])))]
async fn delete_sweep(
    State(st): State<AppState>,
    headers: HeaderMap,
    Path(id): Path<String>,
) -> Result<StatusCode, ApiError> {
    require_api_token(&st, &headers)?;
    sweep_or_404(&st, &id).await?;
    let jobs = st.store.sweep_jobs(&id).await?;
    if let Some(j) = jobs.iter().find(|j| !j.status().is_terminal()) {
        return Err(ApiError::Conflict(format!(
            "job `{}` of sweep `{id}` is {}; cancel the sweep first",
            j.id, j.status
        )));
    }
    for j in &jobs {
        if st.store.delete(&j.id).await? {
            let files = st.files.clone();
            let jid = j.id.clone();
            tokio::task::spawn_blocking(move || files.delete(&jid))
                .await
                .map_err(ApiError::internal)?
                .map_err(ApiError::internal)?;
        }
    }
    st.store.delete_sweep(&id).await?;
    Ok(StatusCode::NO_CONTENT)
}

// ---------------------------------------------------------------------------------------
// Worker protocol

/// Claim the best queued job, waiting up to `wait_seconds` (200 with the claim, 204 none).
#[utoipa::path(post, path = "/api/v1/worker/claim", tag = "worker",
    request_body(content = Object, description = "`{worker_id, wait_seconds}`"),
    responses((status = 200, description = "`{job_id, fence, attempt, scene, lease_seconds}`", body = Object),
        (status = 204, description = "No job"),
        (status = 401, description = "Missing or wrong worker token", body = ErrorDoc)))]
async fn worker_claim(
    State(st): State<AppState>,
    headers: HeaderMap,
    ApiJson(req): ApiJson<ClaimRequest>,
) -> Result<Response, ApiError> {
    require_worker_token(&st, &headers)?;
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
            let files = st.files.clone();
            let (jid, fence) = (job.id.clone(), job.fence);
            let scene: Option<Scene> = serde_json::from_str(&job.scene).ok();
            tokio::task::spawn_blocking(move || files.start(&jid, fence, scene.as_ref()))
                .await
                .map_err(ApiError::internal)?
                .map_err(ApiError::internal)?;
            tracing::info!(job = %job.id, worker = %req.worker_id, attempt = job.attempts, "claimed");
            st.announce(&job);
            let scene = serde_json::from_str(&job.scene).map_err(ApiError::internal)?;
            return Ok(Json(Claim {
                job_id: job.id,
                fence: job.fence,
                attempt: job.attempts.max(0) as u32,
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
    request_body(content = Object, description = "`{fence, progress}`"),
    responses((status = 200, description = "`{cancel, lease_seconds}`", body = Object),
        (status = 409, description = "Stale fencing token: drop the job", body = ErrorDoc)))]
async fn worker_heartbeat(
    State(st): State<AppState>,
    headers: HeaderMap,
    Path(id): Path<String>,
    ApiJson(hb): ApiJson<Heartbeat>,
) -> Result<Json<HeartbeatReply>, ApiError> {
    require_worker_token(&st, &headers)?;
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

async fn write_file(st: &AppState, id: &str, fence: i64, rec: Record) -> Result<(), ApiError> {
    let files = st.files.clone();
    let id = id.to_string();
    tokio::task::spawn_blocking(move || files.write(&id, fence, rec))
        .await
        .map_err(ApiError::internal)?
        .map_err(ApiError::internal)
}

/// Append energy rows.
#[utoipa::path(post, path = "/api/v1/worker/jobs/{id}/energy", tag = "worker",
    params(("id" = String, Path, description = "Job id")),
    request_body(content = Object, description = "`{fence, rows}`"),
    responses((status = 204, description = "Stored"),
        (status = 409, description = "Stale fencing token", body = ErrorDoc)))]
async fn worker_energy(
    State(st): State<AppState>,
    headers: HeaderMap,
    Path(id): Path<String>,
    ApiJson(b): ApiJson<EnergyBatch>,
) -> Result<StatusCode, ApiError> {
    require_worker_token(&st, &headers)?;
    let rows: Vec<EnergyRow> = b.rows;
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
    request_body(content = Object, description = "`{fence, rows}`"),
    responses((status = 204, description = "Stored"),
        (status = 409, description = "Stale fencing token", body = ErrorDoc)))]
async fn worker_crack_tips(
    State(st): State<AppState>,
    headers: HeaderMap,
    Path(id): Path<String>,
    ApiJson(b): ApiJson<CrackTipBatch>,
) -> Result<StatusCode, ApiError> {
    require_worker_token(&st, &headers)?;
    let rows: Vec<CrackTipRow> = b.rows;
    st.store
        .append_crack_tips(&id, b.fence, st.cfg.lease, &rows)
        .await?;
    write_file(&st, &id, b.fence, Record::CrackTips(rows.clone())).await?;
    st.hub.send(&id, JobEvent::CrackTips(rows));
    Ok(StatusCode::NO_CONTENT)
}

/// Query of the snapshot upload.
#[derive(Debug, Deserialize, utoipa::IntoParams)]
struct FenceQuery {
    /// Fencing token of the claim.
    fence: i64,
}

/// Upload a snapshot (binary body, see `codec`).
#[utoipa::path(post, path = "/api/v1/worker/jobs/{id}/snapshots", tag = "worker",
    params(("id" = String, Path, description = "Job id"), FenceQuery),
    request_body(content = Vec<u8>, description = "Encoded snapshot", content_type = "application/octet-stream"),
    responses((status = 204, description = "Stored"),
        (status = 409, description = "Stale fencing token", body = ErrorDoc)))]
async fn worker_snapshot(
    State(st): State<AppState>,
    headers: HeaderMap,
    Path(id): Path<String>,
    Query(q): Query<FenceQuery>,
    RawBody(body): RawBody,
) -> Result<StatusCode, ApiError> {
    require_worker_token(&st, &headers)?;
    let snap = codec::decode_snapshot(&body).map_err(|e| ApiError::BadRequest(e.to_string()))?;
    st.store
        .put_snapshot(&id, q.fence, st.cfg.lease, &snap, &body)
        .await?;
    let info = SnapshotInfo {
        index: snap.index,
        time: snap.time,
        fields: snap.fields.clone(),
        components: snap.components.iter().map(|c| c.name.clone()).collect(),
    };
    write_file(&st, &id, q.fence, Record::Snapshot(Box::new(snap))).await?;
    st.hub.send(&id, JobEvent::Snapshot(info));
    Ok(StatusCode::NO_CONTENT)
}

/// Finish the run with its summary.
#[utoipa::path(post, path = "/api/v1/worker/jobs/{id}/finish", tag = "worker",
    params(("id" = String, Path, description = "Job id")),
    request_body(content = Object, description = "`{fence, summary}`"),
    responses((status = 200, description = "The job", body = Object),
        (status = 409, description = "Stale fencing token", body = ErrorDoc)))]
async fn worker_finish(
    State(st): State<AppState>,
    headers: HeaderMap,
    Path(id): Path<String>,
    ApiJson(f): ApiJson<FinishRequest>,
) -> Result<Json<JobInfo>, ApiError> {
    require_worker_token(&st, &headers)?;
    // Close the file first so a client that sees the final status gets a complete MCAP.
    let current = job_or_404(&st, &id).await?;
    if current.fence != f.fence || current.status() != JobStatus::Running {
        return Err(StoreError::Fenced.into());
    }
    let files = st.files.clone();
    let id2 = id.clone();
    tokio::task::spawn_blocking(move || files.finish(&id2))
        .await
        .map_err(ApiError::internal)?
        .map_err(ApiError::internal)?;
    let row = st.store.finish(&id, f.fence, &f.summary).await?;
    tracing::info!(job = %id, status = %row.status, "finished");
    st.announce(&row);
    st.queue_changed.notify_waiters();
    Ok(Json(row.info(false)))
}

// ---------------------------------------------------------------------------------------
// Dashboard

async fn static_files(uri: Uri) -> Response {
    let path = uri.path().trim_start_matches('/');
    if path.starts_with("api/") || path == "api" {
        return ApiError::NotFound(format!("no route {}", uri.path())).into_response();
    }
    let path = if path.is_empty() { "index.html" } else { path };
    let file = crate::assets::Web::get(path).or_else(|| {
        // Client-side routes (no extension) get the dashboard page.
        (!path.contains('.'))
            .then(|| crate::assets::Web::get("index.html"))
            .flatten()
    });
    match file {
        Some(f) => {
            let ct = crate::assets::mime(if path.contains('.') {
                path
            } else {
                "index.html"
            });
            ([(header::CONTENT_TYPE, ct)], f.data.into_owned()).into_response()
        }
        None => {
            let body = ErrorBody {
                error: "not_found".into(),
                message: format!("no page {}", uri.path()),
                details: vec![],
            };
            (StatusCode::NOT_FOUND, Json(body)).into_response()
        }
    }
}
