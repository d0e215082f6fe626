//! The store: SQLite (embedded, the default) or PostgreSQL (`--database postgres://…`); the
//! server is its only writer.
//!
//! * [`Store`]: the database ([`Store::open`]: a SQLite file, one connection in EXCLUSIVE
//!   locking mode, so the WAL index lives in heap memory and no file is mapped into the
//!   process; [`Store::open_postgres`]: a pool of connections and a session lock that makes
//!   this server the database's only one), the embedded numbered migrations of each
//!   (`server/migrations/`, `server/migrations-postgres/`, never edited after they land),
//!   [`StoreError`].
//! * `jobs`: job rows ([`JobRow`]), creation, lists, cancellation, deletion.
//! * `queue`: the durable queue: claims (SQLite: one `UPDATE … RETURNING`; PostgreSQL:
//!   `SELECT … FOR UPDATE SKIP LOCKED` then the `UPDATE`, in one transaction), leases,
//!   heartbeats, fencing tokens, the reaper, release at shutdown.
//! * `results`: history rows (energy, crack tips) and snapshots, all fenced writes.
//! * `sweeps`: sweep rows and their jobs.
//!
//! # Two backends, one query each
//!
//! `Db` holds the pool of either backend and `Tx` a transaction of either. A query is
//! written **once** with `$1`, `$2`, … placeholders (SQLite reads `$N` as the N-th bound
//! value, as PostgreSQL does) in the SQL both understand, and run with `on_db!` (on the
//! pool) or `on_tx!` (inside a transaction). These expand their body once per backend,
//! with the connection of that backend, so the same `.bind(…)` chain and the same row
//! decoding (`StoreRow`) serve both:
//!
//! ```ignore
//! pub async fn get(&self, id: &str) -> Result<Option<JobRow>, StoreError> {
//!     on_db!(&self.db, c => sqlx::query("SELECT * FROM jobs WHERE id = $1")
//!         .bind(id)
//!         .fetch_optional(c)
//!         .await?
//!         .as_ref()
//!         .map(JobRow::decode)
//!         .transpose())
//! }
//! ```
//!
//! Where the dialects differ (JSON functions, `FOR UPDATE SKIP LOCKED`), the two texts
//! are given side by side and picked by the backend: `self.db.backend().pick(SQLITE,
//! POSTGRES)`. Portable SQL: times are bound from Rust (`now_text`) rather than read from
//! the database's clock; `CASE` instead of the two-argument `MAX`; `COUNT(*) FILTER
//! (WHERE …)`; `INSERT … ON CONFLICT … DO UPDATE`; every integer column is `BIGINT` in
//! PostgreSQL (decoded as `i64` by both), every real `DOUBLE PRECISION`, JSON stays
//! `TEXT`, and the history tables have a `rowid` column in PostgreSQL so the same
//! `ORDER BY rowid` reads rows in insertion order. Bind only types both encode (`i64`,
//! `f64`, `bool`, text, bytes, and `Option`s of them; no unsigned integers).
//!
//! A new migration goes into both folders under the same number (the PostgreSQL folder
//! starts with the schema of SQLite's 0001–0008 in one file); `tests/store.rs` runs every
//! store test on both backends.
//!
//! # Writes
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
use std::sync::Arc;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use serde::de::DeserializeOwned;
use sqlx::postgres::{PgConnectOptions, PgConnection, PgPool, PgPoolOptions, PgRow};
use sqlx::sqlite::{
    SqliteConnectOptions, SqliteJournalMode, SqliteLockingMode, SqlitePoolOptions, SqliteRow,
    SqliteSynchronous,
};
use sqlx::{Connection, Postgres, Row, Sqlite, SqlitePool};

mod jobs;
mod queue;
mod results;
mod sweeps;

pub use jobs::{JobRow, ListFilter, NewJob, RunningJob, StoreMetrics};
pub use queue::{Claimed, HistoryCursor, Restart};
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
    /// Another fracture server holds the database (PostgreSQL: its session lock).
    #[error("{0}")]
    InUse(String),
}

/// Milliseconds since the Unix epoch.
pub fn now_ms() -> i64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_millis() as i64)
        .unwrap_or(0)
}

pub use fracture_api::clock::{now_text, parse_time_text, time_text};

