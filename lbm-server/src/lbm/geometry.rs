//! What the lattice looks like: size, the boundary type of each domain face, solid cells, and the
//! collision operator. Everything in lattice units.

use super::kernel::Kernel;
use super::mrt;
use super::storage::Storage;

/// Boundary type of a domain face (the wall lies half-way between the last cell and the outside).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Face {
    /// Wraps around to the opposite face (which must be periodic too).
    Periodic,
    /// No-slip wall at rest: half-way bounce-back.
    Wall,
    /// No-slip wall moving with this velocity (Ladd's bounce-back with momentum term).
    MovingWall([f64; 3]),
    /// Velocity inlet: bounce-back imposing this velocity.
    VelocityInlet([f64; 3]),
    /// Pressure (density) outlet: anti-bounce-back with this density.
    PressureOutlet(f64),
}

impl Face {
    /// Code used by the shader.
    pub fn code(&self) -> u32 {
        match self {
            Face::Periodic => 0,
            Face::Wall => 1,
            Face::MovingWall(_) => 2,
            Face::VelocityInlet(_) => 2,
            Face::PressureOutlet(_) => 3,
        }
    }

    /// (velocity, density) parameters of the face.
    pub fn values(&self) -> ([f64; 3], f64) {
        match *self {
            Face::MovingWall(u) | Face::VelocityInlet(u) => (u, 1.0),
            Face::PressureOutlet(rho) => ([0.0; 3], rho),
            _ => ([0.0; 3], 1.0),
        }
    }
}

/// Collision operator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Operator {
    /// Single relaxation time (seed eq. 4).
    Bgk,
    /// Two relaxation times with the magic parameter Lambda (3/16 puts the bounce-back wall
    /// exactly half-way for Poiseuille flow, independent of tau).
    Trt { magic: f64 },
    /// Multiple relaxation times on the d'Humieres moments; the shear rate is 1/tau.
    Mrt { rates: mrt::Rates },
}

impl Operator {
    pub fn code(&self) -> u32 {
        match self {
            Operator::Bgk => 0,
            Operator::Trt { .. } => 1,
            Operator::Mrt { .. } => 2,
        }
    }

    pub fn name(&self) -> &'static str {
        match self {
            Operator::Bgk => "bgk",
            Operator::Trt { .. } => "trt",
            Operator::Mrt { .. } => "mrt",
        }
    }
}

/// A lattice ready to run: size, faces, solid mask, relaxation, body force.
#[derive(Debug, Clone)]
pub struct Setup {
    pub n: [usize; 3],
    pub faces: [Face; 6],
    /// One flag per cell, x fastest: true = solid (no-slip, at rest).
    pub solid: Vec<bool>,
    /// Relaxation time of the shear moments.
    pub tau: f64,
    pub operator: Operator,
    /// Body force density (lattice units), Guo forcing.
    pub force: [f64; 3],
    /// Steps over which the velocity inlets and moving walls rise from rest
    /// (`lattice.ramp_time` / dt; 0: at full velocity from the first step).
    pub ramp_steps: f64,
    /// How the populations are stored on the device (`lattice.storage`).
    pub storage: Storage,
    /// The fluid kernels a lattice starts with (`lattice.kernel`).
    pub kernel: Kernel,
    /// The faces (x_min, x_max, y_min, y_max, z_min, z_max) whose outermost layer of cells is a
    /// ghost layer: a neighbouring rank's cells, whose populations the halo exchange writes
    /// (`crate::parallel`). Their face is a wall that closes the ghost layer; the health check
    /// leaves their cells out. None on a lattice held by one rank.
    pub ghost_faces: [bool; 6],
}

/// TRT's antisymmetric relaxation time tau- = 1/2 + Lambda / (tau - 1/2) of magic parameter
/// Lambda at shear relaxation time tau.
pub fn tau_minus(magic: f64, tau: f64) -> f64 {
    0.5 + magic / (tau - 0.5)
}

/// What lies along a link from a fluid cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Link {
    Cell(usize),
    /// The face crossed and its index (x_min, x_max, y_min, y_max, z_min, z_max), or a solid
    /// cell ([`SOLID_FACE`]).
    Boundary(Face, usize),
}

