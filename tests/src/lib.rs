//! End-to-end test support: start the real `fracture` binary on `127.0.0.1:0` with a
//! temporary data folder and local worker processes, talk to it over loopback HTTP.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

/// The `fracture` binary next to the test executable (`target/<profile>/fracture`).
///
/// `cargo test --workspace` (or `-p fracture-cli -p fracture-e2e`) builds it, because
/// `fracture-cli`'s own integration tests need it; Cargo does not build the binaries of
/// dependencies, so when it is missing this runs `cargo build -p fracture-cli --bin
/// fracture` once (bounded to 10 minutes).
pub fn fracture_bin() -> PathBuf {
    static BUILT: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();
    BUILT
        .get_or_init(|| {
            let exe = std::env::current_exe().expect("test executable path");
            let mut dir = exe.parent().map(Path::to_path_buf).expect("parent");
            // target/<profile>/deps/<test> → target/<profile>
            if dir.ends_with("deps") {
                dir.pop();
            }
            let bin = dir.join(format!("fracture{}", std::env::consts::EXE_SUFFIX));
            if !bin.exists() {
                let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
                let mut cmd = Command::new(cargo);
                cmd.args(["build", "-q", "-p", "fracture-cli", "--bin", "fracture"]);
                if dir.file_name().is_some_and(|n| n == "release") {
                    cmd.arg("--release");
                }
                if let Ok(mut child) = cmd.spawn() {
                    let t0 = Instant::now();
                    while t0.elapsed() < Duration::from_secs(600) {
                        if let Ok(Some(_)) = child.try_wait() {
                            break;
                        }
                        std::thread::sleep(Duration::from_millis(200));
                    }
                    let _ = child.kill();
                    let _ = child.wait();
                }
            }
            assert!(
                bin.exists(),
                "{} is not built: run `cargo test -p fracture-cli -p fracture-e2e`",
                bin.display()
            );
            bin
        })
        .clone()
}

/// Tests start one server at a time: the machine has few cores and leases are short.
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// A running server process.
pub struct Server {
    child: Option<Child>,
    _turn: std::sync::MutexGuard<'static, ()>,
    /// Base URL, `http://127.0.0.1:PORT`.
    pub url: String,
    /// Its data folder.
    pub data: PathBuf,
    args: Vec<String>,
    /// `--bind` of the next launch.
    bind: String,
    /// HTTP client for tests.
    pub http: reqwest::blocking::Client,
}

impl Server {
    /// Start a server on a free port with `extra` arguments (e.g. `--workers 2`).
    pub fn start(data: &Path, extra: &[&str]) -> Server {
        let args: Vec<String> = extra.iter().map(|s| s.to_string()).collect();
        let turn = ONE_AT_A_TIME.lock().unwrap_or_else(|p| p.into_inner());
        let mut s = Server {
            child: None,
            _turn: turn,
            url: String::new(),
            data: data.to_path_buf(),
            args,
            bind: "127.0.0.1:0".into(),
            http: reqwest::blocking::Client::builder()
                .timeout(Duration::from_secs(30))
                .build()
                .expect("client"),
        };
        s.launch();
        s
    }