/// Which database a store runs on (and so which SQL dialect a query is written in).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Backend {
    /// The embedded SQLite file.
    Sqlite,
    /// A PostgreSQL server.
    Postgres,
}

impl Backend {
    /// The SQL text of this backend, where the two dialects differ.
    pub fn pick(self, sqlite: &'static str, postgres: &'static str) -> &'static str {
        match self {
            Backend::Sqlite => sqlite,
            Backend::Postgres => postgres,
        }
    }
}

/// The pool of either backend.
#[derive(Debug, Clone)]
enum Db {
    Sqlite(SqlitePool),
    Postgres(PgPool),
}

/// A transaction of either backend.
enum Tx {
    Sqlite(sqlx::Transaction<'static, Sqlite>),
    Postgres(sqlx::Transaction<'static, Postgres>),
}

/// Run `$body` once per backend with `$c` the backend's pool (`&Pool<DB>`, an executor).
/// `$c, $DB => …` also names the backend's `sqlx::Database` type (for `QueryBuilder`).
macro_rules! on_db {
    ($db:expr, $c:ident => $body:expr) => {
        on_db!($db, $c, _DB => $body)
    };
    ($db:expr, $c:ident, $DB:ident => $body:expr) => {
        match $db {
            Db::Sqlite($c) => {
                #[allow(dead_code)]
                type $DB = sqlx::Sqlite;
                $body
            }
            Db::Postgres($c) => {
                #[allow(dead_code)]
                type $DB = sqlx::Postgres;
                $body
            }
        }
    };
}

/// Run `$body` once per backend with `$c` the transaction's connection
/// (`&mut <DB as Database>::Connection`: pass it as `&mut *c` to run more than one
/// statement). `$c, $DB => …` also names the backend's `sqlx::Database` type.
macro_rules! on_tx {
    ($tx:expr, $c:ident => $body:expr) => {
        on_tx!($tx, $c, _DB => $body)
    };
    ($tx:expr, $c:ident, $DB:ident => $body:expr) => {
        match $tx {
            Tx::Sqlite(t) => {
                #[allow(dead_code)]
                type $DB = sqlx::Sqlite;
                let $c = &mut **t;
                $body
            }
            Tx::Postgres(t) => {
                #[allow(dead_code)]
                type $DB = sqlx::Postgres;
                let $c = &mut **t;
                $body
            }
        }
    };
}
pub(crate) use {on_db, on_tx};

impl Db {
    fn backend(&self) -> Backend {
        match self {
            Db::Sqlite(_) => Backend::Sqlite,
            Db::Postgres(_) => Backend::Postgres,
        }
    }

    async fn begin(&self) -> Result<Tx, StoreError> {
        Ok(match self {
            Db::Sqlite(p) => Tx::Sqlite(p.begin().await?),
            Db::Postgres(p) => Tx::Postgres(p.begin().await?),
        })
    }
}

impl Tx {
    fn backend(&self) -> Backend {
        match self {
            Tx::Sqlite(_) => Backend::Sqlite,
            Tx::Postgres(_) => Backend::Postgres,
        }
    }

    async fn commit(self) -> Result<(), StoreError> {
        match self {
            Tx::Sqlite(t) => t.commit().await?,
            Tx::Postgres(t) => t.commit().await?,
        }
        Ok(())
    }
}

/// The key of the session-level advisory lock a server holds on its PostgreSQL database
/// (the bytes of "fracture"): one server per database, as one per data folder.
const PG_LOCK_KEY: i64 = 0x6672_6163_7475_7265;

/// Connections of the PostgreSQL pool.
const PG_CONNECTIONS: u32 = 10;

/// Handle to the database (cheap to clone).
#[derive(Debug, Clone)]
pub struct Store {
    db: Db,
    /// PostgreSQL: the connection holding the database's session lock ([`PG_LOCK_KEY`]).
    lock: Option<Arc<tokio::sync::Mutex<Option<PgConnection>>>>,
}

impl Store {
    /// Open (creating if needed) the SQLite database file and run the embedded migrations.
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
        Ok(Store {
            db: Db::Sqlite(pool),
            lock: None,
        })
    }

    /// Connect to the PostgreSQL database at `url` (`postgres://user[:password]@host[:port]/db`),
    /// take its session lock (another server on the same database is
    /// [`StoreError::InUse`]) and run the embedded migrations.
    pub async fn open_postgres(url: &str) -> Result<Store, StoreError> {
        let opts = PgConnectOptions::from_str(url)?;
        // The lock first, on a connection of its own: nothing is migrated or re-queued
        // under another server.
        let mut lock = PgConnection::connect_with(&opts).await?;
        let got: bool = sqlx::query_scalar("SELECT pg_try_advisory_lock($1)")
            .bind(PG_LOCK_KEY)
            .fetch_one(&mut lock)
            .await?;
        if !got {
            let holder: Option<String> = sqlx::query_scalar(
                "SELECT COALESCE(a.application_name, '') || ' (pid ' || a.pid || ', from ' \
                        || COALESCE(host(a.client_addr), 'a local socket') || ')'
                 FROM pg_locks l JOIN pg_stat_activity a ON a.pid = l.pid
                 WHERE l.locktype = 'advisory' AND l.granted
                   AND l.database = (SELECT oid FROM pg_database WHERE datname = current_database())
                   AND ((l.classid::bigint << 32) | l.objid::bigint) = $1
                 LIMIT 1",
            )
            .bind(PG_LOCK_KEY)
            .fetch_optional(&mut lock)
            .await
            .ok()
            .flatten();
            let _ = lock.close().await;
            return Err(StoreError::InUse(format!(
                "the PostgreSQL database is in use by another fracture server{}; stop it \
                 first or choose another database",
                holder.map(|h| format!(": session {h}")).unwrap_or_default()
            )));
        }
        let pool = PgPoolOptions::new()
            .max_connections(PG_CONNECTIONS)
            .acquire_timeout(Duration::from_secs(10))
            .connect_with(opts)
            .await?;
        sqlx::migrate!("./migrations-postgres").run(&pool).await?;
        Ok(Store {
            db: Db::Postgres(pool),
            lock: Some(Arc::new(tokio::sync::Mutex::new(Some(lock)))),
        })
    }

    /// The database this store runs on.
    pub fn backend(&self) -> Backend {
        self.db.backend()
    }

    /// Close the pool (waits for connections to be returned) and release the database's
    /// lock.
    pub async fn close(&self) {
        match &self.db {
            Db::Sqlite(p) => p.close().await,
            Db::Postgres(p) => p.close().await,
        }
        if let Some(lock) = &self.lock
            && let Some(mut conn) = lock.lock().await.take()
        {
            // Unlock explicitly: closing the connection only asks the backend to exit, and
            // PostgreSQL drops a session lock when that process ends, some time after the
            // client returns (a server restarted at once was refused as "in use"). The
            // unlock's reply comes after the lock is released.
            if let Err(e) = sqlx::query_scalar::<_, bool>("SELECT pg_advisory_unlock($1)")
                .bind(PG_LOCK_KEY)
                .fetch_one(&mut conn)
                .await
            {
                tracing::warn!("releasing the PostgreSQL database lock failed: {e}");
            }
            let _ = conn.close().await;
        }
    }

    /// The ids of every stored job (for the sweep of orphaned result folders at start).
    pub async fn job_ids(&self) -> Result<std::collections::HashSet<String>, StoreError> {
        let ids: Vec<String> = on_db!(&self.db, c => sqlx::query_scalar("SELECT id FROM jobs")
            .fetch_all(c)
            .await?);
        Ok(ids.into_iter().collect())
    }

    /// The SQLite pool, for tests and fault injection (e.g. `PRAGMA max_page_count`);
    /// `None` on PostgreSQL.
    #[doc(hidden)]
    pub fn sqlite_pool(&self) -> Option<&SqlitePool> {
        match &self.db {
            Db::Sqlite(p) => Some(p),
            Db::Postgres(_) => None,
        }
    }

    /// The PostgreSQL pool, for tests; `None` on SQLite.
    #[doc(hidden)]
    pub fn postgres_pool(&self) -> Option<&PgPool> {
        match &self.db {
            Db::Sqlite(_) => None,
            Db::Postgres(p) => Some(p),
        }
    }
}

/// A row of either backend, decoded by column name into the types the schema uses; a
/// missing column or a value of another type is [`StoreError::Corrupt`] naming it.
trait StoreRow {
    fn int(&self, name: &str) -> Result<i64, StoreError>;
    fn opt_int(&self, name: &str) -> Result<Option<i64>, StoreError>;
    fn real(&self, name: &str) -> Result<f64, StoreError>;
    fn opt_real(&self, name: &str) -> Result<Option<f64>, StoreError>;
    fn text(&self, name: &str) -> Result<String, StoreError>;
    fn opt_text(&self, name: &str) -> Result<Option<String>, StoreError>;
    fn bytes(&self, name: &str) -> Result<Vec<u8>, StoreError>;

