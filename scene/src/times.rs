//! Times a scene may give in seconds instead of steps: `time.duration` for `time.steps`,
//! `output.time_interval` for `output.interval`, `output.fields_time_interval` for
//! `output.fields_interval`, `output.checkpoint_time_interval` for `output.checkpoint_interval`. With a `[lattice]` the time step is derived, so a count of steps is
//! not something a user can write down before the first run; a time is. Each becomes a whole
//! number of steps of `time.dt`: the duration the steps that cover it, an interval the nearest.

use crate::{default_interval, Scene, SceneError};

/// Most steps a time may stand for (a typo of a few orders of magnitude, not a run).
pub(crate) const MOST_STEPS: f64 = 1e12;

/// How a time becomes steps.
#[derive(Clone, Copy)]
enum Round {
    /// The steps that cover it (a duration).
    Up,
    /// The nearest whole number, at least one (an interval).
    Nearest,
}

/// A count of steps that a scene gives either as steps or as a time.
struct Either<'a> {
    steps_field: &'a str,
    steps: Option<u64>,
    time_field: &'a str,
    time: Option<f64>,
    round: Round,
}

impl Scene {
    /// Resolves `time.steps`, `output.interval` and `output.fields_interval` from what the scene
    /// gives, now that `time.dt` is known (derived from the lattice, or given). A bad `time.dt`
    /// is left to `validate`, which names it.
    pub(crate) fn resolve_steps(&mut self, file: &str) -> Result<(), SceneError> {
        let dt = self.time.dt;
        if !(dt.is_finite() && dt > 0.0) {
            return Ok(());
        }
        let run = Either {
            steps_field: "time.steps",
            steps: self.time.given_steps,
            time_field: "time.duration",
            time: self.time.duration,
            round: Round::Up,
        };
        self.time.steps = run.resolve(dt, file)?.ok_or_else(|| SceneError {
            file: file.into(),
            field: "time.steps".into(),
            value: "missing".into(),
            problem: "give the run's length: time.steps (coupled steps) or time.duration [s]".into(),
        })?;
        let rows = Either {
            steps_field: "output.interval",
            steps: self.output.given_interval,
            time_field: "output.time_interval",
            time: self.output.time_interval,
            round: Round::Nearest,
        };
        self.output.interval = rows.resolve(dt, file)?.unwrap_or_else(default_interval);
        let snapshots = Either {
            steps_field: "output.fields_interval",
            steps: self.output.given_fields_interval,
            time_field: "output.fields_time_interval",
            time: self.output.fields_time_interval,
            round: Round::Nearest,
        };
        self.output.fields_interval = snapshots.resolve(dt, file)?.unwrap_or(0);
        let checkpoints = Either {
            steps_field: "output.checkpoint_interval",
            steps: self.output.given_checkpoint_interval,
            time_field: "output.checkpoint_time_interval",
            time: self.output.checkpoint_time_interval,
            round: Round::Nearest,
        };
        self.output.checkpoint_interval = checkpoints.resolve(dt, file)?.unwrap_or(0);
        Ok(())
    }
}

impl Scene {
    /// The steps of `time.dt` that cover `duration` seconds, as `time.duration` gives them; a
    /// bad duration is refused naming `field` (e.g. a command-line option).
    pub fn steps_covering(&self, duration: f64, field: &str) -> Result<u64, String> {
        let run = Either {
            steps_field: "",
            steps: None,
            time_field: field,
            time: Some(duration),
            round: Round::Up,
        };
        let steps = run
            .resolve(self.time.dt, "")
            .map_err(|e| format!("{} = {}: {}", e.field, e.value, e.problem))?;
        Ok(steps.expect("a duration given"))
    }
}

impl Either<'_> {
    /// The steps given, or those of the time given; None when neither is.
    fn resolve(&self, dt: f64, file: &str) -> Result<Option<u64>, SceneError> {
        let fail = |time: f64, problem: String| SceneError {
            file: file.into(),
            field: self.time_field.into(),
            value: format!("{time} s"),
            problem,
        };
        match (self.steps, self.time) {
            (Some(_), Some(time)) => Err(fail(
                time,
                format!("{} is given too: give one of them", self.steps_field),
            )),
            (Some(n), None) => Ok(Some(n)),
            (None, None) => Ok(None),
            (None, Some(time)) => {
                if !(time.is_finite() && time > 0.0) {
                    return Err(fail(time, "must be a finite number > 0".into()));
                }
                let steps = steps_of(time, dt, self.round);
                if steps < 1.0 {
                    return Err(fail(
                        time,
                        format!("is shorter than half a step (time.dt = {dt:e} s): give at least {dt:e} s"),
                    ));
                }
                if steps > MOST_STEPS {
                    return Err(fail(time, format!("is {steps:e} steps of {dt:e} s: too many")));
                }
                Ok(Some(steps as u64))
            }
        }
    }
}

