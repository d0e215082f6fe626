//! Service commands: `serve`, `worker`, `submit`, `sweep`.

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Duration;

use clap::Parser;
use fracture_api::jobs::JobStatus;
use tokio::process::{Child, Command};
use tokio::sync::watch;

use crate::client::{self, SubmitConfig, SubmitOutcome, WorkerConfig};
use crate::config::{Config, Limits};
use crate::files::JobFiles;
use crate::server::{AppState, random_hex};
use crate::store::Store;

/// Arguments of `fracture serve`.
#[derive(clap::Args, Debug, Clone)]
pub struct ServeArgs {
    /// Address to listen on (`127.0.0.1:0` picks a free port; the bound address is written
    /// to `<data>/server.addr`).
    #[arg(long, env = "FRACTURE_BIND", default_value = "127.0.0.1:8080")]
    pub bind: String,
    /// Data folder: the SQLite store and `jobs/<id>/fields.mcap`.
    #[arg(long, env = "FRACTURE_DATA", default_value = "./fracture-data")]
    pub data: PathBuf,
    /// Local worker processes (default: one per two cores, at least one; 0: none).
    #[arg(long, env = "FRACTURE_WORKERS")]
    pub workers: Option<usize>,
    /// Solver threads per local worker (default: cores / workers, at least one).
    #[arg(long, env = "FRACTURE_WORKER_THREADS")]
    pub worker_threads: Option<usize>,
    /// API token required (as `Authorization: Bearer`) for submit, cancel and delete.
    #[arg(long, env = "FRACTURE_TOKEN", hide_env_values = true)]
    pub token: Option<String>,
    /// Token of the worker routes (default: generated at start, given to local workers).
    #[arg(long, env = "FRACTURE_WORKER_TOKEN", hide_env_values = true)]
    pub worker_token: Option<String>,
    /// Lease of a claimed job without heartbeats (s).
    #[arg(long, env = "FRACTURE_LEASE_SECONDS", default_value_t = 30.0)]
    pub lease_seconds: f64,
    /// Claims of a job before a lost lease fails it.
    #[arg(long, env = "FRACTURE_MAX_ATTEMPTS", default_value_t = 3)]
    pub max_attempts: u32,
    /// Most particles a scene may have.
    #[arg(long, env = "FRACTURE_MAX_PARTICLES", default_value_t = Limits::default().max_particles)]
    pub max_particles: u64,
    /// Most time steps a scene may take.
    #[arg(long, env = "FRACTURE_MAX_STEPS", default_value_t = Limits::default().max_steps)]
    pub max_steps: u64,
    /// Most snapshots × grid nodes a scene may record.
    #[arg(long, env = "FRACTURE_MAX_SNAPSHOT_VOLUME", default_value_t = Limits::default().max_snapshot_volume)]
    pub max_snapshot_volume: u64,
    /// Largest request body of the public API (bytes).
    #[arg(long, env = "FRACTURE_MAX_BODY_BYTES", default_value_t = Limits::default().max_body_bytes)]
    pub max_body_bytes: usize,
    /// Most jobs (parameter combinations) one sweep may create.
    #[arg(long, env = "FRACTURE_MAX_SWEEP_JOBS", default_value_t = Limits::default().max_sweep_jobs)]
    pub max_sweep_jobs: u64,
}

#[derive(Parser, Debug)]
struct ServeOnly {
    #[command(flatten)]
    args: ServeArgs,
}

impl Default for ServeArgs {
    fn default() -> Self {
        ServeArgs::from_env()
    }
}

impl ServeArgs {
    /// Defaults and `FRACTURE_*` variables (what `cargo run --release` with no arguments uses).
    pub fn from_env() -> Self {
        match ServeOnly::try_parse_from(["fracture"]) {
            Ok(s) => s.args,
            Err(e) => e.exit(),
        }
    }
}

