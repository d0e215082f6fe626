//! The service under a hostile tester's conditions, with the real binary: a full disk (a
//! small tmpfs), a second server on the same data folder, a public bind without a token,
//! a worker killed under its job (local, and a remote worker's process under its
//! supervisor), a full disk under a running job's uploads, data files made immutable
//! mid-run (SIGBUS before), bad flags, a closed stdout pipe.
//!
//! The disk-full tests mount a tmpfs and the immutable-files test a loop-mounted ext4 image
//! (root only); where mounting is not allowed they say so and pass without running (the
//! store-level fault injection of `server/tests/safety.rs` still runs).

use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use fracture_e2e::{RemoteWorker, Server, children_of, fracture_bin, scene, tiny_scene};
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

/// An ext4 file system in a loop-mounted image file (tmpfs pages are never written back,
/// so they cannot show what a disk does), unmounted on drop. `Err` says why not (no root,
/// no loop devices, no mkfs.ext4).
struct Ext4 {
    dir: PathBuf,
    _parent: tempfile::TempDir,
}

impl Ext4 {
    fn mount(size_mb: u64) -> Result<Ext4, String> {
        let parent = tempfile::tempdir().map_err(|e| e.to_string())?;
        let img = parent.path().join("fs.img");
        let dir = parent.path().join("mnt");
        std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
        std::fs::File::create(&img)
            .and_then(|f| f.set_len(size_mb << 20))
            .map_err(|e| e.to_string())?;
        let run = |cmd: &mut Command| -> Result<(), String> {
            let out = cmd.output().map_err(|e| format!("{cmd:?}: {e}"))?;
            if out.status.success() {
                Ok(())
            } else {
                Err(format!(
                    "{cmd:?}: {}",
                    String::from_utf8_lossy(&out.stderr).trim()
                ))
            }
        };
        run(Command::new("mkfs.ext4").args(["-q", "-F"]).arg(&img))?;
        run(Command::new("mount")
            .args(["-o", "loop"])
            .arg(&img)
            .arg(&dir))?;
        Ok(Ext4 {
            dir,
            _parent: parent,
        })
    }
}

impl Drop for Ext4 {
    fn drop(&mut self) {
        let _ = Command::new("chattr")
            .arg("-R")
            .arg("-i")
            .arg(&self.dir)
            .status();
        let quiet = Command::new("umount")
            .arg(&self.dir)
            .stderr(Stdio::null())
            .status();
        if !quiet.is_ok_and(|s| s.success()) {
            let _ = Command::new("umount").arg("-l").arg(&self.dir).status();
        }
    }
}

