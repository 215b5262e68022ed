//! `lbm-server bench --particles N` on several ranks (`ranks.rs`): the blocks' steps coupled to
//! the bench's N spheres of 4 cells (`coupled.rs`), the covered cells taking their solid term the
//! first way `--covered-cells` names, rank 0 gathering the loads as in a run
//! (`BlockLattice::step_coupled_with`), no DEM: what the exchange costs in a coupled step,
//! overlapped or after the whole step (`--exchange exposed`).

use super::coupled::{bench_spheres, covered_cell_modes};
use super::BenchArgs;
use crate::lbm::imb::{ImbOptions, SolidParticle};
use crate::parallel::{BlockLattice, Communicator};

/// The coupling of the bench's steps on ranks: the spheres and the coupling's settings.
pub(super) struct Coupled {
    particles: Vec<SolidParticle>,
    pub(super) options: ImbOptions,
}

/// The coupling `--particles` asks for on the grid `n` (its first count; none without it).
pub(super) fn coupling(args: &BenchArgs, n: [usize; 3]) -> Result<Option<Coupled>, String> {
    let Some(&count) = args.particles.first() else {
        return Ok(None);
    };
    let mode = covered_cell_modes(&args.covered_cells)?[0];
    Ok(Some(Coupled {
        particles: bench_spheres(count, n)?,
        options: ImbOptions {
            covered_cells: mode,
            ..ImbOptions::default()
        },
    }))
}

impl Coupled {
    /// `steps` coupled steps of `lattice` as in a run (the exchange as the lattice is set, the
    /// loads gathered at rank 0), or `alone`: each block's own coupled step, no exchange and
    /// nothing gathered (the compute alone).
    pub(super) fn step(
        &self,
        lattice: &mut BlockLattice,
        comm: &dyn Communicator,
        alone: bool,
        steps: u64,
    ) -> Result<(), String> {
        let mut loads = Vec::new();
        for _ in 0..steps {
            match alone {
                true => lattice
                    .lattice
                    .step_coupled_with(&self.particles[..], &mut loads, |_, l| l)?,
                false => lattice.step_coupled_with(&self.particles[..], &mut loads, |_, l| l, comm)?,
            }
        }
        Ok(())
    }

    /// The coupling's line of the bench's table: the spheres and the way of the covered cells.
    pub(super) fn print(&self) {
        let mode = self.options.covered_cells.definite();
        println!(
            "coupled: {} spheres of 4 cells diameter, covered cells {}, the loads gathered at rank 0",
            self.particles.len(),
            mode.name(),
        );
    }
}
