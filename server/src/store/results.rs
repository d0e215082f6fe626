//! What runs produce, as stored: energy and crack-tip history rows and field snapshots.
//! Every write is fenced ([`Store::fence_check`] is its first statement).
//!
//! SQLite stores a NaN `REAL` as `NULL`, so a `NULL` number of a history row reads back as
//! NaN (the rows' JSON convention too: `fracture_api::nan`); anything else that does not
//! decode is [`StoreError::Corrupt`].

use std::time::Duration;

use fracture_api::jobs::SnapshotInfo;
use fracture_api::results::{CrackTipRow, EnergyRow, Snapshot};
use fracture_results::codec;
use sqlx::sqlite::SqliteRow;
use sqlx::{QueryBuilder, Sqlite};

use super::{Store, StoreError, col, col_u32, json_col, to_json};

/// A nullable `REAL` column: `NULL` is NaN (how SQLite stores it).
fn real(r: &SqliteRow, name: &str) -> Result<f64, StoreError> {
    Ok(col::<Option<f64>>(r, name)?.unwrap_or(f64::NAN))
}

/// Decode a stored snapshot blob.
fn decode(data: &[u8]) -> Result<Snapshot, StoreError> {
    codec::decode_snapshot(data).map_err(|e| StoreError::Corrupt(format!("snapshot: {e}")))
}

/// Run a CPU-bound decode off the async threads.
async fn blocking<T: Send + 'static>(
    f: impl FnOnce() -> Result<T, StoreError> + Send + 'static,
) -> Result<T, StoreError> {
    tokio::task::spawn_blocking(f)
        .await
        .map_err(|e| StoreError::Corrupt(format!("decoding task failed: {e}")))?
}

