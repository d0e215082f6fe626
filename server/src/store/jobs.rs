//! Job rows: what a job is in the database, and the writes of the public API (create,
//! cancel, delete) and its reads (one job, lists, counts).

use std::collections::BTreeMap;

use fracture_api::AnyScene;
use fracture_api::jobs::{JobInfo, JobStatus, StatusEvent};
use fracture_api::results::{Progress, Summary};
use sqlx::QueryBuilder;

use super::{
    Db, Store, StoreError, StoreRow, Tx, delete_job_rows, from_json, now_text, on_db, on_tx,
    parse_time_text, to_json,
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
    pub(super) fn decode(r: &impl StoreRow) -> Result<JobRow, StoreError> {
        let status = r.text("status")?;
        let status = JobStatus::parse(&status)
            .ok_or_else(|| StoreError::Corrupt(format!("column `status`: unknown `{status}`")))?;
        Ok(JobRow {
            seq: r.int("seq")?,
            id: r.text("id")?,
            name: r.text("name")?,
            status,
            priority: r.int("priority")?,
            labels: r.json("labels")?,
            scene: r.text("scene")?,
            end_time: r.real("end_time")?,
            created_at: r.text("created_at")?,
            started_at: r.opt_text("started_at")?,
            finished_at: r.opt_text("finished_at")?,
            attempts: r.u32("attempts")?,
            fence: r.int("fence")?,
            worker_id: r.opt_text("worker_id")?,
            lease_until_ms: r.opt_int("lease_until_ms")?,
            cancel_requested: r.int("cancel_requested")? != 0,
            progress: r.opt_json("progress")?,
            summary: r.opt_json("summary")?,
            message: r.opt_text("message")?,
            sweep_id: r.opt_text("sweep_id")?,
            sweep_index: r.opt_u32("sweep_index")?,
            sweep_label: r.opt_text("sweep_label")?,
            sweep_values: r.opt_json("sweep_values")?,
            rerun_of: r.opt_text("rerun_of")?,
            scene_hash: r.opt_text("scene_hash")?,
            cached_from: r.opt_text("cached_from")?,
            max_attempts: r.opt_u32("max_attempts")?,
        })
    }

    /// Decode many rows.
    pub(super) fn decode_all<R: StoreRow>(rows: &[R]) -> Result<Vec<JobRow>, StoreError> {
        rows.iter().map(JobRow::decode).collect()
    }

    /// The job as the API shows it; `with_scene` adds the scene document (decoded here:
    /// a stored scene this version cannot read is [`StoreError::Corrupt`]).
    pub fn info(&self, with_scene: bool) -> Result<JobInfo, StoreError> {
        let scene: Option<AnyScene> = if with_scene {
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
    /// SHA-256 of the canonical scene JSON ([`fracture_api::AnyScene::hash`]).
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
    tx: &mut Tx,
    scene_hash: &str,
    solver_version: &str,
) -> Result<Option<String>, StoreError> {
    let sql = tx.backend().pick(
        "SELECT id FROM jobs WHERE scene_hash = $1 AND status = 'completed' AND cached_from IS NULL
           AND json_extract(summary, '$.solver_version') = $2
         ORDER BY seq DESC LIMIT 1",
        "SELECT id FROM jobs WHERE scene_hash = $1 AND status = 'completed' AND cached_from IS NULL
           AND (summary::jsonb ->> 'solver_version') = $2
         ORDER BY seq DESC LIMIT 1",
    );
    Ok(on_tx!(tx, c => sqlx::query_scalar(sql)
        .bind(scene_hash)
        .bind(solver_version)
        .fetch_optional(c)
        .await?))
}

/// Insert a job: a copy of a completed run of the same scene (status `completed`, its
/// summary and progress, `cached_from` set) when `j.use_cache` finds one, else queued.
pub(super) async fn insert_job(
    tx: &mut Tx,
    j: &NewJob,
    sweep: Option<SweepPlace<'_>>,
) -> Result<JobRow, StoreError> {
    let (sweep_id, sweep_index, sweep_label, sweep_values) = match sweep {
        Some((a, b, c, d)) => (Some(a), Some(b), Some(c), Some(d)),
        None => (None, None, None, None),
    };
    let source = if j.use_cache {
        cache_source(tx, &j.scene_hash, fracture_api::SOLVER_VERSION).await?
    } else {
        None
    };
    let labels = to_json("labels", &j.labels)?;
    let now = now_text();
    // A copy (`$15`: the completed job copied) or a queued job: the same 15 values.
    let sql = if source.is_some() {
        "INSERT INTO jobs (id, name, status, priority, labels, scene, end_time, created_at,
                           started_at, finished_at, rerun_of, sweep_id, sweep_index,
                           sweep_label, sweep_values, scene_hash, max_attempts, cached_from,
                           progress, summary)
         SELECT $1, $2, 'completed', $3, $4, $5, $6, $7, $7, $7,
                $8, $9, $10, $11, $12, $13, $14, id, progress, summary
         FROM jobs WHERE id = $15
         RETURNING *"
    } else {
        "INSERT INTO jobs (id, name, status, priority, labels, scene, end_time, created_at,
                           rerun_of, sweep_id, sweep_index, sweep_label, sweep_values,
                           scene_hash, max_attempts)
         VALUES ($1, $2, 'queued', $3, $4, $5, $6, $7, $8, $9, $10, $11, $12, $13, $14)
         RETURNING *"
    };
    on_tx!(tx, c => {
        let mut q = sqlx::query(sql)
            .bind(&j.id)
            .bind(&j.name)
            .bind(j.priority)
            .bind(&labels)
            .bind(&j.scene)
            .bind(j.end_time)
            .bind(&now)
            .bind(&j.rerun_of)
            .bind(sweep_id)
            .bind(sweep_index)
            .bind(sweep_label)
            .bind(sweep_values)
            .bind(&j.scene_hash)
            .bind(j.max_attempts.map(i64::from));
        if let Some(src) = &source {
            q = q.bind(src);
        }
        JobRow::decode(&q.fetch_one(c).await?)
    })
}

