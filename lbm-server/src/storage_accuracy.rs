//! The measured accuracy of the 16-bit storages of the populations (`lattice.storage`) and the
//! warning of a scene that uses one where it was measured to fail (validation/lbm/REPORT.md,
//! "Storage of the populations"): at low lattice speeds, where a flow's deviation from rest is a
//! few of the format's smallest steps. The closed box's mass drift (1.5e-5 FP16S, 4.0e-6 FP16C,
//! steady after 10,000 steps) and the flows at the usual speeds (within 0.3%) warn of nothing.

use crate::terminal::Warning;
use scene::lattice::{LatticeUnits, Storage};

/// A measured change against FP32 beyond this (in %) makes a scene warn (the 16-bit storages'
/// target in drag and settling speed).
const CHANGE_WARN: f64 = 0.5;

/// The Zick-Homsy array (solid fraction 0.125, box 16, TRT, tau 1) by driving force, slowest
/// last (`lbm-server validate --only storage`): its mean speed through the array (FP32) and the
/// change of its drag K against FP32 in %, of FP16S and of FP16C.
const ARRAY: [(f64, [f64; 2]); 5] = [
    (6.89e-2, [0.027, 0.018]),
    (6.94e-3, [0.010, -0.002]),
    (6.94e-4, [0.078, -0.041]),
    (6.94e-5, [0.991, 0.038]),
    (6.94e-6, [846.5, 415.9]),
];

/// The Taylor-Green vortex (32 x 32, TRT, tau 0.8) decaying from lattice speed 9.2e-3 to 4.9e-6:
/// the change of its measured viscosity against FP32 in %, of FP16S and of FP16C.
const VORTEX: [f64; 2] = [-9.2, -4.4];

/// The warning of a scene whose storage was measured to fail at its lattice speed (Mach number x
/// c_s): a 16-bit storage below the slowest speed of [`ARRAY`] still within [`CHANGE_WARN`] above
/// the first that was not.
pub fn storage_warning(units: &LatticeUnits) -> Option<Warning> {
    let (k, other) = match units.storage {
        Storage::Fp16s => (0, "\"fp16c\" (measured within target down to 6.9e-5) or \"fp32\""),
        Storage::Fp16c => (1, "\"fp32\""),
        Storage::Fp32 => return None,
    };
    let failed = ARRAY
        .iter()
        .position(|(_, change)| change[k].abs() > CHANGE_WARN)?;
    let held = ARRAY[..failed].last().map_or(f64::INFINITY, |&(u, _)| u);
    let speed = units.mach / 3f64.sqrt();
    if speed >= held {
        return None;
    }
    let (slow, change) = (ARRAY[failed].0, ARRAY[failed].1[k]);
    let full = format!(
        "lattice.storage = \"{}\" at lattice speed {speed:.2e} (lattice.mach {:.2e} x c_s), below \
         {held:.1e}: the Zick-Homsy array's drag measured {:+.2}% against FP32 at {held:.1e}, \
         {change:+.2}% at {slow:.1e}, and a Taylor-Green vortex decaying to 4.9e-6 its viscosity \
         {:+.1}% (validation/lbm/REPORT.md, \"Storage of the populations\"; target {CHANGE_WARN}%): \
         16 bits lose a flow a few of their smallest steps from rest. Raise lattice.mach to {:.1e} \
         or more (or lower lattice.velocity_scale), or use lattice.storage = {other}",
        units.storage,
        units.mach,
        ARRAY[failed - 1].1[k],
        VORTEX[k],
        held * 3f64.sqrt(),
    );
    let brief = format!(
        "lattice.storage = \"{}\" at lattice speed {speed:.2e}: below {held:.1e}, where its drag \
         was measured off by {change:+.2}% at {slow:.1e}; raise lattice.mach or use {other}",
        units.storage,
    );
    Some(Warning { brief, full })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ten Cate's E1 (validation/scenes/ten-cate-e1.toml) with `storage` at Mach `mach`.
    fn e1(storage: &str, mach: f64) -> LatticeUnits {
        let text = include_str!("../../validation/scenes/ten-cate-e1.toml")
            .replace("mach = 0.1", &format!("mach = {mach}"))
            .replace(
                "operator = \"trt\"",
                &format!("operator = \"trt\"\nstorage = \"{storage}\""),
            );
        let scene = scene::Scene::parse(&text, "e1.toml").expect("scene");
        scene.lattice_units.expect("lattice")
    }

    /// FP16S warns below lattice speed 6.9e-4 (Mach 1.2e-3) with the measured changes, FP16C
    /// below 6.9e-5 (Mach 1.2e-4); FP32 never, and neither at the default Mach 0.1.
    #[test]
    fn a_sixteen_bit_storage_warns_below_the_speed_it_was_measured_to_hold() {
        for storage in ["fp32", "fp16s", "fp16c"] {
            assert_eq!(storage_warning(&e1(storage, 0.1)), None, "{storage} at Mach 0.1");
        }
        assert_eq!(storage_warning(&e1("fp32", 1e-4)), None, "fp32 at Mach 1e-4");
        assert_eq!(storage_warning(&e1("fp16s", 1.3e-3)), None, "fp16s at 7.5e-4");
        let fp16s = storage_warning(&e1("fp16s", 1e-3))
            .expect("fp16s at lattice speed 5.8e-4")
            .full;
        assert!(
            fp16s.contains("lattice speed 5.77e-4")
                && fp16s.contains("below 6.9e-4")
                && fp16s.contains("+0.08% against FP32 at 6.9e-4, +0.99% at 6.9e-5")
                && fp16s.contains("viscosity -9.2%")
                && fp16s.contains("Raise lattice.mach to 1.2e-3")
                && fp16s.contains("\"fp16c\""),
            "{fp16s}"
        );
        assert_eq!(storage_warning(&e1("fp16c", 1e-3)), None, "fp16c at 5.8e-4");
        let fp16c = storage_warning(&e1("fp16c", 1e-4))
            .expect("fp16c at lattice speed 5.8e-5")
            .full;
        assert!(
            fp16c.contains("below 6.9e-5")
                && fp16c.contains("+0.04% against FP32 at 6.9e-5, +415.90% at 6.9e-6")
                && fp16c.contains("viscosity -4.4%"),
            "{fp16c}"
        );
    }
}
