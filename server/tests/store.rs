//! The store's test suite, run on both backends: every case below is one test on a fresh
//! SQLite file (`sqlite::…`) and one on a fresh database of a real PostgreSQL server
//! (`postgres::…`, see `support/postgres.rs`: skipped with the reason when there is none,
//! unless `FRACTURE_REQUIRE_POSTGRES=1`).
//!
//! Submit, claim order, heartbeats, fencing, lease expiry and the reaper, per-job and
//! server attempt limits, cancellation, releases, the cache by scene hash, sweeps and
//! `max_concurrent`, results rows, deletion, metrics, and claims in parallel (no job
//! claimed twice; a sweep's limit held under racing claimers).

#![allow(clippy::unwrap_used)]

#[path = "support/postgres.rs"]
mod pg;

use std::collections::{BTreeMap, HashSet};
use std::time::Duration;

use fracture_api::jobs::JobStatus;
use fracture_api::results::{CrackTipRow, EnergyRow, Progress, RunStatus, Snapshot, Summary};
use fracture_server::store::{
    Backend, HistoryCursor, ListFilter, NewJob, NewSweep, NewSweepJob, Store, StoreError,
};

const LEASE: Duration = Duration::from_secs(30);

fn job(id: &str, priority: i64) -> NewJob {
    NewJob {
        id: id.to_string(),
        name: format!("scene {id}"),
        scene: format!("{{\"name\":\"{id}\"}}"),
        end_time: 1e-6,
        priority,
        labels: BTreeMap::from([("owner".to_string(), format!("o-{id}"))]),
        rerun_of: None,
        scene_hash: format!("hash-{id}"),
        use_cache: false,
        max_attempts: None,
    }
}

fn summary(status: RunStatus, scene_hash: &str, solver_version: &str) -> Summary {
    serde_json::from_value(serde_json::json!({
        "status": status, "steps": 10, "time_step": 1e-7, "sim_time": 1e-6, "particles": 4,
        "grid_nodes": 9, "active_nodes_mean": 9.0, "wall_seconds": 0.5,
        "particle_steps_per_second": 80.0, "threads": 1, "scene_hash": scene_hash,
        "solver_version": solver_version,
    }))
    .unwrap()
}

fn completed(hash: &str) -> Summary {
    summary(RunStatus::Completed, hash, fracture_api::SOLVER_VERSION)
}

async fn claim_id(store: &Store, worker: &str) -> Option<(String, i64)> {
    store
        .claim(worker, LEASE)
        .await
        .unwrap()
        .map(|c| (c.job.id, c.job.fence))
}

/// The claim order, the job rows and their reads.
async fn submit_claim_order_and_reads(store: Store) {
    for (id, p) in [("a", 0), ("b", 5), ("c", 0), ("d", 5)] {
        let row = store.create_job(&job(id, p)).await.unwrap();
        assert_eq!(row.status, JobStatus::Queued);
        assert_eq!(row.attempts, 0);
        assert_eq!(row.labels["owner"], format!("o-{id}"));
        assert_eq!(row.end_time, 1e-6);
        assert!(row.created_at.ends_with('Z') && row.created_at.len() == 24);
    }
    let dup = store.create_job(&job("a", 0)).await;
    assert!(matches!(dup, Err(StoreError::Db(_))), "{dup:?}");
    assert_eq!(store.counts().await.unwrap(), (4, 0));
    assert_eq!(store.count_all().await.unwrap(), 4);
    assert_eq!(store.job_ids().await.unwrap().len(), 4);

    let list = |f: ListFilter| {
        let store = store.clone();
        async move {
            store
                .list(&ListFilter { limit: 10, ..f })
                .await
                .unwrap()
                .into_iter()
                .map(|j| j.id)
                .collect::<Vec<_>>()
        }
    };
    assert_eq!(list(ListFilter::default()).await, ["d", "c", "b", "a"]);
    let labelled = ListFilter {
        labels: vec![("owner".into(), "o-c".into())],
        ..Default::default()
    };
    assert_eq!(list(labelled).await, ["c"]);
    let named = ListFilter {
        name_contains: Some("SCENE B".into()),
        ..Default::default()
    };
    assert_eq!(list(named).await, ["b"]);
    let seq_c = store.get("c").await.unwrap().unwrap().seq;
    let older = ListFilter {
        before_seq: Some(seq_c),
        ..Default::default()
    };
    assert_eq!(list(older).await, ["b", "a"]);

    // Highest priority first, then oldest.
    let order: Vec<String> = [
        claim_id(&store, "w1").await,
        claim_id(&store, "w2").await,
        claim_id(&store, "w1").await,
        claim_id(&store, "w2").await,
    ]
    .into_iter()
    .map(|c| c.unwrap().0)
    .collect();
    assert_eq!(order, ["b", "d", "a", "c"]);
    assert!(store.claim("w3", LEASE).await.unwrap().is_none());
    let b = store.get("b").await.unwrap().unwrap();
    assert_eq!((b.status, b.attempts, b.fence), (JobStatus::Running, 1, 1));
    assert_eq!(b.worker_id.as_deref(), Some("w1"));
    assert!(b.started_at.is_some() && b.lease_until_ms.is_some());
    let running = ListFilter {
        status: Some(JobStatus::Running),
        ..Default::default()
    };
    assert_eq!(list(running).await.len(), 4);
    assert_eq!(store.counts().await.unwrap(), (0, 4));
    assert!(store.get("nope").await.unwrap().is_none());
}

