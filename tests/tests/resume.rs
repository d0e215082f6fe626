//! Checkpoints end to end (`docs/service.md`, "Checkpoints"): the real `fracture` binary, a
//! real server and real remote worker processes. A job whose crack grows by the equation of
//! motion is checkpointed every 100 steps; its worker process is killed (SIGKILL) after a
//! checkpoint and well before the end; another worker re-claims it and resumes from the
//! checkpoint (not from step 0). Its history and summary must then be those of an
//! uninterrupted run of the same scene: the energy and crack-tip rows byte for byte as the
//! API serves them, the snapshots, the MCAP file's rows and the deterministic summary fields,
//! with no row duplicated or lost. The checkpoint is gone once the job completed.

use std::process::Command;
use std::time::{Duration, Instant};

use fracture_e2e::{RemoteWorker, Server};
use serde_json::{Value, json};

const LONG: Duration = Duration::from_secs(180);

fn status(j: &Value) -> &str {
    j["status"].as_str().unwrap_or("")
}

/// A strip 150 mm × 20.5 mm (0.5 mm cells, 2×2 particles per cell) gripped top and bottom and
/// pulled apart by 20 µm over 40 µs, then held: its 30 mm edge crack on the mid-plane grows
/// by the equation of motion with a process zone from about 45 µs on (toughness 150 J/m²,
/// G_∞ ≈ 250 J/m²), steadily, without cutting through before the end (120 µs, ≈ 1200
/// steps). History every ≈ 10 steps, 4 snapshots.
fn growing(name: &str) -> Value {
    let (h, len, b) = (0.0005, 0.150, 0.010);
    let m = 2.0 * h;
    let (y0, y1) = (m, m + 2.0 * b);
    let cy = 0.5 * (y0 + y1) + 0.5 * h;
    let y1 = y1 + h;
    let (t_load, ramp, end) = (4.0e-5, 1.0e-5, 1.2e-4);
    let v = 2.0e-5 / (t_load - 0.5 * ramp);
    json!({
        "name": name,
        "grid": {"cell_size": h, "min": [0.0, 0.0], "max": [len + 2.0 * m, y1 + m]},
        "materials": {"homalite": {"model": "linear_elastic", "density": 1230.0,
                                   "youngs_modulus": 3.96e9, "poissons_ratio": 0.35}},
        "bodies": [{"material": "homalite",
                    "region": {"rectangle": {"min": [m, y0], "max": [m + len, y1]}}}],
        "cracks": [{"points": [[m - 0.5 * h, cy], [m + 0.030, cy]],
                    "j_integral": {"method": "domain", "radius": 6.0 * h},
                    "propagation": {"criterion": "energy_release", "toughness": 150.0,
                                    "direction": {"fixed": [1.0, 0.0]},
                                    "speed": "equation_of_motion"}}],
        "boundary_conditions": [
            {"region": {"rectangle": {"min": [0.0, y1 - 0.5 * h], "max": [1.0, 1.0]}},
             "velocity": {"x": 0.0, "y": v}, "ramp_time": ramp, "end": t_load},
            {"region": {"rectangle": {"min": [0.0, y1 - 0.5 * h], "max": [1.0, 1.0]}},
             "velocity": {"x": 0.0, "y": 0.0}, "start": t_load},
            {"region": {"rectangle": {"min": [0.0, 0.0], "max": [1.0, y0 + 0.5 * h]}},
             "velocity": {"x": 0.0, "y": -v}, "ramp_time": ramp, "end": t_load},
            {"region": {"rectangle": {"min": [0.0, 0.0], "max": [1.0, y0 + 0.5 * h]}},
             "velocity": {"x": 0.0, "y": 0.0}, "start": t_load}
        ],
        "output": {"speed_window": 2.0e-6, "history_interval": end / 120.0,
                   "snapshot_interval": end / 4.0 * 0.999, "fields": ["stress"]},
        "time": {"end": end, "cfl": 0.5}
    })
}

/// The step and time of the job's checkpoint file, if it has one (its header: magic, u32
/// length, JSON with `step` and `time_bits`).
fn checkpoint_at(data: &std::path::Path, id: &str) -> Option<(u64, f64)> {
    let b = std::fs::read(data.join("jobs").join(id).join("checkpoint.bin")).ok()?;
    let n = u32::from_le_bytes(b.get(8..12)?.try_into().ok()?) as usize;
    let h: Value = serde_json::from_slice(b.get(12..12 + n)?).ok()?;
    Some((
        h["step"].as_u64()?,
        f64::from_bits(h["time_bits"].as_u64()?),
    ))
}

fn text(s: &Server, path: &str) -> String {
    s.http
        .get(s.at(path))
        .send()
        .expect("GET")
        .text()
        .expect("body")
}

/// The summary without what differs between any two runs (wall time, speed, provenance).
fn deterministic(summary: &Value) -> Value {
    let mut v = summary.clone();
    if let Some(o) = v.as_object_mut() {
        for k in [
            "wall_seconds",
            "particle_steps_per_second",
            "provenance",
            "message",
        ] {
            o.remove(k);
        }
    }
    v
}

fn mcap_rows(data: &std::path::Path, id: &str) -> (Vec<String>, Vec<String>, usize) {
    let path = data.join("jobs").join(id).join("fields.mcap");
    let mut e: Vec<String> = fracture_results::mcapfile::read_energy(&path)
        .expect("MCAP energy")
        .iter()
        .map(|r| format!("{r:?}"))
        .collect();
    let mut c: Vec<String> = fracture_results::mcapfile::read_crack_tips(&path)
        .expect("MCAP crack tips")
        .iter()
        .map(|r| format!("{r:?}"))
        .collect();
    e.sort();
    c.sort();
    let n = fracture_results::mcapfile::read_snapshots(&path)
        .expect("MCAP snapshots")
        .len();
    (e, c, n)
}