/// Arguments of `fracture worker`.
#[derive(clap::Args, Debug)]
pub struct WorkerArgs {
    /// URL of the server.
    #[arg(long, env = "FRACTURE_SERVER", default_value = "http://127.0.0.1:8080")]
    pub server: String,
    /// Worker token of the server.
    #[arg(long, env = "FRACTURE_WORKER_TOKEN", hide_env_values = true)]
    pub token: String,
    /// Solver threads (0: the solver's default).
    #[arg(long, env = "FRACTURE_THREADS", default_value_t = 0)]
    pub threads: usize,
    /// How often the run reports progress and sends its rows (ms).
    #[arg(long, default_value_t = 500)]
    pub flush_ms: u64,
    /// Exit after the server has been unreachable this long (s).
    #[arg(long, default_value_t = 120)]
    pub give_up_seconds: u64,
    /// Exit when this process is no longer the parent (set for a server's local workers).
    #[arg(long, hide = true)]
    pub parent_pid: Option<u32>,
}

/// Arguments of `fracture submit`.
#[derive(clap::Args, Debug)]
pub struct SubmitArgs {
    /// Scene JSON file (a scene, or `{"scene": …, "priority": …, "labels": …}`).
    pub scene: PathBuf,
    /// URL of the server.
    #[arg(long, env = "FRACTURE_SERVER", default_value = "http://127.0.0.1:8080")]
    pub server: String,
    /// API token.
    #[arg(long, env = "FRACTURE_TOKEN", hide_env_values = true)]
    pub token: Option<String>,
    /// Priority (higher runs first).
    #[arg(long)]
    pub priority: Option<i64>,
    /// Label `key=value` (repeatable).
    #[arg(long = "label")]
    pub labels: Vec<String>,
    /// Show progress and exit with the job's outcome (0 completed, 3 failed, 4 cancelled).
    #[arg(long)]
    pub wait: bool,
}

/// Arguments of `fracture sweep`.
#[derive(clap::Args, Debug)]
pub struct SweepArgs {
    /// Base scene JSON file (a scene, or `{"scene": …}`).
    pub scene: PathBuf,
    /// A swept parameter, `json.path=v1,v2,…` (repeatable; one job per combination).
    /// Numeric path segments index arrays; each value is read as JSON (a number, `true`,
    /// `"text"`), or as a string if it is not JSON; `path=[…]` gives the values as a JSON
    /// array (for values with commas).
    #[arg(long = "param", required = true)]
    pub params: Vec<String>,
    /// URL of the server.
    #[arg(long, env = "FRACTURE_SERVER", default_value = "http://127.0.0.1:8080")]
    pub server: String,
    /// API token.
    #[arg(long, env = "FRACTURE_TOKEN", hide_env_values = true)]
    pub token: Option<String>,
    /// Name of the sweep (default: the scene's name).
    #[arg(long)]
    pub name: Option<String>,
    /// Priority of its jobs (higher runs first).
    #[arg(long)]
    pub priority: Option<i64>,
    /// Label `key=value` for every job (repeatable).
    #[arg(long = "label")]
    pub labels: Vec<String>,
    /// Show the progress of all jobs and exit with the outcome (0 all completed, 3 some
    /// failed, 4 some cancelled and none failed).
    #[arg(long)]
    pub wait: bool,
}

/// Parse one `--param path=v1,v2` into the path and its values.
pub fn parse_param(arg: &str) -> Result<(String, Vec<serde_json::Value>), String> {
    let (path, values) = arg
        .split_once('=')
        .ok_or_else(|| format!("--param must be path=v1,v2,…, got `{arg}`"))?;
    let path = path.trim();
    if path.is_empty() {
        return Err(format!("--param `{arg}`: the path is empty"));
    }
    let values = values.trim();
    let list: Vec<serde_json::Value> = if values.starts_with('[') {
        serde_json::from_str(values)
            .map_err(|e| format!("--param {path}: `{values}` is not a JSON array: {e}"))?
    } else {
        values
            .split(',')
            .map(str::trim)
            .filter(|v| !v.is_empty())
            .map(|v| {
                serde_json::from_str(v).unwrap_or_else(|_| serde_json::Value::String(v.into()))
            })
            .collect()
    };
    if list.is_empty() {
        return Err(format!("--param {path}: no values"));
    }
    Ok((path.to_string(), list))
}

