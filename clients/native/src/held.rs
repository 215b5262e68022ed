//! The fluid's force and torque on each atom over the LIGGGHTS steps of one fluid step
//! (clients/liggghts/held_loads.py's `HeldLoads`, compiled): held constant, or following the
//! atoms ([`SubstepLoads`]).
//!
//! LIGGGHTS integrates with velocity Verlet; `fix external`'s callback, called where the forces
//! are summed (`post_force`), writes the force into `fexternal` (the fix then adds it to the
//! atoms' force) and adds the torque to the atoms' torque. The coupled loop runs
//! `run k pre no post no`, so the first half kick of a fluid step uses the forces LIGGGHTS summed
//! at the end of the previous one, with the previous loads: [`Loads::hold`] adds the change of
//! the loads to them, so that every LIGGGHTS step of fluid step n sees the loads of step n.

use crate::lammps::{row_of, Atoms, Lammps};
use crate::vec3::{add_to, scale, sub, V3};
use crate::within::{Kinematics, SubstepLoads};
use protocol::ParticleReply;

/// What a callback wrote into its fix's `fexternal` since the last `hold`: the fix's own per-atom
/// array, which LIGGGHTS moves with its atoms when it sorts them or loses some (FixExternal's
/// `copy_arrays`), so that it holds each atom's load until the loads change or atoms come in.
#[derive(Clone, Copy, PartialEq)]
struct Written {
    address: usize,
    count: usize,
}

/// `napply` of the held loads' two `fix external`s: their own loop that adds `fexternal` to the
/// force runs only at the steps that are multiples of it (the callbacks add the loads).
pub const NEVER: i64 = 2_147_483_647;

/// Force and torque by particle id (atom ID - 1), applied by `fix external`.
pub struct Loads {
    pub lammps: Lammps,
    force: Vec<V3>,
    torque: Vec<V3>,
    /// The loads within the fluid step (None: held), the LIGGGHTS step at its start.
    pub within: Option<SubstepLoads>,
    first_step: i64,
    written: Option<Written>,
    written_torque: Option<Written>,
    /// The force fix's `fexternal` at this step (its callback comes first), for the torque's.
    force_rows: Option<(i64, Written)>,
    /// Whether any held torque is not 0.
    any_torque: bool,
    /// Each atom's id, the id -> atom row map, and the spin scratch of the following loads.
    rows: Vec<usize>,
    row_of_id: Vec<usize>,
    spin: Vec<V3>,
    /// What went wrong in the callback (LIGGGHTS cannot be stopped from there).
    pub error: Option<String>,
}

impl Loads {
    pub fn new(lammps: Lammps) -> Loads {
        Loads {
            lammps,
            force: Vec::new(),
            torque: Vec::new(),
            within: None,
            first_step: 0,
            written: None,
            written_torque: None,
            force_rows: None,
            any_torque: false,
            rows: Vec::new(),
            row_of_id: Vec::new(),
            spin: Vec::new(),
            error: None,
        }
    }

    /// Holds the reply's loads. With `ran` (LIGGGHTS ran before: its forces are summed) the
    /// atoms' force and torque take the change of the loads, for the first half kick of the next
    /// run.
    pub fn hold(&mut self, replies: &[ParticleReply], ran: bool) -> Result<(), String> {
        let size = replies
            .iter()
            .map(|r| r.id as usize + 1)
            .max()
            .unwrap_or(0)
            .max(self.force.len());
        // SAFETY: LIGGGHTS is between runs.
        let atoms = unsafe { self.lammps.atoms()? };
        self.map_rows(atoms.tag, size)?;
        let size = self.row_of_id.len();
        let (mut force, mut torque) = (vec![[0.0; 3]; size], vec![[0.0; 3]; size]);
        for r in replies {
            force[r.id as usize] = r.force;
            torque[r.id as usize] = r.torque;
        }
        if self.within.is_some() {
            self.hold_within(&mut force, &torque, &atoms)?;
        }
        if ran {
            for (i, &id) in self.rows.iter().enumerate() {
                add_to(
                    &mut atoms.f[i],
                    sub(force[id], self.force.get(id).copied().unwrap_or_default()),
                );
                add_to(
                    &mut atoms.torque[i],
                    sub(torque[id], self.torque.get(id).copied().unwrap_or_default()),
                );
            }
        }
        self.any_torque = torque.iter().any(|t| *t != [0.0; 3]);
        (self.force, self.torque, self.written, self.written_torque) = (force, torque, None, None);
        Ok(())
    }

    /// Starts the fluid step of `self.within` from the atoms' state; `force` takes the loads at
    /// its start (the drag is 0 there: F_n and the films).
    fn hold_within(&mut self, force: &mut [V3], torque: &[V3], atoms: &Atoms) -> Result<(), String> {
        let (_, step) = self.lammps.clock()?;
        self.first_step = step;
        let kin = Kinematics {
            x: atoms.x,
            v: atoms.v,
            omega: atoms.omega,
            radius: atoms.radius,
        };
        let within = self.within.as_mut().expect("within");
        within.hold(&self.rows, force, torque, &kin, atoms.rmass);
        let mut start = vec![[0.0; 3]; self.rows.len()];
        self.spin.resize(self.rows.len(), [0.0; 3]);
        within.loads(
            &self.rows,
            0.0,
            &kin,
            |_| ([0.0; 3], [0.0; 3]),
            0.0,
            &mut start,
            &mut self.spin,
        );
        for (i, &id) in self.rows.iter().enumerate() {
            force[id] = start[i];
        }
        Ok(())
    }

