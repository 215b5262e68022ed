//! The native helper of the external-DEM adapters: the work an adapter does at each of the
//! external DEM's steps, compiled, so that the adapter adds little to the DEM's own step.
//!
//! clients/liggghts/native.py loads this library (`liblbmdem_native.so`, built with the
//! workspace) at run time with ctypes and hands LIGGGHTS's `fix external` the C function
//! [`ffi::lbmdem_loads_apply`] as its callback. Once per fluid step the adapter gathers the
//! atoms into the fluid's particle states ([`states`]) and holds the fluid's reply ([`held`]); at
//! each LIGGGHTS step the callback writes the held force into `fexternal` and adds the held torque
//! to the atoms' torque, or, with the loads following the atoms ([`within`]: the sub-step drag of
//! PROTOCOL.md 3.2 and the squeeze films of 4.5, [`films`]), evaluates them from the atoms' state
//! as dem-client does. The laws are the protocol crate's (`protocol::substep_drag`,
//! `protocol::squeeze_film`). LIGGGHTS's arrays are reached through the LAMMPS C library
//! interface's `lammps_extract_atom` and `lammps_extract_global`, passed in by address
//! ([`lammps`]): nothing here links against LIGGGHTS.

pub mod ffi;
pub mod films;
pub mod held;
pub mod lammps;
pub mod states;
pub mod vec3;
pub mod within;