/// Whether process `pid` is running (not gone, not a zombie).
fn alive(pid: u32) -> bool {
    std::fs::read_to_string(format!("/proc/{pid}/stat"))
        .ok()
        .and_then(|s| s.rsplit_once(')').map(|(_, r)| r.trim_start().to_string()))
        .is_some_and(|r| !r.starts_with('Z'))
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

/// The status events of job `id` (SSE), each with the time it arrived, until the job ends.
fn status_events(s: &Server, id: &str) -> std::thread::JoinHandle<Vec<(Instant, Value)>> {
    let url = s.at(&format!("/api/v1/jobs/{id}/events"));
    std::thread::spawn(move || {
        let http = reqwest::blocking::Client::builder()
            .timeout(LONG)
            .build()
            .expect("client");
        let mut out = Vec::new();
        let Ok(r) = http.get(url).send() else {
            return out;
        };
        let mut event = String::new();
        for line in std::io::BufRead::lines(std::io::BufReader::new(r)) {
            let Ok(line) = line else { break };
            if let Some(e) = line.strip_prefix("event:") {
                event = e.trim().to_string();
            } else if let Some(d) = line.strip_prefix("data:")
                && event == "status"
            {
                let v: Value = serde_json::from_str(d.trim()).unwrap_or(Value::Null);
                let done = matches!(status(&v), "completed" | "failed" | "cancelled");
                out.push((Instant::now(), v));
                if done {
                    break;
                }
            }
        }
        out
    })
}

/// Energy rows strictly in time order and snapshots indexed 0, 1, …: no row of the killed
/// attempt survives next to the re-run's.
fn assert_no_duplicate_rows(s: &Server, id: &str) {
    let e = s.get_json(&format!("/api/v1/jobs/{id}/energy"));
    let times: Vec<f64> = e
        .as_array()
        .expect("energy")
        .iter()
        .map(|r| r["time"].as_f64().unwrap_or(f64::NAN))
        .collect();
    assert!(!times.is_empty());
    for w in times.windows(2) {
        assert!(w[1] > w[0], "energy rows repeat or go back: {w:?}");
    }
    let snaps = s.get_json(&format!("/api/v1/jobs/{id}/snapshots"));
    for (k, sn) in snaps.as_array().expect("snapshots").iter().enumerate() {
        assert_eq!(sn["index"].as_u64(), Some(k as u64), "{snaps}");
    }
}

/// A remote `fracture worker` is a supervisor and a worker process: when the worker
/// process is killed (SIGKILL) under its job, the supervisor reports the cause and the
/// server releases the job at once (well before its 60 s lease) with "signal 9" in its
/// message; the new worker process re-runs it to completion without duplicate rows.
#[test]
fn a_remote_workers_death_is_reported_by_its_supervisor_at_once() {
    let dir = tempfile::tempdir().expect("tmp");
    let token = "remote-worker-token";
    let s = Server::start(
        dir.path(),
        &[
            "--workers",
            "0",
            "--worker-token",
            token,
            "--lease-seconds",
            "60",
        ],
    );
    let w = RemoteWorker::start(
        &s,
        token,
        &dir.path().join("worker.log"),
        &["--flush-ms", "100", "--give-up-seconds", "2"],
    );
    let id = s.submit(&scene("remote-killed", 30, 15, 8000, 5));
    let events = status_events(&s, &id);
    let j = s.wait_for(&id, LONG, |j| {
        status(j) == "running" && j["progress"]["step"].as_u64().unwrap_or(0) > 0
            || matches!(status(j), "completed" | "failed")
    });
    assert_eq!(status(&j), "running", "make the scene longer");
    // The worker id is `host-PID-random`, PID the worker process (the supervisor's child).
    let pid: u32 = j["worker"]
        .as_str()
        .and_then(|w| w.rsplit('-').nth(1))
        .and_then(|p| p.parse().ok())
        .expect("pid in the worker id");
    assert_ne!(pid, w.pid(), "the job runs in the supervisor's child");
    assert!(
        children_of(w.pid()).contains(&pid),
        "not the supervisor's child"
    );
    let t0 = Instant::now();
    assert!(
        Command::new("kill")
            .args(["-9", &pid.to_string()])
            .status()
            .is_ok_and(|s| s.success())
    );
    let done = s.wait_done(&id, LONG);
    let events = events.join().expect("events");
    let released = events
        .iter()
        .find(|(_, e)| status(e) == "queued" && e["attempts"] == 1)
        .unwrap_or_else(|| panic!("never released: {events:?}"));
    let m = released.1["message"].as_str().unwrap_or("");
    assert!(
        released.0.duration_since(t0) < Duration::from_secs(15),
        "released after {:?}, not at once",
        released.0.duration_since(t0)
    );
    assert!(m.contains("signal 9") && m.contains("SIGKILL"), "{m}");
    assert!(!m.contains("lease expired"), "{m}");
    assert_eq!(status(&done), "completed", "{done}");
    assert_eq!(done["attempts"], 2, "{done}");
    assert_no_duplicate_rows(&s, &id);
    drop(w);
}

/// A worker whose uploads fail because the server's disk is full does not burn attempts:
/// a remote worker (its log outside the full tmpfs) runs a job on a server whose data
/// folder is a small tmpfs; the tmpfs is filled while the job runs, the worker's uploads
/// get 507 and are retried while it keeps the job (its attempts stay 1, it is not failed
/// as "lost"), and once space is freed a few seconds later the job completes, once.
#[test]
fn uploads_on_a_full_disk_keep_the_job_and_complete_once_space_returns() {
    let Some(fs) = Tmpfs::mount("16m") else {
        eprintln!("skipped: cannot mount a tmpfs here (needs root)");
        return;
    };
    let data = fs.dir.join("data");
    std::fs::create_dir_all(&data).expect("data");
    let logs = tempfile::tempdir().expect("tmp");
    let token = "disk-full-worker-token";
    let s = Server::start(
        &data,
        &[
            "--workers",
            "0",
            "--worker-token",
            token,
            "--lease-seconds",
            "30",
        ],
    );
    let log = logs.path().join("worker.log");
    let _w = RemoteWorker::start(&s, token, &log, &["--flush-ms", "50"]);
    let id = s.submit(&scene("disk-full-run", 30, 15, 20000, 60));
    let j = s.wait_for(&id, LONG, |j| {
        status(j) == "running" && j["progress"]["step"].as_u64().unwrap_or(0) > 0
            || matches!(status(j), "completed" | "failed")
    });
    assert_eq!(status(&j), "running", "make the scene longer");
    let filler = fill(&fs.dir);
    // Wait until the worker has been refused (507) at least once.
    let t0 = Instant::now();
    let said = || {
        std::fs::read_to_string(&log)
            .unwrap_or_default()
            .contains("the server's disk is full; retrying")
    };
    while !said() {
        let j = s.job(&id);
        assert_eq!(status(&j), "running", "ended before a 507: {j}");
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "the worker never met the full disk"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    // A few seconds on the full disk: the job stays running, its first attempt.
    let full_since = Instant::now();
    while full_since.elapsed() < Duration::from_secs(3) {
        let j = s.job(&id);
        assert_eq!(status(&j), "running", "{j}");
        assert_eq!(j["attempts"], 1, "attempts climb on a full disk: {j}");
        std::thread::sleep(Duration::from_millis(200));
    }
    drop(filler);
    std::fs::remove_file(fs.dir.join("filler")).expect("free space");
    let done = s.wait_done(&id, LONG);
    assert_eq!(status(&done), "completed", "{done}");
    assert_eq!(done["attempts"], 1, "{done}");
    assert_no_duplicate_rows(&s, &id);
    drop(s);
}

/// The data folder's files become unwritable mid-run (`chattr -R +i`, after `sync` has
/// written the pages back, on a real ext4 file system): the server used to die of SIGBUS
/// at its next write to SQLite's memory-mapped WAL index (`fracture.db-shm`). Now every
/// request is answered within a second, writes with 507 (and reads too, once an I/O error
/// has broken the store's connection: a new one cannot lock a read-only file), the server
/// stays up, and once the files are writable again writes and reads come back without a
/// restart, with every acknowledged job.
#[test]
fn files_made_immutable_mid_run_give_507_not_sigbus() {
    let fs = match Ext4::mount(64) {
        Ok(fs) => fs,
        Err(why) => {
            eprintln!("skipped: cannot mount an ext4 image here ({why})");
            return;
        }
    };
    let data = fs.dir.join("data");
    std::fs::create_dir_all(&data).expect("data");
    let s = Server::start(&data, &["--workers", "1", "--lease-seconds", "30"]);
    let running = s.submit(&scene("immutable-run", 30, 15, 20000, 30));
    s.wait_for(&running, LONG, |j| status(j) != "queued");
    let before = s.submit(&tiny_scene("before", 10, 0));
    assert!(Command::new("sync").status().is_ok_and(|s| s.success()));
    let chattr = Command::new("chattr")
        .arg("-R")
        .arg("+i")
        .arg(&data)
        .status();
    if !chattr.is_ok_and(|s| s.success()) {
        eprintln!("skipped: chattr +i does not work here");
        return;
    }
    let mut refused = 0;
    for i in 0..20 {
        let t0 = Instant::now();
        let r = s
            .http
            .post(s.at("/api/v1/jobs"))
            .json(&tiny_scene(&format!("while-immutable-{i}"), 10, 0))
            .send();
        assert!(
            alive(s.pid()),
            "the server died (SIGBUS?) at submission {i}: {r:?}"
        );
        let r = r.expect("an answer");
        let st = r.status().as_u16();
        let v: Value = r.json().unwrap_or(Value::Null);
        assert!(
            t0.elapsed() < Duration::from_secs(1),
            "took {:?}",
            t0.elapsed()
        );
        match st {
            507 => {
                assert_eq!(v["error"], "insufficient_storage", "{v}");
                refused += 1;
            }
            201 => {}
            other => panic!("submission {i}: {other}: {v}"),
        }
        let t0 = Instant::now();
        let r = s
            .http
            .get(s.at(&format!("/api/v1/jobs/{before}")))
            .send()
            .expect("a read is answered");
        assert!(
            matches!(r.status().as_u16(), 200 | 507),
            "read: {}",
            r.status()
        );
        assert!(t0.elapsed() < Duration::from_secs(1));
    }
    assert!(
        refused > 0,
        "no write was refused: the files were not unwritable"
    );
    assert!(alive(s.pid()));
    // Writable again: writes and reads come back without a restart.
    let _ = Command::new("chattr")
        .arg("-R")
        .arg("-i")
        .arg(&data)
        .status();
    let t0 = Instant::now();
    let after = loop {
        let (st, v) = submit_any(&s, &tiny_scene("after", 10, 0));
        if st == 201 {
            break v["id"].as_str().expect("id").to_string();
        }
        assert_eq!(st, 507, "{v}");
        assert!(
            t0.elapsed() < Duration::from_secs(10),
            "writes did not come back"
        );
        std::thread::sleep(Duration::from_millis(100));
    };
    assert_eq!(status(&s.job(&before)), "queued");
    assert_eq!(status(&s.job(&after)), "queued");
    let (st, _) = s.post_json(&format!("/api/v1/jobs/{running}/cancel"), &json!({}));
    assert_eq!(st, 200);
    drop(s);
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
