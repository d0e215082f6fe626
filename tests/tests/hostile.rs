//! The service under a hostile tester's conditions, with the real binary: a full disk (a
//! small tmpfs), a second server on the same data folder, a public bind without a token,
//! a worker killed under its job, bad flags, a closed stdout pipe.
//!
//! The disk-full test mounts a tmpfs (root only); where mounting is not allowed it says so
//! and passes without running (the store-level fault injection of
//! `server/tests/safety.rs` still runs).

use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use fracture_e2e::{Server, fracture_bin, scene, tiny_scene};
use serde_json::{Value, json};

const LONG: Duration = Duration::from_secs(90);

fn status(j: &Value) -> &str {
    j["status"].as_str().unwrap_or("")
}

/// A tmpfs of `size` mounted at a fresh folder, unmounted on drop.
struct Tmpfs {
    dir: PathBuf,
    _parent: tempfile::TempDir,
}

impl Tmpfs {
    fn mount(size: &str) -> Option<Tmpfs> {
        let parent = tempfile::tempdir().ok()?;
        let dir = parent.path().join("mnt");
        std::fs::create_dir_all(&dir).ok()?;
        let ok = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={size}"), "tmpfs"])
            .arg(&dir)
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success());
        ok.then_some(Tmpfs {
            dir,
            _parent: parent,
        })
    }
}

impl Drop for Tmpfs {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg("-l").arg(&self.dir).status();
    }
}

/// Fill the file system of `dir` with `dir/filler` until it is full.
fn fill(dir: &Path) -> std::fs::File {
    let mut f = std::fs::File::create(dir.join("filler")).expect("filler");
    let chunk = vec![0u8; 64 * 1024];
    while f.write_all(&chunk).is_ok() {}
    let _ = f.sync_all();
    f
}

fn submit_any(s: &Server, body: &Value) -> (u16, Value) {
    s.post_json("/api/v1/jobs", body)
}

/// On a full disk: 201 means kept (now and after a restart), 204 means gone, a refused
/// write is 507 within a second, reads agree, writes work again once space is freed —
/// without a restart — and the graceful shutdown completes.
#[test]
fn full_disk_201_means_kept_204_means_gone_and_space_returns_without_restart() {
    let Some(fs) = Tmpfs::mount("24m") else {
        eprintln!("skipped: cannot mount a tmpfs here (needs root)");
        return;
    };
    let data = fs.dir.join("data");
    std::fs::create_dir_all(&data).expect("data");
    let mut s = Server::start(&data, &["--workers", "0"]);
    let big_labels: serde_json::Map<String, Value> = (0..16)
        .map(|k| (format!("k{k}"), Value::String("x".repeat(250))))
        .collect();
    // Two finished jobs to delete while the disk is full.
    let doomed: Vec<String> = (0..2)
        .map(|k| {
            let id = s.submit(&tiny_scene(&format!("doomed-{k}"), 10, 0));
            let (st, _) = s.post_json(&format!("/api/v1/jobs/{id}/cancel"), &json!({}));
            assert_eq!(st, 200);
            id
        })
        .collect();

    let filler = fill(&fs.dir);
    let mut kept = Vec::new();
    let mut refused = 0;
    for i in 0..5000 {
        let t0 = Instant::now();
        let (st, v) = submit_any(
            &s,
            &json!({"scene": tiny_scene(&format!("fill-{i}"), 10, 0), "labels": big_labels}),
        );
        match st {
            201 => kept.push(v["id"].as_str().expect("id").to_string()),
            507 => {
                assert_eq!(v["error"], "insufficient_storage", "{v}");
                assert!(
                    v["message"].as_str().unwrap_or("").contains("full"),
                    "says why: {v}"
                );
                assert!(
                    t0.elapsed() < Duration::from_secs(1),
                    "507 took {:?}",
                    t0.elapsed()
                );
                refused += 1;
                if refused == 10 {
                    break;
                }
            }
            other => panic!("submission {i}: unexpected {other}: {v}"),
        }
    }
    assert_eq!(refused, 10, "the disk never filled up");
    // Reads agree: every acknowledged job is there, once, in every view.
    for id in &kept {
        let j = s.job(id);
        assert_eq!(status(&j), "queued", "{j}");
        assert_eq!(j["attempts"], 0, "{j}");
    }
    let listed = s.get_json("/api/v1/jobs?status=queued&limit=500");
    assert_eq!(listed.as_array().map(Vec::len), Some(kept.len().min(500)));
    // Deletes on the full disk: 204 (then gone) or 507 (then kept).
    let mut deleted = Vec::new();
    for id in &doomed {
        let r = s
            .http
            .delete(s.at(&format!("/api/v1/jobs/{id}")))
            .send()
            .expect("delete");
        match r.status().as_u16() {
            204 => deleted.push(id.clone()),
            507 => {}
            other => panic!("delete: {other}"),
        }
    }
    // Space returns: writes work again at once, no restart.
    drop(filler);
    std::fs::remove_file(fs.dir.join("filler")).expect("free space");
    let mut back = None;
    for _ in 0..20 {
        let (st, v) = submit_any(&s, &tiny_scene("after", 10, 0));
        if st == 201 {
            back = Some(v["id"].as_str().expect("id").to_string());
            break;
        }
        assert_eq!(st, 507, "{v}");
        std::thread::sleep(Duration::from_millis(100));
    }
    kept.push(back.expect("writes did not come back once space was freed"));
    for id in &doomed {
        let (st, _) = s.post_json(&format!("/api/v1/jobs/{id}/cancel"), &json!({}));
        // A 204-deleted job is gone; a refused delete left it.
        assert_eq!(st == 404, deleted.contains(id), "{id}: {st}");
    }

    // Graceful shutdown completes (Server::stop panics after 20 s), and a restart keeps
    // everything acknowledged.
    s.restart();
    for id in &kept {
        let r = s
            .http
            .get(s.at(&format!("/api/v1/jobs/{id}")))
            .send()
            .expect("get");
        assert_eq!(
            r.status().as_u16(),
            200,
            "201 job {id} lost after the restart"
        );
    }
    for id in &doomed {
        let r = s
            .http
            .get(s.at(&format!("/api/v1/jobs/{id}")))
            .send()
            .expect("get");
        assert_eq!(
            r.status().as_u16() == 404,
            deleted.contains(id),
            "{id}: a 204 delete must stay deleted, a 507 one must not happen"
        );
    }
    let health = s.get_json("/api/v1/health");
    assert_eq!(
        health["queued"].as_u64(),
        Some(kept.len() as u64),
        "{health}"
    );
    drop(s);
}

