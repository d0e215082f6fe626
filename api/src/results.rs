//! What a run produces (`run-output.md`): history rows, field snapshots and the summary.
//! The same types travel from a worker to the server and from the server to clients.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Column header of `energy.csv`.
/// `run-output.md`'s columns; `fracture` (the part of `dissipated` spent on new crack
/// surface) is the contract's extension at the end.
pub const ENERGY_CSV_HEADER: &str =
    "time,kinetic,strain,external_work,dissipated,total_error,fracture";
/// Column header of `crack_tips.csv`.
/// Column header of `crack_tips.csv`: `run-output.md`'s columns, then (an extension, at the
/// end) the path-independence report and the crack-opening K.
pub const CRACK_TIPS_CSV_HEADER: &str = "time,crack,tip,x,y,length,speed,j1,j2,k1,k2,growing,j1_half,j2_half,j1_double,j2_double,k1_cod,k2_cod,zone_x,zone_y,connected_x,connected_y,zone_connected_x,zone_connected_y";

/// One energy sample (J per the scene's thickness). Every number may be NaN (written as
/// JSON `null`, read back as NaN: [`crate::nan`]).
#[derive(
    Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize, JsonSchema, utoipa::ToSchema,
)]
pub struct EnergyRow {
    /// Simulated time (s).
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub time: f64,
    /// Kinetic energy Σ ½ m |v|².
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub kinetic: f64,
    /// Strain energy Σ V W.
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub strain: f64,
    /// Work done on the body by boundary conditions and loads.
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub external_work: f64,
    /// Energy removed by friction, damping and crack growth.
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub dissipated: f64,
    /// kinetic + strain + dissipated − external_work − initial total.
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub total_error: f64,
    /// The part of `dissipated` spent on new crack surface: the work of the process-zone
    /// tractions behind growing tips (and of cohesive interfaces). NaN (null) in rows written
    /// before the column.
    #[serde(
        default = "crate::nan::nan",
        deserialize_with = "crate::nan::f64_or_nan"
    )]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub fracture: f64,
}

