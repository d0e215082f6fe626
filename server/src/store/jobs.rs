//! Job rows: what a job is in the database, and the writes of the public API (create,
//! cancel, delete) and its reads (one job, lists, counts).

use std::collections::BTreeMap;

use fracture_api::Scene;
use fracture_api::jobs::{JobInfo, JobStatus, StatusEvent};
use fracture_api::results::{Progress, Summary};
use sqlx::sqlite::SqliteRow;
use sqlx::{QueryBuilder, Sqlite};

use super::{
    Store, StoreError, col, col_u32, delete_job_rows, from_json, json_col, opt_json_col, to_json,
};

/// A job as stored, decoded.
#[derive(Debug, Clone)]
pub struct JobRow {
    /// Insertion order (cursor of lists).
    pub seq: i64,
    /// Job id.
    pub id: String,
    /// Scene name.
    pub name: String,
    /// State.
    pub status: JobStatus,
    /// Priority (higher first).
    pub priority: i64,
    /// Labels.
    pub labels: BTreeMap<String, String>,
    /// Canonical scene JSON (decoded only where it is shown: [`JobRow::info`]).
    pub scene: String,
    /// Scene end time (s).
    pub end_time: f64,
    /// RFC 3339.
    pub created_at: String,
    /// RFC 3339.
    pub started_at: Option<String>,
    /// RFC 3339.
    pub finished_at: Option<String>,
    /// Claims counted against the attempt limit.
    pub attempts: u32,
    /// Fencing token.
    pub fence: i64,
    /// Worker holding the lease.
    pub worker_id: Option<String>,
    /// Lease end (ms since epoch).
    pub lease_until_ms: Option<i64>,
    /// Cancellation asked for while running.
    pub cancel_requested: bool,
    /// Latest progress.
    pub progress: Option<Progress>,
    /// The run summary once finished.
    pub summary: Option<Summary>,
    /// Why it failed or was cancelled.
    pub message: Option<String>,
    /// The sweep the job belongs to.
    pub sweep_id: Option<String>,
    /// Place of the job in its sweep (order of the combinations).
    pub sweep_index: Option<u32>,
    /// Label of the job's combination, e.g. `toughness=100`.
    pub sweep_label: Option<String>,
    /// The job's parameter values, `{"path": value}`.
    pub sweep_values: Option<serde_json::Map<String, serde_json::Value>>,
    /// The job this one reruns.
    pub rerun_of: Option<String>,
    /// SHA-256 of the canonical scene JSON (NULL for queued jobs stored before migration 6).
    pub scene_hash: Option<String>,
    /// The completed job whose results this one serves (a cache hit).
    pub cached_from: Option<String>,
    /// The job's own retry budget (`None`: the server's `--max-attempts`).
    pub max_attempts: Option<u32>,
}

impl JobRow {
    /// Decode a `SELECT * FROM jobs` (or `RETURNING *`) row.
    pub(super) fn decode(r: &SqliteRow) -> Result<JobRow, StoreError> {
        let status: String = col(r, "status")?;
        let status = JobStatus::parse(&status)
            .ok_or_else(|| StoreError::Corrupt(format!("column `status`: unknown `{status}`")))?;
        let sweep_index: Option<i64> = col(r, "sweep_index")?;
        let sweep_index = sweep_index
            .map(|i| {
                u32::try_from(i).map_err(|_| {
                    StoreError::Corrupt(format!("column `sweep_index`: {i} is not a u32"))
                })
            })
            .transpose()?;
        Ok(JobRow {
            seq: col(r, "seq")?,
            id: col(r, "id")?,
            name: col(r, "name")?,
            status,
            priority: col(r, "priority")?,
            labels: json_col(r, "labels")?,
            scene: col(r, "scene")?,
            end_time: col(r, "end_time")?,
            created_at: col(r, "created_at")?,
            started_at: col(r, "started_at")?,
            finished_at: col(r, "finished_at")?,
            attempts: col_u32(r, "attempts")?,
            fence: col(r, "fence")?,
            worker_id: col(r, "worker_id")?,
            lease_until_ms: col(r, "lease_until_ms")?,
            cancel_requested: col::<i64>(r, "cancel_requested")? != 0,
            progress: opt_json_col(r, "progress")?,
            summary: opt_json_col(r, "summary")?,
            message: col(r, "message")?,
            sweep_id: col(r, "sweep_id")?,
            sweep_index,
            sweep_label: col(r, "sweep_label")?,
            sweep_values: opt_json_col(r, "sweep_values")?,
            rerun_of: col(r, "rerun_of")?,
            scene_hash: col(r, "scene_hash")?,
            cached_from: col(r, "cached_from")?,
            max_attempts: col::<Option<i64>>(r, "max_attempts")?
                .map(|n| {
                    u32::try_from(n).map_err(|_| {
                        StoreError::Corrupt(format!("column `max_attempts`: {n} is not a u32"))
                    })
                })
                .transpose()?,
        })
    }

