//! A coupled run on several ranks: rank 0 joins the DEM (as on one process) and leads, and every
//! other rank follows it ([`follow`]). Each of rank 0's calls into its [`FluidSide`] that the
//! others take part in (`step`, `check_last_step`, `unstable_now`, `write_fields_of_early_end`,
//! `checkpoint`, `end_ranks`) first broadcasts a command, the step's with the DEM's states (the
//! bytes the fluid reads); each rank then runs the same code on its block of the lattice, with
//! the same particles in the whole lattice's coordinates, and meets the others where they gather
//! (the step's pairs, the health checks, the fields). On one rank nothing is sent.

use super::FluidSide;
use crate::lbm::imb::LostCovers;
use crate::parallel::{all, Communicator, ParallelSummary};
use protocol::{ParticleReply, ParticleState};
use scene::Scene;
use std::path::Path;
use std::rc::Rc;
use std::time::Instant;

/// The commands rank 0 broadcasts (a command's first byte).
const STEP: u8 = 0;
const CHECK_LAST: u8 = 1;
const UNSTABLE_NOW: u8 = 2;
const EARLY_END: u8 = 3;
/// With the run's exit code as its second byte.
const END: u8 = 4;
/// Every rank sends rank 0 its block for a checkpoint (`field_outputs.rs`).
pub(super) const CHECKPOINT: u8 = 5;

impl FluidSide {
    /// Advances the fluid one step with the particles `states` (SI) and returns their loads (SI):
    /// the lattice's, buoyancy added, then the lubrication correction; then the health check
    /// where one is due, and the field outputs (`step_here`). The other ranks step with it.
    pub fn step(&mut self, states: &[ParticleState], out: &mut Vec<ParticleReply>) -> Result<(), String> {
        let now = self.made.elapsed().as_secs_f64();
        if self.comm.size() > 1 {
            // The step's start on rank 0's clock (every rank's start-up trial goes by it), and the
            // states as the DEM sent them (PROTOCOL.md 3.1): the same bits on every rank.
            let mut command = vec![STEP];
            command.extend_from_slice(&now.to_le_bytes());
            command.extend_from_slice(bytemuck::cast_slice(states));
            self.comm.broadcast(command);
        }
        self.step_here(states, out, now)
    }

    /// After the run's last step: the health check and the covers' warning, unless the last
    /// step was a check already (`check_last_step_here`).
    pub fn check_last_step(&mut self) -> Result<(), String> {
        self.lead(CHECK_LAST);
        self.check_last_step_here()
    }

    /// The fluid's blow-up, where the health check finds one now (run when the particles'
    /// states went wrong: the fluid's forces may be why).
    pub fn unstable_now(&mut self) -> Option<String> {
        self.lead(UNSTABLE_NOW);
        self.unstable_now_here()
    }

    /// Where a run ends before its last step (Ctrl-C, the DEM's STOP): the field outputs a last
    /// step gets, less those this step wrote already.
    pub fn write_fields_of_early_end(&mut self) -> Result<(), String> {
        self.lead(EARLY_END);
        self.write_fields_of_early_end_here()
    }

    /// The run ends with `code` after `wall` seconds: the other ranks end with it; what
    /// summary.json says of the ranks, gathered.
    pub fn end_ranks(&self, code: u8, wall: f64) -> ParallelSummary {
        if self.comm.size() > 1 {
            self.comm.broadcast(vec![END, code]);
        }
        self.parallel_summary(wall)
    }

    fn parallel_summary(&self, wall: f64) -> ParallelSummary {
        ParallelSummary::gather(&*self.comm, &self.lattice, self.device(), wall)
    }

    /// Rank 0 tells the others to do what it does next.
    pub(super) fn lead(&self, command: u8) {
        if self.comm.size() > 1 {
            self.comm.broadcast(vec![command]);
        }
    }

