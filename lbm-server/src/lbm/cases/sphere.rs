//! A sphere held in a uniform stream (C_d against Schiller & Naumann, the unconfined drag from
//! confined boxes) and the same sphere towed through fluid at rest.

use super::coupled_lattice;
use crate::lbm::geometry::{Face, Operator, Setup};
use crate::lbm::gpu::{equilibrium_field, Gpu, GpuLattice};
use crate::lbm::imb::{ImbOptions, SolidParticle};
use std::sync::Arc;

/// Drag of a sphere held fixed in a uniform stream.
#[derive(Debug, Clone, Copy)]
pub struct SphereDrag {
    pub reynolds: f64,
    /// Sphere diameter, box width (y and z) and length (x), cells.
    pub diameter: f64,
    pub width: usize,
    pub length: usize,
    pub u0: f64,
    pub tau: f64,
    /// The radius it was drawn larger by, cells.
    pub drawn_larger: f64,
    pub steps: u64,
    /// C_d = F / (1/2 rho u0^2 pi d^2 / 4), measured.
    pub cd: f64,
}

impl SphereDrag {
    /// Schiller & Naumann (1933): C_d = 24 / Re (1 + 0.15 Re^0.687), Re < 800.
    pub fn schiller_naumann(&self) -> f64 {
        schiller_naumann(self.reynolds)
    }
}

/// Schiller & Naumann (1933): C_d = 24 / Re (1 + 0.15 Re^0.687), Re < 800.
pub fn schiller_naumann(re: f64) -> f64 {
    24.0 / re * (1.0 + 0.15 * re.powf(0.687))
}

