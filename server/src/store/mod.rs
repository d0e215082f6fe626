//! The SQLite store: the server is its only writer.
//!
//! * [`Store`]: the pool (one connection in SQLite's EXCLUSIVE locking mode, so the WAL index
//!   lives in heap memory: no file is mapped into the process), [`Store::open`] with the
//!   embedded numbered migrations
//!   (`server/migrations/`, never edited after they land), [`StoreError`].
//! * `jobs`: job rows ([`JobRow`]), creation, lists, cancellation, deletion.
//! * `queue`: the durable queue: claim with one `UPDATE … RETURNING`, leases, heartbeats,
//!   fencing tokens, the reaper, release at shutdown.
//! * `results`: history rows (energy, crack tips) and snapshots, all fenced writes.
//! * `sweeps`: sweep rows and their jobs.
//!
//! Every write is one statement or one transaction, and no connection goes back to the pool
//! with a transaction open ([`Store::open`]): after a failed `COMMIT` (a full disk, an I/O
//! error) SQLite may keep the transaction or roll it back behind sqlx's back, and a pooled
//! connection left inside one would hold the write lock (every other writer: "database is
//! locked") and swallow later autocommit writes that are never committed. Such a
//! connection is rolled back, and closed when that fails or when it can no longer begin a
//! transaction (after an I/O error). A write with `RETURNING` runs in an explicit
//! transaction: in autocommit mode SQLite commits such a statement when it is reset after
//! its first row is read, and a commit that fails there (a full disk) never reaches the
//! caller, who already has the row — the server answered 201 for jobs that were never
//! stored. With `COMMIT` as its own statement, its failure is the request's error.
//!
//! Every write a worker makes is fenced: it names the fence of its claim, and the write
//! happens only while the job is `running` under that fence. Rows are decoded with typed
//! columns: a column that does not decode is a [`StoreError::Corrupt`] naming it, never a
//! silent default.

use std::path::Path;
use std::str::FromStr;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use serde::de::DeserializeOwned;
use sqlx::sqlite::{
    SqliteConnectOptions, SqliteJournalMode, SqliteLockingMode, SqlitePoolOptions, SqliteRow,
    SqliteSynchronous,
};
use sqlx::{Connection, Row, Sqlite, SqlitePool};

mod jobs;
mod queue;
mod results;
mod sweeps;

pub use jobs::{JobRow, ListFilter, NewJob, RunningJob, StoreMetrics};
pub use queue::{Claimed, HistoryCursor};
pub use sweeps::{NewSweep, NewSweepJob, SweepRow};

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

/// Every timestamp is SQLite's UTC clock in RFC 3339 with milliseconds (this expression).
pub const TIMESTAMP_SQL: &str = "strftime('%Y-%m-%dT%H:%M:%fZ','now')";

/// Handle to the database (cheap to clone).
#[derive(Debug, Clone)]
pub struct Store {
    pool: SqlitePool,
}

impl Store {
    /// Open (creating if needed) the database file and run the embedded migrations.
    pub async fn open(path: &Path) -> Result<Store, StoreError> {
        // EXCLUSIVE locking before WAL: SQLite keeps the WAL index in heap memory instead of
        // a shared-memory file (`fracture.db-shm`) mapped into the process. A mapped file
        // turns a data folder whose files become unwritable under it (`chattr +i`, a file
        // system that fails) into SIGBUS, a crash of the server, at the next write to a page
        // the kernel had written back; with no mapping such writes are I/O errors (507).
        // Safe because one server process owns the folder (its lock) and the pool has one
        // connection, which holds the database's lock.
        let opts = SqliteConnectOptions::from_str("sqlite://")?
            .filename(path)
            .create_if_missing(true)
            .locking_mode(SqliteLockingMode::Exclusive)
            .journal_mode(SqliteJournalMode::Wal)
            .synchronous(SqliteSynchronous::Normal)
            .busy_timeout(Duration::from_secs(15))
            .foreign_keys(true);
        let pool = SqlitePoolOptions::new()
            .max_connections(1)
            .acquire_timeout(Duration::from_secs(10))
            .after_release(|conn, _| {
                Box::pin(async move {
                    // `ROLLBACK` succeeds only inside a transaction: none may be open here.
                    let was_open = sqlx::raw_sql("ROLLBACK").execute(&mut *conn).await.is_ok();
                    if conn.is_in_transaction() {
                        tracing::warn!(
                            "a store connection came back inside a transaction that does not \
                             roll back; closed"
                        );
                        return Ok(false);
                    }
                    if was_open {
                        tracing::warn!(
                            "a store connection came back inside a transaction (after a failed \
                             commit?); rolled back"
                        );
                    }
                    // A connection that can no longer read or begin a write is closed, so
                    // the next request gets a fresh one. It is kept otherwise, also after an
                    // I/O error: while the data files are unwritable a fresh connection
                    // cannot take the file's lock at all (reads would fail too), the open
                    // one still reads. No I/O here in EXCLUSIVE mode: the lock is held and
                    // the WAL index is in memory.
                    let healthy = sqlx::raw_sql(
                        "BEGIN IMMEDIATE; SELECT count(*) FROM sqlite_master; ROLLBACK",
                    )
                    .execute(&mut *conn)
                    .await
                    .is_ok();
                    if !healthy {
                        let _ = sqlx::raw_sql("ROLLBACK").execute(&mut *conn).await;
                        tracing::warn!("a store connection failed its health check; closed");
                        return Ok(false);
                    }
                    Ok(true)
                })
            })
            .connect_with(opts)
            .await?;
        sqlx::migrate!("./migrations").run(&pool).await?;
        Ok(Store { pool })
    }

