//! What a run says on the terminal (stderr): a short header, a progress line (a bar on a
//! terminal, a line every 2 s otherwise) and a last line. The long explanations are said once, in
//! a line each that points at `--verbose`; with `lbm-server run --verbose` they are said in full:
//! each warning's measurements and remedies, the run's full settings, each trial's times, each
//! health check's dropped covers (and the DEM's step limits and figures, `dem-client connect
//! --verbose`).

use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Whether the run says everything (`--verbose`).
static VERBOSE: AtomicBool = AtomicBool::new(false);

/// The progress bar while one is drawn: lines are said above it.
static BAR: Mutex<Option<indicatif::ProgressBar>> = Mutex::new(None);

/// What a brief line adds to point at the whole explanation.
pub const MORE: &str = "(--verbose says more)";

pub fn set_verbose(on: bool) {
    VERBOSE.store(on, Ordering::Relaxed);
}

pub fn verbose() -> bool {
    VERBOSE.load(Ordering::Relaxed)
}

/// Says one line, above the progress bar where one is drawn.
pub fn say(line: &str) {
    let bar = BAR.lock().ok().and_then(|b| b.clone());
    match bar {
        Some(bar) => bar.suspend(|| protocol::write_line(line)),
        None => protocol::write_line(line),
    }
}

/// Says `brief`, or with `--verbose` `full`.
pub fn say_either(brief: &str, full: &str) {
    say(if verbose() { full } else { brief });
}

/// A time in seconds for a line: three decimals, or three significant digits below 0.01 s.
pub fn seconds(t: f64) -> String {
    if t >= 0.01 {
        format!("{t:.3}")
    } else {
        format!("{t:.3e}")
    }
}

/// A warning of a run's settings: one line, and the whole explanation (what was measured, where,
/// and what to change).
#[derive(Debug, Clone, PartialEq)]
pub struct Warning {
    pub brief: String,
    pub full: String,
}

impl Warning {
    /// Says the warning: its line pointing at `--verbose`, or with `--verbose` in full.
    pub fn say(&self) {
        say_either(
            &format!("lbm-server: warning: {} {MORE}", self.brief),
            &format!("lbm-server: warning: {}", self.full),
        );
    }
}

/// A progress bar on a terminal, plain periodic log lines otherwise.
pub struct Progress {
    bar: Option<indicatif::ProgressBar>,
    total: u64,
    start: Instant,
    last_log: Instant,
}

/// Seconds between two plain log lines.
const LOG_EVERY: Duration = Duration::from_secs(2);

impl Progress {
    pub fn new(total: u64) -> Self {
        let bar = std::io::stderr().is_terminal().then(|| {
            let bar = indicatif::ProgressBar::new(total);
            let style = indicatif::ProgressStyle::with_template(
                "{bar:40} {pos}/{len} steps  {per_sec}  ETA {eta}  {msg}",
            )
            .expect("valid template");
            bar.set_style(style);
            bar
        });
        if let Ok(mut drawn) = BAR.lock() {
            drawn.clone_from(&bar);
        }
        let now = Instant::now();
        Self {
            bar,
            total,
            start: now,
            last_log: now,
        }
    }

    /// Records that `done` steps have completed.
    pub fn update(&mut self, done: u64) {
        if let Some(bar) = &self.bar {
            if !bar.is_finished() {
                bar.set_position(done);
            }
        } else if self.last_log.elapsed() >= LOG_EVERY || done == self.total {
            self.last_log = Instant::now();
            let rate = done as f64 / self.start.elapsed().as_secs_f64().max(1e-9);
            let eta = (self.total - done) as f64 / rate.max(1e-9);
            protocol::say!(
                "lbm-server: step {done}/{} ({:.0}%), {rate:.0} steps/s, ETA {eta:.1} s",
                self.total,
                100.0 * done as f64 / self.total as f64
            );
        }
    }

    /// Takes the bar off the terminal (the run's last line says how it went): before the reply
    /// that ends the run, so that the DEM's last line comes below it.
    pub fn finish(&self) {
        if let Some(bar) = self.bar.as_ref().filter(|b| !b.is_finished()) {
            bar.finish_and_clear();
        }
        if let Ok(mut drawn) = BAR.lock() {
            *drawn = None;
        }
    }
}

impl Progress {
    /// Leaves the bar at the step where a run stopped early, unless it has left the terminal.
    pub fn abandon(&self) {
        if let Some(bar) = self.bar.as_ref().filter(|b| !b.is_finished()) {
            bar.abandon();
        }
        if let Ok(mut drawn) = BAR.lock() {
            *drawn = None;
        }
    }
}

impl Drop for Progress {
    /// A run that fails leaves its bar where it stopped, and the error below it.
    fn drop(&mut self) {
        if let Some(bar) = self.bar.as_ref().filter(|b| !b.is_finished()) {
            bar.abandon();
        }
        if let Ok(mut drawn) = BAR.lock() {
            *drawn = None;
        }
    }
}