/// Heartbeats, fenced writes, results rows and the finish.
async fn heartbeats_fencing_results_and_finish(store: Store) {
    store.create_job(&job("j", 0)).await.unwrap();
    let (id, fence) = claim_id(&store, "w").await.unwrap();
    let p = Progress {
        step: 7,
        sim_time: 7e-8,
        end_time: 1e-6,
        fraction: 0.07,
    };
    assert!(!store.heartbeat(&id, fence, LEASE, Some(&p)).await.unwrap());
    assert_eq!(store.get(&id).await.unwrap().unwrap().progress, Some(p));
    assert!(matches!(
        store.heartbeat(&id, fence + 1, LEASE, None).await,
        Err(StoreError::Fenced)
    ));

    let energy: Vec<EnergyRow> = (0..250)
        .map(|i| EnergyRow {
            time: i as f64 * 1e-8,
            kinetic: i as f64,
            strain: f64::NAN,
            ..Default::default()
        })
        .collect();
    store
        .append_energy(&id, fence, LEASE, &energy)
        .await
        .unwrap();
    let tips: Vec<CrackTipRow> = (0..120)
        .map(|i| CrackTipRow {
            time: i as f64 * 1e-8,
            crack: 1,
            tip: i % 2,
            x: 0.5,
            growing: i % 3 == 0,
            k1_cod: f64::NAN,
            ..Default::default()
        })
        .collect();
    store
        .append_crack_tips(&id, fence, LEASE, &tips)
        .await
        .unwrap();
    let snap = |index: u32, v: f32| Snapshot {
        index,
        time: index as f64 * 1e-7,
        nx: 2,
        ny: 1,
        origin: [0.0, 0.0],
        cell_size: 1e-3,
        fields: vec!["velocity".into()],
        components: vec![fracture_api::results::FieldComponent {
            name: "vx".into(),
            values: vec![v, f32::NAN],
        }],
        cracks: vec![],
        particles: None,
        slice: None,
    };
    for (i, v) in [(0, 1.0), (1, 2.0), (1, 3.0)] {
        let s = snap(i, v);
        let enc = fracture_results::codec::encode_snapshot(&s);
        store
            .put_snapshot(&id, fence, LEASE, &s, &enc)
            .await
            .unwrap();
    }
    // A stale fence writes nothing.
    assert!(matches!(
        store
            .append_energy(&id, fence - 1, LEASE, &energy[..1])
            .await,
        Err(StoreError::Fenced)
    ));
    assert_eq!(store.row_counts(&id).await.unwrap(), (250, 120, 2));

    let back = store.energy(&id, None).await.unwrap();
    assert_eq!(back.len(), 250);
    assert!(back.iter().enumerate().all(|(i, r)| r.kinetic == i as f64));
    assert!(back[3].strain.is_nan());
    let since = store.energy(&id, Some(2.005e-6)).await.unwrap();
    assert_eq!(since.len(), 49, "rows after t = 2.005e-6 s");
    let tips_back = store.crack_tips(&id, None).await.unwrap();
    assert_eq!(tips_back.len(), 120);
    assert_eq!((tips_back[5].crack, tips_back[5].tip), (1, 1));
    assert!(tips_back[3].growing && !tips_back[4].growing);
    assert!(tips_back[0].k1_cod.is_nan() && tips_back[0].x == 0.5);
    let index = store.snapshots(&id).await.unwrap();
    assert_eq!(index.iter().map(|s| s.index).collect::<Vec<_>>(), [0, 1]);
    assert_eq!(index[1].components, ["vx"]);
    let s1 = store.snapshot(&id, 1).await.unwrap().unwrap();
    assert_eq!(
        s1.components[0].values[0], 3.0,
        "a repeated index replaces the snapshot"
    );
    assert!(store.snapshot(&id, 9).await.unwrap().is_none());

    let done = store
        .finish(&id, fence, &completed("hash-j"))
        .await
        .unwrap();
    assert_eq!(done.status, JobStatus::Completed);
    assert!(done.finished_at.is_some() && done.worker_id.is_none());
    assert_eq!(done.summary.as_ref().unwrap().steps, 10);
    // Once finished, the claim is over.
    assert!(matches!(
        store.heartbeat(&id, fence, LEASE, None).await,
        Err(StoreError::Fenced)
    ));
    assert!(matches!(
        store.finish(&id, fence, &completed("hash-j")).await,
        Err(StoreError::Fenced)
    ));
    assert!(matches!(
        store
            .put_snapshot(&id, fence, LEASE, &snap(2, 0.0), &[])
            .await,
        Err(StoreError::Fenced)
    ));
}

