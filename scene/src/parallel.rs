//! `[parallel]`: how `lbm-server` cuts the lattice into blocks, one per MPI rank (`mpirun -np N
//! lbm-server run SCENE`), and whether the halo exchange overlaps the interior's update.
//! Optional: without it the blocks are chosen for the fewest halo cells, and the exchange overlaps
//! on a GPU.

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
    /// Whether each rank's halo exchange overlaps the update of its block's interior (true), or
    /// follows the whole step (false: exposed); the same results either way, bit for bit. By
    /// default true on a GPU and false on a CPU driver (lavapipe), which runs each submission to
    /// its end within the submit: nothing overlaps there, and the split step only adds
    /// submissions. A coupled run whose covered cells are redone exchanges after the whole step
    /// either way.
    pub overlap: Option<bool>,
}

impl Parallel {
    /// The blocks, where the scene gives them.
    pub fn blocks(&self) -> Option<[usize; 3]> {
        self.blocks.map(|b| b.map(|v| v as usize))
    }

    /// Whether the halo exchange overlaps the interior's update: `overlap` where the scene gives
    /// it, else on a GPU (`on_gpu`), not on a CPU driver.
    pub fn overlap(&self, on_gpu: bool) -> bool {
        self.overlap.unwrap_or(on_gpu)
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

#[cfg(test)]
mod tests {
    use crate::Scene;

    /// A fluid-only scene of 8 x 8 x 4 cells with `parallel`.
    fn parse(parallel: &str) -> Result<Scene, crate::SceneError> {
        let text = format!(
            "name = \"p\"\n[domain]\nmin = [0.0, 0.0, 0.0]\nmax = [0.008, 0.008, 0.004]\n[fluid]\n\
             density = 1000.0\ndynamic_viscosity = 1.0e-3\n[time]\nsteps = 10\n[lattice]\ndx = 0.001\n\
             tau = 0.8\nvelocity_scale = 5.0e-4\n{parallel}\n"
        );
        Scene::parse(&text, "p.toml")
    }

    #[test]
    fn blocks_that_divide_the_lattice_are_taken() {
        let scene = parse("[parallel]\nblocks = [2, 4, 2]").unwrap();
        assert_eq!(scene.parallel.blocks(), Some([2, 4, 2]));
        assert_eq!(parse("").unwrap().parallel.blocks(), None);
    }

    #[test]
    fn blocks_that_cannot_be_are_refused_naming_the_field() {
        let e = parse("[parallel]\nblocks = [3, 1, 1]").unwrap_err();
        assert_eq!(
            (e.field.as_str(), e.value.as_str()),
            ("parallel.blocks[0]", "3"),
            "{e}"
        );
        assert!(e.problem.contains("divide the lattice's 8 cells along x"), "{e}");
        let e = parse("[parallel]\nblocks = [1, 1, 4]").unwrap_err();
        assert_eq!(e.field, "parallel.blocks[2]", "{e}");
        assert!(e.problem.contains("thinner than the halo"), "{e}");
        let e = parse("[parallel]\nblocks = [1, 0, 1]").unwrap_err();
        assert_eq!(e.field, "parallel.blocks[1]", "{e}");
    }
}
