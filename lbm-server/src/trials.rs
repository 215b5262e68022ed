//! `coupling.covered_cells = "timed"` (and "auto" on a GPU): the ways of giving the covered cells
//! their solid term (redo, skip, fused: docs/imb.md "Speed") leave the same populations and loads
//! bit for bit, so a run times each on its own steps, in the lockstep with its DEM, and keeps the
//! fastest. Which is fastest depends on the device (a GPU or a CPU driver), the grid, the
//! particles (how many cells they cover: a suspension settling into a bed changes it) and how
//! long the DEM's step is (the redo and skip run the fluid kernels while the DEM steps): timed,
//! not guessed.
//!
//! A trial runs each way for [`BLOCK`] steps, [`ROUNDS`] times, the order turned by one each
//! round; a block's first step is not timed (its wait includes the previous way's last fluid
//! kernels, and it builds the way the first time). A step's time is from its start to the next
//! step's, the DEM's step included. The way whose median step is the quickest is kept until the
//! next trial, [`EVERY`] steps after this one began. A trial starts only where the run has room
//! for [`ROOM`] trials' length after it and, with `auto`, where the steps left would take
//! [`AUTO_MIN_SECONDS`] at the pace so far; before the first (the first [`FIRST`] steps, with the
//! face ramp and the first allocations) and in shorter runs the run keeps the way `auto` takes by
//! the covered fraction (`CoveredCells::for_scene`).

use crate::lbm::imb::CoveredCells;

/// The ways a trial times, in the order of its first round.
pub const WAYS: [CoveredCells; 3] = [CoveredCells::Redo, CoveredCells::Skip, CoveredCells::Fused];
/// Steps per way and round; the first of them is not timed.
pub const BLOCK: u64 = 6;
/// Rounds of a trial.
pub const ROUNDS: u64 = 3;
/// The step at which the first trial starts.
pub const FIRST: u64 = 10;
/// Steps from the start of one trial to the start of the next (more than a trial's length).
pub const EVERY: u64 = 2000;
/// A trial starts only where the steps from its start hold this many trials' length.
pub const ROOM: u64 = 4;
/// With `auto` a trial starts only where the steps left would take this long at the speed of the
/// steps so far: building the two other ways' kernels costs a run about 1 s each on lavapipe (on
/// a GPU not yet measured), which a shorter run does not win back.
pub const AUTO_MIN_SECONDS: f64 = 10.0;

/// Steps one trial takes.
pub const fn trial_steps() -> u64 {
    WAYS.len() as u64 * BLOCK * ROUNDS
}

/// The trials of a run: which way each step takes, from the times at which the steps start.
#[derive(Debug, Clone)]
pub struct WayTrials {
    /// The way kept outside the trials.
    kept: CoveredCells,
    /// Steps of the run.
    steps: u64,
    /// A trial starts only where the steps left would take this long (seconds).
    min_seconds: f64,
    /// When step 1 started: the run's pace from there (step 0 builds and uploads).
    step_one: Option<f64>,
    /// The step at which the current or next trial starts.
    start: u64,
    /// The timed steps' seconds of each way (index in [`WAYS`]) so far in the trial.
    times: [Vec<f64>; WAYS.len()],
    /// The last step if the trial times it: its way (index in [`WAYS`]) and when it started.
    timing: Option<(usize, f64)>,
    /// What the last finished trial measured, for the run's log (taken once).
    report: Option<String>,
    /// The ways the device did not build (index in [`WAYS`]): left out of the trials.
    refused: [bool; WAYS.len()],
}

impl WayTrials {
    /// Trials for a run of `steps` steps that starts with the way `kept`, each where the steps
    /// left would take at least `min_seconds` at the pace of the steps so far.
    pub fn new(kept: CoveredCells, steps: u64, min_seconds: f64) -> WayTrials {
        WayTrials {
            kept: kept.definite(),
            steps,
            min_seconds,
            step_one: None,
            start: FIRST,
            times: Default::default(),
            timing: None,
            report: None,
            refused: [false; WAYS.len()],
        }
    }

