//! Which cells a particle covers: the reach of a sphere's solid fraction, its bounding box, and
//! the fraction of a lattice's cells that spheres cover.

/// How far from the centre of a sphere of radius `r` (cells) a cell's centre gets a solid
/// fraction: r + 1/2 - 1/(12 r). The fraction at distance d is clamp(reach - d, 0, 1)
/// (imb.wgsl `solid_fraction`, docs/imb.md "Solid fraction").
pub fn solid_reach(r: f64) -> f64 {
    r - 1.0 / (12.0 * r) + 0.5
}

/// The fraction of the cells that spheres of these radii (cells) cover: those whose centre lies
/// within [`solid_reach`] of a sphere's centre (where the solid fraction is above 0), counted per
/// sphere (overlaps twice).
pub fn covered_fraction(radii: impl Iterator<Item = f64>, cells: usize) -> f64 {
    let covered: f64 = radii
        .map(|r| 4.0 / 3.0 * std::f64::consts::PI * solid_reach(r).powi(3))
        .sum();
    covered / cells as f64
}

/// The largest bounding box edge: imb.wgsl's `divide` takes box indices below 2^24 = 256^3.
pub(super) const MAX_BOX_EDGE: u32 = 255;

/// Edge of the bounding box of a sphere of radius r, in cells (matches `cover` in imb.wgsl): from
/// the cell holding x - r to the one holding x + r, the cells whose centre lies within r + 1/2 of
/// x along each axis (beyond, the solid fraction is 0; docs/imb.md).
pub fn box_edge(radius: f64) -> u32 {
    // ceil(2 r) without `f64::ceil`, a libm call on baseline x86-64 that made it a third of the
    // host's pass over the particles; saturating for radii beyond u32 (refused later).
    let diameter = 2.0 * radius;
    let whole = diameter as u32;
    let ceil = if (whole as f64) < diameter {
        whole.saturating_add(1)
    } else {
        whole
    };
    ceil.saturating_add(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Cells whose centre lies where the solid fraction of a sphere at `c` (radius r) is above 0.
    fn cells_covered(c: [f64; 3], r: f64) -> usize {
        let reach = solid_reach(r);
        let m = reach.ceil() as i64 + 1;
        let base = c.map(|x| x.floor() as i64);
        let mut count = 0;
        for dz in -m..=m {
            for dy in -m..=m {
                for dx in -m..=m {
                    let q = [base[0] + dx, base[1] + dy, base[2] + dz];
                    let d2: f64 = (0..3).map(|a| (q[a] as f64 + 0.5 - c[a]).powi(2)).sum();
                    count += usize::from(d2.sqrt() < reach);
                }
            }
        }
        count
    }

    #[test]
    fn covered_fraction_counts_the_cells_with_a_solid_fraction() {
        for (r, tolerance) in [(2.0, 0.08), (4.0, 0.03), (8.0, 0.01)] {
            let centres = [
                [10.0, 10.0, 10.0],
                [10.3, 10.7, 10.1],
                [10.5, 10.5, 10.5],
                [10.9, 10.2, 10.6],
            ];
            let counted: usize = centres.iter().map(|&c| cells_covered(c, r)).sum();
            let estimate = covered_fraction(std::iter::repeat_n(r, centres.len()), 1000) * 1000.0;
            let error = (estimate - counted as f64).abs() / counted as f64;
            assert!(
                error < tolerance,
                "r {r}: {estimate:.1} against {counted} cells counted"
            );
        }
    }
}
