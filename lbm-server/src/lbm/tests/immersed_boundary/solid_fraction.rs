//! The solid fraction (that eq. 7's B weighs): its sum over the cells is the sphere's volume,
//! and every cell with one lies in the particle's bounding box.

use super::*;

#[test]
fn solid_fraction_sums_to_the_sphere_volume() {
    // Worst of 2000, 500 and 100 random centres (docs/imb.md): 1.1%, 0.39%, 0.05%.
    for (r, tolerance) in [(2.0, 0.015), (4.0, 0.005), (8.0, 0.001)] {
        for k in 0..16 {
            let c = [0.37, 0.61, 0.83].map(|a: f64| 10.0 + (a * k as f64).fract());
            let volume = covered_volume(c, r);
            let exact = 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
            let err = (volume - exact).abs() / exact;
            assert!(
                err < tolerance,
                "r = {r}, centre {c:?}: covered volume {volume} vs {exact} ({err:.2e})"
            );
        }
    }
}

#[test]
fn the_bounding_box_holds_every_cell_with_a_solid_fraction() {
    let setup = Setup::new([24; 3], [Face::Periodic; 6], 0.7, Operator::Bgk);
    for r in [0.3f64, 0.7, 1.3, 2.0, 2.5, 4.0, 7.3] {
        // Centres with x - r and x + r on cell faces included.
        for offset in [0.0, 0.25, 0.5, 0.999, 1.0 - r.fract()] {
            let p = SolidParticle {
                position: [11.0 + offset, 12.0 - offset, 11.5 + offset],
                radius: r,
                ..Default::default()
            };
            let in_box: f64 = reference::box_cells(&setup, &p)
                .map(|(_, x)| reference::solid_fraction(x, p.position, r))
                .sum();
            let everywhere: f64 = (0..setup.cells())
                .map(|k| setup.coords(k).map(|v| v as f64 + 0.5))
                .map(|x| reference::solid_fraction(x, p.position, r))
                .sum();
            assert!(
                (in_box - everywhere).abs() < 1e-9,
                "r = {r}, centre {:?}: {in_box} in the box, {everywhere} in the grid",
                p.position
            );
        }
    }
}

/// The sum of the solid fractions of a 21^3 grid around a sphere.
fn covered_volume(c: [f64; 3], r: f64) -> f64 {
    let mut volume = 0.0;
    for x in 0..21 {
        for y in 0..21 {
            for z in 0..21 {
                volume += reference::solid_fraction([x, y, z].map(|v| v as f64 + 0.5), c, r);
            }
        }
    }
    volume
}
