//! The run loop.
//!
//! (Over 700 lines because its unit tests, which drive the loop with a scripted model, live
//! here with it: the loop itself is about 430 lines.)

use std::any::Any;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::time::Instant;

use fracture_api::results::{
    CrackTipRow, EnergyRow, FailureKind, FractureEnergy, Progress, RunStatus, Snapshot, Summary,
    Volume,
};
use fracture_api::scene::{FieldKind, Output, Reference};
use fracture_api::scene3::Scene3;
use fracture_api::tips::{TipSummaryBuilder, check_references};
use fracture_api::{Scene, ValidScene};
use fracture_solver::{Simulation, SolverConfig, StepError, StepStats};

use crate::checkpoint::{CheckpointAt, CheckpointPolicy, LoopCursor};
use crate::{Control, RunOptions, RunSink, SinkError};

/// What the run loop needs from a simulation. Implemented by
/// [`Simulation`]; tests drive the loop with scripted models.
pub trait Model {
    /// Advance one step; the error is the solver's diagnosis.
    fn step(&mut self) -> Result<StepStats, String>;
    fn time(&self) -> f64;
    fn time_step(&self) -> f64;
    fn end_time(&self) -> f64;
    fn steps_taken(&self) -> u64;
    fn is_finished(&self) -> bool;
    fn particle_count(&self) -> usize;
    fn grid_node_count(&self) -> usize;
    fn threads(&self) -> usize;
    fn energy(&self) -> EnergyRow;
    fn crack_tips(&mut self) -> Vec<CrackTipRow>;
    fn snapshot(&self, index: u32, fields: &[FieldKind]) -> Snapshot;
    /// The snapshots of one snapshot time, indices from `index` (a 3D run writes one per
    /// slice); by default the one [`Model::snapshot`].
    fn snapshots(&self, index: u32, fields: &[FieldKind]) -> Vec<Snapshot> {
        vec![self.snapshot(index, fields)]
    }
    /// The fields on the whole grid at this snapshot time (3D runs; None for 2D).
    fn volume(&self, _index: u32, _fields: &[FieldKind]) -> Option<Volume> {
        None
    }
    /// The fracture-energy report of growing tips (None without growth).
    fn fracture_energy(&self) -> Option<FractureEnergy> {
        None
    }
    /// The solver's checkpoint (None: this model keeps none).
    fn checkpoint(&self) -> Option<Vec<u8>> {
        None
    }
}

impl Model for Simulation {
    fn step(&mut self) -> Result<StepStats, String> {
        Simulation::step(self).map_err(|e: StepError| e.to_string())
    }
    fn time(&self) -> f64 {
        Simulation::time(self)
    }
    fn time_step(&self) -> f64 {
        Simulation::time_step(self)
    }
    fn end_time(&self) -> f64 {
        Simulation::end_time(self)
    }
    fn steps_taken(&self) -> u64 {
        Simulation::steps_taken(self)
    }
    fn is_finished(&self) -> bool {
        Simulation::is_finished(self)
    }
    fn particle_count(&self) -> usize {
        Simulation::particle_count(self)
    }
    fn grid_node_count(&self) -> usize {
        Simulation::grid_node_count(self)
    }
    fn threads(&self) -> usize {
        Simulation::threads(self)
    }
    fn energy(&self) -> EnergyRow {
        Simulation::energy(self)
    }
    fn crack_tips(&mut self) -> Vec<CrackTipRow> {
        Simulation::crack_tips(self)
    }
    fn snapshot(&self, index: u32, fields: &[FieldKind]) -> Snapshot {
        Simulation::snapshot(self, index, fields)
    }
    fn fracture_energy(&self) -> Option<FractureEnergy> {
        Simulation::fracture_energy(self)
    }
    fn checkpoint(&self) -> Option<Vec<u8>> {
        Some(Simulation::checkpoint(self))
    }
}

/// Run a scene to its end time, sending results to `sink`, and return the summary (also
/// given to [`RunSink::finish`]).
///
/// * Energies and crack tips are sampled at t = 0, then every `output.history_interval` of
///   simulated time (every step when absent), and once more at the end if the last step
///   was not sampled. Rows are buffered and flushed just before each progress report.
/// * Snapshots are taken at t = 0 and then every `output.snapshot_interval` (none when 0),
///   with `output.fields`, and sent at once.
/// * `progress` is called about every [`RunOptions::flush_every`] of wall time, and once at
///   the end; [`Control::Cancel`] ends the run `cancelled`.
/// * A step error ends the run `failed` with its diagnosis; so does a sink error (the
///   message says so) and a panic inside the solver (the message carries the panic's).
///   Whatever was sampled before is flushed, plus one final sample where the solver can
///   still give one.
pub fn run_scene(scene: &ValidScene, opts: &RunOptions, sink: &mut dyn RunSink) -> Summary {
    let config = SolverConfig {
        threads: opts.threads,
    };
    let built = catch_unwind(AssertUnwindSafe(|| Simulation::new(scene, config)));
    match built {
        Ok(Ok(mut sim)) => run_model(
            &mut sim,
            scene.scene(),
            opts,
            CheckpointPolicy::none(),
            None,
            sink,
        ),
        Ok(Err(e)) => finish_early(
            scene.scene(),
            sink,
            FailureKind::Output,
            format!("could not build the simulation: {e}"),
        ),
        Err(p) => finish_early(
            scene.scene(),
            sink,
            FailureKind::Panic,
            format!(
                "solver panicked while building the simulation: {}",
                panic_message(&*p)
            ),
        ),
    }
}