impl Store {
    /// Insert a job: queued, or a completed copy of a run of the same scene
    /// ([`NewJob::use_cache`]).
    pub async fn create_job(&self, j: &NewJob) -> Result<JobRow, StoreError> {
        let mut tx = self.db.begin().await?;
        let row = insert_job(&mut tx, j, None).await?;
        tx.commit().await?;
        Ok(row)
    }

    /// One job.
    pub async fn get(&self, id: &str) -> Result<Option<JobRow>, StoreError> {
        on_db!(&self.db, c => sqlx::query("SELECT * FROM jobs WHERE id = $1")
            .bind(id)
            .fetch_optional(c)
            .await?
            .as_ref()
            .map(JobRow::decode)
            .transpose())
    }

    /// Jobs, newest first.
    pub async fn list(&self, f: &ListFilter) -> Result<Vec<JobRow>, StoreError> {
        let backend = self.db.backend();
        on_db!(&self.db, c, DB => {
            let mut q: QueryBuilder<DB> = QueryBuilder::new("SELECT * FROM jobs WHERE 1 = 1");
            if let Some(s) = f.status {
                q.push(" AND status = ").push_bind(s.as_str());
            }
            for (k, v) in &f.labels {
                q.push(backend.pick(
                    " AND EXISTS (SELECT 1 FROM json_each(jobs.labels) WHERE json_each.key = ",
                    " AND EXISTS (SELECT 1 FROM jsonb_each_text(jobs.labels::jsonb) e WHERE e.key = ",
                ))
                .push_bind(k.clone())
                .push(backend.pick(" AND json_each.value = ", " AND e.value = "))
                .push_bind(v.clone())
                .push(")");
            }
            if let Some(text) = &f.name_contains {
                // Both compare ASCII letters case-insensitively (PostgreSQL's `lower` also
                // folds other letters, by the database's locale).
                q.push(backend.pick(" AND instr(lower(name), lower(", " AND strpos(lower(name), lower("))
                    .push_bind(text.clone())
                    .push(")) > 0");
            }
            if let Some(b) = f.before_seq {
                q.push(" AND seq < ").push_bind(b);
            }
            q.push(" ORDER BY seq DESC LIMIT ").push_bind(f.limit);
            JobRow::decode_all(&q.build().fetch_all(c).await?)
        })
    }

