//! End-to-end tests of the service: the real `fracture` binary on 127.0.0.1:0, real worker
//! processes, a temporary SQLite file. Each test starts its own server.

use std::collections::HashSet;
use std::io::{BufRead, BufReader};
use std::process::Command;
use std::time::{Duration, Instant};

use fracture_e2e::{Server, fracture_bin, scene, tiny_scene};
use serde_json::{Value, json};

const LONG: Duration = Duration::from_secs(90);

fn status(j: &Value) -> &str {
    j["status"].as_str().unwrap_or("")
}

/// Times of the job's energy rows are strictly increasing: no row was written twice.
fn assert_no_duplicates(s: &Server, id: &str) -> (usize, usize, usize) {
    let e = s.get_json(&format!("/api/v1/jobs/{id}/energy"));
    let e = e.as_array().expect("energy array");
    let times: Vec<f64> = e
        .iter()
        .map(|r| r["time"].as_f64().unwrap_or(f64::NAN))
        .collect();
    for w in times.windows(2) {
        assert!(
            w[1] > w[0],
            "energy rows of {id} repeat or go back in time: {w:?}"
        );
    }
    let c = s.get_json(&format!("/api/v1/jobs/{id}/crack-tips"));
    let c = c.as_array().expect("crack-tip array");
    let mut seen = HashSet::new();
    for r in c {
        let key = (
            r["time"].as_f64().unwrap_or(0.0).to_bits(),
            r["crack"].as_u64(),
            r["tip"].as_u64(),
        );
        assert!(seen.insert(key), "crack-tip row of {id} repeated: {r}");
    }
    let snaps = s.get_json(&format!("/api/v1/jobs/{id}/snapshots"));
    let snaps = snaps.as_array().expect("snapshot array");
    for (k, sn) in snaps.iter().enumerate() {
        assert_eq!(
            sn["index"].as_u64(),
            Some(k as u64),
            "snapshot indices of {id}: {snaps:?}"
        );
    }
    (e.len(), c.len(), snaps.len())
}

/// Read a job's SSE stream until a terminal `status` (or `timeout`); returns (event, data).
fn read_events(s: &Server, id: &str, timeout: Duration) -> Vec<(String, Value)> {
    let http = reqwest::blocking::Client::builder()
        .timeout(timeout)
        .build()
        .expect("client");
    let resp = http
        .get(s.at(&format!("/api/v1/jobs/{id}/events")))
        .send()
        .expect("events");
    assert_eq!(resp.status().as_u16(), 200);
    let mut out = Vec::new();
    let (mut ev, mut data) = (String::new(), String::new());
    for line in BufReader::new(resp).lines() {
        let Ok(line) = line else { break };
        if let Some(e) = line.strip_prefix("event:") {
            ev = e.trim().into();
        } else if let Some(d) = line.strip_prefix("data:") {
            data.push_str(d.trim_start());
        } else if line.is_empty() && !ev.is_empty() {
            let v: Value = serde_json::from_str(&data).unwrap_or(Value::Null);
            let terminal =
                ev == "status" && matches!(status(&v), "completed" | "failed" | "cancelled");
            out.push((std::mem::take(&mut ev), v));
            data.clear();
            if terminal {
                break;
            }
        }
    }
    out
}

