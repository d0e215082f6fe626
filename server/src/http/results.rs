//! What a run produced: crack-tip and energy histories (JSON, or CSV with
//! `Accept: text/csv`, as an attachment), the snapshot index, snapshot fields as PNG (with
//! render options in the query and the render report in headers, or as JSON), the MCAP
//! file, and the snapshots as a zipped VTK series for ParaView.

use axum::Json;
use axum::extract::{Path, State};
use axum::http::{HeaderMap, HeaderValue, header};
use axum::response::{IntoResponse, Response};
use fracture_api::jobs::{ErrorBody, JobStatus, SnapshotInfo};
use fracture_api::results::{CRACK_TIPS_CSV_HEADER, CrackTipRow, ENERGY_CSV_HEADER, EnergyRow};
use fracture_results::render::{self, RenderOptions, RenderReport};
use fracture_results::vtk;
use serde::{Deserialize, Serialize};

use super::{blocking, results_of};
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

/// A CSV download: `filename` goes into `Content-Disposition: attachment` (browsers save it
/// under that name; `curl -OJ` too).
fn csv_response(
    filename: &str,
    header_line: &str,
    lines: impl Iterator<Item = String>,
) -> Response {
    let mut body = String::from(header_line);
    body.push('\n');
    for l in lines {
        body.push_str(&l);
        body.push('\n');
    }
    (
        [
            (header::CONTENT_TYPE, "text/csv; charset=utf-8".to_string()),
            (header::CONTENT_DISPOSITION, attachment(filename)),
        ],
        body,
    )
        .into_response()
}

/// `attachment; filename="…"` for a file name made of the job id (letters, digits, `-`) and
/// our own suffixes; anything else is replaced so the header stays valid.
fn attachment(filename: &str) -> String {
    let safe: String = filename
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.') {
                c
            } else {
                '_'
            }
        })
        .collect();
    format!("attachment; filename=\"{safe}\"")
}

/// Crack-tip history (`crack_tips.csv` rows), JSON or CSV (`Accept: text/csv`).
#[utoipa::path(get, path = "/api/v1/jobs/{id}/crack-tips", tag = "results",
    params(("id" = String, Path, description = "Job id"), SinceQuery),
    responses((status = 200, description = "The rows (a NaN number is `null`); CSV with `Accept: text/csv` \
            (as an attachment, `Content-Disposition: attachment; filename=\"<job-id>-<name>.csv\"`)",
            body = Vec<CrackTipRow>),
        (status = 404, description = "Unknown id", body = ErrorBody)))]
pub(super) async fn get_crack_tips(
    State(st): State<AppState>,
    Path(id): Path<String>,
    ApiQuery(q): ApiQuery<SinceQuery>,
    headers: HeaderMap,
) -> Result<Response, ApiError> {
    let (_, src) = results_of(&st, &id).await?;
    let rows = st.store.crack_tips(&src, q.since).await?;
    if wants_csv(&headers) {
        Ok(csv_response(
            &format!("{id}-crack_tips.csv"),
            CRACK_TIPS_CSV_HEADER,
            rows.iter().map(CrackTipRow::to_csv),
        ))
    } else {
        Ok(Json(rows).into_response())
    }
}

/// The crack-path picture (`path.svg` of a run folder): the bodies' outlines, the scene's
/// cracks and interfaces, and the x–y path of every crack tip over time, coloured by time.
/// Drawn from the rows stored so far, so it grows while the job runs.
#[utoipa::path(get, path = "/api/v1/jobs/{id}/path.svg", tag = "results",
    params(("id" = String, Path, description = "Job id")),
    responses((status = 200, description = "An SVG picture (`image/svg+xml`)", content_type = "image/svg+xml", body = String),
        (status = 404, description = "Unknown id, a scene without cracks or interfaces, or a 3D scene", body = ErrorBody)))]
