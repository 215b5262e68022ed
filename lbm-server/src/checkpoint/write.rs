//! A fluid checkpoint written: the lattice's state, copied off the device, is written on a thread
//! while the run goes on, into OUT/checkpoint.staging (where the DEM has written its own part),
//! with each file's size and checksum in header.json; then the folder is put in place.

use crate::lbm::gpu::RawState;
use crate::lbm::storage::Storage;
use scene::checkpoint::{files_besides, put_in_place, staging_folder, write_synced, FileEntry, Header, DIR};
use std::path::{Path, PathBuf};
use std::thread::JoinHandle;
use std::time::Instant;

/// What a checkpoint holds: its header (its files are added as they are written) and the lattice's
/// state.
pub struct Snapshot {
    pub header: Header,
    pub state: RawState,
    /// Seconds the run waited for the state to come off the device (all it waits for).
    pub readback_s: f64,
}

/// Writes a run's checkpoints, one at a time.
pub struct Writer {
    out: PathBuf,
    /// The one being written (its step, once written).
    pending: Option<JoinHandle<Result<u64, String>>>,
    /// The step of the last one written.
    pub last: Option<u64>,
}

impl Writer {
    pub fn new(out: &Path) -> Self {
        Self {
            out: out.to_path_buf(),
            pending: None,
            last: None,
        }
    }

    /// Waits for the checkpoint being written, then makes an empty staging folder (for the DEM to
    /// write its part into); its path.
    pub fn stage(&mut self) -> Result<PathBuf, String> {
        self.wait()?;
        staging_folder(&self.out)
    }

    /// Writes `snapshot` into the staging folder and puts it in place, on a thread.
    pub fn commit(&mut self, snapshot: Snapshot) {
        let out = self.out.clone();
        self.pending = Some(std::thread::spawn(move || write_staged(&out, snapshot)));
    }

    /// Waits for the checkpoint being written: its error, where it failed.
    pub fn wait(&mut self) -> Result<(), String> {
        let Some(thread) = self.pending.take() else {
            return Ok(());
        };
        let step = thread
            .join()
            .unwrap_or_else(|_| Err("the checkpoint's writer panicked".into()))?;
        self.last = Some(step);
        Ok(())
    }
}

/// numpy's dtype of the populations of `storage` (FP16C's custom half as its raw u16).
pub fn population_dtype(storage: Storage) -> &'static str {
    match storage {
        Storage::Fp32 => "<f4",
        Storage::Fp16s => "<f2",
        Storage::Fp16c => "<u2",
    }
}

/// Writes the arrays, lists the DEM's files, writes header.json and puts the folder in place;
/// the checkpoint's step.
fn write_staged(out: &Path, snapshot: Snapshot) -> Result<u64, String> {
    let started = Instant::now();
    let staging = out.join(scene::checkpoint::STAGING);
    let Snapshot {
        mut header,
        state,
        readback_s,
    } = snapshot;
    let storage = Storage::named(&header.storage).expect("the lattice's storage");
    let [nx, ny, nz] = header.lattice;
    let populations: Vec<&[u8]> = state.populations.iter().map(|p| p.as_slice()).collect();
    let mut files: Vec<FileEntry> = vec![
        write_synced(
            &staging.join("populations.bin"),
            "populations",
            population_dtype(storage),
            vec![19, nz, ny, nx],
            &populations,
        )?,
        write_synced(
            &staging.join("status.bin"),
            "status",
            "<u4",
            vec![state.status.len() / 4],
            &[&state.status],
        )?,
    ];
    files.extend(files_besides(&staging, &files)?);
    header.files = files;
    let bytes: u64 = header.files.iter().map(|f| f.bytes).sum();
    put_in_place(out, &header)?;
    protocol::say!(
        "lbm-server: checkpoint at step {} written to {} ({:.1} MiB: off the device in {:.3} s, \
         then written in {:.2} s while the run went on)",
        header.step,
        out.join(DIR).display(),
        bytes as f64 / (1024.0 * 1024.0),
        readback_s,
        started.elapsed().as_secs_f64()
    );
    Ok(header.step)
}