    fn launch(&mut self) {
        let addr_file = self.data.join("server.addr");
        let _ = std::fs::remove_file(&addr_file);
        let log = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(self.data.join("server.log"))
            .expect("log file");
        let child = Command::new(fracture_bin())
            .arg("serve")
            .arg("--bind")
            .arg(&self.bind)
            .arg("--data")
            .arg(&self.data)
            .args(&self.args)
            .env_remove("FRACTURE_TOKEN")
            .env_remove("FRACTURE_WORKERS")
            .env("RUST_LOG", "info,tower_http=warn,sqlx=warn")
            .stdout(Stdio::null())
            .stderr(log)
            .spawn()
            .expect("start the server");
        self.child = Some(child);
        let t0 = Instant::now();
        loop {
            if let Ok(a) = std::fs::read_to_string(&addr_file)
                && !a.trim().is_empty()
            {
                self.url = format!("http://{}", a.trim());
                break;
            }
            assert!(
                t0.elapsed() < Duration::from_secs(30),
                "server did not start; see {}",
                self.data.join("server.log").display()
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    /// The server's process id.
    pub fn pid(&self) -> u32 {
        self.child.as_ref().map(Child::id).unwrap_or(0)
    }

    /// Stop with SIGTERM (graceful) and wait for the exit (at most 20 s).
    pub fn stop(&mut self) -> std::time::Duration {
        let t0 = Instant::now();
        if let Some(mut c) = self.child.take() {
            let _ = Command::new("kill")
                .arg("-TERM")
                .arg(c.id().to_string())
                .status();
            loop {
                if let Ok(Some(_)) = c.try_wait() {
                    break;
                }
                if t0.elapsed() > Duration::from_secs(20) {
                    let _ = c.kill();
                    let _ = c.wait();
                    panic!("server did not stop within 20 s of SIGTERM");
                }
                std::thread::sleep(Duration::from_millis(50));
            }
        }
        t0.elapsed()
    }

    /// Start again on the same data folder (a new port).
    pub fn restart(&mut self) {
        self.stop();
        self.launch();
    }

    /// Start again on the same data folder and the same port (clients that retry their
    /// connection find it again), after `pause` with no server.
    pub fn restart_on_same_port(&mut self, pause: Duration) {
        self.stop();
        std::thread::sleep(pause);
        self.bind = self
            .url
            .strip_prefix("http://")
            .unwrap_or("127.0.0.1:0")
            .to_string();
        self.launch();
        self.bind = "127.0.0.1:0".into();
    }

    /// Full URL of an API path.
    pub fn at(&self, path: &str) -> String {
        format!("{}{}", self.url, path)
    }

    /// GET a JSON document (panics on non-2xx).
    pub fn get_json(&self, path: &str) -> Value {
        let r = self.http.get(self.at(path)).send().expect("GET");
        assert!(r.status().is_success(), "GET {path}: {}", r.status());
        r.json().expect("json")
    }

    /// POST JSON, returning status and body.
    pub fn post_json(&self, path: &str, body: &Value) -> (u16, Value) {
        let r = self
            .http
            .post(self.at(path))
            .json(body)
            .send()
            .expect("POST");
        let s = r.status().as_u16();
        (s, r.json().unwrap_or(Value::Null))
    }

    /// Submit a scene; returns the job id.
    pub fn submit(&self, body: &Value) -> String {
        let (s, v) = self.post_json("/api/v1/jobs", body);
        assert_eq!(s, 201, "submit: {v}");
        v["id"].as_str().expect("id").to_string()
    }

    /// The job document.
    pub fn job(&self, id: &str) -> Value {
        self.get_json(&format!("/api/v1/jobs/{id}"))
    }

    /// Wait until the job's status satisfies `pred` (panics after `timeout`).
    pub fn wait_for(&self, id: &str, timeout: Duration, pred: impl Fn(&Value) -> bool) -> Value {
        let t0 = Instant::now();
        loop {
            let j = self.job(id);
            if pred(&j) {
                return j;
            }
            assert!(
                t0.elapsed() < timeout,
                "job {id} did not reach the state in {timeout:?}: {j}"
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    /// Wait until the job has ended.
    pub fn wait_done(&self, id: &str, timeout: Duration) -> Value {
        self.wait_for(id, timeout, |j| {
            matches!(
                j["status"].as_str(),
                Some("completed" | "failed" | "cancelled")
            )
        })
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        if let Some(mut c) = self.child.take() {
            // Graceful first so local workers are stopped by their server.
            let _ = Command::new("kill")
                .arg("-TERM")
                .arg(c.id().to_string())
                .status();
            let t0 = Instant::now();
            while t0.elapsed() < Duration::from_secs(10) {
                if let Ok(Some(_)) = c.try_wait() {
                    return;
                }
                std::thread::sleep(Duration::from_millis(50));
            }
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

/// A small valid scene: a 20×10-cell plate (800 particles) with an edge crack, pulled at
/// its top edge; `steps` time steps (Δt ≈ 0.5·h/c_L ≈ 1.96e-7 s), `snapshots` snapshots.
pub fn tiny_scene(name: &str, steps: u32, snapshots: u32) -> Value {
    scene(name, 20, 10, steps, snapshots)
}

/// A plate of `cx`×`cy` cells of 1 mm, Homalite, edge crack, traction on top, bottom fixed.
pub fn scene(name: &str, cx: u32, cy: u32, steps: u32, snapshots: u32) -> Value {
    let h = 0.001;
    let dt = 0.5 * h / 2551.0; // c_L of Homalite in plane strain
    let end = dt * steps as f64 * 0.999;
    let (w, ht) = (cx as f64 * h, cy as f64 * h);
    let mut output = serde_json::json!({
        "history_interval": end / 20.0,
        "fields": ["stress", "velocity", "fringe"],
        "fringe_constant": 22000.0
    });
    if snapshots > 0 {
        output["snapshot_interval"] = Value::from(end / snapshots as f64 * 0.999);
    }
    serde_json::json!({
        "name": name,
        "thickness": 0.005,
        "grid": { "cell_size": h, "min": [0.0, 0.0], "max": [w + 2.0 * h, ht + 2.0 * h] },
        "materials": { "homalite": { "model": "linear_elastic", "density": 1230.0,
                                      "youngs_modulus": 3.96e9, "poissons_ratio": 0.35 } },
        "bodies": [ { "material": "homalite",
                      "region": { "rectangle": { "min": [h, h], "max": [w + h, ht + h] } },
                      "particles_per_cell": 2 } ],
        "cracks": [ { "points": [[0.0, ht / 2.0 + h], [w * 0.4 + h, ht / 2.0 + h]] } ],
        "boundary_conditions": [ { "region": { "rectangle": { "min": [0.0, 0.0], "max": [w + 2.0 * h, 1.5 * h] } },
                                   "velocity": { "y": 0.0 } } ],
        "loads": [ { "region": { "rectangle": { "min": [0.0, ht + 0.5 * h], "max": [w + 2.0 * h, ht + 2.0 * h] } },
                     "traction": [0.0, 2.0e6], "ramp_time": end / 4.0 } ],
        "time": { "end": end, "cfl": 0.5 },
        "output": output
    })
}

/// The process ids whose parent is `pid` (from `/proc/*/stat`; empty where there is none).
pub fn children_of(pid: u32) -> Vec<u32> {
    let Ok(dir) = std::fs::read_dir("/proc") else {
        return Vec::new();
    };
    dir.flatten()
        .filter_map(|e| {
            let child: u32 = e.file_name().to_str()?.parse().ok()?;
            let stat = std::fs::read_to_string(e.path().join("stat")).ok()?;
            // `pid (comm) state ppid …`; comm may hold spaces, so split after the last ')'.
            let ppid: u32 = stat
                .rsplit_once(')')?
                .1
                .split_whitespace()
                .nth(1)?
                .parse()
                .ok()?;
            (ppid == pid).then_some(child)
        })
        .collect()
}

/// A remote worker, `fracture worker --server URL` (a supervisor and its worker process),
/// stopped with its worker process on drop.
pub struct RemoteWorker {
    child: Child,
}

impl RemoteWorker {
    /// Start `fracture worker` against `server` with the worker token `token`; its stderr
    /// goes to `log`.
    pub fn start(server: &Server, token: &str, log: &Path, extra: &[&str]) -> RemoteWorker {
        let log = std::fs::File::create(log).expect("worker log");
        let child = Command::new(fracture_bin())
            .args(["worker", "--server", &server.url, "--threads", "1"])
            .args(extra)
            .env("FRACTURE_WORKER_TOKEN", token)
            .env("RUST_LOG", "info")
            .stdout(Stdio::null())
            .stderr(log)
            .spawn()
            .expect("start the worker");
        RemoteWorker { child }
    }

    /// The supervisor's process id.
    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// Wait for the supervisor to exit by itself (at most `timeout`; `None`: still running).
    pub fn wait_exit(&mut self, timeout: Duration) -> Option<std::process::ExitStatus> {
        let t0 = Instant::now();
        loop {
            if let Ok(Some(s)) = self.child.try_wait() {
                return Some(s);
            }
            if t0.elapsed() >= timeout {
                return None;
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

impl Drop for RemoteWorker {
    fn drop(&mut self) {
        let kids = children_of(self.child.id());
        let _ = self.child.kill();
        let _ = self.child.wait();
        for k in kids {
            let _ = Command::new("kill").arg("-9").arg(k.to_string()).status();
        }
    }
}

/// The steps at which the server resumed job `id` from a checkpoint, from its log
/// (`DATA/server.log`, one "resuming from its checkpoint … step=N" line per resume).
pub fn resumed_steps(data: &Path, id: &str) -> Vec<u64> {
    let log = std::fs::read_to_string(data.join("server.log")).unwrap_or_default();
    log.lines()
        .filter(|l| l.contains("resuming from its checkpoint") && l.contains(id))
        .filter_map(|l| {
            l.split("step=")
                .nth(1)?
                .split(|c: char| !c.is_ascii_digit())
                .next()?
                .parse()
                .ok()
        })
        .collect()
}