    /// `rows` (each atom's id) and `row_of_id` for the atoms' tags, ids below `size`.
    fn map_rows(&mut self, tags: &[i32], size: usize) -> Result<(), String> {
        self.rows.clear();
        for &t in tags {
            self.rows.push(row_of(t)?);
        }
        let size = size.max(self.rows.iter().map(|&r| r + 1).max().unwrap_or(0));
        self.row_of_id.clear();
        self.row_of_id.resize(size, usize::MAX);
        for (i, &id) in self.rows.iter().enumerate() {
            self.row_of_id[id] = i;
        }
        Ok(())
    }

    /// `fix external`'s callback: fexternal = the force (following the atoms, also torque +=
    /// the torque). Held, the fix's `fexternal` keeps the force, added by `apply_torque`.
    pub fn apply(&mut self, step: i64, tags: &[i32], fexternal: &mut [V3]) -> Result<(), String> {
        if self.within.is_some() {
            return self.follow(step, tags, fexternal);
        }
        let now = Written {
            address: fexternal.as_ptr() as usize,
            count: tags.len(),
        };
        if self.written != Some(now) {
            by_tag(&self.force, tags, fexternal)?;
            self.written = Some(now);
        }
        self.force_rows = Some((step, now));
        Ok(())
    }

    /// The callback of the second, held, `fix external` (of no atoms), whose `fexternal` keeps
    /// the held torque in the atoms' order: force += the first fix's `fexternal`, torque += this
    /// one's, in one pass (where the fixes' own loop runs, at multiples of `NEVER`, the force is
    /// left to it).
    pub fn apply_torque(&mut self, step: i64, tags: &[i32], held: &mut [V3]) -> Result<(), String> {
        let now = Written {
            address: held.as_ptr() as usize,
            count: tags.len(),
        };
        if self.any_torque && self.written_torque != Some(now) {
            by_tag(&self.torque, tags, held)?;
            self.written_torque = Some(now);
        }
        let Some((at, rows)) = self
            .force_rows
            .take()
            .filter(|(at, w)| *at == step && w.count == tags.len())
        else {
            return Err(format!(
                "step {step}: the force's fix external did not run before the torque's"
            ));
        };
        // SAFETY: inside LIGGGHTS's post_force; `rows` is the force fix's fexternal of this step.
        let (f, torque) = unsafe { self.lammps.forces(tags.len())? };
        let force = unsafe { std::slice::from_raw_parts(rows.address as *const V3, rows.count) };
        let force_too = at % NEVER != 0;
        match (force_too, self.any_torque) {
            (true, true) => {
                for (((f, t), fh), th) in f.iter_mut().zip(torque.iter_mut()).zip(force).zip(held.iter()) {
                    add_to(f, *fh);
                    add_to(t, *th);
                }
            }
            (true, false) => f.iter_mut().zip(force).for_each(|(f, fh)| add_to(f, *fh)),
            (false, true) => torque
                .iter_mut()
                .zip(held.iter())
                .for_each(|(t, th)| add_to(t, *th)),
            (false, false) => {}
        }
        Ok(())
    }

    /// The following loads at this LIGGGHTS step; what the callback wrote is kept in
    /// `self.force`, `self.torque` (the next `hold` corrects the first half kick by it).
    fn follow(&mut self, step: i64, tags: &[i32], fexternal: &mut [V3]) -> Result<(), String> {
        let (dt, _) = self.lammps.clock()?;
        // SAFETY: inside LIGGGHTS's post_force.
        let atoms = unsafe { self.lammps.atoms()? };
        if self.rows.len() != tags.len() || self.rows.iter().zip(tags).any(|(&r, &t)| r + 1 != t as usize) {
            let size = self.force.len();
            self.map_rows(tags, size)?;
            self.remap(self.row_of_id.len(), atoms.radius);
        }
        let within = self.within.as_mut().expect("within");
        let kin = Kinematics {
            x: atoms.x,
            v: atoms.v,
            omega: atoms.omega,
            radius: atoms.radius,
        };
        let g = within.gravity;
        let (f, torque, mass) = (&*atoms.f, &*atoms.torque, atoms.rmass);
        self.spin.resize(tags.len(), [0.0; 3]);
        within.loads(
            &self.rows,
            (step - self.first_step) as f64 * dt,
            &kin,
            |i| (sub(f[i], scale(g, mass[i])), torque[i]),
            dt,
            fexternal,
            &mut self.spin,
        );
        for (i, &id) in self.rows.iter().enumerate() {
            add_to(&mut atoms.torque[i], self.spin[i]);
            self.force[id] = fexternal[i];
            self.torque[id] = self.spin[i];
        }
        Ok(())
    }

    /// Grows the held tables (and the following loads' tables) to `size` ids; the films' pairs
    /// take the atoms' new rows (`radius` by row).
    fn remap(&mut self, size: usize, radius: &[f64]) {
        if size > self.force.len() {
            self.force.resize(size, [0.0; 3]);
            self.torque.resize(size, [0.0; 3]);
        }
        if let Some(w) = &mut self.within {
            w.remap(size, &self.row_of_id, radius);
        }
    }
}

/// `out[i]` = `table[tag[i] - 1]` (0 for an ID beyond the table).
fn by_tag(table: &[V3], tags: &[i32], out: &mut [V3]) -> Result<(), String> {
    for (o, &t) in out.iter_mut().zip(tags) {
        *o = table.get(row_of(t)?).copied().unwrap_or_default();
    }
    Ok(())
}
