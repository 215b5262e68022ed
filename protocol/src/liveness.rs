//! Is the peer process alive, dead, or suspended? Both sides share memory, so they share a host
//! and a process table: `/proc/PID/stat` answers without any cooperation from the peer.

/// What the process table says about a peer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ProcessState {
    Running,
    /// Stopped by a signal (SIGSTOP, SIGTSTP) or by a tracer.
    Stopped,
    /// Gone, or a zombie waiting to be reaped.
    Dead,
}

/// Reads the state letter of `/proc/PID/stat` (the field after the parenthesised command name).
pub fn process_state(pid: u32) -> ProcessState {
    let Ok(stat) = std::fs::read_to_string(format!("/proc/{pid}/stat")) else {
        return ProcessState::Dead;
    };
    let state = stat
        .rfind(')')
        .and_then(|i| stat[i + 1..].trim_start().chars().next());
    match state {
        Some('T') | Some('t') => ProcessState::Stopped,
        Some('Z') | Some('X') | Some('x') | None => ProcessState::Dead,
        Some(_) => ProcessState::Running,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