    /// Close the pool (waits for connections to be returned).
    pub async fn close(&self) {
        self.pool.close().await;
    }

    /// The ids of every stored job (for the sweep of orphaned result folders at start).
    pub async fn job_ids(&self) -> Result<std::collections::HashSet<String>, StoreError> {
        let ids: Vec<String> = sqlx::query_scalar("SELECT id FROM jobs")
            .fetch_all(&self.pool)
            .await?;
        Ok(ids.into_iter().collect())
    }

    /// A raw handle for tests and fault injection (e.g. `PRAGMA max_page_count`).
    #[doc(hidden)]
    pub fn pool(&self) -> &SqlitePool {
        &self.pool
    }
}

/// Column `name` of `row` as a `T`; a missing column or a value of another type is
/// [`StoreError::Corrupt`].
fn col<'r, T>(row: &'r SqliteRow, name: &str) -> Result<T, StoreError>
where
    T: sqlx::Decode<'r, Sqlite> + sqlx::Type<Sqlite>,
{
    row.try_get::<T, _>(name)
        .map_err(|e| StoreError::Corrupt(format!("column `{name}`: {e}")))
}

/// A non-negative integer column as a `u32`.
fn col_u32(row: &SqliteRow, name: &str) -> Result<u32, StoreError> {
    let v: i64 = col(row, name)?;
    u32::try_from(v).map_err(|_| StoreError::Corrupt(format!("column `{name}`: {v} is not a u32")))
}

/// Parse the JSON text `text` of column `name`.
fn from_json<T: DeserializeOwned>(name: &str, text: &str) -> Result<T, StoreError> {
    serde_json::from_str(text)
        .map_err(|e| StoreError::Corrupt(format!("column `{name}` is not the expected JSON: {e}")))
}

/// A JSON text column, decoded.
fn json_col<T: DeserializeOwned>(row: &SqliteRow, name: &str) -> Result<T, StoreError> {
    let text: String = col(row, name)?;
    from_json(name, &text)
}

/// A nullable JSON text column, decoded (`NULL` is `None`).
fn opt_json_col<T: DeserializeOwned>(row: &SqliteRow, name: &str) -> Result<Option<T>, StoreError> {
    let text: Option<String> = col(row, name)?;
    text.as_deref().map(|t| from_json(name, t)).transpose()
}

/// Encode a value as JSON text for a column (our own types always encode).
fn to_json<T: serde::Serialize>(what: &str, v: &T) -> Result<String, StoreError> {
    serde_json::to_string(v).map_err(|e| StoreError::Corrupt(format!("{what}: {e}")))
}

/// Delete a job's history rows and snapshots (a new attempt or a deletion).
async fn delete_job_rows(conn: &mut sqlx::SqliteConnection, id: &str) -> Result<(), StoreError> {
    for sql in [
        "DELETE FROM energy WHERE job_id = ?",
        "DELETE FROM crack_tips WHERE job_id = ?",
        "DELETE FROM snapshots WHERE job_id = ?",
    ] {
        sqlx::query(sql).bind(id).execute(&mut *conn).await?;
    }
    Ok(())
}
