//! HTTP clients of `fracture submit` and `fracture sweep`: post the request, then (with
//! `--wait`) follow the job's or sweep's events until it ends.

use std::io::{BufRead, BufReader, Write};
use std::time::{Duration, Instant};

use fracture_api::jobs::{ErrorBody, JobInfo, JobStatus, StatusEvent};
use fracture_api::results::Progress;
use fracture_api::sweep::SweepInfo;
use reqwest::StatusCode;
use reqwest::blocking::Client;

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
    Ended(String, Box<SweepInfo>),
}

fn http_client() -> reqwest::Result<Client> {
    Client::builder()
        .connect_timeout(Duration::from_secs(5))
        .timeout(None::<Duration>)
        .build()
}

/// One line of a sweep's state: `3 jobs: 1 completed, 1 running, 1 queued (45%)`.
pub fn sweep_line(s: &SweepInfo) -> String {
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
    use SweepInfo;
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