/// The face index of [`Link::Boundary`] into a solid cell.
pub const SOLID_FACE: usize = 6;

impl Setup {
    pub fn new(n: [usize; 3], faces: [Face; 6], tau: f64, operator: Operator) -> Self {
        Self {
            n,
            faces,
            solid: vec![false; n[0] * n[1] * n[2]],
            tau,
            operator,
            force: [0.0; 3],
            ramp_steps: 0.0,
            storage: Storage::Fp32,
            kernel: Kernel::Quads,
            ghost_faces: [false; 6],
        }
    }

    /// The share of their velocity the velocity inlets and moving walls have in the step from
    /// `step` to `step + 1`: (1 - cos(pi (step + 1) / ramp_steps)) / 2 until the ramp's end, then 1.
    pub fn face_ramp(&self, step: u64) -> f64 {
        let x = (step + 1) as f64 / self.ramp_steps;
        if x >= 1.0 || x.is_nan() {
            1.0
        } else {
            0.5 * (1.0 - (std::f64::consts::PI * x).cos())
        }
    }

    /// Whether axis a (0 x, 1 y, 2 z) is periodic (its two faces come in a pair).
    pub fn periodic(&self, axis: usize) -> bool {
        self.faces[2 * axis] == Face::Periodic
    }

    /// Whether cell `x` lies in a ghost layer ([`Setup::ghost_faces`]).
    pub fn is_ghost(&self, x: [usize; 3]) -> bool {
        (0..3).any(|a| {
            (x[a] == 0 && self.ghost_faces[2 * a]) || (x[a] + 1 == self.n[a] && self.ghost_faces[2 * a + 1])
        })
    }

    pub fn cells(&self) -> usize {
        self.n[0] * self.n[1] * self.n[2]
    }

    pub fn index(&self, x: [usize; 3]) -> usize {
        x[0] + self.n[0] * (x[1] + self.n[1] * x[2])
    }

    pub fn coords(&self, cell: usize) -> [usize; 3] {
        [
            cell % self.n[0],
            (cell / self.n[0]) % self.n[1],
            cell / (self.n[0] * self.n[1]),
        ]
    }

    /// The neighbour of `cell` along `c` (periodic faces wrap). A link that crosses several
    /// non-periodic faces (an edge or corner) takes the face of highest code (wall < moving wall or
    /// inlet < outlet): a moving lid then owns its edge links and conserves mass. A solid neighbour
    /// is a wall at rest.
    pub fn link(&self, cell: usize, c: [i32; 3]) -> Link {
        let x = self.coords(cell);
        let mut y = [0usize; 3];
        let mut crossed: Option<(Face, usize)> = None;
        for a in 0..3 {
            let v = x[a] as i64 + c[a] as i64;
            let n = self.n[a] as i64;
            if v < 0 || v >= n {
                let index = 2 * a + usize::from(v >= n);
                let face = self.faces[index];
                if face != Face::Periodic && crossed.is_none_or(|(f, _)| face.code() > f.code()) {
                    crossed = Some((face, index));
                }
            }
            y[a] = v.rem_euclid(n) as usize;
        }
        if let Some((face, index)) = crossed {
            return Link::Boundary(face, index);
        }
        let t = self.index(y);
        if self.solid[t] {
            Link::Boundary(Face::Wall, SOLID_FACE)
        } else {
            Link::Cell(t)
        }
    }

    /// Omega of the antisymmetric (odd) moments for TRT.
    pub fn omega_minus(&self) -> f64 {
        match self.operator {
            Operator::Trt { magic } => 1.0 / tau_minus(magic, self.tau),
            _ => 1.0 / self.tau,
        }
    }

    /// Kinematic viscosity nu = (tau - 1/2) / 3 (seed eq. 4 in lattice units, c = dt = 1).
    pub fn viscosity(&self) -> f64 {
        (self.tau - 0.5) / 3.0
    }
}

/// The 19 shifted populations (f_i - w_i) of one cell.
pub type Cell = [f64; 19];