    /// Decode many rows.
    pub(super) fn decode_all(rows: &[SqliteRow]) -> Result<Vec<JobRow>, StoreError> {
        rows.iter().map(JobRow::decode).collect()
    }

    /// The job as the API shows it; `with_scene` adds the scene document (decoded here:
    /// a stored scene this version cannot read is [`StoreError::Corrupt`]).
    pub fn info(&self, with_scene: bool) -> Result<JobInfo, StoreError> {
        let scene: Option<Scene> = if with_scene {
            Some(from_json("scene", &self.scene)?)
        } else {
            None
        };
        Ok(JobInfo {
            id: self.id.clone(),
            status: self.status,
            name: self.name.clone(),
            labels: self.labels.clone(),
            priority: self.priority,
            scene,
            created_at: self.created_at.clone(),
            started_at: self.started_at.clone(),
            finished_at: self.finished_at.clone(),
            attempts: self.attempts,
            progress: self.progress,
            summary: self.summary.clone(),
            message: self.message.clone(),
            sweep_id: self.sweep_id.clone(),
            rerun_of: self.rerun_of.clone(),
            cached_from: self.cached_from.clone(),
            max_attempts: self.max_attempts,
        })
    }

    /// The `status` event of this job.
    pub fn status_event(&self) -> StatusEvent {
        StatusEvent {
            id: self.id.clone(),
            status: self.status,
            attempts: self.attempts,
            message: self.message.clone(),
            summary: self.summary.clone(),
        }
    }
}

/// Filters of `GET /api/v1/jobs`.
#[derive(Debug, Clone, Default)]
pub struct ListFilter {
    /// Only this status.
    pub status: Option<JobStatus>,
    /// Only jobs with every one of these labels `(key, value)`.
    pub labels: Vec<(String, String)>,
    /// Only jobs whose name contains this text (ASCII letters compared case-insensitively).
    pub name_contains: Option<String>,
    /// Page size.
    pub limit: i64,
    /// Only jobs older than this sequence number.
    pub before_seq: Option<i64>,
}

/// A new job.
#[derive(Debug, Clone)]
pub struct NewJob {
    /// Job id.
    pub id: String,
    /// Scene name.
    pub name: String,
    /// Canonical scene JSON.
    pub scene: String,
    /// Scene end time.
    pub end_time: f64,
    /// Priority.
    pub priority: i64,
    /// Labels.
    pub labels: BTreeMap<String, String>,
    /// The job this one reruns, if any.
    pub rerun_of: Option<String>,
    /// SHA-256 of the canonical scene JSON ([`fracture_api::Scene::hash`]).
    pub scene_hash: String,
    /// Answer from a completed job with the same scene hash and this server's solver
    /// version, if there is one, instead of queueing a run.
    pub use_cache: bool,
    /// The job's own retry budget (`None`: the server's `--max-attempts`).
    pub max_attempts: Option<u32>,
}

/// Where a new job sits in its sweep: sweep id, index, label, `{"path": value}` JSON.
pub(super) type SweepPlace<'a> = (&'a str, i64, &'a str, &'a str);

/// The completed job a new job with this scene hash reuses: the newest completed job with
/// that hash whose summary has `solver_version`, that is not itself a cached copy.
async fn cache_source(
    tx: &mut sqlx::SqliteConnection,
    scene_hash: &str,
    solver_version: &str,
) -> Result<Option<String>, StoreError> {
    Ok(sqlx::query_scalar(
        "SELECT id FROM jobs WHERE scene_hash = ? AND status = 'completed' AND cached_from IS NULL
           AND json_extract(summary, '$.solver_version') = ?
         ORDER BY seq DESC LIMIT 1",
    )
    .bind(scene_hash)
    .bind(solver_version)
    .fetch_optional(&mut *tx)
    .await?)
}

