//! What a run produced: crack-tip and energy histories (JSON, or CSV with
//! `Accept: text/csv`), the snapshot index, snapshot fields as PNG, the MCAP file.

use axum::Json;
use axum::extract::{Path, State};
use axum::http::{HeaderMap, header};
use axum::response::{IntoResponse, Response};
use fracture_api::jobs::{ErrorBody, JobStatus, SnapshotInfo};
use fracture_api::results::{CRACK_TIPS_CSV_HEADER, CrackTipRow, ENERGY_CSV_HEADER, EnergyRow};
use fracture_results::render;
use serde::Deserialize;

use super::{blocking, job_or_404};
use crate::error::{ApiError, ApiQuery};
use crate::server::AppState;

/// Query of the history routes.
#[derive(Debug, Deserialize, utoipa::IntoParams)]
#[serde(deny_unknown_fields)]
pub(super) struct SinceQuery {
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
    responses((status = 200, description = "The rows (a NaN number is `null`); CSV with `Accept: text/csv`",
            body = Vec<CrackTipRow>),
        (status = 404, description = "Unknown id", body = ErrorBody)))]
pub(super) async fn get_crack_tips(
    State(st): State<AppState>,
    Path(id): Path<String>,
    ApiQuery(q): ApiQuery<SinceQuery>,
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
    responses((status = 200, description = "The rows (a NaN number is `null`); CSV with `Accept: text/csv`",
            body = Vec<EnergyRow>),
        (status = 404, description = "Unknown id", body = ErrorBody)))]
pub(super) async fn get_energy(
    State(st): State<AppState>,
    Path(id): Path<String>,
    ApiQuery(q): ApiQuery<SinceQuery>,
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
    responses((status = 200, description = "The snapshot index", body = Vec<SnapshotInfo>),
        (status = 404, description = "Unknown id", body = ErrorBody)))]
pub(super) async fn list_snapshots(
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
        (status = 404, description = "Unknown job, snapshot or field", body = ErrorBody)))]
pub(super) async fn snapshot_png(
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
    let png = blocking(move || {
        render::render_png(&snap, &field).map_err(|e| match e {
            render::RenderError::UnknownField(_) => ApiError::NotFound(e.to_string()),
            other => ApiError::internal(other),
        })
    })
    .await?;
    Ok(([(header::CONTENT_TYPE, "image/png")], png).into_response())
}

/// The job's MCAP file (while running: what has been written so far).
#[utoipa::path(get, path = "/api/v1/jobs/{id}/fields.mcap", tag = "results",
    params(("id" = String, Path, description = "Job id")),
    responses((status = 200, description = "MCAP", content_type = "application/octet-stream"),
        (status = 404, description = "Unknown id, or no file yet", body = ErrorBody)))]
pub(super) async fn fields_mcap(
    State(st): State<AppState>,
    Path(id): Path<String>,
) -> Result<Response, ApiError> {
    let job = job_or_404(&st, &id).await?;
    if let Some(why) = st.files.broken(&id) {
        return Err(ApiError::NotFound(format!(
            "job `{id}` has no MCAP file: writing it failed ({why}); its rows and snapshots \
             are served by the crack-tips, energy and snapshots routes"
        )));
    }
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
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            Err(ApiError::NotFound(match job.status {
                JobStatus::Queued => {
                    format!("job `{id}` has no MCAP file yet (it has not started)")
                }
                s if s.is_terminal() && job.started_at.is_some() => {
                    tracing::warn!(job = %id, "MCAP file missing from the data folder");
                    format!(
                        "job `{id}` is {} but its MCAP file is missing from the data folder \
                         (removed outside the service?); its rows and snapshots are served by \
                         the crack-tips, energy and snapshots routes",
                        s.as_str()
                    )
                }
                s => format!("job `{id}` ({}) has no MCAP file", s.as_str()),
            }))
        }
        Err(e) => Err(ApiError::io(&e)),
    }
}
