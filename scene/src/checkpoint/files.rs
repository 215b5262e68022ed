//! A checkpoint's files: written and synced with their checksum, the staging folder made and put
//! in place (OUT/checkpoint moved to checkpoint.old first, removed once the new one is in place: a
//! crash in between leaves checkpoint.old, which is found instead), and the newest complete one
//! found with every file's size and checksum checked.

use super::header::{FileEntry, Header, FORMAT, VERSION};
use super::{DIR, OLD, STAGING};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// An empty staging folder in `out` (an earlier, unfinished one removed); its path.
pub fn staging_folder(out: &Path) -> Result<PathBuf, String> {
    let staging = out.join(STAGING);
    let io = |e: std::io::Error| format!("{}: {e}", staging.display());
    if staging.exists() {
        std::fs::remove_dir_all(&staging).map_err(io)?;
    }
    std::fs::create_dir_all(&staging).map_err(io)?;
    Ok(staging)
}

/// Writes `parts` one after the other to `path` and syncs it to the disk; its entry in the header
/// (`name`, numpy's `dtype` and C-order `shape`).
pub fn write_synced(
    path: &Path,
    name: &str,
    dtype: &str,
    shape: Vec<usize>,
    parts: &[&[u8]],
) -> Result<FileEntry, String> {
    let io = |e: std::io::Error| format!("checkpoint: {}: {e}", path.display());
    let file = File::create(path).map_err(io)?;
    let mut w = BufWriter::with_capacity(1 << 20, file);
    let mut hash = crate::checksum::FNV_OFFSET;
    for part in parts {
        hash = crate::checksum::fnv1a64_from(hash, part);
        w.write_all(part).map_err(io)?;
    }
    let file = w.into_inner().map_err(|e| io(e.into_error()))?;
    file.sync_all().map_err(io)?;
    Ok(FileEntry {
        name: name.to_string(),
        file: path.file_name().expect("a file").to_string_lossy().into_owned(),
        dtype: dtype.to_string(),
        shape,
        bytes: parts.iter().map(|p| p.len() as u64).sum(),
        checksum: format!("{hash:016x}"),
    })
}

/// The files of `staging` besides `ours` and header.json (those the other program wrote), with
/// their checksums, `dtype` "dem".
pub fn files_besides(staging: &Path, ours: &[FileEntry]) -> Result<Vec<FileEntry>, String> {
    let io = |e: std::io::Error| format!("checkpoint: {}: {e}", staging.display());
    let mut names: Vec<String> = std::fs::read_dir(staging)
        .map_err(io)?
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n != "header.json" && !ours.iter().any(|f| &f.file == n))
        .collect();
    names.sort();
    names
        .into_iter()
        .map(|file| {
            let (checksum, bytes) = crate::checksum::of_file(&staging.join(&file)).map_err(io)?;
            Ok(FileEntry {
                name: file.trim_end_matches(".bin").to_string(),
                file,
                dtype: "dem".into(),
                shape: vec![bytes as usize],
                bytes,
                checksum,
            })
        })
        .collect()
}

/// Writes `header` as header.json into the staging folder and puts the folder in place.
pub fn put_in_place(out: &Path, header: &Header) -> Result<(), String> {
    let (dir, old, staging) = (out.join(DIR), out.join(OLD), out.join(STAGING));
    let text = serde_json::to_string_pretty(header).expect("a header serializes");
    write_synced(
        &staging.join("header.json"),
        "header",
        "json",
        vec![],
        &[text.as_bytes()],
    )?;
    let io = |e: std::io::Error| format!("checkpoint: {}: {e}", out.display());
    if dir.exists() {
        if old.exists() {
            std::fs::remove_dir_all(&old).map_err(io)?;
        }
        std::fs::rename(&dir, &old).map_err(io)?;
    }
    std::fs::rename(&staging, &dir).map_err(io)?;
    if let Ok(folder) = File::open(out) {
        let _ = folder.sync_all();
    }
    if old.exists() {
        std::fs::remove_dir_all(&old).map_err(io)?;
    }
    Ok(())
}

/// The newest complete checkpoint in `out` (checkpoint/, else checkpoint.old/): its folder and
/// header, every file's size and checksum checked.
pub fn open_newest(out: &Path) -> Result<(PathBuf, Header), String> {
    let dir = [DIR, OLD]
        .iter()
        .map(|d| out.join(d))
        .find(|d| d.join("header.json").is_file())
        .ok_or_else(|| format!("no checkpoint in {} (no {DIR}/header.json)", out.display()))?;
    let path = dir.join("header.json");
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let header: Header = serde_json::from_str(&text)
        .map_err(|e| format!("{}: not a checkpoint header: {e}", path.display()))?;
    if header.format != FORMAT || header.version != VERSION {
        return Err(format!(
            "{}: format '{}' version {}, this build reads '{FORMAT}' version {VERSION}",
            path.display(),
            header.format,
            header.version
        ));
    }
    for entry in &header.files {
        check_file(&dir, entry)?;
    }
    Ok((dir, header))
}

