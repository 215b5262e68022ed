//! The ways a coupled run's covered cells take their solid term (`coupling.covered_cells`): the
//! one it starts with, and, where it times them (trials.rs), the one each step takes.

use super::FluidSide;
use crate::lbm::gpu::Gpu;
use crate::lbm::imb::{covered_fraction, CoveredCells};
use crate::terminal::{self, MORE};
use crate::trials::{WayTrials, AUTO_MIN_SECONDS};
use scene::lattice::LatticeUnits;
use scene::Scene;

/// The scene's `coupling.covered_cells`, "auto" and "timed" made definite for the scene's initial
/// particles (their covered fraction of the lattice; `radii` in m): the way the run starts with.
pub(super) fn covered_cells(
    scene: &Scene,
    units: &LatticeUnits,
    radii: &[f64],
) -> Result<CoveredCells, String> {
    let name = match scene.coupling.covered_cells.as_str() {
        "timed" => "auto",
        name => name,
    };
    let mode = CoveredCells::from_name(name).ok_or_else(|| {
        format!(
            "coupling.covered_cells = {:?}: expected \"auto\", \"timed\", \"fused\", \"redo\" or \"skip\"",
            scene.coupling.covered_cells
        )
    })?;
    let radii = radii.iter().map(|&r| units.cells(r));
    let cells = units.n.iter().product();
    Ok(mode.for_scene(covered_fraction(radii, cells)))
}

/// Whether the run times its ways of treating the covered cells (trials.rs), and how long the
/// steps left must take for a trial to start: "timed" on every device, always; "auto" on all but
/// CPU drivers, where building the other two ways' kernels costs more than a short run gains
/// (lavapipe, 2 cores: about 1 s each, against a default scene of 4.5 s) and
/// `CoveredCells::for_scene`'s rule was measured, and only with [`AUTO_MIN_SECONDS`] ahead.
pub(super) fn way_trials(scene: &Scene, gpu: &Gpu) -> Option<f64> {
    match scene.coupling.covered_cells.as_str() {
        "timed" => Some(0.0),
        "auto" if gpu.adapter.device_type != wgpu::DeviceType::Cpu => Some(AUTO_MIN_SECONDS),
        _ => None,
    }
}

impl FluidSide {
    /// The way the covered cells take their solid term (when timed: the one the last trial kept),
    /// for summary.json.
    pub fn covered_cells(&self) -> CoveredCells {
        self.trials
            .as_ref()
            .map_or(self.lattice.covered_cells(), WayTrials::kept)
    }

    /// When the run times its ways: the one this step takes (and the last trial's line in the
    /// log); a way the device does not build is left out of the trials (this step keeps the
    /// lattice's way).
    pub(super) fn take_way(&mut self) {
        let Some(trials) = &mut self.trials else {
            return;
        };
        let way = trials.way_for(self.steps, self.made.elapsed().as_secs_f64());
        if let Some(report) = trials.take_report() {
            terminal::say_either(
                &format!(
                    "lbm-server: covered cells timed on the run's steps: {} kept {MORE}",
                    trials.kept().name()
                ),
                &format!("lbm-server: {report}"),
            );
        }
        if let Err(e) = self.lattice.set_covered_cells(way) {
            protocol::say!("lbm-server: warning: {e}; the run times the other ways without it");
            trials.refuse(way);
        }
    }
}
