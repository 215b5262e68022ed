//! An output folder holds one run's outputs: a run removes those an earlier run left there under
//! the names it writes itself (a stale last_good.vti, summary.json or snapshot would otherwise
//! pass for this run's), and nothing else.

use std::path::Path;

/// The outputs of `lbm-server run` (a fluid-only or a coupled run).
pub const LBM_SERVER: &[&str] = &[
    "particles.csv",
    "particles.pvd",
    "particles_*.vtp",
    "summary.json",
    "last_good.vti",
    "last_good.pvti",
    "last_good/rank*.vti",
    "fields.pvd",
    "fields/step*.vti",
    "fields/step*.pvti",
    "fields/step*/rank*.vti",
    "line*.csv",
];

/// The outputs of `dem-client run` (a granular scene alone).
pub const DEM_CLIENT: &[&str] = &["particles.csv", "energy.csv", "particles.pvd", "particles_*.vtp"];

/// Removes the files of `out` that match `names` (a name, or one `*` standing for any run of
/// characters, under at most two subfolders, the last of which may hold a `*` too: the folders
/// of a snapshot's pieces, removed once empty) and returns how many it removed. A folder that
/// does not exist holds none.
pub fn clear_earlier(out: &Path, names: &[&str]) -> std::io::Result<usize> {
    let mut removed = 0;
    for name in names {
        let (folder, file) = name.rsplit_once('/').unwrap_or(("", name));
        for dir in folders(out, folder)? {
            removed += clear_in(&dir, file)?;
            if folder.contains('*') {
                // A piece folder another file still holds stays.
                let _ = std::fs::remove_dir(&dir);
            }
        }
    }
    Ok(removed)
}

/// The folders of `out` that `folder` names (its last part may hold a `*`).
fn folders(out: &Path, folder: &str) -> std::io::Result<Vec<std::path::PathBuf>> {
    let (parent, last) = folder.rsplit_once('/').unwrap_or(("", folder));
    if !last.contains('*') {
        return Ok(vec![out.join(folder)]);
    }
    let mut found = Vec::new();
    for entry in entries(&out.join(parent))? {
        let entry = entry?;
        if entry.file_type()?.is_dir() && entry.file_name().to_str().is_some_and(|n| matches(last, n)) {
            found.push(entry.path());
        }
    }
    Ok(found)
}

/// Removes the files of `dir` that match `file`; how many.
fn clear_in(dir: &Path, file: &str) -> std::io::Result<usize> {
    let mut removed = 0;
    for entry in entries(dir)? {
        let entry = entry?;
        let matches = entry.file_name().to_str().is_some_and(|n| matches(file, n));
        if matches && entry.file_type()?.is_file() {
            std::fs::remove_file(entry.path())?;
            removed += 1;
        }
    }
    Ok(removed)
}

/// The entries of `dir` (none where it does not exist).
fn entries(dir: &Path) -> std::io::Result<Vec<std::io::Result<std::fs::DirEntry>>> {
    match std::fs::read_dir(dir) {
        Ok(entries) => Ok(entries.collect()),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(Vec::new()),
        Err(e) => Err(e),
    }
}

/// Whether `name` matches `pattern` (with at most one `*`).
fn matches(pattern: &str, name: &str) -> bool {
    match pattern.split_once('*') {
        None => pattern == name,
        Some((head, tail)) => {
            name.len() >= head.len() + tail.len() && name.starts_with(head) && name.ends_with(tail)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_earlier_runs_outputs_are_removed_and_nothing_else() {
        let dir = std::env::temp_dir().join(format!("clear-earlier-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("fields/step000000100")).unwrap();
        std::fs::create_dir_all(dir.join("last_good")).unwrap();
        let ours = [
            "summary.json",
            "last_good.vti",
            "last_good.pvti",
            "last_good/rank1.vti",
            "fields.pvd",
            "fields/step000000100.vti",
            "fields/step000000100.pvti",
            "fields/step000000100/rank0.vti",
            "line0.csv",
            "line12.csv",
        ];
        let theirs = [
            "notes.txt",
            "fields/mine.vti",
            "line.txt",
            "summary.json.bak",
            "scene.toml",
        ];
        for f in ours.iter().chain(&theirs) {
            std::fs::write(dir.join(f), "x").unwrap();
        }
        std::fs::create_dir_all(dir.join("line_dir.csv")).unwrap();
        assert_eq!(clear_earlier(&dir, LBM_SERVER).unwrap(), ours.len());
        for f in ours {
            assert!(!dir.join(f).exists(), "{f} left");
        }
        for f in theirs {
            assert!(dir.join(f).is_file(), "{f} removed");
        }
        assert!(dir.join("line_dir.csv").is_dir(), "a folder is not an output");
        assert!(
            !dir.join("fields/step000000100").exists(),
            "an emptied piece folder is removed"
        );
        assert_eq!(clear_earlier(&dir.join("none"), LBM_SERVER).unwrap(), 0);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_star_stands_for_any_run_of_characters() {
        assert!(matches("line*.csv", "line0.csv"));
        assert!(matches("line*.csv", "line.csv"));
        assert!(!matches("line*.csv", "line0.csvx"));
        assert!(!matches("particles_*.vtp", "particles.vtp"));
        assert!(!matches("ab*ba", "aba"), "head and tail may not overlap");
        assert!(matches("summary.json", "summary.json"));
        assert!(!matches("summary.json", "summary.jsonx"));
    }
}
