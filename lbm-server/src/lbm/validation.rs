//! Analytic validation cases of the lattice (lattice units). Each returns what it measured, so the
//! tests assert on it and `lbm-server validate` writes it to validation/lbm/REPORT.md.

use super::geometry::{Face, Operator, Setup};
use super::gpu::{equilibrium_field, total_mass, Gpu, Health, Lattice};
use std::sync::Arc;

/// Result of a steady channel flow: L2 error of u_x against the analytic profile, relative to max.
#[derive(Debug, Clone, Copy)]
pub struct Channel {
    pub cells: usize,
    pub tau: f64,
    pub l2_error: f64,
    pub steps: u64,
}

/// Poiseuille flow between plates at y = -1/2 and y = n - 1/2 (half-way bounce-back), driven by a
/// body force chosen for a centre-line speed `u_max`.
pub fn poiseuille_plates(gpu: &Arc<Gpu>, n: usize, tau: f64, operator: Operator, u_max: f64) -> Channel {
    let faces = [
        Face::Periodic,
        Face::Periodic,
        Face::Wall,
        Face::Wall,
        Face::Periodic,
        Face::Periodic,
    ];
    let mut setup = Setup::new([1, n, 1], faces, tau, operator);
    let nu = setup.viscosity();
    let h = n as f64;
    setup.force = [8.0 * nu * u_max / (h * h), 0.0, 0.0];
    let exact = |y: usize| {
        let y = y as f64 + 0.5;
        4.0 * u_max * y * (h - y) / (h * h)
    };
    let steps = relaxation_steps(h, nu, 20.0);
    let (fields, _) = run_steady(gpu, &setup, |p| (1.0, [exact(p[1]), 0.0, 0.0]), steps);
    let error = l2_relative((0..n).map(|y| (fields[y][1] as f64, exact(y))));
    Channel {
        cells: n,
        tau,
        l2_error: error,
        steps,
    }
}

/// Flow through a square duct of n x n cells (walls on y and z), against the series solution.
pub fn poiseuille_duct(gpu: &Arc<Gpu>, n: usize, tau: f64, operator: Operator, u_max: f64) -> Channel {
    let faces = [
        Face::Periodic,
        Face::Periodic,
        Face::Wall,
        Face::Wall,
        Face::Wall,
        Face::Wall,
    ];
    let mut setup = Setup::new([1, n, n], faces, tau, operator);
    let nu = setup.viscosity();
    let a = n as f64;
    // Series solution for unit forcing, scaled so that the centre speed is u_max.
    let unit = |y: f64, z: f64| duct_series(y / a, z / a) * a * a / nu;
    let g = u_max / unit(a / 2.0, a / 2.0);
    setup.force = [g, 0.0, 0.0];
    let exact = |p: [usize; 3]| g * unit(p[1] as f64 + 0.5, p[2] as f64 + 0.5);
    let steps = relaxation_steps(a, nu, 12.0);
    let (fields, _) = run_steady(gpu, &setup, |p| (1.0, [exact(p), 0.0, 0.0]), steps);
    let error = l2_relative((0..setup.cells()).map(|k| (fields[k][1] as f64, exact(setup.coords(k)))));
    Channel {
        cells: n,
        tau,
        l2_error: error,
        steps,
    }
}

/// u(y, z) of unit force, unit viscosity in the unit square with no-slip walls (Fourier series).
fn duct_series(y: f64, z: f64) -> f64 {
    let pi = std::f64::consts::PI;
    let mut sum = 0.0;
    for i in (1..80).step_by(2) {
        for j in (1..80).step_by(2) {
            let (a, b) = (i as f64 * pi, j as f64 * pi);
            sum += 16.0 / (a * b * (a * a + b * b)) * (a * y).sin() * (b * z).sin();
        }
    }
    sum
}

/// Steps for a diffusive start-up to decay by e^-k: k L^2 / (pi^2 nu).
fn relaxation_steps(length: f64, nu: f64, k: f64) -> u64 {
    (k * length * length / (std::f64::consts::PI.powi(2) * nu)).ceil() as u64 + 100
}

fn run_steady(
    gpu: &Arc<Gpu>,
    setup: &Setup,
    initial: impl Fn([usize; 3]) -> (f64, [f64; 3]),
    steps: u64,
) -> (Vec<[f32; 4]>, u64) {
    let mut lattice = Lattice::new(gpu.clone(), setup.clone(), Health::default(), None).expect("lattice");
    lattice.set_populations(&equilibrium_field(setup, initial));
    lattice.step(steps);
    let (fields, bad) = lattice.fields();
    assert!(bad.is_none(), "unhealthy: {bad:?}");
    (fields, steps)
}

