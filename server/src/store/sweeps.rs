//! Sweep rows: a base scene and its parameters; the sweep's jobs are job rows with
//! `sweep_id`, `sweep_index`, `sweep_label` and `sweep_values` set, inserted with the sweep
//! in one transaction.

use std::collections::BTreeMap;

use super::jobs::insert_job;
use super::{
    Db, JobRow, NewJob, Store, StoreError, StoreRow, Tx, delete_job_rows, from_json, now_text,
    on_db, on_tx, to_json,
};
use fracture_api::sweep::SweepParameter;

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
    fn decode(r: &impl StoreRow) -> Result<SweepRow, StoreError> {
        Ok(SweepRow {
            seq: r.int("seq")?,
            id: r.text("id")?,
            name: r.text("name")?,
            scene: r.text("scene")?,
            parameters: r.json("parameters")?,
            priority: r.int("priority")?,
            labels: r.json("labels")?,
            created_at: r.text("created_at")?,
            max_concurrent: r.opt_u32("max_concurrent")?,
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
        let parameters = to_json("parameters", &sw.parameters)?;
        let labels = to_json("labels", &sw.labels)?;
        let now = now_text();
        let mut tx = self.db.begin().await?;
        let row = on_tx!(&mut tx, c => SweepRow::decode(&sqlx::query(
            "INSERT INTO sweeps (id, name, scene, parameters, priority, labels, created_at,
                                 max_concurrent)
             VALUES ($1, $2, $3, $4, $5, $6, $7, $8)
             RETURNING *",
        )
        .bind(&sw.id)
        .bind(&sw.name)
        .bind(&sw.scene)
        .bind(&parameters)
        .bind(sw.priority)
        .bind(&labels)
        .bind(&now)
        .bind(sw.max_concurrent.map(i64::from))
        .fetch_one(c)
        .await?)?);
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
        on_db!(&self.db, c => sqlx::query("SELECT * FROM sweeps WHERE id = $1")
            .bind(id)
            .fetch_optional(c)
            .await?
            .as_ref()
            .map(SweepRow::decode)
            .transpose())
    }

    /// Sweeps, newest first: at most `limit`, older than `before_seq` when given.
    pub async fn sweeps(
        &self,
        limit: i64,
        before_seq: Option<i64>,
    ) -> Result<Vec<SweepRow>, StoreError> {
        on_db!(&self.db, c => sqlx::query(
            "SELECT * FROM sweeps WHERE ($1 IS NULL OR seq < $1) ORDER BY seq DESC LIMIT $2",
        )
        .bind(before_seq)
        .bind(limit)
        .fetch_all(c)
        .await?
        .iter()
        .map(SweepRow::decode)
        .collect())
    }

    /// The jobs of a sweep, in the order of its combinations.
    pub async fn sweep_jobs(&self, id: &str) -> Result<Vec<JobRow>, StoreError> {
        on_db!(&self.db, c => JobRow::decode_all(
            &sqlx::query("SELECT * FROM jobs WHERE sweep_id = $1 ORDER BY sweep_index, seq")
                .bind(id)
                .fetch_all(c)
                .await?,
        ))
    }

    /// Delete a sweep and its finished jobs (with their rows) in one transaction; returns
    /// the ids of the deleted jobs. Unfinished jobs are left (the caller refuses those).
    pub async fn delete_sweep(&self, id: &str) -> Result<Vec<String>, StoreError> {
        let mut tx = self.db.begin().await?;
        let ids: Vec<String> = on_tx!(&mut tx, c => sqlx::query_scalar(
            "DELETE FROM jobs WHERE sweep_id = $1 AND status IN ('completed', 'failed', 'cancelled')
             RETURNING id",
        )
        .bind(id)
        .fetch_all(c)
        .await?);
        for jid in &ids {
            delete_job_rows(&mut tx, jid).await?;
        }
        on_tx!(&mut tx, c => {
            sqlx::query("DELETE FROM sweeps WHERE id = $1")
                .bind(id)
                .execute(c)
                .await?;
        });
        tx.commit().await?;
        Ok(ids)
    }
}
