//! The field snapshots of a run on several ranks as ParaView parallel image data
//! ([`FieldPieces`]): each rank writes its block's own cells as a .vti piece
//! (NAME/rankR.vti), placed in the whole grid by its extent; rank 0 writes NAME.pvti, which names
//! the pieces, so that ParaView opens the whole field. Nothing of the field crosses to rank 0.

use super::{all, Communicator, Decomposition};
use crate::fields::{last_good_line, si_fields, snapshot_name, FieldOutput};
use crate::vtk::{write_pvti, write_vti_piece, Extent, Grid};
use scene::lattice::LatticeUnits;
use scene::Scene;
use std::path::PathBuf;

/// One rank's pieces of the snapshots, into the run's output folder.
pub struct FieldPieces {
    out: PathBuf,
    grid: Grid,
    rank: usize,
    /// Every rank's block (rank order).
    blocks: Vec<Extent>,
    fluid_density: f64,
    units: LatticeUnits,
}

impl FieldPieces {
    /// The pieces of the block `d` (rank `rank`'s) of a run of `scene` on `units`, into `out`.
    pub fn new(
        scene: &Scene,
        units: &LatticeUnits,
        out: PathBuf,
        d: &Decomposition,
        rank: usize,
    ) -> FieldPieces {
        let blocks = (0..d.ranks())
            .map(|r| {
                let b = Decomposition::new(d.n, d.periodic(), d.blocks, r);
                Extent {
                    first: b.origin,
                    size: b.size,
                }
            })
            .collect();
        FieldPieces {
            out,
            grid: Grid {
                n: units.n,
                origin: scene.domain.min,
                dx: units.dx,
            },
            rank,
            blocks,
            fluid_density: scene.fluid.density,
            units: units.clone(),
        }
    }

    /// Every rank writes its piece of the snapshot `name` (relative to the output folder, no
    /// extension) from its block's `own` fields (lattice units, x fastest); rank 0 then writes
    /// NAME.pvti and returns its name. Every rank fails where one could not write.
    pub fn write(&self, comm: &dyn Communicator, name: &str, own: &[[f32; 4]]) -> Result<String, String> {
        let written = self.write_piece(name, own);
        if !all(comm, written.is_ok()) {
            return Err(written
                .err()
                .unwrap_or_else(|| format!("{name}: another rank could not write its piece")));
        }
        let pvti = format!("{name}.pvti");
        if self.rank == 0 {
            let stem = name.rsplit('/').next().unwrap_or(name);
            let pieces: Vec<(Extent, String)> = (0..self.blocks.len())
                .map(|r| (self.blocks[r], format!("{stem}/{}", piece_file(r))))
                .collect();
            write_pvti(&self.out.join(&pvti), &self.grid, &pieces).map_err(|e| format!("{pvti}: {e}"))?;
        }
        Ok(pvti)
    }

    /// Where the file `name` (relative to the output folder) lies.
    pub fn path(&self, name: &str) -> PathBuf {
        self.out.join(name)
    }

    /// This rank's piece of `name`: NAME/rankR.vti.
    fn write_piece(&self, name: &str, own: &[[f32; 4]]) -> Result<(), String> {
        let dir = self.out.join(name);
        let file = format!("{name}/{}", piece_file(self.rank));
        let io = |e: std::io::Error| format!("{file}: {e}");
        std::fs::create_dir_all(&dir).map_err(io)?;
        let (density, velocity) = si_fields(own, self.fluid_density, &self.units);
        let extent = self.blocks[self.rank];
        write_vti_piece(&self.out.join(&file), &self.grid, extent, &density, &velocity).map_err(io)
    }
}

/// The snapshot of `step` from this rank's `own` fields: on one rank (no `pieces`) the whole
/// .vti, on several a .pvti of every rank's piece; listed in fields.pvd by rank 0 (`fields`).
pub fn write_snapshot_of_ranks(
    comm: &dyn Communicator,
    (fields, pieces): (Option<&mut FieldOutput>, Option<&FieldPieces>),
    step: u64,
    own: &[[f32; 4]],
) -> Result<(), String> {
    let Some(pieces) = pieces else {
        return fields.map_or(Ok(()), |f| f.write_snapshot(step, own));
    };
    let name = pieces.write(comm, &snapshot_name(step), own)?;
    fields.map_or(Ok(()), |f| f.add_snapshot(step, &name))
}

/// The snapshot of the last check that passed (step `good`, this block's `own` fields then):
/// last_good.vti, on several ranks last_good.pvti and its pieces; a line for the error.
pub fn write_last_good_of_ranks(
    comm: &dyn Communicator,
    (fields, pieces): (Option<&FieldOutput>, Option<&FieldPieces>),
    good: u64,
    own: &[[f32; 4]],
) -> String {
    match (pieces, fields) {
        (Some(pieces), _) => {
            let written = pieces.write(comm, "last_good", own);
            last_good_line(good, written.map(|name| pieces.path(&name)))
        }
        (None, Some(out)) => out.write_last_good(good, own),
        (None, None) => String::new(),
    }
}

/// The file of rank `rank`'s piece, in the folder named after the snapshot.
fn piece_file(rank: usize) -> String {
    format!("rank{rank}.vti")
}
