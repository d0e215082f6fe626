//! HTTP clients of the service: the worker process (claims jobs, runs them with
//! [`fracture_worker::run_scene`] and streams results through an HTTP [`RunSink`]) and
//! `fracture submit` and `fracture sweep`.

use std::io::{BufRead, BufReader, Write};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use fracture_api::Scene;
use fracture_api::jobs::{ErrorBody, JobInfo, JobStatus, StatusEvent};
use fracture_api::results::{CrackTipRow, EnergyRow, Progress, RunStatus, Snapshot, Summary};
use fracture_worker::{Control, RunOptions, RunSink, SinkError};
use reqwest::StatusCode;
use reqwest::blocking::{Client, Response};

use crate::codec;
use crate::protocol::{
    Claim, ClaimRequest, CrackTipBatch, EnergyBatch, FinishRequest, Heartbeat, HeartbeatReply,
    WireCrackTip, WireEnergy,
};

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
    /// Solver threads (0: the solver's default).
    pub threads: usize,
    /// How often the solver reports progress (and flushes rows).
    pub flush_every: Duration,
    /// Give up after the server has been unreachable this long.
    pub give_up: Duration,
    /// Exit when this process is no longer our parent (local workers of a server).
    pub parent_pid: Option<u32>,
    /// Name of this worker.
    pub worker_id: String,
}

