//! Steps timed in alternation with the LBM-only lockstep ([`paired`]): blocks of the steps under
//! test between blocks of as many LBM-only steps, each submitted and waited for as a coupled step
//! is, so that both see the same moments of a shared machine; by the wall clock and by this
//! process's CPU time (all threads: lavapipe's workers do the work, and the CPU time moves less
//! than the wall time when other jobs share the cores).

use crate::lbm::gpu::{Gpu, GpuLattice};
use std::time::{Duration, Instant};

/// The blocks of each kind that a paired timing alternates (fewer where there are fewer steps).
const BLOCKS: u64 = 4;

/// Steps by the two clocks.
#[derive(Clone, Copy)]
pub(super) struct Timed {
    pub mlups: f64,
    /// CPU milliseconds per step.
    pub cpu_ms: f64,
}

impl Timed {
    /// `steps` steps of `cells` cells that took `wall` and `cpu` seconds.
    fn of([wall, cpu]: [f64; 2], cells: usize, steps: u64) -> Timed {
        Timed {
            mlups: cells as f64 * steps as f64 / wall / 1e6,
            cpu_ms: cpu * 1e3 / steps as f64,
        }
    }
}

/// The steps under test and the LBM-only lockstep steps timed beside them.
#[derive(Clone, Copy)]
pub(super) struct Paired {
    pub steps: Timed,
    pub lbm_only: Timed,
}

impl Paired {
    /// The LBM-only lockstep's CPU time over the steps' (100% when they cost as much).
    pub fn ratio_by_cpu(&self) -> f64 {
        100.0 * self.lbm_only.cpu_ms / self.steps.cpu_ms
    }
}

/// `steps` calls of `step` (one step of `cells` cells each, the host idle `dem` after each) in
/// blocks, each after as many LBM-only lockstep steps of `lbm`.
pub(super) fn paired(
    gpu: &Gpu,
    lbm: &mut GpuLattice,
    cells: usize,
    steps: u64,
    dem: Duration,
    step: &mut dyn FnMut() -> Result<(), String>,
) -> Result<Paired, String> {
    let blocks = steps.clamp(1, BLOCKS);
    let mut sums = [[0.0; 2]; 2];
    for b in 0..blocks {
        let n = steps * (b + 1) / blocks - steps * b / blocks;
        let lockstep = timed_steps(gpu, n, dem, &mut || lockstep_step(gpu, lbm))?;
        let tested = timed_steps(gpu, n, dem, step)?;
        for (sum, t) in sums.iter_mut().zip([lockstep, tested]) {
            sum[0] += t[0];
            sum[1] += t[1];
        }
    }
    Ok(Paired {
        steps: Timed::of(sums[1], cells, steps),
        lbm_only: Timed::of(sums[0], cells, steps),
    })
}

/// `steps` LBM-only steps of `lbm`, each submitted and waited for on its own, the host idle `dem`
/// after each: the lockstep's own cost.
pub(super) fn lockstep(gpu: &Gpu, lbm: &mut GpuLattice, steps: u64, dem: Duration) -> Result<Timed, String> {
    let cells = lbm.setup.cells();
    let clocks = timed_steps(gpu, steps, dem, &mut || lockstep_step(gpu, lbm))?;
    Ok(Timed::of(clocks, cells, steps))
}

/// One LBM-only step of `lbm`, submitted and waited for on its own.
pub(super) fn lockstep_step(gpu: &Gpu, lbm: &mut GpuLattice) -> Result<(), String> {
    lbm.step(1);
    gpu.wait();
    Ok(())
}

/// Wall and CPU seconds of `n` calls of `step`, the host idle `dem` after each; the device idle
/// at the start and the end (the redo's last fluid kernels may run after its step returns).
fn timed_steps(
    gpu: &Gpu,
    n: u64,
    dem: Duration,
    step: &mut dyn FnMut() -> Result<(), String>,
) -> Result<[f64; 2], String> {
    gpu.wait();
    let (wall, cpu) = (Instant::now(), process_cpu_seconds());
    for _ in 0..n {
        step()?;
        std::thread::sleep(dem);
    }
    gpu.wait();
    Ok([wall.elapsed().as_secs_f64(), process_cpu_seconds() - cpu])
}

/// CPU seconds of this process, all threads (0 where the clock is not available).
pub(super) fn process_cpu_seconds() -> f64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes one timespec, which `t` is.
    let ok = unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut t) } == 0;
    if ok {
        t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9
    } else {
        0.0
    }
}
