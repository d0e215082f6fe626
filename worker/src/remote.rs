//! The remote worker: claims jobs from a server over HTTP (`/api/v1/worker/…`), runs them
//! with [`run_job`](crate::run_job) (2D) or [`run_job3`](crate::run_job3) (3D scenes,
//! `"analysis": "3d"`: energies, progress and slice snapshots stream alike), heartbeats, obeys cancellation, and streams the
//! results through an HTTP [`RunSink`], retrying transient failures. Asked to stop
//! ([`crate::batch`]) it hands its job back to the queue and exits; it also exits after
//! `idle_exit` without a job or after `max_jobs` claims.
//!
//! Memory: before building a job's simulation the worker estimates its memory
//! (`fracture_api::cost`); a job over the worker's `max_memory` fails at once with the
//! numbers, and otherwise the process's address space is capped (`RLIMIT_AS`) at what it
//! uses now plus the estimate and a margin, so a run that still outgrows its estimate
//! fails its allocation ("memory allocation of N bytes failed", which the server's
//! supervisor reports in the job's message) instead of driving the machine into the
//! out-of-memory killer.
//!
//! Storage: a server that answers 507 (its disk is full) is not failing transiently: the
//! worker keeps the job and retries with back-off for [`STORAGE_BUDGET`] while it
//! heartbeats, then fails the job with the server's message; claims pause while the
//! server's disk is full (a claim there would only burn attempts).

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use crate::{Control, RunOptions, RunSink, SinkError};
use fracture_api::jobs::ErrorBody;
use fracture_api::results::{
    CrackTipRow, EnergyRow, FailureKind, Progress, RunStatus, Snapshot, Summary,
};
use fracture_api::{AnyScene, ValidScene, ValidScene3};
use reqwest::StatusCode;
use reqwest::blocking::{Client, Response};

use fracture_api::protocol::{
    Claim, ClaimRequest, CrackTipBatch, EnergyBatch, FinishRequest, Heartbeat, HeartbeatReply,
    WorkerRelease,
};
use fracture_results::codec;

/// Errors talking to the server.
#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    /// The job is no longer ours (stale fencing token).
    #[error("lease lost: {0}")]
    Fenced(String),
    /// The server refused our token.
    #[error("unauthorized: {0}")]
    Unauthorized(String),
    /// Worth retrying: connection problems, 5xx, 503 during shutdown.
    #[error("transient: {0}")]
    Transient(String),
    /// The server cannot store anything (507: its disk is full or failing).
    #[error("the server cannot store results: {0}")]
    Storage(String),
    /// Not worth retrying.
    #[error("{0}")]
    Fatal(String),
}

/// Settings of a worker process.
#[derive(Debug, Clone)]
pub struct WorkerConfig {
    /// Base URL of the server, e.g. `http://127.0.0.1:8080`.
    pub server: String,
    /// Worker token.
    pub token: String,
    /// Solver threads.
    pub threads: fracture_solver::Parallelism,
    /// How often the solver reports progress (and flushes rows).
    pub flush_every: Duration,
    /// Give up after the server has been unreachable this long.
    pub give_up: Duration,
    /// Exit when this process is no longer our parent (local workers of a server).
    pub parent_pid: Option<u32>,
    /// Name of this worker.
    pub worker_id: String,
    /// Jobs whose memory estimate exceeds this fail before they are built (bytes).
    pub max_memory: Option<u64>,
    /// Tell a supervising parent on stdout which claim this process holds
    /// ([`crate::supervise`]): `HOLDS <job> <fence>` after a claim, `IDLE` when it ends.
    pub announce_claims: bool,
    /// When a running job is checkpointed (`docs/service.md`, "Checkpoints").
    pub checkpoints: crate::CheckpointPolicy,
    /// Exit (status 0) after this long without a job (a batch worker gives its node back
    /// once the queue is drained); `None`: never.
    pub idle_exit: Option<Duration>,
    /// Exit (status 0) after this many claims; `None`: no limit.
    pub max_jobs: Option<u64>,
    /// Claims made before this process by earlier worker processes of the same supervisor
    /// (they count towards `max_jobs`).
    pub jobs_before: u64,
}