/// Insert a job: a copy of a completed run of the same scene (status `completed`, its
/// summary and progress, `cached_from` set) when `j.use_cache` finds one, else queued.
pub(super) async fn insert_job(
    tx: &mut sqlx::SqliteConnection,
    j: &NewJob,
    sweep: Option<SweepPlace<'_>>,
) -> Result<JobRow, StoreError> {
    let (sweep_id, sweep_index, sweep_label, sweep_values) = match sweep {
        Some((a, b, c, d)) => (Some(a), Some(b), Some(c), Some(d)),
        None => (None, None, None, None),
    };
    let source = if j.use_cache {
        cache_source(&mut *tx, &j.scene_hash, fracture_api::SOLVER_VERSION).await?
    } else {
        None
    };
    let labels = to_json("labels", &j.labels)?;
    let row = if let Some(src) = source {
        sqlx::query(
            "INSERT INTO jobs (id, name, status, priority, labels, scene, end_time, created_at,
                               started_at, finished_at, rerun_of, sweep_id, sweep_index,
                               sweep_label, sweep_values, scene_hash, max_attempts, cached_from,
                               progress, summary)
             SELECT ?, ?, 'completed', ?, ?, ?, ?, strftime('%Y-%m-%dT%H:%M:%fZ','now'),
                    strftime('%Y-%m-%dT%H:%M:%fZ','now'), strftime('%Y-%m-%dT%H:%M:%fZ','now'),
                    ?, ?, ?, ?, ?, ?, ?, id, progress, summary
             FROM jobs WHERE id = ?
             RETURNING *",
        )
        .bind(&j.id)
        .bind(&j.name)
        .bind(j.priority)
        .bind(&labels)
        .bind(&j.scene)
        .bind(j.end_time)
        .bind(&j.rerun_of)
        .bind(sweep_id)
        .bind(sweep_index)
        .bind(sweep_label)
        .bind(sweep_values)
        .bind(&j.scene_hash)
        .bind(j.max_attempts.map(i64::from))
        .bind(&src)
        .fetch_one(&mut *tx)
        .await?
    } else {
        sqlx::query(
            "INSERT INTO jobs (id, name, status, priority, labels, scene, end_time, created_at,
                               rerun_of, sweep_id, sweep_index, sweep_label, sweep_values,
                               scene_hash, max_attempts)
             VALUES (?, ?, 'queued', ?, ?, ?, ?, strftime('%Y-%m-%dT%H:%M:%fZ','now'),
                     ?, ?, ?, ?, ?, ?, ?)
             RETURNING *",
        )
        .bind(&j.id)
        .bind(&j.name)
        .bind(j.priority)
        .bind(&labels)
        .bind(&j.scene)
        .bind(j.end_time)
        .bind(&j.rerun_of)
        .bind(sweep_id)
        .bind(sweep_index)
        .bind(sweep_label)
        .bind(sweep_values)
        .bind(&j.scene_hash)
        .bind(j.max_attempts.map(i64::from))
        .fetch_one(&mut *tx)
        .await?
    };
    JobRow::decode(&row)
}

impl Store {
    /// Insert a job: queued, or a completed copy of a run of the same scene
    /// ([`NewJob::use_cache`]).
    pub async fn create_job(&self, j: &NewJob) -> Result<JobRow, StoreError> {
        let mut tx = self.pool.begin().await?;
        let row = insert_job(&mut tx, j, None).await?;
        tx.commit().await?;
        Ok(row)
    }

    /// One job.
    pub async fn get(&self, id: &str) -> Result<Option<JobRow>, StoreError> {
        sqlx::query("SELECT * FROM jobs WHERE id = ?")
            .bind(id)
            .fetch_optional(&self.pool)
            .await?
            .as_ref()
            .map(JobRow::decode)
            .transpose()
    }

    /// Jobs, newest first.
    pub async fn list(&self, f: &ListFilter) -> Result<Vec<JobRow>, StoreError> {
        let mut q: QueryBuilder<Sqlite> = QueryBuilder::new("SELECT * FROM jobs WHERE 1 = 1");
        if let Some(s) = f.status {
            q.push(" AND status = ").push_bind(s.as_str());
        }
        for (k, v) in &f.labels {
            q.push(" AND EXISTS (SELECT 1 FROM json_each(jobs.labels) WHERE json_each.key = ")
                .push_bind(k.clone())
                .push(" AND json_each.value = ")
                .push_bind(v.clone())
                .push(")");
        }
        if let Some(text) = &f.name_contains {
            q.push(" AND instr(lower(name), lower(")
                .push_bind(text.clone())
                .push(")) > 0");
        }
        if let Some(b) = f.before_seq {
            q.push(" AND seq < ").push_bind(b);
        }
        q.push(" ORDER BY seq DESC LIMIT ").push_bind(f.limit);
        JobRow::decode_all(&q.build().fetch_all(&self.pool).await?)
    }