#[test]
fn job_lifecycle_results_readable_while_running_and_after() {
    let dir = tempfile::tempdir().expect("tmp");
    let s = Server::start(dir.path(), &["--workers", "1", "--lease-seconds", "3"]);
    let health = s.get_json("/api/v1/health");
    assert_eq!(health["status"], "ok");
    assert_eq!(health["workers"], 1);

    // Long enough to be seen running: 30×15 cells (1800 particles), 4000 steps (≈ 2 s), 6 snapshots.
    let id = s
        .submit(&json!({"scene": scene("lifecycle", 30, 15, 4000, 6), "labels": {"suite": "e2e"}}));
    let events = std::thread::scope(|sc| {
        let ev = sc.spawn(|| read_events(&s, &id, LONG));
        // While it runs, every route answers.
        let t0 = Instant::now();
        let mut seen_running = 0;
        loop {
            let j = s.job(&id);
            match status(&j) {
                "running" => {
                    seen_running += 1;
                    for p in ["energy", "crack-tips", "snapshots"] {
                        let v = s.get_json(&format!("/api/v1/jobs/{id}/{p}"));
                        assert!(v.is_array(), "{p} while running: {v}");
                    }
                    let snaps = s.get_json(&format!("/api/v1/jobs/{id}/snapshots"));
                    if let Some(first) = snaps.as_array().and_then(|a| a.first()) {
                        let r = s
                            .http
                            .get(s.at(&format!(
                                "/api/v1/jobs/{id}/snapshots/{}/sxx.png",
                                first["index"]
                            )))
                            .send()
                            .expect("png");
                        assert_eq!(r.status().as_u16(), 200);
                    }
                }
                "completed" | "failed" | "cancelled" => break,
                _ => {}
            }
            assert!(t0.elapsed() < LONG, "job did not end");
            std::thread::sleep(Duration::from_millis(100));
        }
        assert!(seen_running > 0, "the job was never seen running");
        ev.join().expect("events thread")
    });
    let j = s.job(&id);
    assert_eq!(status(&j), "completed", "{j}");
    eprintln!("lifecycle run: {}", j["summary"]);
    assert_eq!(j["attempts"], 1);
    assert_eq!(j["labels"]["suite"], "e2e");
    assert_eq!(j["summary"]["status"], "completed");
    assert!(j["finished_at"].is_string() && j["started_at"].is_string());

    // SSE: progress events, then the final status last.
    let names: Vec<&str> = events.iter().map(|(e, _)| e.as_str()).collect();
    assert!(names.contains(&"progress"), "events: {names:?}");
    let (last, data) = events.last().expect("events");
    assert_eq!(last, "status");
    assert_eq!(status(data), "completed");
    // A late subscriber gets the current (final) state at once.
    let late = read_events(&s, &id, Duration::from_secs(10));
    let (e, d) = late.last().expect("late events");
    assert_eq!(e, "status");
    assert_eq!(status(d), "completed");

    let (ne, nc, ns) = assert_no_duplicates(&s, &id);
    assert!(
        ne > 0 && nc > 0 && ns > 0,
        "rows: energy {ne}, crack tips {nc}, snapshots {ns}"
    );

    // CSV forms.
    let csv = s
        .http
        .get(s.at(&format!("/api/v1/jobs/{id}/energy")))
        .header("accept", "text/csv")
        .send()
        .expect("csv")
        .text()
        .expect("text");
    assert!(csv.starts_with("time,kinetic,strain,external_work,dissipated,total_error,fracture\n"));
    assert_eq!(csv.lines().count(), ne + 1);
    let csv = s
        .http
        .get(s.at(&format!("/api/v1/jobs/{id}/crack-tips?since=0")))
        .header("accept", "text/csv")
        .send()
        .expect("csv")
        .text()
        .expect("text");
    assert!(csv.starts_with("time,crack,tip,x,y,length,speed,j1,j2,k1,k2,growing,"));

    // Images of every recorded component and kind.
    let snaps = s.get_json(&format!("/api/v1/jobs/{id}/snapshots"));
    let last = snaps
        .as_array()
        .and_then(|a| a.last())
        .expect("a snapshot")
        .clone();
    let mut names: Vec<String> = last["components"]
        .as_array()
        .expect("components")
        .iter()
        .filter_map(|c| c.as_str().map(String::from))
        .collect();
    names.extend(["stress", "velocity", "fringe"].map(String::from));
    for f in &names {
        let r = s
            .http
            .get(s.at(&format!(
                "/api/v1/jobs/{id}/snapshots/{}/{f}.png",
                last["index"]
            )))
            .send()
            .expect("png");
        assert_eq!(r.status().as_u16(), 200, "{f}.png");
        assert_eq!(r.headers()["content-type"], "image/png");
        let b = r.bytes().expect("bytes");
        assert_eq!(&b[1..4], b"PNG");
    }
    let r = s
        .http
        .get(s.at(&format!(
            "/api/v1/jobs/{id}/snapshots/{}/nonsense.png",
            last["index"]
        )))
        .send()
        .expect("png");
    assert_eq!(r.status().as_u16(), 404);

    // The MCAP file is valid and holds the snapshots.
    let bytes = s
        .http
        .get(s.at(&format!("/api/v1/jobs/{id}/fields.mcap")))
        .send()
        .expect("mcap")
        .bytes()
        .expect("bytes");
    let summary = mcap::Summary::read(&bytes)
        .expect("mcap summary")
        .expect("has summary");
    assert!(!summary.channels.is_empty());
    let mut messages = 0;
    for m in mcap::MessageStream::new(&bytes).expect("mcap stream") {
        m.expect("valid message");
        messages += 1;
    }
    assert!(messages >= ns, "{messages} messages for {ns} snapshots");
    let path = dir.path().join("jobs").join(&id).join("fields.mcap");
    let snaps = fracture_results::mcapfile::read_snapshots(&path).expect("read snapshots");
    assert_eq!(snaps.len(), ns, "snapshots in the MCAP file");

    // Lists and filters.
    let l = s.get_json("/api/v1/jobs?label=suite:e2e&status=completed");
    assert_eq!(l.as_array().map(Vec::len), Some(1));
    let l = s.get_json("/api/v1/jobs?label=suite:other");
    assert_eq!(l.as_array().map(Vec::len), Some(0));

    // Delete removes the job and its files.
    let r = s
        .http
        .delete(s.at(&format!("/api/v1/jobs/{id}")))
        .send()
        .expect("delete");
    assert_eq!(r.status().as_u16(), 204);
    assert!(!dir.path().join("jobs").join(&id).exists());
    let r = s
        .http
        .get(s.at(&format!("/api/v1/jobs/{id}")))
        .send()
        .expect("get");
    assert_eq!(r.status().as_u16(), 404);
}

