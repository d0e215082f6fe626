//! Workers from a real Slurm cluster: a single-node cluster (Debian's `slurmctld`, `slurmd`
//! and `munged`, configured and started by this test under a temporary folder, stopped by
//! pid at the end) runs `deploy/slurm/worker.sbatch` as a job array against a local server.
//!
//! 1. An array of 3 workers (at most 4 jobs each) drains 9 jobs: each completes exactly
//!    once (attempt 1, every row once), records the Slurm array task and host that ran it,
//!    all three workers take part, and they exit by themselves, status 0 (`--max-jobs`, or
//!    `--idle-exit` once the queue is empty).
//! 2. A worker signalled mid-job the way Slurm warns before a time limit
//!    (`scancel --signal=USR1 --batch`, as `--signal=B:USR1@120` does) hands its job back
//!    (queued, no attempt counted) and exits 0; a second array job completes it.
//!
//! When the Slurm daemons cannot run here (not installed, not root, the daemons do not
//! start) the test prints why and returns without checking anything
//! (`FRACTURE_REQUIRE_SLURM=1` makes that a failure instead).

#![allow(clippy::unwrap_used)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use fracture_e2e::{Server, fracture_bin, scene, tiny_scene};
use serde_json::Value;

const TOKEN: &str = "slurm-test-token";

/// A single-node Slurm cluster of this test.
struct Cluster {
    dir: PathBuf,
    conf: PathBuf,
    node: String,
}

fn run(cmd: &mut Command) -> Result<Output, String> {
    cmd.output()
        .map_err(|e| format!("cannot run {:?}: {e}", cmd.get_program()))
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .unwrap()
}