/// How long uploads are retried while the server answers 507 (its disk is full).
pub const STORAGE_BUDGET: Duration = Duration::from_secs(120);

/// A small blocking client for the worker routes.
pub(crate) struct Api {
    pub(crate) http: Client,
    pub(crate) base: String,
    pub(crate) token: String,
}

impl Api {
    fn url(&self, path: &str) -> String {
        format!("{}/api/v1/worker/{path}", self.base)
    }

    fn check(r: Result<Response, reqwest::Error>) -> Result<Response, ClientError> {
        let r = r.map_err(|e| ClientError::Transient(e.to_string()))?;
        let status = r.status();
        if status.is_success() {
            return Ok(r);
        }
        let body = r.text().unwrap_or_default();
        let msg = serde_json::from_str::<ErrorBody>(&body)
            .map(|b| b.message)
            .unwrap_or(body);
        Err(match status {
            StatusCode::CONFLICT => ClientError::Fenced(msg),
            StatusCode::UNAUTHORIZED => ClientError::Unauthorized(msg),
            StatusCode::INSUFFICIENT_STORAGE => ClientError::Storage(msg),
            s if s.is_server_error() || s == StatusCode::TOO_MANY_REQUESTS => {
                ClientError::Transient(format!("{s}: {msg}"))
            }
            s => ClientError::Fatal(format!("{s}: {msg}")),
        })
    }

    pub(crate) fn post_json<T: serde::Serialize>(
        &self,
        path: &str,
        body: &T,
    ) -> Result<Response, ClientError> {
        Self::check(
            self.http
                .post(self.url(path))
                .bearer_auth(&self.token)
                .json(body)
                .send(),
        )
    }

    fn put_bytes(&self, path: &str, body: Vec<u8>) -> Result<Response, ClientError> {
        Self::check(
            self.http
                .put(self.url(path))
                .bearer_auth(&self.token)
                .header(reqwest::header::CONTENT_TYPE, "application/octet-stream")
                .body(body)
                .send(),
        )
    }

    /// The job's checkpoint (None: it has none).
    fn get_checkpoint(&self, job: &str, fence: i64) -> Result<Option<Vec<u8>>, ClientError> {
        let r = self
            .http
            .get(self.url(&format!("jobs/{job}/checkpoint?fence={fence}")))
            .bearer_auth(&self.token)
            .send();
        if let Ok(resp) = &r
            && resp.status() == StatusCode::NOT_FOUND
        {
            return Ok(None);
        }
        let bytes = Self::check(r)?
            .bytes()
            .map_err(|e| ClientError::Transient(e.to_string()))?;
        Ok(Some(bytes.to_vec()))
    }

    /// Refuse the job's checkpoint: the server drops it and the history after step 0, and
    /// the run starts over.
    fn refuse_checkpoint(&self, job: &str, fence: i64) -> Result<(), ClientError> {
        Self::check(
            self.http
                .delete(self.url(&format!("jobs/{job}/checkpoint?fence={fence}")))
                .bearer_auth(&self.token)
                .send(),
        )
        .map(drop)
    }

    fn post_bytes(&self, path: &str, body: Vec<u8>) -> Result<Response, ClientError> {
        Self::check(
            self.http
                .post(self.url(path))
                .bearer_auth(&self.token)
                .header(reqwest::header::CONTENT_TYPE, "application/octet-stream")
                .body(body)
                .send(),
        )
    }

    /// Retry transient failures for up to `budget`, and a server without storage (507)
    /// for up to [`STORAGE_BUDGET`] (its disk may be freed).
    pub(crate) fn retry<T>(
        &self,
        budget: Duration,
        mut f: impl FnMut() -> Result<T, ClientError>,
    ) -> Result<T, ClientError> {
        let start = Instant::now();
        let mut nap = Duration::from_millis(100);
        loop {
            match f() {
                Err(ClientError::Transient(e)) if start.elapsed() < budget => {
                    tracing::warn!(error = %e, "retrying");
                    std::thread::sleep(nap);
                    nap = (nap * 2).min(Duration::from_secs(2));
                }
                Err(ClientError::Storage(e)) if start.elapsed() < STORAGE_BUDGET.max(budget) => {
                    tracing::warn!(error = %e, "the server's disk is full; retrying");
                    std::thread::sleep(nap);
                    nap = (nap * 2).min(Duration::from_secs(5));
                }
                r => return r,
            }
        }
    }
}

