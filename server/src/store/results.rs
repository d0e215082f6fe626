//! What runs produce, as stored: energy and crack-tip history rows and field snapshots.
//! Every write is fenced ([`Store::fence_check`] is its first statement).
//!
//! SQLite stores a NaN `REAL` as `NULL`, so a `NULL` number of a history row reads back as
//! NaN (the rows' JSON convention too: `fracture_api::nan`; PostgreSQL keeps the NaN);
//! anything else that does not decode is [`StoreError::Corrupt`].

use std::time::Duration;

use fracture_api::jobs::SnapshotInfo;
use fracture_api::results::{CrackTipRow, EnergyRow, Snapshot};
use fracture_results::codec;
use sqlx::QueryBuilder;

use super::{Db, Store, StoreError, StoreRow, Tx, on_db, on_tx, to_json};

/// A nullable `REAL` column: `NULL` is NaN (how SQLite stores it).
fn real(r: &impl StoreRow, name: &str) -> Result<f64, StoreError> {
    Ok(r.opt_real(name)?.unwrap_or(f64::NAN))
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
        let mut tx = self.db.begin().await?;
        Self::fence_check(&mut tx, id, fence, lease).await?;
        for chunk in rows.chunks(100) {
            on_tx!(&mut tx, c, DB => {
            let mut q: QueryBuilder<DB> = QueryBuilder::new(
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
            q.build().execute(c).await?;
            });
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
        let mut tx = self.db.begin().await?;
        Self::fence_check(&mut tx, id, fence, lease).await?;
        for chunk in rows.chunks(50) {
            on_tx!(&mut tx, c, DB => {
            let mut q: QueryBuilder<DB> = QueryBuilder::new(
                "INSERT INTO crack_tips (job_id, time, crack, tip, x, y, length, speed, j1, j2, k1, k2, growing, \
                 j1_half, j2_half, j1_double, j2_double, k1_cod, k2_cod, zone_x, zone_y, connected_x, \
                 connected_y, zone_connected_x, zone_connected_y) ",
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
                    .push_bind(r.zone_y)
                    .push_bind(r.connected_x)
                    .push_bind(r.connected_y)
                    .push_bind(r.zone_connected_x)
                    .push_bind(r.zone_connected_y);
            });
            q.build().execute(c).await?;
            });
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
        let mut tx = self.db.begin().await?;
        Self::fence_check(&mut tx, id, fence, lease).await?;
        on_tx!(&mut tx, c => {
            sqlx::query(
            "INSERT INTO snapshots (job_id, idx, time, fields, data) VALUES ($1, $2, $3, $4, $5)
             ON CONFLICT (job_id, idx) DO UPDATE
             SET time = excluded.time, fields = excluded.fields, data = excluded.data",
        )
        .bind(id)
        .bind(i64::from(snap.index))
        .bind(snap.time)
        .bind(&fields)
        .bind(encoded)
        .execute(c)
        .await?;
        });
        tx.commit().await?;
        Ok(())
    }

    /// Energy rows, optionally only those after `since`.
    pub async fn energy(&self, id: &str, since: Option<f64>) -> Result<Vec<EnergyRow>, StoreError> {
        on_db!(&self.db, c => sqlx::query(
            "SELECT time, kinetic, strain, external_work, dissipated, total_error, fracture FROM energy
             WHERE job_id = $1 AND ($2 IS NULL OR time > $2) ORDER BY rowid",
        )
        .bind(id)
        .bind(since)
        .fetch_all(c)
        .await?
        .iter()
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
        .collect())
    }

    /// Crack-tip rows, optionally only those after `since`.
    pub async fn crack_tips(
        &self,
        id: &str,
        since: Option<f64>,
    ) -> Result<Vec<CrackTipRow>, StoreError> {
        on_db!(&self.db, c => sqlx::query(
            "SELECT time, crack, tip, x, y, length, speed, j1, j2, k1, k2, growing,
                    j1_half, j2_half, j1_double, j2_double, k1_cod, k2_cod, zone_x, zone_y,
                    connected_x, connected_y, zone_connected_x, zone_connected_y
             FROM crack_tips
             WHERE job_id = $1 AND ($2 IS NULL OR time > $2) ORDER BY rowid",
        )
        .bind(id)
        .bind(since)
        .fetch_all(c)
        .await?
        .iter()
        .map(|r| {
            Ok(CrackTipRow {
                time: real(r, "time")?,
                crack: r.u32("crack")?,
                tip: r.u32("tip")?,
                x: real(r, "x")?,
                y: real(r, "y")?,
                length: real(r, "length")?,
                speed: real(r, "speed")?,
                j1: real(r, "j1")?,
                j2: real(r, "j2")?,
                k1: real(r, "k1")?,
                k2: real(r, "k2")?,
                growing: r.int("growing")? != 0,
                j1_half: real(r, "j1_half")?,
                j2_half: real(r, "j2_half")?,
                j1_double: real(r, "j1_double")?,
                j2_double: real(r, "j2_double")?,
                k1_cod: real(r, "k1_cod")?,
                k2_cod: real(r, "k2_cod")?,
                zone_x: real(r, "zone_x")?,
                zone_y: real(r, "zone_y")?,
                connected_x: real(r, "connected_x")?,
                connected_y: real(r, "connected_y")?,
                zone_connected_x: real(r, "zone_connected_x")?,
                zone_connected_y: real(r, "zone_connected_y")?,
            })
        })
        .collect())
    }

    /// Snapshot index entries, in order. The component names (and a 3D run's slice plane)
    /// come from the blobs, decoded off the async threads (a snapshot holds every grid node).
    pub async fn snapshots(&self, id: &str) -> Result<Vec<SnapshotInfo>, StoreError> {
        let rows = on_db!(&self.db, c => sqlx::query(
            "SELECT idx, time, fields, data FROM snapshots WHERE job_id = $1 ORDER BY idx",
        )
        .bind(id)
        .fetch_all(c)
        .await?
        .iter()
        .map(|r| Ok((r.u32("idx")?, r.real("time")?, r.json("fields")?, r.bytes("data")?)))
        .collect::<Result<Vec<_>, StoreError>>()?);
        blocking(move || {
            rows.into_iter()
                .map(|(index, time, fields, data)| {
                    let snap = decode(&data)?;
                    Ok(SnapshotInfo {
                        index,
                        time,
                        fields,
                        components: snap.components.into_iter().map(|c| c.name).collect(),
                        slice: snap.slice,
                    })
                })
                .collect()
        })
        .await
    }

    /// One snapshot (decoded off the async threads).
    pub async fn snapshot(&self, id: &str, index: u32) -> Result<Option<Snapshot>, StoreError> {
        let data = on_db!(&self.db, c => sqlx::query(
            "SELECT data FROM snapshots WHERE job_id = $1 AND idx = $2",
        )
        .bind(id)
        .bind(i64::from(index))
        .fetch_optional(c)
        .await?
        .map(|r| r.bytes("data"))
        .transpose()?);
        match data {
            None => Ok(None),
            Some(data) => blocking(move || decode(&data).map(Some)).await,
        }
    }

    /// Row counts of a job: (energy, crack tips, snapshots) — for tests.
    pub async fn row_counts(&self, id: &str) -> Result<(u64, u64, u64), StoreError> {
        let (e, c, s) = on_db!(&self.db, c => {
            let r = sqlx::query(
                "SELECT (SELECT COUNT(*) FROM energy WHERE job_id = $1) AS e,
                        (SELECT COUNT(*) FROM crack_tips WHERE job_id = $1) AS c,
                        (SELECT COUNT(*) FROM snapshots WHERE job_id = $1) AS s",
            )
            .bind(id)
            .fetch_one(c)
            .await?;
            (r.int("e")?, r.int("c")?, r.int("s")?)
        });
        let g = |v: i64| v.max(0) as u64;
        Ok((g(e), g(c), g(s)))
    }
}