/// The body of `POST /api/v1/sweeps` as text: the parameters in the order given (a
/// `serde_json::Value` would sort them).
pub fn sweep_body(
    scene: &serde_json::Value,
    params: &[(String, Vec<serde_json::Value>)],
    name: Option<&str>,
    priority: i64,
    labels: &serde_json::Map<String, serde_json::Value>,
) -> String {
    let params: Vec<String> = params
        .iter()
        .map(|(p, v)| {
            format!(
                "{}: {}",
                serde_json::Value::String(p.clone()),
                serde_json::Value::Array(v.clone())
            )
        })
        .collect();
    let mut body = format!(
        "{{\"scene\": {scene}, \"parameters\": {{{}}}, \"priority\": {priority}, \"labels\": {}",
        params.join(", "),
        serde_json::Value::Object(labels.clone())
    );
    if let Some(n) = name {
        body.push_str(&format!(
            ", \"name\": {}",
            serde_json::Value::String(n.into())
        ));
    }
    body.push('}');
    body
}

/// A JSON file the command line names; an unreadable or invalid file is reported on stderr
/// and gives exit code 2.
fn read_json_file(path: &std::path::Path) -> Result<serde_json::Value, ExitCode> {
    let text = std::fs::read_to_string(path).map_err(|e| {
        eprintln!("cannot read {}: {e}", path.display());
        ExitCode::from(2)
    })?;
    serde_json::from_str(&text).map_err(|e| {
        eprintln!("{} is not valid JSON: {e}", path.display());
        ExitCode::from(2)
    })
}

/// `--label key=value` arguments as a JSON object; a malformed one is reported on stderr and
/// gives exit code 2.
fn parse_labels(args: &[String]) -> Result<serde_json::Map<String, serde_json::Value>, ExitCode> {
    let mut labels = serde_json::Map::new();
    for l in args {
        let Some((k, v)) = l.split_once('=') else {
            eprintln!("--label must be key=value, got `{l}`");
            return Err(ExitCode::from(2));
        };
        labels.insert(k.to_string(), serde_json::Value::String(v.to_string()));
    }
    Ok(labels)
}

/// `fracture sweep`.
pub fn sweep(a: SweepArgs) -> ExitCode {
    let doc = match read_json_file(&a.scene) {
        Ok(v) => v,
        Err(code) => return code,
    };
    let scene = match doc.get("scene") {
        Some(s) if doc.get("grid").is_none() => s.clone(),
        _ => doc,
    };
    let mut params = Vec::new();
    for p in &a.params {
        match parse_param(p) {
            Ok(p) => params.push(p),
            Err(e) => {
                eprintln!("{e}");
                return ExitCode::from(2);
            }
        }
    }
    let labels = match parse_labels(&a.labels) {
        Ok(l) => l,
        Err(code) => return code,
    };
    let cfg = client::SweepConfig {
        server: a.server,
        token: a.token,
        body: sweep_body(
            &scene,
            &params,
            a.name.as_deref(),
            a.priority.unwrap_or(0),
            &labels,
        ),
        wait: a.wait,
    };
    let mut out = std::io::stdout();
    match client::sweep(&cfg, &mut out) {
        Ok(client::SweepOutcome::Rejected(_, msg)) => {
            eprintln!("{msg}");
            ExitCode::from(2)
        }
        Ok(client::SweepOutcome::Submitted(_)) => ExitCode::SUCCESS,
        Ok(client::SweepOutcome::Ended(_, s)) => match s.status.as_str() {
            "completed" => ExitCode::SUCCESS,
            "cancelled" => ExitCode::from(4),
            _ => ExitCode::from(3),
        },
        Err(e) => {
            eprintln!("sweep failed: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn init_tracing() {
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("info,tower_http=warn,sqlx=warn"));
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .try_init();
}

fn runtime() -> std::io::Result<tokio::runtime::Runtime> {
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(4)
        .enable_all()
        .build()
}

/// `fracture serve`.
pub fn serve(a: ServeArgs) -> ExitCode {
    init_tracing();
    let rt = match runtime() {
        Ok(rt) => rt,
        Err(e) => {
            tracing::error!(error = %e, "cannot start the runtime");
            return ExitCode::FAILURE;
        }
    };
    match rt.block_on(serve_async(a)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            tracing::error!(error = format!("{e:#}"), "server failed");
            ExitCode::FAILURE
        }
    }
}

fn write_atomically(path: &Path, text: &str) -> std::io::Result<()> {
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, text)?;
    std::fs::rename(tmp, path)
}

