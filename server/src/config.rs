//! Run-time configuration of the service: queue timing and the limits that keep one request
//! from exhausting the machine.
//!
//! A scene is admitted in two stages ([`Limits::admit`]): [`Limits::precheck`] estimates the
//! particle count from the bodies' regions in O(bodies), so an enormous scene is refused
//! before anything walks its lattice; then the O(particles) validation
//! (`fracture_api::validate`) and [`Limits::check`] of the exact size, which callers run off
//! the async threads.
//!
//! Besides the size limits, a run's cost is bounded before it runs
//! (`fracture_api::cost`): its memory estimate (grid, particles, crack tables, a snapshot
//! in flight) by `max_memory_bytes`, and its work (particles × steps) by
//! `max_particle_steps` — both in the precheck with the particle estimate, and again with
//! the exact count. Names and labels are bounded too ([`Limits::check_names`]).

use std::time::Duration;

use std::collections::BTreeMap;

use fracture_api::cost;
use fracture_api::jobs::ErrorDetail;
use fracture_api::scene::Region;
use fracture_api::{RunSize, Scene, validate};

use crate::error::ApiError;

/// Limits on what one request may ask for.
#[derive(Debug, Clone)]
pub struct Limits {
    /// Most particles a scene may have.
    pub max_particles: u64,
    /// Most time steps a scene may take.
    pub max_steps: u64,
    /// Most snapshot volume: number of snapshots × grid nodes.
    pub max_snapshot_volume: u64,
    /// Largest request body of the public API (bytes).
    pub max_body_bytes: usize,
    /// Largest request body of the worker API (bytes; snapshots are large).
    pub max_worker_body_bytes: usize,
    /// Most jobs (parameter combinations) one sweep may create.
    pub max_sweep_jobs: u64,
    /// Most memory a run may need (`fracture_api::cost::memory_estimate`, bytes).
    pub max_memory_bytes: u64,
    /// Most work a run may take: particles × time steps.
    pub max_particle_steps: u64,
    /// Longest scene, job or sweep name (bytes).
    pub max_name_bytes: usize,
    /// Most labels on a job or sweep.
    pub max_labels: usize,
    /// Longest label key (bytes).
    pub max_label_key_bytes: usize,
    /// Longest label value (bytes).
    pub max_label_value_bytes: usize,
}

/// Default of [`Limits::max_memory_bytes`] where the machine's memory is not known: 8 GiB.
pub const DEFAULT_MAX_MEMORY_BYTES: u64 = 8 << 30;

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_particles: 4_000_000,
            max_steps: 5_000_000,
            max_snapshot_volume: 400_000_000,
            max_body_bytes: 4 << 20,
            max_worker_body_bytes: 512 << 20,
            max_sweep_jobs: 100,
            max_memory_bytes: DEFAULT_MAX_MEMORY_BYTES,
            max_particle_steps: 100_000_000_000,
            max_name_bytes: 256,
            max_labels: 32,
            max_label_key_bytes: 64,
            max_label_value_bytes: 256,
        }
    }
}

