//! `summary.provenance`: the build, the machine and the times of a run.

use fracture_api::results::Provenance;

/// Git commit this binary was built from (`FRACTURE_GIT_COMMIT` or `git rev-parse HEAD` at
/// build time; `None` when neither was there).
pub const SOLVER_COMMIT: Option<&str> = option_env!("FRACTURE_GIT_COMMIT");

/// Now, RFC 3339 UTC with milliseconds (`2026-12-02T02:30:00.123Z`).
pub(crate) fn now() -> String {
    let t = time::OffsetDateTime::now_utc();
    let t = t
        .replace_nanosecond(t.millisecond() as u32 * 1_000_000)
        .unwrap_or(t);
    t.format(&time::format_description::well_known::Rfc3339)
        .unwrap_or_default()
}

/// This machine's host name, `None` when it cannot be read.
pub(crate) fn host() -> Option<String> {
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

/// Provenance of a run that started at `started_at` and ends now.
pub(crate) fn provenance(started_at: String) -> Box<Provenance> {
    Box::new(Provenance {
        solver_commit: SOLVER_COMMIT.map(String::from),
        host: host(),
        started_at,
        finished_at: now(),
    })
}
