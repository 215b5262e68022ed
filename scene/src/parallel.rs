//! `[parallel]`: how `lbm-server` cuts the lattice into blocks, one per MPI rank (`mpirun -np N
//! lbm-server run SCENE`). Optional: without it the blocks are chosen for the fewest halo cells.

use crate::numbers::fail;
use crate::{Scene, SceneError, AXES};
use serde::Deserialize;

/// The thinnest block along a cut axis: one layer of cells against each neighbour's ghost layer
/// (`lbm-server/src/parallel/decomposition.rs`).
pub const MIN_BLOCK_CELLS: u64 = 2;

#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Parallel {
    /// Blocks along x, y and z: each divides the lattice's cells along its axis, and the run has
    /// their product of ranks.
    pub blocks: Option<[u64; 3]>,
}

impl Parallel {
    /// The blocks, where the scene gives them.
    pub fn blocks(&self) -> Option<[usize; 3]> {
        self.blocks.map(|b| b.map(|v| v as usize))
    }
}

impl Scene {
    /// `parallel.blocks`: with a `[lattice]`, each axis cut into equal blocks at least
    /// [`MIN_BLOCK_CELLS`] thick.
    pub(crate) fn validate_parallel(&self, file: &str) -> Result<(), SceneError> {
        let Some(blocks) = self.parallel.blocks else {
            return Ok(());
        };
        let shown = format!("[{}, {}, {}]", blocks[0], blocks[1], blocks[2]);
        let Some(units) = &self.lattice_units else {
            return Err(fail(
                file,
                "parallel.blocks",
                shown,
                "cuts the lattice into blocks: the scene has no [lattice]",
            ));
        };
        for (a, &b) in blocks.iter().enumerate() {
            let cells = units.n[a] as u64;
            let field = format!("parallel.blocks[{a}]");
            if b == 0 || !cells.is_multiple_of(b) {
                return Err(fail(
                    file,
                    field,
                    b,
                    format!("must divide the lattice's {cells} cells along {}", AXES[a]),
                ));
            }
            if b > 1 && cells / b < MIN_BLOCK_CELLS {
                return Err(fail(
                    file,
                    field,
                    b,
                    format!(
                        "blocks of {} cell(s) along {}, thinner than the halo needs (at least \
                         {MIN_BLOCK_CELLS})",
                        cells / b,
                        AXES[a]
                    ),
                ));
            }
        }
        Ok(())
    }
}
