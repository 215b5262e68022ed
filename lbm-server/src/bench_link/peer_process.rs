//! The spawned `bench-link-peer` process that plays the fluid side of one measurement.

use super::READY;
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, ChildStdout, Command, Stdio};
use std::time::{Duration, Instant};

/// A running `bench-link-peer`; killed and reaped on drop if it has not exited by then, and
/// killed with the bench (started from its main thread) if that is killed.
pub(super) struct PeerProcess {
    child: Child,
    stdout: BufReader<ChildStdout>,
}

impl PeerProcess {
    pub(super) fn spawn(exe: &Path, args: &[String]) -> Result<Self, String> {
        let mut cmd = Command::new(exe);
        let mut child = protocol::liveness::die_with_parent(&mut cmd, libc::SIGKILL)
            .arg("bench-link-peer")
            .args(args)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .spawn()
            .map_err(|e| format!("cannot start the peer process {}: {e}", exe.display()))?;
        let stdout = child.stdout.take().expect("stdout is piped");
        Ok(Self {
            child,
            stdout: BufReader::new(stdout),
        })
    }

    /// Waits for the peer's ready line; if it ends instead, says how it ended.
    pub(super) fn wait_ready(&mut self) -> Result<(), String> {
        let mut line = String::new();
        let read = self.stdout.read_line(&mut line);
        if matches!(read, Ok(n) if n > 0) && line.trim() == READY {
            return Ok(());
        }
        let status = self
            .child
            .wait()
            .map_err(|e| format!("waiting for the peer: {e}"))?;
        Err(format!(
            "the peer process failed to start ({status}; its error is above)"
        ))
    }

    /// An error if the peer has already exited.
    pub(super) fn check_running(&mut self) -> Result<(), String> {
        match self.child.try_wait() {
            Ok(None) => Ok(()),
            Ok(Some(status)) => Err(format!("the peer process ended ({status})")),
            Err(e) => Err(format!("cannot watch the peer process: {e}")),
        }
    }

    /// Adds to `error` how the peer ended, if it ends within a moment (a closed socket can be
    /// seen a little before its process has exited).
    pub(super) fn explain(&mut self, error: String) -> String {
        let start = Instant::now();
        while start.elapsed() < Duration::from_millis(200) {
            if let Err(ended) = self.check_running() {
                return format!("{error}; {ended}");
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        error
    }

    /// Waits up to `grace` for the peer to exit by itself; an error unless it exited with 0.
    pub(super) fn finish(mut self, grace: Duration) -> Result<(), String> {
        match crate::launch::end_child(&mut self.child, grace) {
            Some(0) => Ok(()),
            Some(code) => Err(format!(
                "the peer process exited with code {code} (its error is above)"
            )),
            None => Err("the peer process did not exit by itself and was killed".into()),
        }
    }
}

impl Drop for PeerProcess {
    fn drop(&mut self) {
        if matches!(self.child.try_wait(), Ok(None)) {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

pub(super) fn peer_timeout(seconds: f64) -> Result<Duration, String> {
    Duration::try_from_secs_f64(seconds).map_err(|_| format!("--timeout = {seconds} s: must be >= 0"))
}