    /// The way the run keeps between trials now.
    pub fn kept(&self) -> CoveredCells {
        self.kept
    }

    /// The way step `step` (0 for the first; called for every step in order) takes, told that
    /// it starts at `now` (seconds on a clock that only goes forward).
    pub fn way_for(&mut self, step: u64, now: f64) -> CoveredCells {
        if step == 1 {
            self.step_one = Some(now);
        }
        // The step before, timed, lasted until now.
        if let Some((k, from)) = self.timing.take() {
            self.times[k].push(now - from);
        }
        if step.wrapping_sub(self.start) == trial_steps() {
            self.decide();
            self.start += EVERY;
        }
        let at = step.wrapping_sub(self.start);
        if at == 0 && !self.worth_a_trial(step, now) {
            self.start += EVERY;
            return self.kept;
        }
        if at >= trial_steps() {
            return self.kept;
        }
        let way = self.way_of_block(at / BLOCK);
        let k = index(way);
        if self.refused[k] {
            return self.kept;
        }
        if !at.is_multiple_of(BLOCK) {
            self.timing = Some((k, now));
        }
        way
    }

    /// Leaves `way` out of this trial and every later one (the device did not build it): the step
    /// that asked for it is not timed.
    pub fn refuse(&mut self, way: CoveredCells) {
        self.refused[index(way)] = true;
        self.timing = None;
    }

    /// Whether a trial starting at `step` (at `now`) fits the run: [`ROOM`] trials' length of
    /// steps ahead, and the steps left taking at least `min_seconds` at the pace since step 1.
    fn worth_a_trial(&self, step: u64, now: f64) -> bool {
        if step + ROOM * trial_steps() > self.steps {
            return false;
        }
        let pace = match self.step_one {
            Some(one) if step > 1 => (now - one) / (step - 1) as f64,
            _ => f64::INFINITY,
        };
        (self.steps - step) as f64 * pace >= self.min_seconds
    }

    /// The way of a trial's block: round r takes the ways turned by r.
    fn way_of_block(&self, block: u64) -> CoveredCells {
        let n = WAYS.len() as u64;
        let (round, k) = (block / n, block % n);
        WAYS[((k + round) % n) as usize]
    }

    /// Keeps the way of the lowest median step and clears the times for the next trial. A median,
    /// not a mean: a step that also wrote particles.csv, checked the lattice's health or waited
    /// for a DEM's neighbour-list build is a few of each way's, not its typical step.
    fn decide(&mut self) {
        let medians: Vec<f64> = self.times.iter().map(|t| median(t)).collect();
        let best = (0..WAYS.len())
            .filter(|&k| medians[k].is_finite())
            .min_by(|&a, &b| medians[a].total_cmp(&medians[b]));
        if let Some(best) = best {
            self.kept = WAYS[best];
        }
        let each: Vec<String> = WAYS
            .iter()
            .zip(&medians)
            .zip(self.refused)
            .map(|((w, m), refused)| match refused {
                true => format!("{} not built", w.name()),
                false => format!("{} {:.3} ms", w.name(), m * 1e3),
            })
            .collect();
        self.report = Some(format!(
            "covered cells timed at steps {}-{} (median of {} steps each): {} per step: {} kept",
            self.start,
            self.start + trial_steps() - 1,
            (BLOCK - 1) * ROUNDS,
            each.join(", "),
            self.kept.name()
        ));
        self.times = Default::default();
    }

    /// The run's first line's words for the trials.
    pub fn describe(&self) -> String {
        if self.min_seconds > 0.0 {
            format!(
                "the ways timed on the run's steps where {} s of them are left, the fastest kept",
                self.min_seconds
            )
        } else {
            "the ways timed on the run's steps, the fastest kept".into()
        }
    }

    /// What the last trial measured and kept, once.
    pub fn take_report(&mut self) -> Option<String> {
        self.report.take()
    }
}

