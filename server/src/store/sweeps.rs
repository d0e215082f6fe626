//! Sweep rows: a base scene and its parameters; the sweep's jobs are job rows with
//! `sweep_id`, `sweep_index`, `sweep_label` and `sweep_values` set, inserted with the sweep
//! in one transaction.

use std::collections::BTreeMap;

use fracture_api::sweep::SweepParameter;
use sqlx::sqlite::SqliteRow;

use super::jobs::insert_job;
use super::{
    JobRow, NewJob, Store, StoreError, col, delete_job_rows, from_json, json_col, to_json,
};

/// A sweep as stored, decoded.
#[derive(Debug, Clone)]
pub struct SweepRow {
    /// Insertion order (cursor of lists).
    pub seq: i64,
    /// Sweep id.
    pub id: String,
    /// Name.
    pub name: String,
    /// Base scene JSON (decoded only where it is shown: [`SweepRow::scene_value`]).
    pub scene: String,
    /// The swept parameters, in the order of the request.
    pub parameters: Vec<SweepParameter>,
    /// Priority of its jobs.
    pub priority: i64,
    /// Labels given with the request.
    pub labels: BTreeMap<String, String>,
    /// RFC 3339.
    pub created_at: String,
    /// Most of its jobs running at once (`None`: no limit).
    pub max_concurrent: Option<u32>,
}

impl SweepRow {
    fn decode(r: &SqliteRow) -> Result<SweepRow, StoreError> {
        Ok(SweepRow {
            seq: col(r, "seq")?,
            id: col(r, "id")?,
            name: col(r, "name")?,
            scene: col(r, "scene")?,
            parameters: json_col(r, "parameters")?,
            priority: col(r, "priority")?,
            labels: json_col(r, "labels")?,
            created_at: col(r, "created_at")?,
            max_concurrent: col::<Option<i64>>(r, "max_concurrent")?
                .map(|n| {
                    u32::try_from(n).map_err(|_| {
                        StoreError::Corrupt(format!("column `max_concurrent`: {n} is not a u32"))
                    })
                })
                .transpose()?,
        })
    }

    /// The base scene document.
    pub fn scene_value(&self) -> Result<serde_json::Value, StoreError> {
        from_json("scene", &self.scene)
    }
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
    /// The swept parameters, in order.
    pub parameters: Vec<SweepParameter>,
    /// Priority of its jobs.
    pub priority: i64,
    /// Labels given with the request.
    pub labels: BTreeMap<String, String>,
    /// Most of its jobs running at once (`None`: no limit).
    pub max_concurrent: Option<u32>,
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

impl Store {
    /// Insert a sweep and all its jobs (queued, or completed copies of cached runs) in one
    /// transaction.
    pub async fn create_sweep(
        &self,
        sw: &NewSweep,
        jobs: &[NewSweepJob],
    ) -> Result<SweepRow, StoreError> {
        let mut tx = self.pool.begin().await?;
        let row = sqlx::query(
            "INSERT INTO sweeps (id, name, scene, parameters, priority, labels, created_at,
                                 max_concurrent)
             VALUES (?, ?, ?, ?, ?, ?, strftime('%Y-%m-%dT%H:%M:%fZ','now'), ?)
             RETURNING *",
        )
        .bind(&sw.id)
        .bind(&sw.name)
        .bind(&sw.scene)
        .bind(to_json("parameters", &sw.parameters)?)
        .bind(sw.priority)
        .bind(to_json("labels", &sw.labels)?)
        .bind(sw.max_concurrent.map(i64::from))
        .fetch_one(&mut *tx)
        .await?;
        let row = SweepRow::decode(&row)?;
        for (i, j) in jobs.iter().enumerate() {
            insert_job(
                &mut tx,
                &j.job,
                Some((&sw.id, i as i64, &j.label, &j.values)),
            )
            .await?;
        }
        tx.commit().await?;
        Ok(row)
    }

    /// One sweep.
    pub async fn sweep(&self, id: &str) -> Result<Option<SweepRow>, StoreError> {
        sqlx::query("SELECT * FROM sweeps WHERE id = ?")
            .bind(id)
            .fetch_optional(&self.pool)
            .await?
            .as_ref()
            .map(SweepRow::decode)
            .transpose()
    }

    /// Sweeps, newest first: at most `limit`, older than `before_seq` when given.
    pub async fn sweeps(
        &self,
        limit: i64,
        before_seq: Option<i64>,
    ) -> Result<Vec<SweepRow>, StoreError> {
        let rows = sqlx::query(
            "SELECT * FROM sweeps WHERE (? IS NULL OR seq < ?) ORDER BY seq DESC LIMIT ?",
        )
        .bind(before_seq)
        .bind(before_seq)
        .bind(limit)
        .fetch_all(&self.pool)
        .await?;
        rows.iter().map(SweepRow::decode).collect()
    }

    /// The jobs of a sweep, in the order of its combinations.
    pub async fn sweep_jobs(&self, id: &str) -> Result<Vec<JobRow>, StoreError> {
        let rows = sqlx::query("SELECT * FROM jobs WHERE sweep_id = ? ORDER BY sweep_index, seq")
            .bind(id)
            .fetch_all(&self.pool)
            .await?;
        JobRow::decode_all(&rows)
    }

    /// Delete a sweep and its finished jobs (with their rows) in one transaction; returns
    /// the ids of the deleted jobs. Unfinished jobs are left (the caller refuses those).
    pub async fn delete_sweep(&self, id: &str) -> Result<Vec<String>, StoreError> {
        let mut tx = self.pool.begin().await?;
        let ids: Vec<String> = sqlx::query_scalar(
            "DELETE FROM jobs WHERE sweep_id = ? AND status IN ('completed', 'failed', 'cancelled')
             RETURNING id",
        )
        .bind(id)
        .fetch_all(&mut *tx)
        .await?;
        for jid in &ids {
            delete_job_rows(&mut tx, jid).await?;
        }
        sqlx::query("DELETE FROM sweeps WHERE id = ?")
            .bind(id)
            .execute(&mut *tx)
            .await?;
        tx.commit().await?;
        Ok(ids)
    }
}