fn l2_relative(pairs: impl Iterator<Item = (f64, f64)>) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (got, want) in pairs {
        num += (got - want).powi(2);
        den += want * want;
    }
    (num / den).sqrt()
}

/// Observed order of convergence between two (resolution, error) points.
pub fn order(a: &Channel, b: &Channel) -> f64 {
    (a.l2_error / b.l2_error).ln() / (b.cells as f64 / a.cells as f64).ln()
}

/// Taylor-Green vortex decay: the measured viscosity against the one set by tau.
#[derive(Debug, Clone, Copy)]
pub struct Decay {
    pub nu_expected: f64,
    pub nu_measured: f64,
    pub relative_error: f64,
}

/// A 2D Taylor-Green vortex in an n x n periodic box: kinetic energy decays as exp(-4 nu k^2 t).
pub fn taylor_green(gpu: &Arc<Gpu>, n: usize, tau: f64, operator: Operator, u0: f64, steps: u64) -> Decay {
    let setup = Setup::new([n, n, 1], [Face::Periodic; 6], tau, operator);
    let k = 2.0 * std::f64::consts::PI / n as f64;
    let state = |p: [usize; 3]| {
        let (x, y) = (p[0] as f64 + 0.5, p[1] as f64 + 0.5);
        let u = [
            u0 * (k * x).sin() * (k * y).cos(),
            -u0 * (k * x).cos() * (k * y).sin(),
            0.0,
        ];
        let pressure = -u0 * u0 / 4.0 * ((2.0 * k * x).cos() + (2.0 * k * y).cos());
        (1.0 + 3.0 * pressure, u)
    };
    let mut lattice = Lattice::new(gpu.clone(), setup.clone(), Health::default(), None).expect("lattice");
    lattice.set_populations(&equilibrium_field(&setup, state));
    // Skip the first steps (initial pressure transients), then fit between two times.
    let energy = |lattice: &Lattice| -> f64 {
        let (fields, _) = lattice.fields();
        fields.iter().map(|f| (f[1] * f[1] + f[2] * f[2]) as f64).sum()
    };
    lattice.step(steps / 10);
    let e0 = energy(&lattice);
    lattice.step(steps);
    let e1 = energy(&lattice);
    let nu_measured = (e0 / e1).ln() / (4.0 * k * k * steps as f64);
    let nu_expected = setup.viscosity();
    Decay {
        nu_expected,
        nu_measured,
        relative_error: (nu_measured - nu_expected).abs() / nu_expected,
    }
}

/// Mass in a closed box with a moving lid, before and after `steps` steps.
#[derive(Debug, Clone, Copy)]
pub struct Mass {
    pub before: f64,
    pub after: f64,
    pub relative_drift: f64,
}

pub fn closed_box_mass(gpu: &Arc<Gpu>, n: usize, steps: u64, operator: Operator) -> Mass {
    let mut faces = [Face::Wall; 6];
    faces[5] = Face::MovingWall([0.05, 0.0, 0.0]);
    let setup = Setup::new([n, n, n], faces, 0.6, operator);
    let mut lattice = Lattice::new(gpu.clone(), setup.clone(), Health::default(), None).expect("lattice");
    let start = super::random::random_populations(&setup, 7);
    lattice.set_populations(&start);
    let before = total_mass(&setup, &lattice.populations());
    lattice.step(steps);
    let after = total_mass(&setup, &lattice.populations());
    Mass {
        before,
        after,
        relative_drift: (after - before).abs() / before,
    }
}

/// Drag on a fixed sphere in a periodic cube (a simple cubic array), against Zick & Homsy (1982).
#[derive(Debug, Clone, Copy)]
pub struct ArrayDrag {
    pub radius: f64,
    /// K = F / (6 pi mu a U) with F the total force on the sphere (see [`zick_homsy`]).
    pub k: f64,
    /// The same from the driving alone: F = f n^3 (the force balance of the unit cell).
    pub k_balance: f64,
    pub steps: u64,
}