fn parent_gone(cfg: &WorkerConfig) -> bool {
    cfg.parent_pid
        .is_some_and(|p| std::os::unix::process::parent_id() != p)
}

/// Run a worker until the server is gone for good (or the parent server exits).
pub fn run_worker(cfg: WorkerConfig) -> anyhow::Result<()> {
    let api = Api {
        http: Client::builder()
            .timeout(Duration::from_secs(120))
            .connect_timeout(Duration::from_secs(5))
            .build()?,
        base: cfg.server.trim_end_matches('/').to_string(),
        token: cfg.token.clone(),
    };
    tracing::info!(
        worker = %cfg.worker_id,
        server = %api.base,
        host = crate::provenance::host().as_deref().unwrap_or("?"),
        scheduler = crate::provenance::scheduler().as_deref().unwrap_or("none"),
        "worker started"
    );
    let mut failing_since: Option<Instant> = None;
    let mut claims = cfg.jobs_before;
    let mut idle_since = Instant::now();
    loop {
        if parent_gone(&cfg) {
            tracing::info!("parent server exited; worker stops");
            return Ok(());
        }
        if crate::handback::requested() {
            tracing::info!("asked to stop; worker exits");
            return Ok(());
        }
        if let Some(max) = cfg.max_jobs.filter(|m| claims >= *m) {
            tracing::info!(
                jobs = claims,
                "ran its {max} jobs (--max-jobs); worker exits"
            );
            return Ok(());
        }
        let mut wait = 10.0_f64;
        if let Some(idle) = cfg.idle_exit {
            let left = idle.saturating_sub(idle_since.elapsed());
            if left.is_zero() {
                tracing::info!(idle = ?idle, "no job for the idle time (--idle-exit); worker exits");
                return Ok(());
            }
            wait = wait.min(left.as_secs_f64());
        }
        let req = ClaimRequest {
            worker_id: cfg.worker_id.clone(),
            wait_seconds: wait,
        };
        match api.post_json("claim", &req) {
            Ok(r) if r.status() == StatusCode::NO_CONTENT => failing_since = None,
            Ok(r) => {
                failing_since = None;
                let claim: Claim = match r.json() {
                    Ok(c) => c,
                    Err(e) => {
                        tracing::error!(error = %e, "unreadable claim");
                        continue;
                    }
                };
                claims += 1;
                let handed_back = run_claim(&api, &cfg, claim);
                idle_since = Instant::now();
                if handed_back {
                    tracing::info!("job handed back; worker exits");
                    return Ok(());
                }
            }
            Err(ClientError::Unauthorized(m)) => {
                anyhow::bail!("the server refused the worker token: {m}")
            }
            Err(ClientError::Storage(m)) => {
                // The server is there but cannot record a claim: wait for space.
                failing_since = None;
                tracing::warn!(error = %m, "the server's disk is full; not claiming for 5 s");
                std::thread::sleep(Duration::from_secs(5));
            }
            Err(e) => {
                let since = *failing_since.get_or_insert_with(Instant::now);
                if since.elapsed() > cfg.give_up {
                    anyhow::bail!("the server has been unreachable for {:?}: {e}", cfg.give_up);
                }
                tracing::warn!(error = %e, "claim failed; retrying");
                std::thread::sleep(Duration::from_millis(500));
            }
        }
    }
}