pub(super) async fn path_svg(
    State(st): State<AppState>,
    Path(id): Path<String>,
) -> Result<Response, ApiError> {
    let (job, src) = results_of(&st, &id).await?;
    let scene: fracture_api::AnyScene =
        serde_json::from_str(&job.scene).map_err(ApiError::internal)?;
    let Some(scene) = scene.as_2d().cloned() else {
        return Err(ApiError::NotFound(format!(
            "job `{id}` is a 3D run: its cracks are surfaces with fronts, not tip paths to draw"
        )));
    };
    if scene.cracks.is_empty() && scene.interfaces.is_empty() {
        return Err(ApiError::NotFound(format!(
            "job `{id}` has no cracks or interfaces: there is no crack path to draw"
        )));
    }
    let rows = st.store.crack_tips(&src, None).await?;
    let svg = blocking(move || {
        let mut paths = fracture_results::path::PathRecorder::new();
        paths.extend(&rows);
        Ok(fracture_results::path::path_svg(&scene, paths.paths()))
    })
    .await?;
    Ok((
        [
            (header::CONTENT_TYPE, "image/svg+xml".to_string()),
            (header::CACHE_CONTROL, "no-store".to_string()),
        ],
        svg,
    )
        .into_response())
}

/// Energy history (`energy.csv` rows), JSON or CSV (`Accept: text/csv`).
#[utoipa::path(get, path = "/api/v1/jobs/{id}/energy", tag = "results",
    params(("id" = String, Path, description = "Job id"), SinceQuery),
    responses((status = 200, description = "The rows (a NaN number is `null`); CSV with `Accept: text/csv` \
            (as an attachment, `Content-Disposition: attachment; filename=\"<job-id>-<name>.csv\"`)",
            body = Vec<EnergyRow>),
        (status = 404, description = "Unknown id", body = ErrorBody)))]