/// A second `fracture serve` on the same data folder fails at once naming the folder and
/// the holder's address, and re-queues nothing.
#[test]
fn second_server_on_the_same_folder_fails_at_once_and_requeues_nothing() {
    let dir = tempfile::tempdir().expect("tmp");
    let s = Server::start(dir.path(), &["--workers", "1", "--lease-seconds", "5"]);
    let id = s.submit(&scene("held", 30, 15, 20000, 0));
    let before = s.wait_for(&id, LONG, |j| {
        status(j) == "running" && j["progress"]["step"].as_u64().unwrap_or(0) > 0
            || matches!(status(j), "completed" | "failed")
    });
    assert_eq!(status(&before), "running", "make the scene longer");
    let t0 = Instant::now();
    let out = Command::new(fracture_bin())
        .args(["serve", "--bind", "127.0.0.1:0", "--workers", "0", "--data"])
        .arg(dir.path())
        .env_remove("FRACTURE_TOKEN")
        .output()
        .expect("second server");
    assert!(t0.elapsed() < Duration::from_secs(10), "{:?}", t0.elapsed());
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(&dir.path().display().to_string()),
        "names the folder: {err}"
    );
    let addr = s.url.trim_start_matches("http://");
    assert!(
        err.contains(addr),
        "names the holder's address {addr}: {err}"
    );
    let after = s.job(&id);
    assert_eq!(status(&after), "running", "{after}");
    assert_eq!(after["attempts"], before["attempts"], "{after}");
    assert_eq!(after["worker"], before["worker"], "{after}");
    assert!(after["message"].is_null(), "{after}");
    let (st, _) = s.post_json(&format!("/api/v1/jobs/{id}/cancel"), &json!({}));
    assert_eq!(st, 200);
}

/// `--bind 0.0.0.0` without `--token` is refused unless `--insecure-no-token` says so.
#[test]
fn a_public_bind_without_a_token_is_refused() {
    let dir = tempfile::tempdir().expect("tmp");
    let data = dir.path().join("data");
    let out = Command::new(fracture_bin())
        .args(["serve", "--bind", "0.0.0.0:0", "--workers", "0", "--data"])
        .arg(&data)
        .env_remove("FRACTURE_TOKEN")
        .env_remove("FRACTURE_INSECURE_NO_TOKEN")
        .output()
        .expect("serve");
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--insecure-no-token") && err.contains("--token"),
        "{err}"
    );
    assert!(!data.exists(), "nothing created");
    // With the explicit flag it starts.
    let mut child = Command::new(fracture_bin())
        .args([
            "serve",
            "--bind",
            "0.0.0.0:0",
            "--workers",
            "0",
            "--insecure-no-token",
            "--data",
        ])
        .arg(&data)
        .env_remove("FRACTURE_TOKEN")
        .stderr(Stdio::null())
        .spawn()
        .expect("serve");
    let t0 = Instant::now();
    while !data.join("server.addr").exists() {
        assert!(t0.elapsed() < Duration::from_secs(30), "did not start");
        std::thread::sleep(Duration::from_millis(50));
    }
    let _ = Command::new("kill")
        .arg("-TERM")
        .arg(child.id().to_string())
        .status();
    let _ = child.wait();
}

