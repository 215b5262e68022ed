//! `lbm-server bench --particles`: the coupled step against the LBM-only step of the same run,
//! and (`--passes`) each of its passes.

use super::paired::{lockstep, lockstep_step, paired, process_cpu_seconds, Paired};
use super::BenchArgs;
use crate::lbm::geometry::Setup;
use crate::lbm::gpu::{Gpu, GpuLattice, Health};
use crate::lbm::imb::{CoveredCells, ImbOptions, SolidParticle};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// The ways of treating the covered cells that `--covered-cells` names.
pub(super) fn covered_cell_modes(name: &str) -> Result<Vec<CoveredCells>, String> {
    match name {
        "both" => return Ok(vec![CoveredCells::Redo, CoveredCells::Fused]),
        "all" => return Ok(CoveredCells::DEFINITE.to_vec()),
        _ => {}
    }
    CoveredCells::from_name(name)
        .map(|mode| vec![mode])
        .ok_or_else(|| format!("--covered-cells {name}: expected auto, fused, redo, skip, both or all"))
}

/// The coupled rows of the bench: the lockstep's own cost, then coupled MLUPS for each particle
/// count and way of treating the covered cells, against the LBM-only figure of the same run.
pub struct Sweep {
    pub gpu: Arc<Gpu>,
    pub setup: Setup,
    pub steps: u64,
    /// Also time each pass (`--passes`).
    pub passes: bool,
    pub modes: Vec<CoveredCells>,
    /// The host's idle milliseconds per step after the loads, a stand-in for the DEM's step.
    pub dem_ms: f64,
}

impl Sweep {
    /// The sweep that the bench's arguments ask for.
    pub fn new(gpu: &Arc<Gpu>, setup: &Setup, args: &BenchArgs) -> Result<Sweep, String> {
        let modes = covered_cell_modes(&args.covered_cells)?;
        let dem_ms = args.dem_ms;
        if !(dem_ms.is_finite() && dem_ms >= 0.0) {
            return Err(format!("--dem-ms = {dem_ms}: expected 0 or more milliseconds"));
        }
        Ok(Sweep {
            gpu: gpu.clone(),
            setup: setup.clone(),
            steps: args.steps,
            passes: args.passes,
            modes,
            dem_ms,
        })
    }

    fn dem(&self) -> Duration {
        Duration::from_secs_f64(self.dem_ms / 1e3)
    }

    /// Prints the sweep's table over `counts` particles, against `lbm_only` MLUPS; the LBM-only
    /// `lbm` lattice of that figure is stepped as the lockstep steps beside each row (the table by
    /// CPU time).
    pub fn run(&self, mut lbm: GpuLattice, counts: &[usize], lbm_only: f64) -> Result<(), String> {
        self.print_head(lbm_only);
        let mut by_cpu = Vec::new();
        let mut row = |particles: &str, covered_cells: &str, timed: Paired| {
            let mlups = timed.steps.mlups;
            println!(
                "| {particles} | {covered_cells} | {mlups:.1} | {:.0}% |",
                100.0 * mlups / lbm_only
            );
            by_cpu.push((particles.to_string(), covered_cells.to_string(), timed));
        };
        self.lockstep_rows(&mut lbm, &mut row)?;
        let mut tables = PassTables::default();
        for &count in counts {
            let particles = bench_spheres(count, self.setup.n)?;
            for &mode in &self.modes {
                let mut lattice = self.lattice(mode)?;
                let name = lattice.covered_cells().name();
                let timed = self.coupled_timed(&mut lattice, &particles, &mut lbm)?;
                row(&count.to_string(), name, timed);
                if self.passes {
                    tables.add(count, name, &mut lattice, &particles, self.steps)?;
                }
            }
        }
        print_by_cpu(&by_cpu);
        if self.passes {
            tables.print();
        }
        Ok(())
    }

    fn print_head(&self, lbm_only: f64) {
        println!("coupled (spheres of 4 cells diameter, immersed moving boundary, one readback per step):");
        if self.dem_ms > 0.0 {
            let dem_ms = self.dem_ms;
            println!("(the host waits {dem_ms} ms per step after the loads, a stand-in for the DEM's step)");
        }
        println!("| particles | covered cells | MLUPS | ratio to LBM-only ({lbm_only:.1} MLUPS) |");
        println!("|---:|---|---:|---:|");
    }

    /// The lockstep's own cost: LBM-only steps, each submitted and waited for as a coupled step
    /// is (after 5 untimed); then the fluid kernels that test the cover mask (one bit per cell),
    /// no particle, beside them.
    fn lockstep_rows(
        &self,
        lbm: &mut GpuLattice,
        row: &mut dyn FnMut(&str, &str, Paired),
    ) -> Result<(), String> {
        lbm.step(5);
        let timed = lockstep(&self.gpu, lbm, self.steps, self.dem())?;
        let alone = Paired {
            steps: timed,
            lbm_only: timed,
        };
        row("0 (no coupling: one submit and wait per step)", "-", alone);
        for mode in [CoveredCells::Fused, CoveredCells::Skip] {
            if !self.modes.contains(&mode) {
                continue;
            }
            let name = mode.name();
            let mut lattice = self.lattice(mode)?;
            lattice.step(5);
            let mut step = || lockstep_step(&self.gpu, &mut lattice);
            let timed = self.beside(lbm, &mut step)?;
            let what = format!("0 ({name} fluid kernels, no particle: one submit and wait per step)");
            row(&what, name, timed);
        }
        Ok(())
    }

