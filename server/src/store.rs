//! The SQLite store: jobs, the durable queue (claim with one `UPDATE … RETURNING`, leases,
//! heartbeats, fencing tokens, a reaper), history rows and snapshots.
//!
//! The server is the only writer. Every write a worker makes is fenced: it names the fence
//! of its claim, and the write happens only while the job is `running` under that fence.

use std::collections::BTreeMap;
use std::path::Path;
use std::str::FromStr;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use fracture_api::jobs::{JobInfo, JobStatus, SnapshotInfo, StatusEvent};
use fracture_api::results::{CrackTipRow, EnergyRow, Progress, Snapshot, Summary};
use sqlx::sqlite::{SqliteConnectOptions, SqliteJournalMode, SqlitePoolOptions, SqliteSynchronous};
use sqlx::{QueryBuilder, Row, Sqlite, SqlitePool};

use fracture_results::codec;

/// Errors of the store.
#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    /// The database failed.
    #[error(transparent)]
    Db(#[from] sqlx::Error),
    /// Migrations failed.
    #[error(transparent)]
    Migrate(#[from] sqlx::migrate::MigrateError),
    /// The fence is stale or the job is no longer running under it.
    #[error("the job is not running under this claim (stale fencing token)")]
    Fenced,
    /// Stored data could not be decoded.
    #[error("corrupt stored data: {0}")]
    Corrupt(String),
}

/// Milliseconds since the Unix epoch.
pub fn now_ms() -> i64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_millis() as i64)
        .unwrap_or(0)
}

const NOW: &str = "strftime('%Y-%m-%dT%H:%M:%fZ','now')";

/// A job as stored.
#[derive(Debug, Clone, sqlx::FromRow)]
pub struct JobRow {
    /// Insertion order (cursor of lists).
    pub seq: i64,
    /// Job id.
    pub id: String,
    /// Scene name.
    pub name: String,
    /// Status name.
    pub status: String,
    /// Priority (higher first).
    pub priority: i64,
    /// Labels as a JSON object.
    pub labels: String,
    /// Scene JSON.
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
    pub attempts: i64,
    /// Fencing token.
    pub fence: i64,
    /// Worker holding the lease.
    pub worker_id: Option<String>,
    /// Lease end (ms since epoch).
    pub lease_until_ms: Option<i64>,
    /// Cancellation asked for while running.
    pub cancel_requested: i64,
    /// Progress JSON.
    pub progress: Option<String>,
    /// Summary JSON.
    pub summary: Option<String>,
    /// Why it failed or was cancelled.
    pub message: Option<String>,
    /// The sweep the job belongs to.
    pub sweep_id: Option<String>,
    /// Place of the job in its sweep (order of the combinations).
    pub sweep_index: Option<i64>,
    /// Label of the job's combination, e.g. `toughness=100`.
    pub sweep_label: Option<String>,
    /// The job's parameter values, `{"path": value}` as JSON.
    pub sweep_values: Option<String>,
}

impl JobRow {
    /// The status.
    pub fn status(&self) -> JobStatus {
        JobStatus::parse(&self.status).unwrap_or(JobStatus::Failed)
    }
    /// The job as the API shows it; `with_scene` adds the scene document.
    pub fn info(&self, with_scene: bool) -> JobInfo {
        JobInfo {
            id: self.id.clone(),
            status: self.status(),
            name: self.name.clone(),
            labels: serde_json::from_str(&self.labels).unwrap_or_default(),
            priority: self.priority,
            scene: if with_scene {
                serde_json::from_str(&self.scene).ok()
            } else {
                None
            },
            created_at: self.created_at.clone(),
            started_at: self.started_at.clone(),
            finished_at: self.finished_at.clone(),
            attempts: self.attempts.max(0) as u32,
            progress: self.progress(),
            summary: self
                .summary
                .as_deref()
                .and_then(|s| serde_json::from_str(s).ok()),
            message: self.message.clone(),
            sweep_id: self.sweep_id.clone(),
        }
    }
    /// Latest progress.
    pub fn progress(&self) -> Option<Progress> {
        self.progress
            .as_deref()
            .and_then(|s| serde_json::from_str(s).ok())
    }
    /// The `status` event of this job.
    pub fn status_event(&self) -> StatusEvent {
        let i = self.info(false);
        StatusEvent {
            id: i.id,
            status: i.status,
            attempts: i.attempts,
            message: i.message,
            summary: i.summary,
        }
    }
}

