//! Soft-sphere DEM in f64: contact laws, broad phase, walls, velocity-Verlet integration, and the
//! set-up of a world from a scene.

pub mod batch;
pub mod bytes;
pub mod contact;
pub mod lubrication;
pub mod neighbor;
pub mod timestep;
pub mod world;

#[cfg(test)]
mod cross_code;
#[cfg(test)]
mod tests;

use contact::{linear_spring_dashpot, ContactLaw};
use neighbor::Periodic;
use scene::dem::NormalLaw;
use scene::{Scene, SceneError};
use world::{Body, Shape, Wall, World};

/// 3-vector of f64.
pub type V3 = nalgebra::Vector3<f64>;

/// A world built from a scene, with how its time step came about.
pub struct SceneWorld {
    pub world: World,
    /// Shortest contact time of the scene [s].
    pub contact_time: f64,
    /// Largest DEM step the scene allows: `dem.dt`, or t_c / dt_divisor [s].
    pub dt_max: f64,
}

fn v3(a: [f64; 3]) -> V3 {
    V3::new(a[0], a[1], a[2])
}

/// The walls of a scene: planes, boxes (a container becomes six planes), the domain faces.
pub fn walls(scene: &Scene) -> Vec<Wall> {
    let dem = &scene.dem;
    let mut out = Vec::new();
    let container = |out: &mut Vec<Wall>, min: [f64; 3], max: [f64; 3], material: usize, open: [bool; 3]| {
        for a in (0..3).filter(|&a| !open[a]) {
            let mut n = V3::zeros();
            n[a] = 1.0;
            out.push(Wall {
                shape: Shape::Plane {
                    point: v3(min),
                    normal: n,
                },
                material,
            });
            out.push(Wall {
                shape: Shape::Plane {
                    point: v3(max),
                    normal: -n,
                },
                material,
            });
        }
    };
    for p in &dem.plane {
        out.push(Wall {
            shape: Shape::Plane {
                point: v3(p.point),
                normal: v3(p.normal).normalize(),
            },
            material: dem.material_index(p.material.as_deref()),
        });
    }
    for b in &dem.boxes {
        let material = dem.material_index(b.material.as_deref());
        if b.inside {
            container(&mut out, b.min, b.max, material, [false; 3]);
        } else {
            out.push(Wall {
                shape: Shape::Solid {
                    min: v3(b.min),
                    max: v3(b.max),
                },
                material,
            });
        }
    }
    if dem.uses_domain_walls() {
        let material = dem.material_index(dem.domain_wall_material.as_deref());
        // No walls on the periodic faces: the spheres pass through them.
        container(
            &mut out,
            scene.domain.min,
            scene.domain.max,
            material,
            scene.periodic_axes(),
        );
    }
    out
}

/// The spheres of a scene, ids as in `Scene::initial_particles`.
pub fn bodies(scene: &Scene) -> Vec<Body> {
    let dem = &scene.dem;
    let materials = dem.materials();
    let generated = &dem.generated;
    let particles = scene.initial_particles();
    let first_generated = particles.len() - generated.len();
    particles
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let name = (k >= first_generated).then(|| generated[k - first_generated].1.as_str());
            let material = dem.material_index(name);
            let density = materials[material].density.unwrap_or(scene.particles.density);
            Body::sphere(
                p.id,
                v3(p.position),
                v3(p.velocity),
                v3(p.angular_velocity),
                p.radius,
                density,
                material,
            )
        })
        .collect()
}

/// Characteristic impact velocity of the Hertz time-step rule: `dem.contact.impact_velocity`, or
/// sqrt(2 |g| H) + the fastest initial speed (H the domain's extent along g), at least 0.1 m/s.
pub fn impact_velocity(scene: &Scene, bodies: &[Body]) -> f64 {
    if let Some(v) = scene.dem.contact.impact_velocity {
        return v;
    }
    let g = v3(scene.gravity);
    let extent = v3(scene.domain.max) - v3(scene.domain.min);
    let height = if g.norm() > 0.0 {
        extent.dot(&g.abs()) / g.norm()
    } else {
        0.0
    };
    let fastest = bodies.iter().map(|b| b.v.norm()).fold(0.0, f64::max);
    ((2.0 * g.norm() * height).sqrt() + fastest).max(0.1)
}