#[test]
fn killed_worker_job_is_rerun_by_another_without_duplicates() {
    let dir = tempfile::tempdir().expect("tmp");
    let s = Server::start(dir.path(), &["--workers", "2", "--lease-seconds", "2"]);
    let id = s.submit(&scene("kill-me", 30, 15, 8000, 5));
    let j = s.wait_for(&id, LONG, |j| {
        status(j) == "running" && j["progress"]["step"].as_u64().unwrap_or(0) > 0
            || matches!(status(j), "completed" | "failed")
    });
    assert_eq!(
        status(&j),
        "running",
        "the job ended before the kill: make the scene longer"
    );
    let worker = j["worker"].as_str().expect("worker id").to_string();
    let pid: u32 = worker
        .rsplit('-')
        .nth(1)
        .and_then(|p| p.parse().ok())
        .expect("pid in worker id");
    let ok = Command::new("kill")
        .arg("-9")
        .arg(pid.to_string())
        .status()
        .expect("kill");
    assert!(ok.success());
    let j = s.wait_done(&id, LONG);
    assert_eq!(status(&j), "completed", "{j}");
    assert_eq!(j["attempts"], 2, "{j}");
    assert_ne!(j["summary"]["status"], Value::Null);
    let (ne, _, ns) = assert_no_duplicates(&s, &id);
    assert!(ne > 0 && ns > 0);
    // The re-run's MCAP file holds each snapshot once.
    let path = dir.path().join("jobs").join(&id).join("fields.mcap");
    let snaps = fracture_results::mcapfile::read_snapshots(&path).expect("read snapshots");
    assert_eq!(snaps.len(), ns);
}

#[test]
fn server_restart_with_jobs_queued_and_running_loses_nothing() {
    let dir = tempfile::tempdir().expect("tmp");
    let mut s = Server::start(dir.path(), &["--workers", "1", "--lease-seconds", "3"]);
    let ids: Vec<String> = (0..4)
        .map(|k| s.submit(&scene(&format!("restart-{k}"), 20, 10, 6000, 2)))
        .collect();
    s.wait_for(&ids[0], LONG, |j| status(j) != "queued");
    assert_eq!(status(&s.job(&ids[0])), "running", "make the scenes longer");
    assert_eq!(status(&s.job(&ids[3])), "queued");
    // An open event stream must not hold the shutdown up.
    let url = s.at(&format!("/api/v1/jobs/{}/events", ids[3]));
    let sse = std::thread::spawn(move || {
        let http = reqwest::blocking::Client::builder()
            .timeout(Duration::from_secs(60))
            .build()
            .expect("client");
        if let Ok(r) = http.get(url).send() {
            let _ = r.text();
        }
    });
    std::thread::sleep(Duration::from_millis(300));
    let stopped_in = {
        let t0 = Instant::now();
        s.restart();
        t0.elapsed()
    };
    sse.join().expect("sse thread");
    assert!(
        stopped_in < Duration::from_secs(15),
        "restart took {stopped_in:?}"
    );
    for id in &ids {
        let j = s.wait_done(id, LONG);
        assert_eq!(status(&j), "completed", "{j}");
        // The job interrupted by the restart was given back without counting an attempt.
        assert_eq!(j["attempts"], 1, "{j}");
        assert_no_duplicates(&s, id);
    }
    let all = s.get_json("/api/v1/jobs");
    assert_eq!(all.as_array().map(Vec::len), Some(4));
}

