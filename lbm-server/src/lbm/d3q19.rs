//! The D3Q19 lattice (seed eq. 1-6): velocities, weights, opposites, equilibrium, Guo forcing.
//!
//! Direction order (as in FluidX3D): 0 rest, 1-6 the faces (+x -x +y -y +z -z), 7-18 the edges in
//! opposite pairs, so that `opposite(i)` is the neighbour index of the pair.

/// Lattice velocities c_i (seed eq. 2).
pub const C: [[i32; 3]; 19] = [
    [0, 0, 0],
    [1, 0, 0],
    [-1, 0, 0],
    [0, 1, 0],
    [0, -1, 0],
    [0, 0, 1],
    [0, 0, -1],
    [1, 1, 0],
    [-1, -1, 0],
    [1, 0, 1],
    [-1, 0, -1],
    [0, 1, 1],
    [0, -1, -1],
    [1, -1, 0],
    [-1, 1, 0],
    [1, 0, -1],
    [-1, 0, 1],
    [0, 1, -1],
    [0, -1, 1],
];

/// Weights w_i (of the equilibrium, seed eq. 3).
pub const W: [f64; 19] = [
    1.0 / 3.0,
    1.0 / 18.0,
    1.0 / 18.0,
    1.0 / 18.0,
    1.0 / 18.0,
    1.0 / 18.0,
    1.0 / 18.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 36.0,
];

/// Index of -c_i.
pub const fn opposite(i: usize) -> usize {
    if i == 0 {
        0
    } else if i % 2 == 1 {
        i + 1
    } else {
        i - 1
    }
}

/// c_i . v
pub fn dot(i: usize, v: [f64; 3]) -> f64 {
    C[i][0] as f64 * v[0] + C[i][1] as f64 * v[1] + C[i][2] as f64 * v[2]
}

/// Shifted equilibrium f_eq_i - w_i (seed eq. 3) for density rho and velocity u (second order in u).
pub fn equilibrium_shifted(i: usize, rho: f64, u: [f64; 3]) -> f64 {
    let cu = dot(i, u);
    let uu = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
    W[i] * ((rho - 1.0) + rho * (3.0 * cu + 4.5 * cu * cu - 1.5 * uu))
}

/// Guo forcing term S_i = w_i [3 (c_i - u) + 9 (c_i . u) c_i] . F (seed eq. 1's G_i, before the
/// (1 - omega/2) factor).
#[cfg(test)]
pub fn guo_source(i: usize, u: [f64; 3], force: [f64; 3]) -> f64 {
    let cu = dot(i, u);
    (0..3)
        .map(|a| (3.0 * (C[i][a] as f64 - u[a]) + 9.0 * cu * C[i][a] as f64) * force[a])
        .sum::<f64>()
        * W[i]
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)]
mod tests {
    use super::*;

    #[test]
    fn lattice_is_isotropic_and_paired() {
        let w: f64 = W.iter().sum();
        assert!((w - 1.0).abs() < 1e-15);
        for a in 0..3 {
            for b in 0..3 {
                let m2: f64 = (0..19).map(|i| W[i] * (C[i][a] * C[i][b]) as f64).sum();
                let expect = if a == b { 1.0 / 3.0 } else { 0.0 };
                assert!((m2 - expect).abs() < 1e-15);
            }
        }
        for i in 0..19 {
            let o = opposite(i);
            assert_eq!(opposite(o), i);
            assert_eq!([-C[i][0], -C[i][1], -C[i][2]], C[o]);
        }
    }

    #[test]
    fn equilibrium_has_the_right_moments() {
        let (rho, u) = (1.05, [0.03, -0.02, 0.01]);
        let feq: Vec<f64> = (0..19).map(|i| equilibrium_shifted(i, rho, u) + W[i]).collect();
        let m0: f64 = feq.iter().sum();
        assert!((m0 - rho).abs() < 1e-14);
        for a in 0..3 {
            let j: f64 = (0..19).map(|i| feq[i] * C[i][a] as f64).sum();
            assert!((j - rho * u[a]).abs() < 1e-14);
        }
    }
}