/// One exceeded limit: its name and the detail naming the quantity, the value and the limit.
pub(crate) type Exceeded = (&'static str, ErrorDetail);

pub(crate) fn exceeded(found: Vec<Exceeded>) -> Result<(), ApiError> {
    if found.is_empty() {
        return Ok(());
    }
    let mut names: Vec<&str> = found.iter().map(|(n, _)| *n).collect();
    names.dedup();
    Err(ApiError::LimitExceeded {
        message: format!(
            "the scene exceeds this server's limits: {}",
            names.join(", ")
        ),
        details: found.into_iter().map(|(_, d)| d).collect(),
    })
}

impl Limits {
    /// The cheap check, before any lattice walk: refuse (422 `limit_exceeded`, naming
    /// `max_particles`) a scene whose estimated particles exceed `max_particles`, or whose
    /// bodies would make validation examine more than [`SITES_PER_PARTICLE`] ×
    /// `max_particles` candidate sites. O(bodies): fine on an async thread.
    pub fn precheck(&self, scene: &Scene) -> Result<(), ApiError> {
        let est = estimate_particles(scene);
        if let Some(e) = self.particle_precheck(est.at_least, est.sites) {
            return Err(e);
        }
        if let Some(e) = time_step_overflow(scene) {
            return Err(e);
        }
        // The cost with the lower particle estimate: cheap counts first.
        let steps = cost::steps_estimate(scene).unwrap_or(0);
        exceeded(self.cost(scene, est.at_least, steps, "at least "))
    }

    /// The `max_particles` part of a precheck, from a lower estimate of the particle count
    /// and the candidate sites of the lattice walk (2D and 3D alike).
    pub(crate) fn particle_precheck(&self, at_least: u64, sites: u64) -> Option<ApiError> {
        let message = if at_least > self.max_particles {
            format!(
                "the scene has at least {} particles (estimated from its bodies' regions), \
                 more than this server's limit max_particles = {}",
                at_least, self.max_particles
            )
        } else if sites > self.max_particles.saturating_mul(SITES_PER_PARTICLE) {
            format!(
                "the bodies' bounding boxes hold {} candidate particle sites, more than this \
                 server examines ({SITES_PER_PARTICLE} × its limit max_particles = {})",
                sites, self.max_particles
            )
        } else {
            return None;
        };
        Some(ApiError::LimitExceeded {
            message: "the scene exceeds this server's limits: max_particles".into(),
            details: vec![ErrorDetail {
                path: "bodies".into(),
                message,
            }],
        })
    }

    /// The cost limits (memory estimate, particle-steps) for `particles` particles and
    /// `steps` steps; `qualifier` ("at least ", or "" for exact counts) goes before the
    /// particle count in the messages.
    fn cost(&self, scene: &Scene, particles: u64, steps: u64, qualifier: &str) -> Vec<Exceeded> {
        let mem = cost::memory_estimate(scene, particles);
        let (nx, ny) = cost::grid_dims(scene).unwrap_or((0, 0));
        let grid = format!("{nx} × {ny} = {}", nx.saturating_mul(ny));
        self.cost_of(&mem, &grid, particles, steps, qualifier)
    }

    /// [`Limits::cost`] of a run whose memory estimate is `mem`; `grid` describes its grid
    /// nodes (`nx × ny = n`) in the message.
    pub(crate) fn cost_of(
        &self,
        mem: &cost::MemoryEstimate,
        grid: &str,
        particles: u64,
        steps: u64,
        qualifier: &str,
    ) -> Vec<Exceeded> {
        let mut found = Vec::new();
        if mem.total > self.max_memory_bytes {
            let path = if mem.grid + mem.cracks + mem.snapshot >= mem.particles {
                "grid.cell_size"
            } else {
                "bodies"
            };
            found.push((
                "max_memory_bytes",
                ErrorDetail {
                    path: path.into(),
                    message: format!(
                        "the run needs about {} bytes of memory ({grid} grid nodes, \
                         {qualifier}{particles} particles: {mem}), more than this server's \
                         limit max_memory_bytes = {} ({})",
                        mem.total,
                        self.max_memory_bytes,
                        cost::bytes(self.max_memory_bytes)
                    ),
                },
            ));
        }
        let work = cost::particle_steps(particles, steps);
        if work > self.max_particle_steps {
            found.push((
                "max_particle_steps",
                ErrorDetail {
                    path: "time.end".into(),
                    message: format!(
                        "the run takes {qualifier}{particles} particles × {steps} steps = \
                         {work:.3e} particle-steps, more than this server's limit \
                         max_particle_steps = {:.3e}",
                        self.max_particle_steps as f64,
                        work = work as f64
                    ),
                },
            ));
        }
        found
    }

    /// Names and labels within their limits (422 `limit_exceeded` naming the field).
    pub fn check_names(
        &self,
        name: Option<&str>,
        labels: &BTreeMap<String, String>,
    ) -> Result<(), ApiError> {
        let mut found: Vec<Exceeded> = Vec::new();
        if let Some(n) = name
            && n.len() > self.max_name_bytes
        {
            found.push((
                "max_name_bytes",
                ErrorDetail {
                    path: "name".into(),
                    message: format!(
                        "the name is {} bytes long, more than this server's limit \
                         max_name_bytes = {}",
                        n.len(),
                        self.max_name_bytes
                    ),
                },
            ));
        }
        if labels.len() > self.max_labels {
            found.push((
                "max_labels",
                ErrorDetail {
                    path: "labels".into(),
                    message: format!(
                        "{} labels, more than this server's limit max_labels = {}",
                        labels.len(),
                        self.max_labels
                    ),
                },
            ));
        }
        for (k, v) in labels {
            let short: String = k.chars().take(40).collect();
            if k.len() > self.max_label_key_bytes {
                found.push((
                    "max_label_key_bytes",
                    ErrorDetail {
                        path: format!("labels.{short}"),
                        message: format!(
                            "the label key is {} bytes long, more than this server's limit \
                             max_label_key_bytes = {}",
                            k.len(),
                            self.max_label_key_bytes
                        ),
                    },
                ));
            }
            if v.len() > self.max_label_value_bytes {
                found.push((
                    "max_label_value_bytes",
                    ErrorDetail {
                        path: format!("labels.{short}"),
                        message: format!(
                            "the label value is {} bytes long, more than this server's limit \
                             max_label_value_bytes = {}",
                            v.len(),
                            self.max_label_value_bytes
                        ),
                    },
                ));
            }
            if found.len() > 20 {
                break;
            }
        }
        if found.is_empty() {
            return Ok(());
        }
        let mut names: Vec<&str> = found.iter().map(|(n, _)| *n).collect();
        names.dedup();
        Err(ApiError::LimitExceeded {
            message: format!(
                "the request exceeds this server's limits: {}",
                names.join(", ")
            ),
            details: found.into_iter().map(|(_, d)| d).collect(),
        })
    }

    /// Admit a scene: [`Limits::precheck`], then validation (every problem with its path)
    /// and [`Limits::check`] of the exact size. CPU-bound (validation places every
    /// particle): call it off the async threads.
    pub fn admit(&self, scene: &Scene) -> Result<RunSize, ApiError> {
        self.precheck(scene)?;
        let size = validate::validate(scene)?;
        self.check(scene, &size)?;
        Ok(size)
    }

    /// Check a valid scene's size against the limits: 422 naming each exceeded limit.
    pub fn check(&self, scene: &Scene, size: &RunSize) -> Result<(), ApiError> {
        let mut found = self.size_limits(&scene.name, size);
        let snapshots = snapshot_count(scene);
        let volume = snapshots.saturating_mul(size.grid_nodes);
        if volume > self.max_snapshot_volume {
            found.push((
                "max_snapshot_volume",
                ErrorDetail {
                    path: "output.snapshot_interval".into(),
                    message: format!(
                        "{snapshots} snapshots × {} grid nodes = {volume}, more than this server's \
                         limit max_snapshot_volume = {}",
                        size.grid_nodes, self.max_snapshot_volume
                    ),
                },
            ));
        }
        found.extend(self.cost(scene, size.particles, size.steps, ""));
        exceeded(found)
    }

    /// The limits on a valid scene's name, particles and steps (2D and 3D alike).
    pub(crate) fn size_limits(&self, name: &str, size: &RunSize) -> Vec<Exceeded> {
        let mut found: Vec<Exceeded> = Vec::new();
        if let Err(e) = self.check_names(Some(name), &BTreeMap::new())
            && let ApiError::LimitExceeded { details, .. } = e
        {
            found.extend(details.into_iter().map(|d| ("max_name_bytes", d)));
        }
        if size.particles > self.max_particles {
            found.push((
                "max_particles",
                ErrorDetail {
                    path: "bodies".into(),
                    message: format!(
                        "the scene has {} particles, more than this server's limit max_particles = {}",
                        size.particles, self.max_particles
                    ),
                },
            ));
        }
        if size.steps > self.max_steps {
            found.push((
                "max_steps",
                ErrorDetail {
                    path: "time.end".into(),
                    message: format!(
                        "the run takes {} time steps, more than this server's limit max_steps = {}",
                        size.steps, self.max_steps
                    ),
                },
            ));
        }
        found
    }
}

/// A scene whose materials are each valid but whose time step is not a finite positive
/// number (a wave speed that overflows, e.g. density 1e-300): 422 naming the material,
/// instead of a run that "needs NaN steps".
fn time_step_overflow(scene: &Scene) -> Option<ApiError> {
    if scene.materials.is_empty()
        || scene
            .time_step()
            .is_some_and(|dt| dt > 0.0 && dt.is_finite())
    {
        return None;
    }
    let ok = |x: f64| x.is_finite() && x > 0.0;
    let (name, m) = scene.materials.iter().find(|(_, m)| {
        ok(m.density())
            && ok(m.youngs_modulus())
            && (-1.0..0.5).contains(&m.poissons_ratio())
            && !m.wave_speeds(scene.analysis).c_l.is_finite()
    })?;
    Some(ApiError::InvalidScene(vec![ErrorDetail {
        path: format!("materials.{name}.density"),
        message: format!(
            "{:e} gives a longitudinal wave speed that is not a finite number (E/ρ = {:e} / {:e} \
             overflows), so the time step cannot be computed",
            m.density(),
            m.youngs_modulus(),
            m.density()
        ),
    }]))
}

/// The lattice walk of validation examines at most this many candidate sites per allowed
/// particle (`max_particles`); a scene whose bodies' bounding boxes hold more is refused
/// before the walk. Only bodies whose bounding box is mostly empty (thin slanted polygons,
/// heavily overlapping bodies) come near it.
pub const SITES_PER_PARTICLE: u64 = 16;

/// What [`estimate_particles`] can tell without walking a lattice.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ParticleEstimate {
    /// A conservative lower estimate of the particle count: the largest rectangle or
    /// circle, less a one-cell band along its edge, at the sparsest lattice among it and the
    /// bodies before it (those win an overlap). Polygons count 0 here: the even-odd rule
    /// makes their area unsafe to guess.
    pub at_least: u64,
    /// Candidate sites the lattice walk visits: every body's bounding box, clipped to the
    /// grid box, in sub-cells. An upper bound of the particle count and the walk's work.
    pub sites: u64,
}