/// The drag of an unconfined sphere from three confined ones: C_d(W) = C_inf + a (d / W)^p through
/// the three points (d / W, C_d) with the smallest d / W, p found by bisection in [0.5, 8]. None
/// when fewer than three points are given or the three are not monotone in d / W.
pub fn unconfined_drag(points: &[(f64, f64)]) -> Option<(f64, f64)> {
    let mut sorted = points.to_vec();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    let [(x1, c1), (x2, c2), (x3, c3)] = *sorted.get(..3)? else {
        return None;
    };
    let ratio = (c3 - c2) / (c2 - c1);
    if !ratio.is_finite() || ratio <= 0.0 {
        return None;
    }
    let shape = |p: f64| (x3.powf(p) - x2.powf(p)) / (x2.powf(p) - x1.powf(p));
    let (mut lo, mut hi) = (0.5, 8.0);
    if (shape(lo) - ratio) * (shape(hi) - ratio) > 0.0 {
        return None;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if (shape(lo) - ratio) * (shape(mid) - ratio) <= 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let p = 0.5 * (lo + hi);
    let a = (c2 - c1) / (x2.powf(p) - x1.powf(p));
    Some((c1 - a * x1.powf(p), p))
}

/// The largest stream velocity (lattice units) of [`fixed_sphere`]: Mach 0.14.
pub const STREAM_VELOCITY: f64 = 0.08;

/// The largest tau of [`fixed_sphere`]: the stream is slowed rather than tau raised past it.
pub const STREAM_TAU: f64 = 1.0;

/// A sphere held at rest in a stream: its Reynolds number, size, box and lattice.
#[derive(Debug, Clone, Copy)]
pub struct HeldSphere {
    /// Re = u0 d / nu, with the nominal diameter.
    pub reynolds: f64,
    /// Nominal diameter, cells.
    pub diameter: f64,
    /// Box width (y and z) and length (x), cells.
    pub width: usize,
    pub length: usize,
    /// The lattice's tau; None: the stream at [`STREAM_VELOCITY`] unless tau would pass
    /// [`STREAM_TAU`].
    pub tau: Option<f64>,
    /// The radius the sphere is drawn larger by (cells; the radius correction, 0 without it).
    pub drawn_larger: f64,
    /// The fluid's collision operator.
    pub operator: Operator,
    /// The coupling's options (the weighting B).
    pub imb: ImbOptions,
    /// Cells the held sphere's centre is moved downstream from L/3 (its place against the
    /// lattice; not used by the towed sphere, which passes every place).
    pub shift: f64,
}

impl HeldSphere {
    /// The held sphere: at rest, its centre a third of the length downstream (moved by `shift`)
    /// on the box's axis, drawn larger by `drawn_larger`.
    pub(super) fn particle(&self) -> SolidParticle {
        let (w, l) = (self.width as f64, self.length as f64);
        SolidParticle {
            position: [l / 3.0 + self.shift, w / 2.0, w / 2.0],
            radius: self.diameter / 2.0 + self.drawn_larger,
            ..Default::default()
        }
    }
}

/// A sphere of `diameter` cells held at rest in a stream along x at Reynolds number `re` = u0 d
/// / nu (see [`held_sphere`]), at the stream velocity's tau and drawn at its radius.
pub fn fixed_sphere(
    gpu: &Arc<Gpu>,
    re: f64,
    diameter: f64,
    width: usize,
    length: usize,
) -> Result<SphereDrag, String> {
    held_sphere(
        gpu,
        &HeldSphere {
            reynolds: re,
            diameter,
            width,
            length,
            tau: None,
            drawn_larger: 0.0,
            operator: Operator::Trt { magic: 3.0 / 16.0 },
            imb: Default::default(),
            shift: 0.0,
        },
    )
}

/// A coupled lattice of `size` cells (this operator and coupling) with fluid moving at `stream`
/// everywhere: velocity inlet at x = 0, pressure outlet at x = length, the four side faces
/// moving with the stream.
pub(super) fn stream_box(
    gpu: &Arc<Gpu>,
    size: [usize; 3],
    tau: f64,
    operator: Operator,
    imb: ImbOptions,
    stream: [f64; 3],
) -> GpuLattice {
    let faces = [
        Face::VelocityInlet(stream),
        Face::PressureOutlet(1.0),
        Face::MovingWall(stream),
        Face::MovingWall(stream),
        Face::MovingWall(stream),
        Face::MovingWall(stream),
    ];
    let setup = Setup::new(size, faces, tau, operator);
    let mut lattice = coupled_lattice(gpu, &setup, imb);
    lattice.set_populations(&equilibrium_field(&setup, |_| (1.0, stream)));
    lattice
}

/// C_d = F / (1/2 rho u0^2 pi d^2 / 4) of a sphere of `diameter` cells in a stream `u0` (rho 1).
pub(super) fn drag_coefficient(force: f64, u0: f64, diameter: f64) -> f64 {
    force / (0.5 * u0 * u0 * std::f64::consts::PI * diameter * diameter / 4.0)
}

/// The stream velocity and tau of a held sphere: at the given tau, or at [`STREAM_VELOCITY`]
/// unless tau would pass [`STREAM_TAU`].
pub(super) fn stream_of(case: &HeldSphere) -> (f64, f64) {
    let (re, d) = (case.reynolds, case.diameter);
    match case.tau {
        Some(tau) => (re * (tau - 0.5) / 3.0 / d, tau),
        None => {
            let nu_max = (STREAM_TAU - 0.5) / 3.0;
            let u0 = STREAM_VELOCITY.min(re * nu_max / d);
            (u0, 3.0 * u0 * d / re + 0.5)
        }
    }
}

/// A sphere held at rest in a stream along x: velocity inlet at x = 0, pressure outlet at x =
/// length, the four side faces moving with the stream (a far field that adds no shear), the
/// sphere a third of the length downstream; C_d with the nominal diameter. Runs until the drag
/// changes by less than 1e-4 relative over 100 steps (at least two passes of the stream through
/// the box). Err: the run blew up or found no steady drag (what and when).
pub fn held_sphere(gpu: &Arc<Gpu>, case: &HeldSphere) -> Result<SphereDrag, String> {
    let (u0, tau) = stream_of(case);
    let (diameter, width, length) = (case.diameter, case.width, case.length);
    let stream = [u0, 0.0, 0.0];
    let mut lattice = stream_box(gpu, [length, width, width], tau, case.operator, case.imb, stream);
    let sphere = case.particle();
    let passes = (2.0 * length as f64 / u0) as u64;
    let (mut steps, mut last, mut force) = (0u64, f64::INFINITY, 0.0);
    while steps < passes || (force - last).abs() > 1e-4 * force.abs() {
        last = force;
        for _ in 0..100 {
            force = lattice.step_coupled(&[sphere])?[0].force[0];
        }
        steps += 100;
        if !force.is_finite() {
            let (_, bad) = lattice.fields();
            return Err(format!(
                "blew up by step {steps} (tau {tau:.4}, u0 {u0}): {bad:?}"
            ));
        }
        if steps >= 20 * passes {
            return Err(format!("no steady drag after {steps} steps: {force} vs {last}"));
        }
    }
    Ok(SphereDrag {
        reynolds: case.reynolds,
        diameter,
        width,
        length,
        u0,
        tau,
        drawn_larger: case.drawn_larger,
        steps,
        cd: drag_coefficient(force, u0, diameter),
    })
}

/// Drag of a sphere towed at constant speed through fluid at rest ([`towed_sphere`]).
#[derive(Debug, Clone, Copy)]
pub struct TowedDrag {
    /// The held sphere's case it is the moving counterpart of.
    pub case: HeldSphere,
    pub u0: f64,
    pub tau: f64,
    pub steps: u64,
    /// C_d (nominal diameter) averaged over the sphere's travel from 10 to 12 and from 12 to 14
    /// diameters past its start.
    pub cd_early: f64,
    pub cd: f64,
}

/// Diameters a towed sphere travels, and where its drag is averaged ([`towed_sphere`]).
const TOW_TRAVEL: f64 = 14.0;
const TOW_WINDOWS: [(f64, f64); 2] = [(10.0, 12.0), (12.0, 14.0)];

/// The held sphere of `case` in the frame of the fluid far away: the sphere moves at -u0 along
/// x through fluid at rest, between side walls at rest (the held box's walls moving with the
/// stream), from 19 to 5 diameters from the x = 0 face (velocity 0) of a box 24 diameters long
/// (pressure outlet at x = length). Started impulsively; C_d averaged over whole diameters of
/// travel ([`TOW_WINDOWS`]). The same flow as the held sphere's, but with the sphere's cells
/// covered and uncovered as it moves and the flow unsteady on the lattice: the difference is
/// what the immersed boundary does differently moving and at rest. The case's length is not
/// used (the tow sets it).
pub fn towed_sphere(gpu: &Arc<Gpu>, case: &HeldSphere) -> Result<TowedDrag, String> {
    let (u0, tau) = stream_of(case);
    let d = case.diameter;
    let length = (24.0 * d).round() as usize;
    let rest = [0.0; 3];
    let mut lattice = stream_box(
        gpu,
        [length, case.width, case.width],
        tau,
        case.operator,
        case.imb,
        rest,
    );
    let centre = case.width as f64 / 2.0;
    let start = 19.0 * d;
    let steps = (TOW_TRAVEL * d / u0).ceil() as u64;
    let mut sums = [(0.0, 0u64); 2];
    for step in 0..steps {
        let sphere = SolidParticle {
            position: [start - u0 * step as f64, centre, centre],
            radius: d / 2.0 + case.drawn_larger,
            velocity: [-u0, 0.0, 0.0],
            ..Default::default()
        };
        let force = lattice.step_coupled(&[sphere])?[0].force[0];
        if !force.is_finite() {
            return Err(format!("blew up by step {step} (tau {tau:.4}, u0 {u0})"));
        }
        let travel = u0 * step as f64 / d;
        for (sum, &(from, to)) in sums.iter_mut().zip(&TOW_WINDOWS) {
            if (from..to).contains(&travel) {
                *sum = (sum.0 + force, sum.1 + 1);
            }
        }
    }
    let cd = |(sum, n): (f64, u64)| drag_coefficient(sum / n as f64, u0, d);
    Ok(TowedDrag {
        case: *case,
        u0,
        tau,
        steps,
        cd_early: cd(sums[0]),
        cd: cd(sums[1]),
    })
}

#[cfg(test)]
mod tests {
    use super::unconfined_drag;

    #[test]
    fn the_unconfined_drag_is_recovered_from_three_confined_boxes() {
        let drag = |x: f64| 2.0 + 3.0 * x.powf(2.5);
        let points: Vec<(f64, f64)> = [0.25, 1.0 / 6.0, 0.125, 0.1].map(|x| (x, drag(x))).to_vec();
        let (c_inf, p) = unconfined_drag(&points).expect("a fit");
        assert!((c_inf - 2.0).abs() < 1e-9, "{c_inf}");
        assert!((p - 2.5).abs() < 1e-6, "{p}");
        assert_eq!(unconfined_drag(&points[..2]), None);
        let zigzag = [(0.1, 2.0), (0.125, 2.5), (0.25, 2.2)];
        assert_eq!(unconfined_drag(&zigzag), None);
    }
}
