//! Is the peer process alive, dead, or suspended? Both sides share memory, so they share a host
//! and a process table: `/proc/PID/stat` answers without any cooperation from the peer.

use std::time::{Duration, Instant};

/// What the process table says about a peer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ProcessState {
    Running,
    /// Stopped by a signal (SIGSTOP, SIGTSTP) or by a tracer.
    Stopped,
    /// Gone, or a zombie waiting to be reaped.
    Dead,
}

/// The fields of `/proc/PID/stat` after the parenthesised command name (which may hold spaces),
/// from the state letter (the line's third field) on; None when the process is gone.
fn stat_fields(pid: u32) -> Option<Vec<String>> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    let rest = &stat[stat.rfind(')')? + 1..];
    Some(rest.split_whitespace().map(str::to_owned).collect())
}

/// Reads the state letter of `/proc/PID/stat`.
pub fn process_state(pid: u32) -> ProcessState {
    let state = stat_fields(pid).and_then(|f| f.first().and_then(|s| s.chars().next()));
    match state {
        Some('T') | Some('t') => ProcessState::Stopped,
        Some('Z') | Some('X') | Some('x') | None => ProcessState::Dead,
        Some(_) => ProcessState::Running,
    }
}

/// The CPU time the process has used so far, all its threads (`utime + stime` of
/// `/proc/PID/stat`, in clock ticks of usually 10 ms); None when it cannot be read.
pub fn cpu_time(pid: u32) -> Option<Duration> {
    // utime and stime are the line's 14th and 15th fields, 12 and 13 after the state letter.
    let fields = stat_fields(pid)?;
    let utime: u64 = fields.get(11)?.parse().ok()?;
    let stime: u64 = fields.get(12)?.parse().ok()?;
    Some(Duration::from_secs_f64(
        (utime + stime) as f64 / clock_ticks_per_second(),
    ))
}

fn clock_ticks_per_second() -> f64 {
    // SAFETY: sysconf reads a constant of the system; it has no preconditions.
    match unsafe { libc::sysconf(libc::_SC_CLK_TCK) } {
        t if t > 0 => t as f64,
        _ => 100.0,
    }
}

/// Is a silent peer working (answering late) or idle (hung in a wait, a deadlock)? It works
/// while its CPU time grows: at least [`BUSY_SHARE`] of a core, and two clock ticks, over each
/// window of the wait.
#[derive(Debug)]
pub struct Activity {
    pid: u32,
    window: Duration,
    window_start: Instant,
    cpu_at_start: Option<Duration>,
    last_busy: Instant,
}

/// The share of one core a peer must use over a window to count as working: a waiting peer
/// (waking every 50 ms to look) uses a few thousandths.
pub const BUSY_SHARE: f64 = 0.02;

impl Activity {
    /// Watches `pid` for a wait with `timeout` that began at `since`: windows of half the timeout,
    /// 0.1 to 1 s (below 0.2 s the first window ends with the timeout), from `since`. The CPU time
    /// is read from now on: started later than `since`, the first window counts less of it.
    pub fn for_timeout(pid: u32, timeout: Duration, since: Instant) -> Self {
        Activity {
            pid,
            window: (timeout / 2).clamp(Duration::from_millis(100), Duration::from_secs(1)),
            window_start: since,
            cpu_at_start: cpu_time(pid),
            last_busy: since,
        }
    }

    /// Looks at the peer's CPU time if a window has passed; returns the end of the last window
    /// in which it worked (the start of the watch if none).
    pub fn last_busy(&mut self) -> Instant {
        let now = Instant::now();
        let span = now - self.window_start;
        if span >= self.window {
            let cpu = cpu_time(self.pid);
            if let (Some(before), Some(after)) = (self.cpu_at_start, cpu) {
                let used = after.saturating_sub(before).as_secs_f64();
                let tick = 1.0 / clock_ticks_per_second();
                if used >= (BUSY_SHARE * span.as_secs_f64()).max(2.0 * tick) {
                    self.last_busy = now;
                }
            }
            self.window_start = now;
            self.cpu_at_start = cpu;
        }
        self.last_busy
    }
}