/// The summary of a job that failed before (or instead of) running: `hash` is its scene's
/// hash (empty when the scene could not be read), `dimension` `Some(3)` for a 3D scene.
fn failed_summary(
    hash: String,
    dimension: Option<u32>,
    failure: FailureKind,
    message: String,
) -> Summary {
    Summary {
        status: RunStatus::Failed,
        message: Some(message),
        failure: Some(failure),
        steps: 0,
        time_step: 0.0,
        sim_time: 0.0,
        particles: 0,
        grid_nodes: 0,
        active_nodes_mean: 0.0,
        wall_seconds: 0.0,
        particle_steps_per_second: 0.0,
        threads: 0,
        scene_hash: hash,
        solver_version: fracture_api::SOLVER_VERSION.to_string(),
        fracture: None,
        provenance: Some(crate::provenance::provenance(
            fracture_api::clock::now_text(),
        )),
        tips: Vec::new(),
        references: Vec::new(),
        dimension,
    }
}

/// A claimed job's scene as this worker validated it: 2D, or 3D (`"analysis": "3d"`).
enum Valid {
    /// A 2D scene, run by [`crate::run_job`].
    Two(ValidScene),
    /// A 3D scene, run by [`crate::run_job3`].
    Three(ValidScene3),
}

impl Valid {
    /// Validate a scene of either dimension.
    fn new(scene: AnyScene) -> Result<Valid, fracture_api::ValidationErrors> {
        Ok(match scene {
            AnyScene::Two(s) => Valid::Two(ValidScene::new(s)?),
            AnyScene::Three(s) => Valid::Three(ValidScene3::new(s)?),
        })
    }

    /// The scene's hash.
    fn hash(&self) -> String {
        match self {
            Valid::Two(v) => v.scene().hash(),
            Valid::Three(v) => v.scene().hash(),
        }
    }

    /// `Some(3)` for a 3D scene (as its summary says), `None` for 2D.
    fn dimension(&self) -> Option<u32> {
        matches!(self, Valid::Three(_)).then_some(3)
    }

    /// The failed summary of this scene's job.
    fn failed(&self, failure: FailureKind, message: String) -> Summary {
        failed_summary(self.hash(), self.dimension(), failure, message)
    }

    /// The run's memory estimate (`fracture_api::cost`) with the validated particle count.
    fn memory(&self) -> fracture_api::cost::MemoryEstimate {
        match self {
            Valid::Two(v) => fracture_api::cost::memory_estimate(v.scene(), v.size().particles),
            Valid::Three(v) => fracture_api::cost::memory_estimate3(v.scene(), v.size().particles),
        }
    }

    /// Run the job (resuming from `checkpoint` when given; `Err` when it cannot be used).
    fn run(
        &self,
        opts: &RunOptions,
        policy: crate::CheckpointPolicy,
        checkpoint: Option<&[u8]>,
        sink: &mut HttpSink<'_>,
    ) -> Result<Summary, String> {
        match self {
            Valid::Two(v) => crate::run_job(v, opts, policy, checkpoint, sink),
            Valid::Three(v) => crate::run_job3(v, opts, policy, checkpoint, sink),
        }
    }
}