/// Run a job: like [`run_scene`], writing checkpoints by `policy` (and when a hand back is
/// requested, [`crate::handback`], after which the run stops and is handed back), and
/// resuming from `checkpoint` when one is given. A checkpoint that cannot be used (corrupt,
/// of another scene or build) is refused before anything is sent: `Err` with the reason, and
/// the caller starts over from step 0.
pub fn run_job(
    scene: &ValidScene,
    opts: &RunOptions,
    policy: CheckpointPolicy,
    checkpoint: Option<&[u8]>,
    sink: &mut dyn RunSink,
) -> Result<Summary, String> {
    let Some(bytes) = checkpoint else {
        let config = SolverConfig {
            threads: opts.threads,
        };
        let built = catch_unwind(AssertUnwindSafe(|| Simulation::new(scene, config)));
        return Ok(match built {
            Ok(Ok(mut sim)) => run_model(&mut sim, scene.scene(), opts, policy, None, sink),
            _ => run_scene(scene, opts, sink),
        });
    };
    let d = crate::checkpoint::decode(bytes, &scene.scene().hash())?;
    let config = SolverConfig {
        threads: opts.threads,
    };
    let mut sim = catch_unwind(AssertUnwindSafe(|| {
        Simulation::restore(scene, config, &d.solver)
    }))
    .map_err(|p| format!("solver panicked restoring it: {}", panic_message(&*p)))?
    .map_err(|e| e.to_string())?;
    if sim.steps_taken() != d.at.step || sim.time().to_bits() != d.at.time.to_bits() {
        return Err("the solver state is not at the checkpoint's step".into());
    }
    Ok(run_model(
        &mut sim,
        scene.scene(),
        opts,
        policy,
        Some(d.cursor),
        sink,
    ))
}

/// What the run loop needs from a scene of either dimension.
pub trait RunPlan {
    /// The scene's hash.
    fn hash(&self) -> String;
    /// The sampling settings (a 3D scene's in the 2D form: cadences, fields, speed window).
    fn output(&self) -> Output;
    /// End time (s).
    fn end_time(&self) -> f64;
    /// Reference values the summary checks.
    fn references(&self) -> &[Reference];
    /// `Some(3)` for a 3D scene.
    fn dimension(&self) -> Option<u32>;
}

impl RunPlan for Scene {
    fn hash(&self) -> String {
        Scene::hash(self)
    }
    fn output(&self) -> Output {
        self.output.clone()
    }
    fn end_time(&self) -> f64 {
        self.time.end
    }
    fn references(&self) -> &[Reference] {
        &self.references
    }
    fn dimension(&self) -> Option<u32> {
        None
    }
}

impl RunPlan for Scene3 {
    fn hash(&self) -> String {
        Scene3::hash(self)
    }
    fn output(&self) -> Output {
        let o = &self.output;
        Output {
            history_interval: o.history_interval,
            snapshot_interval: o.snapshot_interval,
            fields: o.fields.clone(),
            fringe_constant: None,
            speed_window: o.speed_window,
            particles: o.particles,
        }
    }
    fn end_time(&self) -> f64 {
        self.time.end
    }
    fn references(&self) -> &[Reference] {
        &[]
    }
    fn dimension(&self) -> Option<u32> {
        Some(3)
    }
}

fn base_summary<P: RunPlan + ?Sized>(scene: &P) -> Summary {
    Summary {
        status: RunStatus::Failed,
        message: None,
        failure: None,
        steps: 0,
        time_step: 0.0,
        sim_time: 0.0,
        particles: 0,
        grid_nodes: 0,
        active_nodes_mean: 0.0,
        wall_seconds: 0.0,
        particle_steps_per_second: 0.0,
        threads: 0,
        scene_hash: scene.hash(),
        solver_version: fracture_api::SOLVER_VERSION.to_string(),
        fracture: None,
        // Started now; `finished_at` is stamped again as the summary is handed over.
        provenance: Some(crate::provenance::provenance(
            fracture_api::clock::now_text(),
        )),
        tips: Vec::new(),
        references: Vec::new(),
        dimension: scene.dimension(),
    }
}

/// Stamp `provenance.finished_at` (the summary is about to be handed to the sink).
fn stamp_finish(summary: &mut Summary) {
    if let Some(p) = summary.provenance.as_mut() {
        p.finished_at = fracture_api::clock::now_text();
    }
}

/// A run that could not start: a failed summary (kind `output`) with `message`, handed to
/// the sink.
pub(crate) fn finish_early_failed<P: RunPlan + ?Sized>(
    scene: &P,
    sink: &mut dyn RunSink,
    message: String,
) -> Summary {
    finish_early(scene, sink, FailureKind::Output, message)
}

fn finish_early<P: RunPlan + ?Sized>(
    scene: &P,
    sink: &mut dyn RunSink,
    failure: FailureKind,
    message: String,
) -> Summary {
    let mut summary = base_summary(scene);
    summary.message = Some(message);
    summary.failure = Some(failure);
    stamp_finish(&mut summary);
    // Nothing else can be done with a sink error here: the summary already says failed.
    let _ = sink.finish(&summary);
    summary
}

