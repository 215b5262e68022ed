//! The Unix-socket transport of `bench-link`: the DEM end writes the states into a buffer the
//! kernel copies, the fluid end (the peer) answers each step until the socket closes.

use super::peer_process::{peer_timeout, PeerProcess};
use super::{reply_for, state, time_rounds, touch_replies, PeerArgs, Plan, RoundTrip};
use protocol::transport::new_run_name;
use protocol::{ParticleReply, ParticleState, StepHeader};
use std::io::{IoSlice, Read, Write};
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// The DEM end of the socket link, with buffers reused across rounds.
struct SocketBench {
    stream: UnixStream,
    states: Vec<ParticleState>,
    replies: Vec<ParticleReply>,
}

impl RoundTrip for SocketBench {
    fn round(&mut self, step: u64) -> Result<(), String> {
        let n = self.states.len();
        for (i, s) in self.states.iter_mut().enumerate() {
            *s = state(i, step);
        }
        let header = StepHeader::new(step, 0.0, n, 0);
        let io = |e: std::io::Error| format!("Unix socket, step {step}: {e}");
        write_parts(
            &mut self.stream,
            [bytemuck::bytes_of(&header), bytemuck::cast_slice(&self.states)],
        )
        .map_err(io)?;
        let mut back = StepHeader::default();
        self.stream
            .read_exact(bytemuck::bytes_of_mut(&mut back))
            .map_err(io)?;
        if back.step != step || back.count != n as u64 {
            return Err(format!(
                "Unix socket: step {step} of {n} answered as step {} of {}",
                back.step, back.count
            ));
        }
        self.stream
            .read_exact(bytemuck::cast_slice_mut(&mut self.replies))
            .map_err(io)?;
        touch_replies(&self.replies, n)
    }
}

/// Times `rounds` rounds of `n` particles over a Unix socket against a spawned peer.
pub(super) fn measure_socket(plan: &Plan, n: usize, rounds: usize) -> Result<Vec<f64>, String> {
    let dir = TempDir::create()?;
    let path = dir.0.join("link.sock");
    let listener =
        UnixListener::bind(&path).map_err(|e| format!("cannot listen on {}: {e}", path.display()))?;
    let mut peer = PeerProcess::spawn(
        &plan.exe,
        &[
            "--socket".into(),
            path.display().to_string(),
            "--capacity".into(),
            n.to_string(),
            "--timeout".into(),
            plan.timeout.as_secs_f64().to_string(),
        ],
    )?;
    let stream = accept_peer(&listener, &mut peer, plan.timeout)?;
    let mut bench = SocketBench {
        stream,
        states: vec![ParticleState::default(); n],
        replies: vec![ParticleReply::default(); n],
    };
    let times = time_rounds(&mut bench, plan.warmup, rounds).map_err(|e| peer.explain(e))?;
    drop(bench); // end of stream: the peer exits
    peer.finish(plan.timeout)?;
    Ok(times)
}

/// Waits for the peer to connect, noticing if it exits first.
fn accept_peer(
    listener: &UnixListener,
    peer: &mut PeerProcess,
    timeout: Duration,
) -> Result<UnixStream, String> {
    let failed = |e: std::io::Error| format!("Unix socket: accept failed: {e}");
    listener.set_nonblocking(true).map_err(failed)?;
    let start = Instant::now();
    loop {
        match listener.accept() {
            Ok((stream, _)) => {
                stream.set_nonblocking(false).map_err(failed)?;
                stream.set_read_timeout(Some(timeout)).map_err(failed)?;
                return Ok(stream);
            }
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {}
            Err(e) => return Err(failed(e)),
        }
        peer.check_running()?;
        if start.elapsed() >= timeout {
            return Err(format!(
                "the peer did not connect within {:.1} s",
                timeout.as_secs_f64()
            ));
        }
        std::thread::sleep(Duration::from_millis(1));
    }
}

/// The fluid end of the socket link: answers each step until the benchmark closes the socket.
pub(super) fn serve_socket(path: &Path, args: &PeerArgs) -> Result<(), String> {
    let timeout = peer_timeout(args.timeout)?;
    let mut stream =
        UnixStream::connect(path).map_err(|e| format!("cannot connect to {}: {e}", path.display()))?;
    stream
        .set_read_timeout(Some(timeout))
        .map_err(|e| e.to_string())?;
    let mut states = Vec::with_capacity(args.capacity);
    let mut replies = Vec::with_capacity(args.capacity);
    let mut header = StepHeader::default();
    loop {
        match stream.read_exact(bytemuck::bytes_of_mut(&mut header)) {
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => return Ok(()),
            other => other.map_err(|e| format!("reading a step header: {e}"))?,
        }
        let n = header.count as usize;
        if n > args.capacity {
            return Err(format!(
                "step {} carries {n} particles, capacity {}",
                header.step, args.capacity
            ));
        }
        states.resize(n, ParticleState::default());
        stream
            .read_exact(bytemuck::cast_slice_mut(&mut states))
            .map_err(|e| format!("reading step {}: {e}", header.step))?;
        replies.clear();
        replies.extend(states.iter().map(reply_for));
        let back = StepHeader::new(header.step, header.time, n, 0);
        write_parts(
            &mut stream,
            [bytemuck::bytes_of(&back), bytemuck::cast_slice(&replies)],
        )
        .map_err(|e| format!("answering step {}: {e}", header.step))?;
    }
}

/// Writes both parts with as few system calls as the socket allows (one, if its buffer has room).
fn write_parts(stream: &mut UnixStream, parts: [&[u8]; 2]) -> std::io::Result<()> {
    let mut slices = parts.map(IoSlice::new);
    let mut rest = &mut slices[..];
    while !rest.is_empty() {
        match stream.write_vectored(rest) {
            Ok(0) => return Err(std::io::ErrorKind::WriteZero.into()),
            Ok(written) => IoSlice::advance_slices(&mut rest, written),
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(())
}

/// A private folder for the socket, removed on drop.
struct TempDir(PathBuf);

impl TempDir {
    fn create() -> Result<Self, String> {
        let path = std::env::temp_dir().join(format!("lbm-bench-link-{}", new_run_name()));
        std::fs::create_dir(&path).map_err(|e| format!("cannot create {}: {e}", path.display()))?;
        Ok(Self(path))
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_views_cover_the_whole_struct() {
        let mut header = StepHeader::new(3, 0.5, 7, 0);
        assert_eq!(bytemuck::bytes_of(&header).len(), 32);
        bytemuck::bytes_of_mut(&mut header)[..8].copy_from_slice(&9u64.to_ne_bytes());
        assert_eq!(header.step, 9);
    }
}
