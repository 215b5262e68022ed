//! The health of a coupled run's fluid: the lattice's checks, the loads that are not finite, and
//! the blow-up's error (with the fields of the last check that passed as last_good.vti, on several
//! ranks last_good.pvti and its pieces).

use super::FluidSide;
use crate::fluid::health_of;
use crate::parallel::{write_last_good_of_ranks, RankUnhealthy};
use crate::terminal;
use protocol::ParticleReply;

impl FluidSide {
    /// After the run's last step: the health check and the covers' warning, unless the last step
    /// was a check already (a run shorter than `lattice.check_interval`, or its tail beyond the
    /// last multiple, went unchecked).
    pub(super) fn check_last_step_here(&mut self) -> Result<(), String> {
        if self.steps.is_multiple_of(self.units.check_interval) {
            return Ok(());
        }
        self.check()
    }

    /// The health check of the lattice (a pass keeps its fields on the device for
    /// last_good.vti), and a warning when cells had more particles than slots: the first time,
    /// with `--verbose` at every check.
    pub(super) fn check(&mut self) -> Result<(), String> {
        if let Some(bad) = self.lattice.health(&*self.comm) {
            return Err(self.unstable(bad));
        }
        self.lattice.keep_fields();
        self.last_good = Some(self.steps);
        let lost = self.lost_covers();
        let (unlisted, dropped) = (lost.unlisted, lost.dropped);
        if unlisted > 0 {
            return Err(format!(
                "by step {}, {unlisted} covered cells did not fit the list of covered cells (room for {} \
                 on this device: its storage binding limit / 80 bytes), so their solid term was missing: \
                 use fewer or smaller particles, or a device with a larger binding limit",
                self.steps,
                self.lattice.lattice.covered_cell_capacity()
            ));
        }
        let root = self.comm.rank() == 0;
        if root && dropped > 0 && (terminal::verbose() || !self.said_dropped) {
            let line = format!(
                "lbm-server: warning: by step {}, {dropped} particle-cell covers did not fit coupling.slots = {}",
                self.steps,
                self.lattice.lattice.slots()
            );
            terminal::say_either(
                &format!(
                    "{line}: a cell covered by more particles keeps those that cover most of it \
                     (docs/imb.md, \"One coupled step\"); later checks' counts with --verbose"
                ),
                &line,
            );
            self.said_dropped = true;
        }
        Ok(())
    }

    /// The error of a blow-up found at this step: the step, the cell furthest out of bounds
    /// (`bad`, the first found, where none is further) and its quantities, and the fields of the
    /// last check that passed written as last_good.vti.
    pub(super) fn unstable(&mut self, bad: RankUnhealthy) -> String {
        let comm = &*self.comm;
        let bad = self.lattice.furthest_unhealthy(comm).unwrap_or(bad);
        let what = bad.cell.describe(&health_of(&self.units), |c| {
            self.units.cell_centre(c, self.origin)
        });
        let rank = match comm.size() {
            1 => String::new(),
            _ => format!("rank {}, ", bad.rank),
        };
        let mut msg = format!(
            "the fluid became unstable by step {}: furthest out of bounds, {rank}{what}",
            self.steps
        );
        let kept = self.lattice.kept_own_fields();
        if let Some((good, own)) = self.last_good.take().zip(kept) {
            let outputs = (self.fields.as_ref(), self.pieces.as_ref());
            msg += &write_last_good_of_ranks(comm, outputs, good, &own);
        }
        if let Some(fields) = &mut self.fields {
            let _ = fields.flush();
        }
        msg
    }

    /// The fluid's blow-up, where the health check finds one now (run when the particles' states
    /// went wrong: the fluid's forces may be why).
    pub(super) fn unstable_now_here(&mut self) -> Option<String> {
        let bad = self.lattice.health(&*self.comm)?;
        Some(self.unstable(bad))
    }

    /// The error where a particle's load is not a finite number: the fluid's blow-up where the
    /// health check finds one now (before a NaN reaches the DEM, which would otherwise be
    /// blamed for the state it integrates from it), else the particle and its load.
    pub(super) fn not_finite(&mut self, reply: Option<&ParticleReply>) -> String {
        if let Some(cause) = self.unstable_now_here() {
            return cause;
        }
        let Some(reply) = reply else {
            return format!("rank 0 found a load that is not finite at step {}", self.steps);
        };
        format!(
            "the fluid's load on particle id {} at step {} is not finite (force {:?} N, torque {:?} N m), \
             though the fluid passed its health check",
            reply.id, self.steps, reply.force, reply.torque
        )
    }
}

/// Whether a particle's force and torque are finite numbers.
pub(super) fn finite_load(reply: &ParticleReply) -> bool {
    reply.force.iter().chain(&reply.torque).all(|v| v.is_finite())
}
