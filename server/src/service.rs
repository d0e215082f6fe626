//! `fracture serve`: the service process. Takes the data folder's lock (one server per
//! folder), opens the store, re-queues jobs a previous server left running, serves the API
//! and dashboard, keeps the local worker processes alive (`fracture worker` children of
//! this executable; a child's exit cause and the last lines of its stderr go into the
//! message of the job it held), and shuts down gracefully.

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Duration;

use clap::Parser;
use tokio::process::{Child, Command};

use fracture_api::protocol::{STDERR_TAIL, exit_cause};

use crate::config::{Config, DatabaseUrl, Limits};
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
    /// Data folder: the SQLite store (unless `--database`) and `jobs/<id>/fields.mcap`.
    #[arg(long, env = "FRACTURE_DATA", default_value = "./fracture-data")]
    pub data: PathBuf,
    /// The store on a PostgreSQL server instead of the embedded SQLite file
    /// (`postgres://user[:password]@host[:port]/database`); results files stay in `--data`.
    // Checked at start (`DatabaseUrl::parse`), not by the argument parser, whose error
    // would show the value with its password.
    #[arg(long, env = "FRACTURE_DATABASE", hide_env_values = true)]
    pub database: Option<String>,
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
    /// Lease of a claimed job without heartbeats (s, 0.5 to 3600).
    #[arg(long, env = "FRACTURE_LEASE_SECONDS", default_value_t = 30.0, value_parser = parse_lease)]
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
    /// Most memory one run may need, by the estimate of `fracture_api::cost` (bytes;
    /// default: half of this machine's memory). Local workers are capped at the estimate
    /// of their job plus a margin.
    #[arg(long, env = "FRACTURE_MAX_MEMORY_BYTES")]
    pub max_memory_bytes: Option<u64>,
    /// Most work one run may take: particles × time steps.
    #[arg(long, env = "FRACTURE_MAX_PARTICLE_STEPS", default_value_t = Limits::default().max_particle_steps)]
    pub max_particle_steps: u64,
    /// A host name the server answers to besides loopback names and IP literals
    /// (repeatable, or comma-separated in the variable; `*`: any). Guards against DNS
    /// rebinding.
    #[arg(
        long = "allowed-host",
        env = "FRACTURE_ALLOWED_HOSTS",
        value_delimiter = ','
    )]
    pub allowed_hosts: Vec<String>,
    /// Listen on a non-loopback address without `--token`: anyone who can reach the port
    /// may submit, cancel and delete jobs.
    #[arg(long, env = "FRACTURE_INSECURE_NO_TOKEN")]
    pub insecure_no_token: bool,
}

/// `--lease-seconds`: a finite number of seconds in 0.5..=3600.
fn parse_lease(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("`{s}` is not a number of seconds"))?;
    if v.is_finite() && (0.5..=3600.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("{v} is not in 0.5..=3600 seconds"))
    }
}

