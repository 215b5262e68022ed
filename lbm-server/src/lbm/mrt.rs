//! D3Q19 multiple-relaxation-time collision (d'Humieres et al. 2002): the orthogonal moment basis M
//! and, for given relaxation rates S, the matrices the kernels apply in population space:
//! f* = f - A (f - f_eq) + B S_guo with A = M^-1 S M and B = M^-1 (I - S/2) M.

use super::d3q19::C;

/// Rows of M as polynomials of c (Gram-Schmidt order of d'Humieres 2002).
fn moment_row(k: usize, c: [f64; 3]) -> f64 {
    let [x, y, z] = c;
    let c2 = x * x + y * y + z * z;
    match k {
        0 => 1.0,
        1 => 19.0 * c2 - 30.0,
        2 => (21.0 * c2 * c2 - 53.0 * c2 + 24.0) / 2.0,
        3 => x,
        4 => (5.0 * c2 - 9.0) * x,
        5 => y,
        6 => (5.0 * c2 - 9.0) * y,
        7 => z,
        8 => (5.0 * c2 - 9.0) * z,
        9 => 3.0 * x * x - c2,
        10 => (3.0 * c2 - 5.0) * (3.0 * x * x - c2),
        11 => y * y - z * z,
        12 => (3.0 * c2 - 5.0) * (y * y - z * z),
        13 => x * y,
        14 => y * z,
        15 => x * z,
        16 => (y * y - z * z) * x,
        17 => (z * z - x * x) * y,
        _ => (x * x - y * y) * z,
    }
}

/// The moment matrix M[k][i].
pub fn moment_matrix() -> [[f64; 19]; 19] {
    std::array::from_fn(|k| std::array::from_fn(|i| moment_row(k, C[i].map(|v| v as f64))))
}

/// Relaxation rates of the 19 moments.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rates {
    /// Shear viscosity rate 1/tau (moments 9, 11, 13, 14, 15).
    pub nu: f64,
    /// Bulk (energy) moment e.
    pub e: f64,
    /// Energy square epsilon.
    pub epsilon: f64,
    /// Energy fluxes q.
    pub q: f64,
    /// Ghost moments pi (10, 12).
    pub pi: f64,
    /// Ghost moments m (16-18).
    pub m: f64,
}

impl Rates {
    /// d'Humieres et al. (2002) rates for the non-hydrodynamic moments.
    pub fn dhumieres(omega: f64) -> Self {
        Self {
            nu: omega,
            e: 1.19,
            epsilon: 1.4,
            q: 1.2,
            pi: 1.4,
            m: 1.98,
        }
    }

    /// Rate of moment k. Conserved moments (0, 3, 5, 7) get 1: irrelevant for them.
    pub fn of(&self, k: usize) -> f64 {
        match k {
            0 | 3 | 5 | 7 => 1.0,
            1 => self.e,
            2 => self.epsilon,
            4 | 6 | 8 => self.q,
            9 | 11 | 13 | 14 | 15 => self.nu,
            10 | 12 => self.pi,
            _ => self.m,
        }
    }
}

/// (A, B) in population space, row-major 19 x 19.
pub fn collision_matrices(rates: &Rates) -> ([[f64; 19]; 19], [[f64; 19]; 19]) {
    let m = moment_matrix();
    let norm: [f64; 19] = std::array::from_fn(|k| m[k].iter().map(|v| v * v).sum());
    let project = |scale: &dyn Fn(usize) -> f64| -> [[f64; 19]; 19] {
        // (M^-1 D M)[i][j] = sum_k M[k][i] / |M_k|^2 * d_k * M[k][j]
        std::array::from_fn(|i| {
            std::array::from_fn(|j| (0..19).map(|k| m[k][i] / norm[k] * scale(k) * m[k][j]).sum())
        })
    };
    let a = project(&|k| rates.of(k));
    let b = project(&|k| 1.0 - rates.of(k) / 2.0);
    (a, b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moment_basis_is_orthogonal() {
        let m = moment_matrix();
        for a in 0..19 {
            for b in 0..19 {
                let dot: f64 = (0..19).map(|i| m[a][i] * m[b][i]).sum();
                if a != b {
                    assert!(dot.abs() < 1e-12, "rows {a} and {b}: {dot}");
                } else {
                    assert!(dot > 0.0);
                }
            }
        }
    }

    #[test]
    fn equal_rates_reduce_to_bgk() {
        let omega = 1.3;
        let rates = Rates {
            nu: omega,
            e: omega,
            epsilon: omega,
            q: omega,
            pi: omega,
            m: omega,
        };
        let (a, _) = collision_matrices(&rates);
        let m = moment_matrix();
        // A non-equilibrium vector orthogonal to the conserved moments (rows 0, 3, 5, 7).
        let mut v: [f64; 19] = std::array::from_fn(|i| ((i * 7 + 3) % 11) as f64 - 5.0);
        for k in [0, 3, 5, 7] {
            let norm: f64 = m[k].iter().map(|x| x * x).sum();
            let proj: f64 = (0..19).map(|i| m[k][i] * v[i]).sum::<f64>() / norm;
            for i in 0..19 {
                v[i] -= proj * m[k][i];
            }
        }
        for i in 0..19 {
            let av: f64 = (0..19).map(|j| a[i][j] * v[j]).sum();
            assert!((av - omega * v[i]).abs() < 1e-12);
        }
    }
}