impl Store {
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
                "INSERT INTO energy (job_id, time, kinetic, strain, external_work, dissipated, total_error, fracture) ",
            );
            q.push_values(chunk, |mut b, r| {
                b.push_bind(id)
                    .push_bind(r.time)
                    .push_bind(r.kinetic)
                    .push_bind(r.strain)
                    .push_bind(r.external_work)
                    .push_bind(r.dissipated)
                    .push_bind(r.total_error)
                    .push_bind(r.fracture);
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
                "INSERT INTO crack_tips (job_id, time, crack, tip, x, y, length, speed, j1, j2, k1, k2, growing, \
                 j1_half, j2_half, j1_double, j2_double, k1_cod, k2_cod, zone_x, zone_y) ",
            );
            q.push_values(chunk, |mut b, r| {
                b.push_bind(id)
                    .push_bind(r.time)
                    .push_bind(i64::from(r.crack))
                    .push_bind(i64::from(r.tip))
                    .push_bind(r.x)
                    .push_bind(r.y)
                    .push_bind(r.length)
                    .push_bind(r.speed)
                    .push_bind(r.j1)
                    .push_bind(r.j2)
                    .push_bind(r.k1)
                    .push_bind(r.k2)
                    .push_bind(i64::from(r.growing))
                    .push_bind(r.j1_half)
                    .push_bind(r.j2_half)
                    .push_bind(r.j1_double)
                    .push_bind(r.j2_double)
                    .push_bind(r.k1_cod)
                    .push_bind(r.k2_cod)
                    .push_bind(r.zone_x)
                    .push_bind(r.zone_y);
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
        let fields = to_json("snapshot fields", &snap.fields)?;
        let mut tx = self.pool.begin().await?;
        Self::fence_check(&mut tx, id, fence, lease).await?;
        sqlx::query(
            "INSERT OR REPLACE INTO snapshots (job_id, idx, time, fields, data) VALUES (?, ?, ?, ?, ?)",
        )
        .bind(id)
        .bind(i64::from(snap.index))
        .bind(snap.time)
        .bind(fields)
        .bind(encoded)
        .execute(&mut *tx)
        .await?;
        tx.commit().await?;
        Ok(())
    }

    /// Energy rows, optionally only those after `since`.
    pub async fn energy(&self, id: &str, since: Option<f64>) -> Result<Vec<EnergyRow>, StoreError> {
        let rows = sqlx::query(
            "SELECT time, kinetic, strain, external_work, dissipated, total_error, fracture FROM energy
             WHERE job_id = ? AND (? IS NULL OR time > ?) ORDER BY rowid",
        )
        .bind(id)
        .bind(since)
        .bind(since)
        .fetch_all(&self.pool)
        .await?;
        rows.iter()
            .map(|r| {
                Ok(EnergyRow {
                    time: real(r, "time")?,
                    kinetic: real(r, "kinetic")?,
                    strain: real(r, "strain")?,
                    external_work: real(r, "external_work")?,
                    dissipated: real(r, "dissipated")?,
                    total_error: real(r, "total_error")?,
                    fracture: real(r, "fracture")?,
                })
            })
            .collect()
    }

    /// Crack-tip rows, optionally only those after `since`.
    pub async fn crack_tips(
        &self,
        id: &str,
        since: Option<f64>,
    ) -> Result<Vec<CrackTipRow>, StoreError> {
        let rows = sqlx::query(
            "SELECT time, crack, tip, x, y, length, speed, j1, j2, k1, k2, growing,
                    j1_half, j2_half, j1_double, j2_double, k1_cod, k2_cod, zone_x, zone_y
             FROM crack_tips
             WHERE job_id = ? AND (? IS NULL OR time > ?) ORDER BY rowid",
        )
        .bind(id)
        .bind(since)
        .bind(since)
        .fetch_all(&self.pool)
        .await?;
        rows.iter()
            .map(|r| {
                Ok(CrackTipRow {
                    time: real(r, "time")?,
                    crack: col_u32(r, "crack")?,
                    tip: col_u32(r, "tip")?,
                    x: real(r, "x")?,
                    y: real(r, "y")?,
                    length: real(r, "length")?,
                    speed: real(r, "speed")?,
                    j1: real(r, "j1")?,
                    j2: real(r, "j2")?,
                    k1: real(r, "k1")?,
                    k2: real(r, "k2")?,
                    growing: col::<i64>(r, "growing")? != 0,
                    j1_half: real(r, "j1_half")?,
                    j2_half: real(r, "j2_half")?,
                    j1_double: real(r, "j1_double")?,
                    j2_double: real(r, "j2_double")?,
                    k1_cod: real(r, "k1_cod")?,
                    k2_cod: real(r, "k2_cod")?,
                    zone_x: real(r, "zone_x")?,
                    zone_y: real(r, "zone_y")?,
                })
            })
            .collect()
    }

    /// Snapshot index entries, in order. The component names come from the blobs, decoded
    /// off the async threads (a snapshot holds every grid node).
    pub async fn snapshots(&self, id: &str) -> Result<Vec<SnapshotInfo>, StoreError> {
        let rows = sqlx::query(
            "SELECT idx, time, fields, data FROM snapshots WHERE job_id = ? ORDER BY idx",
        )
        .bind(id)
        .fetch_all(&self.pool)
        .await?;
        blocking(move || {
            rows.iter()
                .map(|r| {
                    let data: Vec<u8> = col(r, "data")?;
                    Ok(SnapshotInfo {
                        index: col_u32(r, "idx")?,
                        time: col(r, "time")?,
                        fields: json_col(r, "fields")?,
                        components: decode(&data)?
                            .components
                            .into_iter()
                            .map(|c| c.name)
                            .collect(),
                    })
                })
                .collect()
        })
        .await
    }

    /// One snapshot (decoded off the async threads).
    pub async fn snapshot(&self, id: &str, index: u32) -> Result<Option<Snapshot>, StoreError> {
        let row = sqlx::query("SELECT data FROM snapshots WHERE job_id = ? AND idx = ?")
            .bind(id)
            .bind(i64::from(index))
            .fetch_optional(&self.pool)
            .await?;
        match row {
            None => Ok(None),
            Some(r) => {
                let data: Vec<u8> = col(&r, "data")?;
                blocking(move || decode(&data).map(Some)).await
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
        let g = |c: &str| col::<i64>(&r, c).map(|v| v.max(0) as u64);
        Ok((g("e")?, g("c")?, g("s")?))
    }
}