/// Run one claimed job to its end; returns whether it was handed back instead (a stop
/// signal, [`crate::batch`]).
fn run_claim(api: &Api, cfg: &WorkerConfig, claim: Claim) -> bool {
    let job = claim.job_id.clone();
    let fence = claim.fence;
    if cfg.announce_claims {
        crate::supervise::announce(Some((&job, fence)));
    }
    if crate::handback::requested() {
        // Asked to stop while the claim was on its way: give it back untouched.
        hand_back(api, cfg, &job, fence, None);
        if cfg.announce_claims {
            crate::supervise::announce(None);
        }
        return true;
    }
    tracing::info!(job = %job, attempt = claim.attempt, "running");
    let cancel = Arc::new(AtomicBool::new(false));
    let lost = Arc::new(AtomicBool::new(false));
    let (stop_tx, stop_rx) = mpsc::channel::<()>();
    // Heartbeats keep the lease while the solver works between progress reports.
    let beat = (claim.lease_seconds / 4.0).clamp(0.2, 1.0);
    let hb = {
        let (cancel, lost) = (cancel.clone(), lost.clone());
        let http = api.http.clone();
        let (base, token, job) = (api.base.clone(), api.token.clone(), job.clone());
        let cfg = cfg.clone();
        std::thread::spawn(move || {
            let api = Api { http, base, token };
            loop {
                match stop_rx.recv_timeout(Duration::from_secs_f64(beat)) {
                    Err(mpsc::RecvTimeoutError::Timeout) => {}
                    _ => return,
                }
                if parent_gone(&cfg) {
                    tracing::info!("parent server exited; worker stops");
                    std::process::exit(0);
                }
                let hb = Heartbeat {
                    fence,
                    progress: None,
                };
                match api.post_json(&format!("jobs/{job}/heartbeat"), &hb) {
                    Ok(r) => {
                        if let Ok(rep) = r.json::<HeartbeatReply>()
                            && rep.cancel
                        {
                            cancel.store(true, Ordering::SeqCst);
                        }
                    }
                    Err(ClientError::Fenced(_)) => {
                        lost.store(true, Ordering::SeqCst);
                        return;
                    }
                    Err(e) => tracing::warn!(error = %e, "heartbeat failed"),
                }
            }
        })
    };
    let mut sink = HttpSink {
        api,
        job: job.clone(),
        fence,
        cancel: cancel.clone(),
        lost: lost.clone(),
        finished: false,
        handed_back: None,
    };
    // The server validated the scene before queueing it; a worker of another version may
    // still disagree, so it validates once more here (the only way to a `ValidScene` or a
    // `ValidScene3`).
    let summary = match fracture_api::any_scene_from_value(claim.scene) {
        Ok(scene) => {
            let (hash, dimension) = (scene.hash(), (scene.dimension() == 3).then_some(3));
            match Valid::new(scene) {
                Ok(valid) => {
                    let threads = cfg.threads.resolve();
                    let est = valid.memory();
                    match cfg.max_memory.filter(|m| est.total > *m) {
                        Some(max) => valid.failed(
                            FailureKind::InvalidScene,
                            format!(
                                "the run needs about {} of memory ({est}), more than this \
                                 worker's limit of {}",
                                fracture_api::cost::bytes(est.total),
                                fracture_api::cost::bytes(max)
                            ),
                        ),
                        None => {
                            let _cap = MemoryCap::set(est.total, threads);
                            let opts = RunOptions {
                                threads: cfg.threads,
                                flush_every: cfg.flush_every,
                            };
                            run_resumable(api, cfg, &job, fence, &valid, &opts, &mut sink)
                        }
                    }
                }
                Err(e) => failed_summary(
                    hash,
                    dimension,
                    FailureKind::InvalidScene,
                    format!("the claimed scene is not valid here:\n{e}"),
                ),
            }
        }
        Err(e) => failed_summary(
            String::new(),
            None,
            FailureKind::InvalidScene,
            format!("the claimed scene could not be read: {e}"),
        ),
    };
    let handed_back = sink.handed_back;
    if handed_back.is_none() && !sink.finished && !lost.load(Ordering::SeqCst) {
        let _ = sink.finish(&summary);
    }
    let _ = stop_tx.send(());
    let _ = hb.join();
    if let Some(step) = handed_back
        && !lost.load(Ordering::SeqCst)
    {
        // After the run function returned: a checkpoint written as it stopped comes first.
        hand_back(api, cfg, &job, fence, Some(step));
    }
    if cfg.announce_claims {
        crate::supervise::announce(None);
    }
    match handed_back {
        Some(step) => tracing::info!(job = %job, step, "run handed back"),
        None => tracing::info!(job = %job, status = ?summary.status, "run ended"),
    }
    handed_back.is_some()
}

