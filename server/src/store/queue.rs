//! The durable queue: claims (highest priority then oldest), leases extended by heartbeats
//! and fenced writes, fencing tokens raised on every claim, the reaper of expired leases,
//! and the release of running jobs at shutdown.
//!
//! The claim is the one query whose shape differs by backend. SQLite has one writer: one
//! `UPDATE … WHERE seq = (SELECT … LIMIT 1) RETURNING *`. PostgreSQL has many connections
//! claiming at once: the candidate is selected `FOR UPDATE OF q SKIP LOCKED` (a job another
//! claim holds is skipped, not waited for), and when it belongs to a sweep with
//! `max_concurrent` the sweep's row is locked and its running jobs counted again, so two
//! claims never both take the sweep's last free place; then the `UPDATE`, all in one
//! transaction.

use std::time::Duration;

use fracture_api::results::{Progress, RunStatus, Summary};

use super::{
    Backend, JobRow, Store, StoreError, StoreRow, Tx, delete_job_rows, now_ms, now_text, on_tx,
    to_json,
};

/// The release of a dead worker's jobs (`$1` max attempts unless the job has its own, `$2`
/// deterministic, `$3` the cause, `$4` now); the caller adds the `WHERE` clause (from `$5`).
const RELEASE: &str = "UPDATE jobs SET
    status = CASE WHEN cancel_requested != 0 THEN 'cancelled'
                  WHEN $2 OR attempts >= COALESCE(max_attempts, $1) THEN 'failed' ELSE 'queued' END,
    message = CASE WHEN cancel_requested != 0 THEN 'cancelled (its worker died: ' || $3 || ')'
                  WHEN $2 THEN 'the worker running it died: ' || $3
                  WHEN attempts >= COALESCE(max_attempts, $1) THEN 'the worker running it died (attempt ' || attempts || ' of ' || COALESCE(max_attempts, $1) || '; giving up): ' || $3
                  ELSE 're-queued: the worker running it died: ' || $3 END,
    finished_at = CASE WHEN cancel_requested != 0 OR $2 OR attempts >= COALESCE(max_attempts, $1)
                       THEN $4 ELSE NULL END,
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

/// The claim's update of the chosen job (`$1` worker, `$2` lease end, `$3` now); the
/// caller adds the `WHERE` clause.
///
/// The job's message and progress stay: [`Store::rewind_history`], which the claim route
/// runs next, reads them (how far the previous attempt got, and why it stopped) and then
/// clears or rewinds them.
const CLAIM_SET: &str = "UPDATE jobs SET status = 'running', attempts = attempts + 1,
        fence = fence + 1, worker_id = $1, lease_until_ms = $2, started_at = $3";

/// The best claimable job (after the caller's `SELECT` list): queued, not of a sweep that
/// has `max_concurrent` of its jobs running; highest priority, then oldest.
const CANDIDATE: &str = "FROM jobs q LEFT JOIN sweeps s ON s.id = q.sweep_id
     WHERE q.status = 'queued'
       AND (s.max_concurrent IS NULL
            OR (SELECT COUNT(*) FROM jobs r WHERE r.sweep_id = q.sweep_id
                  AND r.status = 'running') < s.max_concurrent)
     ORDER BY q.priority DESC, q.seq ASC LIMIT 1";