/// Stokes flow through a simple cubic array: one sphere of radius r (lattice units) fixed in a
/// periodic n^3 box, flow driven by a body force f on the fluid; K = F / (6 pi mu a U).
///
/// Zick & Homsy's F is the total force on a sphere of an array driven by a mean pressure gradient
/// G, which balances the unit cell: F = G n^3. A body force f = G on the fluid gives the same
/// flow, but the sphere then misses the mean gradient's share G V_s: the momentum exchange
/// measures F - G V_s (= f (1 - phi) n^3 in steady state). So F = exchange + f V_s.
pub fn zick_homsy(gpu: &Arc<Gpu>, n: usize, radius: f64, tau: f64, operator: Operator) -> ArrayDrag {
    zick_homsy_with(gpu, n, radius, tau, operator, super::imb::ImbOptions::default())
}

/// [`zick_homsy`] with given coupling options.
pub fn zick_homsy_with(
    gpu: &Arc<Gpu>,
    n: usize,
    radius: f64,
    tau: f64,
    operator: Operator,
    options: super::imb::ImbOptions,
) -> ArrayDrag {
    array_drag(gpu, n, [radius, radius], tau, operator, options)
}

/// How much larger (`delta`, cells) the immersed boundary must draw a sphere for the array to
/// have Zick & Homsy's drag: the boundary's hydrodynamic radius falls short of the nominal one by
/// an amount that grows with tau (validation/lbm/REPORT.md, "drag against tau").
#[derive(Debug, Clone, Copy)]
pub struct RadiusDeficit {
    pub delta: f64,
    /// K drawn at the nominal radius, and at the nominal radius + delta (both normalised with
    /// the nominal radius).
    pub k_nominal: f64,
    pub k_drawn: f64,
    pub steps: u64,
}

/// [`RadiusDeficit`] of a sphere of nominal `radius` in an n^3 array at this tau: the drag at
/// delta = 0 and 0.25 cells, delta from the secant through them, and the drag drawn with it.
pub fn radius_deficit(
    gpu: &Arc<Gpu>,
    n: usize,
    radius: f64,
    k_ref: f64,
    tau: f64,
    operator: Operator,
) -> RadiusDeficit {
    let options = super::imb::ImbOptions::default();
    let k_at = |delta: f64| array_drag(gpu, n, [radius + delta, radius], tau, operator, options);
    let (nominal, probe) = (k_at(0.0), k_at(0.25));
    let delta = 0.25 * (k_ref - nominal.k) / (probe.k - nominal.k);
    let drawn = k_at(delta);
    RadiusDeficit {
        delta,
        k_nominal: nominal.k,
        k_drawn: drawn.k,
        steps: nominal.steps,
    }
}

/// The array of [`zick_homsy_with`] with the sphere drawn at `[drawn, nominal]` radius: the
/// lattice covers the drawn one, K and the pressure-gradient share are the nominal one's.
fn array_drag(
    gpu: &Arc<Gpu>,
    n: usize,
    radii: [f64; 2],
    tau: f64,
    operator: Operator,
    options: super::imb::ImbOptions,
) -> ArrayDrag {
    moving_array_drag(gpu, n, radii, tau, operator, options, 0.0)
}