/// A successful claim.
#[derive(Debug, Clone)]
pub struct Claimed {
    /// The claimed job (status running).
    pub job: JobRow,
}

/// Filters of `GET /api/v1/jobs`.
#[derive(Debug, Clone, Default)]
pub struct ListFilter {
    /// Only this status.
    pub status: Option<JobStatus>,
    /// Only jobs with this label `(key, value)`.
    pub label: Option<(String, String)>,
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
}

/// A sweep as stored.
#[derive(Debug, Clone, sqlx::FromRow)]
pub struct SweepRow {
    /// Insertion order (cursor of lists).
    pub seq: i64,
    /// Sweep id.
    pub id: String,
    /// Name.
    pub name: String,
    /// Base scene JSON.
    pub scene: String,
    /// `[{"path", "values"}]` JSON.
    pub parameters: String,
    /// Priority of its jobs.
    pub priority: i64,
    /// Labels given with the request (JSON object).
    pub labels: String,
    /// RFC 3339.
    pub created_at: String,
}

/// A new sweep.
#[derive(Debug, Clone)]
pub struct NewSweep {
    /// Sweep id.
    pub id: String,
    /// Name.
    pub name: String,
    /// Base scene JSON.
    pub scene: String,
    /// `[{"path", "values"}]` JSON.
    pub parameters: String,
    /// Priority of its jobs.
    pub priority: i64,
    /// Labels given with the request.
    pub labels: BTreeMap<String, String>,
}

/// One job of a new sweep.
#[derive(Debug, Clone)]
pub struct NewSweepJob {
    /// The job.
    pub job: NewJob,
    /// Label of its combination.
    pub label: String,
    /// `{"path": value}` JSON.
    pub values: String,
}

/// Handle to the database (cheap to clone).
#[derive(Debug, Clone)]
pub struct Store {
    pool: SqlitePool,
}

impl Store {
    /// Open (creating if needed) the database file and run the embedded migrations.
    pub async fn open(path: &Path) -> Result<Store, StoreError> {
        let opts = SqliteConnectOptions::from_str("sqlite://")?
            .filename(path)
            .create_if_missing(true)
            .journal_mode(SqliteJournalMode::Wal)
            .synchronous(SqliteSynchronous::Normal)
            .busy_timeout(Duration::from_secs(15))
            .foreign_keys(true);
        let pool = SqlitePoolOptions::new()
            .max_connections(8)
            .connect_with(opts)
            .await?;
        sqlx::migrate!("./migrations").run(&pool).await?;
        Ok(Store { pool })
    }

    /// Close the pool (waits for connections to be returned).
    pub async fn close(&self) {
        self.pool.close().await;
    }

    /// Insert a queued job.
    pub async fn create_job(&self, j: &NewJob) -> Result<JobRow, StoreError> {
        let labels = serde_json::to_string(&j.labels).unwrap_or_else(|_| "{}".into());
        let row = sqlx::query_as::<_, JobRow>(
            "INSERT INTO jobs (id, name, status, priority, labels, scene, end_time, created_at)
             VALUES (?, ?, 'queued', ?, ?, ?, ?, strftime('%Y-%m-%dT%H:%M:%fZ','now'))
             RETURNING *",
        )
        .bind(&j.id)
        .bind(&j.name)
        .bind(j.priority)
        .bind(labels)
        .bind(&j.scene)
        .bind(j.end_time)
        .fetch_one(&self.pool)
        .await?;
        Ok(row)
    }