/// Lease expiry: the reaper re-queues, the next claim raises the fence and drops the
/// earlier attempt's rows, the last allowed loss fails the job; a lost job that was to be
/// cancelled ends cancelled.
async fn lease_expiry_reaper_and_attempt_limit(store: Store) {
    let short = Duration::from_millis(50);
    store.create_job(&job("j", 0)).await.unwrap();
    let c1 = store.claim("w1", short).await.unwrap().unwrap().job;
    store
        .append_energy(&c1.id, c1.fence, short, &[EnergyRow::default()])
        .await
        .unwrap();
    assert!(
        store.reap(2).await.unwrap().is_empty(),
        "the lease still runs"
    );
    tokio::time::sleep(Duration::from_millis(120)).await;
    let reaped = store.reap(2).await.unwrap();
    assert_eq!(reaped.len(), 1);
    assert_eq!(reaped[0].status, JobStatus::Queued);
    assert_eq!(
        reaped[0].message.as_deref(),
        Some("the worker was lost (lease expired); re-queued")
    );
    assert!(reaped[0].worker_id.is_none() && reaped[0].finished_at.is_none());

    let c2 = store.claim("w2", short).await.unwrap().unwrap().job;
    assert_eq!((c2.attempts, c2.fence), (2, c1.fence + 1));
    // The claim route rewinds the history (to the checkpoint, here none: all of it).
    store
        .rewind_history(&c2.id, c2.fence, short, None)
        .await
        .unwrap();
    assert_eq!(
        store.row_counts("j").await.unwrap(),
        (0, 0, 0),
        "attempt 1's rows dropped"
    );
    // The first worker's late writes are fenced off.
    assert!(matches!(
        store
            .append_energy("j", c1.fence, short, &[EnergyRow::default()])
            .await,
        Err(StoreError::Fenced)
    ));
    tokio::time::sleep(Duration::from_millis(120)).await;
    let failed = store.reap(2).await.unwrap();
    assert_eq!(failed[0].status, JobStatus::Failed);
    assert_eq!(
        failed[0].message.as_deref(),
        Some("the worker was lost 2 times (lease expired); giving up")
    );
    assert!(failed[0].finished_at.is_some());

    store.create_job(&job("k", 0)).await.unwrap();
    store.claim("w3", short).await.unwrap().unwrap();
    store.cancel("k").await.unwrap();
    tokio::time::sleep(Duration::from_millis(120)).await;
    let cancelled = store.reap(5).await.unwrap();
    assert_eq!(cancelled[0].status, JobStatus::Cancelled);
    assert_eq!(
        cancelled[0].message.as_deref(),
        Some("cancelled (its worker stopped answering)")
    );
}

