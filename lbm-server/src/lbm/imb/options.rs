//! The coupling's settings: how many particles a cell holds, the weighting and the solid
//! collision term, and where the covered cells get their solid term.

/// Settings of the coupling.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImbOptions {
    /// Particles one cell can hold (1-4); more are dropped and counted.
    pub slots: u32,
    /// B = eps (the seed's choice) instead of Noble & Torczynski's B(eps, tau).
    pub seed_weighting: bool,
    /// The solid collision term Omega.
    pub solid_collision: SolidCollision,
    /// Where the covered cells get their solid term.
    pub covered_cells: CoveredCells,
}

impl Default for ImbOptions {
    fn default() -> Self {
        Self {
            slots: 2,
            seed_weighting: false,
            solid_collision: SolidCollision::NobleTorczynski,
            covered_cells: CoveredCells::Auto,
        }
    }
}

/// The solid collision term Omega_i that a covered cell adds, weighted by B, to its fluid part
/// f_i - (1 - B) (f_i - post_i) (docs/imb.md, "The solid collision").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SolidCollision {
    /// Noble & Torczynski (1998), the seed's eq. 8: the non-equilibrium part bounced back,
    /// Omega_i = f_ibar - f_i + f_eq_i(rho, u_s) - f_eq_ibar(rho, u).
    #[default]
    NobleTorczynski,
    /// Superposition (Holdych 2003): the fluid's own collision without its body-force source,
    /// with the equilibrium moved to the solid's velocity, Omega_i = f_eq_i(rho, u_s) -
    /// f_eq_i(rho, u) + post_i - S_i - f_i; the covered cell becomes post_i - B S_i + B
    /// (f_eq_i(rho, u_s) - f_eq_i(rho, u)).
    Superposition,
}

impl SolidCollision {
    /// The scene's `coupling.solid_collision` ("noble-torczynski", "superposition").
    pub fn from_name(name: &str) -> Option<SolidCollision> {
        match name {
            "noble-torczynski" => Some(SolidCollision::NobleTorczynski),
            "superposition" => Some(SolidCollision::Superposition),
            _ => None,
        }
    }
}

/// Where the covered cells get their solid term (docs/imb.md, "Speed"). Both give the same
/// populations and loads (tested bit for bit); they differ in cost.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CoveredCells {
    /// Redo for sparse particles, fused from [`FUSED_FROM`] of the cells covered, on every device.
    #[default]
    Auto,
    /// In the fluid kernels: every cell tests one bit of a cover mask, and a covered cell takes
    /// its solid term where it collides (no four-cell quads). Moves no population twice; costs a
    /// branch in the fluid kernels, which a GPU pays per warp that holds a covered cell and a CPU
    /// driver such as lavapipe (which runs both sides of a branch) for every cell.
    Fused,
    /// Collided with the solid term before the fluid kernels (the loads then go back to the host
    /// while they run) and stored over their result: the fluid kernels stay branch-free, each
    /// covered cell's populations move three times.
    Redo,
    /// Collided with the solid term in place before the fluid kernels (the loads then go back to
    /// the host while they run), which skip them by one bit of a cover mask per cell (the
    /// four-cell quads by four bits, storing a covered cell's populations back as they were): each
    /// covered cell's populations move once, and the fluid kernels carry no solid term. Built for
    /// a GPU; not yet timed on one (a timed run tries it).
    Skip,
}

impl CoveredCells {
    /// The definite ways (what `bench --covered-cells all` and the reference tests run).
    pub const DEFINITE: [CoveredCells; 3] = [CoveredCells::Redo, CoveredCells::Fused, CoveredCells::Skip];

    /// The scene's `coupling.covered_cells` ("auto", "fused", "redo", "skip").
    pub fn from_name(name: &str) -> Option<CoveredCells> {
        match name {
            "auto" => Some(CoveredCells::Auto),
            "fused" => Some(CoveredCells::Fused),
            "redo" => Some(CoveredCells::Redo),
            "skip" => Some(CoveredCells::Skip),
            _ => None,
        }
    }

    /// Whether the solid term goes in the fluid kernels (`Auto` taken as sparse particles; see
    /// [`CoveredCells::for_scene`]).
    pub fn fused(self) -> bool {
        self == CoveredCells::Fused
    }

    /// The scene's name of a definite way (`Auto` as the redo it takes).
    pub fn name(self) -> &'static str {
        match self.definite() {
            CoveredCells::Fused => "fused",
            CoveredCells::Skip => "skip",
            _ => "redo",
        }
    }

    /// The way a lattice made with this choice takes (`Auto` as sparse particles: the redo).
    pub fn definite(self) -> CoveredCells {
        match self {
            CoveredCells::Auto => CoveredCells::Redo,
            mode => mode,
        }
    }

    /// Whether the fluid kernels give the covered cells their solid term (no four-cell quads).
    pub fn fuses(self) -> bool {
        self == CoveredCells::Fused
    }

    /// The name a run's first line and `bench` give it.
    pub fn describe(self) -> &'static str {
        match self.definite() {
            CoveredCells::Fused => "solid term in the fluid kernels",
            CoveredCells::Skip => "covered cells first, skipped by the fluid kernels",
            _ => "covered cells redone",
        }
    }

    /// `Auto` made definite for particles that cover `covered_fraction` of the cells: redo for
    /// sparse particles, fused from [`FUSED_FROM`] on.
    pub fn for_scene(self, covered_fraction: f64) -> CoveredCells {
        match self {
            CoveredCells::Auto if covered_fraction >= FUSED_FROM => CoveredCells::Fused,
            mode => mode.definite(),
        }
    }
}

/// The covered fraction of the cells from which the coupled step runs faster with the solid term
/// fused (BENCHMARKS.md): `auto`'s way on a CPU driver, and the way a timed run starts with
/// (trials.rs). Lavapipe, 64 x 64 x 128, TRT, spheres of 4 cells: the redo runs at 94 /
/// 64 / 44 / 30 / 26% of LBM-only at 1 / 512 / 1728 / 2744 / 4096 spheres (0.01 / 6 / 21 / 33 /
/// 49% of the cells covered by [`covered_fraction`]), fused at 57 / 53 / 43 / 39 / 37%. NVIDIA
/// H200, 256 x 256 x 512: the redo faster from 1 to 4096 spheres (up to 0.7% covered; 71-57%
/// against 62-54%), fused faster with half the cells covered (44% against 18%), before the redo
/// let the fluid kernels run during the host's part of the step; the crossover between is not
/// measured there.
pub const FUSED_FROM: f64 = 0.2;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_fuses_only_for_dense_beds() {
        let auto = CoveredCells::Auto;
        assert_eq!(auto.for_scene(0.0), CoveredCells::Redo);
        assert_eq!(auto.for_scene(0.05), CoveredCells::Redo);
        assert_eq!(auto.for_scene(0.3), CoveredCells::Fused);
        assert!(!auto.fused());
        assert_eq!(CoveredCells::Redo.for_scene(0.9), CoveredCells::Redo);
        assert_eq!(CoveredCells::Fused.for_scene(0.0), CoveredCells::Fused);
    }
}