    /// Insert a sweep and all its jobs (queued) in one transaction.
    pub async fn create_sweep(
        &self,
        sw: &NewSweep,
        jobs: &[NewSweepJob],
    ) -> Result<SweepRow, StoreError> {
        let mut tx = self.pool.begin().await?;
        let labels = serde_json::to_string(&sw.labels).unwrap_or_else(|_| "{}".into());
        let row = sqlx::query_as::<_, SweepRow>(
            "INSERT INTO sweeps (id, name, scene, parameters, priority, labels, created_at)
             VALUES (?, ?, ?, ?, ?, ?, strftime('%Y-%m-%dT%H:%M:%fZ','now'))
             RETURNING *",
        )
        .bind(&sw.id)
        .bind(&sw.name)
        .bind(&sw.scene)
        .bind(&sw.parameters)
        .bind(sw.priority)
        .bind(labels)
        .fetch_one(&mut *tx)
        .await?;
        for (i, j) in jobs.iter().enumerate() {
            let labels = serde_json::to_string(&j.job.labels).unwrap_or_else(|_| "{}".into());
            sqlx::query(
                "INSERT INTO jobs (id, name, status, priority, labels, scene, end_time, created_at,
                                   sweep_id, sweep_index, sweep_label, sweep_values)
                 VALUES (?, ?, 'queued', ?, ?, ?, ?, strftime('%Y-%m-%dT%H:%M:%fZ','now'), ?, ?, ?, ?)",
            )
            .bind(&j.job.id)
            .bind(&j.job.name)
            .bind(j.job.priority)
            .bind(labels)
            .bind(&j.job.scene)
            .bind(j.job.end_time)
            .bind(&sw.id)
            .bind(i as i64)
            .bind(&j.label)
            .bind(&j.values)
            .execute(&mut *tx)
            .await?;
        }
        tx.commit().await?;
        Ok(row)
    }

    /// One sweep.
    pub async fn sweep(&self, id: &str) -> Result<Option<SweepRow>, StoreError> {
        Ok(
            sqlx::query_as::<_, SweepRow>("SELECT * FROM sweeps WHERE id = ?")
                .bind(id)
                .fetch_optional(&self.pool)
                .await?,
        )
    }

    /// Sweeps, newest first: at most `limit`, older than `before_seq` when given.
    pub async fn sweeps(
        &self,
        limit: i64,
        before_seq: Option<i64>,
    ) -> Result<Vec<SweepRow>, StoreError> {
        Ok(sqlx::query_as::<_, SweepRow>(
            "SELECT * FROM sweeps WHERE (? IS NULL OR seq < ?) ORDER BY seq DESC LIMIT ?",
        )
        .bind(before_seq)
        .bind(before_seq)
        .bind(limit)
        .fetch_all(&self.pool)
        .await?)
    }

    /// The jobs of a sweep, in the order of its combinations.
    pub async fn sweep_jobs(&self, id: &str) -> Result<Vec<JobRow>, StoreError> {
        Ok(sqlx::query_as::<_, JobRow>(
            "SELECT * FROM jobs WHERE sweep_id = ? ORDER BY sweep_index, seq",
        )
        .bind(id)
        .fetch_all(&self.pool)
        .await?)
    }

    /// Delete a sweep row (its jobs are deleted one by one by the caller).
    pub async fn delete_sweep(&self, id: &str) -> Result<bool, StoreError> {
        let n = sqlx::query("DELETE FROM sweeps WHERE id = ?")
            .bind(id)
            .execute(&self.pool)
            .await?
            .rows_affected();
        Ok(n == 1)
    }

    /// One job.
    pub async fn get(&self, id: &str) -> Result<Option<JobRow>, StoreError> {
        Ok(
            sqlx::query_as::<_, JobRow>("SELECT * FROM jobs WHERE id = ?")
                .bind(id)
                .fetch_optional(&self.pool)
                .await?,
        )
    }

    /// Jobs, newest first.
    pub async fn list(&self, f: &ListFilter) -> Result<Vec<JobRow>, StoreError> {
        let mut q: QueryBuilder<Sqlite> = QueryBuilder::new("SELECT * FROM jobs WHERE 1 = 1");
        if let Some(s) = f.status {
            q.push(" AND status = ").push_bind(s.as_str());
        }
        if let Some((k, v)) = &f.label {
            q.push(" AND EXISTS (SELECT 1 FROM json_each(jobs.labels) WHERE json_each.key = ")
                .push_bind(k.clone())
                .push(" AND json_each.value = ")
                .push_bind(v.clone())
                .push(")");
        }
        if let Some(b) = f.before_seq {
            q.push(" AND seq < ").push_bind(b);
        }
        q.push(" ORDER BY seq DESC LIMIT ").push_bind(f.limit);
        Ok(q.build_query_as::<JobRow>().fetch_all(&self.pool).await?)
    }

    /// Number of queued and running jobs.
    pub async fn counts(&self) -> Result<(u64, u64), StoreError> {
        let row = sqlx::query(
            "SELECT COALESCE(SUM(status = 'queued'), 0) AS q, COALESCE(SUM(status = 'running'), 0) AS r FROM jobs",
        )
        .fetch_one(&self.pool)
        .await?;
        let q: i64 = row.try_get("q")?;
        let r: i64 = row.try_get("r")?;
        Ok((q.max(0) as u64, r.max(0) as u64))
    }

    /// Total number of jobs (tests and health checks).
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
            for sql in [
                "DELETE FROM energy WHERE job_id = ?",
                "DELETE FROM crack_tips WHERE job_id = ?",
                "DELETE FROM snapshots WHERE job_id = ?",
            ] {
                sqlx::query(sql).bind(id).execute(&mut *tx).await?;
            }
        }
        tx.commit().await?;
        Ok(n == 1)
    }

    /// Claim the best queued job (highest priority, then oldest) for `worker`, with a lease.
    /// A job claimed again (after a lost worker) loses the previous attempt's rows.
    pub async fn claim(
        &self,
        worker: &str,
        lease: Duration,
    ) -> Result<Option<Claimed>, StoreError> {
        let until = now_ms() + lease.as_millis() as i64;
        let mut tx = self.pool.begin().await?;
        let job = sqlx::query_as::<_, JobRow>(
            "UPDATE jobs SET status = 'running', attempts = attempts + 1, fence = fence + 1,
                worker_id = ?, lease_until_ms = ?, message = NULL, progress = NULL,
                started_at = strftime('%Y-%m-%dT%H:%M:%fZ','now')
             WHERE seq = (SELECT seq FROM jobs WHERE status = 'queued'
                          ORDER BY priority DESC, seq ASC LIMIT 1)
               AND status = 'queued'
             RETURNING *",
        )
        .bind(worker)
        .bind(until)
        .fetch_optional(&mut *tx)
        .await?;
        if let Some(j) = &job {
            for sql in [
                "DELETE FROM energy WHERE job_id = ?",
                "DELETE FROM crack_tips WHERE job_id = ?",
                "DELETE FROM snapshots WHERE job_id = ?",
            ] {
                sqlx::query(sql).bind(&j.id).execute(&mut *tx).await?;
            }
        }
        tx.commit().await?;
        Ok(job.map(|job| Claimed { job }))
    }

    /// Extend the lease of a job running under `fence` (the first statement of a fenced
    /// write, so the transaction holds the write lock from its start).
    async fn fence_check(
        conn: &mut sqlx::SqliteConnection,
        id: &str,
        fence: i64,
        lease: Duration,
    ) -> Result<bool, StoreError> {
        let until = now_ms() + lease.as_millis() as i64;
        let row = sqlx::query(
            "UPDATE jobs SET lease_until_ms = MAX(COALESCE(lease_until_ms, 0), ?)
             WHERE id = ? AND fence = ? AND status = 'running'
             RETURNING cancel_requested",
        )
        .bind(until)
        .bind(id)
        .bind(fence)
        .fetch_optional(&mut *conn)
        .await?;
        match row {
            None => Err(StoreError::Fenced),
            Some(r) => Ok(r.try_get::<i64, _>("cancel_requested")? != 0),
        }
    }

    /// Heartbeat: extend the lease, record progress; returns whether cancellation was asked.
    pub async fn heartbeat(
        &self,
        id: &str,
        fence: i64,
        lease: Duration,
        progress: Option<&Progress>,
    ) -> Result<bool, StoreError> {
        let until = now_ms() + lease.as_millis() as i64;
        let p = progress.and_then(|p| serde_json::to_string(p).ok());
        let row = sqlx::query(
            "UPDATE jobs SET lease_until_ms = ?, progress = COALESCE(?, progress)
             WHERE id = ? AND fence = ? AND status = 'running'
             RETURNING cancel_requested",
        )
        .bind(until)
        .bind(p)
        .bind(id)
        .bind(fence)
        .fetch_optional(&self.pool)
        .await?;
        match row {
            None => Err(StoreError::Fenced),
            Some(r) => Ok(r.try_get::<i64, _>("cancel_requested")? != 0),
        }
    }

    /// Append energy rows (fenced).
    pub async fn append_energy(
        &self,
        id: &str,
        fence: i64,
        lease: Duration,
        rows: &[EnergyRow],
    ) -> Result<(), StoreError> {
        let mut tx = self.pool.begin().await?;
        Self::fence_check(&mut tx, id, fence, lease).await?;
        for chunk in rows.chunks(100) {
            let mut q: QueryBuilder<Sqlite> = QueryBuilder::new(
                "INSERT INTO energy (job_id, time, kinetic, strain, external_work, dissipated, total_error) ",
            );
            q.push_values(chunk, |mut b, r| {
                b.push_bind(id)
                    .push_bind(r.time)
                    .push_bind(r.kinetic)
                    .push_bind(r.strain)
                    .push_bind(r.external_work)
                    .push_bind(r.dissipated)
                    .push_bind(r.total_error);
            });
            q.build().execute(&mut *tx).await?;
        }
        tx.commit().await?;
        Ok(())
    }

    /// Append crack-tip rows (fenced).
    pub async fn append_crack_tips(
        &self,
        id: &str,
        fence: i64,
        lease: Duration,
        rows: &[CrackTipRow],
    ) -> Result<(), StoreError> {
        let mut tx = self.pool.begin().await?;
        Self::fence_check(&mut tx, id, fence, lease).await?;
        for chunk in rows.chunks(50) {
            let mut q: QueryBuilder<Sqlite> = QueryBuilder::new(
                "INSERT INTO crack_tips (job_id, time, crack, tip, x, y, length, speed, j1, j2, k1, k2, growing) ",
            );
            q.push_values(chunk, |mut b, r| {
                b.push_bind(id)
                    .push_bind(r.time)
                    .push_bind(r.crack as i64)
                    .push_bind(r.tip as i64)
                    .push_bind(r.x)
                    .push_bind(r.y)
                    .push_bind(r.length)
                    .push_bind(r.speed)
                    .push_bind(r.j1)
                    .push_bind(r.j2)
                    .push_bind(r.k1)
                    .push_bind(r.k2)
                    .push_bind(i64::from(r.growing));
            });
            q.build().execute(&mut *tx).await?;
        }
        tx.commit().await?;
        Ok(())
    }

    /// Store a snapshot (fenced; a repeated index replaces the earlier one).
    pub async fn put_snapshot(
        &self,
        id: &str,
        fence: i64,
        lease: Duration,
        snap: &Snapshot,
        encoded: &[u8],
    ) -> Result<(), StoreError> {
        let mut tx = self.pool.begin().await?;
        Self::fence_check(&mut tx, id, fence, lease).await?;
        sqlx::query(
            "INSERT OR REPLACE INTO snapshots (job_id, idx, time, fields, data) VALUES (?, ?, ?, ?, ?)",
        )
        .bind(id)
        .bind(snap.index as i64)
        .bind(snap.time)
        .bind(serde_json::to_string(&snap.fields).unwrap_or_else(|_| "[]".into()))
        .bind(encoded)
        .execute(&mut *tx)
        .await?;
        tx.commit().await?;
        Ok(())
    }

    /// Finish a run (fenced): the job takes the summary's status (a cancellation asked for
    /// while running wins over a normal end only if the run stopped early).
    pub async fn finish(
        &self,
        id: &str,
        fence: i64,
        summary: &Summary,
    ) -> Result<JobRow, StoreError> {
        use fracture_api::results::RunStatus;
        let status = match summary.status {
            RunStatus::Completed => "completed",
            RunStatus::Failed => "failed",
            RunStatus::Cancelled => "cancelled",
        };
        let s = serde_json::to_string(summary).map_err(|e| StoreError::Corrupt(e.to_string()))?;
        let row = sqlx::query_as::<_, JobRow>(
            "UPDATE jobs SET status = ?, summary = ?, message = ?, worker_id = NULL,
                lease_until_ms = NULL, finished_at = strftime('%Y-%m-%dT%H:%M:%fZ','now')
             WHERE id = ? AND fence = ? AND status = 'running'
             RETURNING *",
        )
        .bind(status)
        .bind(s)
        .bind(summary.message.clone())
        .bind(id)
        .bind(fence)
        .fetch_optional(&self.pool)
        .await?;
        row.ok_or(StoreError::Fenced)
    }

    /// Re-queue (or fail, past the attempt limit; or cancel, if asked) running jobs whose
    /// lease has expired. Returns the changed jobs.
    pub async fn reap(&self, max_attempts: u32) -> Result<Vec<JobRow>, StoreError> {
        let rows = sqlx::query_as::<_, JobRow>(
            "UPDATE jobs SET
                status = CASE WHEN cancel_requested != 0 THEN 'cancelled'
                              WHEN attempts >= ? THEN 'failed' ELSE 'queued' END,
                message = CASE WHEN cancel_requested != 0 THEN 'cancelled (its worker stopped answering)'
                              WHEN attempts >= ? THEN 'the worker was lost ' || attempts || ' times (lease expired); giving up'
                              ELSE 'the worker was lost (lease expired); re-queued' END,
                finished_at = CASE WHEN cancel_requested != 0 OR attempts >= ?
                                   THEN strftime('%Y-%m-%dT%H:%M:%fZ','now') ELSE NULL END,
                worker_id = NULL, lease_until_ms = NULL
             WHERE status = 'running' AND lease_until_ms < ?
             RETURNING *",
        )
        .bind(max_attempts as i64)
        .bind(max_attempts as i64)
        .bind(max_attempts as i64)
        .bind(now_ms())
        .fetch_all(&self.pool)
        .await?;
        Ok(rows)
    }

    /// Put every running job back in the queue without counting the attempt (shutdown of
    /// this server, or recovery at start). Later writes of their workers are fenced off.
    pub async fn release_running(&self, reason: &str) -> Result<Vec<JobRow>, StoreError> {
        Ok(sqlx::query_as::<_, JobRow>(
            "UPDATE jobs SET
                status = CASE WHEN cancel_requested != 0 THEN 'cancelled' ELSE 'queued' END,
                finished_at = CASE WHEN cancel_requested != 0
                                   THEN strftime('%Y-%m-%dT%H:%M:%fZ','now') ELSE NULL END,
                attempts = MAX(attempts - 1, 0), message = ?,
                worker_id = NULL, lease_until_ms = NULL
             WHERE status = 'running'
             RETURNING *",
        )
        .bind(reason)
        .fetch_all(&self.pool)
        .await?)
    }

    /// Energy rows, optionally only those after `since`.
    pub async fn energy(&self, id: &str, since: Option<f64>) -> Result<Vec<EnergyRow>, StoreError> {
        let rows = sqlx::query(
            "SELECT time, kinetic, strain, external_work, dissipated, total_error FROM energy
             WHERE job_id = ? AND (? IS NULL OR time > ?) ORDER BY rowid",
        )
        .bind(id)
        .bind(since)
        .bind(since)
        .fetch_all(&self.pool)
        .await?;
        let f = |r: &sqlx::sqlite::SqliteRow, c: &str| -> f64 {
            r.try_get::<Option<f64>, _>(c)
                .ok()
                .flatten()
                .unwrap_or(f64::NAN)
        };
        Ok(rows
            .iter()
            .map(|r| EnergyRow {
                time: f(r, "time"),
                kinetic: f(r, "kinetic"),
                strain: f(r, "strain"),
                external_work: f(r, "external_work"),
                dissipated: f(r, "dissipated"),
                total_error: f(r, "total_error"),
            })
            .collect())
    }

    /// Crack-tip rows, optionally only those after `since`.
    pub async fn crack_tips(
        &self,
        id: &str,
        since: Option<f64>,
    ) -> Result<Vec<CrackTipRow>, StoreError> {
        let rows = sqlx::query(
            "SELECT time, crack, tip, x, y, length, speed, j1, j2, k1, k2, growing FROM crack_tips
             WHERE job_id = ? AND (? IS NULL OR time > ?) ORDER BY rowid",
        )
        .bind(id)
        .bind(since)
        .bind(since)
        .fetch_all(&self.pool)
        .await?;
        let f = |r: &sqlx::sqlite::SqliteRow, c: &str| -> f64 {
            r.try_get::<Option<f64>, _>(c)
                .ok()
                .flatten()
                .unwrap_or(f64::NAN)
        };
        let i =
            |r: &sqlx::sqlite::SqliteRow, c: &str| -> i64 { r.try_get::<i64, _>(c).unwrap_or(0) };
        Ok(rows
            .iter()
            .map(|r| CrackTipRow {
                time: f(r, "time"),
                crack: i(r, "crack") as u32,
                tip: i(r, "tip") as u32,
                x: f(r, "x"),
                y: f(r, "y"),
                length: f(r, "length"),
                speed: f(r, "speed"),
                j1: f(r, "j1"),
                j2: f(r, "j2"),
                k1: f(r, "k1"),
                k2: f(r, "k2"),
                growing: i(r, "growing") != 0,
            })
            .collect())
    }

    /// Snapshot index entries, in order.
    pub async fn snapshots(&self, id: &str) -> Result<Vec<SnapshotInfo>, StoreError> {
        let rows = sqlx::query(
            "SELECT idx, time, fields, data FROM snapshots WHERE job_id = ? ORDER BY idx",
        )
        .bind(id)
        .fetch_all(&self.pool)
        .await?;
        let mut out = Vec::with_capacity(rows.len());
        for r in rows {
            let idx: i64 = r.try_get("idx")?;
            let time: f64 = r.try_get("time")?;
            let fields: String = r.try_get("fields")?;
            let data: Vec<u8> = r.try_get("data")?;
            let components = codec::decode_snapshot(&data)
                .map(|s| s.components.into_iter().map(|c| c.name).collect())
                .unwrap_or_default();
            out.push(SnapshotInfo {
                index: idx as u32,
                time,
                fields: serde_json::from_str(&fields).unwrap_or_default(),
                components,
            });
        }
        Ok(out)
    }

    /// One snapshot.
    pub async fn snapshot(&self, id: &str, index: u32) -> Result<Option<Snapshot>, StoreError> {
        let row = sqlx::query("SELECT data FROM snapshots WHERE job_id = ? AND idx = ?")
            .bind(id)
            .bind(index as i64)
            .fetch_optional(&self.pool)
            .await?;
        match row {
            None => Ok(None),
            Some(r) => {
                let data: Vec<u8> = r.try_get("data")?;
                codec::decode_snapshot(&data)
                    .map(Some)
                    .map_err(|e| StoreError::Corrupt(e.to_string()))
            }
        }
    }

    /// Row counts of a job: (energy, crack tips, snapshots) — for tests.
    pub async fn row_counts(&self, id: &str) -> Result<(u64, u64, u64), StoreError> {
        let r = sqlx::query(
            "SELECT (SELECT COUNT(*) FROM energy WHERE job_id = ?1) AS e,
                    (SELECT COUNT(*) FROM crack_tips WHERE job_id = ?1) AS c,
                    (SELECT COUNT(*) FROM snapshots WHERE job_id = ?1) AS s",
        )
        .bind(id)
        .fetch_one(&self.pool)
        .await?;
        let g = |c: &str| r.try_get::<i64, _>(c).map(|v| v.max(0) as u64);
        Ok((g("e")?, g("c")?, g("s")?))
    }
}

/// `NOW` is kept for readers of this module: every timestamp is SQLite's UTC clock in
/// RFC 3339 with milliseconds.
pub const TIMESTAMP_SQL: &str = NOW;
