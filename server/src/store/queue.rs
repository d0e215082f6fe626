//! The durable queue: claims (one `UPDATE … RETURNING`, highest priority then oldest),
//! leases extended by heartbeats and fenced writes, fencing tokens raised on every claim,
//! the reaper of expired leases, and the release of running jobs at shutdown.

use std::time::Duration;

use fracture_api::results::{Progress, RunStatus, Summary};

use super::{JobRow, Store, StoreError, col, delete_job_rows, now_ms, to_json};

/// The release of a dead worker's jobs (`?1` max attempts unless the job has its own, `?2` deterministic, `?3` the
/// cause); the caller adds the `WHERE` clause.
const RELEASE: &str = "UPDATE jobs SET
    status = CASE WHEN cancel_requested != 0 THEN 'cancelled'
                  WHEN ?2 OR attempts >= COALESCE(max_attempts, ?1) THEN 'failed' ELSE 'queued' END,
    message = CASE WHEN cancel_requested != 0 THEN 'cancelled (its worker died: ' || ?3 || ')'
                  WHEN ?2 THEN 'the worker running it died: ' || ?3
                  WHEN attempts >= COALESCE(max_attempts, ?1) THEN 'the worker running it died (attempt ' || attempts || ' of ' || COALESCE(max_attempts, ?1) || '; giving up): ' || ?3
                  ELSE 're-queued: the worker running it died: ' || ?3 END,
    finished_at = CASE WHEN cancel_requested != 0 OR ?2 OR attempts >= COALESCE(max_attempts, ?1)
                       THEN strftime('%Y-%m-%dT%H:%M:%fZ','now') ELSE NULL END,
    worker_id = NULL, lease_until_ms = NULL";

/// Where a resumed job's history continues (its checkpoint's position).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HistoryCursor {
    /// Steps taken at the checkpoint.
    pub step: u64,
    /// Simulated time of the checkpoint (s): rows at later times are deleted.
    pub time: f64,
    /// Snapshots taken by then: snapshots with this index or more are deleted.
    pub snapshots: u32,
}

/// A successful claim.
#[derive(Debug, Clone)]
pub struct Claimed {
    /// The claimed job (status running).
    pub job: JobRow,
}

impl Store {
    /// Claim the best queued job (highest priority, then oldest) for `worker`, with a lease,
    /// skipping the jobs of a sweep that has `max_concurrent` of its jobs running.
    /// The claim's history is set by [`Store::rewind_history`] (called by the claim route
    /// before it answers: a re-claimed job keeps only what its checkpoint covers).
    pub async fn claim(
        &self,
        worker: &str,
        lease: Duration,
    ) -> Result<Option<Claimed>, StoreError> {
        let until = now_ms() + lease.as_millis() as i64;
        let mut tx = self.pool.begin().await?;
        let row = sqlx::query(
            "UPDATE jobs SET status = 'running', attempts = attempts + 1, fence = fence + 1,
                worker_id = ?, lease_until_ms = ?, message = NULL, progress = NULL,
                started_at = strftime('%Y-%m-%dT%H:%M:%fZ','now')
             WHERE seq = (SELECT q.seq FROM jobs q LEFT JOIN sweeps s ON s.id = q.sweep_id
                          WHERE q.status = 'queued'
                            AND (s.max_concurrent IS NULL
                                 OR (SELECT COUNT(*) FROM jobs r WHERE r.sweep_id = q.sweep_id
                                       AND r.status = 'running') < s.max_concurrent)
                          ORDER BY q.priority DESC, q.seq ASC LIMIT 1)
               AND status = 'queued'
             RETURNING *",
        )
        .bind(worker)
        .bind(until)
        .fetch_optional(&mut *tx)
        .await?;
        let job = row.as_ref().map(JobRow::decode).transpose()?;
        tx.commit().await?;
        Ok(job.map(|job| Claimed { job }))
    }

