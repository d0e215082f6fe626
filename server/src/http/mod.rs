//! The HTTP API (`api.md`), one module per resource:
//!
//! * `meta`: health, example scenes, scene validation (and the admission of scenes that
//!   every submitting route shares); [`metrics`]: version and Prometheus metrics;
//! * `jobs`: create, list, get, cancel, delete; `events`: a job's SSE stream;
//! * `results`: crack tips, energy, snapshots, PNG fields, the MCAP file;
//! * `sweeps`: parameter sweeps; `worker`: the worker protocol (claim, heartbeat, batches,
//!   snapshot upload, finish);
//! * [`auth`]: the bearer-token extractors; [`security`]: the `Host` allow-list, the
//!   same-origin rule of state-changing requests and the security headers.
//!
//! This module assembles the router ([`app`]), the OpenAPI document (served at
//! `/api/v1/openapi.json`, Swagger UI at `/api/v1/docs`), the dashboard fallback and the
//! helpers the handlers share.

use axum::extract::DefaultBodyLimit;
use axum::http::{HeaderMap, HeaderValue, StatusCode, Uri, header};
use axum::response::{IntoResponse, Response};
use axum::{Extension, Json, Router};
use fracture_api::jobs::ErrorBody;
use utoipa::OpenApi;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;
use utoipa_swagger_ui::SwaggerUi;

use crate::error::{ApiError, BodyLimit};
use crate::server::AppState;
use crate::store::JobRow;

pub mod auth;
mod checkpoint;
mod events;
mod jobs;
mod meta;
pub mod metrics;
mod results;
pub mod security;
mod sweeps;
mod worker;

pub use meta::NOMINAL_PARTICLE_STEPS_PER_SECOND;

#[derive(OpenApi)]
#[openapi(
    info(
        title = "mpm-fracture",
        description = "Dynamic fracture with the material point method: submit scenes, follow \
                       runs, read crack-tip histories, energies and field snapshots. Scene \
                       bodies are described here as `object`: their JSON Schema is what \
                       `fracture schema` prints."
    ),
    tags(
        (name = "jobs", description = "Submit and follow simulation jobs"),
        (name = "sweeps", description = "Parameter sweeps: one job per combination of values"),
        (name = "results", description = "What a run produced"),
        (name = "scenes", description = "Example scenes and validation"),
        (name = "service", description = "Health, version, metrics"),
        (name = "worker", description = "Worker protocol (worker token)")
    ),
    components(schemas(
        ErrorBody,
        fracture_api::jobs::ErrorDetail,
        fracture_api::jobs::JobInfo,
        fracture_api::jobs::JobStatus,
        fracture_api::jobs::StatusEvent,
        fracture_api::results::Progress,
        fracture_api::results::Summary,
        fracture_api::sweep::SweepInfo,
        fracture_api::sweep::SweepJob,
        fracture_api::sweep::SweepParameter,
    )),
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

/// The router of the whole service over `state`.
pub fn app(state: AppState) -> Router {
    let limits = state.cfg.limits.clone();
    let public = OpenApiRouter::with_openapi(ApiDoc::openapi())
        .routes(routes!(meta::health))
        .routes(routes!(metrics::version))
        .routes(routes!(metrics::metrics))
        .routes(routes!(meta::list_scenes))
        .routes(routes!(meta::validate_scene))
        .routes(routes!(jobs::create_job, jobs::list_jobs))
        .routes(routes!(jobs::get_job, jobs::delete_job))
        .routes(routes!(jobs::cancel_job))
        .routes(routes!(jobs::rerun_job))
        .routes(routes!(results::get_crack_tips))
        .routes(routes!(results::path_svg))
        .routes(routes!(results::get_energy))
        .routes(routes!(results::list_snapshots))
        .routes(routes!(results::snapshot_png))
        .routes(routes!(results::fields_mcap))
        .routes(routes!(results::vtk_zip))
        .routes(routes!(events::job_events))
        .routes(routes!(sweeps::create_sweep, sweeps::list_sweeps))
        .routes(routes!(sweeps::get_sweep, sweeps::delete_sweep))
        .routes(routes!(sweeps::cancel_sweep))
        .layer(DefaultBodyLimit::max(limits.max_body_bytes))
        .layer(Extension(BodyLimit(limits.max_body_bytes)));
    let worker = OpenApiRouter::new()
        .routes(routes!(worker::worker_claim))
        .routes(routes!(worker::worker_heartbeat))
        .routes(routes!(worker::worker_energy))
        .routes(routes!(worker::worker_crack_tips))
        .routes(routes!(worker::worker_snapshot))
        .routes(routes!(worker::worker_finish))
        .routes(routes!(worker::worker_died))
        .routes(routes!(
            checkpoint::put_checkpoint,
            checkpoint::get_checkpoint,
            checkpoint::delete_checkpoint
        ))
        .routes(routes!(worker::worker_release))
        .layer(DefaultBodyLimit::max(limits.max_worker_body_bytes))
        .layer(Extension(BodyLimit(limits.max_worker_body_bytes)));
    let (router, api) = public.merge(worker).split_for_parts();
    router
        .route("/docs/{file}", axum::routing::get(meta::doc_file))
        .merge(SwaggerUi::new("/api/v1/docs").url("/api/v1/openapi.json", api))
        .method_not_allowed_fallback(method_not_allowed)
        .fallback(static_files)
        .layer(axum::middleware::from_fn_with_state(
            state.clone(),
            security::guard,
        ))
        .layer(tower_http::trace::TraceLayer::new_for_http())
        .layer(tower_http::compression::CompressionLayer::new())
        .with_state(state)
}

