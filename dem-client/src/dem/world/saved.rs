//! A world's state as a checkpoint saves it (dem.bin): every sphere whole, the clock, and the
//! neighbour lists with all they carry (the contact histories of pairs and walls, the periodic
//! shifts, the last forces and films, where each sphere was at the build, the drift since), so
//! that a world restored steps on to the same bits. What follows from the scene and the fluid's
//! Welcome (walls, law, materials, gravity, step, films, periodic axes) is set up as for a fresh
//! run first; the adjacency of the lists is rebuilt from the slots; the spare island's world, the
//! timings of the ways (`everyone`, same bits either way) and of the builds are not state (a
//! checkpoint of the same step is the same bytes).

use super::pairs::Slot;
use super::{Body, World};
use crate::dem::bytes::{Decoder, Encoder};
use crate::dem::contact::ContactForce;

impl World {
    /// Writes the world's state.
    pub fn save(&self, e: &mut Encoder) {
        e.list(&self.bodies, save_body);
        e.f64(self.time);
        e.list(&self.slots, |e, s| {
            e.u64(s.i as u64);
            e.u64(s.j as u64);
            e.u64(s.material as u64);
            e.u64(s.touching as u64);
        });
        e.v3s(&self.pair_history);
        e.v3s(&self.pair_shift);
        e.list(&self.out, |e, c| {
            e.v3(&c.force);
            e.v3(&c.torque_i);
            e.v3(&c.torque_j);
        });
        e.v3s(&self.films);
        e.list(&self.touch, |e, t| e.u64(*t as u64));
        e.v3s(&self.wall_history);
        e.u32s(&self.near_start);
        e.u32s(&self.near);
        e.v3s(&self.x_at_build);
        e.list(&self.ids_at_build, |e, id| e.u64(*id));
        e.u64(self.stale as u64);
        e.f64(self.peak_drift2);
        for count in [
            self.contacts as u64,
            self.builds,
            self.islands,
            self.dropped_islands,
        ] {
            e.u64(count);
        }
    }

    /// Reads back what `save` wrote, over a world set up for the same scene and fluid.
    pub fn restore(&mut self, d: &mut Decoder) -> Result<(), String> {
        self.bodies = d.list(restore_body)?;
        self.time = d.f64()?;
        self.slots = d.list(|d| {
            Ok(Slot {
                i: d.u64()? as u32,
                j: d.u64()? as u32,
                material: d.u64()? as u32,
                touching: d.u64()? != 0,
            })
        })?;
        self.pair_history = d.v3s()?;
        self.pair_shift = d.v3s()?;
        self.out = d.list(|d| {
            Ok(ContactForce {
                force: d.v3()?,
                torque_i: d.v3()?,
                torque_j: d.v3()?,
            })
        })?;
        self.films = d.v3s()?;
        self.touch = d.list(|d| Ok(d.u64()? != 0))?;
        self.wall_history = d.v3s()?;
        self.near_start = d.u32s()?;
        self.near = d.u32s()?;
        self.x_at_build = d.v3s()?;
        self.ids_at_build = d.list(|d| d.u64())?;
        self.stale = d.u64()? != 0;
        self.peak_drift2 = d.f64()?;
        self.contacts = d.u64()? as usize;
        (self.builds, self.islands, self.dropped_islands) = (d.u64()?, d.u64()?, d.u64()?);
        self.build_adjacency();
        self.spare = None;
        Ok(())
    }
}

fn save_body(e: &mut Encoder, b: &Body) {
    e.u64(b.id);
    for v in [&b.x, &b.v, &b.w] {
        e.v3(v);
    }
    for s in [b.r, b.m, b.inertia] {
        e.f64(s);
    }
    e.u64(b.material as u64);
    for v in [&b.f, &b.t, &b.f_ext, &b.t_ext] {
        e.v3(v);
    }
    e.f64(b.drag);
    e.f64(b.spin_drag);
    for v in [
        &b.f_ext_rate,
        &b.t_ext_rate,
        &b.contact_impulse,
        &b.contact_angular_impulse,
    ] {
        e.v3(v);
    }
}

fn restore_body(d: &mut Decoder) -> Result<Body, String> {
    Ok(Body {
        id: d.u64()?,
        x: d.v3()?,
        v: d.v3()?,
        w: d.v3()?,
        r: d.f64()?,
        m: d.f64()?,
        inertia: d.f64()?,
        material: d.u64()? as usize,
        f: d.v3()?,
        t: d.v3()?,
        f_ext: d.v3()?,
        t_ext: d.v3()?,
        drag: d.f64()?,
        spin_drag: d.f64()?,
        f_ext_rate: d.v3()?,
        t_ext_rate: d.v3()?,
        contact_impulse: d.v3()?,
        contact_angular_impulse: d.v3()?,
    })
}