/// A worker killed under its job: the job's message says how the worker ended (signal,
/// what it usually means), not just "lost".
#[test]
fn a_dead_workers_exit_cause_is_in_the_jobs_message() {
    let dir = tempfile::tempdir().expect("tmp");
    let s = Server::start(
        dir.path(),
        &[
            "--workers",
            "1",
            "--max-attempts",
            "1",
            "--lease-seconds",
            "30",
        ],
    );
    let id = s.submit(&scene("killed", 30, 15, 20000, 0));
    let j = s.wait_for(&id, LONG, |j| {
        status(j) == "running" && j["progress"]["step"].as_u64().unwrap_or(0) > 0
            || matches!(status(j), "completed" | "failed")
    });
    assert_eq!(status(&j), "running", "make the scene longer");
    let pid = std::fs::read_to_string(dir.path().join("workers").join("0.pid")).expect("pid");
    let t0 = Instant::now();
    assert!(
        Command::new("kill")
            .args(["-9", pid.trim()])
            .status()
            .is_ok_and(|s| s.success())
    );
    let j = s.wait_done(&id, LONG);
    // Released by the supervisor at once, not after the 30 s lease.
    assert!(t0.elapsed() < Duration::from_secs(15), "{:?}", t0.elapsed());
    assert_eq!(status(&j), "failed", "{j}");
    let m = j["message"].as_str().unwrap_or("");
    assert!(m.contains("signal 9") && m.contains("SIGKILL"), "{m}");
    assert!(!m.contains("lease expired"), "{m}");
}

/// `--lease-seconds NaN` is a usage error (exit 2), not a panic.
#[test]
fn a_nan_lease_is_a_usage_error() {
    for bad in ["NaN", "inf", "-1", "0", "1e9", "soon"] {
        let out = Command::new(fracture_bin())
            .args([
                "serve",
                "--workers",
                "0",
                &format!("--lease-seconds={bad}"),
                "--data",
            ])
            .arg(std::env::temp_dir().join("fracture-never-created"))
            .output()
            .expect("serve");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{bad}: {err}");
        assert!(
            err.contains("lease-seconds") && !err.contains("panicked"),
            "{bad}: {err}"
        );
    }
}

/// `fracture validate x | head` and `fracture schema | head`: a closed stdout is not a panic.
#[test]
fn a_closed_stdout_pipe_is_not_a_panic() {
    let scene_file = tempfile::NamedTempFile::new().expect("tmp");
    std::fs::write(scene_file.path(), tiny_scene("pipe", 10, 0).to_string()).expect("write");
    for args in [
        vec!["schema".to_string()],
        vec![
            "validate".to_string(),
            scene_file.path().display().to_string(),
        ],
    ] {
        let mut child = Command::new(fracture_bin())
            .args(&args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("spawn");
        drop(child.stdout.take()); // the reader goes away before the output is written
        let mut err = String::new();
        if let Some(mut e) = child.stderr.take() {
            let _ = e.read_to_string(&mut err);
        }
        let st = child.wait().expect("wait");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert_ne!(st.code(), Some(101), "{args:?}: {err}");
    }
}

/// A server whose stderr cannot be written (its log on a full disk) still answers: a log
/// line that cannot be written is dropped, not a panic of the request that logged it.
#[test]
fn an_unwritable_log_does_not_break_requests() {
    let dir = tempfile::tempdir().expect("tmp");
    let Ok(full) = std::fs::OpenOptions::new().write(true).open("/dev/full") else {
        eprintln!("skipped: no /dev/full");
        return;
    };
    let mut child = Command::new(fracture_bin())
        .args(["serve", "--bind", "127.0.0.1:0", "--workers", "0", "--data"])
        .arg(dir.path())
        .env_remove("FRACTURE_TOKEN")
        .env("RUST_LOG", "debug")
        .stderr(full)
        .spawn()
        .expect("serve");
    let t0 = Instant::now();
    let addr = loop {
        if let Ok(a) = std::fs::read_to_string(dir.path().join("server.addr"))
            && !a.trim().is_empty()
        {
            break a.trim().to_string();
        }
        assert!(t0.elapsed() < Duration::from_secs(30), "did not start");
        std::thread::sleep(Duration::from_millis(50));
    };
    let http = reqwest::blocking::Client::new();
    for path in ["/api/v1/health", "/api/v1/jobs/nope"] {
        let r = http.get(format!("http://{addr}{path}")).send().expect(path);
        assert!(
            r.status().as_u16() == 200 || r.status().as_u16() == 404,
            "{path}"
        );
    }
    let r = http
        .post(format!("http://{addr}/api/v1/jobs"))
        .json(&tiny_scene("logless", 10, 0))
        .send()
        .expect("post");
    assert_eq!(r.status().as_u16(), 201);
    let _ = Command::new("kill")
        .arg("-TERM")
        .arg(child.id().to_string())
        .status();
    let _ = child.wait();
}