/// A number as a CSV field: plain decimal for magnitudes in [1e-4, 1e15) and zero (`0`,
/// `0.0125`, `2500`), scientific otherwise (`1.7e-5`, `5.2e9` is written `5200000000`), always
/// the shortest text that reads back as the same f64; `NaN`, `inf`, `-inf` as such.
pub fn csv_number(x: f64) -> String {
    if !x.is_finite() {
        return if x.is_nan() {
            "NaN".into()
        } else if x > 0.0 {
            "inf".into()
        } else {
            "-inf".into()
        };
    }
    let a = x.abs();
    if a == 0.0 || (1e-4..1e15).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

impl EnergyRow {
    /// The row as a CSV line (no newline), columns as [`ENERGY_CSV_HEADER`].
    pub fn to_csv(&self) -> String {
        [
            self.time,
            self.kinetic,
            self.strain,
            self.external_work,
            self.dissipated,
            self.total_error,
            self.fracture,
        ]
        .map(csv_number)
        .join(",")
    }
}

/// One crack-tip sample. A number not defined for this sample (a K of an intersonic tip, a J
/// whose domain left the grid) is NaN, written as JSON `null` and read back as NaN.
#[derive(
    Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize, JsonSchema, utoipa::ToSchema,
)]
pub struct CrackTipRow {
    /// Simulated time (s).
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub time: f64,
    /// Index into `scene.cracks`.
    pub crack: u32,
    /// 0 for the start of the polyline, 1 for its end.
    pub tip: u32,
    /// Tip position x (m).
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub x: f64,
    /// Tip position y (m).
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub y: f64,
    /// Current crack length along its path (m).
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub length: f64,
    /// Tip speed (m/s), moving-box average over `output.speed_window`.
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub speed: f64,
    /// J along the crack (J/m²), tip frame.
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub j1: f64,
    /// J normal to the crack (J/m²), positive to the crack's left.
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub j2: f64,
    /// Mode I stress intensity factor (Pa·√m).
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub k1: f64,
    /// Mode II stress intensity factor (Pa·√m).
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub k2: f64,
    /// Whether the tip advanced in this sample's step.
    pub growing: bool,
    /// J1 of the domain integral at half the J radius (path-independence report; J/m²). NaN (null) where not defined.
    #[serde(
        default = "crate::nan::nan",
        deserialize_with = "crate::nan::f64_or_nan"
    )]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub j1_half: f64,
    /// J2 at half the J radius. NaN (null) where not defined.
    #[serde(
        default = "crate::nan::nan",
        deserialize_with = "crate::nan::f64_or_nan"
    )]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub j2_half: f64,
    /// J1 at twice the J radius. NaN (null) where not defined.
    #[serde(
        default = "crate::nan::nan",
        deserialize_with = "crate::nan::f64_or_nan"
    )]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub j1_double: f64,
    /// J2 at twice the J radius. NaN (null) where not defined.
    #[serde(
        default = "crate::nan::nan",
        deserialize_with = "crate::nan::f64_or_nan"
    )]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub j2_double: f64,
    /// K_I by the crack-opening ratio (the seed's method, for comparison; Pa·√m). NaN (null) where not defined.
    #[serde(
        default = "crate::nan::nan",
        deserialize_with = "crate::nan::f64_or_nan"
    )]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub k1_cod: f64,
    /// K_II by the crack-opening ratio. NaN (null) where not defined.
    #[serde(
        default = "crate::nan::nan",
        deserialize_with = "crate::nan::f64_or_nan"
    )]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub k2_cod: f64,
    /// A cohesive interface's process-zone front x (m): its farthest bond point past the peak
    /// traction (`algorithm.md` §8). NaN (null) for crack tips and before any point softens.
    #[serde(
        default = "crate::nan::nan",
        deserialize_with = "crate::nan::f64_or_nan"
    )]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub zone_x: f64,
    /// The process-zone front's y (m), as `zone_x`.
    #[serde(
        default = "crate::nan::nan",
        deserialize_with = "crate::nan::f64_or_nan"
    )]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub zone_y: f64,
    /// A cohesive interface's failure front connected to its start (m): the last point of the
    /// unbroken run of failed bond points from the interface's first point (`x`, `y` is the
    /// farthest failed point, connected or not: a daughter crack ahead puts them apart).
    /// NaN (null) for crack tips and before the first point has failed.
    #[serde(
        default = "crate::nan::nan",
        deserialize_with = "crate::nan::f64_or_nan"
    )]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub connected_x: f64,
    /// The connected failure front's y (m), as `connected_x`.
    #[serde(
        default = "crate::nan::nan",
        deserialize_with = "crate::nan::f64_or_nan"
    )]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub connected_y: f64,
    /// The end of the softened region connected to the interface's start (m): the last point
    /// of the unbroken run of softening or failed points from its first point (`zone_x` is the
    /// farthest, connected or not). NaN (null) for crack tips and before any point softens.
    #[serde(
        default = "crate::nan::nan",
        deserialize_with = "crate::nan::f64_or_nan"
    )]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub zone_connected_x: f64,
    /// The connected softened region's end y (m), as `zone_connected_x`.
    #[serde(
        default = "crate::nan::nan",
        deserialize_with = "crate::nan::f64_or_nan"
    )]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub zone_connected_y: f64,
}

impl CrackTipRow {
    /// The row as a CSV line (no newline), columns as [`CRACK_TIPS_CSV_HEADER`].
    pub fn to_csv(&self) -> String {
        let n = |xs: &[f64]| {
            xs.iter()
                .map(|&x| csv_number(x))
                .collect::<Vec<_>>()
                .join(",")
        };
        format!(
            "{},{},{},{},{},{}",
            csv_number(self.time),
            self.crack,
            self.tip,
            n(&[
                self.x,
                self.y,
                self.length,
                self.speed,
                self.j1,
                self.j2,
                self.k1,
                self.k2
            ]),
            u8::from(self.growing),
            n(&[
                self.j1_half,
                self.j2_half,
                self.j1_double,
                self.j2_double,
                self.k1_cod,
                self.k2_cod,
                self.zone_x,
                self.zone_y,
                self.connected_x,
                self.connected_y,
                self.zone_connected_x,
                self.zone_connected_y
            ])
        )
    }
}

/// Final state of a run.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema, utoipa::ToSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum RunStatus {
    /// Reached the end time.
    Completed,
    /// Stopped by a numerical failure or an error; see the message.
    Failed,
    /// Stopped on request.
    Cancelled,
}

/// The kind of a failed run.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema, utoipa::ToSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum FailureKind {
    /// The scene did not validate (deterministic).
    InvalidScene,
    /// The solver stopped with a numerical diagnosis (deterministic: the solver is).
    Numerical,
    /// The solver panicked (a bug; deterministic for the same scene and build).
    Panic,
    /// Results could not be recorded (disk, network): worth retrying.
    Output,
}