/// The text of a panic payload.
pub(crate) fn panic_message(p: &(dyn Any + Send)) -> String {
    if let Some(s) = p.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = p.downcast_ref::<String>() {
        s.clone()
    } else {
        "(panic with a non-text payload)".to_string()
    }
}

/// Why the loop stopped early.
enum Stop {
    Cancelled,
    HandedBack,
    Step(String),
    Panic(String),
    Sink(SinkError),
}

/// Sampling cadence: sample k is due at k·interval (k = 0, 1, …); `None` interval = every
/// call.
struct Cadence {
    interval: Option<f64>,
    next: u64,
}

impl Cadence {
    fn new(interval: Option<f64>) -> Self {
        Cadence { interval, next: 0 }
    }
    /// Whether a sample is due at time `t` (with a tolerance of a small fraction of `dt`
    /// for rounding in the accumulated time); advances past `t` when it is.
    fn due(&mut self, t: f64, dt: f64) -> bool {
        match self.interval {
            None => true,
            Some(iv) => {
                let tol = 1e-6 * dt.abs();
                if (self.next as f64) * iv <= t + tol {
                    // Skip every sample time already passed (interval shorter than dt).
                    let k = ((t + tol) / iv).floor();
                    self.next = if k.is_finite() && k >= 0.0 {
                        (k as u64).saturating_add(1).max(self.next + 1)
                    } else {
                        self.next + 1
                    };
                    true
                } else {
                    false
                }
            }
        }
    }
}

struct Loop<'a, M: Model> {
    model: &'a mut M,
    sink: &'a mut dyn RunSink,
    fields: Vec<FieldKind>,
    energy: Vec<EnergyRow>,
    tips: Vec<CrackTipRow>,
    /// `summary.tips` from the rows sampled by this loop (a resumed loop sees only the rows
    /// since the checkpoint: the service rebuilds it from every stored row).
    summarizer: TipSummaryBuilder,
    snapshots: u32,
    /// Step count at the last history sample (`None`: not sampled yet).
    sampled_at: Option<u64>,
}

impl<M: Model> Loop<'_, M> {
    /// Sample energy and crack tips into the buffers.
    fn sample(&mut self) -> Result<(), Stop> {
        let model = &mut *self.model;
        let (e, tips) = catch_unwind(AssertUnwindSafe(|| (model.energy(), model.crack_tips())))
            .map_err(|p| {
                Stop::Panic(format!(
                    "solver panicked while sampling: {}",
                    panic_message(&*p)
                ))
            })?;
        self.energy.push(e);
        self.summarizer.extend(&tips);
        self.tips.extend(tips);
        self.sampled_at = Some(self.model.steps_taken());
        Ok(())
    }

    fn snapshot(&mut self) -> Result<(), Stop> {
        // Keep the file in time order: rows sampled before the snapshot go first.
        self.flush().map_err(Stop::Sink)?;
        let model = &*self.model;
        let index = self.snapshots;
        let fields = &self.fields;
        let snaps =
            catch_unwind(AssertUnwindSafe(|| model.snapshots(index, fields))).map_err(|p| {
                Stop::Panic(format!(
                    "solver panicked while taking snapshot {index}: {}",
                    panic_message(&*p)
                ))
            })?;
        for snap in &snaps {
            self.snapshots += 1;
            self.sink.snapshot(snap).map_err(Stop::Sink)?;
        }
        if self.sink.wants_volumes() {
            let volume =
                catch_unwind(AssertUnwindSafe(|| model.volume(index, fields))).map_err(|p| {
                    Stop::Panic(format!(
                        "solver panicked while taking volume {index}: {}",
                        panic_message(&*p)
                    ))
                })?;
            if let Some(v) = volume {
                self.sink.volume(&v).map_err(Stop::Sink)?;
            }
        }
        Ok(())
    }

    fn flush(&mut self) -> Result<(), SinkError> {
        if !self.energy.is_empty() {
            self.sink.energy(&self.energy)?;
            self.energy.clear();
        }
        if !self.tips.is_empty() {
            self.sink.crack_tips(&self.tips)?;
            self.tips.clear();
        }
        Ok(())
    }

    /// Write a checkpoint now: flush the rows sampled so far (the checkpoint covers them),
    /// take the solver's checkpoint, hand it to the sink. A checkpoint that cannot be taken
    /// or stored is logged and the run goes on; only a sink error on the flush stops it.
    fn checkpoint_now(&mut self, scene_hash: &str, cursor: LoopCursor) -> Result<(), Stop> {
        self.flush().map_err(Stop::Sink)?;
        let model = &*self.model;
        let Ok(Some(solver)) = catch_unwind(AssertUnwindSafe(|| model.checkpoint())) else {
            tracing::warn!("the solver gave no checkpoint");
            return Ok(());
        };
        let at = CheckpointAt {
            step: model.steps_taken(),
            time: model.time(),
            snapshots: self.snapshots,
        };
        let t0 = Instant::now();
        match crate::checkpoint::encode(scene_hash, at.step, at.time, cursor, solver) {
            Ok(bytes) => {
                let encoded = t0.elapsed();
                match self.sink.checkpoint(&bytes, &at) {
                    Ok(()) => tracing::info!(
                        step = at.step,
                        bytes = bytes.len(),
                        encode_ms = encoded.as_secs_f64() * 1e3,
                        total_ms = t0.elapsed().as_secs_f64() * 1e3,
                        "checkpoint written"
                    ),
                    Err(e) => tracing::warn!(step = at.step, error = %e, "checkpoint not stored"),
                }
            }
            Err(e) => tracing::warn!(error = %e, "checkpoint not encoded"),
        }
        Ok(())
    }

    fn progress(&self) -> Progress {
        let t = self.model.time();
        let end = self.model.end_time();
        let fraction = if end > 0.0 && t.is_finite() {
            (t / end).clamp(0.0, 1.0)
        } else if self.model.is_finished() {
            1.0
        } else {
            0.0
        };
        Progress {
            step: self.model.steps_taken(),
            sim_time: t,
            end_time: end,
            fraction,
        }
    }
}