/// 405 in the API's error format (axum's own has an empty body).
async fn method_not_allowed(method: axum::http::Method, uri: Uri) -> ApiError {
    ApiError::MethodNotAllowed(format!("{} does not accept {method}", uri.path()))
}

// ---------------------------------------------------------------------------------------
// Helpers of the handlers

/// The job `id`, or 404.
async fn job_or_404(st: &AppState, id: &str) -> Result<JobRow, ApiError> {
    st.store
        .get(id)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("no job with id `{id}`")))
}

/// A job and the id its results are stored under: its own, or for a cache hit that of the
/// completed job it was answered from (404 naming it when that job was deleted since).
async fn results_of(st: &AppState, id: &str) -> Result<(JobRow, String), ApiError> {
    let job = job_or_404(st, id).await?;
    match job.cached_from.clone() {
        None => {
            let src = job.id.clone();
            Ok((job, src))
        }
        Some(src) => {
            if st.store.get(&src).await?.is_none() {
                return Err(ApiError::NotFound(format!(
                    "job `{id}` was answered from the cache with the results of job `{src}`, \
                     which has been deleted"
                )));
            }
            Ok((job, src))
        }
    }
}

/// Run blocking work (file IO, decoding, rendering, validation) off the async threads.
async fn blocking<T: Send + 'static>(
    f: impl FnOnce() -> Result<T, ApiError> + Send + 'static,
) -> Result<T, ApiError> {
    tokio::task::spawn_blocking(f)
        .await
        .map_err(ApiError::internal)?
}

/// Page size of a list (`?limit=`, default 50, at most 500).
fn page_limit(limit: Option<i64>) -> Result<i64, ApiError> {
    let limit = limit.unwrap_or(50);
    if (1..=500).contains(&limit) {
        Ok(limit)
    } else {
        Err(ApiError::BadRequest("limit must be in 1..=500".into()))
    }
}

/// The `?cursor=` of a list: the `seq` of the previous page's last row.
fn page_cursor(cursor: Option<&str>) -> Result<Option<i64>, ApiError> {
    match cursor {
        None | Some("") => Ok(None),
        Some(c) => c
            .parse::<i64>()
            .map(Some)
            .map_err(|_| ApiError::BadRequest(format!("bad cursor `{c}`"))),
    }
}

/// A list page as JSON, with `X-Next-Cursor` when the page is full.
fn page<T: serde::Serialize>(items: Vec<T>, limit: i64, last_seq: Option<i64>) -> Response {
    let full = items.len() as i64 == limit;
    let mut resp = Json(items).into_response();
    if full
        && let Some(n) = last_seq
        && let Ok(v) = HeaderValue::from_str(&n.to_string())
    {
        resp.headers_mut().insert("x-next-cursor", v);
    }
    resp
}

/// A `Location` header for a created resource.
fn location(path: &str) -> HeaderMap {
    let mut h = HeaderMap::new();
    if let Ok(v) = HeaderValue::from_str(path) {
        h.insert(header::LOCATION, v);
    }
    h
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
            (
                [
                    (header::CONTENT_TYPE, ct),
                    (header::CONTENT_SECURITY_POLICY, security::DASHBOARD_CSP),
                ],
                f.data.into_owned(),
            )
                .into_response()
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
