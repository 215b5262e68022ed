//! The atoms as the fluid's particle states (clients/liggghts/lbm_liggghts.py's `states_of`,
//! compiled): ids atom ID - 1, centres wrapped along the periodic axes (LIGGGHTS wraps only when
//! it rebuilds its neighbour lists).

use crate::lammps::{row_of, Atoms};
use protocol::ParticleState;

/// The domain of the fluid: its corners and which axes are periodic.
#[derive(Debug, Clone, Copy)]
pub struct Domain {
    pub lo: [f64; 3],
    pub hi: [f64; 3],
    pub periodic: [bool; 3],
}

/// Writes the atoms' states to `out` (as many as there are atoms).
pub fn gather(atoms: &Atoms, domain: &Domain, out: &mut [ParticleState]) -> Result<(), String> {
    for (i, s) in out.iter_mut().enumerate() {
        let mut position = atoms.x[i];
        for (a, p) in position.iter_mut().enumerate() {
            if domain.periodic[a] {
                let (lo, span) = (domain.lo[a], domain.hi[a] - domain.lo[a]);
                *p = lo + floored_mod(*p - lo, span);
            }
        }
        *s = ParticleState {
            id: row_of(atoms.tag[i])? as u64,
            position,
            velocity: atoms.v[i],
            angular_velocity: atoms.omega[i],
            radius: atoms.radius[i],
        };
    }
    Ok(())
}

/// numpy's `mod` for a positive divisor: the remainder with the divisor's sign.
fn floored_mod(a: f64, b: f64) -> f64 {
    let r = a % b;
    if r != 0.0 && (r < 0.0) != (b < 0.0) {
        r + b
    } else {
        r
    }
}

#[cfg(test)]
mod tests {
    use super::floored_mod;

    #[test]
    fn the_remainder_takes_the_divisors_sign() {
        assert_eq!(floored_mod(-0.25, 1.0), 0.75);
        assert_eq!(floored_mod(1.25, 1.0), 0.25);
        assert_eq!(floored_mod(0.5, 1.0), 0.5);
    }
}