pub(super) async fn get_energy(
    State(st): State<AppState>,
    Path(id): Path<String>,
    ApiQuery(q): ApiQuery<SinceQuery>,
    headers: HeaderMap,
) -> Result<Response, ApiError> {
    let (_, src) = results_of(&st, &id).await?;
    let rows = st.store.energy(&src, q.since).await?;
    if wants_csv(&headers) {
        Ok(csv_response(
            &format!("{id}-energy.csv"),
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
    let (_, src) = results_of(&st, &id).await?;
    Ok(Json(st.store.snapshots(&src).await?))
}

/// Query of the snapshot picture routes: the render options of
/// [`fracture_results::render::RenderOptions`]. Values are read here (not by serde) so that a
/// bad one gets a 400 naming the parameter and the value.
#[derive(Debug, Default, Deserialize, utoipa::IntoParams)]
#[serde(deny_unknown_fields)]
pub(super) struct PictureQuery {
    /// Pixels per grid cell (> 0, e.g. `8` or `2.5`); takes precedence over `width`.
    /// Default: at least 4, about 960 pixels on the long side for small grids.
    #[param(value_type = Option<f64>)]
    px_per_cell: Option<String>,
    /// Width of the field area in pixels (1–20000; the legend is added around it).
    #[param(value_type = Option<u32>)]
    width: Option<String>,
    /// Fixed colour range `LO,HI` in SI units (Pa, m/s, m), e.g. `-2e6,2e6`, instead of the
    /// data range (signed maps use the larger magnitude symmetrically; ignored for `fringe`
    /// and `material`).
    range: Option<String>,
    /// Fringes per pascal of σ1 − σ2 (thickness over the fringe constant, > 0): the fringe
    /// order is then computed per pixel from the interpolated stresses.
    #[param(value_type = Option<f64>)]
    fringe_per_pa: Option<String>,
    /// Draw the cracks (`true`/`false`, `1`/`0`; default true).
    #[param(value_type = Option<bool>)]
    cracks: Option<String>,
    /// Draw the legend (`true`/`false`, `1`/`0`; default true); without it the picture is the
    /// field area alone.
    #[param(value_type = Option<bool>)]
    legend: Option<String>,
}

/// The largest `width` a picture may ask for (the pixel budget of the renderer still
/// applies to the whole field area).
const MAX_PICTURE_WIDTH: u32 = 20_000;

fn positive(name: &str, v: &str) -> Result<f64, ApiError> {
    match v.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        _ => Err(ApiError::bad_parameter(
            name,
            format!("`{v}` is not a positive number"),
        )),
    }
}

fn flag(name: &str, v: &str) -> Result<bool, ApiError> {
    match v.trim() {
        "true" | "1" | "yes" => Ok(true),
        "false" | "0" | "no" => Ok(false),
        _ => Err(ApiError::bad_parameter(
            name,
            format!("`{v}` is not `true` or `false`"),
        )),
    }
}

impl PictureQuery {
    /// The render options, or a 400 naming the first bad parameter.
    fn options(&self) -> Result<RenderOptions, ApiError> {
        let mut o = RenderOptions::default();
        if let Some(v) = self.px_per_cell.as_deref() {
            o.px_per_cell = Some(positive("px_per_cell", v)?);
        }
        if let Some(v) = self.width.as_deref() {
            o.width = Some(match v.trim().parse::<u32>() {
                Ok(w) if (1..=MAX_PICTURE_WIDTH).contains(&w) => w,
                _ => {
                    return Err(ApiError::bad_parameter(
                        "width",
                        format!("`{v}` is not a whole number of pixels in 1..={MAX_PICTURE_WIDTH}"),
                    ));
                }
            });
        }
        if let Some(v) = self.range.as_deref() {
            let bad = || {
                ApiError::bad_parameter(
                    "range",
                    format!("`{v}` is not `LO,HI` with two finite numbers, LO < HI"),
                )
            };
            let (lo, hi) = v.split_once(',').ok_or_else(bad)?;
            let (lo, hi) = (
                lo.trim().parse::<f64>().map_err(|_| bad())?,
                hi.trim().parse::<f64>().map_err(|_| bad())?,
            );
            if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                return Err(bad());
            }
            o.range = Some([lo, hi]);
        }
        if let Some(v) = self.fringe_per_pa.as_deref() {
            o.fringe_per_pa = Some(positive("fringe_per_pa", v)?);
        }
        if let Some(v) = self.cracks.as_deref() {
            o.cracks = flag("cracks", v)?;
        }
        if let Some(v) = self.legend.as_deref() {
            o.legend = flag("legend", v)?;
        }
        Ok(o)
    }

    /// The parameter a size refusal of the renderer is about.
    fn size_parameter(&self) -> &'static str {
        if self.px_per_cell.is_some() {
            "px_per_cell"
        } else if self.width.is_some() {
            "width"
        } else {
            "px_per_cell"
        }
    }
}

/// What a snapshot picture shows and how well it resolves the field: the renderer's report
/// (`GET …/snapshots/{index}/{field}.json`).
#[derive(Debug, Clone, Serialize, utoipa::ToSchema)]
pub(super) struct PictureInfo {
    /// The component drawn (`fringe`, `sxx`, …).
    component: String,
    /// Quantity and unit as in the legend, e.g. `σxx (MPa)`.
    label: String,
    /// Size of the whole PNG (pixels).
    width: u32,
    /// Size of the whole PNG (pixels).
    height: u32,
    /// The field area inside the PNG: x, y of its top-left pixel, width, height.
    plot: [u32; 4],
    /// Pixels per grid cell used.
    px_per_cell: f64,
    /// Colour range in SI units (fringes: [0, largest N]).
    range: [f64; 2],
    /// Fringe pictures: the largest change of the fringe order between adjacent pixels.
    max_fringes_per_pixel: Option<f64>,
    /// Adjacent pixel pairs whose fringe order differs by more than one fringe.
    aliased_pairs: u64,
    /// Some fringes are not resolved (more pixels per cell would resolve more of them).
    aliased: bool,
    /// Box around the aliased pixel pairs (m: x0, y0, x1, y1).
    aliased_box: Option<[f64; 4]>,
    /// The `X-Fringe-Aliasing` header of the PNG (fringe pictures only).
    aliasing: Option<String>,
}