    /// A non-negative integer column as a `u32`.
    fn u32(&self, name: &str) -> Result<u32, StoreError> {
        let v = self.int(name)?;
        u32::try_from(v)
            .map_err(|_| StoreError::Corrupt(format!("column `{name}`: {v} is not a u32")))
    }

    /// A nullable non-negative integer column as a `u32`.
    fn opt_u32(&self, name: &str) -> Result<Option<u32>, StoreError> {
        self.opt_int(name)?
            .map(|v| {
                u32::try_from(v)
                    .map_err(|_| StoreError::Corrupt(format!("column `{name}`: {v} is not a u32")))
            })
            .transpose()
    }

    /// A JSON text column, decoded.
    fn json<T: DeserializeOwned>(&self, name: &str) -> Result<T, StoreError> {
        from_json(name, &self.text(name)?)
    }

    /// A nullable JSON text column, decoded (`NULL` is `None`).
    fn opt_json<T: DeserializeOwned>(&self, name: &str) -> Result<Option<T>, StoreError> {
        self.opt_text(name)?
            .as_deref()
            .map(|t| from_json(name, t))
            .transpose()
    }
}

/// [`StoreRow`] for a backend's row type.
macro_rules! store_row {
    ($row:ty) => {
        impl StoreRow for $row {
            fn int(&self, name: &str) -> Result<i64, StoreError> {
                get(self, name)
            }
            fn opt_int(&self, name: &str) -> Result<Option<i64>, StoreError> {
                get(self, name)
            }
            fn real(&self, name: &str) -> Result<f64, StoreError> {
                get(self, name)
            }
            fn opt_real(&self, name: &str) -> Result<Option<f64>, StoreError> {
                get(self, name)
            }
            fn text(&self, name: &str) -> Result<String, StoreError> {
                get(self, name)
            }
            fn opt_text(&self, name: &str) -> Result<Option<String>, StoreError> {
                get(self, name)
            }
            fn bytes(&self, name: &str) -> Result<Vec<u8>, StoreError> {
                get(self, name)
            }
        }
    };
}
store_row!(SqliteRow);
store_row!(PgRow);

/// Column `name` of `row` as a `T`.
fn get<'r, R, T>(row: &'r R, name: &str) -> Result<T, StoreError>
where
    R: Row,
    for<'a> &'a str: sqlx::ColumnIndex<R>,
    T: sqlx::Decode<'r, R::Database> + sqlx::Type<R::Database>,
{
    row.try_get::<T, _>(name)
        .map_err(|e| StoreError::Corrupt(format!("column `{name}`: {e}")))
}

/// Parse the JSON text `text` of column `name`.
fn from_json<T: DeserializeOwned>(name: &str, text: &str) -> Result<T, StoreError> {
    serde_json::from_str(text)
        .map_err(|e| StoreError::Corrupt(format!("column `{name}` is not the expected JSON: {e}")))
}

/// Encode a value as JSON text for a column (our own types always encode).
fn to_json<T: serde::Serialize>(what: &str, v: &T) -> Result<String, StoreError> {
    serde_json::to_string(v).map_err(|e| StoreError::Corrupt(format!("{what}: {e}")))
}

/// Delete a job's history rows and snapshots (a new attempt or a deletion).
async fn delete_job_rows(tx: &mut Tx, id: &str) -> Result<(), StoreError> {
    for sql in [
        "DELETE FROM energy WHERE job_id = $1",
        "DELETE FROM crack_tips WHERE job_id = $1",
        "DELETE FROM snapshots WHERE job_id = $1",
    ] {
        on_tx!(tx, c => {
            sqlx::query(sql).bind(id).execute(c).await?;
        });
    }
    Ok(())
}