async fn serve_async(a: ServeArgs) -> anyhow::Result<()> {
    use anyhow::Context;
    std::fs::create_dir_all(&a.data)
        .with_context(|| format!("cannot create the data folder {}", a.data.display()))?;
    let store = Store::open(&a.data.join("fracture.db"))
        .await
        .context("cannot open the store")?;
    // Jobs left running by a previous server go back to the queue (their workers' late
    // writes are fenced off; a new claim restarts their files).
    let recovered = store
        .release_running("re-queued after a server restart")
        .await?;
    if !recovered.is_empty() {
        tracing::info!(jobs = recovered.len(), "re-queued jobs left running");
    }
    let cores = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(2);
    let workers = a.workers.unwrap_or((cores / 2).max(1));
    let worker_threads = a.worker_threads.unwrap_or((cores / workers.max(1)).max(1));
    let lease = Duration::from_secs_f64(a.lease_seconds.clamp(0.5, 3600.0));
    let cfg = Config {
        api_token: a.token.clone().filter(|t| !t.is_empty()),
        worker_token: a
            .worker_token
            .clone()
            .filter(|t| !t.is_empty())
            .unwrap_or_else(|| random_hex(24)),
        lease,
        max_attempts: a.max_attempts.max(1),
        claim_wait: Duration::from_secs(20),
        limits: Limits {
            max_particles: a.max_particles,
            max_steps: a.max_steps,
            max_snapshot_volume: a.max_snapshot_volume,
            max_body_bytes: a.max_body_bytes,
            max_sweep_jobs: a.max_sweep_jobs,
            ..Limits::default()
        },
        local_workers: workers,
    };
    let files = JobFiles::new(&a.data);
    let (state, shutdown_tx) = AppState::new(store.clone(), cfg, files.clone());
    let listener = tokio::net::TcpListener::bind(&a.bind)
        .await
        .with_context(|| format!("cannot listen on {}", a.bind))?;
    let addr = listener.local_addr()?;
    write_atomically(&a.data.join("server.addr"), &addr.to_string())?;
    tracing::info!(%addr, workers, data = %a.data.display(), "listening on http://{addr}");

    let reaper = tokio::spawn(
        state
            .clone()
            .run_reaper((lease / 4).clamp(Duration::from_millis(200), Duration::from_secs(2))),
    );
    let supervisor = tokio::spawn(supervise_workers(
        workers,
        worker_threads,
        local_url(addr),
        state.cfg.worker_token.clone(),
        a.data.join("workers"),
        state.shutdown.clone(),
    ));

    let app = crate::app(state.clone());
    let mut sd = state.shutdown.clone();
    let server = axum::serve(listener, app)
        .with_graceful_shutdown(async move {
            let _ = sd.wait_for(|s| *s).await;
        })
        .into_future();
    let server = tokio::spawn(server);

    shutdown_signal().await;
    tracing::info!("shutting down");
    let _ = shutdown_tx.send(true);
    // Stop the local workers first so they write nothing more, then give their jobs back.
    let _ = tokio::time::timeout(Duration::from_secs(10), supervisor).await;
    let released = store
        .release_running("re-queued: the server shut down while it ran")
        .await?;
    for j in &released {
        state.announce(j);
    }
    let f = files.clone();
    let _ = tokio::task::spawn_blocking(move || f.finish_all()).await;
    // SSE streams and long polls end on the shutdown signal; bound the drain anyway.
    match tokio::time::timeout(Duration::from_secs(5), server).await {
        Ok(_) => {}
        Err(_) => tracing::warn!("connections still open after 5 s; closing"),
    }
    let _ = reaper.await;
    store.close().await;
    tracing::info!(released = released.len(), "stopped");
    Ok(())
}

