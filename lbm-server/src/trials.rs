//! The start-up trial: the fluid kernels (`lattice.kernel`: the quads' or the per-cell kernel)
//! and the ways of giving the covered cells their solid term (`coupling.covered_cells`: redo,
//! skip, fused) leave the same populations and loads bit for bit, so a run times the choices its
//! scene leaves open ("auto") on its own first steps, on its device, and keeps the fastest for the
//! rest of the run. Which is fastest depends on the device (a GPU or a CPU driver such as
//! lavapipe, which runs both sides of every branch), the grid and the particles: timed, not
//! guessed.
//!
//! Two stages, from step [`FIRST`] (before it the face ramp and the first allocations): the
//! kernels with the way the run starts with, then the ways with the kernel kept (a stage with one
//! choice is left out). A stage runs each choice for [`BLOCK`] steps, [`ROUNDS`] times, the order
//! turned by one each round; a block's first step is not timed (its wait includes the previous
//! choice's last kernels, and it builds the choice's kernels the first time). A step's time is
//! from its start to the next step's (in a coupled run the DEM's step included). After the first
//! round a choice whose median step takes more than [`DROP`] times the best's is dropped, so that
//! a kernel many times slower on this device costs one block. The choice of the lowest median step
//! is kept. The trial runs only where the run has [`ROOM`] times the trial's longest length of
//! steps from [`FIRST`]; in shorter runs "auto" takes the quads' kernels and the redo.

use crate::lbm::gpu::GpuLattice;
use crate::lbm::imb::CoveredCells;
use crate::lbm::kernel::Kernel;
use crate::parallel::{all, Communicator};

/// Steps per choice and round; the first of them is not timed.
pub const BLOCK: u64 = 5;
/// Rounds of a stage.
pub const ROUNDS: u64 = 3;
/// The step at which the trial starts.
pub const FIRST: u64 = 10;
/// A trial runs only where the steps from [`FIRST`] hold this many trials' longest length.
pub const ROOM: u64 = 3;
/// After a stage's first round, a choice whose median step is more than this many times the
/// best's is not timed again.
pub const DROP: f64 = 1.5;

/// The kernels `lattice.kernel` leaves open: both with "auto" (None; the quads' first: the
/// kernels a run starts with), else the one it names.
pub fn kernels_of(kernel: Option<Kernel>) -> Vec<Kernel> {
    match kernel {
        Some(kernel) => vec![kernel],
        None => Kernel::ALL.to_vec(),
    }
}

/// What a step takes: the fluid kernels and the way of the covered cells.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Choice {
    pub kernel: Kernel,
    pub way: CoveredCells,
}