impl Cluster {
    /// Configure and start munged, slurmctld and slurmd; wait for the node to be idle.
    /// `Err`: why the cluster cannot run here.
    fn start(dir: &Path) -> Result<Cluster, String> {
        for tool in [
            "munged",
            "slurmctld",
            "slurmd",
            "sbatch",
            "sinfo",
            "squeue",
            "scancel",
            "scontrol",
        ] {
            let found = ["/usr/sbin", "/usr/bin", "/sbin", "/bin"]
                .iter()
                .any(|d| Path::new(d).join(tool).exists());
            if !found {
                return Err(format!(
                    "`{tool}` is not installed (apt-get install slurm-wlm munge)"
                ));
            }
        }
        let uid = run(Command::new("id").arg("-u"))?;
        if String::from_utf8_lossy(&uid.stdout).trim() != "0" {
            return Err("the test cluster's daemons run as root (SlurmUser=root)".into());
        }
        let node = run(Command::new("hostname").arg("-s"))?;
        let node = String::from_utf8_lossy(&node.stdout).trim().to_string();
        if node.is_empty() {
            return Err("no host name".into());
        }
        for d in ["state", "spool", "munge"] {
            std::fs::create_dir_all(dir.join(d)).map_err(|e| e.to_string())?;
        }
        let cl = Cluster {
            dir: dir.to_path_buf(),
            conf: dir.join("slurm.conf"),
            node: node.clone(),
        };
        // Munge: a key of its own and a socket in the folder.
        let key = dir.join("munge/munge.key");
        let bytes: Vec<u8> = (0..1024u32)
            .map(|i| (i.wrapping_mul(2654435761) >> 13) as u8 ^ (std::process::id() as u8))
            .collect();
        std::fs::write(&key, bytes).map_err(|e| e.to_string())?;
        let _ = run(Command::new("chmod").arg("400").arg(&key));
        let socket = dir.join("munge/munge.socket");
        let o = run(Command::new("munged")
            .arg(format!("--key-file={}", key.display()))
            .arg(format!("--socket={}", socket.display()))
            .arg(format!(
                "--pid-file={}",
                dir.join("munge/munged.pid").display()
            ))
            .arg(format!(
                "--log-file={}",
                dir.join("munge/munged.log").display()
            ))
            .arg(format!("--seed-file={}", dir.join("munge/seed").display()))
            .arg("--force"))?;
        if !o.status.success() {
            return Err(format!("munged did not start: {}", text(&o)));
        }
        let d = dir.display();
        let conf = format!(
            "ClusterName=fracturetest
SlurmctldHost={node}(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort={ctld}
SlurmdPort={slurmd}
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket={socket}
StateSaveLocation={d}/state
SlurmdSpoolDir={d}/spool
SlurmctldPidFile={d}/slurmctld.pid
SlurmdPidFile={d}/slurmd.pid
SlurmctldLogFile={d}/slurmctld.log
SlurmdLogFile={d}/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SlurmdParameters=config_overrides
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
ReturnToService=2
SchedulerType=sched/backfill
SchedulerParameters=sched_interval=1
MessageTimeout=10
KillWait=10
InactiveLimit=0
MinJobAge=600
NodeName={node} NodeAddr=127.0.0.1 CPUs=4 RealMemory=8000 State=UNKNOWN
PartitionName=test Nodes={node} Default=YES MaxTime=INFINITE State=UP
",
            ctld = free_port(),
            slurmd = free_port(),
            socket = socket.display(),
        );
        std::fs::write(&cl.conf, conf).map_err(|e| e.to_string())?;
        for daemon in ["slurmctld", "slurmd"] {
            let o = run(Command::new(daemon).arg("-f").arg(&cl.conf))?;
            if !o.status.success() {
                return Err(format!("{daemon} did not start: {}", text(&o)));
            }
        }
        let t0 = Instant::now();
        loop {
            let o = cl
                .cmd("sinfo")
                .args(["-h", "-o", "%T", "-n", &node])
                .output();
            let state = o.map(|o| text(&o)).unwrap_or_default();
            if state.trim() == "idle" {
                return Ok(cl);
            }
            if t0.elapsed() > Duration::from_secs(40) {
                let logs = cl.logs();
                return Err(format!(
                    "the node did not become idle in 40 s (sinfo: {}); {logs}",
                    state.trim()
                ));
            }
            std::thread::sleep(Duration::from_millis(300));
        }
    }

    /// A Slurm client command of this cluster.
    fn cmd(&self, program: &str) -> Command {
        let mut c = Command::new(program);
        c.env("SLURM_CONF", &self.conf);
        c
    }

    /// The daemons' last log lines.
    fn logs(&self) -> String {
        ["slurmctld.log", "slurmd.log", "munge/munged.log"]
            .iter()
            .map(|f| {
                let t = std::fs::read_to_string(self.dir.join(f)).unwrap_or_default();
                let lines: Vec<&str> = t.lines().collect();
                format!(
                    "{f}: {}",
                    lines[lines.len().saturating_sub(5)..].join(" | ")
                )
            })
            .collect::<Vec<_>>()
            .join("; ")
    }

    /// Submit `deploy/slurm/worker.sbatch` as the array `array` against `server`, with
    /// `env` added; returns the array's job id.
    fn submit_workers(&self, server: &Server, array: &str, env: &[(&str, &str)]) -> String {
        let sbatch = Path::new(env!("CARGO_MANIFEST_DIR")).join("../deploy/slurm/worker.sbatch");
        let bin = fracture_bin();
        let mut export = format!(
            "ALL,FRACTURE_SERVER={},FRACTURE_WORKER_TOKEN={TOKEN},FRACTURE_BIN={},\
             FRACTURE_THREADS=1,RUST_LOG=info",
            server.url,
            bin.display()
        );
        for (k, v) in env {
            export.push_str(&format!(",{k}={v}"));
        }
        let o = self
            .cmd("sbatch")
            .arg("--parsable")
            .arg(format!("--array={array}"))
            .args(["--cpus-per-task=1", "--mem=1G", "--time=10"])
            .arg(format!("--chdir={}", self.dir.display()))
            .arg(format!("--output={}/worker-%A_%a.out", self.dir.display()))
            .arg(format!("--export={export}"))
            .arg(&sbatch)
            .output()
            .unwrap();
        assert!(o.status.success(), "sbatch: {}", text(&o));
        let id = String::from_utf8_lossy(&o.stdout).trim().to_string();
        id.split(';').next().unwrap().to_string()
    }

    /// Tasks of the array `id` still pending or running.
    fn active(&self, id: &str) -> usize {
        let o = self
            .cmd("squeue")
            .args(["-h", "-j", id, "-o", "%i"])
            .output();
        o.map(|o| {
            String::from_utf8_lossy(&o.stdout)
                .lines()
                .filter(|l| !l.trim().is_empty())
                .count()
        })
        .unwrap_or(0)
    }

    /// Wait until no task of the array `id` is pending or running.
    fn wait_gone(&self, id: &str, timeout: Duration) {
        let t0 = Instant::now();
        while self.active(id) > 0 {
            assert!(
                t0.elapsed() < timeout,
                "array {id} still has tasks after {timeout:?}: {}",
                self.show(id)
            );
            std::thread::sleep(Duration::from_millis(300));
        }
    }

    /// `scontrol show job` of the array `id`, one line per task.
    fn show(&self, id: &str) -> String {
        let o = self
            .cmd("scontrol")
            .args(["-o", "show", "job", id])
            .output();
        o.map(|o| text(&o)).unwrap_or_default()
    }

    /// (task, JobState, ExitCode) of every task of the array `id`.
    fn task_states(&self, id: &str) -> Vec<(String, String, String)> {
        self.show(id)
            .lines()
            .filter_map(|l| {
                let field = |k: &str| {
                    l.split_whitespace()
                        .find_map(|w| w.strip_prefix(k))
                        .map(str::to_string)
                };
                Some((
                    field("ArrayTaskId=")?,
                    field("JobState=")?,
                    field("ExitCode=")?,
                ))
            })
            .collect()
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        // Jobs first (the workers end with them), then the daemons, by their pid files.
        let _ = self.cmd("scancel").args(["--user", "root"]).output();
        let t0 = Instant::now();
        while t0.elapsed() < Duration::from_secs(15) {
            let o = self.cmd("squeue").args(["-h", "-o", "%i"]).output();
            if o.map(|o| o.stdout.iter().all(u8::is_ascii_whitespace))
                .unwrap_or(true)
            {
                break;
            }
            std::thread::sleep(Duration::from_millis(300));
        }
        for pidfile in ["slurmd.pid", "slurmctld.pid", "munge/munged.pid"] {
            let Ok(pid) = std::fs::read_to_string(self.dir.join(pidfile)) else {
                continue;
            };
            let pid = pid.trim().to_string();
            let _ = Command::new("kill").args(["-TERM", &pid]).status();
            let t0 = Instant::now();
            while Path::new(&format!("/proc/{pid}")).exists()
                && t0.elapsed() < Duration::from_secs(10)
            {
                std::thread::sleep(Duration::from_millis(100));
            }
            if Path::new(&format!("/proc/{pid}")).exists() {
                let _ = Command::new("kill").args(["-KILL", &pid]).status();
            }
        }
    }
}

fn status(j: &Value) -> &str {
    j["status"].as_str().unwrap_or("?")
}

/// Energy rows of a job: their times strictly increase (no row twice).
fn assert_rows_once(s: &Server, id: &str) -> usize {
    let rows = s.get_json(&format!("/api/v1/jobs/{id}/energy"));
    let times: Vec<f64> = rows
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["time"].as_f64().unwrap())
        .collect();
    assert!(!times.is_empty(), "job {id} has no energy rows");
    assert!(
        times.windows(2).all(|w| w[0] < w[1]),
        "job {id} has rows twice or out of order: {times:?}"
    );
    times.len()
}