/// A job's own `max_attempts` overrides the server's; the releases of dead workers by
/// worker-id prefix and by claim.
async fn per_job_attempts_and_dead_worker_releases(store: Store) {
    let mut once = job("once", 0);
    once.max_attempts = Some(1);
    let row = store.create_job(&once).await.unwrap();
    assert_eq!(row.max_attempts, Some(1));
    store.create_job(&job("plain", 0)).await.unwrap();
    store.create_job(&job("other", 0)).await.unwrap();
    let a = store
        .claim("local0-11-aa", LEASE)
        .await
        .unwrap()
        .unwrap()
        .job;
    let b = store
        .claim("local0-11-aa", LEASE)
        .await
        .unwrap()
        .unwrap()
        .job;
    let o = store
        .claim("local1-12-bb", LEASE)
        .await
        .unwrap()
        .unwrap()
        .job;
    assert_eq!((a.id.as_str(), b.id.as_str()), ("once", "plain"));

    let released = store
        .release_worker("local0-11-", "killed by signal 9", 3, false)
        .await
        .unwrap();
    let by_id: BTreeMap<_, _> = released.iter().map(|j| (j.id.as_str(), j)).collect();
    assert_eq!(by_id.len(), 2, "only the dead worker's jobs");
    assert_eq!(by_id["once"].status, JobStatus::Failed);
    assert_eq!(
        by_id["once"].message.as_deref(),
        Some("the worker running it died (attempt 1 of 1; giving up): killed by signal 9")
    );
    assert_eq!(by_id["plain"].status, JobStatus::Queued);
    assert_eq!(
        by_id["plain"].message.as_deref(),
        Some("re-queued: the worker running it died: killed by signal 9")
    );
    assert_eq!(
        store.get(&o.id).await.unwrap().unwrap().status,
        JobStatus::Running
    );

    // By claim: a stale fence changes nothing; a deterministic cause fails at once.
    assert!(matches!(
        store.release_claim(&o.id, o.fence + 1, "x", 3, false).await,
        Err(StoreError::Fenced)
    ));
    let r = store
        .release_claim(&o.id, o.fence, "out of memory", 3, true)
        .await
        .unwrap();
    assert_eq!(r.status, JobStatus::Failed);
    assert_eq!(
        r.message.as_deref(),
        Some("the worker running it died: out of memory")
    );
    assert!(matches!(
        store.release_claim(&o.id, o.fence, "again", 3, false).await,
        Err(StoreError::Fenced)
    ));
}

/// Cancellation of queued and running jobs; the shutdown's release of running jobs.
async fn cancel_and_release_at_shutdown(store: Store) {
    for id in ["q", "r", "s"] {
        store.create_job(&job(id, 0)).await.unwrap();
    }
    let (r, fr) = claim_id(&store, "w").await.unwrap();
    let (s, _) = claim_id(&store, "w").await.unwrap();
    assert_eq!((r.as_str(), s.as_str()), ("q", "r"));
    store.create_job(&job("t", 0)).await.unwrap();
    let t = store.cancel("t").await.unwrap().unwrap();
    assert_eq!(t.status, JobStatus::Cancelled);
    assert_eq!(t.message.as_deref(), Some("cancelled before it started"));
    assert!(store.cancel("missing").await.unwrap().is_none());
    let q = store.cancel(&r).await.unwrap().unwrap();
    assert_eq!((q.status, q.cancel_requested), (JobStatus::Running, true));
    assert!(
        store.heartbeat(&r, fr, LEASE, None).await.unwrap(),
        "the worker is told"
    );

    let released = store.release_running("server stopping").await.unwrap();
    let by_id: BTreeMap<_, _> = released.iter().map(|j| (j.id.as_str(), j)).collect();
    assert_eq!(by_id["q"].status, JobStatus::Cancelled);
    assert!(by_id["q"].finished_at.is_some());
    assert_eq!(by_id["r"].status, JobStatus::Queued);
    assert_eq!(
        by_id["r"].attempts, 0,
        "a release does not count the attempt"
    );
    assert_eq!(by_id["r"].message.as_deref(), Some("server stopping"));
    assert!(matches!(
        store.heartbeat(&r, fr, LEASE, None).await,
        Err(StoreError::Fenced)
    ));
    let again = store.claim("w2", LEASE).await.unwrap().unwrap().job;
    assert_eq!(
        (again.id.as_str(), again.attempts, again.fence),
        ("r", 1, 2)
    );
}