/// PostgreSQL: claims retried when the sweep of their candidate filled up meanwhile.
const PG_CLAIM_TRIES: usize = 8;

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
        let now = now_text();
        let job = match self.db.backend() {
            Backend::Sqlite => {
                let mut tx = self.db.begin().await?;
                // Constant text: the update and the candidate query above.
                let sql = format!(
                    "{CLAIM_SET} WHERE seq = (SELECT q.seq {CANDIDATE}) AND status = 'queued'
                     RETURNING *"
                );
                let job = on_tx!(&mut tx, c => sqlx::query(sqlx::AssertSqlSafe(sql))
                    .bind(worker)
                    .bind(until)
                    .bind(&now)
                    .fetch_optional(c)
                    .await?
                    .as_ref()
                    .map(JobRow::decode)
                    .transpose()?);
                tx.commit().await?;
                job
            }
            Backend::Postgres => self.claim_postgres(worker, until, &now).await?,
        };
        Ok(job.map(|job| Claimed { job }))
    }

    /// The claim on PostgreSQL (see the module's documentation).
    async fn claim_postgres(
        &self,
        worker: &str,
        until: i64,
        now: &str,
    ) -> Result<Option<JobRow>, StoreError> {
        let candidate = format!(
            "SELECT q.seq, q.sweep_id, s.max_concurrent {CANDIDATE} FOR UPDATE OF q SKIP LOCKED"
        );
        let update = format!("{CLAIM_SET} WHERE seq = $4 AND status = 'queued' RETURNING *");
        for _ in 0..PG_CLAIM_TRIES {
            let mut tx = self.db.begin().await?;
            // Constant text: the candidate query above.
            let row = on_tx!(&mut tx, c => {
                match sqlx::query(sqlx::AssertSqlSafe(candidate.clone()))
                    .fetch_optional(c)
                    .await?
                {
                    None => None,
                    Some(r) => Some((r.int("seq")?, r.opt_text("sweep_id")?, r.opt_int("max_concurrent")?)),
                }
            });
            let Some((seq, sweep, cap)) = row else {
                return Ok(None);
            };
            if let (Some(sweep), Some(cap)) = (sweep, cap) {
                // Claims of this sweep's jobs wait for each other here; a fresh count sees
                // the jobs the others claimed (READ COMMITTED: each statement its snapshot).
                let running: i64 = on_tx!(&mut tx, c => {
                    sqlx::query("SELECT 1 FROM sweeps WHERE id = $1 FOR UPDATE")
                        .bind(&sweep)
                        .execute(&mut *c)
                        .await?;
                    sqlx::query_scalar(
                        "SELECT COUNT(*) FROM jobs WHERE sweep_id = $1 AND status = 'running'",
                    )
                    .bind(&sweep)
                    .fetch_one(&mut *c)
                    .await?
                });
                if running >= cap {
                    drop(tx); // rolled back: the candidate goes back to the others
                    continue;
                }
            }
            // Constant text: the update above.
            let job = on_tx!(&mut tx, c => sqlx::query(sqlx::AssertSqlSafe(update.clone()))
                .bind(worker)
                .bind(until)
                .bind(now)
                .bind(seq)
                .fetch_optional(c)
                .await?
                .as_ref()
                .map(JobRow::decode)
                .transpose()?);
            tx.commit().await?;
            return Ok(job);
        }
        Ok(None)
    }

    /// The history a new claim under `fence` starts from: the rows and snapshots of earlier
    /// attempts are deleted, all of them, or with a checkpoint to resume from only those
    /// after it (`keep`: rows at times ≤ `time` and snapshots with index < `snapshots`
    /// stay). Fenced. A claim after an earlier attempt (a lost worker, a hand-back) also
    /// rewinds the job's progress to where it resumes and says so in its message
    /// (`restart` of [`Restart`]); that note is returned, `None` for a first attempt.
    pub async fn rewind_history(
        &self,
        id: &str,
        fence: i64,
        lease: Duration,
        keep: Option<HistoryCursor>,
    ) -> Result<Option<Restart>, StoreError> {
        let mut tx = self.db.begin().await?;
        Self::fence_check(&mut tx, id, fence, lease).await?;
        let before = on_tx!(&mut tx, c => sqlx::query(
            "SELECT progress, message, attempts FROM jobs WHERE id = $1",
        )
        .bind(id)
        .fetch_optional(c)
        .await?
        .map(|r| -> Result<_, StoreError> {
            Ok((
                r.opt_json::<Progress>("progress")?,
                r.opt_text("message")?,
                u32::try_from(r.int("attempts")?).unwrap_or(0),
            ))
        })
        .transpose()?);
        let (progress, cause, attempts) = before.unwrap_or((None, None, 0));
        match keep {
            None => delete_job_rows(&mut tx, id).await?,
            Some(k) => {
                on_tx!(&mut tx, c => {
                    for sql in [
                        "DELETE FROM energy WHERE job_id = $1 AND time > $2",
                        "DELETE FROM crack_tips WHERE job_id = $1 AND time > $2",
                    ] {
                        sqlx::query(sql).bind(id).bind(k.time).execute(&mut *c).await?;
                    }
                    sqlx::query("DELETE FROM snapshots WHERE job_id = $1 AND idx >= $2")
                        .bind(id)
                        .bind(i64::from(k.snapshots))
                        .execute(&mut *c)
                        .await?;
                });
            }
        }
        let restart = Restart::after(attempts, progress, cause.as_deref(), keep);
        // A first attempt starts with no message and no progress.
        let (message, p) = match &restart {
            Some(r) => (
                Some(r.message.clone()),
                Some(to_json("progress", &r.progress)?),
            ),
            None => (None, None),
        };
        on_tx!(&mut tx, c => sqlx::query(
            "UPDATE jobs SET message = $1, progress = $2 WHERE id = $3",
        )
        .bind(message)
        .bind(p)
        .bind(id)
        .execute(c)
        .await
        .map(|_| ())?);
        tx.commit().await?;
        Ok(restart)
    }

    /// Extend the lease of a job running under `fence` (the first statement of a fenced
    /// write, so the transaction holds the job's row, and on SQLite the write lock, from
    /// its start). Returns whether cancellation was asked.
    pub(super) async fn fence_check(
        tx: &mut Tx,
        id: &str,
        fence: i64,
        lease: Duration,
    ) -> Result<bool, StoreError> {
        let until = now_ms() + lease.as_millis() as i64;
        let row = on_tx!(tx, c => sqlx::query(
            "UPDATE jobs SET lease_until_ms = CASE WHEN COALESCE(lease_until_ms, 0) > $1
                                                   THEN lease_until_ms ELSE $1 END
             WHERE id = $2 AND fence = $3 AND status = 'running'
             RETURNING cancel_requested",
        )
        .bind(until)
        .bind(id)
        .bind(fence)
        .fetch_optional(c)
        .await?
        .map(|r| r.int("cancel_requested"))
        .transpose()?);
        match row {
            None => Err(StoreError::Fenced),
            Some(c) => Ok(c != 0),
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
        let mut tx = self.db.begin().await?;
        let row = on_tx!(&mut tx, c => sqlx::query(
            "UPDATE jobs SET lease_until_ms = $1, progress = COALESCE($2, progress)
             WHERE id = $3 AND fence = $4 AND status = 'running'
             RETURNING cancel_requested",
        )
        .bind(until)
        .bind(p)
        .bind(id)
        .bind(fence)
        .fetch_optional(c)
        .await?
        .map(|r| r.int("cancel_requested"))
        .transpose()?);
        tx.commit().await?;
        match row {
            None => Err(StoreError::Fenced),
            Some(c) => Ok(c != 0),
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
        let summary_json = to_json("summary", summary)?;
        let now = now_text();
        let mut tx = self.db.begin().await?;
        let row = on_tx!(&mut tx, c => sqlx::query(
            "UPDATE jobs SET status = $1, summary = $2, message = $3, worker_id = NULL,
                lease_until_ms = NULL, finished_at = $4
             WHERE id = $5 AND fence = $6 AND status = 'running'
             RETURNING *",
        )
        .bind(status)
        .bind(&summary_json)
        .bind(summary.message.clone())
        .bind(&now)
        .bind(id)
        .bind(fence)
        .fetch_optional(c)
        .await?
        .as_ref()
        .map(JobRow::decode)
        .transpose()?);
        tx.commit().await?;
        row.ok_or(StoreError::Fenced)
    }

    /// Re-queue (or fail, past the attempt limit; or cancel, if asked) running jobs whose
    /// lease has expired. Returns the changed jobs.
    pub async fn reap(&self, max_attempts: u32) -> Result<Vec<JobRow>, StoreError> {
        let now = now_text();
        let mut tx = self.db.begin().await?;
        let rows = on_tx!(&mut tx, c => JobRow::decode_all(&sqlx::query(
            "UPDATE jobs SET
                status = CASE WHEN cancel_requested != 0 THEN 'cancelled'
                              WHEN attempts >= COALESCE(max_attempts, $1) THEN 'failed' ELSE 'queued' END,
                message = CASE WHEN cancel_requested != 0 THEN 'cancelled (its worker stopped answering)'
                              WHEN attempts >= COALESCE(max_attempts, $1) THEN 'the worker was lost ' || attempts || ' times (lease expired); giving up'
                              ELSE 'the worker was lost (lease expired); re-queued' END,
                finished_at = CASE WHEN cancel_requested != 0 OR attempts >= COALESCE(max_attempts, $1)
                                   THEN $3 ELSE NULL END,
                worker_id = NULL, lease_until_ms = NULL
             WHERE status = 'running' AND lease_until_ms < $2
             RETURNING *",
        )
        .bind(max_attempts as i64)
        .bind(now_ms())
        .bind(&now)
        .fetch_all(c)
        .await?)?);
        tx.commit().await?;
        Ok(rows)
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
        let now = now_text();
        let mut tx = self.db.begin().await?;
        // Constant text: only the WHERE clause differs between the two releases.
        let sql = format!(
            "{RELEASE} WHERE status = 'running' AND substr(worker_id, 1, length($5)) = $5 RETURNING *"
        );
        let rows = on_tx!(&mut tx, c => JobRow::decode_all(
            &sqlx::query(sqlx::AssertSqlSafe(sql))
                .bind(max_attempts as i64)
                .bind(deterministic)
                .bind(cause)
                .bind(&now)
                .bind(worker_prefix)
                .fetch_all(c)
                .await?,
        )?);
        tx.commit().await?;
        Ok(rows)
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
        let now = now_text();
        let mut tx = self.db.begin().await?;
        // Constant text: only the WHERE clause differs between the two releases.
        let sql =
            format!("{RELEASE} WHERE status = 'running' AND id = $5 AND fence = $6 RETURNING *");
        let row = on_tx!(&mut tx, c => sqlx::query(sqlx::AssertSqlSafe(sql))
            .bind(max_attempts as i64)
            .bind(deterministic)
            .bind(cause)
            .bind(&now)
            .bind(id)
            .bind(fence)
            .fetch_optional(c)
            .await?
            .as_ref()
            .map(JobRow::decode)
            .transpose()?);
        tx.commit().await?;
        row.ok_or(StoreError::Fenced)
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
        let now = now_text();
        let mut tx = self.db.begin().await?;
        let job = on_tx!(&mut tx, c => sqlx::query(
            "UPDATE jobs SET
                status = CASE WHEN cancel_requested != 0 THEN 'cancelled' ELSE 'queued' END,
                finished_at = CASE WHEN cancel_requested != 0 THEN $4 ELSE NULL END,
                attempts = CASE WHEN attempts > 0 THEN attempts - 1 ELSE 0 END, message = $1,
                worker_id = NULL, lease_until_ms = NULL
             WHERE id = $2 AND fence = $3 AND status = 'running'
             RETURNING *",
        )
        .bind(message)
        .bind(id)
        .bind(fence)
        .bind(&now)
        .fetch_optional(c)
        .await?
        .as_ref()
        .map(JobRow::decode)
        .transpose()?);
        tx.commit().await?;
        job.ok_or(StoreError::Fenced)
    }

    /// Put every running job back in the queue without counting the attempt (shutdown of
    /// this server, or recovery at start). Later writes of their workers are fenced off.
    pub async fn release_running(&self, reason: &str) -> Result<Vec<JobRow>, StoreError> {
        let now = now_text();
        let mut tx = self.db.begin().await?;
        let rows = on_tx!(&mut tx, c => JobRow::decode_all(&sqlx::query(
            "UPDATE jobs SET
                status = CASE WHEN cancel_requested != 0 THEN 'cancelled' ELSE 'queued' END,
                finished_at = CASE WHEN cancel_requested != 0 THEN $2 ELSE NULL END,
                attempts = CASE WHEN attempts > 0 THEN attempts - 1 ELSE 0 END, message = $1,
                worker_id = NULL, lease_until_ms = NULL
             WHERE status = 'running'
             RETURNING *",
        )
        .bind(reason)
        .bind(&now)
        .fetch_all(c)
        .await?)?);
        tx.commit().await?;
        Ok(rows)
    }
}

/// Where a job's new attempt starts, after an earlier one ended unfinished: the progress it
/// resumes at, and a message that says so (the job's `message` and the `restart` event).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Restart {
    /// The attempt starting (2 for the first restart).
    pub attempt: u32,
    /// The progress it starts from (the checkpoint's; 0 without one).
    pub progress: Progress,
    /// Where it resumes from, how far the previous attempt got, and why it stopped.
    pub message: String,
}

