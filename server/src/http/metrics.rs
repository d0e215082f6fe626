//! `GET /api/v1/version` (service and solver version, git commit, build profile) and
//! `GET /metrics` (Prometheus text format 0.0.4).
//!
//! The metrics are a handful of gauges read from the store at each scrape, so the text is
//! written here directly: a metrics registry (`metrics` + `metrics-exporter-prometheus`)
//! would add a recorder, a global and two crates for values that live in SQLite anyway.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::sync::{Arc, Mutex};

use axum::Json;
use axum::extract::State;
use axum::http::header;
use axum::response::{IntoResponse, Response};
use serde::Serialize;

use super::blocking;
use crate::error::ApiError;
use crate::server::AppState;

/// Window of the `fracture_jobs_finished_per_second` rate (s).
pub const RATE_WINDOW_SECONDS: u32 = 60;

/// `GET /api/v1/version`.
#[derive(Debug, Clone, Serialize, utoipa::ToSchema)]
pub struct VersionInfo {
    /// `fracture-server`.
    pub service: String,
    /// Version of the service (its crate version).
    pub version: String,
    /// Version of the solver and data model recorded in run summaries.
    pub solver_version: String,
    /// Git commit the binary was built from (`FRACTURE_GIT_COMMIT` at build time, else
    /// `git rev-parse` by the build script); `null` when neither was available.
    pub git_commit: Option<String>,
    /// Cargo profile of the build: `debug` or `release`.
    pub build_profile: String,
}

/// The version of this build.
pub fn version_info() -> VersionInfo {
    VersionInfo {
        service: env!("CARGO_PKG_NAME").to_string(),
        version: env!("CARGO_PKG_VERSION").to_string(),
        solver_version: fracture_api::SOLVER_VERSION.to_string(),
        git_commit: option_env!("FRACTURE_GIT_COMMIT")
            .filter(|c| !c.is_empty())
            .map(str::to_string),
        build_profile: option_env!("FRACTURE_BUILD_PROFILE")
            .unwrap_or(if cfg!(debug_assertions) {
                "debug"
            } else {
                "release"
            })
            .to_string(),
    }
}

/// Version of the service and solver, git commit and build profile.
#[utoipa::path(get, path = "/api/v1/version", tag = "service",
    responses((status = 200, description = "The build", body = VersionInfo)))]
pub(super) async fn version() -> Json<VersionInfo> {
    Json(version_info())
}

/// Particle counts of running jobs (exact, from validation), kept while they run.
#[derive(Debug, Default)]
pub struct ParticleCache(Mutex<HashMap<String, u64>>);

impl ParticleCache {
    fn get(&self, id: &str) -> Option<u64> {
        self.0.lock().ok()?.get(id).copied()
    }
    fn put(&self, id: &str, n: u64) {
        if let Ok(mut m) = self.0.lock() {
            m.insert(id.to_string(), n);
        }
    }
    fn keep_only(&self, ids: &[&str]) {
        if let Ok(mut m) = self.0.lock() {
            m.retain(|k, _| ids.contains(&k.as_str()));
        }
    }
}

/// The particle count of a job's scene (the validation walk, once per job).
async fn particles(cache: &Arc<ParticleCache>, id: &str, scene: &str) -> Option<u64> {
    if let Some(n) = cache.get(id) {
        return Some(n);
    }
    let scene = scene.to_string();
    let n = blocking(move || {
        let s: fracture_api::AnyScene = serde_json::from_str(&scene).map_err(ApiError::internal)?;
        fracture_api::validate_any(&s)
            .map(|size| size.particles)
            .map_err(|e| ApiError::internal(format!("{e:?}")))
    })
    .await
    .ok()?;
    cache.put(id, n);
    Some(n)
}

fn metric(out: &mut String, name: &str, kind: &str, help: &str) {
    let _ = writeln!(out, "# HELP {name} {help}");
    let _ = writeln!(out, "# TYPE {name} {kind}");
}

/// A sample value in the text format (`NaN`, `+Inf` spelled as Prometheus reads them).
fn value(x: f64) -> String {
    if x.is_nan() {
        "NaN".into()
    } else if x.is_infinite() {
        if x > 0.0 {
            "+Inf".into()
        } else {
            "-Inf".into()
        }
    } else {
        format!("{x}")
    }
}

/// Service metrics in the Prometheus text format.
#[utoipa::path(get, path = "/metrics", tag = "service",
    responses((status = 200, description = "Prometheus text format 0.0.4: `fracture_queue_depth`, \
        `fracture_jobs_running`, `fracture_jobs{status}`, `fracture_jobs_finished_per_second`, \
        `fracture_particle_steps_per_second`, `fracture_workers`", content_type = "text/plain")))]
pub(super) async fn metrics(State(st): State<AppState>) -> Result<Response, ApiError> {
    let m = st.store.metrics(RATE_WINDOW_SECONDS).await?;
    let mut out = String::new();
    metric(
        &mut out,
        "fracture_queue_depth",
        "gauge",
        "Jobs waiting for a worker.",
    );
    let count = |s: &str| m.by_status.get(s).copied().unwrap_or(0);
    let _ = writeln!(out, "fracture_queue_depth {}", count("queued"));
    metric(
        &mut out,
        "fracture_jobs_running",
        "gauge",
        "Jobs being run.",
    );
    let _ = writeln!(out, "fracture_jobs_running {}", count("running"));
    metric(
        &mut out,
        "fracture_jobs",
        "gauge",
        "Jobs in the store by state (deleting jobs lowers the finished ones).",
    );
    for s in ["queued", "running", "completed", "failed", "cancelled"] {
        let _ = writeln!(out, "fracture_jobs{{status=\"{s}\"}} {}", count(s));
    }
    metric(
        &mut out,
        "fracture_jobs_finished_per_second",
        "gauge",
        "Jobs that ended (any final state) per second over the last window.",
    );
    let _ = writeln!(
        out,
        "fracture_jobs_finished_per_second{{window=\"{RATE_WINDOW_SECONDS}s\"}} {}",
        value(m.finished_in_window as f64 / f64::from(RATE_WINDOW_SECONDS))
    );
    // Particle-steps per second of the running jobs: particles × steps taken / time since
    // the claim, summed.
    let mut rate = 0.0;
    for r in &m.running {
        if r.elapsed_seconds > 0.0
            && let Some(n) = particles(&st.particles, &r.id, &r.scene).await
        {
            rate += n as f64 * r.step as f64 / r.elapsed_seconds;
        }
    }
    let ids: Vec<&str> = m.running.iter().map(|r| r.id.as_str()).collect();
    st.particles.keep_only(&ids);
    metric(
        &mut out,
        "fracture_particle_steps_per_second",
        "gauge",
        "Particle-steps per second of the running jobs (each: particles x steps / time since its claim).",
    );
    let _ = writeln!(out, "fracture_particle_steps_per_second {}", value(rate));
    metric(
        &mut out,
        "fracture_workers",
        "gauge",
        "Local worker processes the server supervises.",
    );
    let _ = writeln!(out, "fracture_workers {}", st.cfg.local_workers);
    Ok((
        [(
            header::CONTENT_TYPE,
            "text/plain; version=0.0.4; charset=utf-8",
        )],
        out,
    )
        .into_response())
}