    /// The ranks agree on rank 0's `result` (of writing its outputs): all fail where it failed.
    pub(super) fn agreed(&self, result: Result<(), String>) -> Result<(), String> {
        if all(&*self.comm, result.is_ok()) {
            return Ok(());
        }
        Err(result
            .err()
            .unwrap_or_else(|| "rank 0 could not write its outputs".into()))
    }

    /// The covers lost so far: at rank 0 every rank's summed; elsewhere this rank's dropped
    /// covers, and unlisted cells where any rank had some (every rank stops then).
    pub(super) fn lost_covers(&self) -> LostCovers {
        let mine = self.lattice.lattice.lost_covers();
        if self.comm.size() == 1 {
            return mine;
        }
        let comm = &*self.comm;
        let counts = [mine.dropped, mine.unlisted].map(u32::to_le_bytes).concat();
        let sums = comm.gather(&counts).iter().fold([0u32; 2], |sum, piece| {
            let word = |i: usize| u32::from_le_bytes(piece[4 * i..4 * i + 4].try_into().expect("4 bytes"));
            [sum[0] + word(0), sum[1] + word(1)]
        });
        let none_unlisted = all(comm, mine.unlisted == 0);
        match comm.rank() {
            0 => LostCovers {
                dropped: sums[0],
                unlisted: sums[1],
            },
            _ => LostCovers {
                dropped: mine.dropped,
                unlisted: u32::from(!none_unlisted),
            },
        }
    }
}

/// A rank other than 0 of a coupled run of `scene` (`steps` steps, outputs in `out` written by
/// rank 0): its block of the lattice cut into `blocks`, which does what rank 0 says until the
/// run ends; the run's exit code.
pub fn follow(
    scene: &Scene,
    steps: u64,
    out: &Path,
    (comm, blocks): (Rc<dyn Communicator>, [usize; 3]),
) -> u8 {
    let started = Instant::now();
    let rank = comm.rank();
    let mut fluid = match FluidSide::for_scene(scene, steps, out, None, (comm.clone(), blocks)) {
        Ok(fluid) => fluid,
        Err(e) => {
            protocol::say!("lbm-server: error: rank {rank}: {e}");
            return 1;
        }
    };
    crate::run::started();
    let mut states = Vec::new();
    let mut replies = Vec::new();
    loop {
        let command = comm.broadcast(Vec::new());
        // Failures are rank 0's to say: every rank meets the same ones (the ranks agree).
        match command[0] {
            STEP => {
                let now = f64::from_le_bytes(command[1..9].try_into().expect("rank 0's clock"));
                states.clear();
                states.extend(
                    command[9..]
                        .chunks_exact(size_of::<ParticleState>())
                        .map(bytemuck::pod_read_unaligned::<ParticleState>),
                );
                let _ = fluid.step_here(&states, &mut replies, now);
            }
            CHECK_LAST => {
                let _ = fluid.check_last_step_here();
            }
            UNSTABLE_NOW => {
                let _ = fluid.unstable_now_here();
            }
            EARLY_END => {
                let _ = fluid.write_fields_of_early_end_here();
            }
            CHECKPOINT => fluid.send_checkpoint_block(),
            _ => {
                fluid.parallel_summary(started.elapsed().as_secs_f64());
                return command[1];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_state_crosses_to_the_other_ranks_bit_for_bit() {
        let s = ParticleState {
            id: 7,
            position: [0.1, -0.0, f64::MIN_POSITIVE],
            velocity: [1e-300, 2.5, -3.0],
            angular_velocity: [0.3, f64::EPSILON, 9.0],
            radius: 0.002,
        };
        let bytes: &[u8] = bytemuck::bytes_of(&s);
        assert_eq!(bytes.len(), 88, "PROTOCOL.md 3.1's layout");
        let back: ParticleState = bytemuck::pod_read_unaligned(bytes);
        assert_eq!(back, s);
        assert_eq!(back.position[1].to_bits(), (-0.0f64).to_bits());
    }
}
