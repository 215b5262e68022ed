//! A scene ready to run: loaded, checked (a `[lattice]` where it has particles, one this device
//! can hold, the steps, the connect timeout), its output folder made, locked for this run and
//! cleared of an earlier run's outputs.

use super::{DemMode, RunArgs};
use crate::checkpoint::{Checkpoints, Loaded};
use crate::parallel::{blocks_of, Communicator};
use scene::output_lock::OutputLock;
use scene::Scene;
use std::path::PathBuf;
use std::time::Duration;

/// A scene ready to run: validated, with its output folder made and locked.
pub(super) struct Prepared {
    pub(super) scene: Scene,
    pub(super) scene_file: String,
    /// The scene file's text (its hash is a checkpoint's `scene_hash`).
    pub(super) scene_text: String,
    pub(super) steps: u64,
    pub(super) out: PathBuf,
    pub(super) scene_copy: PathBuf,
    pub(super) connect_timeout: Duration,
    /// The lattice's blocks along x, y and z, one per rank.
    pub(super) blocks: [usize; 3],
    /// The checkpoint a resumed run goes on from (`--resume`), found and checked.
    pub(super) resumed: Option<Loaded>,
    /// `--checkpoint-interval`.
    pub(super) checkpoint_interval: Option<u64>,
    /// The output folder's lock, held for the whole run (by rank 0, which writes the outputs).
    pub(super) _lock: Option<OutputLock>,
}

/// The scene of `args` ready to run on the ranks of `comm`: rank 0 alone makes and locks the
/// output folder.
pub(super) fn prepare(args: &RunArgs, comm: &dyn Communicator) -> Result<Prepared, String> {
    if let Some(out) = &args.resume {
        return super::resume::prepare_resume(args, out, comm);
    }
    let (scene, scene_file, text) = match &args.scene {
        Some(path) => {
            let scene = Scene::load(path).map_err(|e| e.to_string())?;
            let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
            (scene, path.display().to_string(), text)
        }
        None => (
            Scene::default_scene(),
            scene::DEFAULT_SCENE_FILE.to_string(),
            scene::DEFAULT_SCENE.to_string(),
        ),
    };
    for warning in &scene.warnings {
        protocol::say!("lbm-server: warning: {warning}");
    }
    require_lattice(&scene, &scene_file)?;
    let steps = run_steps(args, &scene)?;
    let connect_timeout = connect_timeout(args)?;
    if scene.particle_count() > 0 {
        // Every rank reaches this with the same scene: the gather is every rank's.
        crate::parallel::dem_hosts(&crate::parallel::hosts(comm))?;
    }
    let blocks = blocks(&scene, comm.size())?;
    if let Some(units) = &scene.lattice_units {
        let block: [usize; 3] = std::array::from_fn(|a| units.n[a] / blocks[a]);
        fits_the_device(block)?;
    }
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(&scene.name));
    let scene_copy = out.join("scene.toml");
    let lock = if comm.rank() == 0 {
        Some(output_folder(&out, &scene_copy, &text)?)
    } else {
        None
    };
    Ok(Prepared {
        scene,
        scene_file,
        scene_text: text,
        steps,
        out,
        scene_copy,
        connect_timeout,
        blocks,
        resumed: None,
        checkpoint_interval: args.checkpoint_interval,
        _lock: lock,
    })
}

/// The output folder `out` made, locked, cleared of an earlier run's outputs, with the scene's
/// `text` copied to `scene_copy`.
fn output_folder(
    out: &std::path::Path,
    scene_copy: &std::path::Path,
    text: &str,
) -> Result<OutputLock, String> {
    std::fs::create_dir_all(out)
        .map_err(|e| format!("cannot create the output folder {}: {e}", out.display()))?;
    let lock = OutputLock::take(out)?;
    clear_earlier_outputs(out)?;
    std::fs::write(scene_copy, text).map_err(|e| format!("{}: {e}", scene_copy.display()))?;
    Ok(lock)
}

/// The lattice's blocks on `ranks` ranks (`[parallel] blocks` or chosen).
pub(super) fn blocks(scene: &Scene, ranks: usize) -> Result<[usize; 3], String> {
    let given = scene.parallel.blocks();
    let Some(units) = &scene.lattice_units else {
        return match ranks {
            1 => Ok([1, 1, 1]),
            _ => Err(format!(
                "{ranks} ranks: a scene without a [lattice] runs on one rank"
            )),
        };
    };
    blocks_of(units.n, scene.periodic_axes(), given, ranks)
}