/// The loop proper, for any [`Model`].
pub(crate) fn run_model<M: Model, P: RunPlan + ?Sized>(
    model: &mut M,
    scene: &P,
    opts: &RunOptions,
    policy: CheckpointPolicy,
    resume: Option<LoopCursor>,
    sink: &mut dyn RunSink,
) -> Summary {
    let mut summary = base_summary(scene);
    summary.time_step = model.time_step();
    summary.particles = model.particle_count() as u64;
    summary.grid_nodes = model.grid_node_count() as u64;
    summary.threads = u32::try_from(model.threads()).unwrap_or(u32::MAX);

    let out = &scene.output();
    let mut history = Cadence::new(out.history_interval);
    let snapshot_interval = (out.snapshot_interval > 0.0).then_some(out.snapshot_interval);
    let mut snapshots = Cadence::new(snapshot_interval);

    let mut lp = Loop {
        model,
        sink,
        fields: out.fields.clone(),
        energy: Vec::new(),
        tips: Vec::new(),
        summarizer: TipSummaryBuilder::with(out.speed_window, scene.end_time()),
        snapshots: 0,
        sampled_at: None,
    };

    let start = Instant::now();
    let mut last_report = start;
    let mut active_sum = 0.0_f64;
    let mut active_steps = 0u64;
    let mut wall_before = 0.0_f64;
    if let Some(c) = resume {
        history.next = c.history_next;
        snapshots.next = c.snapshot_next;
        lp.snapshots = c.snapshots;
        lp.sampled_at = c.sampled_at;
        active_sum = c.active_sum;
        active_steps = c.active_steps;
        wall_before = c.wall_seconds;
    }
    let hash = scene.hash();
    let mut last_checkpoint = (lp.model.steps_taken(), start);

    let result: Result<(), Stop> = (|| {
        let dt = lp.model.time_step();
        // t = 0 (a resumed run sampled it before).
        if resume.is_none() {
            lp.sample()?;
            history.due(lp.model.time(), dt);
            if snapshot_interval.is_some() && snapshots.due(lp.model.time(), dt) {
                lp.snapshot()?;
            }
        }
        while !lp.model.is_finished() {
            let model = &mut *lp.model;
            let stats = match catch_unwind(AssertUnwindSafe(|| model.step())) {
                Ok(Ok(s)) => s,
                Ok(Err(e)) => return Err(Stop::Step(e)),
                Err(p) => {
                    return Err(Stop::Panic(format!(
                        "solver panicked in step {}: {}",
                        lp.model.steps_taken() + 1,
                        panic_message(&*p)
                    )));
                }
            };
            active_sum += stats.active_nodes as f64;
            active_steps += 1;
            let t = lp.model.time();
            let sampled = history.due(t, dt);
            if sampled {
                lp.sample()?;
            }
            if snapshot_interval.is_some() && snapshots.due(t, dt) {
                lp.snapshot()?;
            }
            // The loop's cursor, for a checkpoint taken now.
            let cursor = |history: &Cadence, snapshots: &Cadence, lp: &Loop<'_, M>| LoopCursor {
                history_next: history.next,
                snapshot_next: snapshots.next,
                snapshots: lp.snapshots,
                sampled_at: lp.sampled_at,
                active_sum,
                active_steps,
                wall_seconds: wall_before + start.elapsed().as_secs_f64(),
            };
            // Checkpoints by the policy, at a history sample.
            let steps = lp.model.steps_taken();
            if sampled && policy.due(steps - last_checkpoint.0, last_checkpoint.1.elapsed()) {
                let c = cursor(&history, &snapshots, &lp);
                lp.checkpoint_now(&hash, c)?;
                last_checkpoint = (steps, Instant::now());
            }
            if last_report.elapsed() >= opts.flush_every {
                last_report = Instant::now();
                lp.flush().map_err(Stop::Sink)?;
                let p = lp.progress();
                match lp.sink.progress(&p).map_err(Stop::Sink)? {
                    Control::Continue => {}
                    Control::Cancel => return Err(Stop::Cancelled),
                    // The job goes back to the queue unfinished. Checkpoint: a checkpoint of
                    // the state at this step is written here, before the loop returns (the
                    // caller releases the job after `run_scene` returns).
                    Control::HandBack => {
                        if policy.enabled() {
                            let c = cursor(&history, &snapshots, &lp);
                            lp.checkpoint_now(&hash, c)?;
                        }
                        return Err(Stop::HandedBack);
                    }
                }
            }
        }
        Ok(())
    })();
    let wall = wall_before + start.elapsed().as_secs_f64();
    let handed_back = matches!(result, Err(Stop::HandedBack));

    // One final sample where the last step was not sampled (also after a failure: the
    // state that failed is the diagnosis). Not after a panic or a sink error.
    let mut final_error = None;
    if matches!(result, Ok(()) | Err(Stop::Cancelled) | Err(Stop::Step(_)))
        && lp.sampled_at != Some(lp.model.steps_taken())
        && let Err(e) = lp.sample()
    {
        final_error = Some(e);
    }

    // Flush what is buffered, unless the sink already failed.
    let mut sink_error = match &result {
        Err(Stop::Sink(_)) => None,
        _ => lp.flush().err(),
    };
    let sink_broken = matches!(result, Err(Stop::Sink(_))) || sink_error.is_some();

    summary.steps = lp.model.steps_taken();
    summary.sim_time = lp.model.time();
    summary.fracture = lp.model.fracture_energy();
    summary.tips = lp.summarizer.finish();
    summary.references = check_references(scene.references(), &summary.tips);
    summary.wall_seconds = wall;
    summary.particle_steps_per_second = if wall > 0.0 {
        summary.particles as f64 * active_steps as f64 / wall
    } else {
        0.0
    };
    summary.active_nodes_mean = if active_steps > 0 {
        active_sum / active_steps as f64
    } else {
        0.0
    };
    let (status, message) = match result {
        Ok(()) => (RunStatus::Completed, None),
        Err(Stop::Cancelled) => (
            RunStatus::Cancelled,
            Some("cancelled on request".to_string()),
        ),
        Err(Stop::HandedBack) => (
            RunStatus::Cancelled,
            Some(format!("handed back at step {}", summary.steps)),
        ),
        Err(Stop::Step(e)) => {
            summary.failure = Some(FailureKind::Numerical);
            (RunStatus::Failed, Some(e.to_string()))
        }
        Err(Stop::Panic(m)) => {
            summary.failure = Some(FailureKind::Panic);
            (RunStatus::Failed, Some(m))
        }
        Err(Stop::Sink(e)) => {
            summary.failure = Some(FailureKind::Output);
            (
                RunStatus::Failed,
                Some(format!("could not record results: {e}")),
            )
        }
    };
    summary.status = status;
    summary.message = message;
    if let Some(Stop::Panic(m)) = final_error
        && summary.status == RunStatus::Completed
    {
        summary.status = RunStatus::Failed;
        summary.message = Some(m);
    }
    if handed_back {
        // Not over: no last progress report and no finish (`Control::HandBack`).
        stamp_finish(&mut summary);
        return summary;
    }
    if !sink_broken {
        // The run is over: a late Cancel changes nothing.
        let p = lp.progress();
        sink_error = lp.sink.progress(&p).err();
    }
    if let Some(e) = sink_error
        && summary.status != RunStatus::Failed
    {
        summary.status = RunStatus::Failed;
        summary.message = Some(format!("could not record results: {e}"));
    }
    stamp_finish(&mut summary);
    if let Err(e) = lp.sink.finish(&summary)
        && summary.status == RunStatus::Completed
    {
        summary.status = RunStatus::Failed;
        summary.message = Some(format!("could not record results: {e}"));
    }
    summary
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use std::time::Duration;

    use fracture_api::results::{FieldComponent, Summary};

    use super::*;

    /// A scripted model: `n` steps of `dt`, one crack tip, optional failure or panic.
    struct Fake {
        n: u64,
        dt: f64,
        taken: u64,
        fail_at: Option<u64>,
        panic_at: Option<u64>,
    }

    impl Fake {
        fn new(n: u64, dt: f64) -> Self {
            Fake {
                n,
                dt,
                taken: 0,
                fail_at: None,
                panic_at: None,
            }
        }
    }

    impl Model for Fake {
        fn step(&mut self) -> Result<StepStats, String> {
            let next = self.taken + 1;
            if self.panic_at == Some(next) {
                panic!("index out of bounds in step {next}");
            }
            self.taken = next;
            if self.fail_at == Some(next) {
                return Err(StepError::NonFinite {
                    step: next,
                    particle: 7,
                    quantity: "velocity",
                    x: 0.0,
                    y: 0.0,
                }
                .to_string());
            }
            Ok(StepStats {
                grew: false,
                active_nodes: 10 + (next % 2) as usize,
            })
        }
        fn time(&self) -> f64 {
            self.taken as f64 * self.dt
        }
        fn time_step(&self) -> f64 {
            self.dt
        }
        fn end_time(&self) -> f64 {
            self.n as f64 * self.dt
        }
        fn steps_taken(&self) -> u64 {
            self.taken
        }
        fn is_finished(&self) -> bool {
            self.taken >= self.n
        }
        fn checkpoint(&self) -> Option<Vec<u8>> {
            Some(self.taken.to_le_bytes().to_vec())
        }
        fn particle_count(&self) -> usize {
            100
        }
        fn grid_node_count(&self) -> usize {
            36
        }
        fn threads(&self) -> usize {
            3
        }
        fn energy(&self) -> EnergyRow {
            EnergyRow {
                time: self.time(),
                kinetic: self.taken as f64,
                ..Default::default()
            }
        }
        fn crack_tips(&mut self) -> Vec<CrackTipRow> {
            vec![CrackTipRow {
                time: self.time(),
                ..Default::default()
            }]
        }
        fn snapshot(&self, index: u32, fields: &[FieldKind]) -> Snapshot {
            Snapshot {
                index,
                time: self.time(),
                nx: 6,
                ny: 6,
                origin: [0.0; 2],
                cell_size: 1.0,
                fields: fields.iter().map(|f| f.name().to_string()).collect(),
                components: vec![FieldComponent {
                    name: "sxx".into(),
                    values: vec![0.0; 36],
                }],
                cracks: Vec::new(),
                particles: None,
                slice: None,
            }
        }
    }

    #[derive(Default)]
    struct Record {
        energy: Vec<EnergyRow>,
        tips: Vec<CrackTipRow>,
        snapshots: Vec<(u32, f64)>,
        progress: Vec<Progress>,
        finished: Vec<Summary>,
        /// Answer Cancel from this progress call on (0-based).
        cancel_at: Option<usize>,
        /// Fail the n-th energy batch (0-based).
        fail_energy_at: Option<usize>,
        energy_batches: usize,
        /// Order of calls, to check flush-before-progress.
        log: Vec<&'static str>,
        checkpoints: Vec<(CheckpointAt, Vec<u8>)>,
        /// Answer HandBack from this progress call on (0-based).
        hand_back_at: Option<usize>,
    }

    impl RunSink for Record {
        fn progress(&mut self, p: &Progress) -> Result<Control, SinkError> {
            self.log.push("progress");
            self.progress.push(*p);
            Ok(match (self.cancel_at, self.hand_back_at) {
                (Some(k), _) if self.progress.len() > k => Control::Cancel,
                (_, Some(k)) if self.progress.len() > k => Control::HandBack,
                _ => Control::Continue,
            })
        }
        fn energy(&mut self, rows: &[EnergyRow]) -> Result<(), SinkError> {
            self.log.push("energy");
            let k = self.energy_batches;
            self.energy_batches += 1;
            if self.fail_energy_at == Some(k) {
                return Err(SinkError("disk full".into()));
            }
            self.energy.extend_from_slice(rows);
            Ok(())
        }
        fn crack_tips(&mut self, rows: &[CrackTipRow]) -> Result<(), SinkError> {
            self.log.push("crack_tips");
            self.tips.extend_from_slice(rows);
            Ok(())
        }
        fn snapshot(&mut self, snap: &Snapshot) -> Result<(), SinkError> {
            self.log.push("snapshot");
            self.snapshots.push((snap.index, snap.time));
            Ok(())
        }
        fn finish(&mut self, summary: &Summary) -> Result<(), SinkError> {
            self.log.push("finish");
            self.finished.push(summary.clone());
            Ok(())
        }
        fn checkpoint(&mut self, bytes: &[u8], at: &CheckpointAt) -> Result<(), SinkError> {
            self.log.push("checkpoint");
            self.checkpoints.push((*at, bytes.to_vec()));
            Ok(())
        }
    }

    fn scene(history: Option<f64>, snapshots: f64) -> Scene {
        let history = history.map_or(String::new(), |h| format!("\"history_interval\": {h},"));
        fracture_api::validate::parse_scene(&format!(
            r#"{{"grid": {{"cell_size": 1.0, "min": [0,0], "max": [5,5]}},
                "materials": {{"m": {{"model": "linear_elastic", "density": 1.0,
                                     "youngs_modulus": 1.0, "poissons_ratio": 0.3}}}},
                "bodies": [{{"material": "m", "region": {{"rectangle": {{"min": [1,1], "max": [4,4]}}}}}}],
                "time": {{"end": 1.0}},
                "output": {{ {history} "snapshot_interval": {snapshots} }} }}"#
        ))
        .unwrap()
    }

    fn opts(ms: u64) -> RunOptions {
        RunOptions {
            threads: fracture_solver::Parallelism::threads(1),
            flush_every: Duration::from_millis(ms),
        }
    }

    #[test]
    fn samples_on_the_simulated_time_cadence() {
        // dt = 0.1, history every 0.25 → samples at steps 0, 3 (0.3), 5 (0.5), 8 (0.8),
        // 10 (1.0); snapshots every 0.5 → steps 0, 5, 10.
        let mut m = Fake::new(10, 0.1);
        let mut sink = Record::default();
        let s = run_model(
            &mut m,
            &scene(Some(0.25), 0.5),
            &opts(0),
            CheckpointPolicy::none(),
            None,
            &mut sink,
        );
        assert_eq!(s.status, RunStatus::Completed, "{s:?}");
        assert_eq!(s.message, None);
        let times: Vec<u64> = sink.energy.iter().map(|e| e.kinetic as u64).collect();
        assert_eq!(times, vec![0, 3, 5, 8, 10]);
        assert_eq!(sink.tips.len(), 5);
        let snaps: Vec<u32> = sink.snapshots.iter().map(|s| s.0).collect();
        assert_eq!(snaps, vec![0, 1, 2]);
        assert!((sink.snapshots[1].1 - 0.5).abs() < 1e-12);
        assert!((sink.snapshots[2].1 - 1.0).abs() < 1e-12);
        assert_eq!(s.steps, 10);
        assert_eq!((s.particles, s.grid_nodes, s.threads), (100, 36, 3));
        assert!((s.active_nodes_mean - 10.5).abs() < 1e-12);
        // Provenance: this build, this machine, start before finish (RFC 3339 sorts as text).
        let p = s.provenance.as_ref().expect("provenance");
        assert_eq!(p.solver_commit.as_deref(), crate::provenance::SOLVER_COMMIT);
        assert_eq!(p.host, crate::provenance::host());
        assert!(p.host.as_deref().is_some_and(|h| !h.is_empty()), "{p:?}");
        assert!(
            p.started_at.ends_with('Z') && p.started_at <= p.finished_at,
            "{p:?}"
        );
        assert_eq!(
            sink.finished[0].provenance.as_ref(),
            Some(p),
            "the sink got it too"
        );
        assert!((s.sim_time - 1.0).abs() < 1e-12);
        assert_eq!(s.solver_version, fracture_api::SOLVER_VERSION);
        assert_eq!(s.scene_hash, scene(Some(0.25), 0.5).hash());
        assert_eq!(sink.finished, vec![s.clone()]);
        let last = sink.progress.last().unwrap();
        assert_eq!((last.step, last.fraction), (10, 1.0));
        assert_eq!(sink.log.last(), Some(&"finish"));
    }

    #[test]
    fn every_step_without_history_interval_and_no_snapshots_at_zero() {
        let mut m = Fake::new(7, 0.1);
        let mut sink = Record::default();
        let s = run_model(
            &mut m,
            &scene(None, 0.0),
            &opts(3_600_000),
            CheckpointPolicy::none(),
            None,
            &mut sink,
        );
        assert_eq!(s.status, RunStatus::Completed);
        assert_eq!(sink.energy.len(), 8, "t = 0 and each of 7 steps");
        assert!(sink.snapshots.is_empty());
        // Long flush interval: rows come in one batch before the single final progress.
        assert_eq!(sink.progress.len(), 1);
        assert_eq!(sink.log, vec!["energy", "crack_tips", "progress", "finish"]);
    }

    #[test]
    fn rows_are_flushed_before_each_progress_report() {
        let mut m = Fake::new(20, 0.1);
        let mut sink = Record::default();
        run_model(
            &mut m,
            &scene(None, 0.0),
            &opts(0),
            CheckpointPolicy::none(),
            None,
            &mut sink,
        );
        assert_eq!(
            sink.progress.len(),
            21,
            "every step (flush_every = 0) and the end"
        );
        // The final report has nothing new to flush.
        let n = sink.log.len() - 2;
        assert_eq!(&sink.log[n - 1..], ["progress", "progress", "finish"]);
        for (i, w) in sink.log[..n - 1].windows(2).enumerate() {
            if w[1] == "progress" && i > 0 {
                assert_eq!(w[0], "crack_tips", "at {i}: {:?}", sink.log);
            }
        }
        // Each progress report follows the rows of its own step.
        assert_eq!(sink.energy.len(), 21);
    }

    #[test]
    fn cancel_stops_the_run() {
        let mut m = Fake::new(1000, 0.1);
        let mut sink = Record {
            cancel_at: Some(2),
            ..Default::default()
        };
        let s = run_model(
            &mut m,
            &scene(None, 0.0),
            &opts(0),
            CheckpointPolicy::none(),
            None,
            &mut sink,
        );
        assert_eq!(s.status, RunStatus::Cancelled);
        assert_eq!(s.steps, 3);
        assert!(s.message.is_some());
        assert_eq!(sink.finished.len(), 1);
        assert_eq!(sink.finished[0].status, RunStatus::Cancelled);
        // Rows up to the cancellation are all delivered.
        assert_eq!(sink.energy.last().unwrap().kinetic, 3.0);
    }

    #[test]
    fn hand_back_stops_without_final_sample_progress_or_finish() {
        struct HandBackAt(Record, usize);
        impl RunSink for HandBackAt {
            fn progress(&mut self, p: &Progress) -> Result<Control, SinkError> {
                self.0.progress(p)?;
                Ok(if self.0.progress.len() > self.1 {
                    Control::HandBack
                } else {
                    Control::Continue
                })
            }
            fn energy(&mut self, rows: &[EnergyRow]) -> Result<(), SinkError> {
                self.0.energy(rows)
            }
            fn crack_tips(&mut self, rows: &[CrackTipRow]) -> Result<(), SinkError> {
                self.0.crack_tips(rows)
            }
            fn snapshot(&mut self, snap: &Snapshot) -> Result<(), SinkError> {
                self.0.snapshot(snap)
            }
            fn finish(&mut self, summary: &Summary) -> Result<(), SinkError> {
                self.0.finish(summary)
            }
        }
        let mut m = Fake::new(1000, 0.1);
        let mut sink = HandBackAt(Record::default(), 2);
        let s = run_model(
            &mut m,
            &scene(None, 0.0),
            &opts(0),
            CheckpointPolicy::none(),
            None,
            &mut sink,
        );
        assert_eq!(s.status, RunStatus::Cancelled);
        assert_eq!(s.steps, 3);
        assert_eq!(s.message.as_deref(), Some("handed back at step 3"));
        let r = &sink.0;
        assert!(r.finished.is_empty(), "no finish after a hand-back");
        assert_eq!(r.progress.len(), 3, "no last progress report");
        // Rows up to the hand-back are delivered, and no extra final sample.
        let ks: Vec<u64> = r.energy.iter().map(|e| e.kinetic as u64).collect();
        assert_eq!(ks, vec![0, 1, 2, 3]);
        assert_eq!(r.log.last(), Some(&"progress"));
    }

    #[test]
    fn step_error_fails_with_its_message_and_a_final_sample() {
        let mut m = Fake::new(100, 0.1);
        m.fail_at = Some(6);
        let mut sink = Record::default();
        let s = run_model(
            &mut m,
            &scene(Some(0.25), 0.0),
            &opts(3_600_000),
            CheckpointPolicy::none(),
            None,
            &mut sink,
        );
        assert_eq!(s.status, RunStatus::Failed);
        assert_eq!(
            s.message.as_deref(),
            Some("step 6: velocity of particle 7 at (0.000000e0, 0.000000e0) m is not finite")
        );
        assert_eq!(s.failure, Some(FailureKind::Numerical));
        assert_eq!(s.steps, 6);
        let ks: Vec<u64> = sink.energy.iter().map(|e| e.kinetic as u64).collect();
        assert_eq!(
            ks,
            vec![0, 3, 5, 6],
            "samples so far plus the failing state"
        );
        assert_eq!(sink.finished.len(), 1);
    }

    #[test]
    fn solver_panic_becomes_a_failed_summary() {
        let mut m = Fake::new(100, 0.1);
        m.panic_at = Some(4);
        let mut sink = Record::default();
        let s = run_model(
            &mut m,
            &scene(None, 0.0),
            &opts(3_600_000),
            CheckpointPolicy::none(),
            None,
            &mut sink,
        );
        assert_eq!(s.status, RunStatus::Failed);
        let msg = s.message.unwrap();
        assert!(msg.contains("panicked in step 4"), "{msg}");
        assert!(msg.contains("index out of bounds in step 4"), "{msg}");
        assert_eq!(sink.energy.len(), 4, "t = 0 and steps 1..=3 kept");
        assert_eq!(sink.finished.len(), 1);
    }

    #[test]
    fn sink_error_fails_the_run() {
        let mut m = Fake::new(100, 0.1);
        let mut sink = Record {
            fail_energy_at: Some(1),
            ..Default::default()
        };
        let s = run_model(
            &mut m,
            &scene(None, 0.0),
            &opts(0),
            CheckpointPolicy::none(),
            None,
            &mut sink,
        );
        assert_eq!(s.status, RunStatus::Failed);
        assert_eq!(
            s.message.as_deref(),
            Some("could not record results: disk full")
        );
        assert!(s.steps < 100);
        assert_eq!(sink.finished.len(), 1);
        assert_eq!(sink.finished[0].status, RunStatus::Failed);
    }

    #[test]
    fn panic_messages_are_extracted() {
        let p = std::panic::catch_unwind(|| panic!("plain")).unwrap_err();
        assert_eq!(panic_message(&*p), "plain");
        let n = 3;
        let p = std::panic::catch_unwind(|| panic!("formatted {n}")).unwrap_err();
        assert_eq!(panic_message(&*p), "formatted 3");
    }

    /// Checkpoints by steps come at history samples, after the rows sampled so far were
    /// given to the sink, with the loop's cursor; a hand back checkpoints at once and stops
    /// the run without finishing it.
    #[test]
    fn checkpoints_follow_the_policy_and_a_hand_back_stops_the_run() {
        let policy = CheckpointPolicy {
            steps: Some(3),
            every: None,
        };
        let mut m = Fake::new(10, 0.1);
        let mut sink = Record::default();
        let s = run_model(
            &mut m,
            &scene(Some(0.2), 0.0),
            &opts(3_600_000),
            policy,
            None,
            &mut sink,
        );
        assert_eq!(s.status, RunStatus::Completed);
        // Samples at steps 2, 4, 6, 8, 10: due after 3 steps → at 4 and 8.
        let steps: Vec<u64> = sink.checkpoints.iter().map(|c| c.0.step).collect();
        assert_eq!(steps, vec![4, 8]);
        for (at, bytes) in &sink.checkpoints {
            let d = crate::checkpoint::decode(bytes, &scene(Some(0.2), 0.0).hash()).unwrap();
            assert_eq!(d.solver, at.step.to_le_bytes().to_vec());
            assert_eq!(d.cursor.sampled_at, Some(at.step));
        }
        let first = sink.log.iter().position(|l| *l == "checkpoint").unwrap();
        assert_eq!(sink.log[first - 1], "crack_tips", "{:?}", sink.log);
        assert!(sink.energy.iter().any(|r| (r.time - 0.4).abs() < 1e-9));

        let mut m = Fake::new(10, 0.1);
        let mut sink = Record {
            hand_back_at: Some(0),
            ..Record::default()
        };
        let policy = CheckpointPolicy {
            steps: Some(1000),
            every: None,
        };
        let s = run_model(
            &mut m,
            &scene(Some(0.2), 0.0),
            &opts(0),
            policy,
            None,
            &mut sink,
        );
        assert_eq!(s.status, RunStatus::Cancelled);
        assert_eq!(s.steps, 1);
        assert!(
            sink.finished.is_empty(),
            "a handed-back run is not finished"
        );
        assert_eq!(sink.checkpoints.len(), 1);
        assert_eq!(sink.checkpoints[0].0.step, 1);
        assert_eq!(sink.log.last(), Some(&"checkpoint"));
    }
}
