//! The supervisor of a remote worker (`fracture worker`): it runs the worker loop in a
//! child process (the same executable, re-run with a hidden flag), copies the child's
//! stderr to its own and keeps its last lines, and learns from the child's stdout which
//! claim (job and fence) the child holds. When the child dies holding a claim, the
//! supervisor reports the cause (signal or exit status, what it usually means, the last
//! lines of stderr) to the server (`POST /api/v1/worker/jobs/{id}/died`, fenced), which
//! releases the job at once instead of waiting for its lease; then it starts a new child.
//!
//! A child that ends by itself (status 0, or 1: the server refused the token or stayed
//! unreachable) while it holds nothing ends the supervisor with the same status.
//!
//! A stop signal (SIGTERM, SIGUSR1: [`crate::batch`]) is forwarded to the child, which hands
//! its job back and exits; the supervisor then starts no other and exits with the child's
//! status. Claims are counted across children (`--jobs-before`), so `--max-jobs` holds
//! for the whole `fracture worker`.

use std::collections::VecDeque;
use std::ffi::OsString;
use std::io::{BufRead, BufReader, Write};
use std::path::PathBuf;
use std::process::{Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use fracture_api::protocol::{STDERR_TAIL, WorkerDied, exit_cause};
use reqwest::blocking::Client;

use crate::remote::{Api, ClientError};

/// Start of the lines a supervised child writes on its stdout about its claim.
const CLAIM_LINE: &str = "fracture-worker-claim: ";

/// Tell the supervisor which claim this process holds (`None`: none). Written to stdout;
/// a closed stdout (the supervisor is gone) is ignored.
pub(crate) fn announce(claim: Option<(&str, i64)>) {
    let mut out = std::io::stdout().lock();
    let _ = match claim {
        Some((job, fence)) => writeln!(out, "{CLAIM_LINE}holds {job} {fence}"),
        None => writeln!(out, "{CLAIM_LINE}idle"),
    };
    let _ = out.flush();
}

/// What a line of the child's stdout says about its claim: `Some(Some(claim))` holds,
/// `Some(None)` idle, `None` not a claim line.
fn parse_claim_line(line: &str) -> Option<Option<(String, i64)>> {
    let rest = line.strip_prefix(CLAIM_LINE)?;
    if rest.trim() == "idle" {
        return Some(None);
    }
    let mut it = rest.strip_prefix("holds ")?.split_whitespace();
    let job = it.next()?.to_string();
    let fence = it.next()?.parse().ok()?;
    Some(Some((job, fence)))
}

/// How to run and report the child.
#[derive(Debug, Clone)]
pub struct Supervisor {
    /// The executable of the child (this one).
    pub exe: PathBuf,
    /// The child's arguments; the supervisor adds `--parent-pid <its pid>` so that the
    /// child exits when the supervisor is gone.
    pub args: Vec<OsString>,
    /// Base URL of the server.
    pub server: String,
    /// Worker token.
    pub token: String,
}

/// How one child ended.
struct Ended {
    status: ExitStatus,
    claim: Option<(String, i64)>,
    /// Claims it announced.
    claims: u64,
    tail: Vec<String>,
    ran: Duration,
}

/// The running child (its pid; 0: none) and whether a stop signal came.
#[derive(Default)]
struct Stopping {
    child: AtomicU32,
    asked: AtomicBool,
}

/// Forward the stop signals to the running child and remember that they came.
#[cfg(unix)]
fn forward_stop_signals(st: Arc<Stopping>) -> std::io::Result<()> {
    crate::batch::on_stop_signals(move |sig| {
        st.asked.store(true, Ordering::SeqCst);
        let pid = st.child.load(Ordering::SeqCst);
        tracing::warn!(
            signal = %crate::batch::signal_text(sig),
            child = pid,
            "asked to stop: the worker process hands its job back"
        );
        let signal = if sig == signal_hook::consts::SIGUSR1 {
            rustix::process::Signal::USR1
        } else {
            rustix::process::Signal::TERM
        };
        if let Some(p) = i32::try_from(pid)
            .ok()
            .and_then(rustix::process::Pid::from_raw)
        {
            let _ = rustix::process::kill_process(p, signal);
        }
    })
}

/// Run children until one ends by itself; returns its exit status code.
pub fn supervise(s: &Supervisor) -> i32 {
    let api = Api {
        http: match Client::builder()
            .timeout(Duration::from_secs(20))
            .connect_timeout(Duration::from_secs(5))
            .build()
        {
            Ok(c) => c,
            Err(e) => {
                tracing::error!(error = %e, "cannot build an HTTP client");
                return 1;
            }
        },
        base: s.server.trim_end_matches('/').to_string(),
        token: s.token.clone(),
    };
    let stopping = Arc::new(Stopping::default());
    #[cfg(unix)]
    if let Err(e) = forward_stop_signals(stopping.clone()) {
        tracing::warn!(error = %e, "cannot handle stop signals");
    }
    let mut backoff = Duration::from_millis(200);
    let mut claims = 0u64;
    loop {
        let ended = match run_child(s, claims, &stopping) {
            Ok(e) => e,
            Err(e) => {
                tracing::error!(error = %e, exe = %s.exe.display(), "cannot start the worker process");
                return 1;
            }
        };
        claims += ended.claims;
        let cause = exit_cause(&ended.status, &ended.tail);
        match &ended.claim {
            Some((job, fence)) => {
                tracing::warn!(job = %job, cause = %cause, "the worker process died holding a job");
                report(&api, job, *fence, &cause);
            }
            None => {
                if let Some(code @ (0 | 1)) = ended.status.code() {
                    return code;
                }
                tracing::warn!(cause = %cause, "the worker process died");
            }
        }
        if stopping.asked.load(Ordering::SeqCst) {
            tracing::info!("asked to stop; no new worker process");
            return ended.status.code().unwrap_or(0);
        }
        if ended.ran > Duration::from_secs(10) {
            backoff = Duration::from_millis(200);
        }
        std::thread::sleep(backoff);
        backoff = (backoff * 2).min(Duration::from_secs(5));
        tracing::info!("starting a new worker process");
    }
}

/// Tell the server that the claim `job`/`fence` died with `cause` (retried while the
/// server is unreachable or its disk is full; the lease is the fallback).
fn report(api: &Api, job: &str, fence: i64, cause: &str) {
    let body = WorkerDied {
        fence,
        cause: cause.to_string(),
    };
    let path = format!("jobs/{job}/died");
    let r = api.retry(Duration::from_secs(30), || {
        api.post_json(&path, &body)?
            .json::<serde_json::Value>()
            .map_err(|e| ClientError::Transient(e.to_string()))
    });
    match r {
        Ok(j) => tracing::warn!(
            job,
            status = j["status"].as_str().unwrap_or("?"),
            "the server released the job"
        ),
        Err(ClientError::Fenced(m)) => {
            tracing::info!(job, reason = %m, "the job was no longer held (finished or released)")
        }
        Err(e) => tracing::warn!(
            job,
            error = %e,
            "cannot report the death; the server will find it by the job's lease"
        ),
    }
}

/// Run one child to its end (`claims`: those of the children before it).
fn run_child(s: &Supervisor, claims: u64, stopping: &Stopping) -> std::io::Result<Ended> {
    let started = Instant::now();
    let mut child = Command::new(&s.exe)
        .args(&s.args)
        .arg("--parent-pid")
        .arg(std::process::id().to_string())
        .arg("--jobs-before")
        .arg(claims.to_string())
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()?;
    stopping.child.store(child.id(), Ordering::SeqCst);
    if stopping.asked.load(Ordering::SeqCst) {
        // A signal that came while no child ran: this one stops at once.
        #[cfg(unix)]
        if let Some(p) = i32::try_from(child.id())
            .ok()
            .and_then(rustix::process::Pid::from_raw)
        {
            let _ = rustix::process::kill_process(p, rustix::process::Signal::TERM);
        }
    }
    tracing::info!(pid = child.id(), "worker process started");
    let tail = Arc::new(Mutex::new(VecDeque::with_capacity(STDERR_TAIL)));
    let err_thread = child.stderr.take().map(|err| {
        let tail = tail.clone();
        std::thread::spawn(move || {
            for line in BufReader::new(err).lines() {
                let Ok(line) = line else { break };
                // Our stderr may be gone or full: the tail is kept all the same.
                let _ = writeln!(std::io::stderr().lock(), "{line}");
                if let Ok(mut t) = tail.lock() {
                    if t.len() == STDERR_TAIL {
                        t.pop_front();
                    }
                    t.push_back(line);
                }
            }
        })
    });
    let out_thread = child.stdout.take().map(|out| {
        std::thread::spawn(move || {
            let (mut claim, mut claims) = (None, 0u64);
            for line in BufReader::new(out).lines() {
                let Ok(line) = line else { break };
                match parse_claim_line(&line) {
                    Some(c) => {
                        claims += u64::from(c.is_some());
                        claim = c;
                    }
                    None => {
                        let _ = writeln!(std::io::stdout().lock(), "{line}");
                    }
                }
            }
            (claim, claims)
        })
    });
    let status = child.wait()?;
    stopping.child.store(0, Ordering::SeqCst);
    // The pipes end with the child: what it wrote before dying is read first.
    let (claim, claims) = out_thread.and_then(|t| t.join().ok()).unwrap_or((None, 0));
    if let Some(t) = err_thread {
        let _ = t.join();
    }
    let tail = tail
        .lock()
        .map(|t| t.iter().cloned().collect())
        .unwrap_or_default();
    Ok(Ended {
        status,
        claim,
        claims,
        tail,
        ran: started.elapsed(),
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn claim_lines_are_read_and_others_are_not() {
        assert_eq!(
            parse_claim_line("fracture-worker-claim: holds j-12ab 7"),
            Some(Some(("j-12ab".to_string(), 7)))
        );
        assert_eq!(parse_claim_line("fracture-worker-claim: idle"), Some(None));
        assert_eq!(parse_claim_line("holds j 7"), None);
        assert_eq!(parse_claim_line("fracture-worker-claim: holds j x"), None);
    }
}