#[test]
fn fifty_concurrent_jobs_complete_each_exactly_once() {
    let dir = tempfile::tempdir().expect("tmp");
    let s = Server::start(dir.path(), &["--workers", "2", "--lease-seconds", "5"]);
    let ids: Vec<String> = std::thread::scope(|sc| {
        let hs: Vec<_> = (0..50)
            .map(|k| {
                let s = &s;
                sc.spawn(move || s.submit(&tiny_scene(&format!("many-{k}"), 100, 1)))
            })
            .collect();
        hs.into_iter().map(|h| h.join().expect("submit")).collect()
    });
    assert_eq!(ids.iter().collect::<HashSet<_>>().len(), 50);
    for id in &ids {
        let j = s.wait_done(id, LONG);
        assert_eq!(status(&j), "completed", "{j}");
        assert_eq!(j["attempts"], 1, "ran more than once: {j}");
    }
    let (e0, _, _) = assert_no_duplicates(&s, &ids[0]);
    for id in &ids[1..] {
        let (e, _, _) = assert_no_duplicates(&s, id);
        assert_eq!(e, e0, "same scene, same number of rows");
    }
    let h = s.get_json("/api/v1/health");
    assert_eq!(h["queued"], 0);
    assert_eq!(h["running"], 0);
    assert_eq!(
        s.get_json("/api/v1/jobs?limit=500")
            .as_array()
            .map(Vec::len),
        Some(50)
    );
}

#[test]
fn cancel_queued_and_running_jobs_and_the_worker_moves_on() {
    let dir = tempfile::tempdir().expect("tmp");
    let s = Server::start(dir.path(), &["--workers", "1", "--lease-seconds", "3"]);
    let running = s.submit(&scene("long", 60, 30, 100_000, 0));
    let queued = s.submit(&tiny_scene("behind", 100, 0));
    s.wait_for(&running, LONG, |j| status(j) == "running");
    assert_eq!(status(&s.job(&queued)), "queued");

    let (code, v) = s.post_json(&format!("/api/v1/jobs/{queued}/cancel"), &json!({}));
    assert_eq!(code, 200, "{v}");
    assert_eq!(status(&v), "cancelled");

    let t0 = Instant::now();
    let (code, _) = s.post_json(&format!("/api/v1/jobs/{running}/cancel"), &json!({}));
    assert_eq!(code, 200);
    let j = s.wait_done(&running, Duration::from_secs(10));
    let took = t0.elapsed();
    assert_eq!(status(&j), "cancelled", "{j}");
    assert!(took < Duration::from_secs(4), "cancellation took {took:?}");

    let next = s.submit(&tiny_scene("after", 100, 0));
    let j = s.wait_done(&next, LONG);
    assert_eq!(status(&j), "completed", "{j}");
    assert_eq!(status(&s.job(&queued)), "cancelled");
}

