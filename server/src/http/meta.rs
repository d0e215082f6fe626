//! Health, the built-in example scenes, scene validation, and [`admit`]: the admission of a
//! scene that every route taking one shares (cheap limits first, then the O(particles)
//! validation off the async threads).

use axum::Json;
use axum::extract::State;
use fracture_api::jobs::{ErrorBody, HealthInfo, SceneEntry, ValidateResponse};
use fracture_api::{RunSize, Scene, validate};

use super::blocking;
use crate::error::{ApiError, JsonBody, parse_json};
use crate::server::AppState;

/// Admit a scene: [`crate::config::Limits::precheck`] here (O(bodies): an enormous scene
/// is refused at once), then validation and the exact limits on a blocking thread.
/// Returns the scene back with its size.
pub(super) async fn admit(st: &AppState, scene: Scene) -> Result<(Scene, RunSize), ApiError> {
    let limits = st.cfg.limits.clone();
    limits.precheck(&scene)?;
    blocking(move || {
        let size = limits.admit(&scene)?;
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

/// The built-in example scenes.
#[utoipa::path(get, path = "/api/v1/scenes", tag = "scenes",
    responses((status = 200, description = "`[{name, description, scene}]`", body = Vec<SceneEntry>)))]
pub(super) async fn list_scenes() -> Json<Vec<SceneEntry>> {
    Json(crate::assets::scenes())
}

/// Validate a scene and report the size of its run.
#[utoipa::path(post, path = "/api/v1/scenes/validate", tag = "scenes",
    request_body(content = Object, description = "A scene (its JSON Schema: `fracture schema`)",
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
    let scene = validate::scene_from_value(value)?;
    let (_, size) = admit(&st, scene).await?;
    Ok(Json(ValidateResponse {
        valid: true,
        particles: size.particles,
        grid_nodes: size.grid_nodes,
        time_step: size.time_step,
        steps: size.steps,
    }))
}