/// Estimate a scene's particles from its grid and its bodies' regions in O(bodies) (the
/// exact count, `fracture_api::validate`, walks every candidate site). Bodies validation
/// rejects before its walk (no finite region, `particles_per_cell` outside 1..=8) and an
/// invalid grid are left out.
pub fn estimate_particles(scene: &Scene) -> ParticleEstimate {
    let g = &scene.grid;
    let h = g.cell_size;
    let finite = |v: [f64; 2]| v[0].is_finite() && v[1].is_finite();
    if !(h.is_finite() && h > 0.0 && finite(g.min) && finite(g.max)) {
        return ParticleEstimate::default();
    }
    let mut sites = 0f64;
    let mut at_least = 0f64;
    let mut sparsest = f64::INFINITY; // particles per m² of the sparsest body so far
    for body in &scene.bodies {
        let ppc = body.particles_per_cell;
        if !(1..=8).contains(&ppc) {
            continue;
        }
        let sub = h / f64::from(ppc);
        let density = 1.0 / (sub * sub);
        sparsest = sparsest.min(density);
        let (lo, hi) = body.region.bounds();
        if !(finite(lo) && finite(hi)) {
            continue;
        }
        // The walk's index ranges (as `fracture_api::lattice::for_each_seed`), clipped to
        // the grid box.
        let lo = [lo[0].max(g.min[0]), lo[1].max(g.min[1])];
        let hi = [hi[0].min(g.max[0]), hi[1].min(g.max[1])];
        let span = |k: usize| {
            let i0 = ((lo[k] - g.min[k]) / sub).floor().max(0.0);
            let i1 = ((hi[k] - g.min[k]) / sub).ceil();
            (i1 - i0).max(0.0)
        };
        sites += span(0) * span(1);
        let (area, perimeter) = match &body.region {
            Region::Rectangle { .. } => {
                let (w, t) = ((hi[0] - lo[0]).max(0.0), (hi[1] - lo[1]).max(0.0));
                (w * t, 2.0 * (w + t))
            }
            Region::Circle { radius, .. } => (
                std::f64::consts::PI * radius * radius,
                2.0 * std::f64::consts::PI * radius,
            ),
            Region::Polygon { .. } => (0.0, 0.0),
        };
        let inner = (area - 2.0 * h * perimeter).max(0.0);
        at_least = f64::max(at_least, inner * sparsest);
    }
    let to_u64 = |x: f64| {
        if x >= u64::MAX as f64 {
            u64::MAX
        } else {
            x as u64
        }
    };
    ParticleEstimate {
        at_least: to_u64(at_least),
        sites: to_u64(sites),
    }
}

