//! `lbm-server run --resume OUT`: the run of OUT goes on from its last checkpoint, with the scene
//! of OUT/scene.toml. Found, checked and compared with the scene before anything in OUT is
//! touched: a checkpoint of another scene, lattice or storage, of another format version, one
//! truncated or corrupt, or a coupled one without the DEM's part is refused (exit 2) naming what
//! differs. The outputs are cut back to the checkpoint here for a fluid alone, after the DEM's
//! handshake for a coupled run (`checkpointing.rs`).

use super::prepare::{blocks, connect_timeout, fits_the_device, run_steps, Prepared};
use super::RunArgs;
use crate::checkpoint::{Expected, Loaded};
use crate::parallel::Communicator;
use scene::checkpoint::DEM_COMPLETE;
use scene::output_lock::OutputLock;
use scene::Scene;
use std::path::Path;

/// The run of `out` prepared to go on from its last checkpoint on the ranks of `comm` (any
/// number, whatever the number it was written on): every rank reads the scene, rank 0 alone
/// locks the output folder and finds and checks the checkpoint (it sends each rank its block
/// once all have made theirs: `parallel::resume_blocks`).
pub(super) fn prepare_resume(
    args: &RunArgs,
    out: &Path,
    comm: &dyn Communicator,
) -> Result<Prepared, String> {
    let scene_copy = out.join("scene.toml");
    let mut scene = Scene::load(&scene_copy).map_err(|e| e.to_string())?;
    other_cut(&mut scene, comm);
    let text = std::fs::read_to_string(&scene_copy).map_err(|e| format!("{}: {e}", scene_copy.display()))?;
    let units = scene
        .lattice_units
        .as_ref()
        .ok_or_else(|| format!("{}: a run to resume has a [lattice]", scene_copy.display()))?;
    let steps = run_steps(args, &scene)?;
    let connect_timeout = connect_timeout(args)?;
    if scene.particle_count() > 0 {
        // Every rank reaches this with the same scene: the gather is every rank's.
        crate::parallel::dem_hosts(&crate::parallel::hosts(comm))?;
    }
    let blocks = blocks(&scene, comm.size())?;
    fits_the_device(std::array::from_fn(|a| units.n[a] / blocks[a]))?;
    let (lock, loaded) = match comm.rank() {
        0 => {
            let (lock, loaded) = checked_checkpoint(out, &scene, &text, steps)?;
            (Some(lock), Some(loaded))
        }
        _ => (None, None),
    };
    Ok(Prepared {
        scene,
        scene_file: scene_copy.display().to_string(),
        scene_text: text,
        steps,
        out: out.to_path_buf(),
        scene_copy,
        connect_timeout,
        blocks,
        resumed: loaded,
        checkpoint_interval: args.checkpoint_interval,
        _lock: lock,
    })
}

/// The output folder `out` locked and its newest checkpoint found and checked against the scene
/// (its file's `text`) and the run's last step; a fluid alone's outputs cut back to it.
fn checked_checkpoint(
    out: &Path,
    scene: &Scene,
    text: &str,
    steps: u64,
) -> Result<(OutputLock, Loaded), String> {
    let units = scene.lattice_units.as_ref().expect("checked");
    let lock = OutputLock::take(out)?;
    let started = std::time::Instant::now();
    let loaded = Loaded::open(out)?;
    let read_s = started.elapsed().as_secs_f64();
    let fluid_only = scene.particle_count() == 0;
    loaded.check_run(&Expected {
        scene_text: text,
        lattice: units.n,
        storage: units.storage.name(),
        particles: fluid_only.then_some(0),
    })?;
    let step = loaded.header.step;
    if steps <= step {
        return Err(format!(
            "the checkpoint in {} is at step {step}, the run's last step is {steps}: nothing to \
             resume (give a larger --steps)",
            loaded.dir.display()
        ));
    }
    if fluid_only {
        scene::checkpoint::cut_back(out, &loaded.header.outputs)?;
    } else if !loaded.header.files.iter().any(|f| f.file == DEM_COMPLETE) {
        return Err(format!(
            "cannot resume from {}: it holds no DEM state",
            loaded.dir.display()
        ));
    }
    protocol::say!(
        "lbm-server: resuming {} from its checkpoint at step {step} to step {steps} (read and \
         checked in {read_s:.2} s)",
        out.display()
    );
    Ok((lock, loaded))
}

/// A scene whose `[parallel] blocks` are a cut for another number of ranks than `comm`'s: the
/// run chooses its own (a checkpoint does not depend on the cut), and rank 0 says so.
fn other_cut(scene: &mut Scene, comm: &dyn Communicator) {
    let Some(b) = scene.parallel.blocks() else {
        return;
    };
    let ranks = b.iter().product::<usize>();
    if ranks == comm.size() {
        return;
    }
    if comm.rank() == 0 {
        protocol::say!(
            "lbm-server: note: the scene's parallel.blocks = [{}, {}, {}] cut the lattice for \
             {ranks} ranks; resumed on {}, the run chooses its own blocks",
            b[0],
            b[1],
            b[2],
            comm.size()
        );
    }
    scene.parallel.blocks = None;
}
