//! 3D runs through the same run loop as 2D (`run.rs`): [`Simulation3`] is a
//! [`Model`](crate::run::Model) whose snapshots are its slices (one per `output.slices`
//! plane per snapshot time) and which has no crack tips yet.

use std::panic::{AssertUnwindSafe, catch_unwind};

use fracture_api::ValidScene3;
use fracture_api::results::{CrackTipRow, EnergyRow, Snapshot, Summary, Volume};
use fracture_api::scene::FieldKind;
use fracture_solver::StepStats;
use fracture_solver3d::Simulation3;

use crate::checkpoint::CheckpointPolicy;
use crate::run::{Model, finish_early_failed, panic_message, run_model};
use crate::{RunOptions, RunSink};

impl Model for Simulation3 {
    fn step(&mut self) -> Result<StepStats, String> {
        Simulation3::step(self)
            .map(|s| StepStats {
                grew: false,
                active_nodes: s.active_nodes,
            })
            .map_err(|e| e.to_string())
    }
    fn time(&self) -> f64 {
        Simulation3::time(self)
    }
    fn time_step(&self) -> f64 {
        Simulation3::time_step(self)
    }
    fn end_time(&self) -> f64 {
        Simulation3::end_time(self)
    }
    fn steps_taken(&self) -> u64 {
        Simulation3::steps_taken(self)
    }
    fn is_finished(&self) -> bool {
        Simulation3::is_finished(self)
    }
    fn particle_count(&self) -> usize {
        Simulation3::particle_count(self)
    }
    fn grid_node_count(&self) -> usize {
        Simulation3::grid_node_count(self)
    }
    fn threads(&self) -> usize {
        Simulation3::threads(self)
    }
    fn energy(&self) -> EnergyRow {
        Simulation3::energy(self)
    }
    fn crack_tips(&mut self) -> Vec<CrackTipRow> {
        Vec::new()
    }
    fn snapshot(&self, index: u32, fields: &[FieldKind]) -> Snapshot {
        let mut all = self.slice_snapshots(index, fields);
        // There is always at least one slice (`slices_or_default`).
        all.swap_remove(0)
    }
    fn snapshots(&self, index: u32, fields: &[FieldKind]) -> Vec<Snapshot> {
        self.slice_snapshots(index, fields)
    }
    fn checkpoint(&self) -> Option<Vec<u8>> {
        Some(Simulation3::checkpoint(self))
    }
    fn volume(&self, index: u32, fields: &[FieldKind]) -> Option<Volume> {
        Some(Simulation3::volume(self, index, fields))
    }
}

/// Run a 3D scene to its end time (the 3D [`run_scene`](crate::run_scene)).
pub fn run_scene3(scene: &ValidScene3, opts: &RunOptions, sink: &mut dyn RunSink) -> Summary {
    match run_job3(scene, opts, CheckpointPolicy::none(), None, sink) {
        Ok(s) => s,
        Err(why) => finish_early_failed(scene.scene(), sink, why),
    }
}

/// Run a 3D job (the 3D [`run_job`](crate::run_job)): checkpoints by `policy`, resuming
/// from `checkpoint` when given; a checkpoint that cannot be used is `Err` with the reason,
/// before anything is sent.
pub fn run_job3(
    scene: &ValidScene3,
    opts: &RunOptions,
    policy: CheckpointPolicy,
    checkpoint: Option<&[u8]>,
    sink: &mut dyn RunSink,
) -> Result<Summary, String> {
    let threads = opts.threads.resolve();
    let built = catch_unwind(AssertUnwindSafe(|| Simulation3::new(scene, threads)));
    let mut sim = match built {
        Ok(Ok(sim)) => sim,
        Ok(Err(e)) => return Err(format!("could not build the simulation: {e}")),
        Err(p) => {
            return Err(format!(
                "solver panicked while building the simulation: {}",
                panic_message(&*p)
            ));
        }
    };
    let Some(bytes) = checkpoint else {
        return Ok(run_model(&mut sim, scene.scene(), opts, policy, None, sink));
    };
    let d = crate::checkpoint::decode(bytes, &scene.scene().hash())?;
    sim.restore(&d.solver).map_err(|e| e.to_string())?;
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