    /// Number of queued and running jobs.
    pub async fn counts(&self) -> Result<(u64, u64), StoreError> {
        let row = sqlx::query(
            "SELECT COALESCE(SUM(status = 'queued'), 0) AS q, COALESCE(SUM(status = 'running'), 0) AS r FROM jobs",
        )
        .fetch_one(&self.pool)
        .await?;
        let q: i64 = col(&row, "q")?;
        let r: i64 = col(&row, "r")?;
        Ok((q.max(0) as u64, r.max(0) as u64))
    }

    /// Number of jobs in the store.
    pub async fn count_all(&self) -> Result<u64, StoreError> {
        let n: i64 = sqlx::query_scalar("SELECT COUNT(*) FROM jobs")
            .fetch_one(&self.pool)
            .await?;
        Ok(n.max(0) as u64)
    }

    /// Cancel: a queued job ends at once; a running one is flagged for its worker.
    /// Returns the job after the change, `None` if unknown.
    pub async fn cancel(&self, id: &str) -> Result<Option<JobRow>, StoreError> {
        sqlx::query(
            "UPDATE jobs SET status = 'cancelled', message = 'cancelled before it started',
                finished_at = strftime('%Y-%m-%dT%H:%M:%fZ','now')
             WHERE id = ? AND status = 'queued'",
        )
        .bind(id)
        .execute(&self.pool)
        .await?;
        sqlx::query("UPDATE jobs SET cancel_requested = 1 WHERE id = ? AND status = 'running'")
            .bind(id)
            .execute(&self.pool)
            .await?;
        self.get(id).await
    }

    /// Delete a finished job and its rows. Returns false if it is unknown or not finished.
    pub async fn delete(&self, id: &str) -> Result<bool, StoreError> {
        let mut tx = self.pool.begin().await?;
        let n = sqlx::query(
            "DELETE FROM jobs WHERE id = ? AND status IN ('completed', 'failed', 'cancelled')",
        )
        .bind(id)
        .execute(&mut *tx)
        .await?
        .rows_affected();
        if n == 1 {
            delete_job_rows(&mut tx, id).await?;
        }
        tx.commit().await?;
        Ok(n == 1)
    }
}

/// A running job as the metrics see it.
#[derive(Debug, Clone)]
pub struct RunningJob {
    /// Job id.
    pub id: String,
    /// Canonical scene JSON.
    pub scene: String,
    /// Steps taken (latest progress).
    pub step: u64,
    /// Seconds since the claim.
    pub elapsed_seconds: f64,
}

/// What `GET /metrics` reads from the store.
#[derive(Debug, Clone, Default)]
pub struct StoreMetrics {
    /// Jobs per state.
    pub by_status: std::collections::HashMap<String, u64>,
    /// Jobs that ended within the window.
    pub finished_in_window: u64,
    /// The running jobs.
    pub running: Vec<RunningJob>,
}

impl Store {
    /// Counts per state, jobs finished in the last `window_seconds`, and the running jobs.
    pub async fn metrics(&self, window_seconds: u32) -> Result<StoreMetrics, StoreError> {
        let mut m = StoreMetrics::default();
        for r in sqlx::query("SELECT status, COUNT(*) AS n FROM jobs GROUP BY status")
            .fetch_all(&self.pool)
            .await?
        {
            let s: String = col(&r, "status")?;
            let n: i64 = col(&r, "n")?;
            m.by_status.insert(s, n.max(0) as u64);
        }
        let n: i64 = sqlx::query_scalar(
            "SELECT COUNT(*) FROM jobs WHERE finished_at IS NOT NULL
               AND finished_at >= strftime('%Y-%m-%dT%H:%M:%fZ', 'now', '-' || ? || ' seconds')",
        )
        .bind(i64::from(window_seconds))
        .fetch_one(&self.pool)
        .await?;
        m.finished_in_window = n.max(0) as u64;
        for r in sqlx::query(
            "SELECT id, scene, progress,
                    (julianday('now') - julianday(started_at)) * 86400.0 AS elapsed
             FROM jobs WHERE status = 'running'",
        )
        .fetch_all(&self.pool)
        .await?
        {
            let progress: Option<Progress> = opt_json_col(&r, "progress")?;
            let elapsed: Option<f64> = col(&r, "elapsed")?;
            m.running.push(RunningJob {
                id: col(&r, "id")?,
                scene: col(&r, "scene")?,
                step: progress.map(|p| p.step).unwrap_or(0),
                elapsed_seconds: elapsed.unwrap_or(0.0),
            });
        }
        Ok(m)
    }
}
