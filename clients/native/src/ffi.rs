//! The C functions clients/liggghts/native.py calls (ctypes). Every pointer is the caller's and
//! valid for the call; a [`Loads`] lives from `lbmdem_loads_new` to `lbmdem_loads_free`. Errors
//! return -1 and leave their message for `lbmdem_loads_error`; the callback, which cannot fail in
//! LIGGGHTS, keeps its first error there and does nothing after it.

use crate::films::{SqueezeFilms, Wall};
use crate::held::Loads;
use crate::lammps::{ExtractFn, Lammps};
use crate::states::{gather, Domain};
use crate::within::SubstepLoads;
use protocol::{ParticleReply, ParticleState};
use std::ffi::{c_char, c_int, c_void};
use std::panic::{catch_unwind, AssertUnwindSafe};

/// The version of these functions' signatures (native.py refuses another).
pub const ABI_VERSION: u32 = 3;

#[no_mangle]
pub extern "C" fn lbmdem_native_abi() -> u32 {
    ABI_VERSION
}

/// `napply` of the held loads' two `fix external`s ([`crate::held::NEVER`]).
#[no_mangle]
pub extern "C" fn lbmdem_held_napply() -> i64 {
    crate::held::NEVER
}

/// A new set of loads for the LIGGGHTS instance `handle`, held constant until
/// `lbmdem_loads_follow`.
///
/// # Safety
/// `handle` is a live LIGGGHTS instance, the two functions its library's extract functions.
#[no_mangle]
pub unsafe extern "C" fn lbmdem_loads_new(
    handle: *mut c_void,
    extract_atom: ExtractFn,
    extract_global: ExtractFn,
) -> *mut Loads {
    Box::into_raw(Box::new(Loads::new(Lammps {
        handle,
        extract_atom,
        extract_global,
    })))
}

/// # Safety
/// `loads` from `lbmdem_loads_new`, not used after.
#[no_mangle]
pub unsafe extern "C" fn lbmdem_loads_free(loads: *mut Loads) {
    if !loads.is_null() {
        drop(Box::from_raw(loads));
    }
}

/// The loads follow the atoms within the fluid step: the sub-step drag when `drag` (rho_f
/// `fluid_density`, fluid step `dt`), the squeeze films when `cutoff` > 0 (`walls`: axis, at,
/// sign of each of `n_walls`; `periods`: 0 for a bounded axis).
///
/// # Safety
/// `gravity` and `periods` point to 3 doubles, `wall_axis`, `wall_at`, `wall_sign` to `n_walls`.
#[no_mangle]
pub unsafe extern "C" fn lbmdem_loads_follow(
    loads: *mut Loads,
    fluid_density: f64,
    dt: f64,
    gravity: *const f64,
    drag: c_int,
    viscosity: f64,
    cutoff: f64,
    n_walls: usize,
    wall_axis: *const i64,
    wall_at: *const f64,
    wall_sign: *const f64,
    periods: *const f64,
) {
    let films = (cutoff > 0.0).then(|| {
        let walls = (0..n_walls)
            .map(|w| Wall {
                axis: *wall_axis.add(w) as usize,
                at: *wall_at.add(w),
                sign: *wall_sign.add(w),
            })
            .collect();
        SqueezeFilms::new(viscosity, cutoff, walls, *periods.cast::<[f64; 3]>())
    });
    let gravity = *gravity.cast::<[f64; 3]>();
    (*loads).within = Some(SubstepLoads::new(fluid_density, dt, gravity, drag != 0, films));
}

/// Holds the fluid's reply (`n` replies) over the next run; `ran`: LIGGGHTS ran before.
///
/// # Safety
/// `replies` points to `n` replies.
#[no_mangle]
pub unsafe extern "C" fn lbmdem_loads_hold(
    loads: *mut Loads,
    replies: *const ParticleReply,
    n: usize,
    ran: c_int,
) -> c_int {
    let loads = &mut *loads;
    let replies = if n == 0 {
        &[][..]
    } else {
        std::slice::from_raw_parts(replies, n)
    };
    status(loads, |l| l.hold(replies, ran != 0))
}

/// Writes the atoms' states into `out` (room for `capacity`); returns their number, or -1.
///
/// # Safety
/// `out` has room for `capacity` states; `lo`, `hi` point to 3 doubles, `periodic` to 3 bytes.
#[no_mangle]
pub unsafe extern "C" fn lbmdem_states(
    loads: *mut Loads,
    out: *mut ParticleState,
    capacity: usize,
    lo: *const f64,
    hi: *const f64,
    periodic: *const u8,
) -> isize {
    let loads = &mut *loads;
    let domain = Domain {
        lo: *lo.cast::<[f64; 3]>(),
        hi: *hi.cast::<[f64; 3]>(),
        periodic: [0, 1, 2].map(|a| *periodic.add(a) != 0),
    };
    let mut n = 0;
    let done = status(loads, |l| {
        let atoms = l.lammps.atoms()?;
        n = atoms.tag.len();
        if n > capacity {
            return Err(format!("{n} atoms, room for {capacity} states"));
        }
        gather(&atoms, &domain, std::slice::from_raw_parts_mut(out, n))
    });
    if done == 0 {
        n as isize
    } else {
        -1
    }
}

