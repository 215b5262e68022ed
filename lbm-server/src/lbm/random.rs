//! Reproducible random populations for the kernel tests and the mass-conservation check.

use super::d3q19::equilibrium_shifted;
use super::geometry::{Cell, Setup};

/// xorshift64*: reproducible random numbers without a dependency.
pub struct Random(u64);

impl Random {
    pub fn new(seed: u64) -> Self {
        Self(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }

    /// Uniform in [-1, 1).
    pub fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let v = self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11;
        v as f64 / (1u64 << 52) as f64 - 1.0
    }
}

/// Near-equilibrium random populations with a random non-equilibrium part.
pub fn random_populations(setup: &Setup, seed: u64) -> Vec<Cell> {
    let mut r = Random::new(seed);
    (0..setup.cells())
        .map(|_| {
            let rho = 1.0 + 0.05 * r.next();
            let u = [0.05 * r.next(), 0.05 * r.next(), 0.05 * r.next()];
            std::array::from_fn(|i| equilibrium_shifted(i, rho, u) + 1e-3 * r.next())
        })
        .collect()
}