    /// The history a new claim under `fence` starts from: the rows and snapshots of earlier
    /// attempts are deleted, all of them, or with a checkpoint to resume from only those
    /// after it (`keep`: rows at times ≤ `time` and snapshots with index < `snapshots`
    /// stay). With a checkpoint, the job's message says where it resumes. Fenced.
    pub async fn rewind_history(
        &self,
        id: &str,
        fence: i64,
        lease: Duration,
        keep: Option<HistoryCursor>,
    ) -> Result<(), StoreError> {
        let mut tx = self.pool.begin().await?;
        Self::fence_check(&mut tx, id, fence, lease).await?;
        match keep {
            None => delete_job_rows(&mut tx, id).await?,
            Some(k) => {
                for sql in [
                    "DELETE FROM energy WHERE job_id = ? AND time > ?",
                    "DELETE FROM crack_tips WHERE job_id = ? AND time > ?",
                ] {
                    sqlx::query(sql)
                        .bind(id)
                        .bind(k.time)
                        .execute(&mut *tx)
                        .await?;
                }
                sqlx::query("DELETE FROM snapshots WHERE job_id = ? AND idx >= ?")
                    .bind(id)
                    .bind(i64::from(k.snapshots))
                    .execute(&mut *tx)
                    .await?;
                sqlx::query("UPDATE jobs SET message = ? WHERE id = ?")
                    .bind(format!(
                        "resumed from its checkpoint at step {} (t = {:e} s)",
                        k.step, k.time
                    ))
                    .bind(id)
                    .execute(&mut *tx)
                    .await?;
            }
        }
        tx.commit().await?;
        Ok(())
    }

    /// Extend the lease of a job running under `fence` (the first statement of a fenced
    /// write, so the transaction holds the write lock from its start). Returns whether
    /// cancellation was asked.
    pub(super) async fn fence_check(
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
            Some(r) => Ok(col::<i64>(&r, "cancel_requested")? != 0),
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
        let p = progress.map(|p| to_json("progress", p)).transpose()?;
        let mut tx = self.pool.begin().await?;
        let row = sqlx::query(
            "UPDATE jobs SET lease_until_ms = ?, progress = COALESCE(?, progress)
             WHERE id = ? AND fence = ? AND status = 'running'
             RETURNING cancel_requested",
        )
        .bind(until)
        .bind(p)
        .bind(id)
        .bind(fence)
        .fetch_optional(&mut *tx)
        .await?;
        tx.commit().await?;
        match row {
            None => Err(StoreError::Fenced),
            Some(r) => Ok(col::<i64>(&r, "cancel_requested")? != 0),
        }
    }

    /// Finish a run (fenced): the job takes the summary's status.
    pub async fn finish(
        &self,
        id: &str,
        fence: i64,
        summary: &Summary,
    ) -> Result<JobRow, StoreError> {
        let status = match summary.status {
            RunStatus::Completed => "completed",
            RunStatus::Failed => "failed",
            RunStatus::Cancelled => "cancelled",
        };
        let mut tx = self.pool.begin().await?;
        let row = sqlx::query(
            "UPDATE jobs SET status = ?, summary = ?, message = ?, worker_id = NULL,
                lease_until_ms = NULL, finished_at = strftime('%Y-%m-%dT%H:%M:%fZ','now')
             WHERE id = ? AND fence = ? AND status = 'running'
             RETURNING *",
        )
        .bind(status)
        .bind(to_json("summary", summary)?)
        .bind(summary.message.clone())
        .bind(id)
        .bind(fence)
        .fetch_optional(&mut *tx)
        .await?;
        tx.commit().await?;
        row.as_ref()
            .map(JobRow::decode)
            .transpose()?
            .ok_or(StoreError::Fenced)
    }

    /// Re-queue (or fail, past the attempt limit; or cancel, if asked) running jobs whose
    /// lease has expired. Returns the changed jobs.
    pub async fn reap(&self, max_attempts: u32) -> Result<Vec<JobRow>, StoreError> {
        let mut tx = self.pool.begin().await?;
        let rows = sqlx::query(
            "UPDATE jobs SET
                status = CASE WHEN cancel_requested != 0 THEN 'cancelled'
                              WHEN attempts >= COALESCE(max_attempts, ?) THEN 'failed' ELSE 'queued' END,
                message = CASE WHEN cancel_requested != 0 THEN 'cancelled (its worker stopped answering)'
                              WHEN attempts >= COALESCE(max_attempts, ?) THEN 'the worker was lost ' || attempts || ' times (lease expired); giving up'
                              ELSE 'the worker was lost (lease expired); re-queued' END,
                finished_at = CASE WHEN cancel_requested != 0 OR attempts >= COALESCE(max_attempts, ?)
                                   THEN strftime('%Y-%m-%dT%H:%M:%fZ','now') ELSE NULL END,
                worker_id = NULL, lease_until_ms = NULL
             WHERE status = 'running' AND lease_until_ms < ?
             RETURNING *",
        )
        .bind(max_attempts as i64)
        .bind(max_attempts as i64)
        .bind(max_attempts as i64)
        .bind(now_ms())
        .fetch_all(&mut *tx)
        .await?;
        tx.commit().await?;
        JobRow::decode_all(&rows)
    }