/// `summary.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema, utoipa::ToSchema)]
pub struct Summary {
    /// How the run ended.
    pub status: RunStatus,
    /// Why, when not completed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub message: Option<String>,
    /// What kind of failure, when `failed` (an extension of `run-output.md`: lets a queue
    /// tell a deterministic failure, which a retry repeats, from a lost worker).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub failure: Option<FailureKind>,
    /// Time steps taken.
    pub steps: u64,
    /// Δt (s).
    pub time_step: f64,
    /// Simulated time reached (s).
    pub sim_time: f64,
    /// Number of particles.
    pub particles: u64,
    /// Number of grid nodes in the box.
    pub grid_nodes: u64,
    /// Mean number of active (particle-touched) nodes per step.
    pub active_nodes_mean: f64,
    /// Wall-clock seconds of the time loop.
    pub wall_seconds: f64,
    /// particles × steps / wall_seconds.
    pub particle_steps_per_second: f64,
    /// Threads the solver used.
    pub threads: u32,
    /// SHA-256 of the canonical scene JSON.
    pub scene_hash: String,
    /// Version of the solver.
    pub solver_version: String,
    /// The fracture energy of the run's growing tips (an extension of `run-output.md`): what
    /// the new crack surface should take, what the growth mechanism dissipated, and the rest,
    /// which stayed in the body (the seed's `wave` rule releases the new faces at once and
    /// dissipates none of it). Absent for scenes without growth.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fracture: Option<FractureEnergy>,
    /// Where and when the run was computed (an extension of `run-output.md`; absent in
    /// summaries written before it). With `solver_version`, `threads` and `wall_seconds`
    /// it says which build ran the scene and on what. Boxed: it keeps `Summary` (in every
    /// status event) small.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub provenance: Option<Box<Provenance>>,
    /// (extension) What each crack tip did: initiation, growth, final and peak J and K,
    /// speeds (`docs/run-output-extensions.md`). Empty (omitted) without cracks and in
    /// summaries written before it.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub tips: Vec<crate::tips::TipSummary>,
    /// (extension) The scene's `references` compared with the run. Omitted when the scene
    /// has none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub references: Vec<crate::tips::ReferenceCheck>,
    /// Spatial dimension of the run: `3` for a 3D scene (`three-d.md`); absent for 2D runs,
    /// whose summaries are as before.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dimension: Option<u32>,
}

/// Provenance of a run (`summary.provenance`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema, utoipa::ToSchema)]
pub struct Provenance {
    /// Git commit the solver was built from (`null` when the build did not know it).
    pub solver_commit: Option<String>,
    /// Host name of the machine that ran it (`null` when it could not be read).
    pub host: Option<String>,
    /// When the run started (RFC 3339 UTC, before the simulation was built).
    pub started_at: String,
    /// When it ended (RFC 3339 UTC, as the summary was written).
    pub finished_at: String,
    /// The batch scheduler's job that ran it, when it ran under one: `slurm job 1234
    /// (array 1230 task 4)`, `kubernetes job fracture-worker index 2 (pod …)`. Absent
    /// otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scheduler: Option<String>,
}

/// Fracture energy of the growing tips of a run (J per the scene's thickness × thickness, as
/// `energy.csv`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema, utoipa::ToSchema)]
pub struct FractureEnergy {
    /// Σ Γ(v)·Δa·thickness over every advance of every tip: the energy the new surface takes.
    pub required: f64,
    /// The work of the process-zone tractions behind the tips (energy.csv's `fracture`, tips
    /// only).
    pub dissipated: f64,
    /// required − dissipated: fracture energy the body kept (as waves and strain energy),
    /// including that of faces whose zones are still opening at the end.
    pub not_dissipated: f64,
    /// New crack area (m², length × thickness).
    pub new_area: f64,
    /// The part of `required` above Γ(v) (J): what tips running within 1 % of the equation
    /// of motion's speed limit (0.999 c_R) took beyond the toughness, up to the energy that
    /// reached them (the wall that closes Γ(v) there). 0 when no tip ran there; absent from
    /// summaries written before 2026-12-03.
    #[serde(default)]
    pub at_speed_limit: f64,
}

/// Progress of a run.
#[derive(
    Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize, JsonSchema, utoipa::ToSchema,
)]
pub struct Progress {
    /// Steps taken.
    pub step: u64,
    /// Simulated time (s).
    pub sim_time: f64,
    /// End time (s).
    pub end_time: f64,
    /// sim_time / end_time, in [0, 1].
    pub fraction: f64,
}

