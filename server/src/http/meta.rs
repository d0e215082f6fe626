//! Health, the built-in example scenes (with their size and an estimated wall time), scene
//! validation, and [`admit`]: the admission of a scene that every route taking one shares
//! (cheap limits first, then the O(particles) validation off the async threads).

use std::sync::OnceLock;

use axum::Json;
use axum::extract::{Path, State};
use axum::http::header;
use axum::response::{IntoResponse, Response};
use fracture_api::jobs::{ErrorBody, HealthInfo, JobStatus, SceneEntry, ValidateResponse};
use fracture_api::{AnyScene, RunSize, any_scene_from_value, cost, validate_any};

use super::blocking;
use crate::error::{ApiError, JsonBody, parse_json};
use crate::server::AppState;

/// Admit a scene of either dimension: [`crate::config::Limits::precheck_any`] here
/// (O(bodies): an enormous scene is refused at once), then validation and the exact limits
/// on a blocking thread. Returns the scene back with its size.
pub(super) async fn admit(st: &AppState, scene: AnyScene) -> Result<(AnyScene, RunSize), ApiError> {
    let limits = st.cfg.limits.clone();
    limits.precheck_any(&scene)?;
    blocking(move || {
        let size = limits.admit_any(&scene)?;
        Ok((scene, size))
    })
    .await
}

/// Health of the service.
#[utoipa::path(get, path = "/api/v1/health", tag = "service",
    responses((status = 200, description = "Workers and queue counts", body = HealthInfo)))]
pub(super) async fn health(State(st): State<AppState>) -> Result<Json<HealthInfo>, ApiError> {
    let (queued, running) = st.store.counts().await?;
    Ok(Json(HealthInfo {
        status: "ok".into(),
        workers: st.cfg.local_workers as u64,
        queued,
        running,
    }))
}

/// Throughput assumed for an estimate when this server has no completed run to measure
/// (particle-steps per second): `docs/performance.md` measured 9.8–10.7 M/s for one job on
/// one worker thread (31k particles, "1 thread, 7 interleaved pairs"), so 10 M/s. Scenes
/// with a crack and a J-integral every sample run somewhat slower, two threads faster.
pub const NOMINAL_PARTICLE_STEPS_PER_SECOND: f64 = 1.0e7;

/// Completed runs whose measured throughput the estimate averages (the newest ones).
const MEASURED_RUNS: i64 = 100;

/// The example scenes with their run size, computed once (validation places every
/// particle, so the first request pays for it on a blocking thread).
static SIZED_SCENES: OnceLock<Vec<SceneEntry>> = OnceLock::new();

/// The embedded example scenes (2D and 3D) with `particles`, `steps` and `particle_steps`
/// filled in from validation (left at 0 for a scene that does not validate).
pub fn sized_scenes() -> Vec<SceneEntry> {
    crate::assets::scenes()
        .into_iter()
        .map(|mut e| {
            let size = any_scene_from_value(e.scene.clone())
                .ok()
                .and_then(|s| validate_any(&s).ok());
            if let Some(size) = size {
                e.particles = size.particles;
                e.steps = size.steps;
                e.particle_steps = cost::particle_steps(size.particles, size.steps);
            }
            e
        })
        .collect()
}

/// The throughput to estimate with and where it comes from: the mean measured
/// `particle_steps_per_second` of this server's newest completed runs (cache hits, which
/// copy another run's summary, left out), else [`NOMINAL_PARTICLE_STEPS_PER_SECOND`].
async fn estimate_throughput(st: &AppState) -> Result<(f64, String), ApiError> {
    let rows = st
        .store
        .list(&crate::store::ListFilter {
            status: Some(JobStatus::Completed),
            limit: MEASURED_RUNS,
            ..Default::default()
        })
        .await?;
    let rates: Vec<f64> = rows
        .iter()
        .filter(|r| r.cached_from.is_none())
        .filter_map(|r| r.summary.as_ref().map(|s| s.particle_steps_per_second))
        .filter(|v| v.is_finite() && *v > 0.0)
        .collect();
    Ok(if rates.is_empty() {
        (
            NOMINAL_PARTICLE_STEPS_PER_SECOND,
            "nominal: 10 M particle-steps/s, one worker thread (docs/performance.md)".into(),
        )
    } else {
        let mean = rates.iter().sum::<f64>() / rates.len() as f64;
        let n = rates.len();
        (
            mean,
            format!(
                "measured: the mean of this server's {n} newest completed run{}",
                if n == 1 { "" } else { "s" }
            ),
        )
    })
}