/// `time` in steps of `dt`, rounded as `round` says; a quotient within 1e-9 of a whole number
/// is that number (0.3 s in steps of 0.1 s is 3 steps, not 4).
fn steps_of(time: f64, dt: f64, round: Round) -> f64 {
    let q = time / dt;
    if (q - q.round()).abs() <= 1e-9 * q.max(1.0) {
        return q.round();
    }
    match round {
        Round::Up => q.ceil(),
        Round::Nearest => q.round(),
    }
}

#[cfg(test)]
mod tests {
    use crate::{Scene, DEFAULT_SCENE};

    fn with(from: &str, to: &str) -> Result<Scene, String> {
        assert!(DEFAULT_SCENE.contains(from), "{from}");
        Scene::parse(&DEFAULT_SCENE.replacen(from, to, 1), "s.toml").map_err(|e| e.to_string())
    }

    const STEPS: &str = "steps = 1150 ";
    const ROWS: &str = "interval = 20 ";

    /// The default scene's dt is 0.56269 ms: 0.65 s is 1155.2 steps, so the run takes 1156; a row
    /// every 0.02 s is every 36 steps (35.5), a snapshot every 0.1 s every 178 (177.7).
    #[test]
    fn times_in_seconds_become_whole_steps() {
        let scene = with(STEPS, "duration = 0.65 ").unwrap();
        let dt = scene.time.dt;
        assert!((dt - 5.6268601e-4).abs() < 1e-10, "{dt}");
        assert_eq!(scene.time.steps, 1156);
        let scene = with(ROWS, "time_interval = 0.02\nfields_time_interval = 0.1 ").unwrap();
        assert_eq!(
            (
                scene.time.steps,
                scene.output.interval,
                scene.output.fields_interval
            ),
            (1150, 36, 178)
        );
        // A duration of exactly n steps is n steps, not n + 1.
        let exact = format!("duration = {:.17e} ", 300.0 * dt);
        assert_eq!(with(STEPS, &exact).unwrap().time.steps, 300);
        // Given as steps, as before; the intervals' defaults.
        let scene = with(ROWS, "").unwrap();
        assert_eq!(
            (
                scene.time.steps,
                scene.output.interval,
                scene.output.fields_interval
            ),
            (1150, 100, 0)
        );
    }

    /// `--duration` on the command line: the steps that cover it, a bad one named by the option.
    #[test]
    fn a_duration_given_apart_from_the_scene_is_the_steps_that_cover_it() {
        let scene = with(STEPS, STEPS).unwrap();
        assert_eq!(scene.steps_covering(0.65, "--duration"), Ok(1156));
        assert_eq!(
            scene.steps_covering(-1.0, "--duration"),
            Err("--duration = -1 s: must be a finite number > 0".to_string())
        );
    }

    #[test]
    fn a_time_and_its_steps_are_refused_together_and_bad_times_named() {
        let cases = [
            (STEPS, "steps = 1150\nduration = 1.0 ", "time.duration = 1 s: time.steps is given too"),
            (STEPS, "", "time.steps = missing: give the run's length: time.steps (coupled steps) or time.duration [s]"),
            (STEPS, "duration = -1.0 ", "time.duration = -1 s: must be a finite number > 0"),
            (STEPS, "duration = 1e20 ", "time.duration = 100000000000000000000 s: is 1.77719"),
            (ROWS, "interval = 20\ntime_interval = 0.02 ", "output.time_interval = 0.02 s: output.interval is given too"),
            (ROWS, "time_interval = 0.0002 ", "output.time_interval = 0.0002 s: is shorter than half a step (time.dt = 5.6268"),
            (ROWS, "fields_interval = 5\nfields_time_interval = 0.1 ", "output.fields_time_interval = 0.1 s: output.fields_interval is given too"),
            (ROWS, "fields_time_interval = nan ", "output.fields_time_interval = NaN s"),
        ];
        for (from, to, expected) in cases {
            let err = with(from, to).expect_err(to);
            assert!(err.contains(expected), "{to}: expected {expected:?} in {err}");
        }
    }
}