/// Give the claim `job`/`fence` back to the queue (`POST /api/v1/worker/jobs/{id}/release`),
/// naming this worker, its host and scheduler job, and why (the stop signal; `step`: where
/// the run stopped). Retried for 30 s while the server is unreachable; otherwise the job's
/// lease brings it back.
fn hand_back(api: &Api, cfg: &WorkerConfig, job: &str, fence: i64, step: Option<u64>) {
    let mut reason = crate::batch::stop_reason().unwrap_or_else(|| "asked to stop".into());
    if let Some(step) = step {
        reason.push_str(&format!(", at step {step}"));
    }
    let mut worker = cfg.worker_id.clone();
    if let Some(h) = crate::provenance::host() {
        worker.push_str(&format!(" on {h}"));
    }
    if let Some(s) = crate::provenance::scheduler() {
        worker.push_str(&format!(", {s}"));
    }
    let body = WorkerRelease {
        fence,
        reason,
        worker,
    };
    let path = format!("jobs/{job}/release");
    let r = api.retry(Duration::from_secs(30), || {
        api.post_json(&path, &body)?
            .json::<serde_json::Value>()
            .map_err(|e| ClientError::Transient(e.to_string()))
    });
    match r {
        Ok(j) => tracing::info!(
            job,
            status = j["status"].as_str().unwrap_or("?"),
            "job handed back to the server"
        ),
        Err(ClientError::Fenced(m)) => {
            tracing::info!(job, reason = %m, "the job was no longer held (finished or released)")
        }
        Err(e) => tracing::warn!(
            job,
            error = %e,
            "cannot hand the job back; the server will find it by its lease"
        ),
    }
}

/// Run a claimed job, from its checkpoint when the server has one this build can use; a
/// checkpoint it refuses is dropped on the server (with the history after step 0) and the
/// run starts over.
fn run_resumable(
    api: &Api,
    cfg: &WorkerConfig,
    job: &str,
    fence: i64,
    valid: &Valid,
    opts: &RunOptions,
    sink: &mut HttpSink<'_>,
) -> Summary {
    let policy = cfg.checkpoints;
    let fetched = api.retry(HttpSink::BUDGET, || api.get_checkpoint(job, fence));
    let bytes = match fetched {
        Ok(b) => b,
        Err(e) => {
            // Without it the run cannot start at the history the server kept.
            tracing::warn!(job = %job, error = %e, "cannot fetch the checkpoint");
            if api.refuse_checkpoint(job, fence).is_err() {
                return valid.failed(
                    FailureKind::Output,
                    format!("could not fetch or drop the job's checkpoint: {e}"),
                );
            }
            None
        }
    };
    if let Some(b) = bytes {
        match valid.run(opts, policy, Some(&b), sink) {
            Ok(s) => return s,
            Err(why) => {
                tracing::warn!(job = %job, reason = %why, "checkpoint refused; starting over from step 0");
                if let Err(e) = api.retry(HttpSink::BUDGET, || api.refuse_checkpoint(job, fence)) {
                    return valid.failed(
                        FailureKind::Output,
                        format!(
                            "the job's checkpoint was refused ({why}) and could not be dropped: {e}"
                        ),
                    );
                }
            }
        }
    }
    match valid.run(opts, policy, None, sink) {
        Ok(s) => s,
        Err(e) => valid.failed(FailureKind::Output, e),
    }
}

/// The address-space cap of a running job (`RLIMIT_AS`, soft limit), lifted when dropped.
struct MemoryCap {
    #[cfg(unix)]
    previous: Option<rustix::process::Rlimit>,
}

impl MemoryCap {
    /// Cap the process at its current address space plus 1.5 × `estimate`, 1 GiB and
    /// 128 MiB per solver thread (stacks and allocator arenas reserve address space).
    fn set(estimate: u64, threads: usize) -> MemoryCap {
        #[cfg(unix)]
        {
            use rustix::process::{Resource, Rlimit, getrlimit, setrlimit};
            let now = current_address_space().unwrap_or(0);
            let margin = (1u64 << 30) + (threads as u64).saturating_mul(128 << 20);
            let cap = now
                .saturating_add(estimate.saturating_add(estimate / 2))
                .saturating_add(margin);
            let previous = getrlimit(Resource::As);
            if previous.current.is_some_and(|c| c <= cap) {
                return MemoryCap { previous: None };
            }
            let new = Rlimit {
                current: Some(cap),
                maximum: previous.maximum,
            };
            match setrlimit(Resource::As, new) {
                Ok(()) => {
                    tracing::info!(
                        cap = %fracture_api::cost::bytes(cap),
                        estimate = %fracture_api::cost::bytes(estimate),
                        "memory cap of this job"
                    );
                    MemoryCap {
                        previous: Some(previous),
                    }
                }
                Err(e) => {
                    tracing::warn!(error = %e, "cannot cap this worker's memory");
                    MemoryCap { previous: None }
                }
            }
        }
        #[cfg(not(unix))]
        {
            let _ = (estimate, threads);
            MemoryCap {}
        }
    }
}

