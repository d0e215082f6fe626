//! `fracture worker` as a batch scheduler starts it (no scheduler needed): it exits when
//! idle (`--idle-exit`) and after `--max-jobs` claims, and a stop signal makes it hand its
//! running job back to the queue (no attempt counted) and exit, so that another worker
//! completes the job. The same against a real Slurm cluster: `slurm.rs`.

#![allow(clippy::unwrap_used)]

use std::process::Command;
use std::time::{Duration, Instant};

use fracture_e2e::{RemoteWorker, Server, fracture_bin, scene, tiny_scene};
use serde_json::Value;

const TOKEN: &str = "batch-worker-token";

fn status(j: &Value) -> &str {
    j["status"].as_str().unwrap_or("?")
}

/// Energy rows of a job: their times strictly increase (no row twice).
fn assert_rows_once(s: &Server, id: &str) -> usize {
    let rows = s.get_json(&format!("/api/v1/jobs/{id}/energy"));
    let rows = rows.as_array().unwrap();
    let times: Vec<f64> = rows.iter().map(|r| r["time"].as_f64().unwrap()).collect();
    assert!(!times.is_empty(), "job {id} has no energy rows");
    assert!(
        times.windows(2).all(|w| w[0] < w[1]),
        "job {id} has rows twice or out of order: {times:?}"
    );
    times.len()
}

#[test]
fn a_batch_worker_exits_after_max_jobs_and_when_idle() {
    let dir = tempfile::tempdir().unwrap();
    let s = Server::start(dir.path(), &["--workers", "0", "--worker-token", TOKEN]);
    let ids: Vec<String> = (0..3)
        .map(|i| s.submit(&tiny_scene(&format!("batch-{i}"), 60, 0)))
        .collect();

    // Two claims, then it exits by itself, leaving the third job queued.
    let mut w = RemoteWorker::start(
        &s,
        TOKEN,
        &dir.path().join("w1.log"),
        &["--max-jobs", "2", "--idle-exit", "60"],
    );
    let st = w.wait_exit(Duration::from_secs(60));
    let log = std::fs::read_to_string(dir.path().join("w1.log")).unwrap_or_default();
    assert_eq!(st.and_then(|s| s.code()), Some(0), "{log}");
    assert!(log.contains("--max-jobs"), "{log}");
    let jobs: Vec<Value> = ids.iter().map(|id| s.job(id)).collect();
    assert_eq!(
        jobs.iter().map(status).collect::<Vec<_>>(),
        ["completed", "completed", "queued"],
        "{jobs:?}"
    );

    // With --idle-exit 2: runs the last job, then exits about 2 s after it.
    let t0 = Instant::now();
    let mut w = RemoteWorker::start(&s, TOKEN, &dir.path().join("w2.log"), &["--idle-exit", "2"]);
    let j = s.wait_done(&ids[2], Duration::from_secs(60));
    assert_eq!(status(&j), "completed", "{j}");
    let finished = Instant::now();
    let st = w.wait_exit(Duration::from_secs(30));
    let log = std::fs::read_to_string(dir.path().join("w2.log")).unwrap_or_default();
    assert_eq!(st.and_then(|s| s.code()), Some(0), "{log}");
    let idle = finished.elapsed();
    assert!(
        idle >= Duration::from_millis(1500) && idle < Duration::from_secs(8),
        "exited {idle:?} after its last job (--idle-exit 2); {log}"
    );
    assert!(log.contains("--idle-exit"), "{log}");
    eprintln!(
        "idle exit {:.1} s after the last job ({:.1} s in all)",
        idle.as_secs_f64(),
        t0.elapsed().as_secs_f64()
    );
    for id in &ids {
        assert_eq!(s.job(id)["attempts"], 1);
        assert_rows_once(&s, id);
    }

    // Bad values name the flag and the value.
    for (args, flag) in [
        (["--idle-exit", "-1"], "--idle-exit"),
        (["--idle-exit", "NaN"], "--idle-exit"),
        (["--max-jobs", "0"], "--max-jobs"),
    ] {
        let out = Command::new(fracture_bin())
            .args(["worker", "--server", &s.url, "--token", TOKEN])
            .args(args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains(flag) && err.contains(args[1]),
            "{args:?}: {err}"
        );
    }
}

#[test]
fn a_stop_signal_hands_the_running_job_back_and_another_worker_completes_it() {
    let dir = tempfile::tempdir().unwrap();
    let s = Server::start(dir.path(), &["--workers", "0", "--worker-token", TOKEN]);
    // Long enough to be signalled mid-run on a busy machine (several seconds).
    let id = s.submit(&scene("handback", 40, 20, 6000, 0));
    let log1 = dir.path().join("w1.log");
    let mut w1 = RemoteWorker::start(&s, TOKEN, &log1, &["--flush-ms", "100"]);
    let j = s.wait_for(&id, Duration::from_secs(60), |j| {
        j["progress"]["step"].as_u64().unwrap_or(0) > 0
    });
    assert_eq!(status(&j), "running", "{j}");
    let worker1 = j["worker"].as_str().unwrap().to_string();

    // SIGTERM to `fracture worker` (the supervisor): forwarded to its worker process,
    // which hands the job back at its next progress report and exits 0.
    let t0 = Instant::now();
    let st = Command::new("kill")
        .args(["-TERM", &w1.pid().to_string()])
        .status()
        .unwrap();
    assert!(st.success());
    let j = s.wait_for(&id, Duration::from_secs(20), |j| status(j) != "running");
    let released = t0.elapsed();
    let st = w1.wait_exit(Duration::from_secs(20));
    let log = std::fs::read_to_string(&log1).unwrap_or_default();
    assert_eq!(st.and_then(|s| s.code()), Some(0), "{log}");
    assert_eq!(status(&j), "queued", "{j}");
    assert_eq!(j["attempts"], 0, "the hand-back counts no attempt: {j}");
    let m = j["message"].as_str().unwrap_or("");
    assert!(
        m.contains("handed back") && m.contains("SIGTERM") && m.contains(&worker1),
        "{m}"
    );
    // Well within the 30 s lease: the job was given back, not lost.
    assert!(released < Duration::from_secs(10), "{released:?}; {log}");
    let stopped_at = j["progress"]["step"].as_u64().unwrap_or(0);

    // Another worker completes it, as its first attempt, with every row once.
    let mut w2 = RemoteWorker::start(&s, TOKEN, &dir.path().join("w2.log"), &["--idle-exit", "2"]);
    let j = s.wait_done(&id, Duration::from_secs(120));
    assert_eq!(status(&j), "completed", "{j}");
    assert_eq!(j["attempts"], 1, "{j}");
    let rows = assert_rows_once(&s, &id);
    // The second run resumed from the checkpoint written at the hand-back (the server logs
    // the step of every resume), not from step 0.
    let resumed = fracture_e2e::resumed_steps(dir.path(), &id);
    assert_eq!(resumed.len(), 1, "one resume expected: {resumed:?}");
    assert!(
        resumed[0] > 0 && resumed[0] + 200 >= stopped_at,
        "resumed from step {} after a hand-back at step {stopped_at}",
        resumed[0]
    );
    eprintln!(
        "handed back {:.2} s after SIGTERM at step {stopped_at}; completed by another \
         worker ({rows} energy rows)",
        released.as_secs_f64()
    );
    assert_eq!(
        w2.wait_exit(Duration::from_secs(30)).and_then(|s| s.code()),
        Some(0)
    );
}