/// The Slurm array task that ran a completed job, from its summary's provenance
/// (`slurm job J (array A task T)`): (A, T, J, host).
fn ran_by(j: &Value) -> (String, String, String, String) {
    let p = &j["summary"]["provenance"];
    let sched = p["scheduler"].as_str().unwrap_or("");
    let words: Vec<&str> = sched
        .split(|c: char| c.is_whitespace() || c == '(' || c == ')')
        .filter(|w| !w.is_empty())
        .collect();
    // ["slurm", "job", J, "array", A, "task", T]
    assert!(
        words.len() == 7 && words[0] == "slurm" && words[3] == "array",
        "job {} does not name its Slurm array task: {p}",
        j["id"]
    );
    (
        words[4].to_string(),
        words[6].to_string(),
        words[2].to_string(),
        p["host"].as_str().unwrap_or("?").to_string(),
    )
}

#[test]
fn a_slurm_job_array_drains_the_queue_and_a_signalled_worker_hands_its_job_back() {
    let dir = tempfile::tempdir().unwrap();
    let cluster_dir = dir.path().join("slurm");
    std::fs::create_dir_all(&cluster_dir).unwrap();
    let cluster = match Cluster::start(&cluster_dir) {
        Ok(c) => c,
        Err(why) => {
            // Stop whatever did start (the pid files say what).
            drop(Cluster {
                dir: cluster_dir.clone(),
                conf: cluster_dir.join("slurm.conf"),
                node: String::new(),
            });
            if std::env::var("FRACTURE_REQUIRE_SLURM").is_ok_and(|v| v == "1") {
                panic!("the Slurm test cluster cannot run here: {why}");
            }
            eprintln!("SKIPPED: the Slurm test cluster cannot run here: {why}");
            return;
        }
    };
    let data = dir.path().join("data");
    std::fs::create_dir_all(&data).unwrap();
    let s = Server::start(&data, &["--workers", "0", "--worker-token", TOKEN]);
    let t_start = Instant::now();

    // 1. Nine jobs, drained by an array of three workers (all three at once: `%3`), each
    //    at most 4 jobs (so all three take part: 4 + 4 + 1 at least), exiting 4 s after the
    //    queue is empty.
    let ids: Vec<String> = (0..9)
        .map(|i| s.submit(&tiny_scene(&format!("slurm-{i}"), 2000, 0)))
        .collect();
    let array = cluster.submit_workers(
        &s,
        "0-2%3",
        &[("FRACTURE_IDLE_EXIT", "4"), ("FRACTURE_MAX_JOBS", "4")],
    );
    let jobs: Vec<Value> = ids
        .iter()
        .map(|id| s.wait_done(id, Duration::from_secs(120)))
        .collect();
    let drained = t_start.elapsed();
    cluster.wait_gone(&array, Duration::from_secs(60));
    let mut timeline: Vec<(String, String, String, String, String)> = Vec::new();
    let mut tasks = std::collections::BTreeSet::new();
    for j in &jobs {
        assert_eq!(status(j), "completed", "{j}");
        assert_eq!(j["attempts"], 1, "completed once, on its first claim: {j}");
        assert_rows_once(&s, j["id"].as_str().unwrap());
        let (a, t, job, host) = ran_by(j);
        assert_eq!(a, array, "{j}");
        assert_eq!(host, cluster.node, "{j}");
        tasks.insert(t.clone());
        let p = &j["summary"]["provenance"];
        timeline.push((
            p["started_at"].as_str().unwrap_or("").to_string(),
            p["finished_at"].as_str().unwrap_or("").to_string(),
            j["name"].as_str().unwrap_or("").to_string(),
            format!("array {a} task {t} (slurm job {job})"),
            host,
        ));
    }
    // Every task exited by itself, status 0: after its 4 jobs, or idle (at least one: 12
    // claims could be made for 9 jobs).
    let mut idle = 0;
    let states = cluster.task_states(&array);
    assert_eq!(states.len(), 3, "{}", cluster.show(&array));
    for (task, state, code) in &states {
        assert_eq!(
            (state.as_str(), code.as_str()),
            ("COMPLETED", "0:0"),
            "task {task}: {}",
            cluster.show(&array)
        );
        let out = std::fs::read_to_string(cluster_dir.join(format!("worker-{array}_{task}.out")))
            .unwrap_or_default();
        assert!(
            out.contains("--idle-exit") || out.contains("--max-jobs"),
            "task {task} did not exit by itself: {out}"
        );
        idle += usize::from(out.contains("--idle-exit"));
    }
    assert!(idle >= 1, "no worker exited idle");
    assert_eq!(
        tasks.len(),
        3,
        "the jobs were not spread over the array's workers: {timeline:?}"
    );
    timeline.sort();
    eprintln!(
        "{} jobs drained by array {array} in {:.1} s:",
        jobs.len(),
        drained.as_secs_f64()
    );
    for (start, end, name, by, host) in &timeline {
        eprintln!("  {name}: {start} .. {end}  {by} on {host}");
    }

    // 2. A worker warned by Slurm mid-job hands the job back; another array completes it.
    // Long enough (seconds) to be signalled between two progress reports (0.5 s apart).
    let long = s.submit(&scene("slurm-handback", 40, 20, 10000, 0));
    let first = cluster.submit_workers(
        &s,
        "0",
        &[("FRACTURE_IDLE_EXIT", "60"), ("RUST_LOG", "info")],
    );
    let j = s.wait_for(&long, Duration::from_secs(60), |j| {
        j["progress"]["step"].as_u64().unwrap_or(0) > 0
    });
    assert_eq!(status(&j), "running", "{j}");
    let holder = j["worker"].as_str().unwrap_or("").to_string();
    assert!(
        holder.contains(&format!("slurm{first}_0")),
        "the worker id names its array task: {holder}"
    );
    let t0 = Instant::now();
    let o = cluster
        .cmd("scancel")
        .args(["--signal=USR1", "--batch", &format!("{first}_0")])
        .output()
        .unwrap();
    assert!(o.status.success(), "scancel: {}", text(&o));
    let j = s.wait_for(&long, Duration::from_secs(30), |j| status(j) != "running");
    let handed_back = t0.elapsed();
    assert_eq!(status(&j), "queued", "{j}");
    assert_eq!(j["attempts"], 0, "no attempt counted: {j}");
    let m = j["message"].as_str().unwrap_or("");
    assert!(
        m.contains("handed back")
            && m.contains("SIGUSR1")
            && m.contains(&format!("(array {first} task 0)")),
        "{m}"
    );
    let stopped_at = j["progress"]["step"].as_u64().unwrap_or(0);
    cluster.wait_gone(&first, Duration::from_secs(30));
    let states = cluster.task_states(&first);
    assert_eq!(
        states
            .iter()
            .map(|(_, s, c)| (s.as_str(), c.as_str()))
            .collect::<Vec<_>>(),
        [("COMPLETED", "0:0")],
        "{}",
        cluster.show(&first)
    );
    let second = cluster.submit_workers(&s, "0", &[("FRACTURE_IDLE_EXIT", "3")]);
    let j = s.wait_done(&long, Duration::from_secs(180));
    assert_eq!(status(&j), "completed", "{j}");
    assert_eq!(j["attempts"], 1, "{j}");
    let (a, t, job, host) = ran_by(&j);
    assert_eq!(a, second, "completed by the second array: {j}");
    let rows = assert_rows_once(&s, &long);
    // The second worker resumed from the checkpoint the first wrote at the hand-back (the
    // server logs the step of every resume), not from step 0.
    let resumed = fracture_e2e::resumed_steps(&data, &long);
    assert_eq!(resumed.len(), 1, "one resume expected: {resumed:?}");
    assert!(
        resumed[0] > 0 && resumed[0] + 200 >= stopped_at,
        "resumed from step {} after a hand-back at step {stopped_at}",
        resumed[0]
    );
    cluster.wait_gone(&second, Duration::from_secs(60));
    eprintln!(
        "{}: handed back by array {first} task 0 at step {stopped_at}, {:.2} s after \
         SIGUSR1; completed by array {a} task {t} (slurm job {job}) on {host}, attempt 1, \
         {rows} energy rows; {:.1} s in all",
        j["name"].as_str().unwrap_or(""),
        handed_back.as_secs_f64(),
        t_start.elapsed().as_secs_f64()
    );
    drop(s);
    drop(cluster);
}