impl Drop for MemoryCap {
    fn drop(&mut self) {
        #[cfg(unix)]
        if let Some(p) = self.previous.take() {
            let _ = rustix::process::setrlimit(rustix::process::Resource::As, p);
        }
    }
}

/// The process's address space now (`VmSize` of `/proc/self/status`).
#[cfg(unix)]
fn current_address_space() -> Option<u64> {
    let t = std::fs::read_to_string("/proc/self/status").ok()?;
    let kb: u64 = t
        .lines()
        .find_map(|l| l.strip_prefix("VmSize:"))?
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kb.saturating_mul(1024))
}

/// The [`RunSink`] of a job: every call is an HTTP request to the server, fenced.
struct HttpSink<'a> {
    api: &'a Api,
    job: String,
    fence: i64,
    cancel: Arc<AtomicBool>,
    lost: Arc<AtomicBool>,
    finished: bool,
    /// The step at which the run was told to hand the job back (`Control::HandBack`).
    handed_back: Option<u64>,
}

impl HttpSink<'_> {
    const BUDGET: Duration = Duration::from_secs(20);

    fn guard(&self) -> Result<(), SinkError> {
        if self.lost.load(Ordering::SeqCst) {
            Err(SinkError("the lease on this job was lost".into()))
        } else {
            Ok(())
        }
    }

    fn fail(&self, e: ClientError) -> SinkError {
        if matches!(e, ClientError::Fenced(_)) {
            self.lost.store(true, Ordering::SeqCst);
        }
        SinkError(e.to_string())
    }
}