/// The cache: a completed run of the same scene hash and solver version answers a new
/// job; failed runs, other versions, copies and `use_cache: false` do not.
async fn cache_by_scene_hash(store: Store) {
    let mut orig = job("orig", 0);
    orig.scene_hash = "H".into();
    store.create_job(&orig).await.unwrap();
    let (id, fence) = claim_id(&store, "w").await.unwrap();
    store
        .append_energy(&id, fence, LEASE, &[EnergyRow::default()])
        .await
        .unwrap();
    store.finish(&id, fence, &completed("H")).await.unwrap();

    let mut hit = job("hit", 3);
    hit.scene_hash = "H".into();
    hit.use_cache = true;
    let copy = store.create_job(&hit).await.unwrap();
    assert_eq!(copy.status, JobStatus::Completed);
    assert_eq!(copy.cached_from.as_deref(), Some("orig"));
    assert_eq!(copy.priority, 3);
    assert_eq!(copy.labels["owner"], "o-hit");
    assert_eq!(copy.summary, Some(completed("H")));
    assert!(copy.finished_at.is_some());
    // A copy is never a source: the next hit names the original.
    let mut hit2 = hit.clone();
    hit2.id = "hit2".into();
    assert_eq!(
        store
            .create_job(&hit2)
            .await
            .unwrap()
            .cached_from
            .as_deref(),
        Some("orig")
    );
    // Forced: queued.
    let mut forced = hit.clone();
    forced.id = "forced".into();
    forced.use_cache = false;
    assert_eq!(
        store.create_job(&forced).await.unwrap().status,
        JobStatus::Queued
    );

    // Another solver version, or a failed run, is not reused.
    let mut other = job("other", 0);
    other.scene_hash = "G".into();
    store.create_job(&other).await.unwrap();
    let mut failing = job("failing", 0);
    failing.scene_hash = "F".into();
    store.create_job(&failing).await.unwrap();
    let (f1, g1) = claim_id(&store, "w").await.unwrap();
    let (f2, g2) = claim_id(&store, "w").await.unwrap();
    assert_eq!((f1.as_str(), f2.as_str()), ("forced", "other"));
    store
        .finish(
            &f2,
            g2,
            &summary(RunStatus::Completed, "G", "0.0.0-elsewhere"),
        )
        .await
        .unwrap();
    store.finish(&f1, g1, &completed("H")).await.unwrap();
    let (f3, g3) = claim_id(&store, "w").await.unwrap();
    store
        .finish(
            &f3,
            g3,
            &summary(RunStatus::Failed, "F", fracture_api::SOLVER_VERSION),
        )
        .await
        .unwrap();
    for (id, hash) in [("miss-g", "G"), ("miss-f", "F")] {
        let mut j = job(id, 0);
        j.scene_hash = hash.into();
        j.use_cache = true;
        let row = store.create_job(&j).await.unwrap();
        assert_eq!(
            (row.status, row.cached_from),
            (JobStatus::Queued, None),
            "{id}"
        );
    }
    // The newest completed original answers.
    let mut hit3 = hit.clone();
    hit3.id = "hit3".into();
    assert_eq!(
        store
            .create_job(&hit3)
            .await
            .unwrap()
            .cached_from
            .as_deref(),
        Some("forced")
    );
}

fn sweep(id: &str, max_concurrent: Option<u32>) -> NewSweep {
    NewSweep {
        id: id.to_string(),
        name: format!("sweep {id}"),
        scene: "{\"name\":\"base\"}".into(),
        parameters: serde_json::from_value(serde_json::json!([
            {"path": "cracks.0.propagation.toughness", "values": [25, 100, 250]}
        ]))
        .unwrap(),
        priority: 0,
        labels: BTreeMap::new(),
        max_concurrent,
    }
}

fn sweep_jobs(prefix: &str, n: usize) -> Vec<NewSweepJob> {
    (0..n)
        .map(|i| NewSweepJob {
            job: job(&format!("{prefix}{i}"), 0),
            label: format!("toughness={i}"),
            values: format!("{{\"cracks.0.propagation.toughness\":{i}}}"),
        })
        .collect()
}

