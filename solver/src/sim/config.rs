//! How the solver runs (not physics): threads of the parallel loops. Results are bitwise
//! identical for any thread count (the strip-coloured scatter of `grid::for_strips`).

/// How many threads the solver's parallel loops use. Results are bitwise identical for any
/// choice (deterministic strip-coloured scatter).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Parallelism {
    /// One thread per core (`std::thread::available_parallelism`).
    #[default]
    AllCores,
    /// Exactly this many threads.
    Threads(std::num::NonZeroUsize),
}

impl Parallelism {
    /// Exactly `n` threads (at least one).
    pub fn threads(n: usize) -> Parallelism {
        Parallelism::Threads(std::num::NonZeroUsize::MIN.saturating_add(n.saturating_sub(1)))
    }
    /// The command line's count: 0 means one per core, `n` means `n` threads.
    pub fn from_count(n: usize) -> Parallelism {
        if n == 0 {
            Parallelism::AllCores
        } else {
            Parallelism::threads(n)
        }
    }
    /// The number of threads this means on this machine.
    pub fn resolve(self) -> usize {
        match self {
            Parallelism::AllCores => std::thread::available_parallelism().map_or(1, |n| n.get()),
            Parallelism::Threads(n) => n.get(),
        }
    }
}

impl std::fmt::Display for Parallelism {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Parallelism::AllCores => f.write_str("all"),
            Parallelism::Threads(n) => write!(f, "{n}"),
        }
    }
}

impl std::str::FromStr for Parallelism {
    type Err = String;
    /// `all` (or `0`) for one thread per core, or a thread count.
    fn from_str(s: &str) -> Result<Parallelism, String> {
        let s = s.trim();
        if s.eq_ignore_ascii_case("all") {
            return Ok(Parallelism::AllCores);
        }
        s.parse::<usize>()
            .map(Parallelism::from_count)
            .map_err(|_| format!("`{s}` is not a thread count (a whole number, or `all`)"))
    }
}

/// How the solver runs (not physics).
#[derive(Debug, Clone, Copy, Default)]
pub struct SolverConfig {
    /// Threads of the parallel loops.
    pub threads: Parallelism,
}

impl SolverConfig {
    /// One thread per core.
    pub fn all_cores() -> SolverConfig {
        SolverConfig {
            threads: Parallelism::AllCores,
        }
    }
    /// Exactly `n` threads (at least one).
    pub fn with_threads(n: usize) -> SolverConfig {
        SolverConfig {
            threads: Parallelism::threads(n),
        }
    }
}