/// One field component of a snapshot, sampled at the grid nodes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct FieldComponent {
    /// Component name, e.g. `sxx`, `vx`, `speed`, `fringe`.
    pub name: String,
    /// Values at the nodes, row-major from the lower-left node: index = iy·nx + ix.
    /// NaN where no material touches the node.
    pub values: Vec<f32>,
}

/// A field snapshot: node-sampled fields plus the crack geometry at that time.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Snapshot {
    /// Index of the snapshot in its run (0, 1, …).
    pub index: u32,
    /// Simulated time (s).
    pub time: f64,
    /// Nodes in x.
    pub nx: u32,
    /// Nodes in y.
    pub ny: u32,
    /// Position of node (0, 0).
    pub origin: [f64; 2],
    /// Node spacing (m).
    pub cell_size: f64,
    /// Field kinds recorded (names as in the scene's `output.fields`).
    pub fields: Vec<String>,
    /// The components of those fields.
    pub components: Vec<FieldComponent>,
    /// Each crack's line as a polyline (m).
    pub cracks: Vec<Vec<[f64; 2]>>,
    /// (extension) The particles at that time, with the same components per particle, when
    /// the scene asks for them (`output.particles`). Absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub particles: Option<ParticleSnapshot>,
    /// (extension) For a 3D run: the grid plane this snapshot samples (`output.slices`);
    /// its `origin`, `nx`, `ny` and the crack lines are in the plane's two axes. Absent for
    /// 2D runs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slice: Option<SnapshotSlice>,
}

/// (extension) A 3D run's fields on its whole grid at one time (the `--vtk` volumes of
/// `three-d.md`): mass-weighted averages of particle values at every node, as a
/// [`Snapshot`] samples a plane.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Volume {
    /// Index of the snapshot time in its run (0, 1, …).
    pub index: u32,
    /// Simulated time (s).
    pub time: f64,
    /// Nodes per direction.
    pub n: [u32; 3],
    /// Position of node (0, 0, 0) (m).
    pub origin: [f64; 3],
    /// Node spacing (m).
    pub cell_size: f64,
    /// Field kinds recorded.
    pub fields: Vec<String>,
    /// The components, values at the nodes with x fastest: index = (iz·ny + iy)·nx + ix
    /// (VTK's order); NaN where no material touches the node.
    pub components: Vec<FieldComponent>,
    /// The particles, when the scene records them (`output.particles`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub particles: Option<ParticleCloud>,
}

/// (extension) The particles of a [`Volume`]: positions and the same components per particle.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, JsonSchema)]
pub struct ParticleCloud {
    /// Positions x (m).
    pub x: Vec<f32>,
    /// Positions y (m).
    pub y: Vec<f32>,
    /// Positions z (m).
    pub z: Vec<f32>,
    /// The components, one value per particle.
    pub components: Vec<FieldComponent>,
}

/// (extension) The plane of a 3D run that a [`Snapshot`] samples.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct SnapshotSlice {
    /// The axis normal to the plane: `x`, `y` or `z`.
    pub normal: String,
    /// Where the scene asked for the plane along that axis (m).
    pub at: f64,
    /// The node plane sampled (m): the grid plane nearest to `at`.
    pub node_at: f64,
    /// The plane's two axes, as the snapshot's x and y (`["x", "y"]` for a plane normal to z,
    /// `["x", "z"]` normal to y, `["y", "z"]` normal to x).
    pub axes: [String; 2],
}

/// (extension) The particles of a snapshot: positions and the snapshot's components at
/// each particle (no averaging). Particles are in the solver's order at that time (it
/// re-sorts them), so index k need not be the same particle in two snapshots.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, JsonSchema)]
pub struct ParticleSnapshot {
    /// Positions x (m).
    pub x: Vec<f32>,
    /// Positions y (m).
    pub y: Vec<f32>,
    /// The components, one value per particle (names as the grid's).
    pub components: Vec<FieldComponent>,
}

impl Snapshot {
    /// The component with this name.
    pub fn component(&self, name: &str) -> Option<&FieldComponent> {
        self.components.iter().find(|c| c.name == name)
    }
}

/// The components each field kind produces, in order.
pub fn field_components(kind: crate::scene::FieldKind) -> &'static [&'static str] {
    use crate::scene::FieldKind::*;
    match kind {
        Stress => &["sxx", "syy", "sxy"],
        Strain => &["exx", "eyy", "exy"],
        Velocity => &["vx", "vy", "speed"],
        Displacement => &["ux", "uy"],
        Fringe => &["fringe"],
        Material => &["material"],
    }
}