/// The index of a trial's way in [`WAYS`].
fn index(way: CoveredCells) -> usize {
    WAYS.iter().position(|&w| w == way).expect("a trial's way")
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
mod tests {
    use super::*;

    /// Runs `steps` steps of trials started with `kept`, each step lasting `cost(step, way)`
    /// seconds plus `switch` seconds when its way differs from the previous step's; the ways taken
    /// and the trials' reports.
    fn run(
        kept: CoveredCells,
        steps: u64,
        cost: impl Fn(u64, CoveredCells) -> f64,
        switch: f64,
    ) -> (Vec<CoveredCells>, Vec<String>) {
        run_for(kept, steps, cost, switch, 0.0)
    }

    /// `run` with trials only where the steps left take `min_seconds`.
    fn run_for(
        kept: CoveredCells,
        steps: u64,
        cost: impl Fn(u64, CoveredCells) -> f64,
        switch: f64,
        min_seconds: f64,
    ) -> (Vec<CoveredCells>, Vec<String>) {
        let mut trials = WayTrials::new(kept, steps, min_seconds);
        let (mut now, mut ways, mut reports) = (0.0, Vec::new(), Vec::new());
        for step in 0..steps {
            let way = trials.way_for(step, now);
            reports.extend(trials.take_report());
            if ways.last().is_some_and(|&last| last != way) {
                now += switch;
            }
            now += cost(step, way);
            ways.push(way);
        }
        (ways, reports)
    }

    fn ms(way: CoveredCells, redo: f64, skip: f64, fused: f64) -> f64 {
        1e-3 * match way {
            CoveredCells::Skip => skip,
            CoveredCells::Fused => fused,
            _ => redo,
        }
    }

    /// The first trial starts at step FIRST, takes each way BLOCK steps a round in turned order,
    /// and keeps the fastest (skip here) from its end; the first step of each block, slowed by
    /// the change of way, is not what decides.
    #[test]
    fn a_trial_keeps_the_fastest_way() {
        let (ways, reports) = run(CoveredCells::Redo, 600, |_, w| ms(w, 2.0, 1.5, 3.0), 0.05);
        let (redo, skip, fused) = (CoveredCells::Redo, CoveredCells::Skip, CoveredCells::Fused);
        assert!(ways[..FIRST as usize].iter().all(|&w| w == redo));
        let blocks: Vec<CoveredCells> = (0..9).map(|b| ways[(FIRST + b * BLOCK) as usize]).collect();
        assert_eq!(blocks, [redo, skip, fused, skip, fused, redo, fused, redo, skip]);
        for b in 0..9 {
            let block = &ways[(FIRST + b * BLOCK) as usize..(FIRST + (b + 1) * BLOCK) as usize];
            assert!(block.iter().all(|&w| w == blocks[b as usize]), "block {b}");
        }
        let after = (FIRST + trial_steps()) as usize;
        assert!(
            ways[after..].iter().all(|&w| w == skip),
            "skip kept after the trial"
        );
        assert_eq!(reports.len(), 1, "{reports:?}");
        let r = &reports[0];
        assert!(
            r.contains("redo 2.000 ms, skip 1.500 ms, fused 3.000 ms") && r.ends_with("skip kept"),
            "{r}"
        );
    }

    /// A change of way that costs more than the ways differ by does not decide either: the
    /// block's first step is left out.
    #[test]
    fn the_cost_of_changing_ways_is_left_out() {
        let (ways, _) = run(CoveredCells::Skip, 600, |_, w| ms(w, 1.0, 1.2, 1.1), 10.0);
        assert_eq!(ways[599], CoveredCells::Redo);
    }

    /// Later trials follow the particles: the fastest way changes at step 1000, the trial at
    /// FIRST + EVERY finds it.
    #[test]
    fn a_later_trial_follows_a_change() {
        let cost = |step: u64, w| {
            if step < 1000 {
                ms(w, 1.0, 2.0, 3.0)
            } else {
                ms(w, 3.0, 2.0, 1.0)
            }
        };
        let (ways, reports) = run(CoveredCells::Skip, 5000, cost, 0.0);
        let second = (FIRST + EVERY) as usize;
        assert_eq!(ways[second - 1], CoveredCells::Redo);
        assert_eq!(ways[second + trial_steps() as usize], CoveredCells::Fused);
        assert_eq!(
            reports.len(),
            3,
            "trials at FIRST, FIRST + EVERY, FIRST + 2 EVERY"
        );
    }

    /// A run too short for a trial and the room after it keeps its way throughout; so does one
    /// whose second trial would not fit.
    #[test]
    fn a_short_run_keeps_its_way() {
        let steps = FIRST + ROOM * trial_steps() - 1;
        let (ways, reports) = run(CoveredCells::Fused, steps, |_, w| ms(w, 1.0, 2.0, 3.0), 0.0);
        assert!(ways.iter().all(|&w| w == CoveredCells::Fused) && reports.is_empty());
        let steps = FIRST + EVERY + ROOM * trial_steps() - 1;
        let (ways, reports) = run(CoveredCells::Fused, steps, |_, w| ms(w, 1.0, 2.0, 3.0), 0.0);
        assert_eq!(reports.len(), 1);
        let after = (FIRST + trial_steps()) as usize;
        assert!(ways[after..].iter().all(|&w| w == CoveredCells::Redo));
    }

    /// With a minimum run time (auto), a run whose steps left take less at its pace has no trial,
    /// and one that takes longer has.
    #[test]
    fn a_quick_run_has_no_trial_with_a_minimum_time() {
        let cost = |_, w| ms(w, 2.0, 1.0, 3.0);
        let (ways, reports) = run_for(CoveredCells::Redo, 4000, cost, 0.0, 10.0);
        assert!(ways.iter().all(|&w| w == CoveredCells::Redo) && reports.is_empty());
        let (ways, reports) = run_for(CoveredCells::Redo, 6000, cost, 0.0, 10.0);
        assert_eq!(
            reports.len(),
            1,
            "only the first trial has 10 s ahead: {reports:?}"
        );
        assert_eq!(ways[5999], CoveredCells::Skip);
    }

    /// A slow step now and then (particles.csv written every 10 steps, 25 times a step's time)
    /// does not decide: each way's median step does.
    #[test]
    fn an_occasional_slow_step_does_not_decide() {
        let cost = |step: u64, w| ms(w, 2.0, 1.8, 3.0) + if step.is_multiple_of(10) { 0.05 } else { 0.0 };
        let (ways, reports) = run(CoveredCells::Redo, 600, cost, 0.0);
        assert_eq!(ways[599], CoveredCells::Skip, "{reports:?}");
        assert!(
            reports[0].contains("redo 2.000 ms, skip 1.800 ms, fused 3.000 ms"),
            "{reports:?}"
        );
    }

    /// A way the device does not build is refused at its first block: it is not asked for again,
    /// its steps take the kept way untimed, the others decide, and the report says so.
    #[test]
    fn a_way_not_built_is_left_out() {
        let mut trials = WayTrials::new(CoveredCells::Redo, 600, 0.0);
        let (mut now, mut asked, mut reports) = (0.0, Vec::new(), Vec::new());
        let mut current = CoveredCells::Redo;
        for step in 0..600 {
            let way = trials.way_for(step, now);
            reports.extend(trials.take_report());
            asked.push(way);
            if way == CoveredCells::Fused {
                trials.refuse(way);
            } else {
                current = way;
            }
            now += ms(current, 2.0, 1.5, 0.5);
        }
        assert_eq!(asked.iter().filter(|&&w| w == CoveredCells::Fused).count(), 1);
        assert_eq!(asked[599], CoveredCells::Skip);
        assert!(
            reports.len() == 1 && reports[0].contains("skip 1.500 ms, fused not built"),
            "{reports:?}"
        );
    }
}