/// How many snapshots a run of this scene writes.
pub fn snapshot_count(scene: &Scene) -> u64 {
    let dt = scene.output.snapshot_interval;
    if dt > 0.0 && dt.is_finite() && scene.time.end.is_finite() {
        let n = (scene.time.end / dt).floor();
        if (0.0..1e15).contains(&n) {
            n as u64 + 1
        } else {
            u64::MAX
        }
    } else {
        0
    }
}

/// Configuration of the service (what `fracture serve` turns its flags into).
#[derive(Debug, Clone)]
pub struct Config {
    /// Token required for submit, cancel and delete; `None`: open.
    pub api_token: Option<String>,
    /// Token workers present on `/api/v1/worker/…`.
    pub worker_token: String,
    /// How long a claim or heartbeat holds a job.
    pub lease: Duration,
    /// Claims after which an expiring lease fails the job instead of re-queueing it.
    pub max_attempts: u32,
    /// Longest a claim request waits for a job.
    pub claim_wait: Duration,
    /// Request limits.
    pub limits: Limits,
    /// Local worker processes the server supervises (for `/health`).
    pub local_workers: usize,
    /// Host names (beyond loopback names and IP literals) the server answers to
    /// (`--allowed-host`; `*`: any). See `http::security`.
    pub allowed_hosts: Vec<String>,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            api_token: None,
            worker_token: String::new(),
            lease: Duration::from_secs(30),
            max_attempts: 3,
            claim_wait: Duration::from_secs(20),
            limits: Limits::default(),
            local_workers: 0,
            allowed_hosts: Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use serde_json::json;