    /// Number of queued and running jobs.
    pub async fn counts(&self) -> Result<(u64, u64), StoreError> {
        let (q, r) = on_db!(&self.db, c => {
            let row = sqlx::query(
                "SELECT COUNT(*) FILTER (WHERE status = 'queued') AS q,
                        COUNT(*) FILTER (WHERE status = 'running') AS r FROM jobs",
            )
            .fetch_one(c)
            .await?;
            (row.int("q")?, row.int("r")?)
        });
        Ok((q.max(0) as u64, r.max(0) as u64))
    }

    /// Number of jobs in the store.
    pub async fn count_all(&self) -> Result<u64, StoreError> {
        let n: i64 = on_db!(&self.db, c => sqlx::query_scalar("SELECT COUNT(*) FROM jobs")
            .fetch_one(c)
            .await?);
        Ok(n.max(0) as u64)
    }

    /// Cancel: a queued job ends at once; a running one is flagged for its worker.
    /// Returns the job after the change, `None` if unknown.
    pub async fn cancel(&self, id: &str) -> Result<Option<JobRow>, StoreError> {
        let now = now_text();
        on_db!(&self.db, c => {
            sqlx::query(
                "UPDATE jobs SET status = 'cancelled', message = 'cancelled before it started',
                    finished_at = $2
                 WHERE id = $1 AND status = 'queued'",
            )
            .bind(id)
            .bind(&now)
            .execute(c)
            .await?;
            sqlx::query("UPDATE jobs SET cancel_requested = 1 WHERE id = $1 AND status = 'running'")
                .bind(id)
                .execute(c)
                .await?;
        });
        self.get(id).await
    }

    /// Delete a finished job and its rows. Returns false if it is unknown or not finished.
    pub async fn delete(&self, id: &str) -> Result<bool, StoreError> {
        let mut tx = self.db.begin().await?;
        let n = on_tx!(&mut tx, c => sqlx::query(
            "DELETE FROM jobs WHERE id = $1 AND status IN ('completed', 'failed', 'cancelled')",
        )
        .bind(id)
        .execute(c)
        .await?
        .rows_affected());
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
        let now = time::OffsetDateTime::now_utc();
        let since = super::time_text(now - time::Duration::seconds(i64::from(window_seconds)));
        let (by_status, n, running) = on_db!(&self.db, c => {
            let by_status = sqlx::query("SELECT status, COUNT(*) AS n FROM jobs GROUP BY status")
                .fetch_all(c)
                .await?
                .iter()
                .map(|r| Ok((r.text("status")?, r.int("n")?)))
                .collect::<Result<Vec<_>, StoreError>>()?;
            let n: i64 = sqlx::query_scalar(
                "SELECT COUNT(*) FROM jobs WHERE finished_at IS NOT NULL AND finished_at >= $1",
            )
            .bind(&since)
            .fetch_one(c)
            .await?;
            let running = sqlx::query(
                "SELECT id, scene, progress, started_at FROM jobs WHERE status = 'running'",
            )
            .fetch_all(c)
            .await?
            .iter()
            .map(|r| {
                let progress: Option<Progress> = r.opt_json("progress")?;
                let started = r.opt_text("started_at")?;
                let elapsed = started
                    .as_deref()
                    .and_then(parse_time_text)
                    .map(|t| (now - t).as_seconds_f64().max(0.0));
                Ok(RunningJob {
                    id: r.text("id")?,
                    scene: r.text("scene")?,
                    step: progress.map(|p| p.step).unwrap_or(0),
                    elapsed_seconds: elapsed.unwrap_or(0.0),
                })
            })
            .collect::<Result<Vec<_>, StoreError>>()?;
            (by_status, n, running)
        });
        for (s, k) in by_status {
            m.by_status.insert(s, k.max(0) as u64);
        }
        m.finished_in_window = n.max(0) as u64;
        m.running = running;
        Ok(m)
    }
}