/// Sweeps: rows, their jobs in order, `max_concurrent`, listing and deletion.
async fn sweeps_and_max_concurrent(store: Store) {
    let row = store
        .create_sweep(&sweep("s", Some(2)), &sweep_jobs("s", 3))
        .await
        .unwrap();
    assert_eq!((row.max_concurrent, row.parameters.len()), (Some(2), 1));
    store.create_job(&job("lone", 0)).await.unwrap();
    let jobs = store.sweep_jobs("s").await.unwrap();
    assert_eq!(
        jobs.iter().map(|j| j.sweep_index).collect::<Vec<_>>(),
        [Some(0), Some(1), Some(2)]
    );
    assert_eq!(jobs[1].sweep_label.as_deref(), Some("toughness=1"));
    assert_eq!(
        jobs[2].sweep_values.as_ref().unwrap()["cracks.0.propagation.toughness"],
        2
    );

    let (a, fa) = claim_id(&store, "w").await.unwrap();
    let (b, _) = claim_id(&store, "w").await.unwrap();
    assert_eq!((a.as_str(), b.as_str()), ("s0", "s1"));
    assert_eq!(
        claim_id(&store, "w").await.unwrap().0,
        "lone",
        "s2 waits for a place"
    );
    assert!(store.claim("w", LEASE).await.unwrap().is_none());
    store.finish(&a, fa, &completed("hash-s0")).await.unwrap();
    assert_eq!(claim_id(&store, "w").await.unwrap().0, "s2");

    store
        .create_sweep(&sweep("t", None), &sweep_jobs("t", 2))
        .await
        .unwrap();
    assert_eq!(
        store
            .sweeps(10, None)
            .await
            .unwrap()
            .iter()
            .map(|s| s.id.as_str())
            .collect::<Vec<_>>(),
        ["t", "s"]
    );
    let t_seq = store.sweep("t").await.unwrap().unwrap().seq;
    assert_eq!(store.sweeps(10, Some(t_seq)).await.unwrap()[0].id, "s");
    assert!(store.sweep("nope").await.unwrap().is_none());
    for id in ["t0", "t1"] {
        store.cancel(id).await.unwrap();
    }
    assert_eq!(store.delete_sweep("t").await.unwrap().len(), 2);
    assert!(store.sweep("t").await.unwrap().is_none());
    assert!(store.get("t0").await.unwrap().is_none());
    // A sweep with running jobs: only the finished ones go.
    assert_eq!(store.delete_sweep("s").await.unwrap(), ["s0"]);
}

/// Deletion of finished jobs with their rows; metrics.
async fn delete_and_metrics(store: Store) {
    store.create_job(&job("a", 0)).await.unwrap();
    store.create_job(&job("b", 0)).await.unwrap();
    let (a, fa) = claim_id(&store, "w").await.unwrap();
    let (b, fb) = claim_id(&store, "w").await.unwrap();
    store
        .heartbeat(
            &b,
            fb,
            LEASE,
            Some(&Progress {
                step: 42,
                sim_time: 0.0,
                end_time: 1.0,
                fraction: 0.0,
            }),
        )
        .await
        .unwrap();
    store
        .append_energy(&a, fa, LEASE, &[EnergyRow::default(); 3])
        .await
        .unwrap();
    assert!(
        !store.delete(&a).await.unwrap(),
        "a running job is not deleted"
    );
    store.finish(&a, fa, &completed("hash-a")).await.unwrap();
    tokio::time::sleep(Duration::from_millis(30)).await;
    let m = store.metrics(3600).await.unwrap();
    assert_eq!(m.by_status.get("completed"), Some(&1));
    assert_eq!(m.by_status.get("running"), Some(&1));
    assert_eq!(m.finished_in_window, 1);
    assert_eq!(m.running.len(), 1);
    assert_eq!((m.running[0].id.as_str(), m.running[0].step), ("b", 42));
    assert!(
        m.running[0].elapsed_seconds > 0.0 && m.running[0].elapsed_seconds < 60.0,
        "{}",
        m.running[0].elapsed_seconds
    );
    assert!(store.delete(&a).await.unwrap());
    assert_eq!(store.row_counts(&a).await.unwrap(), (0, 0, 0));
    assert!(store.get(&a).await.unwrap().is_none());
    assert!(!store.delete(&a).await.unwrap());
}

/// Claimers released at once by a barrier, `rounds` times: each round's claims, per
/// claimer. `each` runs one claimer: it claims until `stop` says so.
async fn race<F, Fut>(store: &Store, claimers: usize, each: F) -> Vec<Vec<String>>
where
    F: Fn(Store, String) -> Fut,
    Fut: std::future::Future<Output = Vec<String>> + Send + 'static,
{
    let barrier = std::sync::Arc::new(tokio::sync::Barrier::new(claimers));
    let mut tasks = Vec::new();
    for w in 0..claimers {
        let (barrier, fut) = (barrier.clone(), each(store.clone(), format!("w{w}")));
        tasks.push(tokio::spawn(async move {
            barrier.wait().await;
            fut.await
        }));
    }
    let mut out = Vec::new();
    for t in tasks {
        out.push(t.await.unwrap());
    }
    out
}