fn local_url(addr: SocketAddr) -> String {
    let ip = if addr.ip().is_unspecified() {
        match addr {
            SocketAddr::V4(_) => "127.0.0.1".to_string(),
            SocketAddr::V6(_) => "[::1]".to_string(),
        }
    } else if addr.is_ipv6() {
        format!("[{}]", addr.ip())
    } else {
        addr.ip().to_string()
    };
    format!("http://{ip}:{}", addr.port())
}

async fn shutdown_signal() {
    let ctrl_c = async {
        let _ = tokio::signal::ctrl_c().await;
    };
    #[cfg(unix)]
    let term = async {
        match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
            Ok(mut s) => {
                s.recv().await;
            }
            Err(_) => std::future::pending::<()>().await,
        }
    };
    #[cfg(not(unix))]
    let term = std::future::pending::<()>();
    tokio::select! {
        _ = ctrl_c => {}
        _ = term => {}
    }
}

fn spawn_worker(
    exe: &Path,
    url: &str,
    token: &str,
    threads: usize,
    slot: usize,
    pid_dir: &Path,
) -> std::io::Result<Child> {
    let child = Command::new(exe)
        .arg("worker")
        .arg("--server")
        .arg(url)
        .arg("--threads")
        .arg(threads.to_string())
        .arg("--parent-pid")
        .arg(std::process::id().to_string())
        .env("FRACTURE_WORKER_TOKEN", token)
        .env_remove("FRACTURE_BIND")
        .kill_on_drop(true)
        .spawn()?;
    if let Some(pid) = child.id() {
        let _ = write_atomically(&pid_dir.join(format!("{slot}.pid")), &pid.to_string());
    }
    Ok(child)
}

/// Keep `n` local worker processes alive until shutdown, then stop them.
async fn supervise_workers(
    n: usize,
    threads: usize,
    url: String,
    token: String,
    pid_dir: PathBuf,
    mut shutdown: watch::Receiver<bool>,
) {
    if n == 0 {
        return;
    }
    let exe = match std::env::current_exe() {
        Ok(e) => e,
        Err(e) => {
            tracing::error!(error = %e, "cannot find this executable; no local workers");
            return;
        }
    };
    let _ = std::fs::create_dir_all(&pid_dir);
    let exe = Arc::new(exe);
    let mut slots = Vec::new();
    for slot in 0..n {
        let (exe, url, token, pid_dir) = (exe.clone(), url.clone(), token.clone(), pid_dir.clone());
        let mut sd = shutdown.clone();
        slots.push(tokio::spawn(async move {
            let mut backoff = Duration::from_millis(200);
            loop {
                if *sd.borrow() {
                    return;
                }
                let mut child = match spawn_worker(&exe, &url, &token, threads, slot, &pid_dir) {
                    Ok(c) => c,
                    Err(e) => {
                        tracing::error!(error = %e, slot, "cannot start a worker");
                        tokio::time::sleep(Duration::from_secs(2)).await;
                        continue;
                    }
                };
                let started = tokio::time::Instant::now();
                tokio::select! {
                    st = child.wait() => {
                        tracing::warn!(slot, status = ?st, "worker exited; restarting");
                        if started.elapsed() > Duration::from_secs(10) {
                            backoff = Duration::from_millis(200);
                        }
                        tokio::time::sleep(backoff).await;
                        backoff = (backoff * 2).min(Duration::from_secs(5));
                    }
                    _ = crate::server::until_shutdown(&mut sd) => {
                        let _ = child.start_kill();
                        let _ = child.wait().await;
                        return;
                    }
                }
            }
        }));
    }
    let _ = shutdown.wait_for(|s| *s).await;
    for s in slots {
        let _ = s.await;
    }
}