impl Restart {
    /// The restart of attempt `attempt` (after the claim's increment; `None` for a first
    /// attempt that starts from nothing),
    /// whose previous attempt reached `before` with `cause` as the job's message, resuming
    /// from `keep` (from the start without one).
    pub fn after(
        attempt: u32,
        before: Option<Progress>,
        cause: Option<&str>,
        keep: Option<HistoryCursor>,
    ) -> Option<Restart> {
        if attempt < 2 && keep.is_none() {
            return None;
        }
        let end = before.map_or(f64::NAN, |p| p.end_time);
        let pct = |f: f64| format!("{:.0} %", 100.0 * f);
        let (progress, from) = match keep {
            Some(k) => {
                let fraction = if end > 0.0 && k.time.is_finite() {
                    (k.time / end).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                (
                    Progress {
                        step: k.step,
                        sim_time: k.time,
                        end_time: if end.is_finite() { end } else { 0.0 },
                        fraction,
                    },
                    format!(
                        "resumed from its checkpoint at step {} (t = {:e} s{})",
                        k.step,
                        k.time,
                        if end > 0.0 {
                            format!(", {} of the end time", pct(fraction))
                        } else {
                            String::new()
                        }
                    ),
                )
            }
            None => (
                Progress {
                    end_time: if end.is_finite() { end } else { 0.0 },
                    ..Progress::default()
                },
                "restarted from the beginning (no checkpoint)".to_string(),
            ),
        };
        let reached = before.map_or(String::new(), |p| {
            format!(" after the previous attempt stopped at {}", pct(p.fraction))
        });
        // A previous restart note is not a cause; the release's reason is.
        let why = cause
            .filter(|c| !c.is_empty() && !c.starts_with("attempt ") && !c.starts_with("resumed "))
            .map_or(String::new(), |c| format!(" ({c})"));
        Some(Restart {
            attempt,
            progress,
            message: format!("attempt {attempt}: {from}{reached}{why}"),
        })
    }
}
