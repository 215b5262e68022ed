//! The field outputs of a coupled run's fluid: snapshots (fields/, fields.pvd) and probe lines
//! (line<N>.csv), after the steps the scene asks for and at the run's end.

use super::FluidSide;

impl FluidSide {
    /// The field outputs due after this step: a snapshot every `output.fields_interval` steps
    /// (where it is above 0) and after the run's last step, the probe lines every
    /// `output.interval` steps and after the last (fields/, fields.pvd, line<N>.csv).
    pub(super) fn write_fields(&mut self) -> Result<(), String> {
        let (step, last) = (self.steps, self.steps == self.run_steps);
        let due = |every: u64| every > 0 && (step.is_multiple_of(every) || last);
        self.write_outputs(due(self.fields_every), due(self.lines_every), last)
    }

    /// Where a run ends before its last step (Ctrl-C, the DEM's STOP): the field outputs a last
    /// step gets, less those this step wrote already.
    pub fn write_fields_of_early_end(&mut self) -> Result<(), String> {
        let step = self.steps;
        let left = |every: u64| every > 0 && !step.is_multiple_of(every);
        self.write_outputs(left(self.fields_every), left(self.lines_every), true)
    }

    /// Writes a snapshot and the probe lines (where the scene has any) of this step; `last`
    /// flushes the lines.
    fn write_outputs(&mut self, snapshot: bool, lines: bool, last: bool) -> Result<(), String> {
        let lines = lines && self.fields.has_lines();
        if snapshot || lines {
            let (fields, bad) = self.lattice.fields();
            if let Some(bad) = bad {
                return Err(self.unstable(bad));
            }
            if lines {
                self.fields.write_lines(self.steps, &fields)?;
            }
            if snapshot {
                self.fields.write_snapshot(self.steps, &fields)?;
            }
        }
        if last {
            self.fields.flush()?;
        }
        Ok(())
    }
}