/// The run's steps: `--duration`'s, `--steps` or the scene's.
pub(super) fn run_steps(args: &RunArgs, scene: &Scene) -> Result<u64, String> {
    let steps = match args.duration {
        Some(duration) => scene.steps_covering(duration, "--duration")?,
        None => args.steps.unwrap_or(scene.time.steps),
    };
    if steps == 0 {
        return Err("--steps = 0: must be at least 1".into());
    }
    Ok(steps)
}

/// The longest wait for the DEM to connect (`--connect-timeout`).
pub(super) fn connect_timeout(args: &RunArgs) -> Result<Duration, String> {
    let default_timeout = if args.dem == DemMode::External {
        f64::INFINITY
    } else {
        30.0
    };
    let connect_timeout = args.connect_timeout.unwrap_or(default_timeout);
    if connect_timeout.is_nan() || connect_timeout <= 0.0 {
        return Err(format!("--connect-timeout = {connect_timeout} s: must be > 0"));
    }
    Ok(Duration::try_from_secs_f64(connect_timeout).unwrap_or(Duration::MAX))
}

impl Prepared {
    /// The run's checkpoints: the scene's, every `--checkpoint-interval` steps where given.
    pub(super) fn checkpoints(&self) -> Checkpoints {
        let resumed = self.resumed.clone();
        let every = self.checkpoint_interval;
        Checkpoints::new(&self.out, &self.scene, &self.scene_text, every, resumed)
    }

    /// The run's checkpoints on every rank of `comm`, when all have prepared the run: on
    /// several, every `--checkpoint-interval` steps as rank 0 has it (a resumed run's, where
    /// not given, is its checkpoint's, which rank 0 alone read).
    pub(super) fn checkpoints_on(&self, comm: &dyn Communicator) -> Checkpoints {
        let ours = self.checkpoints();
        if comm.size() == 1 {
            return ours;
        }
        // A flag byte first: MPI refuses a broadcast of none.
        let given = match ours.given() {
            Some(n) => [&[1][..], &n.to_le_bytes()].concat(),
            None => vec![0],
        };
        let given = comm.broadcast(given);
        let every = given[1..].try_into().ok().map(u64::from_le_bytes);
        Checkpoints::new(
            &self.out,
            &self.scene,
            &self.scene_text,
            every,
            self.resumed.clone(),
        )
    }
}

/// A lattice the device cannot hold is refused before the output folder is touched or the
/// lattice allocated: the limits of the adapter the run opens (where none is found, the run's
/// start says why).
pub(super) fn fits_the_device(n: [usize; 3]) -> Result<(), String> {
    match crate::lbm::gpu::Gpu::adapter_limits() {
        Ok(limits) => crate::lbm::gpu::fits_device(&limits, n),
        Err(_) => Ok(()),
    }
}

/// Removes what an earlier run wrote into `out` under this run's output names, saying so.
fn clear_earlier_outputs(out: &std::path::Path) -> Result<(), String> {
    for dir in [
        crate::checkpoint::DIR,
        crate::checkpoint::OLD,
        crate::checkpoint::STAGING,
    ] {
        let dir = out.join(dir);
        if dir.is_dir() {
            std::fs::remove_dir_all(&dir).map_err(|e| format!("cannot remove {}: {e}", dir.display()))?;
        }
    }
    let removed = scene::outputs::clear_earlier(out, scene::outputs::LBM_SERVER).map_err(|e| {
        format!(
            "cannot remove an earlier run's outputs from {}: {e}",
            out.display()
        )
    })?;
    if removed > 0 {
        protocol::say!(
            "lbm-server: removed {removed} output files of an earlier run from {}",
            out.display()
        );
    }
    Ok(())
}

/// A scene with particles runs coupled to the lattice: without a `[lattice]` it is refused.
fn require_lattice(scene: &Scene, file: &str) -> Result<(), String> {
    if scene.lattice.is_some() || scene.particle_count() == 0 {
        return Ok(());
    }
    let error = scene::SceneError {
        file: file.to_string(),
        field: "lattice".into(),
        value: "missing".into(),
        problem: format!(
            "lbm-server couples particles to a lattice-Boltzmann fluid: add a [lattice] section (dx or \
             resolution, velocity_scale, ...; see validation/scenes/default.toml) and remove time.dt, \
             which the lattice derives; or run a granular scene alone with `dem-client run {file}`"
        ),
    };
    Err(error.to_string())
}