/// Eight claimers released at once take 16 jobs, five times over: each job exactly once,
/// and none of them stops early (a claim finds a job while one is left).
async fn parallel_claims_never_take_a_job_twice(store: Store) {
    for round in 0..5 {
        for i in 0..16 {
            store
                .create_job(&job(&format!("r{round}j{i:02}"), i % 3))
                .await
                .unwrap();
        }
        let got = race(&store, 8, |store, w| async move {
            let mut got = Vec::new();
            while let Some(c) = store.claim(&w, LEASE).await.unwrap() {
                got.push(c.job.id);
            }
            got
        })
        .await;
        let all: Vec<String> = got.into_iter().flatten().collect();
        let unique: HashSet<&String> = all.iter().collect();
        assert_eq!(all.len(), 16, "round {round}: claims {all:?}");
        assert_eq!(
            unique.len(),
            16,
            "round {round}: a job was claimed twice: {all:?}"
        );
    }
    assert_eq!(store.counts().await.unwrap(), (0, 80));
    for j in store
        .list(&ListFilter {
            limit: 100,
            ..Default::default()
        })
        .await
        .unwrap()
    {
        assert_eq!((j.attempts, j.fence), (1, 1), "{}", j.id);
    }
}

/// Eight claimers released at once race for a sweep of ten jobs limited to three at once,
/// five times over (a new sweep each time): three run each time.
async fn parallel_claims_keep_a_sweeps_limit(store: Store) {
    for round in 0..5 {
        let id = format!("s{round}");
        store
            .create_sweep(&sweep(&id, Some(3)), &sweep_jobs(&format!("{id}-"), 10))
            .await
            .unwrap();
        let got = race(&store, 8, |store, w| async move {
            store
                .claim(&w, LEASE)
                .await
                .unwrap()
                .map(|c| c.job.id)
                .into_iter()
                .collect()
        })
        .await;
        let claimed: Vec<String> = got.into_iter().flatten().collect();
        assert_eq!(claimed.len(), 3, "round {round}: claimed {claimed:?}");
        assert!(claimed.iter().all(|c| c.starts_with(&format!("{id}-"))));
    }
    assert_eq!(store.counts().await.unwrap(), (35, 15));
}

/// One server per PostgreSQL database: a second store on it is refused, naming why; once
/// the first closes, it opens.
async fn second_server_on_the_same_database_is_refused(store: Store, url: &str) {
    match Store::open_postgres(url).await {
        Err(StoreError::InUse(m)) => {
            assert!(m.contains("in use by another fracture server"), "{m}")
        }
        other => panic!("expected InUse, got {other:?}"),
    }
    store.close().await;
    let again = Store::open_postgres(url).await.unwrap();
    assert_eq!(again.backend(), Backend::Postgres);
    again.close().await;
}

