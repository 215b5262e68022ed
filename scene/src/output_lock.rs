//! One run per output folder: a run holds an OS lock on OUT/.lock (flock on Unix) for as long as
//! it runs, with its pid written inside; a second run into the same folder is refused, naming the
//! first. The lock goes with the process that holds it, so a crashed run's lock blocks nothing;
//! the file stays behind (removing it would let two runs lock two different files of one name).

use std::fs::{File, OpenOptions, TryLockError};
use std::io::{Read, Seek, Write};
use std::path::Path;

/// The lock file's name in an output folder.
pub const LOCK_FILE: &str = ".lock";

/// The lock of an output folder, held until dropped.
#[derive(Debug)]
pub struct OutputLock {
    _file: File,
}

impl OutputLock {
    /// Locks the folder `out` (which must exist) for this process, or says which process holds it.
    pub fn take(out: &Path) -> Result<Self, String> {
        let path = out.join(LOCK_FILE);
        let mut file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .map_err(|e| format!("cannot open the output folder's lock {}: {e}", path.display()))?;
        match file.try_lock() {
            Ok(()) => {}
            Err(TryLockError::WouldBlock) => return Err(in_use(out, &mut file)),
            Err(TryLockError::Error(e)) => {
                return Err(format!("cannot lock the output folder {}: {e}", out.display()))
            }
        }
        let pid = std::process::id();
        let written = file
            .set_len(0)
            .and_then(|()| file.rewind())
            .and_then(|()| writeln!(file, "{pid}"));
        written.map_err(|e| format!("{}: {e}", path.display()))?;
        Ok(Self { _file: file })
    }
}

/// The refusal of a folder locked by another run, naming its pid (as the lock file holds it).
fn in_use(out: &Path, file: &mut File) -> String {
    let mut text = String::new();
    let _ = file.read_to_string(&mut text);
    let holder = match text.trim().parse::<u32>() {
        Ok(pid) => format!("another run (pid {pid})"),
        Err(_) => "another run".to_string(),
    };
    format!(
        "the output folder {} is in use by {holder}: wait for it to end, or choose another --out",
        out.display()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_locked_folder_is_refused_naming_the_holder_and_free_again_once_released() {
        let dir = std::env::temp_dir().join(format!("output-lock-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let held = OutputLock::take(&dir).unwrap();
        let pid = std::process::id();
        let text = std::fs::read_to_string(dir.join(LOCK_FILE)).unwrap();
        assert_eq!(text, format!("{pid}\n"));
        let refused = OutputLock::take(&dir).unwrap_err();
        assert!(
            refused.contains(&format!("in use by another run (pid {pid})")),
            "{refused}"
        );
        drop(held);
        let again = OutputLock::take(&dir);
        assert!(again.is_ok(), "{again:?}");
        drop(again);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
