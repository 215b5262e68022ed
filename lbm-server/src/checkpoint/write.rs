//! A checkpoint written atomically: the fluid's state, copied off the device, is written on a
//! thread while the run goes on, into OUT/checkpoint.staging (where the DEM has written its own
//! part), with each file's size and checksum in header.json; then the staging folder replaces
//! OUT/checkpoint, the previous one moved to checkpoint.old until the new one is in place.

use super::header::{FileEntry, Header};
use super::{DIR, OLD, STAGING};
use crate::lbm::gpu::RawState;
use crate::lbm::storage::Storage;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::thread::JoinHandle;
use std::time::Instant;

/// What a checkpoint holds: its header (its files are added as they are written) and the lattice's
/// state.
pub struct Snapshot {
    pub header: Header,
    pub state: RawState,
}

/// Writes a run's checkpoints, one at a time.
pub struct Writer {
    out: PathBuf,
    /// The one being written.
    pending: Option<JoinHandle<Result<(), String>>>,
}

impl Writer {
    pub fn new(out: &Path) -> Self {
        Self {
            out: out.to_path_buf(),
            pending: None,
        }
    }

    /// Waits for the checkpoint being written, then makes an empty staging folder (for the DEM to
    /// write its part into); its path.
    pub fn stage(&mut self) -> Result<PathBuf, String> {
        self.wait()?;
        let staging = self.out.join(STAGING);
        let io = |e: std::io::Error| format!("{}: {e}", staging.display());
        if staging.exists() {
            std::fs::remove_dir_all(&staging).map_err(io)?;
        }
        std::fs::create_dir_all(&staging).map_err(io)?;
        Ok(staging)
    }

    /// Writes `snapshot` into the staging folder and puts it in place, on a thread.
    pub fn commit(&mut self, snapshot: Snapshot) {
        let out = self.out.clone();
        self.pending = Some(std::thread::spawn(move || write_staged(&out, snapshot)));
    }

    /// Waits for the checkpoint being written: its error, where it failed.
    pub fn wait(&mut self) -> Result<(), String> {
        match self.pending.take() {
            None => Ok(()),
            Some(thread) => thread
                .join()
                .unwrap_or_else(|_| Err("the checkpoint's writer panicked".into())),
        }
    }
}

/// Writes the arrays, lists the DEM's files, writes header.json and puts the folder in place.
fn write_staged(out: &Path, snapshot: Snapshot) -> Result<(), String> {
    let started = Instant::now();
    let staging = out.join(STAGING);
    let Snapshot { mut header, state } = snapshot;
    let storage = Storage::named(&header.storage).expect("the lattice's storage");
    let [nx, ny, nz] = header.lattice;
    let dtype = match storage {
        Storage::Fp32 => "<f4",
        Storage::Fp16s => "<f2",
        Storage::Fp16c => "<u2",
    };
    let mut files = vec![
        write_array(&staging, "populations", dtype, vec![19, nz, ny, nx], &state.populations)?,
        write_array(&staging, "status", "<u4", vec![state.status.len() / 4], &[state.status])?,
    ];
    files.extend(dem_files(&staging, &files)?);
    header.files = files;
    let bytes: u64 = header.files.iter().map(|f| f.bytes).sum();
    let text = serde_json::to_string_pretty(&header).expect("a header serializes");
    write_synced(&staging.join("header.json"), &[text.as_bytes()])?;
    put_in_place(out)?;
    protocol::say!(
        "lbm-server: checkpoint at step {} written to {} ({:.1} MiB in {:.2} s)",
        header.step,
        out.join(DIR).display(),
        bytes as f64 / (1024.0 * 1024.0),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

/// Writes `parts` one after the other as `NAME.bin` in `dir`; its entry.
fn write_array(dir: &Path, name: &str, dtype: &str, shape: Vec<usize>, parts: &[Vec<u8>]) -> Result<FileEntry, String> {
    let file = format!("{name}.bin");
    let slices: Vec<&[u8]> = parts.iter().map(|p| p.as_slice()).collect();
    let hash = write_synced(&dir.join(&file), &slices)?;
    Ok(FileEntry {
        name: name.to_string(),
        file,
        dtype: dtype.to_string(),
        shape,
        bytes: parts.iter().map(|p| p.len() as u64).sum(),
        checksum: format!("{hash:016x}"),
    })
}

/// Writes `parts` to `path` and syncs it to the disk; the checksum of its bytes.
fn write_synced(path: &Path, parts: &[&[u8]]) -> Result<u64, String> {
    let io = |e: std::io::Error| format!("checkpoint: {}: {e}", path.display());
    let file = File::create(path).map_err(io)?;
    let mut w = BufWriter::with_capacity(1 << 20, file);
    let mut hash = scene::checksum::FNV_OFFSET;
    for part in parts {
        hash = scene::checksum::fnv1a64_from(hash, part);
        w.write_all(part).map_err(io)?;
    }
    let file = w.into_inner().map_err(|e| io(e.into_error()))?;
    file.sync_all().map_err(io)?;
    Ok(hash)
}

/// The files the DEM wrote into the staging folder (all but `ours`), with their checksums.
fn dem_files(staging: &Path, ours: &[FileEntry]) -> Result<Vec<FileEntry>, String> {
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
            let (checksum, bytes) = scene::checksum::of_file(&staging.join(&file)).map_err(io)?;
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

/// The staging folder becomes OUT/checkpoint: the previous one moved aside to checkpoint.old first
/// and removed once the new one is in place (a crash in between leaves checkpoint.old, which
/// `--resume` takes).
fn put_in_place(out: &Path) -> Result<(), String> {
    let (dir, old, staging) = (out.join(DIR), out.join(OLD), out.join(STAGING));
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
