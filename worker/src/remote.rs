//! The remote worker: claims jobs from a server over HTTP (`/api/v1/worker/…`), runs them
//! with [`run_scene`](crate::run_scene), heartbeats, obeys cancellation, and streams the
//! results through an HTTP [`RunSink`], retrying transient failures.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use crate::{Control, RunOptions, RunSink, SinkError};
use fracture_api::jobs::ErrorBody;
use fracture_api::results::{
    CrackTipRow, EnergyRow, FailureKind, Progress, RunStatus, Snapshot, Summary,
};
use fracture_api::{Scene, ValidScene};
use reqwest::StatusCode;
use reqwest::blocking::{Client, Response};

use fracture_api::protocol::{
    Claim, ClaimRequest, CrackTipBatch, EnergyBatch, FinishRequest, Heartbeat, HeartbeatReply,
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

fn failed_summary(scene: Option<&Scene>, failure: FailureKind, message: String) -> Summary {
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
    // The server validated the scene before queueing it; a worker of another version may
    // still disagree, so it validates once more here (the only way to a `ValidScene`).
    let summary = match fracture_api::validate::scene_from_value(claim.scene) {
        Ok(scene) => match ValidScene::new(scene.clone()) {
            Ok(valid) => {
                let opts = RunOptions {
                    threads: cfg.threads,
                    flush_every: cfg.flush_every,
                };
                crate::run_scene(&valid, &opts, &mut sink)
            }
            Err(e) => failed_summary(
                Some(&scene),
                FailureKind::InvalidScene,
                format!("the claimed scene is not valid here:\n{e}"),
            ),
        },
        Err(e) => failed_summary(
            None,
            FailureKind::InvalidScene,
            format!("the claimed scene could not be read: {e}"),
        ),
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