/// Makes the process `cmd` starts receive `signal` when the thread that starts it ends (Linux's
/// `PR_SET_PDEATHSIG`), so that it does not outlive a parent that is killed (`kill -9`, a test
/// harness stopped at its timeout). The thread, not the process: start the child from a thread
/// that lives as long as the child should (the main thread of a program, the thread of a test),
/// not from a helper thread that ends first. The signal survives `exec`, not the child's own
/// forks: a shell's children are not covered. A parent that dies before the child has asked for
/// the signal fails the start, so no child is left either way.
pub fn die_with_parent(cmd: &mut std::process::Command, signal: i32) -> &mut std::process::Command {
    use std::os::unix::process::CommandExt;
    let parent = std::process::id() as libc::pid_t;
    // SAFETY: the closure runs between fork and exec and makes only async-signal-safe calls
    // (prctl, getppid) and no allocation.
    unsafe {
        cmd.pre_exec(move || {
            if libc::prctl(libc::PR_SET_PDEATHSIG, signal as libc::c_ulong) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            match libc::getppid() == parent {
                true => Ok(()),
                // Re-parented already: the parent died before the prctl above.
                false => Err(std::io::Error::from_raw_os_error(libc::ESRCH)),
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A child process that spins (a shell's endless loop) or sleeps, killed when dropped.
    struct Child(std::process::Child);

    impl Child {
        fn spinning() -> Self {
            let c = std::process::Command::new("sh")
                .args(["-c", "while :; do :; done"])
                .spawn();
            Child(c.unwrap())
        }
        fn sleeping() -> Self {
            Child(std::process::Command::new("sleep").arg("10").spawn().unwrap())
        }
    }

    impl Drop for Child {
        fn drop(&mut self) {
            let _ = self.0.kill();
            let _ = self.0.wait();
        }
    }

    #[test]
    fn a_spinning_peer_works_and_a_sleeping_one_idles() {
        let busy = Child::spinning();
        let before = cpu_time(busy.0.id()).unwrap();
        let start = Instant::now();
        let mut activity = Activity::for_timeout(busy.0.id(), Duration::from_millis(200), start);
        std::thread::sleep(Duration::from_millis(300));
        let used = cpu_time(busy.0.id()).unwrap() - before;
        assert!(used >= Duration::from_millis(30), "{used:?} of CPU in 0.3 s");
        assert!(activity.last_busy() > start, "spinning counts as working");

        let idle = Child::sleeping();
        let start = Instant::now();
        let mut activity = Activity::for_timeout(idle.0.id(), Duration::from_millis(200), start);
        std::thread::sleep(Duration::from_millis(300));
        assert!(activity.last_busy() <= start, "sleeping does not");
        assert_eq!(cpu_time(u32::MAX), None);
    }

    #[test]
    fn this_process_runs_and_a_reaped_child_is_dead() {
        assert_eq!(process_state(std::process::id()), ProcessState::Running);
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let pid = child.id();
        child.wait().unwrap();
        assert_eq!(process_state(pid), ProcessState::Dead);
    }

    #[test]
    fn a_stopped_child_is_seen_stopped_and_a_zombie_dead() {
        let mut child = std::process::Command::new("sleep").arg("10").spawn().unwrap();
        let pid = child.id();
        unsafe { libc::kill(pid as i32, libc::SIGSTOP) };
        std::thread::sleep(std::time::Duration::from_millis(100));
        assert_eq!(process_state(pid), ProcessState::Stopped);
        unsafe { libc::kill(pid as i32, libc::SIGKILL) };
        std::thread::sleep(std::time::Duration::from_millis(100));
        assert_eq!(process_state(pid), ProcessState::Dead, "zombie counts as dead");
        child.wait().unwrap();
    }

    #[test]
    fn a_child_dies_with_the_thread_that_started_it() {
        let pid = std::thread::spawn(|| {
            let mut cmd = std::process::Command::new("sleep");
            cmd.arg("30");
            die_with_parent(&mut cmd, libc::SIGKILL);
            // Not waited for: reaped by the test process's exit, or seen as a zombie.
            cmd.spawn().unwrap().id()
        })
        .join()
        .unwrap();
        let start = Instant::now();
        while process_state(pid) != ProcessState::Dead && start.elapsed() < Duration::from_secs(5) {
            std::thread::sleep(Duration::from_millis(10));
        }
        assert_eq!(
            process_state(pid),
            ProcessState::Dead,
            "sleep {pid} outlived its thread"
        );
    }

    #[test]
    fn a_child_lives_while_the_thread_that_started_it_does() {
        let mut cmd = std::process::Command::new("sleep");
        cmd.arg("30");
        let child = Child(die_with_parent(&mut cmd, libc::SIGKILL).spawn().unwrap());
        std::thread::sleep(Duration::from_millis(200));
        assert_eq!(process_state(child.0.id()), ProcessState::Running);
    }
}
