//! LIGGGHTS's per-atom arrays through the LAMMPS C library interface (`library.h`:
//! `lammps_extract_atom`, `lammps_extract_global`), whose addresses the adapter passes in: the
//! library is LIGGGHTS's, loaded by the adapter, never linked here.

use crate::vec3::V3;
use std::ffi::{c_char, c_void};

/// `void *lammps_extract_atom(void *, char *)` and `lammps_extract_global` alike.
pub type ExtractFn = unsafe extern "C" fn(*mut c_void, *const c_char) -> *mut c_void;

/// One LIGGGHTS instance: its handle and the two extract functions.
pub struct Lammps {
    pub handle: *mut c_void,
    pub extract_atom: ExtractFn,
    pub extract_global: ExtractFn,
}

/// The owned atoms' arrays as LIGGGHTS holds them now (valid until it runs again or grows
/// them). A `double **` of LAMMPS has its rows in one block: row 0's address is the array's.
pub struct Atoms<'a> {
    pub tag: &'a [i32],
    pub x: &'a [V3],
    pub v: &'a [V3],
    pub omega: &'a [V3],
    pub radius: &'a [f64],
    pub rmass: &'a [f64],
    pub f: &'a mut [V3],
    pub torque: &'a mut [V3],
}

impl Lammps {
    fn atom(&self, name: &'static [u8]) -> Result<*mut c_void, String> {
        // SAFETY: `handle` and `extract_atom` are the adapter's live instance and its function.
        let p = unsafe { (self.extract_atom)(self.handle, name.as_ptr().cast()) };
        if p.is_null() {
            let text = String::from_utf8_lossy(&name[..name.len() - 1]);
            return Err(format!("the atom style has no per-atom '{text}'"));
        }
        Ok(p)
    }

    fn global(&self, name: &'static [u8]) -> Result<*mut c_void, String> {
        // SAFETY: as in `atom`.
        let p = unsafe { (self.extract_global)(self.handle, name.as_ptr().cast()) };
        if p.is_null() {
            return Err(format!(
                "no global '{}'",
                String::from_utf8_lossy(&name[..name.len() - 1])
            ));
        }
        Ok(p)
    }

    /// The number of owned atoms.
    pub fn nlocal(&self) -> Result<usize, String> {
        // SAFETY: LAMMPS's nlocal is an int.
        Ok(unsafe { *self.global(b"nlocal\0")?.cast::<i32>() }.max(0) as usize)
    }

    /// The time step [s] and the step counter.
    pub fn clock(&self) -> Result<(f64, i64), String> {
        // SAFETY: dt is a double, ntimestep a bigint (int64_t).
        unsafe {
            Ok((
                *self.global(b"dt\0")?.cast::<f64>(),
                *self.global(b"ntimestep\0")?.cast::<i64>(),
            ))
        }
    }

    /// A per-atom double[n][3].
    ///
    /// # Safety
    /// `n` must not exceed the atoms LIGGGHTS has allocated; the slice lives until LIGGGHTS
    /// reallocates the array.
    unsafe fn rows<'a>(&self, name: &'static [u8], n: usize) -> Result<&'a mut [V3], String> {
        let rows = self.atom(name)?.cast::<*mut V3>();
        Ok(if n == 0 {
            &mut []
        } else {
            std::slice::from_raw_parts_mut(*rows, n)
        })
    }

    unsafe fn column<'a, T>(&self, name: &'static [u8], n: usize) -> Result<&'a [T], String> {
        let p = self.atom(name)?.cast::<T>();
        Ok(if n == 0 {
            &[]
        } else {
            std::slice::from_raw_parts(p, n)
        })
    }

    /// The atoms' force and torque alone (the held loads' callback).
    ///
    /// # Safety
    /// As for `atoms`; `n` the owned atoms.
    pub unsafe fn forces<'a>(&self, n: usize) -> Result<(&'a mut [V3], &'a mut [V3]), String> {
        Ok((self.rows(b"f\0", n)?, self.rows(b"torque\0", n)?))
    }

    /// The owned atoms' arrays.
    ///
    /// # Safety
    /// The slices alias LIGGGHTS's memory: use them only while LIGGGHTS does not run, or inside
    /// its callback, and hold no two `Atoms` at once.
    pub unsafe fn atoms<'a>(&self) -> Result<Atoms<'a>, String> {
        let n = self.nlocal()?;
        Ok(Atoms {
            tag: self.column(b"id\0", n)?,
            x: self.rows(b"x\0", n)?,
            v: self.rows(b"v\0", n)?,
            omega: self.rows(b"omega\0", n)?,
            radius: self.column(b"radius\0", n)?,
            rmass: self.column(b"rmass\0", n)?,
            f: self.rows(b"f\0", n)?,
            torque: self.rows(b"torque\0", n)?,
        })
    }
}

/// The particle id (row of the id tables) of an atom ID: id = atom ID - 1.
pub fn row_of(tag: i32) -> Result<usize, String> {
    if tag < 1 {
        return Err(format!("atom ID {tag} is not a particle's (IDs start at 1)"));
    }
    Ok(tag as usize - 1)
}
