//! SI <-> lattice units: the one place where a length, a velocity, a force, an acceleration or a
//! number of steps changes units. The scales are the cell size dx [m], the time step dt [s] and
//! the fluid's density [kg/m^3] (the lattice's density 1); `LatticeUnits::derive` sets dx and dt
//! and converts the scene's fields with them.

use super::LatticeUnits;

impl LatticeUnits {
    /// Cells of an SI length [m]: length / dx.
    pub fn cells(&self, length: f64) -> f64 {
        length / self.dx
    }

    /// Lattice position (cells from the lattice's corner `origin` [m]) of an SI point [m].
    pub fn lattice_position(&self, point: [f64; 3], origin: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|a| self.cells(point[a] - origin[a]))
    }

    /// SI centre [m] of the cell at `cell` (its indices) of a lattice whose corner is at `origin` [m].
    pub fn cell_centre(&self, cell: [usize; 3], origin: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|a| origin[a] + (cell[a] as f64 + 0.5) * self.dx)
    }

    /// Lattice velocity of an SI velocity [m/s]: u dt / dx.
    pub fn velocity(&self, u: [f64; 3]) -> [f64; 3] {
        u.map(|v| v * self.dt / self.dx)
    }

    /// Lattice angular velocity (radians per step) of an SI one [rad/s].
    pub fn angular_velocity(&self, w: [f64; 3]) -> [f64; 3] {
        w.map(|w| w * self.dt)
    }

    /// The SI velocity of a lattice velocity of 1 [m/s]: dx / dt.
    pub fn velocity_unit(&self) -> f64 {
        self.dx / self.dt
    }

    /// The SI force of a lattice force of 1 in a fluid of `density` [kg/m^3]: rho dx^4 / dt^2 [N].
    pub fn force_unit(&self, density: f64) -> f64 {
        density * self.dx.powi(4) / (self.dt * self.dt)
    }

    /// The SI torque of a lattice torque of 1 in a fluid of `density` [kg/m^3] [N m].
    pub fn torque_unit(&self, density: f64) -> f64 {
        self.force_unit(density) * self.dx
    }

    /// SI acceleration [m/s^2] of a lattice acceleration (force density at the lattice's density
    /// 1): a dx / dt^2.
    pub fn si_acceleration(&self, a: f64) -> f64 {
        a * self.dx / (self.dt * self.dt)
    }

    /// Seconds of `steps` lattice steps.
    pub fn seconds(&self, steps: f64) -> f64 {
        steps * self.dt
    }
}
