//! The coupling's settings: how many particles a cell holds, the weighting and the solid
//! collision term, where the covered cells get their solid term, and the block of a lattice
//! decomposed over ranks.

use super::block::ImbBlock;

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
    /// Where the lattice is one block of a lattice decomposed over ranks: where the block lies
    /// (the particles' coordinates are the whole lattice's).
    pub block: Option<ImbBlock>,
}

impl Default for ImbOptions {
    fn default() -> Self {
        Self {
            slots: 2,
            seed_weighting: false,
            solid_collision: SolidCollision::NobleTorczynski,
            covered_cells: CoveredCells::Auto,
            block: None,
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
    /// The three timed on the run's first steps, the fastest kept (trials.rs); the redo until
    /// then, and in runs too short for the trial.
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

    /// The scene's `coupling.covered_cells` ("auto", "fused", "redo", "skip"; "timed" is "auto"
    /// timed on every device, coupled/ways.rs).
    pub fn from_name(name: &str) -> Option<CoveredCells> {
        match name {
            "auto" => Some(CoveredCells::Auto),
            "fused" => Some(CoveredCells::Fused),
            "redo" => Some(CoveredCells::Redo),
            "skip" => Some(CoveredCells::Skip),
            _ => None,
        }
    }

    /// Whether the solid term goes in the fluid kernels (`Auto` taken as the redo it starts with).
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
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Auto takes the redo until the trial (trials.rs) times the three; a definite way stays.
    #[test]
    fn auto_is_the_redo_until_timed() {
        let auto = CoveredCells::Auto;
        assert_eq!(auto.definite(), CoveredCells::Redo);
        assert!(!auto.fused());
        assert_eq!(CoveredCells::Redo.definite(), CoveredCells::Redo);
        assert_eq!(CoveredCells::Fused.definite(), CoveredCells::Fused);
    }
}