impl RunSink for HttpSink<'_> {
    fn progress(&mut self, p: &Progress) -> Result<Control, SinkError> {
        self.guard()?;
        let hb = Heartbeat {
            fence: self.fence,
            progress: Some(*p),
        };
        let path = format!("jobs/{}/heartbeat", self.job);
        let rep: HeartbeatReply = self
            .api
            .retry(Self::BUDGET, || {
                self.api
                    .post_json(&path, &hb)?
                    .json()
                    .map_err(|e| ClientError::Transient(e.to_string()))
            })
            .map_err(|e| self.fail(e))?;
        if rep.cancel {
            self.cancel.store(true, Ordering::SeqCst);
        }
        Ok(if self.cancel.load(Ordering::SeqCst) {
            Control::Cancel
        } else if crate::handback::requested() {
            self.handed_back = Some(p.step);
            Control::HandBack
        } else {
            Control::Continue
        })
    }

    fn energy(&mut self, rows: &[EnergyRow]) -> Result<(), SinkError> {
        self.guard()?;
        if rows.is_empty() {
            return Ok(());
        }
        let b = EnergyBatch {
            fence: self.fence,
            rows: rows.to_vec(),
        };
        let path = format!("jobs/{}/energy", self.job);
        self.api
            .retry(Self::BUDGET, || self.api.post_json(&path, &b).map(drop))
            .map_err(|e| self.fail(e))
    }

    fn crack_tips(&mut self, rows: &[CrackTipRow]) -> Result<(), SinkError> {
        self.guard()?;
        if rows.is_empty() {
            return Ok(());
        }
        let b = CrackTipBatch {
            fence: self.fence,
            rows: rows.to_vec(),
        };
        let path = format!("jobs/{}/crack-tips", self.job);
        self.api
            .retry(Self::BUDGET, || self.api.post_json(&path, &b).map(drop))
            .map_err(|e| self.fail(e))
    }

    fn snapshot(&mut self, snap: &Snapshot) -> Result<(), SinkError> {
        self.guard()?;
        let body = codec::encode_snapshot(snap);
        let path = format!("jobs/{}/snapshots?fence={}", self.job, self.fence);
        self.api
            .retry(Self::BUDGET, || {
                self.api.post_bytes(&path, body.clone()).map(drop)
            })
            .map_err(|e| self.fail(e))
    }

    fn checkpoint(&mut self, bytes: &[u8], at: &crate::CheckpointAt) -> Result<(), SinkError> {
        self.guard()?;
        // Rust's `{}` of an f64 is its shortest round-trip text: the server reads the
        // same bits.
        let path = format!(
            "jobs/{}/checkpoint?fence={}&step={}&time={}&snapshots={}",
            self.job, self.fence, at.step, at.time, at.snapshots
        );
        self.api
            .retry(Self::BUDGET, || {
                self.api.put_bytes(&path, bytes.to_vec()).map(drop)
            })
            .map_err(|e| self.fail(e))
    }

    fn finish(&mut self, summary: &Summary) -> Result<(), SinkError> {
        self.guard()?;
        self.finished = true;
        let f = FinishRequest {
            fence: self.fence,
            summary: summary.clone(),
        };
        let path = format!("jobs/{}/finish", self.job);
        self.api
            .retry(Self::BUDGET, || self.api.post_json(&path, &f).map(drop))
            .map_err(|e| self.fail(e))
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use std::io::{Read, Write};

    /// A server that answers every request with `status` and an error body.
    fn answering(status: &'static str) -> String {
        let l = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = l.local_addr().unwrap();
        std::thread::spawn(move || {
            for s in l.incoming().flatten().take(4) {
                let mut s = s;
                let mut buf = [0u8; 4096];
                let _ = s.read(&mut buf);
                let body =
                    r#"{"error":"insufficient_storage","message":"the disk is full","details":[]}"#;
                let _ = write!(
                    s,
                    "HTTP/1.1 {status}\r\ncontent-type: application/json\r\ncontent-length: {}\r\nconnection: close\r\n\r\n{body}",
                    body.len()
                );
            }
        });
        format!("http://{addr}")
    }

    /// The memory cap is enforced: while it is set, an allocation beyond it fails (here
    /// `try_reserve`, which reports what would abort a run: "memory allocation of N bytes
    /// failed"), and the previous limit is back once it is dropped.
    #[cfg(target_os = "linux")]
    #[test]
    fn the_memory_cap_makes_a_larger_allocation_fail_and_is_lifted() {
        use rustix::process::{Resource, getrlimit};
        let before = getrlimit(Resource::As);
        let estimate = 64u64 << 20;
        {
            let _cap = MemoryCap::set(estimate, 1);
            let cap = getrlimit(Resource::As).current.expect("a cap is set");
            let now = current_address_space().unwrap();
            // Current address space + 1.5 × estimate + 1 GiB + 128 MiB per thread.
            assert!(cap >= now && cap - now <= estimate * 3 / 2 + (1 << 30) + (128 << 20));
            let mut v: Vec<u8> = Vec::new();
            assert!(
                v.try_reserve_exact(cap as usize).is_err(),
                "an allocation of the whole cap succeeded under it"
            );
        }
        assert_eq!(getrlimit(Resource::As), before, "the cap was not lifted");
    }

    /// A server whose disk is full (507) is not a transient failure to burn retries and
    /// attempts on: the worker sees `Storage` with the server's message.
    #[test]
    fn a_507_is_a_storage_error_with_the_servers_message() {
        let api = Api {
            http: Client::new(),
            base: answering("507 Insufficient Storage"),
            token: "t".into(),
        };
        match api.post_json("claim", &serde_json::json!({})) {
            Err(ClientError::Storage(m)) => assert!(m.contains("disk is full"), "{m}"),
            other => panic!("{:?}", other.map(|r| r.status())),
        }
    }
}
