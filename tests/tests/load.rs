//! A small, bounded load generator (ignored by default; run with
//! `cargo test --release -p fracture-e2e --test load -- --ignored --nocapture`):
//! 200 tiny jobs submitted by 8 client threads to a server with 2 local workers on
//! loopback; reports request latency percentiles and jobs per second.

use std::time::{Duration, Instant};

use fracture_e2e::{Server, tiny_scene};

fn percentile(sorted: &[Duration], p: f64) -> Duration {
    if sorted.is_empty() {
        return Duration::ZERO;
    }
    let i = ((sorted.len() - 1) as f64 * p).round() as usize;
    sorted[i.min(sorted.len() - 1)]
}

fn report(name: &str, mut v: Vec<Duration>) {
    v.sort();
    eprintln!(
        "{name:>22}: n = {:4}  p50 = {:7.2} ms  p95 = {:7.2} ms  p99 = {:7.2} ms  max = {:7.2} ms",
        v.len(),
        percentile(&v, 0.50).as_secs_f64() * 1e3,
        percentile(&v, 0.95).as_secs_f64() * 1e3,
        percentile(&v, 0.99).as_secs_f64() * 1e3,
        v.last().copied().unwrap_or_default().as_secs_f64() * 1e3,
    );
}

#[test]
#[ignore = "load generator: run explicitly with --ignored --nocapture"]
fn load_tiny_jobs_two_workers() {
    const JOBS: usize = 200;
    const CLIENTS: usize = 8;
    let dir = tempfile::tempdir().expect("tmp");
    let s = Server::start(dir.path(), &["--workers", "2", "--worker-threads", "1"]);
    // 800 particles, 50 steps, histories every 2.5 steps: a run is mostly service overhead.
    let scene = tiny_scene("load", 50, 0);
    let t0 = Instant::now();
    let (ids, submit_lat): (Vec<String>, Vec<Duration>) = std::thread::scope(|sc| {
        let hs: Vec<_> = (0..CLIENTS)
            .map(|c| {
                let (s, scene) = (&s, &scene);
                sc.spawn(move || {
                    let mut out = Vec::new();
                    for _ in (c..JOBS).step_by(CLIENTS) {
                        let t = Instant::now();
                        let id = s.submit(scene);
                        out.push((id, t.elapsed()));
                    }
                    out
                })
            })
            .collect();
        hs.into_iter()
            .flat_map(|h| h.join().expect("client"))
            .unzip()
    });
    let submitted_in = t0.elapsed();
    // Poll until all are done, measuring read latency meanwhile.
    let mut read_lat = Vec::new();
    let mut list_lat = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(300);
    loop {
        let t = Instant::now();
        let h = s.get_json("/api/v1/health");
        read_lat.push(t.elapsed());
        let t = Instant::now();
        let _ = s.get_json("/api/v1/jobs?limit=50");
        list_lat.push(t.elapsed());
        for id in ids.iter().step_by(25) {
            let t = Instant::now();
            let _ = s.job(id);
            read_lat.push(t.elapsed());
        }
        if h["queued"] == 0 && h["running"] == 0 {
            break;
        }
        assert!(Instant::now() < deadline, "load run did not finish: {h}");
        std::thread::sleep(Duration::from_millis(100));
    }
    let total = t0.elapsed();
    let mut completed = 0;
    for id in &ids {
        let j = s.job(id);
        assert_eq!(j["attempts"], 1);
        if j["status"] == "completed" {
            completed += 1;
        }
    }
    assert_eq!(completed, JOBS);
    eprintln!(
        "--- load: {JOBS} tiny jobs, {CLIENTS} client threads, 2 local workers, loopback ---"
    );
    report("POST /api/v1/jobs", submit_lat);
    report("GET job/health", read_lat);
    report("GET /api/v1/jobs?limit=50", list_lat);
    eprintln!(
        "submitted in {:.2} s ({:.0} submits/s); all completed in {:.2} s: {:.1} jobs/s",
        submitted_in.as_secs_f64(),
        JOBS as f64 / submitted_in.as_secs_f64(),
        total.as_secs_f64(),
        JOBS as f64 / total.as_secs_f64()
    );
}