    fn scene(bodies: serde_json::Value) -> Scene {
        validate::scene_from_value(json!({
            "name": "estimate",
            "grid": { "cell_size": 0.001, "min": [0.0, 0.0], "max": [0.05, 0.03] },
            "materials": { "m": { "model": "linear_elastic", "density": 1230.0,
                                  "youngs_modulus": 3.96e9, "poissons_ratio": 0.35 } },
            "bodies": bodies,
            "time": { "end": 1.0e-5 }
        }))
        .unwrap()
    }

    /// The estimate brackets the exact count of the lattice walk: at_least ≤ particles ≤ sites.
    #[test]
    fn the_estimate_brackets_the_exact_count() {
        let rect = |lo: [f64; 2], hi: [f64; 2], ppc: u32| {
            json!({ "material": "m", "region": { "rectangle": { "min": lo, "max": hi } },
                    "particles_per_cell": ppc })
        };
        let cases = [
            json!([rect([0.001, 0.001], [0.049, 0.029], 2)]),
            json!([rect([0.001, 0.001], [0.049, 0.029], 8)]),
            json!([{ "material": "m", "region": { "circle": { "center": [0.025, 0.015], "radius": 0.012 } },
                     "particles_per_cell": 3 }]),
            // Overlap: a sparse body first takes the part a dense one shares with it.
            json!([
                rect([0.001, 0.001], [0.03, 0.029], 1),
                rect([0.01, 0.001], [0.049, 0.029], 4)
            ]),
            json!([{ "material": "m", "region": { "polygon": { "points":
                     [[0.002, 0.002], [0.04, 0.004], [0.02, 0.028]] } }, "particles_per_cell": 2 }]),
        ];
        for bodies in cases {
            let s = scene(bodies.clone());
            let exact = validate::validate(&s).unwrap().particles;
            let est = estimate_particles(&s);
            assert!(
                est.at_least <= exact && exact <= est.sites,
                "{bodies}: {est:?}, exact {exact}"
            );
        }
    }