/// `fix external`'s callback (`FixExternal::FnPtr`): `caller` is the `Loads`.
///
/// # Safety
/// Called by LIGGGHTS's FixExternal::post_force with `caller` from `lbmdem_loads_new`.
#[no_mangle]
pub unsafe extern "C" fn lbmdem_loads_apply(
    caller: *mut c_void,
    step: i64,
    nlocal: c_int,
    tag: *mut c_int,
    _x: *mut *mut f64,
    fexternal: *mut *mut f64,
) {
    in_callback(caller, nlocal, tag, fexternal, |l, tags, fext| {
        l.apply(step, tags, fext)
    });
}

/// The held loads' second callback (`FixExternal::FnPtr`), of a `fix external` of no atoms
/// added after the first: its `fexternal` keeps the torque in the atoms' order; it adds the
/// first fix's `fexternal` to the atoms' force and its own to their torque.
///
/// # Safety
/// As for `lbmdem_loads_apply`.
#[no_mangle]
pub unsafe extern "C" fn lbmdem_torque_apply(
    caller: *mut c_void,
    step: i64,
    nlocal: c_int,
    tag: *mut c_int,
    _x: *mut *mut f64,
    held: *mut *mut f64,
) {
    in_callback(caller, nlocal, tag, held, |l, tags, held| {
        l.apply_torque(step, tags, held)
    });
}

/// Runs `f` on the `Loads` at `caller` with the atoms' tags and the fix's `fexternal` (nothing
/// without atoms or after an error).
///
/// # Safety
/// As for `lbmdem_loads_apply`: LIGGGHTS's arrays of `nlocal` atoms.
unsafe fn in_callback(
    caller: *mut c_void,
    nlocal: c_int,
    tag: *mut c_int,
    fexternal: *mut *mut f64,
    f: impl FnOnce(&mut Loads, &[i32], &mut [[f64; 3]]) -> Result<(), String>,
) {
    let loads = &mut *caller.cast::<Loads>();
    if nlocal <= 0 || loads.error.is_some() {
        return;
    }
    let n = nlocal as usize;
    let tags = std::slice::from_raw_parts(tag, n);
    let rows = std::slice::from_raw_parts_mut((*fexternal).cast::<[f64; 3]>(), n);
    status(loads, |l| f(l, tags, rows));
}

/// A callback that writes zero forces: `fix external`'s own cost
/// (validation/crossdem/adapter_overhead.py).
///
/// # Safety
/// Called by LIGGGHTS's FixExternal::post_force.
#[no_mangle]
pub unsafe extern "C" fn lbmdem_zero_apply(
    _: *mut c_void,
    _: i64,
    nlocal: c_int,
    _: *mut c_int,
    _: *mut *mut f64,
    fexternal: *mut *mut f64,
) {
    if nlocal > 0 {
        std::ptr::write_bytes(*fexternal, 0, 3 * nlocal as usize);
    }
}

/// Copies the error's message (NUL-terminated, cut to `capacity`) into `out`; returns its length
/// (0: no error).
///
/// # Safety
/// `out` has room for `capacity` bytes.
#[no_mangle]
pub unsafe extern "C" fn lbmdem_loads_error(loads: *const Loads, out: *mut c_char, capacity: usize) -> usize {
    let Some(message) = &(*loads).error else { return 0 };
    let bytes = message.as_bytes();
    let n = bytes.len().min(capacity.saturating_sub(1));
    std::ptr::copy_nonoverlapping(bytes.as_ptr(), out.cast::<u8>(), n);
    *out.add(n) = 0;
    bytes.len()
}

/// Runs `f`, keeping its error (or panic) in `loads.error`: 0, or -1.
fn status(loads: &mut Loads, f: impl FnOnce(&mut Loads) -> Result<(), String>) -> c_int {
    match catch_unwind(AssertUnwindSafe(|| f(loads))) {
        Ok(Ok(())) => 0,
        Ok(Err(e)) => {
            loads.error.get_or_insert(e);
            -1
        }
        Err(_) => {
            loads
                .error
                .get_or_insert_with(|| "the native helper panicked".into());
            -1
        }
    }
}
