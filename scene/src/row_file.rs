//! A CSV output that a crash never leaves with a torn row: rows are staged in memory and written
//! to the file whole, all of one output step's rows at once ([`RowFile::commit`]), so a run killed
//! at any moment leaves the rows of its last committed step and none after. A write that fails
//! (a full disk) is cut back to the last whole row and named: what was written is kept.

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

/// A file of whole rows.
pub struct RowFile {
    file: File,
    path: PathBuf,
    /// Rows staged since the last commit.
    staged: Vec<u8>,
    /// Bytes of whole rows in the file.
    kept: u64,
}

impl RowFile {
    /// Creates (truncates) the file at `path` and writes its `header` row.
    pub fn create(path: &Path, header: &str) -> std::io::Result<Self> {
        let file = File::create(path).map_err(|e| named(path, e))?;
        let mut rows = Self {
            file,
            path: path.to_path_buf(),
            staged: Vec::new(),
            kept: 0,
        };
        writeln!(rows.staged, "{header}")?;
        rows.commit()?;
        Ok(rows)
    }

    /// Opens the file at `path` to go on after its first `kept` bytes (a resumed run, whose
    /// checkpoint found it so: the rows written after it are cut off by
    /// `scene::checkpoint::cut_back` before the run writes). A file shorter than that is refused.
    pub fn resume(path: &Path, kept: u64) -> std::io::Result<Self> {
        use std::io::{Seek, SeekFrom};
        let mut file = std::fs::OpenOptions::new()
            .write(true)
            .open(path)
            .map_err(|e| named(path, e))?;
        let len = file.metadata().map_err(|e| named(path, e))?.len();
        if len < kept {
            let problem = format!("holds {len} bytes, the checkpoint needs {kept}");
            return Err(named(path, std::io::Error::other(problem)));
        }
        file.seek(SeekFrom::Start(kept)).map_err(|e| named(path, e))?;
        Ok(Self {
            file,
            path: path.to_path_buf(),
            staged: Vec::new(),
            kept,
        })
    }

    /// The file, positioned at its end (for a writer of its own).
    pub fn into_file(self) -> File {
        self.file
    }

    /// Bytes of whole rows in the file (what a checkpoint records).
    pub fn kept(&self) -> u64 {
        self.kept
    }

    /// Where rows are staged (`write!` into it); they reach the file at the next commit.
    pub fn staged(&mut self) -> &mut Vec<u8> {
        &mut self.staged
    }

    /// Writes the staged rows to the file at once. On an error the file is cut back to its last
    /// whole row and the error names the file.
    pub fn commit(&mut self) -> std::io::Result<()> {
        if self.staged.is_empty() {
            return Ok(());
        }
        if let Err(e) = self.file.write_all(&self.staged) {
            let _ = self.file.set_len(self.kept);
            self.staged.clear();
            return Err(named(&self.path, e));
        }
        self.kept += self.staged.len() as u64;
        self.staged.clear();
        Ok(())
    }
}

/// The error `e` with the name of the file it happened to (its folder is the run's output folder).
fn named(path: &Path, e: std::io::Error) -> std::io::Error {
    let name = path.file_name().unwrap_or(path.as_os_str()).to_string_lossy();
    std::io::Error::new(e.kind(), format!("{name}: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_reach_the_file_whole_at_each_commit_only() {
        let dir = std::env::temp_dir().join(format!("row-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("rows.csv");
        let mut rows = RowFile::create(&path, "a,b").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "a,b\n");
        writeln!(rows.staged(), "1,2").unwrap();
        write!(rows.staged(), "3,").unwrap();
        assert_eq!(
            std::fs::read_to_string(&path).unwrap(),
            "a,b\n",
            "nothing before a commit"
        );
        writeln!(rows.staged(), "4").unwrap();
        rows.commit().unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "a,b\n1,2\n3,4\n");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_failed_write_names_the_file() {
        if !Path::new("/dev/full").exists() {
            return;
        }
        let Err(e) = RowFile::create(Path::new("/dev/full"), "a,b") else {
            panic!("a write to /dev/full succeeded");
        };
        assert_eq!(e.kind(), std::io::ErrorKind::StorageFull);
        assert!(e.to_string().starts_with("full: "), "{e}");
    }
}