/// A batch worker's hand back (the job queued again, the attempt not counted, a stale
/// fence refused) and the history a resumed claim starts from: rows after the checkpoint's
/// time deleted, those before kept, the message saying where it resumes; without a
/// checkpoint every row goes. The zone-front columns round-trip.
async fn hand_back_and_rewind_history(store: Store) {
    store.create_job(&job("h", 0)).await.unwrap();
    let (h, f1) = claim_id(&store, "w").await.unwrap();
    let rows: Vec<EnergyRow> = [1e-6, 2e-6, 3e-6]
        .iter()
        .map(|&time| EnergyRow {
            time,
            kinetic: 1.0,
            ..EnergyRow::default()
        })
        .collect();
    store.append_energy(&h, f1, LEASE, &rows).await.unwrap();
    let tips: Vec<CrackTipRow> = [1e-6, 3e-6]
        .iter()
        .map(|&time| CrackTipRow {
            time,
            crack: 1,
            tip: 1,
            zone_x: 0.021,
            zone_y: f64::NAN,
            connected_x: 0.019,
            zone_connected_y: f64::NAN,
            ..CrackTipRow::default()
        })
        .collect();
    store.append_crack_tips(&h, f1, LEASE, &tips).await.unwrap();
    let back = store.crack_tips(&h, None).await.unwrap();
    assert_eq!(back.len(), 2);
    assert_eq!(back[0].zone_x, 0.021);
    assert!(back[0].zone_y.is_nan());
    assert_eq!(back[0].connected_x, 0.019);
    assert!(back[0].zone_connected_y.is_nan());

    let j = store
        .hand_back(&h, f1, "handed back (SIGUSR1)")
        .await
        .unwrap();
    assert_eq!((j.status, j.attempts), (JobStatus::Queued, 0));
    assert_eq!(j.message.as_deref(), Some("handed back (SIGUSR1)"));
    assert!(matches!(
        store.hand_back(&h, f1, "again").await,
        Err(StoreError::Fenced)
    ));
    // The claim itself keeps the rows: the claim route rewinds them to the checkpoint.
    let (h2, f2) = claim_id(&store, "w2").await.unwrap();
    assert_eq!(h2, h);
    assert_eq!(store.energy(&h, None).await.unwrap().len(), 3);
    let keep = HistoryCursor {
        step: 20,
        time: 2e-6,
        snapshots: 0,
    };
    assert!(matches!(
        store.rewind_history(&h, f1, LEASE, Some(keep)).await,
        Err(StoreError::Fenced)
    ));
    let note = store
        .rewind_history(&h, f2, LEASE, Some(keep))
        .await
        .unwrap()
        .unwrap();
    // Resumed at the checkpoint: the progress says so (the job's end time is unknown here:
    // no progress was ever reported), and the message names the cause of the hand-back.
    assert_eq!((note.progress.step, note.progress.sim_time), (20, 2e-6));
    assert!(
        note.message.contains("(handed back (SIGUSR1))"),
        "{}",
        note.message
    );
    let left: Vec<f64> = store
        .energy(&h, None)
        .await
        .unwrap()
        .iter()
        .map(|r| r.time)
        .collect();
    assert_eq!(left, vec![1e-6, 2e-6]);
    assert_eq!(store.crack_tips(&h, None).await.unwrap().len(), 1);
    let j = store.get(&h).await.unwrap().unwrap();
    assert!(
        j.message
            .as_deref()
            .is_some_and(|m| m.starts_with("attempt 1: resumed from its checkpoint at step 20")),
        "{:?}",
        j.message
    );
    store.rewind_history(&h, f2, LEASE, None).await.unwrap();
    assert!(store.energy(&h, None).await.unwrap().is_empty());
    assert!(store.crack_tips(&h, None).await.unwrap().is_empty());
}

/// One `#[tokio::test]` per case and backend.
macro_rules! on_both {
    ($($case:ident),* $(,)?) => {
        mod sqlite {
            $(
                #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
                async fn $case() {
                    let dir = tempfile::tempdir().unwrap();
                    let store = super::Store::open(&dir.path().join("t.db")).await.unwrap();
                    assert_eq!(store.backend(), super::Backend::Sqlite);
                    super::$case(store.clone()).await;
                    store.close().await;
                }
            )*
        }
        mod postgres {
            $(
                #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
                async fn $case() {
                    let Some(url) = super::pg::fresh_database().await else { return };
                    let store = super::Store::open_postgres(&url).await.unwrap();
                    assert_eq!(store.backend(), super::Backend::Postgres);
                    super::$case(store.clone()).await;
                    store.close().await;
                }
            )*
        }
    };
}

on_both!(
    submit_claim_order_and_reads,
    heartbeats_fencing_results_and_finish,
    lease_expiry_reaper_and_attempt_limit,
    per_job_attempts_and_dead_worker_releases,
    cancel_and_release_at_shutdown,
    cache_by_scene_hash,
    sweeps_and_max_concurrent,
    delete_and_metrics,
    parallel_claims_never_take_a_job_twice,
    parallel_claims_keep_a_sweeps_limit,
    hand_back_and_rewind_history,
);

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn postgres_one_server_per_database() {
    let Some(url) = pg::fresh_database().await else {
        return;
    };
    let store = Store::open_postgres(&url).await.unwrap();
    second_server_on_the_same_database_is_refused(store, &url).await;
}

#[tokio::test]
async fn postgres_unreachable_is_a_clear_error() {
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let err = Store::open_postgres(&format!("postgres://u@127.0.0.1:{port}/db"))
        .await
        .unwrap_err();
    assert!(err.to_string().to_lowercase().contains("refused"), "{err}");
}