impl Choice {
    fn name(self, stage: Stage) -> &'static str {
        match stage {
            Stage::Kernels => self.kernel.name(),
            Stage::Ways => self.way.name(),
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Stage {
    Kernels,
    Ways,
}

/// The run's start-up trial: which choice each step takes, from the times at which the steps
/// start.
#[derive(Debug, Clone)]
pub struct Trial {
    /// The kernels and ways the scene leaves open (one where it pins it).
    kernels: Vec<Kernel>,
    ways: Vec<CoveredCells>,
    /// The choice kept outside the trial (so far).
    kept: Choice,
    /// Whether the trial runs (decided at [`FIRST`]); None before.
    runs: Option<bool>,
    /// The stage under way, its choices and its first step; None when done.
    stage: Option<Stage>,
    choices: Vec<Choice>,
    /// The rest of this round's blocks (indices in `choices`, next last), the round, and the
    /// steps taken in the current block (`BLOCK` when the next step starts a block).
    queue: Vec<usize>,
    round: u64,
    in_block: u64,
    current: usize,
    /// Timed steps' seconds of each choice; dropped after the first round; not built.
    times: Vec<Vec<f64>>,
    dropped: Vec<bool>,
    refused: Vec<bool>,
    /// The last step if it is timed: its choice and when it started.
    timing: Option<(usize, f64)>,
    /// Steps of the run.
    steps: u64,
    /// What each finished stage measured, for the run's log (taken once), and for summary.json.
    report: Vec<String>,
    pub lines: Vec<String>,
}

impl Trial {
    /// The trial of a run of `steps` steps over `kernels` and `ways` (the first of each is the
    /// one the run starts with and keeps where it does not time them; no way for a run without
    /// particles).
    pub fn new(kernels: Vec<Kernel>, ways: Vec<CoveredCells>, steps: u64) -> Trial {
        let ways: Vec<CoveredCells> = ways.into_iter().map(CoveredCells::definite).collect();
        Trial {
            kept: Choice {
                kernel: kernels[0],
                way: ways.first().copied().unwrap_or(CoveredCells::Redo),
            },
            kernels,
            ways,
            runs: None,
            stage: None,
            choices: Vec::new(),
            queue: Vec::new(),
            round: 0,
            in_block: 0,
            current: 0,
            times: Vec::new(),
            dropped: Vec::new(),
            refused: Vec::new(),
            timing: None,
            steps,
            report: Vec::new(),
            lines: Vec::new(),
        }
    }

    /// The choice the run keeps between and after the stages (so far).
    pub fn kept(&self) -> Choice {
        self.kept
    }

    /// Steps of the trial at most: every choice of both stages for every round.
    pub fn longest(&self) -> u64 {
        let stage = |n: usize| if n > 1 { n as u64 * BLOCK * ROUNDS } else { 0 };
        stage(self.kernels.len()) + stage(self.ways.len())
    }

    /// Whether the scene leaves anything to time.
    pub fn open(&self) -> bool {
        self.longest() > 0
    }

    /// Times nothing: the run keeps the kernels and the way it starts with (the first of each).
    pub fn pin_first(&mut self) {
        self.kernels.truncate(1);
        self.ways.truncate(1);
    }

    /// The choice step `step` (0 for the first; called for every step in order) takes, told that
    /// it starts at `now` (seconds on a clock that only goes forward).
    pub fn choice_for(&mut self, step: u64, now: f64) -> Choice {
        if let Some((k, from)) = self.timing.take() {
            self.times[k].push(now - from);
        }
        if step < FIRST {
            return self.kept;
        }
        if self.runs.is_none() {
            let runs = self.open() && FIRST + ROOM * self.longest() <= self.steps;
            self.runs = Some(runs);
            if runs {
                self.begin(if self.kernels.len() > 1 {
                    Stage::Kernels
                } else {
                    Stage::Ways
                });
            }
        }
        if self.stage.is_none() {
            return self.kept;
        }
        if self.in_block == BLOCK && !self.next_block() {
            return self.kept;
        }
        let k = self.current;
        if self.in_block > 0 {
            self.timing = Some((k, now));
        }
        self.in_block += 1;
        self.choices[k]
    }

    /// Whether the trial is under way at the step last asked for (the run then steps one by one):
    /// never where the scene leaves nothing to time.
    pub fn under_way(&self) -> bool {
        self.open() && (self.runs.is_none() || self.stage.is_some())
    }

    /// Gives `lattice` the choice of step `step` (told that it starts at `now`; its stages' lines
    /// for [`Trial::say_report`]); a choice the device does not build is left out of the trial
    /// with a warning (the step keeps the lattice's): false then.
    pub fn give_choice(&mut self, lattice: &mut GpuLattice, step: u64, now: f64) -> bool {
        let choice = self.choice_for(step, now);
        if (choice.kernel, choice.way) == (lattice.kernel(), lattice.covered_cells()) {
            return true;
        }
        if let Err(e) = lattice.set_way(choice.kernel, choice.way) {
            protocol::say!("lbm-server: warning: {e}; the run times the others without it");
            self.refuse();
            return false;
        }
        true
    }

    /// On one of the ranks of `comm`, once every rank has made its trial: where any rank's times
    /// nothing (its device a CPU driver's), none does, so that all step alike.
    pub fn agree_open(&mut self, comm: &dyn Communicator) {
        if !all(comm, self.open()) {
            self.pin_first();
        }
    }

    /// [`Trial::give_choice`] on one of the ranks of `comm`, which step together: `now` is rank
    /// 0's clock, and while the trial is under way a choice that any rank's device does not build
    /// is left out on every rank, so that every rank's trial makes the same choices; rank 0 says
    /// the stages' lines. The ranks' blocks may then run different choices for a step: every
    /// choice gives the same bits.
    pub fn give_agreed_choice(
        &mut self,
        lattice: &mut GpuLattice,
        step: u64,
        now: f64,
        comm: &dyn Communicator,
    ) {
        let built = self.give_choice(lattice, step, now);
        if self.under_way() && !all(comm, built) && built {
            self.refuse();
        }
        self.say_report(comm.rank() == 0);
    }

    /// Leaves the choice just asked for out of the trial (the device did not build it): the step
    /// that asked for it is not timed, and the next step starts the next block.
    pub fn refuse(&mut self) {
        self.refused[self.current] = true;
        self.timing = None;
        self.in_block = BLOCK;
    }

    /// Starts `stage` over its choices (the kept choice with each kernel, or each way).
    fn begin(&mut self, stage: Stage) {
        let kept = self.kept;
        self.choices = match stage {
            Stage::Kernels => self
                .kernels
                .iter()
                .map(|&kernel| Choice { kernel, ..kept })
                .collect(),
            Stage::Ways => self.ways.iter().map(|&way| Choice { way, ..kept }).collect(),
        };
        let n = self.choices.len();
        self.stage = Some(stage);
        self.times = vec![Vec::new(); n];
        self.dropped = vec![false; n];
        self.refused = vec![false; n];
        self.round = 0;
        self.queue = (0..n).rev().collect();
        self.in_block = BLOCK;
    }

    /// Moves to the next block (the next round's first where this round is done, the next stage
    /// where this stage is); false when the trial is done.
    fn next_block(&mut self) -> bool {
        loop {
            if let Some(k) = self.queue.pop() {
                if self.dropped[k] || self.refused[k] {
                    continue;
                }
                self.current = k;
                self.in_block = 0;
                return true;
            }
            self.round += 1;
            if self.round == 1 {
                self.drop_slow();
            }
            let left: Vec<usize> = (0..self.choices.len())
                .filter(|&k| !self.dropped[k] && !self.refused[k])
                .collect();
            if self.round < ROUNDS && left.len() > 1 {
                // Round r takes the choices left turned by r.
                let r = self.round as usize % left.len();
                self.queue = left[r..].iter().chain(&left[..r]).rev().copied().collect();
                continue;
            }
            self.decide();
            match self.stage {
                Some(Stage::Kernels) if self.ways.len() > 1 => self.begin(Stage::Ways),
                _ => {
                    self.stage = None;
                    return false;
                }
            }
        }
    }

    /// After the first round: drops the choices whose median step is more than [`DROP`] times
    /// the best's.
    fn drop_slow(&mut self) {
        let best = self.medians().into_iter().fold(f64::INFINITY, f64::min);
        for (k, m) in self.medians().into_iter().enumerate() {
            if m > DROP * best {
                self.dropped[k] = true;
            }
        }
    }

    fn medians(&self) -> Vec<f64> {
        self.times.iter().map(|t| median(t)).collect()
    }

    /// Keeps the choice of the lowest median step (a median, not a mean: a step that also wrote
    /// particles.csv or checked the lattice's health is a few of each choice's, not its typical
    /// step) and says what the stage measured.
    fn decide(&mut self) {
        let medians = self.medians();
        let best = (0..self.choices.len())
            .filter(|&k| medians[k].is_finite())
            .min_by(|&a, &b| medians[a].total_cmp(&medians[b]));
        if let Some(best) = best {
            self.kept = self.choices[best];
        }
        let stage = self.stage.expect("a stage under way");
        let each: Vec<String> = (0..self.choices.len())
            .map(|k| {
                let name = self.choices[k].name(stage);
                match (self.refused[k], self.dropped[k]) {
                    (true, _) => format!("{name} not built"),
                    (_, true) => format!("{name} {:.3} ms (dropped after a round)", medians[k] * 1e3),
                    _ => format!("{name} {:.3} ms", medians[k] * 1e3),
                }
            })
            .collect();
        let what = match stage {
            Stage::Kernels if self.ways.is_empty() => "kernels timed".to_string(),
            Stage::Kernels => format!("kernels timed with the covered cells {}", self.kept.way.name()),
            Stage::Ways => format!("covered cells timed with the {} kernels", self.kept.kernel.name()),
        };
        let line = format!(
            "{what} (median step of {} rounds of {} steps, the first of each not timed): {}: {} kept",
            ROUNDS,
            BLOCK,
            each.join(", "),
            self.kept.name(stage)
        );
        self.report.push(line.clone());
        self.lines.push(line);
    }

    /// The run's first line's words for the trial.
    pub fn describe(&self) -> String {
        let open: Vec<&str> = [
            (self.kernels.len() > 1, "the kernels"),
            (self.ways.len() > 1, "the ways of the covered cells"),
        ]
        .into_iter()
        .filter_map(|(open, what)| open.then_some(what))
        .collect();
        match self.open() && FIRST + ROOM * self.longest() <= self.steps {
            true => format!(
                "{} timed on the run's first steps, the fastest kept",
                open.join(" and ")
            ),
            false => format!(
                "{} not timed (a run of {} steps or more times them)",
                open.join(" and "),
                FIRST + ROOM * self.longest()
            ),
        }
    }

    /// What the stages finished since the last call measured and kept.
    pub fn take_report(&mut self) -> Vec<String> {
        std::mem::take(&mut self.report)
    }

    /// Says the stages' lines not yet said (where `say`; else lets them go): what each timed and
    /// kept, its times with `--verbose`.
    pub fn say_report(&mut self, say: bool) {
        for line in self.take_report().into_iter().filter(|_| say) {
            crate::terminal::say_either(
                &format!("lbm-server: {} {}", brief_line(&line), crate::terminal::MORE),
                &format!("lbm-server: {line}"),
            );
        }
    }
}

/// A stage's line in brief: what it timed and what it kept, without the times ("kernels timed
/// with the covered cells redo: quads kept").
fn brief_line(line: &str) -> String {
    let what = line.split(" (").next().unwrap_or(line);
    let kept = line.rsplit(": ").next().unwrap_or("");
    format!("{what}: {kept}")
}

/// The median of `values` (NaN when empty).
fn median(values: &[f64]) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

#[cfg(test)]
mod tests;
