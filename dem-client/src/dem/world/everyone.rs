//! A fluid step whose island is every sphere (a bed, a dense suspension) can go two ways with the
//! same bits: through the island's world (`World::advance_island`: the pairs pruned to those that
//! can meet within the step, the world copied out and back) or as the whole world's DEM steps
//! with its full lists (`World::advance`). Which is faster depends on the machine: on this
//! project's 2-core VM the island's (a 32^3 bed: 150 against 285 ms a fluid step on two threads),
//! on the H200 host's 16 cores the whole world's (81 against 102 ms, code of 2026-12-03). So a
//! run times them on its own steps, as `lbm-server` times its covered-cell ways: the first
//! `TRIAL` such steps alternate (island first; the first step of each way, which may build the
//! island's world, not timed), the way with the quicker median step is kept for `KEEP` such
//! steps, then they are timed again.

/// The two ways of a fluid step whose island is every sphere.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Way {
    Island,
    Whole,
}

/// Fluid steps of a trial (alternating, island first).
pub(crate) const TRIAL: u32 = 8;
/// Fluid steps the kept way runs before the next trial.
pub(crate) const KEEP: u32 = 400;

/// The trial and the way kept (`World::everyone`).
#[derive(Debug, Clone, Default)]
pub struct Everyone {
    /// A way fixed by the caller (the tests): no trials.
    pub fixed: Option<Way>,
    kept: Option<Way>,
    /// Steps into the current trial, or since the way was kept.
    steps: u32,
    island: Vec<f64>,
    whole: Vec<f64>,
    /// Median seconds per fluid step of each way at the last trial, and the way kept.
    pub last: Option<(f64, f64, Way)>,
    /// Trials so far.
    pub trials: u32,
}

fn median(t: &mut [f64]) -> f64 {
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

impl Everyone {
    /// The way of the next fluid step whose island is every sphere.
    pub fn next(&self) -> Way {
        if let Some(way) = self.fixed.or(self.kept) {
            return way;
        }
        if self.steps.is_multiple_of(2) {
            Way::Island
        } else {
            Way::Whole
        }
    }

    /// That step went `way` in `seconds`.
    pub fn record(&mut self, way: Way, seconds: f64) {
        if self.fixed.is_some() {
            return;
        }
        if self.kept.is_some() {
            self.steps += 1;
            if self.steps >= KEEP {
                (self.kept, self.steps) = (None, 0);
            }
            return;
        }
        if self.steps >= 2 {
            match way {
                Way::Island => self.island.push(seconds),
                Way::Whole => self.whole.push(seconds),
            }
        }
        self.steps += 1;
        if self.steps == TRIAL {
            let (island, whole) = (median(&mut self.island), median(&mut self.whole));
            let way = if whole < island { Way::Whole } else { Way::Island };
            (self.kept, self.steps, self.last) = (Some(way), 0, Some((island, whole, way)));
            self.island.clear();
            self.whole.clear();
            self.trials += 1;
        }
    }
}

impl Everyone {
    /// One line on the trials, if there were any.
    pub fn summary(&self) -> Option<String> {
        let (island, whole, way) = self.last?;
        Some(format!(
            "fluid steps whose island is every sphere timed {} time(s), the last: {:.3} ms through the \
             island's world, {:.3} ms as the whole world (median of {} each): {} kept",
            self.trials,
            1e3 * island,
            1e3 * whole,
            (TRIAL - 2) / 2,
            match way {
                Way::Island => "the island's world",
                Way::Whole => "the whole world",
            }
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A trial alternates, times all but each way's first step, keeps the quicker median for
    /// KEEP steps, then tries again; a fixed way is never tried.
    #[test]
    fn a_trial_keeps_the_quicker_way_then_tries_again() {
        let mut e = Everyone::default();
        let cost = |way| if way == Way::Island { 0.010 } else { 0.004 };
        let mut ways = Vec::new();
        for k in 0..TRIAL {
            let way = e.next();
            ways.push(way);
            // A slow first step of each way (building the island's world) does not count.
            e.record(way, if k < 2 { 1.0 } else { cost(way) });
        }
        assert_eq!(ways[..4], [Way::Island, Way::Whole, Way::Island, Way::Whole]);
        assert_eq!(e.last, Some((0.010, 0.004, Way::Whole)));
        for _ in 0..KEEP {
            assert_eq!(e.next(), Way::Whole);
            e.record(Way::Whole, 0.004);
        }
        assert_eq!(e.next(), Way::Island, "the next trial");
        let mut fixed = Everyone {
            fixed: Some(Way::Island),
            ..Default::default()
        };
        for _ in 0..2 * TRIAL {
            assert_eq!(fixed.next(), Way::Island);
            fixed.record(Way::Island, 1.0);
        }
        assert_eq!(fixed.trials, 0);
    }

    /// One slow step (a neighbour-list build, the machine busy) does not decide: the median.
    #[test]
    fn one_slow_step_does_not_decide() {
        let mut e = Everyone::default();
        for k in 0..TRIAL {
            let way = e.next();
            let t = match (way, k) {
                (Way::Island, 4) => 1.0,
                (Way::Island, _) => 0.004,
                (Way::Whole, _) => 0.006,
            };
            e.record(way, t);
        }
        assert_eq!(e.last.map(|l| l.2), Some(Way::Island));
    }
}
