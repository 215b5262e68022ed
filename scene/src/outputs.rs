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
    "fields.pvd",
    "fields/step*.vti",
    "line*.csv",
];

/// The outputs of `dem-client run` (a granular scene alone).
pub const DEM_CLIENT: &[&str] = &["particles.csv", "energy.csv", "particles.pvd", "particles_*.vtp"];

/// Removes the files of `out` that match `names` (a name, or one `*` standing for any run of
/// characters, under at most one subfolder) and returns how many it removed. A folder that does
/// not exist holds none.
pub fn clear_earlier(out: &Path, names: &[&str]) -> std::io::Result<usize> {
    let mut removed = 0;
    for name in names {
        let (folder, file) = name.rsplit_once('/').unwrap_or(("", name));
        let dir = out.join(folder);
        let entries = match std::fs::read_dir(&dir) {
            Ok(entries) => entries,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue,
            Err(e) => return Err(e),
        };
        for entry in entries {
            let entry = entry?;
            let matches = entry.file_name().to_str().is_some_and(|n| matches(file, n));
            if matches && entry.file_type()?.is_file() {
                std::fs::remove_file(entry.path())?;
                removed += 1;
            }
        }
    }
    Ok(removed)
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
        std::fs::create_dir_all(dir.join("fields")).unwrap();
        let ours = [
            "summary.json",
            "last_good.vti",
            "fields.pvd",
            "fields/step000000100.vti",
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