#[test]
fn a_killed_workers_job_resumes_from_its_checkpoint_as_if_never_interrupted() {
    let dir = tempfile::tempdir().expect("tmp");
    let logs = tempfile::tempdir().expect("tmp");
    let token = "resume-worker-token";
    let s = Server::start(
        dir.path(),
        &[
            "--workers",
            "0",
            "--worker-token",
            token,
            "--lease-seconds",
            "3",
        ],
    );
    let flags = ["--flush-ms", "50", "--checkpoint-steps", "100"];
    let w1 = RemoteWorker::start(&s, token, &logs.path().join("w1.log"), &flags);
    let id = s.submit(&json!({"scene": growing("resume-me")}));

    // Wait for a checkpoint after the crack started to grow and some steps past it, then
    // kill the worker process.
    let t0 = Instant::now();
    let ((ckpt, ckpt_time), reached, worker) = loop {
        let j = s.job(&id);
        assert!(
            matches!(status(&j), "queued" | "running"),
            "the job ended before the kill (make the scene longer): {j}"
        );
        let step = j["progress"]["step"].as_u64().unwrap_or(0);
        if let Some(c) = checkpoint_at(dir.path(), &id)
            && c.0 >= 700
            && step > c.0 + 20
        {
            break (c, step, j["worker"].as_str().expect("worker").to_string());
        }
        assert!(t0.elapsed() < LONG, "no checkpoint: {j}");
        std::thread::sleep(Duration::from_millis(20));
    };
    let pid: u32 = worker
        .rsplit('-')
        .nth(1)
        .and_then(|p| p.parse().ok())
        .expect("pid in worker id");
    assert!(
        Command::new("kill")
            .args(["-9", &pid.to_string()])
            .status()
            .expect("kill")
            .success()
    );
    drop(w1);
    let _w2 = RemoteWorker::start(&s, token, &logs.path().join("w2.log"), &flags);
    let a = s.wait_done(&id, LONG);
    assert_eq!(status(&a), "completed", "{a}");
    assert_eq!(a["attempts"], 2, "{a}");
    // The restart said where it resumed and how far the killed attempt had got: the server's
    // log carries the job's restart note (the finished job's message is the summary's).
    let log = std::fs::read_to_string(dir.path().join("server.log")).expect("server log");
    assert!(
        log.lines().any(|l| l.contains(&id)
            && l.contains("attempt 2: resumed from its checkpoint at step")
            && l.contains("after the previous attempt stopped at")),
        "no restart note in the log:\n{log}"
    );

    // It resumed from a checkpoint at or after the one seen, not from step 0.
    let log = std::fs::read_to_string(dir.path().join("server.log")).expect("server log");
    let resumed = fracture_e2e::resumed_steps(dir.path(), &id);
    assert_eq!(resumed.len(), 1, "one resume expected:\n{log}");
    let from = resumed[0];
    assert!(
        from >= ckpt && from > 0,
        "resumed from step {from}, checkpoint seen at {ckpt}"
    );
    eprintln!(
        "checkpoint at step {from}; the killed attempt had reported step {reached}: at least {} \
         steps redone",
        reached.saturating_sub(from)
    );
    for l in log
        .lines()
        .filter(|l| l.contains("checkpoint stored"))
        .take(3)
    {
        eprintln!(
            "checkpoint stored:{}",
            l.split_once("checkpoint stored").map_or(l, |x| x.1)
        );
    }
    assert!(
        !dir.path()
            .join("jobs")
            .join(&id)
            .join("checkpoint.bin")
            .exists(),
        "the checkpoint of a completed job is removed"
    );

    // The same scene uninterrupted (forced past the result cache).
    let b_id = s.submit(&json!({"scene": growing("resume-me"), "cache": "force"}));
    let b = s.wait_done(&b_id, LONG);
    assert_eq!(status(&b), "completed", "{b}");
    assert_eq!(b["attempts"], 1, "{b}");

    for what in ["energy", "crack-tips", "snapshots"] {
        let ra = text(&s, &format!("/api/v1/jobs/{id}/{what}"));
        let rb = text(&s, &format!("/api/v1/jobs/{b_id}/{what}"));
        assert!(ra.len() > 2, "{what}: no rows");
        assert_eq!(
            ra, rb,
            "{what} of the resumed run differ from the uninterrupted run's"
        );
    }
    let tips: Value =
        serde_json::from_str(&text(&s, &format!("/api/v1/jobs/{id}/crack-tips"))).expect("tips");
    let rows = tips.as_array().expect("rows");
    let length = |r: &Value| r["length"].as_f64().unwrap_or(0.0);
    let tip1: Vec<&Value> = rows.iter().filter(|r| r["tip"] == 1).collect();
    let at_ckpt = tip1
        .iter()
        .rfind(|r| r["time"].as_f64().unwrap_or(f64::NAN) <= ckpt_time)
        .expect("a row before the checkpoint");
    let (first, last) = (tip1[0], tip1[tip1.len() - 1]);
    assert!(
        length(at_ckpt) > length(first) + 0.0005 && length(last) > length(at_ckpt) + 0.0005,
        "the crack did not grow before and after the checkpoint: first {first}, at the \
         checkpoint {at_ckpt}, last {last}"
    );
    assert_eq!(
        deterministic(&a["summary"]),
        deterministic(&b["summary"]),
        "summaries differ"
    );
    let (ea, ca, na) = mcap_rows(dir.path(), &id);
    let (eb, cb, nb) = mcap_rows(dir.path(), &b_id);
    assert!(!ea.is_empty() && !ca.is_empty() && na > 0);
    assert_eq!((ea, ca, na), (eb, cb, nb), "MCAP files differ");
}