    /// Release the running jobs of a worker that is known to be dead (a local worker process
    /// that exited; its worker ids start with `worker_prefix`): each is cancelled if that
    /// was asked, failed past `max_attempts` claims or when `deterministic` (it ran out of
    /// memory: it would again), and re-queued otherwise; `cause` (how the process ended,
    /// its last output) goes into the message.
    pub async fn release_worker(
        &self,
        worker_prefix: &str,
        cause: &str,
        max_attempts: u32,
        deterministic: bool,
    ) -> Result<Vec<JobRow>, StoreError> {
        let mut tx = self.pool.begin().await?;
        // Constant text: only the WHERE clause differs between the two releases.
        let sql = format!(
            "{RELEASE} WHERE status = 'running' AND substr(worker_id, 1, length(?4)) = ?4 RETURNING *"
        );
        let rows = sqlx::query(sqlx::AssertSqlSafe(sql))
            .bind(max_attempts as i64)
            .bind(deterministic)
            .bind(cause)
            .bind(worker_prefix)
            .fetch_all(&mut *tx)
            .await?;
        tx.commit().await?;
        JobRow::decode_all(&rows)
    }

    /// Release one claim of a dead worker (reported by a remote worker's supervisor), with
    /// the rules of [`Store::release_worker`]; fenced: [`StoreError::Fenced`] when the job
    /// is no longer running under `fence`.
    pub async fn release_claim(
        &self,
        id: &str,
        fence: i64,
        cause: &str,
        max_attempts: u32,
        deterministic: bool,
    ) -> Result<JobRow, StoreError> {
        let mut tx = self.pool.begin().await?;
        // Constant text: only the WHERE clause differs between the two releases.
        let sql =
            format!("{RELEASE} WHERE status = 'running' AND id = ?4 AND fence = ?5 RETURNING *");
        let row = sqlx::query(sqlx::AssertSqlSafe(sql))
            .bind(max_attempts as i64)
            .bind(deterministic)
            .bind(cause)
            .bind(id)
            .bind(fence)
            .fetch_optional(&mut *tx)
            .await?;
        tx.commit().await?;
        row.as_ref()
            .map(JobRow::decode)
            .transpose()?
            .ok_or(StoreError::Fenced)
    }

    /// A worker hands its claim back (a batch worker stopping before its time limit): the
    /// job returns to the queue without counting the attempt (cancelled instead if that was
    /// asked), with `message`. Fenced: [`StoreError::Fenced`] when the job is no longer
    /// running under `fence`.
    pub async fn hand_back(
        &self,
        id: &str,
        fence: i64,
        message: &str,
    ) -> Result<JobRow, StoreError> {
        let mut tx = self.pool.begin().await?;
        let row = sqlx::query(
            "UPDATE jobs SET
                status = CASE WHEN cancel_requested != 0 THEN 'cancelled' ELSE 'queued' END,
                finished_at = CASE WHEN cancel_requested != 0
                                   THEN strftime('%Y-%m-%dT%H:%M:%fZ','now') ELSE NULL END,
                attempts = MAX(attempts - 1, 0), message = ?,
                worker_id = NULL, lease_until_ms = NULL
             WHERE id = ? AND fence = ? AND status = 'running'
             RETURNING *",
        )
        .bind(message)
        .bind(id)
        .bind(fence)
        .fetch_optional(&mut *tx)
        .await?;
        tx.commit().await?;
        row.as_ref()
            .map(JobRow::decode)
            .transpose()?
            .ok_or(StoreError::Fenced)
    }

    /// Put every running job back in the queue without counting the attempt (shutdown of
    /// this server, or recovery at start). Later writes of their workers are fenced off.
    pub async fn release_running(&self, reason: &str) -> Result<Vec<JobRow>, StoreError> {
        let mut tx = self.pool.begin().await?;
        let rows = sqlx::query(
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
        .fetch_all(&mut *tx)
        .await?;
        tx.commit().await?;
        JobRow::decode_all(&rows)
    }
}