    #[test]
    fn precheck_names_max_particles() {
        let s = scene(json!([{ "material": "m",
            "region": { "rectangle": { "min": [0.001, 0.001], "max": [0.049, 0.029] } },
            "particles_per_cell": 4 }]));
        let limits = Limits {
            max_particles: 1000,
            ..Limits::default()
        };
        let e = limits.precheck(&s).unwrap_err();
        assert!(e.to_string().contains("max_particles"), "{e}");
        assert!(Limits::default().precheck(&s).is_ok());
    }
}

/// Where the store lives (`fracture serve --database`, `FRACTURE_DATABASE`): absent, the
/// embedded SQLite file `<data>/fracture.db`; else a PostgreSQL server.
#[derive(Clone, PartialEq, Eq)]
pub struct DatabaseUrl(String);

impl DatabaseUrl {
    /// Parse a `--database` value: `postgres://` or `postgresql://` URLs that sqlx's
    /// PostgreSQL driver accepts; anything else is an error naming the flag and the value
    /// (its password hidden).
    pub fn parse(s: &str) -> Result<DatabaseUrl, String> {
        use std::str::FromStr;
        let s = s.trim();
        let shown = redact_url(s);
        if !(s.starts_with("postgres://") || s.starts_with("postgresql://")) {
            return Err(format!(
                "--database `{shown}` is not a PostgreSQL URL (postgres://user[:password]@host[:port]/database); \
                 leave --database out for the embedded SQLite store in --data"
            ));
        }
        sqlx::postgres::PgConnectOptions::from_str(s)
            .map_err(|e| format!("--database `{shown}` is not a valid PostgreSQL URL: {e}"))?;
        Ok(DatabaseUrl(s.to_string()))
    }

    /// The URL, password included (to connect).
    pub fn url(&self) -> &str {
        &self.0
    }
}

/// The URL with its password hidden (`postgres://user:***@host/db`): for messages and logs.
impl std::fmt::Display for DatabaseUrl {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&redact_url(&self.0))
    }
}

impl std::fmt::Debug for DatabaseUrl {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "DatabaseUrl({self})")
    }
}

/// `scheme://user:password@host…` with the password replaced by `***`; also a
/// `password=` query parameter.
pub fn redact_url(s: &str) -> String {
    let mut out = s.to_string();
    if let Some(start) = s.find("://").map(|i| i + 3) {
        let end = s[start..]
            .find(['/', '?'])
            .map(|i| start + i)
            .unwrap_or(s.len());
        if let Some(at) = s[start..end].rfind('@').map(|i| start + i)
            && let Some(colon) = s[start..at].find(':').map(|i| start + i)
        {
            out = format!("{}:***{}", &s[..colon], &s[at..]);
        }
    }
    if let Some(q) = out.find("password=") {
        let end = out[q..].find('&').map(|i| q + i).unwrap_or(out.len());
        out = format!("{}password=***{}", &out[..q], &out[end..]);
    }
    out
}

#[cfg(test)]
mod database_tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn database_urls_are_checked_and_passwords_never_shown() {
        let ok = DatabaseUrl::parse("postgres://fracture:s3cret@db.example:5433/jobs").unwrap();
        assert_eq!(ok.url(), "postgres://fracture:s3cret@db.example:5433/jobs");
        assert_eq!(
            ok.to_string(),
            "postgres://fracture:***@db.example:5433/jobs"
        );
        assert!(!format!("{ok:?}").contains("s3cret"));
        assert!(DatabaseUrl::parse("postgresql://u@localhost/db").is_ok());
        let e = DatabaseUrl::parse("mysql://u:pw@h/db").unwrap_err();
        assert!(e.contains("--database `mysql://u:***@h/db`"), "{e}");
        assert!(e.contains("not a PostgreSQL URL"), "{e}");
        let e = DatabaseUrl::parse("postgres://u:pw@h:notaport/db").unwrap_err();
        assert!(e.contains("--database") && !e.contains("pw@"), "{e}");
        assert_eq!(
            redact_url("postgres://h/db?user=u&password=pw&sslmode=require"),
            "postgres://h/db?user=u&password=***&sslmode=require"
        );
        assert_eq!(redact_url("postgres://u@h/db"), "postgres://u@h/db");
    }
}
