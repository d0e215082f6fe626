//! `fracture bench accuracy | throughput | skip`: the accuracy ladder of the verification
//! problems, the throughput matrix with the memory-bandwidth model, and the figures of what a
//! scene does not pay for. Every figure of `docs/accuracy.md` and `docs/performance.md` comes
//! from one of these commands, so it can be regenerated on an idle machine. Here: what the
//! benchmarks measure with (the median step, CPU time, the machine); their tables and plots
//! are drawn with [`crate::report`].

pub mod ab;
pub mod accuracy;
pub mod accuracy_plot;
pub mod block3d;
pub mod command;
pub mod skip;
pub mod throughput;

/// Median of `xs` (NaN when empty): the per-step time least disturbed by other load.
pub fn median(xs: &[f64]) -> f64 {
    let mut v: Vec<f64> = xs.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if !n.is_multiple_of(2) {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// CPU time (user + system) of this process so far, in seconds, from `/proc/self/stat`
/// (Linux, USER_HZ = 100); NaN where unavailable. Under load it measures the work of a
/// single-threaded run better than the wall clock does.
pub fn process_cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return f64::NAN;
    };
    // Fields after the command name (which may contain spaces) start at the state, field 3;
    // utime and stime are fields 14 and 15.
    let Some(rest) = stat.rfind(')').map(|i| &stat[i + 1..]) else {
        return f64::NAN;
    };
    let f: Vec<&str> = rest.split_whitespace().collect();
    match (
        f.get(11).and_then(|x| x.parse::<f64>().ok()),
        f.get(12).and_then(|x| x.parse::<f64>().ok()),
    ) {
        (Some(u), Some(s)) => (u + s) / 100.0,
        _ => f64::NAN,
    }
}

/// When and where the figures were taken: UTC time, host load and core count.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Machine {
    /// Seconds since the Unix epoch when the command started.
    pub unix_time: u64,
    /// 1-minute load average at the start (Linux; NaN elsewhere).
    pub load_average: f64,
    /// Cores available to this process.
    pub cores: usize,
    /// Solver version.
    pub solver_version: &'static str,
}

impl Machine {
    /// The machine now.
    pub fn now() -> Machine {
        let load_average = std::fs::read_to_string("/proc/loadavg")
            .ok()
            .and_then(|s| s.split_whitespace().next().and_then(|x| x.parse().ok()))
            .unwrap_or(f64::NAN);
        Machine {
            unix_time: std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_secs()),
            load_average,
            cores: std::thread::available_parallelism().map_or(1, |n| n.get()),
            solver_version: fracture_api::SOLVER_VERSION,
        }
    }
    /// One line for the reports.
    pub fn describe(&self) -> String {
        format!(
            "unix time {}, {} cores, 1-min load average {:.2} at the start{}; solver {}",
            self.unix_time,
            self.cores,
            self.load_average,
            if self.load_average > 0.5 {
                " (the machine was not idle: timings are noisy)"
            } else {
                ""
            },
            self.solver_version
        )
    }
}