/// The `X-Fringe-Aliasing` value of a fringe picture: `none; max-per-pixel=0.42` or
/// `aliased; pairs=12; max-per-pixel=3.1; box=x0,y0,x1,y1` (m). `None` for other fields.
fn aliasing_header(r: &RenderReport) -> Option<String> {
    let max = r.max_fringes_per_pixel?;
    if !r.aliased {
        return Some(format!("none; max-per-pixel={max:.3}"));
    }
    let mut s = format!("aliased; pairs={}; max-per-pixel={max:.3}", r.aliased_pairs);
    if let Some([x0, y0, x1, y1]) = r.aliased_box {
        s.push_str(&format!("; box={x0:e},{y0:e},{x1:e},{y1:e}"));
    }
    Some(s)
}

impl From<&RenderReport> for PictureInfo {
    fn from(r: &RenderReport) -> Self {
        PictureInfo {
            component: r.component.clone(),
            label: r.label.clone(),
            width: r.width,
            height: r.height,
            plot: r.plot,
            px_per_cell: r.px_per_cell,
            range: r.range,
            max_fringes_per_pixel: r.max_fringes_per_pixel,
            aliased_pairs: r.aliased_pairs,
            aliased: r.aliased,
            aliased_box: r.aliased_box,
            aliasing: aliasing_header(r),
        }
    }
}

/// A snapshot field as a PNG (`{field}.png`), or what that picture shows as JSON
/// (`{field}.json`): `{field}` is a component (`sxx`, `vx`, `speed`, `fringe`, …) or a field
/// kind (`stress`, `velocity`, …) for its default component. The query sets the size and
/// range; fringe pictures say in `X-Fringe-Aliasing` whether every fringe is resolved.
#[utoipa::path(get, path = "/api/v1/jobs/{id}/snapshots/{index}/{file}", tag = "results",
    params(("id" = String, Path, description = "Job id"),
        ("index" = u32, Path, description = "Snapshot index"),
        ("file" = String, Path, description = "`{field}.png` (the picture) or `{field}.json` (its render report)"),
        PictureQuery),
    responses((status = 200, description = "The image (headers `X-Render-Px-Per-Cell`, and for fringes \
            `X-Fringe-Aliasing`: `none; max-per-pixel=N` or `aliased; pairs=N; max-per-pixel=N; box=x0,y0,x1,y1`), \
            or for `.json` the render report",
            content((Vec<u8> = "image/png"), (PictureInfo = "application/json"))),
        (status = 400, description = "A bad render option (`details[].path` names the parameter)", body = ErrorBody),
        (status = 404, description = "Unknown job, snapshot or field", body = ErrorBody)))]