/// Half of this machine's memory (`/proc/meminfo`), or 8 GiB where it cannot be read.
pub fn default_max_memory() -> u64 {
    std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find_map(|l| l.strip_prefix("MemTotal:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        })
        .map(|kb| kb.saturating_mul(1024) / 2)
        .unwrap_or(crate::config::DEFAULT_MAX_MEMORY_BYTES)
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
    // A log that cannot be written (stderr redirected to a full disk) is dropped: with
    // `log_internal_errors` on, tracing-subscriber reports it with `eprintln!`, which
    // panics when stderr fails — every request that logged anything died with it.
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .log_internal_errors(false)
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

/// Refuse to listen beyond this machine without an API token (unless the user says so).
fn check_public_bind(a: &ServeArgs) -> anyhow::Result<()> {
    use std::net::ToSocketAddrs;
    let has_token = a.token.as_deref().is_some_and(|t| !t.is_empty());
    if has_token || a.insecure_no_token {
        return Ok(());
    }
    let addrs: Vec<SocketAddr> = a
        .bind
        .to_socket_addrs()
        .map_err(|e| anyhow::anyhow!("cannot resolve --bind {}: {e}", a.bind))?
        .collect();
    if let Some(public) = addrs.iter().find(|x| !x.ip().is_loopback()) {
        anyhow::bail!(
            "refusing to listen on {public} (reachable from other machines) without an API \
             token: anyone who reaches the port could submit, cancel and delete jobs. Pass \
             --token (or FRACTURE_TOKEN), or --insecure-no-token if the network is trusted"
        );
    }
    Ok(())
}

/// The exclusive lock of a data folder: `<data>/server.lock`, held (flock) for the life of
/// the process and released by the OS when it dies; its text names the holder.
pub struct DataLock {
    file: std::fs::File,
    path: PathBuf,
}

impl DataLock {
    /// Take the lock of `data`, or fail at once naming the folder and the holder.
    pub fn acquire(data: &Path) -> anyhow::Result<DataLock> {
        let path = data.join("server.lock");
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .map_err(|e| anyhow::anyhow!("cannot open {}: {e}", path.display()))?;
        match file.try_lock() {
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => {
                let holder = std::fs::read_to_string(&path).unwrap_or_default();
                let holder = holder.trim();
                anyhow::bail!(
                    "the data folder {} is in use by another fracture server ({}); stop it \
                     first or choose another --data",
                    data.display(),
                    if holder.is_empty() {
                        "starting up".to_string()
                    } else {
                        holder.replace('\n', ", ")
                    }
                );
            }
            Err(std::fs::TryLockError::Error(e)) => {
                anyhow::bail!("cannot lock {}: {e}", path.display())
            }
        }
        let lock = DataLock { file, path };
        lock.describe(&format!("pid {}", std::process::id()));
        Ok(lock)
    }

    /// Record who holds the lock (what a second server's error shows).
    pub fn describe(&self, text: &str) {
        use std::io::{Seek, Write};
        let mut f = &self.file;
        let ok = f.set_len(0).is_ok()
            && f.seek(std::io::SeekFrom::Start(0)).is_ok()
            && f.write_all(text.as_bytes()).is_ok();
        if !ok {
            tracing::warn!(path = %self.path.display(), "cannot write the lock file's text");
        }
    }
}

async fn serve_async(a: ServeArgs) -> anyhow::Result<()> {
    use anyhow::Context;
    check_public_bind(&a)?;
    let database = a
        .database
        .as_deref()
        .filter(|d| !d.trim().is_empty())
        .map(DatabaseUrl::parse)
        .transpose()
        .map_err(|e| anyhow::anyhow!(e))?;
    std::fs::create_dir_all(&a.data)
        .with_context(|| format!("cannot create the data folder {}", a.data.display()))?;
    // One server per data folder: nothing is touched before the lock is held.
    let lock = DataLock::acquire(&a.data)?;
    let store = match &database {
        None => Store::open(&a.data.join("fracture.db"))
            .await
            .context("cannot open the store")?,
        Some(db) => {
            let store = Store::open_postgres(db.url()).await.map_err(|e| match e {
                crate::store::StoreError::InUse(m) => anyhow::anyhow!("--database {db}: {m}"),
                e => anyhow::anyhow!("cannot use the PostgreSQL database of --database {db}: {e}"),
            })?;
            tracing::info!(database = %db, "store on PostgreSQL");
            store
        }
    };
    // Jobs left running by a previous server go back to the queue (their workers' late
    // writes are fenced off; a new claim restarts their files).
    let recovered = store
        .release_running("re-queued after a server restart")
        .await?;
    if !recovered.is_empty() {
        tracing::info!(jobs = recovered.len(), "re-queued jobs left running");
    }
    let files = JobFiles::new(&a.data);
    // Folders of jobs whose deletion did not get to remove them.
    match store.job_ids().await {
        Ok(known) => {
            let f = files.clone();
            let n = tokio::task::spawn_blocking(move || f.remove_orphans(&known))
                .await
                .unwrap_or(0);
            if n > 0 {
                tracing::info!(folders = n, "removed results folders of deleted jobs");
            }
        }
        Err(e) => tracing::warn!(error = %e, "cannot list jobs to remove orphaned folders"),
    }
    let cores = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(2);
    let workers = a.workers.unwrap_or((cores / 2).max(1));
    let worker_threads = a.worker_threads.unwrap_or((cores / workers.max(1)).max(1));
    let lease = Duration::from_secs_f64(a.lease_seconds.clamp(0.5, 3600.0));
    let mut allowed_hosts = a.allowed_hosts.clone();
    if let Ok(h) = std::fs::read_to_string("/etc/hostname") {
        let h = h.trim();
        if !h.is_empty() {
            allowed_hosts.push(h.to_string());
        }
    }
    let max_memory = a.max_memory_bytes.unwrap_or_else(default_max_memory);
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
            max_memory_bytes: max_memory,
            max_particle_steps: a.max_particle_steps,
            ..Limits::default()
        },
        local_workers: workers,
        allowed_hosts,
    };
    let (state, shutdown_tx) = AppState::new(store.clone(), cfg, files.clone());
    let listener = tokio::net::TcpListener::bind(&a.bind)
        .await
        .with_context(|| format!("cannot listen on {}", a.bind))?;
    let addr = listener.local_addr()?;
    lock.describe(&format!(
        "pid {}, listening on http://{addr}",
        std::process::id()
    ));
    write_atomically(&a.data.join("server.addr"), &addr.to_string())?;
    tracing::info!(%addr, workers, data = %a.data.display(), "listening on http://{addr}");

    let reaper = tokio::spawn(
        state
            .clone()
            .run_reaper((lease / 4).clamp(Duration::from_millis(200), Duration::from_secs(2))),
    );
    let supervisor = tokio::spawn(supervise_workers(
        state.clone(),
        Workers {
            n: workers,
            threads: worker_threads,
            url: local_url(addr),
            dir: a.data.join("workers"),
            max_memory,
        },
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
    // Every step is best effort: a store that cannot be written (a full disk) must not keep
    // the process from stopping (the next start re-queues what is left running).
    let released = match store
        .release_running("re-queued: the server shut down while it ran")
        .await
    {
        Ok(r) => r,
        Err(e) => {
            tracing::error!(error = %e, "cannot re-queue the running jobs; the next start will");
            Vec::new()
        }
    };
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
    let _ = tokio::time::timeout(Duration::from_secs(5), reaper).await;
    if tokio::time::timeout(Duration::from_secs(5), store.close())
        .await
        .is_err()
    {
        tracing::warn!("the store did not close within 5 s");
    }
    drop(lock);
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

/// The local worker processes.
struct Workers {
    n: usize,
    threads: usize,
    url: String,
    dir: PathBuf,
    max_memory: u64,
}

fn spawn_worker(exe: &Path, w: &Workers, token: &str, slot: usize) -> std::io::Result<Child> {
    let child = Command::new(exe)
        .arg("worker")
        .arg("--server")
        .arg(&w.url)
        .arg("--threads")
        .arg(w.threads.to_string())
        .arg("--parent-pid")
        .arg(std::process::id().to_string())
        .arg("--worker-name")
        .arg(format!("local{slot}"))
        .arg("--max-memory-bytes")
        .arg(w.max_memory.to_string())
        .env("FRACTURE_WORKER_TOKEN", token)
        .env_remove("FRACTURE_BIND")
        .stderr(std::process::Stdio::piped())
        .kill_on_drop(true)
        .spawn()?;
    if let Some(pid) = child.id() {
        let _ = write_atomically(&w.dir.join(format!("{slot}.pid")), &pid.to_string());
    }
    Ok(child)
}

/// Copy a worker's stderr to ours and to `<data>/workers/<slot>.log`, keeping its last
/// lines.
fn tee_stderr(
    child: &mut Child,
    log: PathBuf,
) -> Option<tokio::task::JoinHandle<std::collections::VecDeque<String>>> {
    use tokio::io::{AsyncBufReadExt, AsyncWriteExt};
    let err = child.stderr.take()?;
    Some(tokio::spawn(async move {
        let mut tail = std::collections::VecDeque::new();
        let mut lines = tokio::io::BufReader::new(err).lines();
        let mut file = tokio::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&log)
            .await
            .ok();
        let mut out = tokio::io::stderr();
        while let Ok(Some(line)) = lines.next_line().await {
            let _ = out.write_all(format!("{line}\n").as_bytes()).await;
            if let Some(f) = file.as_mut()
                && f.write_all(format!("{line}\n").as_bytes()).await.is_err()
            {
                file = None; // a full disk: keep the tail in memory only
            }
            if tail.len() == STDERR_TAIL {
                tail.pop_front();
            }
            tail.push_back(line);
        }
        tail
    }))
}

/// Keep the local worker processes alive until shutdown, then stop them. When one exits
/// while it holds a job, the job is released at once with the exit cause in its message
/// (re-queued, or failed past the attempt limit or when the cause is memory).
async fn supervise_workers(st: AppState, w: Workers) {
    if w.n == 0 {
        return;
    }
    let exe = match std::env::current_exe() {
        Ok(e) => e,
        Err(e) => {
            tracing::error!(error = %e, "cannot find this executable; no local workers");
            return;
        }
    };
    let _ = std::fs::create_dir_all(&w.dir);
    let exe = Arc::new(exe);
    let w = Arc::new(w);
    let mut shutdown = st.shutdown.clone();
    let mut slots = Vec::new();
    for slot in 0..w.n {
        let (exe, w, st) = (exe.clone(), w.clone(), st.clone());
        let mut sd = st.shutdown.clone();
        slots.push(tokio::spawn(async move {
            let mut backoff = Duration::from_millis(200);
            loop {
                if *sd.borrow() {
                    return;
                }
                let token = st.cfg.worker_token.clone();
                let mut child = match spawn_worker(&exe, &w, &token, slot) {
                    Ok(c) => c,
                    Err(e) => {
                        tracing::error!(error = %e, slot, "cannot start a worker");
                        tokio::time::sleep(Duration::from_secs(2)).await;
                        continue;
                    }
                };
                // Its jobs carry the worker id `local<slot>-<pid>-<random>`.
                let id_prefix = format!("local{slot}-{}-", child.id().unwrap_or(0));
                let tee = tee_stderr(&mut child, w.dir.join(format!("{slot}.log")));
                let started = tokio::time::Instant::now();
                tokio::select! {
                    st_exit = child.wait() => {
                        let tail: Vec<String> = match tee {
                            Some(t) => match tokio::time::timeout(Duration::from_secs(2), t).await {
                                Ok(Ok(t)) => t.into_iter().collect(),
                                _ => Vec::new(),
                            },
                            None => Vec::new(),
                        };
                        let cause = match &st_exit {
                            Ok(s) => exit_cause(s, &tail),
                            Err(e) => format!("lost ({e})"),
                        };
                        tracing::warn!(slot, cause = %cause, "worker exited; restarting");
                        if let Err(e) = release_dead(&st, DeadWorker::Prefix(&id_prefix), &cause).await {
                            tracing::error!(error = %e, "cannot release the jobs of a dead worker");
                        }
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

/// The jobs a dead worker held: all those of a local worker process (worker ids starting
/// with this prefix), or the one claim a remote worker's supervisor reports.
pub(crate) enum DeadWorker<'a> {
    /// A local worker: every running job whose worker id starts with this.
    Prefix(&'a str),
    /// A remote worker's claim: the job and its fence.
    Claim(&'a str, i64),
}

/// Release the jobs a dead worker held, with its exit cause in their message: re-queued,
/// or failed past `--max-attempts` or at once when the cause shows it ran out of memory
/// (it would again), or cancelled if that was asked. Returns the released jobs.
pub(crate) async fn release_dead(
    st: &AppState,
    who: DeadWorker<'_>,
    cause: &str,
) -> Result<Vec<crate::store::JobRow>, crate::store::StoreError> {
    let memory = fracture_api::protocol::ran_out_of_memory(cause);
    let rows = match who {
        DeadWorker::Prefix(p) => {
            st.store
                .release_worker(p, cause, st.cfg.max_attempts, memory)
                .await?
        }
        DeadWorker::Claim(id, fence) => vec![
            st.store
                .release_claim(id, fence, cause, st.cfg.max_attempts, memory)
                .await?,
        ],
    };
    for j in &rows {
        tracing::warn!(job = %j.id, status = j.status.as_str(), cause, "the job's worker died");
        if j.status.is_terminal() {
            let files = st.files.clone();
            let id = j.id.clone();
            let _ = tokio::task::spawn_blocking(move || files.finish(&id)).await;
        }
        st.announce(j);
    }
    st.queue_changed.notify_waiters();
    Ok(rows)
}
