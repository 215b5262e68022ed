//! The field outputs of a coupled run's fluid: snapshots (fields/, fields.pvd) and probe lines
//! (line<N>.csv), after the steps the scene asks for and at the run's end.

use super::ranks::CHECKPOINT;
use super::FluidSide;
use crate::checkpoint::{Checkpoints, OutputPositions};
use crate::fields::FieldOutput;
use crate::parallel::write_snapshot_of_ranks;

impl FluidSide {
    /// The field outputs due after this step: a snapshot every `output.fields_interval` steps
    /// (where it is above 0) and after the run's last step, the probe lines every
    /// `output.interval` steps and after the last (fields/, fields.pvd, line<N>.csv).
    /// At the last step, where the outputs stood before those it gets only as the last is kept
    /// (`before_last`, for its checkpoint).
    pub(super) fn write_fields(&mut self) -> Result<(), String> {
        let (step, last) = (self.steps, self.steps == self.run_steps);
        let due = |every: u64| every > 0 && step.is_multiple_of(every);
        let (snapshot, lines) = (due(self.fields_every), due(self.lines_every));
        if !last {
            return self.write_outputs(snapshot, lines, false);
        }
        self.write_outputs(snapshot, lines, false)?;
        let mut at = OutputPositions::default();
        let read = self.fields.as_mut().map_or(Ok(()), |f| f.positions(&mut at));
        self.agreed(read)?;
        self.before_last = Some(at);
        let left = |every: u64, written: bool| every > 0 && !written;
        self.write_outputs(
            left(self.fields_every, snapshot),
            left(self.lines_every, lines),
            true,
        )
    }

    /// Where the field outputs stand, into `at` (a checkpoint's): at the last step, before those
    /// only a last step gets.
    pub fn positions(&mut self, at: &mut OutputPositions) -> Result<(), String> {
        match self.before_last.take() {
            Some(before) => {
                at.files.extend(before.files);
                at.fields_pvd = before.fields_pvd;
                Ok(())
            }
            None => self.fields.as_mut().map_or(Ok(()), |f| f.positions(at)),
        }
    }

    /// Takes the lattice's state for a checkpoint (`checkpoints`), with the outputs standing `at`
    /// and the run's `particles`: every rank's block (the others send theirs:
    /// [`FluidSide::send_checkpoint_block`]).
    pub fn checkpoint(&self, checkpoints: &mut Checkpoints, at: OutputPositions, particles: u64) {
        self.lead(CHECKPOINT);
        let time = self.steps as f64 * self.units.dt;
        let way = Some(self.lattice.lattice.covered_cells().name().to_string());
        checkpoints.hold((&self.lattice, &*self.comm), time, particles, at, way);
    }

    /// A rank other than 0: its block's part of the checkpoint rank 0 takes, sent to rank 0.
    pub(super) fn send_checkpoint_block(&self) {
        self.lattice.whole_state(&*self.comm);
    }

    /// Where a run ends before its last step (Ctrl-C, the DEM's STOP): the field outputs a last
    /// step gets, less those this step wrote already.
    pub(super) fn write_fields_of_early_end_here(&mut self) -> Result<(), String> {
        let step = self.steps;
        let left = |every: u64| every > 0 && !step.is_multiple_of(every);
        self.write_outputs(left(self.fields_every), left(self.lines_every), true)
    }

    /// Writes a snapshot and the probe lines (where the scene has any) of this step; `last`
    /// flushes the lines. Rank 0 writes the lines (their cells gathered), every rank its piece
    /// of the snapshot (on one rank, the whole .vti); the ranks agree whether all could.
    fn write_outputs(&mut self, snapshot: bool, lines: bool, last: bool) -> Result<(), String> {
        let lines = lines && !self.line_cells.is_empty();
        if snapshot || lines {
            let (own, bad) = self.lattice.own_fields(&*self.comm);
            if let Some(bad) = bad {
                return Err(self.unstable(bad));
            }
            let (step, comm) = (self.steps, &*self.comm);
            let mut written = Ok(());
            if lines {
                let values = self.lattice.gather_cells(comm, &own, &self.line_cells);
                if let Some(out) = &mut self.fields {
                    written = out.write_line_values(step, &values);
                }
            }
            if snapshot {
                let outputs = (self.fields.as_mut(), self.pieces.as_ref());
                written = written.and(write_snapshot_of_ranks(comm, outputs, step, &own));
            }
            self.agreed(written)?;
        }
        if last {
            let flushed = self.fields.as_mut().map_or(Ok(()), FieldOutput::flush);
            self.agreed(flushed)?;
        }
        Ok(())
    }
}