/// Shortest contact time among the pairs a world can form: the smallest sphere of each material
/// against the smallest of each other material and against each wall material.
pub fn shortest_contact_time(world: &World, v_impact: f64) -> f64 {
    let mut smallest: Vec<(usize, Body)> = Vec::new();
    for b in &world.bodies {
        match smallest.iter_mut().find(|(m, _)| *m == b.material) {
            Some((_, s)) if b.r < s.r => *s = *b,
            Some(_) => {}
            None => smallest.push((b.material, *b)),
        }
    }
    let mut pairs: Vec<(f64, f64, usize, usize)> = Vec::new();
    for (ma, a) in &smallest {
        for (mb, b) in &smallest {
            pairs.push((a.r * b.r / (a.r + b.r), a.m * b.m / (a.m + b.m), *ma, *mb));
        }
        for w in &world.walls {
            pairs.push((world.law.switches.wall_radius_factor * a.r, a.m, *ma, w.material));
        }
    }
    pairs
        .into_iter()
        .map(|(r_eff, m_eff, ma, mb)| {
            pair_contact_time(&world.law, &world.pair(ma, mb), r_eff, m_eff, v_impact)
        })
        .fold(f64::INFINITY, f64::min)
}

/// Contact time of one kind of pair: the undamped Hertz time at `v` or the linear law's.
pub fn pair_contact_time(law: &ContactLaw, m: &contact::PairMaterial, r_eff: f64, m_eff: f64, v: f64) -> f64 {
    match law.normal {
        NormalLaw::Hertz => timestep::hertz_contact_time(m_eff, r_eff, m.y_star, v),
        NormalLaw::Linear => {
            // k_n: the elastic force at a unit overlap.
            let k = linear_spring_dashpot(&law.linear, m.restitution, m_eff, 1.0);
            timestep::linear_contact_time(k.f_elastic, k.gamma_n, m_eff)
        }
    }
}

/// The scene's periodic axes (`Scene::periods`) as the DEM's periodic box (None when there are
/// none).
fn periodic(scene: &Scene) -> Option<Periodic> {
    let periods = scene.periods();
    let box_ = Periodic {
        lo: v3(periods.lo),
        len: periods.len,
    };
    box_.any().then_some(box_)
}

/// Builds the world of a scene and its time step; refuses a `dem.dt` above t_c / 10.
pub fn setup(scene: &Scene, file: &str) -> Result<SceneWorld, SceneError> {
    let bodies = bodies(scene);
    let r_min = bodies.iter().map(|b| b.r).fold(f64::INFINITY, f64::min);
    let skin = scene.dem.skin.unwrap_or(0.5 * r_min);
    let v_impact = impact_velocity(scene, &bodies);
    let law = ContactLaw::from_scene(&scene.dem.contact);
    let materials = scene.dem.materials();
    let mut world = World::new(
        bodies,
        walls(scene),
        law,
        &materials,
        v3(scene.gravity),
        0.0,
        skin,
    );
    // The squeeze films of a coupled run reach one lattice cell further.
    let cutoff = scene.lattice_units.as_ref().map_or(0.0, |u| u.dx);
    world
        .set_periodic(periodic(scene), cutoff)
        .map_err(|problem| SceneError {
            file: file.to_string(),
            // What made the domain periodic: the lattice's faces, or for a granular scene alone
            // `domain.periodic`.
            field: if scene.lattice.is_some() {
                "lattice.faces"
            } else {
                "domain.periodic"
            }
            .into(),
            value: if scene.lattice.is_some() {
                "periodic".into()
            } else {
                format!("{:?}", scene.domain.periodic)
            },
            problem,
        })?;
    let contact_time = shortest_contact_time(&world, v_impact);
    let dt_max = match scene.dem.dt {
        Some(dt) if dt > contact_time / 10.0 => {
            return Err(SceneError {
                file: file.to_string(),
                field: "dem.dt".into(),
                value: format!("{dt} s"),
                problem: format!(
                    "is above the stability limit t_c / 10 = {:.3e} s (shortest contact time t_c = {contact_time:.3e} s)",
                    contact_time / 10.0
                ),
            })
        }
        Some(dt) => dt,
        None => contact_time / scene.dem.dt_divisor,
    };
    world.dt = dt_max;
    Ok(SceneWorld {
        world,
        contact_time,
        dt_max,
    })
}