/// [`array_drag`] with the sphere moving at `velocity` (cells per step, along x) through the
/// periodic lattice, its cells covered and uncovered as it goes; the same body force drives the
/// fluid. Stokes flow depends only on the velocity relative to the sphere, so a boundary that
/// acts the same moving and at rest gives the same K. The loads and the relative velocity are
/// averaged over the last 4 cells of travel (the drag of a moving sphere wavers with its place
/// against the lattice); the relative velocity is the flux through the plane farthest from the
/// sphere less its velocity.
pub fn moving_array_drag(
    gpu: &Arc<Gpu>,
    n: usize,
    [drawn, radius]: [f64; 2],
    tau: f64,
    operator: Operator,
    options: super::imb::ImbOptions,
    velocity: f64,
) -> ArrayDrag {
    use super::imb::SolidParticle;
    let mut setup = Setup::new([n, n, n], [Face::Periodic; 6], tau, operator);
    let nu = setup.viscosity();
    // A force small enough for Stokes flow (Re << 1).
    let f = 1e-6;
    setup.force = [f, 0.0, 0.0];
    let centre = n as f64 / 2.0;
    let sphere_at = |step: u64| SolidParticle {
        position: [
            (centre + velocity * step as f64).rem_euclid(n as f64),
            centre,
            centre,
        ],
        radius: drawn,
        velocity: [velocity, 0.0, 0.0],
        ..Default::default()
    };
    let mut lattice = coupled_lattice(gpu, &setup, options);
    let steps = relaxation_steps(n as f64, nu, 12.0);
    // The last 4 cells of travel, the flux sampled 16 times over them (at rest: the last step).
    let (window, samples) = if velocity == 0.0 {
        (1, 1)
    } else {
        ((4.0 / velocity.abs()).round() as u64, 16)
    };
    let stride = (window / samples).max(1);
    let (mut exchange, mut relative) = (0.0, 0.0);
    for step in 0..steps {
        let sphere = sphere_at(step);
        let load = lattice.step_coupled(&[sphere]).expect("coupled step")[0].force[0];
        let left = steps - step - 1;
        if left < window {
            exchange += load / window as f64;
            if left.is_multiple_of(stride) && left / stride < samples {
                let x_far = (sphere.position[0] + centre).floor() as usize % n;
                relative += (plane_flux(&lattice.fields().0, n, x_far) - velocity) / samples as f64;
            }
        }
    }
    let (_, bad) = lattice.fields();
    assert!(bad.is_none(), "unhealthy: {bad:?}");
    let stokes = 6.0 * std::f64::consts::PI * nu * radius * relative;
    let sphere_volume = 4.0 / 3.0 * std::f64::consts::PI * radius.powi(3);
    ArrayDrag {
        radius,
        k: (exchange + f * sphere_volume) / stokes,
        k_balance: f * (n * n * n) as f64 / stokes,
        steps,
    }
}

/// The mean velocity along x through the plane x of an n^3 lattice's `fields` (the volumetric
/// flux over its area); a moving sphere must not cut the plane (the fluid inside an immersed
/// boundary moves with it, so the plane would count it).
fn plane_flux(fields: &[[f32; 4]], n: usize, x: usize) -> f64 {
    (0..n * n).map(|k| fields[x + k * n][1] as f64).sum::<f64>() / (n * n) as f64
}

/// A lattice coupled to particles, with the default health limits.
fn coupled_lattice(gpu: &Arc<Gpu>, setup: &Setup, options: super::imb::ImbOptions) -> Lattice {
    Lattice::new(gpu.clone(), setup.clone(), Health::default(), Some(options)).expect("lattice")
}

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
    pub imb: super::imb::ImbOptions,
    /// Cells the held sphere's centre is moved downstream from L/3 (its place against the
    /// lattice; not used by the towed sphere, which passes every place).
    pub shift: f64,
}