/// A file's size and checksum as the header records them.
fn check_file(dir: &Path, entry: &FileEntry) -> Result<(), String> {
    let path = dir.join(&entry.file);
    let (checksum, bytes) =
        crate::checksum::of_file(&path).map_err(|e| format!("checkpoint: {}: {e}", path.display()))?;
    if bytes != entry.bytes {
        return Err(format!(
            "checkpoint: {} holds {bytes} bytes, its header says {} (truncated or corrupt)",
            path.display(),
            entry.bytes
        ));
    }
    if checksum != entry.checksum {
        return Err(format!(
            "checkpoint: {} has checksum {checksum}, its header says {} (corrupt)",
            path.display(),
            entry.checksum
        ));
    }
    Ok(())
}

/// Cuts the outputs in `out` back to where the checkpoint `at` found them: each appended file
/// (particles.csv, line<N>.csv, energy.csv) to its recorded length, each .pvd series to the
/// entries the checkpoint lists, the snapshots written after them removed. A resumed run does this
/// once it knows it goes on (a coupled one after the DEM's handshake): until then OUT stays as the
/// earlier run left it, and a resume refused on the way leaves it so.
pub fn cut_back(out: &Path, at: &super::OutputPositions) -> Result<(), String> {
    let io = |name: &str, e: std::io::Error| format!("{}: {e}", out.join(name).display());
    for (name, &kept) in &at.files {
        let file = std::fs::OpenOptions::new()
            .write(true)
            .open(out.join(name))
            .map_err(|e| io(name, e))?;
        let len = file.metadata().map_err(|e| io(name, e))?.len();
        if len < kept {
            return Err(io(
                name,
                std::io::Error::other(format!("holds {len} bytes, the checkpoint needs {kept}")),
            ));
        }
        file.set_len(kept).map_err(|e| io(name, e))?;
    }
    for (name, listed) in [
        ("fields.pvd", &at.fields_pvd),
        ("particles.pvd", &at.particles_pvd),
    ] {
        keep_listed(&out.join(name), listed).map_err(|e| io(name, e))?;
    }
    remove_later_snapshots(out, at).map_err(|e| format!("{}: {e}", out.display()))?;
    Ok(())
}

/// The .pvd series at `path` (where there is one) with the data sets of `listed` alone: each
/// other `<DataSet .../>` line dropped.
fn keep_listed(path: &Path, listed: &[(f64, String)]) -> std::io::Result<()> {
    let text = match std::fs::read_to_string(path) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(e),
    };
    let keep = |line: &&str| {
        !line.trim_start().starts_with("<DataSet")
            || listed
                .iter()
                .any(|(_, f)| line.contains(&format!("file=\"{f}\"")))
    };
    let kept: String = text.lines().filter(keep).flat_map(|l| [l, "\n"]).collect();
    if kept != text {
        std::fs::write(path, kept)?;
    }
    Ok(())
}

/// Removes the snapshot files a run wrote after its checkpoint `at` (those of `fields/step*.vti`,
/// `fields/step*.pvti` with the folder of their pieces, and `particles_*.vtp` that the
/// checkpoint's .pvd entries do not list, from a later step than the last they list): a resumed
/// run writes again those it is due to, on whatever number of ranks. Returns how many.
fn remove_later_snapshots(out: &Path, at: &super::OutputPositions) -> std::io::Result<usize> {
    let mut removed = 0;
    for (folder, head, tails, listed) in [
        ("fields", "step", &[".vti", ".pvti", ""][..], &at.fields_pvd),
        ("", "particles_", &[".vtp"][..], &at.particles_pvd),
    ] {
        let step_of = |name: &str| {
            let rest = name.strip_prefix(head)?;
            tails
                .iter()
                .find_map(|t| rest.strip_suffix(t)?.parse::<u64>().ok())
        };
        let last = listed
            .iter()
            .filter_map(|(_, f)| step_of(f.rsplit('/').next()?))
            .max();
        let entries = match std::fs::read_dir(out.join(folder)) {
            Ok(entries) => entries,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue,
            Err(e) => return Err(e),
        };
        for entry in entries {
            let entry = entry?;
            let name = entry.file_name().to_string_lossy().into_owned();
            let later = step_of(&name).is_some_and(|s| last.is_none_or(|l| s > l));
            if !later {
                continue;
            }
            match entry.file_type()? {
                t if t.is_file() => std::fs::remove_file(entry.path())?,
                t if t.is_dir() && !folder.is_empty() => std::fs::remove_dir_all(entry.path())?,
                _ => continue,
            }
            removed += 1;
        }
    }
    Ok(removed)
}