    fn lattice(&self, mode: CoveredCells) -> Result<GpuLattice, String> {
        let options = ImbOptions {
            covered_cells: mode,
            ..Default::default()
        };
        GpuLattice::new(
            self.gpu.clone(),
            self.setup.clone(),
            Health::default(),
            Some(options),
        )
    }

    /// The sweep's coupled steps with `particles` (after 5 untimed), the host idle `dem` after
    /// each, beside the LBM-only lockstep steps of `lbm`.
    fn coupled_timed(
        &self,
        lattice: &mut GpuLattice,
        particles: &[SolidParticle],
        lbm: &mut GpuLattice,
    ) -> Result<Paired, String> {
        for _ in 0..5 {
            lattice.step_coupled(particles)?;
        }
        let mut step = || lattice.step_coupled(particles).map(|_| ());
        self.beside(lbm, &mut step)
    }

    /// The sweep's steps of `step` timed beside as many LBM-only lockstep steps of `lbm`.
    fn beside(
        &self,
        lbm: &mut GpuLattice,
        step: &mut dyn FnMut() -> Result<(), String>,
    ) -> Result<Paired, String> {
        let cells = self.setup.cells();
        paired(&self.gpu, lbm, cells, self.steps, self.dem(), step)
    }
}

/// The sweep's rows by CPU time per step, each against the LBM-only lockstep steps timed beside
/// it: on a shared machine the ratio that moves least.
fn print_by_cpu(rows: &[(String, String, Paired)]) {
    println!("coupled steps by CPU time (this process, all threads), each beside as many LBM-only steps in alternating blocks:");
    println!("| particles | covered cells | CPU ms per step | LBM-only beside it (CPU ms per step) | ratio to LBM-only by CPU |");
    println!("|---:|---|---:|---:|---:|");
    for (particles, covered_cells, timed) in rows {
        println!(
            "| {particles} | {covered_cells} | {:.2} | {:.2} | {:.0}% |",
            timed.steps.cpu_ms,
            timed.lbm_only.cpu_ms,
            timed.ratio_by_cpu()
        );
    }
}

/// The bench's `count` spheres of 4 cells on a regular lattice filling grid `n`: a cube number of
/// them, at least 4 cells apart.
pub(super) fn bench_spheres(count: usize, n: [usize; 3]) -> Result<Vec<SolidParticle>, String> {
    let side = (count as f64).cbrt().round().max(1.0) as usize;
    if side * side * side != count {
        return Err(format!(
            "--particles {count}: use cubes (1, 8, 64, 512, 4096, 32768)"
        ));
    }
    let spacing: [f64; 3] = std::array::from_fn(|a| n[a] as f64 / side as f64);
    if spacing.iter().any(|s| *s < 4.0) {
        return Err(format!(
            "--particles {count}: {side}^3 spheres of 4 cells do not fit the grid"
        ));
    }
    Ok(sphere_lattice(side, spacing))
}

