//! Initial-overlap check over a hashed cell grid: O(N), never O(N^2).

use crate::InitialParticle;
use std::collections::HashMap;

/// Pairs (id a, id b, overlap depth [m]) whose overlap exceeds `fraction` of the smaller radius.
pub fn overlapping_pairs(particles: &[InitialParticle], fraction: f64) -> Vec<(u64, u64, f64)> {
    let r_max = particles.iter().map(|p| p.radius).fold(0.0, f64::max);
    if particles.len() < 2 || r_max <= 0.0 {
        return Vec::new();
    }
    let cell = 2.0 * r_max;
    let key = |p: &[f64; 3]| p.map(|x| (x / cell).floor() as i64);
    let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    for (i, p) in particles.iter().enumerate() {
        grid.entry(key(&p.position)).or_default().push(i);
    }
    let mut pairs = Vec::new();
    for (i, p) in particles.iter().enumerate() {
        let k = key(&p.position);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let Some(cell) = grid.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) else {
                        continue;
                    };
                    for &j in cell.iter().filter(|&&j| j > i) {
                        let q = &particles[j];
                        let d = (0..3)
                            .map(|a| (p.position[a] - q.position[a]).powi(2))
                            .sum::<f64>()
                            .sqrt();
                        let depth = p.radius + q.radius - d;
                        if depth > fraction * p.radius.min(q.radius) {
                            pairs.push((p.id, q.id, depth));
                        }
                    }
                }
            }
        }
    }
    pairs.sort_by_key(|p| (p.0, p.1));
    pairs
}
