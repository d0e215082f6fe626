//! 3D runs through the whole service (`"analysis": "3d"`): the real `fracture` binary on
//! 127.0.0.1:0 with one local worker process and a temporary SQLite file. Every 3D example
//! scene of `scenes/` is submitted (its end time cut to one snapshot interval, so that a debug
//! build on two cores runs all three in well under a minute) and must complete with the 3D
//! summary (`dimension` 3), energy rows, its slices as snapshots (one per `output.slices`
//! plane per snapshot time, each with its plane), pictures of them, no crack-tip rows, the
//! SSE stream and the MCAP file carrying the same. Invalid 3D input and a limit are 422s.
//! A 3D job whose remote worker is killed after a checkpoint resumes from it on another
//! worker and ends with the history of an uninterrupted run.

use std::io::{BufRead, BufReader};
use std::process::Command;
use std::time::{Duration, Instant};

use fracture_e2e::{RemoteWorker, Server};
use serde_json::{Value, json};

const LONG: Duration = Duration::from_secs(240);

fn example(name: &str) -> Value {
    let path = format!("{}/../scenes/{name}.json", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    serde_json::from_str(&text).expect("scene JSON")
}

/// Read a job's SSE stream until its terminal `status`; returns (event, data) pairs.
fn events(s: &Server, id: &str) -> Vec<(String, Value)> {
    let http = reqwest::blocking::Client::builder()
        .timeout(LONG)
        .build()
        .expect("client");
    let resp = http
        .get(s.at(&format!("/api/v1/jobs/{id}/events")))
        .send()
        .expect("events");
    let mut out = Vec::new();
    let (mut ev, mut data) = (String::new(), String::new());
    for line in BufReader::new(resp).lines() {
        let Ok(line) = line else { break };
        if let Some(e) = line.strip_prefix("event:") {
            ev = e.trim().to_string();
        } else if let Some(d) = line.strip_prefix("data:") {
            data.push_str(d.trim_start());
        } else if line.is_empty() && !ev.is_empty() {
            let v: Value = serde_json::from_str(&data).unwrap_or(Value::Null);
            let done = ev == "status"
                && matches!(
                    v["status"].as_str(),
                    Some("completed" | "failed" | "cancelled")
                );
            out.push((std::mem::take(&mut ev), v));
            data.clear();
            if done {
                break;
            }
        }
    }
    out
}

#[test]
fn every_3d_example_runs_through_the_service() {
    let dir = tempfile::tempdir().expect("tmp");
    let s = Server::start(dir.path(), &["--workers", "1"]);
    let mut ids = Vec::new();
    for name in ["3d-wave-bar", "3d-impact", "3d-sphere-plate"] {
        let mut sc = example(name);
        let interval = sc["output"]["snapshot_interval"]
            .as_f64()
            .expect("interval");
        sc["time"]["end"] = json!(interval);
        let slices = sc["output"]["slices"].as_array().expect("slices").clone();
        let id = s.submit(&json!({"scene": sc, "labels": {"suite": "3d"}, "cache": "force"}));
        ids.push((name, id, slices));
    }
    // The first job's stream, from its start to its end.
    let streamed = events(&s, &ids[0].1);
    for (name, id, slices) in &ids {
        let j = s.wait_done(id, LONG);
        assert_eq!(j["status"], "completed", "{name}: {j}");
        let sum = &j["summary"];
        eprintln!(
            "{name}: {} particles × {} steps in {:.2} s",
            sum["particles"], sum["steps"], sum["wall_seconds"]
        );
        assert_eq!(sum["dimension"], 3, "{name}: {sum}");
        assert_eq!(sum["status"], "completed");
        assert!(sum["particles"].as_u64().unwrap_or(0) > 1000, "{sum}");
        assert_eq!(j["scene"]["analysis"], "3d");
        assert_eq!(j["labels"]["suite"], "3d");

        // Energy rows, as 2D: the 2D columns, times increasing.
        let e = s.get_json(&format!("/api/v1/jobs/{id}/energy"));
        let e = e.as_array().expect("energy rows");
        assert!(e.len() >= 2, "{name}: {} energy rows", e.len());
        for w in e.windows(2) {
            assert!(w[1]["time"].as_f64() > w[0]["time"].as_f64(), "{name}");
        }
        assert!(e.iter().any(|r| r["kinetic"].as_f64().unwrap_or(0.0) > 0.0));
        // No crack tips in 3D.
        let c = s.get_json(&format!("/api/v1/jobs/{id}/crack-tips"));
        assert_eq!(c, json!([]), "{name}");
        // The slices: two snapshot times (0 and the end) × the scene's planes, in order.
        let snaps = s.get_json(&format!("/api/v1/jobs/{id}/snapshots"));
        let snaps = snaps.as_array().expect("snapshots");
        assert_eq!(snaps.len(), 2 * slices.len(), "{name}: {snaps:?}");
        for (k, sn) in snaps.iter().enumerate() {
            assert_eq!(sn["index"], k, "{name}");
            let want = &slices[k % slices.len()];
            assert_eq!(sn["slice"]["normal"], want["normal"], "{name}: {sn}");
            assert_eq!(sn["slice"]["at"], want["at"], "{name}: {sn}");
            assert_eq!(sn["slice"]["axes"].as_array().map(Vec::len), Some(2));
        }
        // Every slice renders: the default stress component and a 3D one.
        for sn in snaps {
            for f in ["stress", "szz"] {
                let r = s
                    .http
                    .get(s.at(&format!(
                        "/api/v1/jobs/{id}/snapshots/{}/{f}.png",
                        sn["index"]
                    )))
                    .send()
                    .expect("png");
                assert_eq!(r.status().as_u16(), 200, "{name} {f}");
                let png = r.bytes().expect("png bytes");
                assert!(png.starts_with(b"\x89PNG"), "{name} {f}");
            }
        }
        // The MCAP file has the rows, the slices and the 3D scene.
        let mcap = s
            .http
            .get(s.at(&format!("/api/v1/jobs/{id}/fields.mcap")))
            .send()
            .expect("mcap")
            .bytes()
            .expect("mcap bytes");
        let file = fracture_results::mcapfile::McapContents::from_bytes(&mcap).expect("MCAP");
        assert_eq!(file.energy.len(), e.len(), "{name}");
        assert_eq!(file.snapshots.len(), snaps.len(), "{name}");
        assert!(file.snapshots.iter().all(|sn| sn.slice.is_some()), "{name}");
        let scene = file.scene.expect("scene metadata");
        assert!(scene["json"].contains(r#""analysis":"3d""#), "{name}");
        // The VTK archive: one series per plane, each image at its plane, and `fields.pvd`
        // with every plane as a part.
        let zip = s
            .http
            .get(s.at(&format!("/api/v1/jobs/{id}/vtk.zip")))
            .send()
            .expect("vtk.zip")
            .bytes()
            .expect("zip bytes");
        let mut zip = zip::ZipArchive::new(std::io::Cursor::new(zip.to_vec())).expect("a zip");
        let mut entries = std::collections::BTreeMap::new();
        for k in 0..zip.len() {
            let mut f = zip.by_index(k).expect("entry");
            let mut data = String::new();
            std::io::Read::read_to_string(&mut f, &mut data).expect("text entry");
            let entry = f.name().expect("entry name").to_string();
            entries.insert(entry.rsplit('/').next().unwrap_or("").to_string(), data);
        }
        let series = entries
            .keys()
            .filter(|k| k.starts_with("slice_") && k.ends_with(".pvd"));
        assert_eq!(series.count(), slices.len(), "{name}: {:?}", entries.keys());
        assert_eq!(
            entries.keys().filter(|k| k.ends_with(".vti")).count(),
            snaps.len(),
            "{name}"
        );
        let fields = &entries["fields.pvd"];
        for part in 0..slices.len() {
            assert!(
                fields.contains(&format!("part=\"{part}\"")),
                "{name}: {fields}"
            );
        }
        assert!(!entries.contains_key("cracks.pvd"), "{name}");
    }
    // The stream carried the run as for 2D: progress, energy, snapshots with their planes,
    // the final status with the 3D summary.
    let names: Vec<&str> = streamed.iter().map(|(e, _)| e.as_str()).collect();
    for want in ["progress", "energy", "snapshot", "status"] {
        assert!(names.contains(&want), "events: {names:?}");
    }
    assert!(
        streamed
            .iter()
            .filter(|(e, _)| e == "snapshot")
            .all(|(_, d)| d["slice"]["normal"].is_string()),
        "snapshot events carry their plane"
    );
    let (last, data) = streamed.last().expect("events");
    assert_eq!(last, "status");
    assert_eq!(data["summary"]["dimension"], 3, "{data}");
}

#[test]
fn invalid_3d_input_and_limits_are_422() {
    let dir = tempfile::tempdir().expect("tmp");
    let s = Server::start(dir.path(), &["--workers", "0", "--max-particles", "5000"]);
    // `thickness` does not exist in 3D.
    let mut sc = example("3d-impact");
    sc["thickness"] = json!(0.001);
    let (code, v) = s.post_json("/api/v1/jobs", &sc);
    assert_eq!(code, 422, "{v}");
    assert_eq!(v["error"], "invalid_scene");
    assert_eq!(v["details"][0]["path"], "thickness", "{v}");
    // An open mesh (a square pyramid without half of its base) names its first bad
    // triangle.
    let mut sc = example("3d-impact");
    sc["bodies"][1]["region"] = json!({"mesh": {
        "vertices": [[0.013, 0.004, 0.004], [0.019, 0.004, 0.004], [0.019, 0.008, 0.004],
                     [0.013, 0.008, 0.004], [0.016, 0.006, 0.008]],
        "triangles": [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4], [0, 2, 1]]
    }});
    let (code, v) = s.post_json("/api/v1/jobs", &json!({ "scene": sc }));
    assert_eq!(code, 422, "{v}");
    assert_eq!(v["error"], "invalid_scene");
    let detail = &v["details"][0];
    let path = detail["path"].as_str().unwrap_or_default();
    assert!(path.starts_with("bodies.1.region.mesh.triangles."), "{v}");
    assert!(
        detail["message"]
            .as_str()
            .unwrap_or_default()
            .contains("open"),
        "{v}"
    );
    // 14 592 particles against --max-particles 5000.
    let (code, v) = s.post_json("/api/v1/jobs", &example("3d-impact"));
    assert_eq!(code, 422, "{v}");
    assert_eq!(v["error"], "limit_exceeded", "{v}");
    assert!(
        v["message"]
            .as_str()
            .unwrap_or_default()
            .contains("max_particles"),
        "{v}"
    );
    // Nothing was queued.
    assert_eq!(s.get_json("/api/v1/jobs"), json!([]));
}

/// The step of the job's checkpoint file, if it has one (its header: 8 bytes of magic, a u32
/// length, JSON with `step`).
fn checkpoint_step(data: &std::path::Path, id: &str) -> Option<u64> {
    let b = std::fs::read(data.join("jobs").join(id).join("checkpoint.bin")).ok()?;
    let n = u32::from_le_bytes(b.get(8..12)?.try_into().ok()?) as usize;
    let h: Value = serde_json::from_slice(b.get(12..12 + n)?).ok()?;
    h["step"].as_u64()
}

/// The summary without what differs between any two runs.
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

#[test]
fn a_3d_job_resumes_from_its_checkpoint_after_its_worker_is_killed() {
    let dir = tempfile::tempdir().expect("tmp");
    let logs = tempfile::tempdir().expect("tmp");
    let token = "three-d-resume";
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
    // The whole 3d-wave-bar (147 steps), a checkpoint every 20 steps.
    let flags = ["--flush-ms", "20", "--checkpoint-steps", "20"];
    let w1 = RemoteWorker::start(&s, token, &logs.path().join("w1.log"), &flags);
    let scene = example("3d-wave-bar");
    let id = s.submit(&json!({ "scene": scene }));
    let t0 = Instant::now();
    let (ckpt, worker) = loop {
        let j = s.job(&id);
        assert!(
            matches!(j["status"].as_str(), Some("queued" | "running")),
            "the job ended before the kill: {j}"
        );
        let step = j["progress"]["step"].as_u64().unwrap_or(0);
        if let Some(c) = checkpoint_step(dir.path(), &id)
            && c >= 40
            && step > c + 5
        {
            break (c, j["worker"].as_str().expect("worker").to_string());
        }
        assert!(t0.elapsed() < LONG, "no checkpoint: {j}");
        std::thread::sleep(Duration::from_millis(5));
    };
    let pid = worker
        .rsplit('-')
        .nth(1)
        .expect("pid in the worker id")
        .to_string();
    assert!(
        Command::new("kill")
            .args(["-9", &pid])
            .status()
            .expect("kill")
            .success()
    );
    drop(w1);
    let _w2 = RemoteWorker::start(&s, token, &logs.path().join("w2.log"), &flags);
    let a = s.wait_done(&id, LONG);
    assert_eq!(a["status"], "completed", "{a}");
    assert_eq!(a["attempts"], 2, "{a}");
    let resumed = fracture_e2e::resumed_steps(dir.path(), &id);
    assert_eq!(resumed.len(), 1, "one resume: {resumed:?}");
    assert!(
        resumed[0] >= ckpt && resumed[0] > 0,
        "{resumed:?}, checkpoint {ckpt}"
    );
    eprintln!(
        "3d-wave-bar resumed at step {} (checkpoint seen at {ckpt})",
        resumed[0]
    );

    // The same scene uninterrupted: the same rows, slices and summary.
    let b_id = s.submit(&json!({"scene": example("3d-wave-bar"), "cache": "force"}));
    let b = s.wait_done(&b_id, LONG);
    assert_eq!(b["status"], "completed", "{b}");
    for what in ["energy", "crack-tips", "snapshots"] {
        let ra = s.get_json(&format!("/api/v1/jobs/{id}/{what}"));
        let rb = s.get_json(&format!("/api/v1/jobs/{b_id}/{what}"));
        assert_eq!(
            ra, rb,
            "{what} of the resumed 3D run differ from the uninterrupted run's"
        );
    }
    assert_eq!(deterministic(&a["summary"]), deterministic(&b["summary"]));
    assert_eq!(a["summary"]["dimension"], 3);
    let snaps = s.get_json(&format!("/api/v1/jobs/{id}/snapshots"));
    assert_eq!(snaps.as_array().map(Vec::len), Some(5 * 2), "{snaps}");
}
