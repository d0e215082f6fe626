//! `fracture serve`: the service process. Opens the store, re-queues jobs a previous server
//! left running, serves the API and dashboard, keeps the local worker processes alive
//! (`fracture worker` children of this executable), and shuts down gracefully.

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Duration;

use clap::Parser;
use tokio::process::{Child, Command};
use tokio::sync::watch;

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

/// Log to stderr with `RUST_LOG` (default `info`), coloured on a terminal.
pub fn init_tracing() {
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
