//! The fluid's answer to a DEM's Hello (the Welcome, in the DEM's units), and the negotiable
//! physics it leaves to a DEM that declares them (PROTOCOL.md 4.5).

use protocol::{Hello, Physics, Welcome};
use scene::Scene;

/// The negotiable effects the fluid leaves to a DEM that declares them: lubrication (a DEM that
/// integrates the squeeze films in its own sub-steps does it better than a force held over the
/// fluid step; PROTOCOL.md 4.5).
pub(super) fn yielded(hello: &Hello) -> u64 {
    hello.physics & Physics::LUBRICATION
}

/// The fluid's answer to a DEM's Hello, in the DEM's units, for a run of `steps` steps from
/// `first_step` (a resumed run's checkpoint's; else 0).
pub(super) fn welcome_for(
    scene: &Scene,
    steps: u64,
    first_step: u64,
    hello: &Hello,
    physics: u64,
) -> Welcome {
    let u = hello.units;
    let accel = u.length_m / (u.time_s * u.time_s);
    let mut w = Welcome::accepted(&format!(
        "lbm-server {} (lattice-Boltzmann + IMB)",
        env!("CARGO_PKG_VERSION")
    ));
    w.steps = steps;
    w.dt = scene.time.dt / u.time_s;
    w.domain_min = scene.domain.min.map(|x| x / u.length_m);
    w.domain_max = scene.domain.max.map(|x| x / u.length_m);
    w.gravity = scene.gravity.map(|g| g / accel);
    w.fluid_density = scene.fluid.density / (u.mass_kg / u.length_m.powi(3));
    w.fluid_viscosity = scene.fluid.dynamic_viscosity / (u.mass_kg / (u.length_m * u.time_s));
    w.physics = physics;
    w.periodic = Welcome::periodic_bits(scene.periodic_axes());
    w.first_step = first_step;
    w.cell_size = scene.lattice_units.as_ref().map_or(0.0, |l| l.dx / u.length_m);
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fluid applies lubrication unless the DEM declares it (then the DEM integrates it in its
    /// sub-steps); gravity and buoyancy are not negotiable.
    #[test]
    fn the_fluid_leaves_lubrication_to_a_dem_that_declares_it() {
        let scene = Scene::default_scene();
        let ours = Physics::LATTICE_BOLTZMANN | Physics::BUOYANCY | Physics::LUBRICATION;
        let welcome = |dem: u64| {
            let hello = Hello::new(protocol::Units::SI, dem, 1, "test");
            welcome_for(&scene, 1, 0, &hello, ours & !yielded(&hello)).physics
        };
        assert_eq!(welcome(Physics::GRAVITY), ours);
        assert_eq!(
            welcome(Physics::GRAVITY | Physics::LUBRICATION),
            ours & !Physics::LUBRICATION
        );
        assert_eq!(
            welcome(Physics::GRAVITY | Physics::BUOYANCY),
            ours,
            "a conflict stays one"
        );
    }
}