/// A small blocking client for the worker routes.
struct Api {
    http: Client,
    base: String,
    token: String,
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
            s if s.is_server_error() || s == StatusCode::TOO_MANY_REQUESTS => {
                ClientError::Transient(format!("{s}: {msg}"))
            }
            s => ClientError::Fatal(format!("{s}: {msg}")),
        })
    }

    fn post_json<T: serde::Serialize>(
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

    /// Retry transient failures for up to `budget`.
    fn retry<T>(
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
    tracing::info!(worker = %cfg.worker_id, server = %api.base, "worker started");
    let mut failing_since: Option<Instant> = None;
    loop {
        if parent_gone(&cfg) {
            tracing::info!("parent server exited; worker stops");
            return Ok(());
        }
        let req = ClaimRequest {
            worker_id: cfg.worker_id.clone(),
            wait_seconds: 10.0,
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
                run_claim(&api, &cfg, claim);
            }
            Err(ClientError::Unauthorized(m)) => {
                anyhow::bail!("the server refused the worker token: {m}")
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

fn failed_summary(scene: Option<&Scene>, message: String) -> Summary {
    Summary {
        status: RunStatus::Failed,
        message: Some(message),
        steps: 0,
        time_step: 0.0,
        sim_time: 0.0,
        particles: 0,
        grid_nodes: 0,
        active_nodes_mean: 0.0,
        wall_seconds: 0.0,
        particle_steps_per_second: 0.0,
        threads: 0,
        scene_hash: scene.map(Scene::hash).unwrap_or_default(),
        solver_version: fracture_api::SOLVER_VERSION.to_string(),
    }
}

fn run_claim(api: &Api, cfg: &WorkerConfig, claim: Claim) {
    let job = claim.job_id.clone();
    let fence = claim.fence;
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
    };
    let scene = serde_json::from_value::<Scene>(claim.scene);
    let summary = match &scene {
        Ok(scene) => {
            let opts = RunOptions {
                threads: cfg.threads,
                flush_every: cfg.flush_every,
            };
            fracture_worker::run_scene(scene, &opts, &mut sink)
        }
        Err(e) => failed_summary(None, format!("the claimed scene could not be read: {e}")),
    };
    if !sink.finished && !lost.load(Ordering::SeqCst) {
        let _ = sink.finish(&summary);
    }
    let _ = stop_tx.send(());
    let _ = hb.join();
    tracing::info!(job = %job, status = ?summary.status, "run ended");
}

/// The [`RunSink`] of a job: every call is an HTTP request to the server, fenced.
struct HttpSink<'a> {
    api: &'a Api,
    job: String,
    fence: i64,
    cancel: Arc<AtomicBool>,
    lost: Arc<AtomicBool>,
    finished: bool,
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
            rows: rows.iter().map(WireEnergy::from).collect(),
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
            rows: rows.iter().map(WireCrackTip::from).collect(),
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

// ---------------------------------------------------------------------------------------
// submit

/// What `fracture submit` does.
#[derive(Debug, Clone)]
pub struct SubmitConfig {
    /// Base URL of the server.
    pub server: String,
    /// API token, if the server needs one.
    pub token: Option<String>,
    /// The scene (or wrapped request) as JSON.
    pub body: serde_json::Value,
    /// Follow the job until it ends.
    pub wait: bool,
}

/// Outcome of a submission.
#[derive(Debug, Clone)]
pub enum SubmitOutcome {
    /// Refused (status and error body).
    Rejected(u16, String),
    /// Accepted and not waited for.
    Submitted(String),
    /// Accepted and ended.
    Ended(String, JobStatus, Option<String>),
}

fn show_error(status: u16, body: &str) -> String {
    match serde_json::from_str::<ErrorBody>(body) {
        Ok(b) => {
            let mut s = format!("{status} {}: {}", b.error, b.message);
            for d in b.details {
                s.push_str(&format!("\n  {}: {}", d.path, d.message));
            }
            s
        }
        Err(_) => format!("{status}: {body}"),
    }
}

/// Send a create request (with the bearer token, if any): the body of a `201 Created` answer,
/// or the status and a readable error for any other answer.
fn post_created(
    req: reqwest::blocking::RequestBuilder,
    token: Option<&str>,
) -> anyhow::Result<Result<String, (u16, String)>> {
    let req = match token {
        Some(t) => req.bearer_auth(t),
        None => req,
    };
    let r = req.timeout(Duration::from_secs(60)).send()?;
    let status = r.status();
    let text = r.text()?;
    if status != StatusCode::CREATED {
        return Ok(Err((status.as_u16(), show_error(status.as_u16(), &text))));
    }
    Ok(Ok(text))
}

/// Submit a scene and, with `wait`, follow its events (falling back to polling) until it ends.
pub fn submit(cfg: &SubmitConfig, out: &mut dyn Write) -> anyhow::Result<SubmitOutcome> {
    let base = cfg.server.trim_end_matches('/').to_string();
    let http = http_client()?;
    let req = http.post(format!("{base}/api/v1/jobs")).json(&cfg.body);
    let text = match post_created(req, cfg.token.as_deref())? {
        Ok(text) => text,
        Err((code, msg)) => return Ok(SubmitOutcome::Rejected(code, msg)),
    };
    let job: JobInfo = serde_json::from_str(&text)?;
    writeln!(out, "{}", job.id)?;
    if !cfg.wait {
        return Ok(SubmitOutcome::Submitted(job.id));
    }
    let id = job.id;
    let tty = std::io::IsTerminal::is_terminal(&std::io::stderr());
    let mut last_line = Instant::now() - Duration::from_secs(10);
    // Follow the SSE stream.
    if let Ok(resp) = http.get(format!("{base}/api/v1/jobs/{id}/events")).send()
        && resp.status().is_success()
    {
        let mut event = String::new();
        let mut data = String::new();
        for line in BufReader::new(resp).lines() {
            let Ok(line) = line else { break };
            if let Some(e) = line.strip_prefix("event:") {
                event = e.trim().to_string();
            } else if let Some(d) = line.strip_prefix("data:") {
                data.push_str(d.trim_start());
            } else if line.is_empty() {
                match event.as_str() {
                    "progress" => {
                        if let Ok(p) = serde_json::from_str::<Progress>(&data) {
                            let msg = format!(
                                "{id}: step {} t = {:.3e} s ({:.0}%)",
                                p.step,
                                p.sim_time,
                                100.0 * p.fraction
                            );
                            if tty {
                                eprint!("\r{msg}   ");
                            } else if last_line.elapsed() > Duration::from_secs(2) {
                                eprintln!("{msg}");
                                last_line = Instant::now();
                            }
                        }
                    }
                    "status" => {
                        if let Ok(s) = serde_json::from_str::<StatusEvent>(&data) {
                            if tty {
                                eprintln!();
                            }
                            eprintln!("{id}: {}", s.status.as_str());
                            if s.status.is_terminal() {
                                return Ok(SubmitOutcome::Ended(id, s.status, s.message));
                            }
                        }
                    }
                    _ => {}
                }
                event.clear();
                data.clear();
            }
        }
    }
    // The stream ended early (server restart?): poll.
    loop {
        let r = http
            .get(format!("{base}/api/v1/jobs/{id}"))
            .timeout(Duration::from_secs(30))
            .send();
        if let Ok(r) = r
            && r.status().is_success()
            && let Ok(j) = r.json::<JobInfo>()
            && j.status.is_terminal()
        {
            return Ok(SubmitOutcome::Ended(id, j.status, j.message));
        }
        std::thread::sleep(Duration::from_secs(1));
    }
}

// ---------------------------------------------------------------------------------------
// sweep

/// What `fracture sweep` does.
#[derive(Debug, Clone)]
pub struct SweepConfig {
    /// Base URL of the server.
    pub server: String,
    /// API token, if the server needs one.
    pub token: Option<String>,
    /// The request body as JSON text (text, so the parameters keep their order).
    pub body: String,
    /// Follow the jobs until all have ended.
    pub wait: bool,
}

/// Outcome of a sweep submission.
#[derive(Debug, Clone)]
pub enum SweepOutcome {
    /// Refused (status and the error body, shown).
    Rejected(u16, String),
    /// Accepted and not waited for (sweep id).
    Submitted(String),
    /// Accepted and every job ended: sweep id and its final state.
    Ended(String, Box<crate::sweep::SweepInfo>),
}

fn http_client() -> reqwest::Result<Client> {
    Client::builder()
        .connect_timeout(Duration::from_secs(5))
        .timeout(None::<Duration>)
        .build()
}

/// One line of a sweep's state: `3 jobs: 1 completed, 1 running, 1 queued (45%)`.
pub fn sweep_line(s: &crate::sweep::SweepInfo) -> String {
    let parts: Vec<String> = ["completed", "running", "queued", "failed", "cancelled"]
        .iter()
        .filter_map(|k| {
            let n = s.counts.get(*k).copied().unwrap_or(0);
            (n > 0).then(|| format!("{n} {k}"))
        })
        .collect();
    format!(
        "{}: {} jobs: {} ({:.0}%)",
        s.id,
        s.total,
        parts.join(", "),
        100.0 * s.progress
    )
}

/// Create a sweep (`POST /api/v1/sweeps`), print its id and one line per job (`id label`)
/// and, with `wait`, poll it until every job has ended, showing progress on stderr.
pub fn sweep(cfg: &SweepConfig, out: &mut dyn Write) -> anyhow::Result<SweepOutcome> {
    use crate::sweep::SweepInfo;
    let base = cfg.server.trim_end_matches('/').to_string();
    let http = http_client()?;
    let req = http
        .post(format!("{base}/api/v1/sweeps"))
        .header(reqwest::header::CONTENT_TYPE, "application/json")
        .body(cfg.body.clone());
    let text = match post_created(req, cfg.token.as_deref())? {
        Ok(text) => text,
        Err((code, msg)) => return Ok(SweepOutcome::Rejected(code, msg)),
    };
    let sweep: SweepInfo = serde_json::from_str(&text)?;
    writeln!(out, "{}", sweep.id)?;
    for j in sweep.jobs.iter().flatten() {
        writeln!(out, "{} {}", j.id, j.label)?;
    }
    if !cfg.wait {
        return Ok(SweepOutcome::Submitted(sweep.id));
    }
    let id = sweep.id;
    let tty = std::io::IsTerminal::is_terminal(&std::io::stderr());
    let mut last_line = String::new();
    let mut last_print = Instant::now() - Duration::from_secs(10);
    let mut failures = 0u32;
    loop {
        let r = http
            .get(format!("{base}/api/v1/sweeps/{id}"))
            .timeout(Duration::from_secs(30))
            .send();
        let info = match r {
            Ok(r) if r.status().is_success() => r.json::<SweepInfo>().ok(),
            Ok(r) if r.status() == StatusCode::NOT_FOUND => {
                anyhow::bail!("sweep {id} disappeared from the server (deleted?)")
            }
            _ => None,
        };
        match info {
            Some(s) => {
                failures = 0;
                let line = sweep_line(&s);
                let done = s.total > 0
                    && s.counts.get("queued").copied().unwrap_or(0) == 0
                    && s.counts.get("running").copied().unwrap_or(0) == 0;
                if tty {
                    eprint!("\r{line}   ");
                } else if line != last_line
                    && (done || last_print.elapsed() > Duration::from_secs(2))
                {
                    eprintln!("{line}");
                    last_print = Instant::now();
                }
                last_line = line;
                if done {
                    if tty {
                        eprintln!();
                    }
                    for j in s.jobs.iter().flatten() {
                        let why = j
                            .message
                            .as_deref()
                            .map(|m| format!(": {m}"))
                            .unwrap_or_default();
                        eprintln!("  {} {} [{}]{why}", j.id, j.status.as_str(), j.label);
                    }
                    return Ok(SweepOutcome::Ended(id, Box::new(s)));
                }
            }
            None => {
                failures += 1;
                if failures > 120 {
                    anyhow::bail!("the server has not answered for two minutes");
                }
            }
        }
        std::thread::sleep(Duration::from_secs(1));
    }
}
