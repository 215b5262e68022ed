//! The fluid kernels and the way of the covered cells a coupled run takes (`lattice.kernel`,
//! `coupling.covered_cells`): those its scene pins, and where it leaves them to "auto", those its
//! start-up trial keeps (trials.rs).

use super::FluidSide;
use crate::lbm::imb::CoveredCells;
use crate::lbm::kernel::Kernel;
use crate::trials::{kernels_of, Trial};
use scene::Scene;

/// The ways of the covered cells the scene's `coupling.covered_cells` leaves open: the three
/// with "auto" or "timed" (the redo first: the way the run starts with), else the one it names.
pub(super) fn covered_cells_of(scene: &Scene) -> Result<Vec<CoveredCells>, String> {
    let name = scene.coupling.covered_cells.as_str();
    match CoveredCells::from_name(name) {
        _ if name == "timed" => Ok(vec![CoveredCells::Redo, CoveredCells::Skip, CoveredCells::Fused]),
        Some(CoveredCells::Auto) => Ok(vec![CoveredCells::Redo, CoveredCells::Skip, CoveredCells::Fused]),
        Some(mode) => Ok(vec![mode]),
        None => Err(format!(
            "coupling.covered_cells = {name:?}: expected \"auto\", \"timed\", \"fused\", \"redo\" or \"skip\""
        )),
    }
}

/// The start-up trial of a coupled run of `steps` steps over what the scene leaves open. On a
/// CPU driver (lavapipe, `cpu`) "auto" times nothing and takes the quads' kernels and the redo:
/// building the other kernels there costs about a second each, more than a short run wins back,
/// and a run busy building them notices a dead DEM late; `coupling.covered_cells = "timed"`
/// times them on every device. On several ranks every rank times the same steps by rank 0's
/// clock (`FluidSide::step` sends it with the states), so that all keep the same.
pub(super) fn trial(scene: &Scene, kernel: Option<Kernel>, steps: u64, cpu: bool) -> Result<Trial, String> {
    let mut trial = Trial::new(kernels_of(kernel), covered_cells_of(scene)?, steps);
    if cpu && scene.coupling.covered_cells != "timed" {
        trial.pin_first();
    }
    Ok(trial)
}

impl FluidSide {
    /// The way the covered cells take their solid term (after the trial: the one it kept), for
    /// summary.json.
    pub fn covered_cells(&self) -> CoveredCells {
        self.trial.kept().way
    }

    /// The fluid kernels the run takes (after the trial: those it kept), for summary.json.
    pub fn kernel(&self) -> Kernel {
        self.trial.kept().kernel
    }

    /// What the trial measured and kept, for summary.json.
    pub fn trial_lines(&self) -> &[String] {
        &self.trial.lines
    }

    /// The kernels and way this step takes, which starts at `now` on rank 0's clock (the trial's;
    /// its stages' lines in rank 0's log); a choice the device does not build is left out of the
    /// trial (this step keeps the lattice's).
    pub(super) fn take_way(&mut self, now: f64) {
        let comm = &*self.comm;
        self.trial
            .give_agreed_choice(&mut self.lattice.lattice, self.steps, now, comm);
    }
}