pub(super) async fn snapshot_png(
    State(st): State<AppState>,
    Path((id, index, file)): Path<(String, String, String)>,
    ApiQuery(q): ApiQuery<PictureQuery>,
) -> Result<Response, ApiError> {
    let (field, as_json) = match (file.strip_suffix(".png"), file.strip_suffix(".json")) {
        (Some(f), _) => (f.to_string(), false),
        (None, Some(f)) => (f.to_string(), true),
        _ => {
            return Err(ApiError::NotFound(format!(
                "`{file}`: only `{{field}}.png` and `{{field}}.json` are served"
            )));
        }
    };
    let index: u32 = index
        .parse()
        .map_err(|_| ApiError::NotFound(format!("no snapshot `{index}`")))?;
    let opts = q.options()?;
    let size_param = q.size_parameter();
    let (_, src) = results_of(&st, &id).await?;
    let snap = st
        .store
        .snapshot(&src, index)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("job `{id}` has no snapshot {index}")))?;
    let rendered = blocking(move || {
        render::render_png_with(&snap, &field, &opts).map_err(|e| match e {
            render::RenderError::UnknownField(_) => ApiError::NotFound(e.to_string()),
            render::RenderError::BadOptions(m) => ApiError::bad_parameter(size_param, m),
            other => ApiError::internal(other),
        })
    })
    .await?;
    let info = PictureInfo::from(&rendered.report);
    if as_json {
        return Ok(Json(info).into_response());
    }
    let mut resp = ([(header::CONTENT_TYPE, "image/png")], rendered.png).into_response();
    let h = resp.headers_mut();
    if let Ok(v) = HeaderValue::from_str(&format!("{}", info.px_per_cell)) {
        h.insert("x-render-px-per-cell", v);
    }
    if let Some(a) = info.aliasing.as_deref()
        && let Ok(v) = HeaderValue::from_str(a)
    {
        h.insert("x-fringe-aliasing", v);
    }
    Ok(resp)
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
    let (job, src) = results_of(&st, &id).await?;
    if let Some(why) = st.files.broken(&src) {
        return Err(ApiError::NotFound(format!(
            "job `{id}` has no MCAP file: writing it failed ({why}); its rows and snapshots \
             are served by the crack-tips, energy and snapshots routes"
        )));
    }
    let path = st.files.mcap_path(&src);
    match tokio::fs::read(&path).await {
        Ok(bytes) => Ok((
            [
                (header::CONTENT_TYPE, "application/octet-stream".to_string()),
                (
                    header::CONTENT_DISPOSITION,
                    attachment(&format!("{id}-fields.mcap")),
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

/// The job's field snapshots as a VTK series for ParaView, zipped: a folder
/// `<id>-vtk/` with `fields.pvd` (open this one), `cracks.pvd`, and per snapshot a
/// `fields_NNNNN.vti` (the nodal grid) and `cracks_NNNNN.vtp` (the crack lines), as
/// `fracture_results::vtk::series_files` writes them (`docs/vtk.md`); a 3D job's slices as
/// one series per plane, each image at its plane, and `fields.pvd` with a part per plane.
/// While the job runs: the snapshots so far.
#[utoipa::path(get, path = "/api/v1/jobs/{id}/vtk.zip", tag = "results",
    params(("id" = String, Path, description = "Job id")),
    responses((status = 200, description = "Zip archive (`Content-Disposition: attachment; filename=\"<id>-vtk.zip\"`)",
            content_type = "application/zip"),
        (status = 404, description = "Unknown id, or no snapshots (yet)", body = ErrorBody)))]
pub(super) async fn vtk_zip(
    State(st): State<AppState>,
    Path(id): Path<String>,
) -> Result<Response, ApiError> {
    let (job, src) = results_of(&st, &id).await?;
    let index = st.store.snapshots(&src).await?;
    if index.is_empty() {
        return Err(ApiError::NotFound(match job.status {
            JobStatus::Queued | JobStatus::Running => {
                format!("job `{id}` has no field snapshots yet")
            }
            s => format!(
                "job `{id}` ({}) has no field snapshots (its scene's `output.snapshot_interval` \
                 gives when they are taken)",
                s.as_str()
            ),
        }));
    }
    let mut snaps = Vec::with_capacity(index.len());
    for s in &index {
        if let Some(snap) = st.store.snapshot(&src, s.index).await? {
            snaps.push(snap);
        }
    }
    let folder = format!("{id}-vtk");
    let bytes = blocking(move || {
        let files = vtk::series_files(&snaps).map_err(ApiError::internal)?;
        zip_files(&folder, &files).map_err(ApiError::internal)
    })
    .await?;
    Ok((
        [
            (header::CONTENT_TYPE, "application/zip".to_string()),
            (
                header::CONTENT_DISPOSITION,
                attachment(&format!("{id}-vtk.zip")),
            ),
        ],
        bytes,
    )
        .into_response())
}

/// A zip archive (deflate) of `files` under the folder `folder/`.
fn zip_files(folder: &str, files: &[(String, Vec<u8>)]) -> zip::result::ZipResult<Vec<u8>> {
    use std::io::Write;
    let mut w = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let opts = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated)
        .unix_permissions(0o644);
    for (name, bytes) in files {
        w.start_file(format!("{folder}/{name}"), opts)?;
        w.write_all(bytes)?;
    }
    Ok(w.finish()?.into_inner())
}