/// The time of each pass per particle count and way (`--passes`), by the three clocks.
#[derive(Default)]
struct PassTables {
    /// Each pass submitted and waited for on its own: wall and CPU time.
    split: Vec<(usize, &'static str, PassTimes<2>)>,
    /// The device's timestamps in steps not split.
    clocked: Vec<(usize, &'static str, PassTimes<1>)>,
    /// The host's own passes, per particle count.
    host: Vec<(usize, [f64; 2])>,
}

impl PassTables {
    fn add(
        &mut self,
        count: usize,
        name: &'static str,
        lattice: &mut GpuLattice,
        particles: &[SolidParticle],
        steps: u64,
    ) -> Result<(), String> {
        self.split
            .push((count, name, time_passes(lattice, particles, steps)?));
        if let Some(times) = clock_passes(lattice, particles, steps)? {
            self.clocked.push((count, name, times));
        }
        if self.host.last().is_none_or(|(c, _)| *c != count) {
            self.host.push((count, lattice.host_pass_times(particles, 21)?));
        }
        Ok(())
    }

    fn print(&self) {
        let split = "each pass submitted and waited for on its own";
        print_passes(&self.split, ["wall", "CPU (all threads)"], split);
        let unsplit = "the device's timestamps between the passes of steps not split, as a run makes them";
        print_passes(&self.clocked, ["device clock"], unsplit);
        print_host_passes(&self.host);
    }
}

/// The host's passes per particle count (`GpuLattice::host_pass_times`).
fn print_host_passes(host: &[(usize, [f64; 2])]) {
    println!(
        "host passes of a coupled step ({} threads, no device; median of 21):",
        rayon::current_num_threads()
    );
    println!("| particles | sizes, checks, records into staging (ms) | loads converted (ms) |");
    println!("|---:|---:|---:|");
    for (count, [upload, loads]) in host {
        println!("| {count} | {upload:.3} | {loads:.3} |");
    }
}

/// side^3 spheres of radius 2 cells at the centres of a regular lattice of `spacing`.
fn sphere_lattice(side: usize, spacing: [f64; 3]) -> Vec<SolidParticle> {
    (0..side * side * side)
        .map(|k| {
            let idx = [k % side, (k / side) % side, k / (side * side)];
            SolidParticle {
                position: std::array::from_fn(|a| (idx[a] as f64 + 0.5) * spacing[a]),
                radius: 2.0,
                ..Default::default()
            }
        })
        .collect()
}

/// Mean milliseconds of each pass of the coupled step over `steps` steps, each pass submitted on
/// its own: wall time and this process's CPU time (all threads: lavapipe's workers do the work, and
/// the CPU time moves less than the wall time when other jobs share the cores).
fn time_passes(
    lattice: &mut GpuLattice,
    particles: &[SolidParticle],
    steps: u64,
) -> Result<PassTimes<2>, String> {
    let clock = || [start_of_run().elapsed().as_secs_f64(), process_cpu_seconds()];
    let mut sums: PassTimes<2> = Vec::new();
    for _ in 0..steps {
        let times = lattice.step_coupled_timed(particles, &clock)?;
        let ms = times.iter().map(|(name, t)| (*name, t.map(|t| t * 1e3)));
        add_mean(&mut sums, ms, steps);
    }
    Ok(sums)
}

/// Milliseconds of each pass by the device's clock over `steps` steps not split into submissions
/// (mean), where the device has timestamps.
fn clock_passes(
    lattice: &mut GpuLattice,
    particles: &[SolidParticle],
    steps: u64,
) -> Result<Option<PassTimes<1>>, String> {
    let Some(clock) = lattice.pass_clock() else {
        return Ok(None);
    };
    let mut sums = Vec::new();
    for _ in 0..steps {
        let times = lattice.step_coupled_clocked(particles, &clock)?;
        add_mean(&mut sums, times.iter().map(|(name, t)| (*name, [*t])), steps);
    }
    Ok(Some(sums))
}

/// Adds one step's times of each pass (ms) over `steps` to `sums` (the passes in the same order).
fn add_mean<const N: usize>(
    sums: &mut PassTimes<N>,
    times: impl Iterator<Item = (&'static str, [f64; N])>,
    steps: u64,
) {
    for (k, (name, t)) in times.enumerate() {
        if k == sums.len() {
            sums.push((name, [0.0; N]));
        }
        for (total, t) in sums[k].1.iter_mut().zip(t) {
            *total += t / steps as f64;
        }
    }
}

fn start_of_run() -> Instant {
    static START: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();
    *START.get_or_init(Instant::now)
}

/// Milliseconds by N clocks of each pass of a coupled step, in the order of the step.
type PassTimes<const N: usize> = Vec<(&'static str, [f64; N])>;

/// The time of each pass per particle count: one table per way of treating the covered cells
/// (their passes differ) and clock; `how` the passes were timed.
fn print_passes<const N: usize>(breakdown: &[(usize, &str, PassTimes<N>)], clocks: [&str; N], how: &str) {
    for mode in CoveredCells::DEFINITE.map(CoveredCells::name) {
        let rows: Vec<(usize, &PassTimes<N>)> = breakdown
            .iter()
            .filter(|(_, m, _)| *m == mode)
            .map(|(count, _, times)| (*count, times))
            .collect();
        print_pass_table(mode, &rows, clocks, how);
    }
}

fn print_pass_table<const N: usize>(
    mode: &str,
    breakdown: &[(usize, &PassTimes<N>)],
    clocks: [&str; N],
    how: &str,
) {
    let Some((_, first)) = breakdown.first() else {
        return;
    };
    let names: Vec<&str> = first.iter().map(|(name, _)| *name).collect();
    for (k, what) in clocks.iter().enumerate() {
        println!("coupled step by pass, covered cells {mode}, {what} ms per step (mean; {how}):");
        println!(
            "| particles | {} | total | total without fluid |",
            names.join(" | ")
        );
        println!("|---:|{}---:|---:|", "---:|".repeat(names.len()));
        for (count, times) in breakdown {
            let cells: Vec<String> = times.iter().map(|(_, t)| format!("{:.2}", t[k])).collect();
            let total: f64 = times.iter().map(|(_, t)| t[k]).sum();
            let fluid: f64 = times
                .iter()
                .filter(|(name, _)| *name == "fluid")
                .map(|(_, t)| t[k])
                .sum();
            println!(
                "| {count} | {} | {total:.2} | {:.2} |",
                cells.join(" | "),
                total - fluid
            );
        }
    }
}
