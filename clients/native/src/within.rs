//! The fluid's loads within a fluid step, as dem-client applies them in its DEM sub-steps
//! (clients/python/substep_loads.py's `SubstepLoads`, compiled): the sub-step drag of PROTOCOL.md
//! 3.2, F(s) = F_n - c (v(s) - v_n - a_n s), T(s) = T_n - c_r (w(s) - w_n - alpha_n s), with
//! a_n = (F_n + J_{n-1} / dt) / m + g, alpha_n likewise with the angular impulse, and the squeeze
//! films of 4.5 ([`SqueezeFilms`]). Per-particle tables are indexed by particle id.

use crate::films::SqueezeFilms;
use crate::vec3::{add, add_to, norm, scale, sub, V3};
use protocol::substep_drag::substep_drag;

/// The state of one atom as the loads read it (rows of LIGGGHTS's arrays).
pub struct Kinematics<'a> {
    pub x: &'a [V3],
    pub v: &'a [V3],
    pub omega: &'a [V3],
    pub radius: &'a [f64],
}

/// The force and torque on each particle at a force evaluation s into fluid step n.
pub struct SubstepLoads {
    /// rho_f / dt_fluid (0: no drag within the step).
    rate: f64,
    dt: f64,
    pub gravity: V3,
    pub films: Option<SqueezeFilms>,
    force: Vec<V3>,
    torque: Vec<V3>,
    v0: Vec<V3>,
    w0: Vec<V3>,
    accel: Vec<V3>,
    spin_accel: Vec<V3>,
    impulse: Vec<V3>,
    angular_impulse: Vec<V3>,
}

impl SubstepLoads {
    pub fn new(fluid_density: f64, dt: f64, gravity: V3, drag: bool, films: Option<SqueezeFilms>) -> Self {
        SubstepLoads {
            rate: if drag { fluid_density / dt } else { 0.0 },
            dt,
            gravity,
            films,
            force: Vec::new(),
            torque: Vec::new(),
            v0: Vec::new(),
            w0: Vec::new(),
            accel: Vec::new(),
            spin_accel: Vec::new(),
            impulse: Vec::new(),
            angular_impulse: Vec::new(),
        }
    }

    /// Takes the reply (`force`, `torque` by id) to the states (`rows[i]` the id of atom i):
    /// F_n, T_n, v_n, w_n, a_n, alpha_n; the impulses summed since the last `hold` make the
    /// previous step's mean contact load.
    pub fn hold(&mut self, rows: &[usize], force: &[V3], torque: &[V3], atoms: &Kinematics, mass: &[f64]) {
        let size = force.len().max(self.impulse.len());
        let (impulse, angular) = (grown(&self.impulse, size), grown(&self.angular_impulse, size));
        for t in self.tables() {
            t.clear();
            t.resize(size, [0.0; 3]);
        }
        for (i, &id) in rows.iter().enumerate() {
            let (m, r) = (mass[i], atoms.radius[i]);
            let inertia = 0.4 * m * (r * r);
            self.force[id] = force[id];
            self.torque[id] = torque[id];
            self.v0[id] = atoms.v[i];
            self.w0[id] = atoms.omega[i];
            self.accel[id] = add(
                scale(add(force[id], scale(impulse[id], 1.0 / self.dt)), 1.0 / m),
                self.gravity,
            );
            self.spin_accel[id] = scale(add(torque[id], scale(angular[id], 1.0 / self.dt)), 1.0 / inertia);
        }
        if let Some(films) = &mut self.films {
            let speed = atoms.v.iter().map(|&v| norm(v)).fold(0.0, f64::max);
            films.candidates(
                rows,
                atoms.x,
                atoms.radius,
                2.0 * speed * self.dt + 1e-3 * films.cutoff,
            );
        }
    }

    /// The loads at time `s` into the step on the atoms (`rows[i]` the id of atom i; the films'
    /// pairs resolved to these rows by `hold` or `remap`), written to `force` and `torque`, the
    /// films first, then the drag in one pass over the atoms; the atoms' contact loads of this
    /// evaluation (`contact`, `contact_torque`) add `substep` times themselves (the films' force
    /// with the contact force) to the impulses.
    #[allow(clippy::too_many_arguments)]
    pub fn loads(
        &mut self,
        rows: &[usize],
        s: f64,
        atoms: &Kinematics,
        contact: impl Fn(usize) -> (V3, V3),
        substep: f64,
        force: &mut [V3],
        torque: &mut [V3],
    ) {
        force.fill([0.0; 3]);
        if let Some(films) = &self.films {
            films.add_forces(atoms.x, atoms.v, atoms.radius, force);
        }
        for (i, &id) in rows.iter().enumerate() {
            let film = force[i];
            let (c, c_r) = substep_drag(self.rate, atoms.radius[i]);
            let spin_lag = sub(sub(atoms.omega[i], self.w0[id]), scale(self.spin_accel[id], s));
            torque[i] = sub(self.torque[id], scale(spin_lag, c_r));
            let lag = sub(sub(atoms.v[i], self.v0[id]), scale(self.accel[id], s));
            let (contact_force, contact_torque) = contact(i);
            add_to(&mut self.impulse[id], scale(add(contact_force, film), substep));
            add_to(&mut self.angular_impulse[id], scale(contact_torque, substep));
            force[i] = add(sub(self.force[id], scale(lag, c)), film);
        }
    }

    /// Every per-id table.
    fn tables(&mut self) -> [&mut Vec<V3>; 8] {
        [
            &mut self.force,
            &mut self.torque,
            &mut self.v0,
            &mut self.w0,
            &mut self.accel,
            &mut self.spin_accel,
            &mut self.impulse,
            &mut self.angular_impulse,
        ]
    }

    /// Grows the tables to `size` ids (zero loads for ids that were not in the reply) and
    /// re-resolves the films' pairs for the atoms' new rows (`row_of_id`; `radius` by row).
    pub fn remap(&mut self, size: usize, row_of_id: &[usize], radius: &[f64]) {
        if let Some(films) = &mut self.films {
            films.remap(row_of_id, radius);
        }
        for t in self.tables() {
            if t.len() < size {
                t.resize(size, [0.0; 3]);
            }
        }
    }
}

/// `t` grown to `size` rows with zeros.
fn grown(t: &[V3], size: usize) -> Vec<V3> {
    let mut out = t.to_vec();
    out.resize(size, [0.0; 3]);
    out
}