#[test]
fn bad_input_gets_status_and_helpful_body_and_stores_nothing() {
    let dir = tempfile::tempdir().expect("tmp");
    let s = Server::start(
        dir.path(),
        &[
            "--workers",
            "1",
            "--token",
            "s3cret",
            "--max-particles",
            "1000",
            "--max-body-bytes",
            "65536",
        ],
    );
    let post = |body: reqwest::blocking::Body, token: Option<&str>| {
        let mut r = s
            .http
            .post(s.at("/api/v1/jobs"))
            .header("content-type", "application/json")
            .body(body);
        if let Some(t) = token {
            r = r.bearer_auth(t);
        }
        let r = r.send().expect("post");
        let code = r.status().as_u16();
        (code, r.json::<Value>().unwrap_or(Value::Null))
    };
    let ok = tiny_scene("ok", 50, 0);
    let good = Some("s3cret");

    let (c, v) = post("{\"grid\": ".into(), good);
    assert_eq!(c, 400, "{v}");
    assert_eq!(v["error"], "bad_request");
    assert!(v["message"].as_str().unwrap_or("").contains("JSON"), "{v}");

    let mut unknown = ok.clone();
    unknown["colour"] = json!("red");
    let (c, v) = post(unknown.to_string().into(), good);
    assert_eq!(c, 422, "{v}");
    assert!(
        v["details"][0]["message"]
            .as_str()
            .unwrap_or("")
            .contains("colour"),
        "{v}"
    );

    let mut bad = ok.clone();
    bad["materials"]["homalite"]["poissons_ratio"] = json!(0.7);
    let (c, v) = post(bad.to_string().into(), good);
    assert_eq!(c, 422, "{v}");
    assert_eq!(v["error"], "invalid_scene");
    assert!(
        v["details"]
            .as_array()
            .expect("details")
            .iter()
            .any(|d| d["path"] == "materials.homalite.poissons_ratio"),
        "{v}"
    );

    let mut big = ok.clone();
    big["description"] = json!("x".repeat(100_000));
    let (c, v) = post(big.to_string().into(), good);
    assert_eq!(c, 413, "{v}");
    assert_eq!(v["error"], "payload_too_large");

    let (c, v) = post(scene("too-many", 40, 20, 50, 0).to_string().into(), good);
    assert_eq!(c, 422, "{v}");
    assert_eq!(v["error"], "limit_exceeded");
    assert!(
        v["message"]
            .as_str()
            .unwrap_or("")
            .contains("max_particles"),
        "{v}"
    );

    let (c, v) = post(ok.to_string().into(), Some("wrong"));
    assert_eq!(c, 401, "{v}");
    assert_eq!(v["error"], "unauthorized");
    let (c, v) = post(ok.to_string().into(), None);
    assert_eq!(c, 401, "{v}");

    // Validation without submitting.
    let (c, v) = s.post_json("/api/v1/scenes/validate", &bad);
    assert_eq!(c, 422, "{v}");
    let (c, v) = s.post_json("/api/v1/scenes/validate", &ok);
    assert_eq!(c, 200, "{v}");
    assert_eq!(v["valid"], true);
    assert_eq!(v["particles"], 800);

    // Nothing stored.
    assert_eq!(s.get_json("/api/v1/jobs").as_array().map(Vec::len), Some(0));
    assert!(
        !dir.path().join("jobs").exists()
            || std::fs::read_dir(dir.path().join("jobs"))
                .map(|d| d.count())
                .unwrap_or(0)
                == 0
    );

    // Unknown ids, read-only routes without a token.
    let r = s.http.get(s.at("/api/v1/jobs/nope")).send().expect("get");
    assert_eq!(r.status().as_u16(), 404);
    let v: Value = r.json().expect("json");
    assert_eq!(v["error"], "not_found");
    let (c, _) = s.post_json("/api/v1/jobs/nope/cancel", &json!({}));
    assert_eq!(c, 401, "cancel needs the token");

    // With the token the same scene is accepted.
    let (c, v) = post(ok.to_string().into(), good);
    assert_eq!(c, 201, "{v}");
    assert_eq!(s.get_json("/api/v1/jobs").as_array().map(Vec::len), Some(1));
    // Worker routes need the worker token.
    let (c, _) = s.post_json("/api/v1/worker/claim", &json!({"worker_id": "intruder"}));
    assert_eq!(c, 401);
}

#[test]
fn submit_command_waits_and_exits_with_the_outcome() {
    let dir = tempfile::tempdir().expect("tmp");
    let s = Server::start(dir.path(), &["--workers", "1"]);
    let scene_file = dir.path().join("scene.json");
    std::fs::write(&scene_file, tiny_scene("cli", 200, 2).to_string()).expect("write");
    let out = Command::new(fracture_bin())
        .args([
            "submit",
            scene_file.to_str().expect("path"),
            "--server",
            &s.url,
            "--wait",
        ])
        .output()
        .expect("run submit");
    assert!(out.status.success(), "submit --wait: {out:?}");
    // The first line is the job id (the result summary follows).
    let id = String::from_utf8_lossy(&out.stdout)
        .lines()
        .next()
        .unwrap_or("")
        .trim()
        .to_string();
    assert_eq!(status(&s.job(&id)), "completed");

    let mut bad = tiny_scene("cli-bad", 200, 0);
    bad["time"]["cfl"] = json!(3.0);
    std::fs::write(&scene_file, bad.to_string()).expect("write");
    let out = Command::new(fracture_bin())
        .args([
            "submit",
            scene_file.to_str().expect("path"),
            "--server",
            &s.url,
        ])
        .output()
        .expect("run submit");
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("time.cfl"),
        "{out:?}"
    );

    // Service pages.
    for p in [
        "/",
        "/api/v1/openapi.json",
        "/api/v1/docs/",
        "/api/v1/scenes",
    ] {
        let r = s.http.get(s.at(p)).send().expect("get");
        assert_eq!(r.status().as_u16(), 200, "{p}");
    }
    let api = s.get_json("/api/v1/openapi.json");
    for p in [
        "/api/v1/jobs",
        "/api/v1/jobs/{id}/events",
        "/api/v1/scenes/validate",
        "/api/v1/health",
    ] {
        assert!(
            api["paths"][p].is_object(),
            "{p} missing from the OpenAPI document"
        );
    }
}