impl HeldSphere {
    /// The held sphere: at rest, its centre a third of the length downstream (moved by `shift`)
    /// on the box's axis, drawn larger by `drawn_larger`.
    fn particle(&self) -> super::imb::SolidParticle {
        let (w, l) = (self.width as f64, self.length as f64);
        super::imb::SolidParticle {
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
fn stream_box(
    gpu: &Arc<Gpu>,
    size: [usize; 3],
    tau: f64,
    operator: Operator,
    imb: super::imb::ImbOptions,
    stream: [f64; 3],
) -> Lattice {
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
fn drag_coefficient(force: f64, u0: f64, diameter: f64) -> f64 {
    force / (0.5 * u0 * u0 * std::f64::consts::PI * diameter * diameter / 4.0)
}

/// The stream velocity and tau of a held sphere: at the given tau, or at [`STREAM_VELOCITY`]
/// unless tau would pass [`STREAM_TAU`].
fn stream_of(case: &HeldSphere) -> (f64, f64) {
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

/// How a held sphere's run near tau = 1/2 ended ([`sphere_stability`]).
#[derive(Debug, Clone, Copy)]
pub struct Stability {
    pub tau: f64,
    /// Steps run: the whole horizon, or up to the health check that failed.
    pub steps: u64,
    /// The first cell that failed the health check (|rho - 1| > 0.5, |u| > 0.4 or not finite),
    /// if one did by `steps`.
    pub unhealthy: Option<super::gpu::Unhealthy>,
    /// C_d over the last pass of the stream through the box: mean, lowest, highest (the wake
    /// may shed); None if it blew up.
    pub cd: Option<[f64; 3]>,
    /// The mean of u_x over the box at the last check, against u0 (the periodic box's stream
    /// slows as the sphere takes its momentum).
    pub stream: f64,
}

/// The faces around a held sphere ([`sphere_stability`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Faces {
    /// [`held_sphere`]'s: velocity inlet, pressure outlet, side faces moving with the stream.
    Open,
    /// Periodic on all six faces: no boundary but the sphere; the stream, not driven, slows.
    Periodic,
}

/// Steps between the health checks of [`sphere_stability`] (each reads every cell back).
pub const STABILITY_CHECK: u64 = 10;

/// The held sphere of `case` ([`held_sphere`]'s stream, sphere and box, with these `faces`) run
/// for `passes` passes of the stream through the box whether or not its drag settles (above Re ~
/// 210 a sphere's wake is unsteady), with the lattice's health checked every `check` steps
/// ([`STABILITY_CHECK`] where that is the question): whether this operator at this tau holds the
/// flow, where it first fails if not, and the drag over the last pass where it holds.
pub fn sphere_stability(
    gpu: &Arc<Gpu>,
    case: &HeldSphere,
    faces: Faces,
    passes: f64,
    check: u64,
) -> Stability {
    let (u0, tau) = stream_of(case);
    let (d, width, length) = (case.diameter, case.width, case.length);
    let size = [length, width, width];
    let stream = [u0, 0.0, 0.0];
    let mut lattice = match faces {
        Faces::Open => stream_box(gpu, size, tau, case.operator, case.imb, stream),
        Faces::Periodic => {
            let setup = Setup::new(size, [Face::Periodic; 6], tau, case.operator);
            let mut lattice = coupled_lattice(gpu, &setup, case.imb);
            lattice.set_populations(&equilibrium_field(&setup, |_| (1.0, stream)));
            lattice
        }
    };
    let sphere = case.particle();
    let pass = (length as f64 / u0).ceil() as u64;
    let horizon = ((passes * pass as f64) as u64).div_ceil(check) * check;
    let last_pass = horizon.saturating_sub(pass);
    let (mut sum, mut low, mut high, mut n) = (0.0, f64::INFINITY, f64::NEG_INFINITY, 0u64);
    let (mut steps, mut stream) = (0, 1.0);
    while steps < horizon {
        for _ in 0..check {
            let force = lattice
                .step_coupled(&[sphere])
                .map_or(f64::NAN, |l| l[0].force[0]);
            steps += 1;
            if steps > last_pass {
                let cd = drag_coefficient(force, u0, d);
                (sum, low, high, n) = (sum + cd, low.min(cd), high.max(cd), n + 1);
            }
        }
        let (fields, unhealthy) = lattice.fields();
        if unhealthy.is_some() {
            return Stability {
                tau,
                steps,
                unhealthy,
                cd: None,
                stream,
            };
        }
        stream = fields.iter().map(|c| c[1] as f64).sum::<f64>() / fields.len() as f64 / u0;
    }
    let cd = sum.is_finite().then_some([sum / n as f64, low, high]);
    Stability {
        tau,
        steps,
        unhealthy: None,
        cd,
        stream,
    }
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
    use super::imb::SolidParticle;
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

/// Zick & Homsy (1982), Table 2: (solid fraction, K), from ../shared/reference/zick-homsy-1982.csv.
pub const ZICK_HOMSY: [(f64, f64); 3] = [(0.027, 2.008), (0.125, 4.292), (0.343, 15.4)];

/// Sangani & Acrivos (1982): K of a dilute simple cubic array of spheres at solid fraction c,
/// their expansion in c^(1/3) (within 0.1% of Zick & Homsy's 2.008 and 4.292 at 0.027 and 0.125).
pub fn sangani_acrivos(c: f64) -> f64 {
    let s = c.cbrt();
    1.0 / (1.0 - 1.7601 * s + c - 1.5593 * c * c + 3.9799 * s.powi(8) - 3.0734 * s.powi(10))
}

/// Radius giving solid fraction phi in an n^3 box.
pub fn radius_for(phi: f64, n: usize) -> f64 {
    (phi * (n * n * n) as f64 * 3.0 / (4.0 * std::f64::consts::PI)).cbrt()
}

/// Total momentum (fluid + particle) in a closed periodic box with one free particle.
#[derive(Debug, Clone, Copy)]
pub struct Momentum {
    pub initial: [f64; 3],
    pub last: [f64; 3],
    pub relative_change: f64,
    pub particle_velocity: [f64; 3],
}

/// A fluid moving at u0 along x around a particle at rest (density ratio 2), periodic box: the
/// particle is dragged along; fluid + particle momentum must not change.
pub fn momentum_exchange(gpu: &Arc<Gpu>, n: usize, steps: u64) -> Momentum {
    use super::imb::{ImbOptions, SolidParticle};
    let setup = Setup::new(
        [n, n, n],
        [Face::Periodic; 6],
        0.7,
        Operator::Trt { magic: 3.0 / 16.0 },
    );
    let mut lattice = coupled_lattice(gpu, &setup, ImbOptions::default());
    let u0 = 0.02;
    lattice.set_populations(&equilibrium_field(&setup, |_| (1.0, [u0, 0.0, 0.0])));
    let radius = n as f64 / 6.0;
    let mass = 2.0 * 4.0 / 3.0 * std::f64::consts::PI * radius.powi(3);
    let mut p = SolidParticle {
        position: [n as f64 / 2.0 + 0.3, n as f64 / 2.0 - 0.2, n as f64 / 2.0],
        radius,
        ..Default::default()
    };
    let fluid_momentum = |lattice: &Lattice| -> [f64; 3] {
        let f = lattice.populations();
        let mut j = [0.0; 3];
        for cell in &f {
            for (i, fi) in cell.iter().enumerate() {
                for (ja, c) in j.iter_mut().zip(super::lattice::C[i]) {
                    *ja += fi * c as f64;
                }
            }
        }
        j
    };
    let total = |lattice: &Lattice, p: &SolidParticle| -> [f64; 3] {
        let j = fluid_momentum(lattice);
        std::array::from_fn(|a| j[a] + mass * p.velocity[a])
    };
    let initial = total(&lattice, &p);
    for _ in 0..steps {
        let load = lattice.step_coupled(&[p]).expect("coupled step")[0];
        for a in 0..3 {
            p.velocity[a] += load.force[a] / mass;
            p.position[a] += p.velocity[a];
        }
    }
    let last = total(&lattice, &p);
    let norm = |v: [f64; 3]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let change = norm(std::array::from_fn(|a| last[a] - initial[a])) / norm(initial);
    Momentum {
        initial,
        last,
        relative_change: change,
        particle_velocity: p.velocity,
    }
}

/// An array of spheres held in a periodic n^3 box ([`array_at_weight`]).
#[derive(Debug, Clone)]
pub struct Array {
    pub cells: usize,
    pub diameter: f64,
    pub centres: Vec<[f64; 3]>,
    /// The x planes whose mean velocity is the superficial velocity: one that no sphere cuts, or
    /// all of them (the mean over the box; the fluid inside a held sphere is at rest).
    pub planes: Vec<usize>,
}

impl Array {
    /// One sphere at the centre of the box: a simple cubic array of solid fraction phi,
    /// d = n (6 phi / pi)^(1/3). The plane x = 0 lies half a box from the centre: no sphere cuts it.
    pub fn simple_cubic(n: usize, phi: f64) -> Self {
        Self {
            cells: n,
            diameter: n as f64 * (6.0 * phi / std::f64::consts::PI).cbrt(),
            centres: vec![[n as f64 / 2.0; 3]],
            planes: vec![0],
        }
    }

    /// Per cell (x fastest): whether its centre lies within a sphere, periodically.
    pub fn staircase(&self) -> Vec<bool> {
        let (n, r) = (self.cells, self.diameter / 2.0);
        let side = n as f64;
        let gap = |a: f64, b: f64| {
            let d = (a - b).abs();
            d.min(side - d)
        };
        (0..n * n * n)
            .map(|k| {
                let x = [k % n, (k / n) % n, k / (n * n)].map(|q| q as f64 + 0.5);
                self.centres
                    .iter()
                    .any(|c| (0..3).map(|a| gap(x[a], c[a]).powi(2)).sum::<f64>() < r * r)
            })
            .collect()
    }

    /// `count` spheres of solid fraction phi placed at random, none overlapping another across
    /// the periodic box (random sequential addition from `seed`): a random array as Tenneti et
    /// al. (2011) simulated theirs. Panics if a sphere finds no place in 100,000 tries.
    pub fn random(n: usize, count: usize, phi: f64, seed: u64) -> Self {
        let side = n as f64;
        let diameter = side * (6.0 * phi / (std::f64::consts::PI * count as f64)).cbrt();
        let mut random = super::random::Random::new(seed);
        let mut centres: Vec<[f64; 3]> = Vec::with_capacity(count);
        let apart = |a: &[f64; 3], b: &[f64; 3]| {
            let gap = |i: usize| {
                let d = (a[i] - b[i]).abs();
                d.min(side - d)
            };
            (gap(0).powi(2) + gap(1).powi(2) + gap(2).powi(2)).sqrt() >= diameter
        };
        for k in 0..count {
            let place = (0..100_000)
                .map(|_| std::array::from_fn(|_| side * 0.5 * (random.next() + 1.0)))
                .find(|c| centres.iter().all(|o| apart(c, o)))
                .unwrap_or_else(|| panic!("sphere {k} of {count} finds no place at solid fraction {phi}"));
            centres.push(place);
        }
        Self {
            cells: n,
            diameter,
            centres,
            planes: (0..n).collect(),
        }
    }
}

/// How the held spheres of an [`Array`] meet the fluid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Spheres {
    /// The immersed moving boundary (partially saturated cells).
    Immersed,
    /// Solid cells, those whose centre lies within a sphere, with half-way bounce-back: a
    /// staircase of the sphere, no solid fractions.
    Staircase,
}

/// An array held against a weight per sphere ([`array_at_weight`]).
#[derive(Debug, Clone, Copy)]
pub struct WeightedArray {
    /// The periodic box's side n and the spheres' diameter d (cells).
    pub cells: usize,
    pub diameter: f64,
    pub tau: f64,
    pub steps: u64,
    /// Particle Reynolds number U d / nu of the superficial velocity U (the mean velocity over the
    /// array's planes): mean, lowest and highest over the last [`WEIGHT_SAMPLES`] checks.
    pub reynolds: [f64; 3],
    /// The first cell that failed the health check, if one did.
    pub unhealthy: Option<super::gpu::Unhealthy>,
}

/// Checks of the flux (one per [`WEIGHT_CHECK`] steps) that [`array_at_weight`] averages over and
/// that must agree to 1e-3 for it to stop.
pub const WEIGHT_SAMPLES: usize = 20;
pub const WEIGHT_CHECK: u64 = 100;

/// The spheres of `array` held in their periodic box, the fluid driven by a mean pressure
/// gradient f whose force on the box, f n^3, is `weight` rho nu^2 per sphere: the force a grain's
/// weight puts on the liquid in a fluidized bed, weight = (rho_p / rho_f - 1) g V / nu^2 = Ar pi
/// / 6. At rho = 1 and viscosity nu the superficial velocity settles where the array's drag
/// carries that weight; the run starts from the fluid at `u_start` everywhere and stops when
/// the last [`WEIGHT_SAMPLES`] fluxes agree to 1e-3 (a steady flow), after `max_steps`, or at a
/// failed health check. `boundary`: how the spheres meet the fluid.
pub fn array_at_weight(
    gpu: &Arc<Gpu>,
    array: &Array,
    [nu, weight]: [f64; 2],
    (operator, boundary): (Operator, Spheres),
    u_start: f64,
    max_steps: u64,
) -> WeightedArray {
    let setup = weighted_array_setup(array, [nu, weight], operator, boundary);
    let mut lattice = match boundary {
        Spheres::Immersed => coupled_lattice(gpu, &setup, Default::default()),
        Spheres::Staircase => {
            Lattice::new(gpu.clone(), setup.clone(), Health::default(), None).expect("lattice")
        }
    };
    lattice.set_populations(&equilibrium_field(&setup, |_| (1.0, [u_start, 0.0, 0.0])));
    let spheres: Vec<super::imb::SolidParticle> = array
        .centres
        .iter()
        .map(|&position| super::imb::SolidParticle {
            position,
            radius: array.diameter / 2.0,
            ..Default::default()
        })
        .collect();
    let mut history: Vec<f64> = Vec::new();
    let mut steps = 0;
    let mut unhealthy = None;
    while steps < max_steps {
        match boundary {
            Spheres::Immersed => {
                for _ in 0..WEIGHT_CHECK {
                    lattice.step_coupled(&spheres).expect("coupled step");
                }
            }
            Spheres::Staircase => lattice.step(WEIGHT_CHECK),
        }
        steps += WEIGHT_CHECK;
        let (fields, bad) = lattice.fields();
        if bad.is_some() {
            unhealthy = bad;
            break;
        }
        history.push(array_reynolds(array, &fields, nu));
        if steady(&history) {
            break;
        }
    }
    let last = &history[history.len().saturating_sub(WEIGHT_SAMPLES)..];
    let mean = last.iter().sum::<f64>() / last.len().max(1) as f64;
    let (low, high) = range(last);
    WeightedArray {
        cells: array.cells,
        diameter: array.diameter,
        tau: setup.tau,
        steps,
        reynolds: [mean, low, high],
        unhealthy,
    }
}

/// The periodic box of `array` with viscosity `nu` and the body force that carries `weight`
/// (in nu^2, per sphere) on the fluid cells: the spheres' solid cells with `Spheres::Staircase`.
fn weighted_array_setup(
    array: &Array,
    [nu, weight]: [f64; 2],
    operator: Operator,
    boundary: Spheres,
) -> Setup {
    let n = array.cells;
    let tau = 0.5 + 3.0 * nu;
    let mut setup = Setup::new([n, n, n], [Face::Periodic; 6], tau, operator);
    if boundary == Spheres::Staircase {
        setup.solid = array.staircase();
    }
    // The force acts on the fluid cells (solid cells are not updated): f times their count is
    // the weight of every sphere.
    let fluid = setup.solid.iter().filter(|&&s| !s).count();
    setup.force = [
        weight * nu * nu * array.centres.len() as f64 / fluid as f64,
        0.0,
        0.0,
    ];
    setup
}

/// The superficial Reynolds number of `array`'s flow: the mean flux through its planes times the
/// diameter over `nu`.
fn array_reynolds(array: &Array, fields: &[[f32; 4]], nu: f64) -> f64 {
    let flux = array
        .planes
        .iter()
        .map(|&x| plane_flux(fields, array.cells, x))
        .sum::<f64>();
    flux / array.planes.len() as f64 * array.diameter / nu
}

/// Whether the last `WEIGHT_SAMPLES` Reynolds numbers of `history` agree within 0.1%.
fn steady(history: &[f64]) -> bool {
    let last = &history[history.len().saturating_sub(WEIGHT_SAMPLES)..];
    let (low, high) = range(last);
    last.len() == WEIGHT_SAMPLES && high - low < 1e-3 * high.abs()
}

/// The lowest and highest of `values`.
fn range(values: &[f64]) -> (f64, f64) {
    values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
            (l.min(v), h.max(v))
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

    /// A random array: its spheres at the solid fraction asked for, none overlapping another across
    /// the periodic box, the same placement from the same seed and another from another.
    #[test]
    fn a_random_array_places_its_spheres_apart_at_the_solid_fraction() {
        let (n, count, phi) = (25, 32, 0.24);
        let array = super::Array::random(n, count, phi, 1);
        assert_eq!(array.centres.len(), count);
        let volume = count as f64 * std::f64::consts::PI / 6.0 * array.diameter.powi(3);
        assert!((volume / (n * n * n) as f64 - phi).abs() < 1e-12);
        let side = n as f64;
        for (i, a) in array.centres.iter().enumerate() {
            assert!(a.iter().all(|&x| (0.0..side).contains(&x)), "{a:?}");
            for b in &array.centres[i + 1..] {
                let d2: f64 = (0..3)
                    .map(|k| {
                        let d = (a[k] - b[k]).abs();
                        d.min(side - d).powi(2)
                    })
                    .sum();
                assert!(d2.sqrt() >= array.diameter, "{a:?} {b:?}");
            }
        }
        assert_eq!(super::Array::random(n, count, phi, 1).centres, array.centres);
        assert_ne!(super::Array::random(n, count, phi, 2).centres, array.centres);
        assert_eq!(array.planes.len(), n);
    }

    /// A staircase: the cells whose centre lies within a sphere, across the periodic faces too;
    /// over 32 spheres at random, near their volume.
    #[test]
    fn a_staircase_marks_the_cells_within_each_sphere_across_the_faces() {
        let (n, diameter) = (16, 7.0);
        let one = |centre: [f64; 3]| super::Array {
            cells: n,
            diameter,
            centres: vec![centre],
            planes: vec![0],
        };
        let middle = one([8.0; 3]).staircase();
        let corner = one([0.0; 3]).staircase();
        let count = |cells: &[bool]| cells.iter().filter(|&&s| s).count();
        assert_eq!(count(&middle), count(&corner));
        assert!(corner[0] && corner[n - 1] && corner[n * n * n - 1]);
        assert!(middle[8 + 8 * n + 8 * n * n] && !middle[0]);
        let random = super::Array::random(25, 32, 0.24, 1);
        let solid = count(&random.staircase()) as f64 / 25f64.powi(3);
        assert!((solid / 0.24 - 1.0).abs() < 0.03, "{solid}");
    }
}