/// The built-in example scenes, each with its run size and estimated wall time.
#[utoipa::path(get, path = "/api/v1/scenes", tag = "scenes",
    responses((status = 200, description = "`[{name, description, scene, particles, steps, \
        particle_steps, estimated_wall_seconds, estimate_particle_steps_per_second, \
        estimate_basis}]`: the size is validation's; the estimate divides the particle-steps \
        by the mean measured throughput of the server's completed runs, or by a nominal 10 M \
        particle-steps/s (one worker thread, docs/performance.md) before any",
        body = Vec<SceneEntry>)))]
pub(super) async fn list_scenes(
    State(st): State<AppState>,
) -> Result<Json<Vec<SceneEntry>>, ApiError> {
    let scenes = match SIZED_SCENES.get() {
        Some(s) => s.clone(),
        None => {
            let s = blocking(|| Ok(sized_scenes())).await?;
            let _ = SIZED_SCENES.set(s.clone());
            s
        }
    };
    let (rate, basis) = estimate_throughput(&st).await?;
    Ok(Json(
        scenes
            .into_iter()
            .map(|mut e| {
                if e.particle_steps > 0 {
                    e.estimated_wall_seconds = Some(e.particle_steps as f64 / rate);
                    e.estimate_particle_steps_per_second = Some(rate);
                    e.estimate_basis = Some(basis.clone());
                }
                e
            })
            .collect(),
    ))
}

/// Validate a scene (2D, or 3D with `"analysis": "3d"`) and report the size of its run.
#[utoipa::path(post, path = "/api/v1/scenes/validate", tag = "scenes",
    request_body(content = Object, description = "A scene, 2D or 3D (`\"analysis\": \"3d\"`; its JSON Schema: `fracture schema`)",
        content_type = "application/json"),
    responses(
        (status = 200, description = "The size of the run", body = ValidateResponse),
        (status = 400, description = "Malformed JSON", body = ErrorBody),
        (status = 413, description = "Body too large", body = ErrorBody),
        (status = 422, description = "Invalid scene (`invalid_scene`) or over a limit (`limit_exceeded`)", body = ErrorBody)))]
pub(super) async fn validate_scene(
    State(st): State<AppState>,
    JsonBody(body): JsonBody,
) -> Result<Json<ValidateResponse>, ApiError> {
    let value: serde_json::Value = parse_json(&body)?;
    let scene = any_scene_from_value(value)?;
    let (_, size) = admit(&st, scene).await?;
    Ok(Json(ValidateResponse {
        valid: true,
        particles: size.particles,
        grid_nodes: size.grid_nodes,
        time_step: size.time_step,
        steps: size.steps,
    }))
}

/// A guide of the repository, `GET /docs/{name}.md` (`docs/{name}.md` as it was when the
/// server was built), as `text/markdown`; the dashboard shows it rendered at `#/docs/{name}`.
pub(super) async fn doc_file(Path(file): Path<String>) -> Response {
    match file.strip_suffix(".md").and_then(crate::assets::doc) {
        Some(text) => (
            [
                (header::CONTENT_TYPE, "text/markdown; charset=utf-8"),
                (header::CACHE_CONTROL, "no-cache"),
            ],
            text,
        )
            .into_response(),
        None => ApiError::NotFound(format!(
            "no guide `{file}` (there are: {})",
            crate::assets::doc_names()
                .iter()
                .map(|n| format!("{n}.md"))
                .collect::<Vec<_>>()
                .join(", ")
        ))
        .into_response(),
    }
}
