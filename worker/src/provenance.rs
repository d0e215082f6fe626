//! `summary.provenance`: the build, the machine and the times of a run.

use fracture_api::results::Provenance;

/// Git commit this binary was built from (`FRACTURE_GIT_COMMIT` or `git rev-parse HEAD` at
/// build time; `None` when neither was there).
pub const SOLVER_COMMIT: Option<&str> = option_env!("FRACTURE_GIT_COMMIT");

/// This machine's host name, `None` when it cannot be read.
pub fn host() -> Option<String> {
    #[cfg(unix)]
    {
        let n = rustix::system::uname()
            .nodename()
            .to_string_lossy()
            .into_owned();
        (!n.is_empty()).then_some(n)
    }
    #[cfg(not(unix))]
    {
        std::env::var("COMPUTERNAME").ok().filter(|n| !n.is_empty())
    }
}

/// The batch scheduler's job this process runs in, from the environment the scheduler
/// sets (`provenance.scheduler`; `None` outside one):
/// * Slurm: `slurm job 1234 (array 1230 task 4)` from `SLURM_JOB_ID`,
///   `SLURM_ARRAY_JOB_ID`, `SLURM_ARRAY_TASK_ID`;
/// * Kubernetes (`KUBERNETES_SERVICE_HOST` set): `kubernetes job NAME index 2 (pod POD)`
///   from `FRACTURE_K8S_JOB` (the manifest sets it), `JOB_COMPLETION_INDEX` (an Indexed
///   Job) and `POD_NAME` (the downward API) or the host name.
pub fn scheduler() -> Option<String> {
    scheduler_from(|k| std::env::var(k).ok().filter(|v| !v.is_empty()))
}

/// [`scheduler`] with the environment as a function (tests).
pub fn scheduler_from(var: impl Fn(&str) -> Option<String>) -> Option<String> {
    if let Some(job) = var("SLURM_JOB_ID") {
        return Some(
            match (var("SLURM_ARRAY_JOB_ID"), var("SLURM_ARRAY_TASK_ID")) {
                (Some(a), Some(t)) => format!("slurm job {job} (array {a} task {t})"),
                _ => format!("slurm job {job}"),
            },
        );
    }
    var("KUBERNETES_SERVICE_HOST")?;
    let mut s = format!(
        "kubernetes job {}",
        var("FRACTURE_K8S_JOB").unwrap_or_else(|| "?".into())
    );
    if let Some(i) = var("JOB_COMPLETION_INDEX") {
        s.push_str(&format!(" index {i}"));
    }
    if let Some(p) = var("POD_NAME").or_else(host) {
        s.push_str(&format!(" (pod {p})"));
    }
    Some(s)
}

/// A short tag of the scheduler's job for worker ids: `slurm1230_4`, `slurm1234`,
/// `k8s2`; `None` outside a scheduler.
pub fn scheduler_tag() -> Option<String> {
    let var = |k: &str| std::env::var(k).ok().filter(|v| !v.is_empty());
    if let Some(job) = var("SLURM_JOB_ID") {
        return Some(
            match (var("SLURM_ARRAY_JOB_ID"), var("SLURM_ARRAY_TASK_ID")) {
                (Some(a), Some(t)) => format!("slurm{a}_{t}"),
                _ => format!("slurm{job}"),
            },
        );
    }
    var("KUBERNETES_SERVICE_HOST")?;
    Some(format!(
        "k8s{}",
        var("JOB_COMPLETION_INDEX").unwrap_or_default()
    ))
}

/// Provenance of a run that started at `started_at` and ends now.
pub(crate) fn provenance(started_at: String) -> Box<Provenance> {
    Box::new(Provenance {
        solver_commit: SOLVER_COMMIT.map(String::from),
        host: host(),
        started_at,
        finished_at: fracture_api::clock::now_text(),
        scheduler: scheduler(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env<'a>(pairs: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
        move |k| {
            pairs
                .iter()
                .find(|(n, _)| *n == k)
                .map(|(_, v)| v.to_string())
        }
    }

    #[test]
    fn the_scheduler_is_read_from_its_environment() {
        assert_eq!(scheduler_from(env(&[])), None);
        assert_eq!(
            scheduler_from(env(&[("SLURM_JOB_ID", "77")])).as_deref(),
            Some("slurm job 77")
        );
        assert_eq!(
            scheduler_from(env(&[
                ("SLURM_JOB_ID", "1234"),
                ("SLURM_ARRAY_JOB_ID", "1230"),
                ("SLURM_ARRAY_TASK_ID", "4")
            ]))
            .as_deref(),
            Some("slurm job 1234 (array 1230 task 4)")
        );
        assert_eq!(
            scheduler_from(env(&[
                ("KUBERNETES_SERVICE_HOST", "10.0.0.1"),
                ("FRACTURE_K8S_JOB", "fracture-worker"),
                ("JOB_COMPLETION_INDEX", "2"),
                ("POD_NAME", "fracture-worker-2-x7k")
            ]))
            .as_deref(),
            Some("kubernetes job fracture-worker index 2 (pod fracture-worker-2-x7k)")
        );
    }
}