/// `fracture worker`.
pub fn worker(a: WorkerArgs) -> ExitCode {
    init_tracing();
    let host = std::fs::read_to_string("/etc/hostname")
        .map(|h| h.trim().to_string())
        .unwrap_or_else(|_| "host".into());
    let cfg = WorkerConfig {
        server: a.server,
        token: a.token,
        threads: a.threads,
        flush_every: Duration::from_millis(a.flush_ms.max(10)),
        give_up: Duration::from_secs(a.give_up_seconds),
        parent_pid: a.parent_pid,
        worker_id: format!("{host}-{}-{}", std::process::id(), random_hex(3)),
    };
    match client::run_worker(cfg) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            tracing::error!(error = format!("{e:#}"), "worker stopped");
            ExitCode::FAILURE
        }
    }
}

/// `fracture submit`.
pub fn submit(a: SubmitArgs) -> ExitCode {
    let mut body = match read_json_file(&a.scene) {
        Ok(v) => v,
        Err(code) => return code,
    };
    if a.priority.is_some() || !a.labels.is_empty() {
        let labels = match parse_labels(&a.labels) {
            Ok(l) => l,
            Err(code) => return code,
        };
        let scene = match body.get("scene") {
            Some(s) if body.get("grid").is_none() => s.clone(),
            _ => body,
        };
        body = serde_json::json!({
            "scene": scene,
            "priority": a.priority.unwrap_or(0),
            "labels": labels,
        });
    }
    let cfg = SubmitConfig {
        server: a.server,
        token: a.token,
        body,
        wait: a.wait,
    };
    let mut out = std::io::stdout();
    match client::submit(&cfg, &mut out) {
        Ok(SubmitOutcome::Rejected(_, msg)) => {
            eprintln!("{msg}");
            ExitCode::from(2)
        }
        Ok(SubmitOutcome::Submitted(_)) => ExitCode::SUCCESS,
        Ok(SubmitOutcome::Ended(_, status, message)) => {
            if let Some(m) = message {
                eprintln!("{m}");
            }
            match status {
                JobStatus::Completed => ExitCode::SUCCESS,
                JobStatus::Cancelled => ExitCode::from(4),
                _ => ExitCode::from(3),
            }
        }
        Err(e) => {
            eprintln!("submit failed: {e:#}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn params_parse_numbers_strings_and_arrays() {
        let (p, v) =
            parse_param("cracks.0.propagation.toughness=25, 100,2.5e2").unwrap_or_default();
        assert_eq!(p, "cracks.0.propagation.toughness");
        assert_eq!(
            v,
            [
                serde_json::json!(25),
                serde_json::json!(100),
                serde_json::json!(250.0)
            ]
        );
        let (_, v) = parse_param("analysis=plane_strain,\"plane_stress\"").unwrap_or_default();
        assert_eq!(
            v,
            [
                serde_json::json!("plane_strain"),
                serde_json::json!("plane_stress")
            ]
        );
        let (_, v) = parse_param("cracks.0.points.1=[[0.1,0.2],[0.3,0.4]]").unwrap_or_default();
        assert_eq!(v.len(), 2);
        assert!(parse_param("toughness").is_err_and(|e| e.contains("path=v1,v2")));
        assert!(parse_param("=1").is_err());
        assert!(parse_param("a=").is_err_and(|e| e.contains("no values")));
        assert!(parse_param("a=[1,").is_err_and(|e| e.contains("not a JSON array")));
    }

    #[test]
    fn sweep_body_keeps_the_parameter_order() {
        let params = vec![
            ("z.b".to_string(), vec![serde_json::json!(1)]),
            ("a.c".to_string(), vec![serde_json::json!("x")]),
        ];
        let body = sweep_body(
            &serde_json::json!({"name": "s"}),
            &params,
            Some("n"),
            2,
            &serde_json::Map::new(),
        );
        let z = body.find("z.b").unwrap_or(usize::MAX);
        let a = body.find("a.c").unwrap_or(0);
        assert!(z < a, "{body}");
        let v: serde_json::Value = serde_json::from_str(&body).unwrap_or_default();
        assert_eq!(v["name"], "n");
        assert_eq!(v["priority"], 2);
        assert_eq!(v["parameters"]["a.c"][0], "x");
    }
}
