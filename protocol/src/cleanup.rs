//! Shared-memory hygiene: remove this run's files after a clean exit, and the files of runs whose
//! processes died (kill -9) at the start of the next run.

use crate::liveness::{process_state, ProcessState};
use std::path::{Path, PathBuf};

/// Every run name starts with this, followed by the pid of the process that created it.
pub const RUN_PREFIX: &str = "lbmdem_";

/// Folders where iceoryx2 keeps the files of a run (shared memory, and its root path).
fn roots() -> Vec<PathBuf> {
    let root = crate::transport::global_config().global.root_path().to_string();
    vec![PathBuf::from("/dev/shm"), PathBuf::from(root)]
}

/// Every file or folder under the roots whose name contains `needle`, deepest first.
fn entries_with(needle: &str) -> Vec<PathBuf> {
    let mut found = Vec::new();
    for root in roots() {
        walk(&root, needle, &mut found);
    }
    found
}

fn walk(dir: &Path, needle: &str, found: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if entry.file_type().is_ok_and(|t| t.is_dir()) {
            walk(&path, needle, found);
        }
        if entry.file_name().to_string_lossy().contains(needle) {
            found.push(path);
        }
    }
}

fn remove(path: &Path) {
    if path.is_dir() {
        let _ = std::fs::remove_dir_all(path);
    } else {
        let _ = std::fs::remove_file(path);
    }
}

/// Removes what is left of run `run` once its processes have ended.
pub fn remove_run(run: &str) {
    for path in entries_with(&format!("{run}_")) {
        remove(&path);
    }
}

/// The pid that created a run, from its name `lbmdem_<pid>_<nonce>`.
fn creator_pid(name: &str) -> Option<(u32, String)> {
    let start = name.find(RUN_PREFIX)?;
    let rest = &name[start + RUN_PREFIX.len()..];
    let mut parts = rest.splitn(3, '_');
    let pid = parts.next()?.parse().ok()?;
    let nonce = parts.next()?;
    Some((pid, format!("{RUN_PREFIX}{pid}_{nonce}")))
}

/// Removes the files of every run whose creating process is gone (a crashed run).
/// Returns the names of the runs cleaned.
pub fn remove_stale_runs() -> Vec<String> {
    let mut stale: Vec<String> = entries_with(RUN_PREFIX)
        .iter()
        .filter_map(|p| creator_pid(&p.file_name()?.to_string_lossy()))
        .filter(|(pid, _)| *pid != std::process::id() && process_state(*pid) == ProcessState::Dead)
        .map(|(_, run)| run)
        .collect();
    stale.sort();
    stale.dedup();
    for run in &stale {
        remove_run(run);
    }
    stale
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn creator_pid_is_read_from_file_names() {
        assert_eq!(
            creator_pid("lbmdem_123_abc_node.0_10_0.global_mgmt"),
            Some((123, "lbmdem_123_abc".to_string()))
        );
        assert_eq!(creator_pid("iox2_foo"), None);
    }
}
