//! Host side of the immersed moving boundary (shaders/imb.wgsl): particle and pair buffers, the
//! bounding boxes, and the coupled step that returns each particle's force and torque.

use super::geometry::Setup;
use super::gpu::{storage_buffer, vec4, Lattice};

/// Settings of the coupling.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImbOptions {
    /// Particles one cell can hold (1-4); more are dropped and counted.
    pub slots: u32,
    /// B = eps (the seed's choice) instead of Noble & Torczynski's B(eps, tau).
    pub seed_weighting: bool,
    /// The solid collision term Omega.
    pub solid_collision: SolidCollision,
    /// Where the covered cells get their solid term.
    pub covered_cells: CoveredCells,
}

impl Default for ImbOptions {
    fn default() -> Self {
        Self {
            slots: 2,
            seed_weighting: false,
            solid_collision: SolidCollision::NobleTorczynski,
            covered_cells: CoveredCells::Auto,
        }
    }
}

/// The solid collision term Omega_i that a covered cell adds, weighted by B, to its fluid part
/// f_i - (1 - B) (f_i - post_i) (docs/imb.md, "The solid collision").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SolidCollision {
    /// Noble & Torczynski (1998), the seed's eq. 8: the non-equilibrium part bounced back,
    /// Omega_i = f_ibar - f_i + f_eq_i(rho, u_s) - f_eq_ibar(rho, u).
    #[default]
    NobleTorczynski,
    /// Superposition (Holdych 2003): the fluid's own collision without its body-force source,
    /// with the equilibrium moved to the solid's velocity, Omega_i = f_eq_i(rho, u_s) -
    /// f_eq_i(rho, u) + post_i - S_i - f_i; the covered cell becomes post_i - B S_i + B
    /// (f_eq_i(rho, u_s) - f_eq_i(rho, u)).
    Superposition,
}

impl SolidCollision {
    /// The scene's `coupling.solid_collision` ("noble-torczynski", "superposition").
    pub fn from_name(name: &str) -> Option<SolidCollision> {
        match name {
            "noble-torczynski" => Some(SolidCollision::NobleTorczynski),
            "superposition" => Some(SolidCollision::Superposition),
            _ => None,
        }
    }
}

/// Where the covered cells get their solid term (docs/imb.md, "Speed"). Both give the same
/// populations and loads (tested bit for bit); they differ in cost.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CoveredCells {
    /// Redo for sparse particles, fused from [`FUSED_FROM`] of the cells covered, on every device.
    #[default]
    Auto,
    /// In the fluid kernels: every cell tests one bit of a cover mask, and a covered cell takes
    /// its solid term where it collides (no four-cell quads). Moves no population twice; costs a
    /// branch in the fluid kernels, which a GPU pays per warp that holds a covered cell and a CPU
    /// driver such as lavapipe (which runs both sides of a branch) for every cell.
    Fused,
    /// Collided with the solid term before the fluid kernels (the loads then go back to the host
    /// while they run) and stored over their result: the fluid kernels stay branch-free, each
    /// covered cell's populations move three times.
    Redo,
    /// Collided with the solid term in place before the fluid kernels (the loads then go back to
    /// the host while they run), which skip them by one bit of a cover mask per cell (the
    /// four-cell quads by four bits, storing a covered cell's populations back as they were): each
    /// covered cell's populations move once, and the fluid kernels carry no solid term. Built for
    /// a GPU; not yet timed on one (a timed run tries it).
    Skip,
}

impl CoveredCells {
    /// The definite ways (what `bench --covered-cells all` and the reference tests run).
    pub const DEFINITE: [CoveredCells; 3] = [CoveredCells::Redo, CoveredCells::Fused, CoveredCells::Skip];

    /// The scene's `coupling.covered_cells` ("auto", "fused", "redo", "skip").
    pub fn from_name(name: &str) -> Option<CoveredCells> {
        match name {
            "auto" => Some(CoveredCells::Auto),
            "fused" => Some(CoveredCells::Fused),
            "redo" => Some(CoveredCells::Redo),
            "skip" => Some(CoveredCells::Skip),
            _ => None,
        }
    }

    /// Whether the solid term goes in the fluid kernels (`Auto` taken as sparse particles; see
    /// [`CoveredCells::for_scene`]).
    pub fn fused(self) -> bool {
        self == CoveredCells::Fused
    }

    /// The scene's name of a definite way (`Auto` as the redo it takes).
    pub fn name(self) -> &'static str {
        match self.definite() {
            CoveredCells::Fused => "fused",
            CoveredCells::Skip => "skip",
            _ => "redo",
        }
    }

    /// The way a lattice made with this choice takes (`Auto` as sparse particles: the redo).
    pub fn definite(self) -> CoveredCells {
        match self {
            CoveredCells::Auto => CoveredCells::Redo,
            mode => mode,
        }
    }

    /// Whether the fluid kernels give the covered cells their solid term (no four-cell quads).
    pub fn fuses(self) -> bool {
        self == CoveredCells::Fused
    }

    /// The name a run's first line and `bench` give it.
    pub fn describe(self) -> &'static str {
        match self.definite() {
            CoveredCells::Fused => "solid term in the fluid kernels",
            CoveredCells::Skip => "covered cells first, skipped by the fluid kernels",
            _ => "covered cells redone",
        }
    }

    /// `Auto` made definite for particles that cover `covered_fraction` of the cells: redo for
    /// sparse particles, fused from [`FUSED_FROM`] on.
    pub fn for_scene(self, covered_fraction: f64) -> CoveredCells {
        match self {
            CoveredCells::Auto if covered_fraction >= FUSED_FROM => CoveredCells::Fused,
            mode => mode.definite(),
        }
    }
}

/// The covered fraction of the cells from which the coupled step runs faster with the solid term
/// fused (BENCHMARKS.md): `auto`'s way on a CPU driver, and the way a timed run starts with
/// (trials.rs). Lavapipe, 64 x 64 x 128, TRT, spheres of 4 cells: the redo runs at 94 /
/// 64 / 44 / 30 / 26% of LBM-only at 1 / 512 / 1728 / 2744 / 4096 spheres (0.01 / 6 / 21 / 33 /
/// 49% of the cells covered by [`covered_fraction`]), fused at 57 / 53 / 43 / 39 / 37%. NVIDIA
/// H200, 256 x 256 x 512: the redo faster from 1 to 4096 spheres (up to 0.7% covered; 71-57%
/// against 62-54%), fused faster with half the cells covered (44% against 18%), before the redo
/// let the fluid kernels run during the host's part of the step; the crossover between is not
/// measured there.
pub const FUSED_FROM: f64 = 0.2;

/// How far from the centre of a sphere of radius `r` (cells) a cell's centre gets a solid
/// fraction: r + 1/2 - 1/(12 r). The fraction at distance d is clamp(reach - d, 0, 1)
/// (imb.wgsl `solid_fraction`, docs/imb.md "Solid fraction").
pub fn solid_reach(r: f64) -> f64 {
    r - 1.0 / (12.0 * r) + 0.5
}

/// The fraction of the cells that spheres of these radii (cells) cover: those whose centre lies
/// within [`solid_reach`] of a sphere's centre (where the solid fraction is above 0), counted per
/// sphere (overlaps twice).
pub fn covered_fraction(radii: impl Iterator<Item = f64>, cells: usize) -> f64 {
    let covered: f64 = radii
        .map(|r| 4.0 / 3.0 * std::f64::consts::PI * solid_reach(r).powi(3))
        .sum();
    covered / cells as f64
}

/// A particle in lattice units (cell i spans [i, i + 1] along each axis).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SolidParticle {
    pub position: [f64; 3],
    pub radius: f64,
    pub velocity: [f64; 3],
    pub angular_velocity: [f64; 3],
}

/// Covers lost since the start of a coupled run ([`Lattice::lost_covers`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LostCovers {
    /// Particle-cell covers beyond a cell's slots (dropped; the run warns).
    pub dropped: u32,
    /// Covered cells beyond the list of covered cells (the run stops).
    pub unlisted: u32,
}

/// Force and torque on a particle over one step, in lattice units.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Load {
    pub force: [f64; 3],
    pub torque: [f64; 3],
}

/// The particles of a coupled step in lattice units, by index: a slice of [`SolidParticle`]s, or
/// a DEM's states converted as the step reads them (no copy in between: the host's passes over
/// the particles are part of every coupled step, docs/imb.md "Speed").
pub trait Particles: Sync {
    fn count(&self) -> usize;
    fn particle(&self, j: usize) -> SolidParticle;
    /// Particle j's radius (the step sizes the pair ranges from the radii first).
    fn radius(&self, j: usize) -> f64 {
        self.particle(j).radius
    }
}

impl Particles for [SolidParticle] {
    fn count(&self) -> usize {
        self.len()
    }
    fn particle(&self, j: usize) -> SolidParticle {
        self[j]
    }
    fn radius(&self, j: usize) -> f64 {
        self[j].radius
    }
}

/// The shader's `Particle`: what goes to the GPU each step (48 bytes).
#[repr(C)]
#[derive(Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuParticle {
    pos_r: [f32; 4],
    vel: [f32; 3],
    first: u32,
    omega: [f32; 3],
    edge: u32,
}

/// The shader's loads: force and torque, what comes back each step (24 bytes).
type GpuLoad = [f32; 6];

const PARTICLE_BYTES: u64 = std::mem::size_of::<GpuParticle>() as u64;
const LOAD_BYTES: u64 = std::mem::size_of::<GpuLoad>() as u64;
/// imb.wgsl's SLICES: `reduce`'s invocations per particle, each with its partial load after the
/// particles' loads in the loads buffer.
const REDUCE_SLICES: u32 = 8;
/// Bytes of the loads buffer per particle: its load and its slices' partial loads.
const LOADS_BUFFER_BYTES: u64 = LOAD_BYTES * (1 + REDUCE_SLICES as u64);
/// The shader's pair: one vec4 per cell of a particle's bounding box.
const PAIR_BYTES: u64 = 16;
/// An entry of the shader's `saved`: a covered cell and its 19 populations (over the `fields` buffer).
const SAVED_BYTES: u64 = 80;

/// Most particles a coupled step takes: imb.wgsl's `slot_key` holds 24-bit particle indices.
const MAX_PARTICLES: usize = 1 << 24;

/// The largest bounding box edge: imb.wgsl's `divide` takes box indices below 2^24 = 256^3.
const MAX_BOX_EDGE: u32 = 255;

/// Edge of the bounding box of a sphere of radius r, in cells (matches `cover` in imb.wgsl): from
/// the cell holding x - r to the one holding x + r, the cells whose centre lies within r + 1/2 of
/// x along each axis (beyond, the solid fraction is 0; docs/imb.md).
pub fn box_edge(radius: f64) -> u32 {
    // ceil(2 r) without `f64::ceil`, a libm call on baseline x86-64 that made it a third of the
    // host's pass over the particles; saturating for radii beyond u32 (refused later).
    let diameter = 2.0 * radius;
    let whole = diameter as u32;
    let ceil = if (whole as f64) < diameter {
        whole.saturating_add(1)
    } else {
        whole
    };
    ceil.saturating_add(1)
}

/// Receives the encoder after each pass of a coupled step (named) and returns the one to go on
/// with: the identity, a submit and wait for timing each pass, or a timestamp.
type Split<'a> = &'a mut dyn FnMut(&'static str, wgpu::CommandEncoder) -> wgpu::CommandEncoder;

/// The device's timestamps between the passes of a coupled step ([`Lattice::pass_clock`]).
pub struct PassClock {
    set: wgpu::QuerySet,
    resolved: wgpu::Buffer,
}

/// Timestamps a coupled step can write (it writes at most 8).
const PASS_STAMPS: u32 = 16;

/// The coupling's kernels: `cover` and `reduce`, and with the redo the passes around the fluid step.
pub(super) struct Passes {
    cover: wgpu::ComputePipeline,
    reduce: wgpu::ComputePipeline,
    sum_loads: wgpu::ComputePipeline,
    redo: Option<Redo>,
}

/// The passes of [`CoveredCells::Redo`] and [`CoveredCells::Skip`]: `covered_groups`, then
/// `collide_covered` (before the fluid kernels) and after them `store_covered` (the redo) or
/// `uncover_listed` (skip), named, for each KIND (bit 0 the parity, bit 1 the covered cells with a
/// link that leaves the fluid).
struct Redo {
    groups: wgpu::ComputePipeline,
    collide: [wgpu::ComputePipeline; 4],
    after: (&'static str, [wgpu::ComputePipeline; 4]),
}

impl Passes {
    /// The cover and reduce pipelines of the way `mode`, and with the redo and skip the covered
    /// cells' collide and store (or uncover) pipelines; `make(entry, KIND)`.
    pub(super) fn new(mode: CoveredCells, make: &dyn Fn(&str, u32) -> wgpu::ComputePipeline) -> Passes {
        let after = if mode == CoveredCells::Skip {
            "uncover_listed"
        } else {
            "store_covered"
        };
        let redo = (mode != CoveredCells::Fused).then(|| Redo {
            groups: make("covered_groups", 0),
            collide: [0, 1, 2, 3].map(|kind| make("collide_covered", kind)),
            after: (after, [0, 1, 2, 3].map(|kind| make(after, kind))),
        });
        Passes {
            cover: make("cover", 0),
            reduce: make("reduce", 0),
            sum_loads: make("sum_loads", 0),
            redo,
        }
    }

    /// Every kernel of the passes.
    pub(super) fn kernels(&self) -> Vec<&wgpu::ComputePipeline> {
        let mut all = vec![&self.cover, &self.reduce, &self.sum_loads];
        if let Some(r) = &self.redo {
            all.push(&r.groups);
            all.extend(r.collide.iter().chain(&r.after.1));
        }
        all
    }
}

/// The pipelines of one coupled step.
struct StepPasses {
    cover: wgpu::ComputePipeline,
    reduce: wgpu::ComputePipeline,
    sum_loads: wgpu::ComputePipeline,
    /// The redo and skip: the passes over the list of covered cells.
    covered: Option<CoveredPasses>,
}

/// The passes over the covered cells of one step's parity, for the front and the back of the list.
struct CoveredPasses {
    groups: wgpu::ComputePipeline,
    collide: [wgpu::ComputePipeline; 2],
    /// "store_covered" (the redo) or "uncover_listed" (skip), and its pipelines.
    after: &'static str,
    after_pipelines: [wgpu::ComputePipeline; 2],
}

/// Buffers of the coupling (tiny placeholders when the scene has no particles).
pub struct Coupling {
    particles: wgpu::Buffer,
    /// Force and torque per particle, apart from the states so that only they are read back; after
    /// them `reduce`'s partial loads (REDUCE_SLICES per particle).
    loads: wgpu::Buffer,
    pairs: wgpu::Buffer,
    /// Per cell the count of its particles, then the cover mask (one bit per cell, 32 to a word).
    covered: wgpu::Buffer,
    slots: wgpu::Buffer,
    info: wgpu::Buffer,
    readback: wgpu::Buffer,
    /// The workgroups of the covered cells (copied from status[5..8]: a buffer bound as storage
    /// cannot be the indirect argument of the same dispatch).
    indirect: wgpu::Buffer,
    particle_capacity: u64,
    pair_capacity: u64,
    slots_per_cell: u32,
    /// Covered cells the `fields` buffer can hold (`Saved` records).
    saved_capacity: u32,
    /// Most covered cells the list may hold (below the device's limit only in tests).
    saved_cap: u64,
}

impl Coupling {
    pub fn new(d: &wgpu::Device, options: Option<ImbOptions>, cells: usize) -> Coupling {
        let per_cell = |bytes: u64| {
            if options.is_some() {
                bytes * cells as u64
            } else {
                256
            }
        };
        let slots = options.map_or(1, |o| o.slots as u64);
        Coupling {
            particles: storage_buffer(d, "particles", PARTICLE_BYTES),
            loads: storage_buffer(d, "loads", LOADS_BUFFER_BYTES),
            pairs: storage_buffer(d, "pairs", PAIR_BYTES),
            covered: storage_buffer(d, "covered", per_cell(4) + per_cell(4).div_ceil(128) * 4),
            slots: storage_buffer(d, "slots", per_cell(4 * slots)),
            info: storage_buffer(d, "imb info", 16),
            readback: readback_buffer(d, LOAD_BYTES),
            indirect: d.create_buffer(&wgpu::BufferDescriptor {
                label: Some("covered cells' workgroups"),
                size: 32,
                usage: wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            particle_capacity: 1,
            pair_capacity: 1,
            slots_per_cell: slots as u32,
            saved_capacity: 0,
            saved_cap: u64::MAX,
        }
    }

    /// The buffers in binding order.
    pub fn buffers(&self) -> [&wgpu::Buffer; 5] {
        [
            &self.particles,
            &self.pairs,
            &self.covered,
            &self.slots,
            &self.info,
        ]
    }

    /// The particles' force and torque (its own binding).
    pub fn loads(&self) -> &wgpu::Buffer {
        &self.loads
    }
}

fn readback_buffer(d: &wgpu::Device, bytes: u64) -> wgpu::Buffer {
    d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("particle readback"),
        size: bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

impl Lattice {
    /// One coupled step: the particles cover the cells, the fluid streams and collides with the
    /// solid term, and the force and torque on each particle over the step come back.
    pub fn step_coupled(&mut self, particles: &[SolidParticle]) -> Result<Vec<Load>, String> {
        let mut loads = Vec::new();
        self.step_coupled_with(particles, &mut loads, |_, load| load)?;
        Ok(loads)
    }

    /// A coupled step that reads the particles where they are and writes `load(j, load of j)` for
    /// each particle j to `out` (replaced): the caller's unit conversions ride on the step's own
    /// passes over the particles, which run in parallel chunks.
    pub fn step_coupled_with<P: Particles + ?Sized, T: Send>(
        &mut self,
        particles: &P,
        out: &mut Vec<T>,
        load: impl Fn(usize, Load) -> T + Sync,
    ) -> Result<(), String> {
        self.coupled_step(particles, &mut |_, encoder| encoder, &mut |loads| {
            convert_loads(loads, out, &load)
        })
    }

    /// A coupled step with each pass submitted and waited for on its own: what `clock` advanced
    /// by over each pass (the submit round trip included), in the order of the step
    /// (`lbm-server bench --passes`). "upload" is the host's pass that writes the particles for
    /// the GPU, "readback" the wait for the loads and the pass that converts them.
    pub fn step_coupled_timed<const N: usize>(
        &mut self,
        particles: &[SolidParticle],
        clock: &dyn Fn() -> [f64; N],
    ) -> Result<Vec<(&'static str, [f64; N])>, String> {
        let gpu = self.gpu.clone();
        let mut times = Vec::new();
        let mut mark = clock();
        let elapsed = |mark: &mut [f64; N]| {
            let now = clock();
            let spent = std::array::from_fn(|i| now[i] - mark[i]);
            *mark = now;
            spent
        };
        let mut split = |pass: &'static str, encoder: wgpu::CommandEncoder| {
            gpu.queue.submit([encoder.finish()]);
            gpu.wait();
            times.push((pass, elapsed(&mut mark)));
            gpu.device.create_command_encoder(&Default::default())
        };
        let mut loads = Vec::new();
        self.coupled_step(particles, &mut split, &mut |l| {
            convert_loads(l, &mut loads, &|_, l| l)
        })?;
        times.push(("readback", elapsed(&mut mark)));
        Ok(times)
    }

    /// Timestamps for [`Lattice::step_coupled_clocked`], where the device writes them inside
    /// command encoders (None elsewhere).
    pub fn pass_clock(&self) -> Option<PassClock> {
        let need = wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS;
        if !self.gpu.device.features().contains(need) {
            return None;
        }
        let d = &self.gpu.device;
        Some(PassClock {
            set: d.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass clock"),
                ty: wgpu::QueryType::Timestamp,
                count: PASS_STAMPS,
            }),
            resolved: d.create_buffer(&wgpu::BufferDescriptor {
                label: Some("pass clock"),
                size: PASS_STAMPS as u64 * 8,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
        })
    }

    /// A coupled step as a run makes it (not split into submissions), with a timestamp after
    /// each pass: the milliseconds of each pass by the device's clock, in the order of the step
    /// (the host's "upload" only marks the start; with the redo "fluid" includes the loads' copy).
    pub fn step_coupled_clocked(
        &mut self,
        particles: &[SolidParticle],
        clock: &PassClock,
    ) -> Result<Vec<(&'static str, f64)>, String> {
        let mut names = Vec::new();
        let mut stamp = |name: &'static str, mut encoder: wgpu::CommandEncoder| {
            encoder.write_timestamp(&clock.set, names.len() as u32);
            names.push(name);
            encoder
        };
        let mut loads = Vec::new();
        self.coupled_step(particles, &mut stamp, &mut |l| {
            convert_loads(l, &mut loads, &|_, l| l)
        })?;
        let count = names.len() as u32;
        let gpu = self.gpu.clone();
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        encoder.resolve_query_set(&clock.set, 0..count, &clock.resolved, 0);
        gpu.queue.submit([encoder.finish()]);
        let ticks: Vec<u64> =
            bytemuck::cast_slice(&gpu.read_range(&clock.resolved, 0, count as u64 * 8)).to_vec();
        let ms_per_tick = gpu.queue.get_timestamp_period() as f64 * 1e-6;
        Ok((1..names.len())
            .map(|k| (names[k], ticks[k].wrapping_sub(ticks[k - 1]) as f64 * ms_per_tick))
            .collect())
    }

    /// The host's own passes of a coupled step over `particles`, timed without the device:
    /// milliseconds (median of `repeats`) to size, check and write the records into staging
    /// memory, and to convert as many loads (`lbm-server bench --passes`: on a GPU machine they
    /// run on its CPU, in series with every step).
    pub fn host_pass_times(
        &mut self,
        particles: &[SolidParticle],
        repeats: usize,
    ) -> Result<[f64; 2], String> {
        let zeros = vec![GpuLoad::default(); particles.len()];
        let mut loads: Vec<Load> = Vec::new();
        let mut times = Vec::new();
        for _ in 0..repeats.max(1) {
            let start = std::time::Instant::now();
            self.stage_particles(particles)?;
            let upload = start.elapsed().as_secs_f64();
            let start = std::time::Instant::now();
            convert_loads(&zeros, &mut loads, &|_, l| l)?;
            times.push([upload, start.elapsed().as_secs_f64()]);
            // The staged records go to the device (the same as the next step's).
            self.gpu.queue.submit([]);
            self.gpu.wait();
        }
        Ok(std::array::from_fn(|k| {
            let mut column: Vec<f64> = times.iter().map(|t| t[k]).collect();
            column.sort_by(f64::total_cmp);
            column[column.len() / 2] * 1e3
        }))
    }

    /// The coupled step; `split` receives the encoder after each pass (named) and returns the one
    /// to go on with; `read` receives the loads.
    fn coupled_step<P: Particles + ?Sized>(
        &mut self,
        particles: &P,
        split: Split,
        read: &mut dyn FnMut(&[GpuLoad]) -> Result<(), String>,
    ) -> Result<(), String> {
        self.ramp_faces();
        let pairs = self.stage_particles(particles)?;
        let passes = self.step_passes()?;
        let n = particles.count() as u32;
        let gpu = self.gpu.clone();
        let coupling = self.imb.as_ref().expect("coupling");
        let info = [n, pairs as u32, 0, coupling.saved_capacity];
        gpu.queue
            .write_buffer(&coupling.info, 0, bytemuck::cast_slice(&info));
        let encoder = split("upload", gpu.device.create_command_encoder(&Default::default()));
        let mut encoder = self.encode_cover(encoder, &passes.cover, n, split);
        encoder = match &passes.covered {
            // The fluid kernels give the covered cells their solid term (shaders/lbm.wgsl).
            None => {
                self.encode_step(&mut encoder);
                split("fluid", encoder)
            }
            Some(covered) => self.encode_covered_collision(encoder, covered, split),
        };
        encoder = self.encode_reduce(encoder, &passes, n, split);
        let bytes = n as u64 * LOAD_BYTES;
        let coupling = self.imb.as_ref().expect("coupling");
        if bytes > 0 {
            encoder.copy_buffer_to_buffer(&coupling.loads, 0, &coupling.readback, 0, bytes);
        }
        let with_loads = gpu.queue.submit([encoder.finish()]);
        if let Some(covered) = &passes.covered {
            self.submit_fluid_after_loads(covered, split);
        }
        self.read_loads(bytes, with_loads, read)
    }

    /// The pipelines of this step's passes, those over the covered cells of this parity.
    fn step_passes(&self) -> Result<StepPasses, String> {
        let passes = self
            .way()
            .passes
            .as_ref()
            .ok_or("this lattice was made without particle coupling")?;
        // KIND = parity + 2 * (list of the cells with a link that leaves the fluid).
        let kind = |list: usize| (self.time % 2) as usize + 2 * list;
        Ok(StepPasses {
            cover: passes.cover.clone(),
            reduce: passes.reduce.clone(),
            sum_loads: passes.sum_loads.clone(),
            covered: passes.redo.as_ref().map(|r| CoveredPasses {
                groups: r.groups.clone(),
                collide: [0, 1].map(|list| r.collide[kind(list)].clone()),
                after: r.after.0,
                after_pipelines: [0, 1].map(|list| r.after.1[kind(list)].clone()),
            }),
        })
    }

    /// The solid fractions: `cover` over the `n` particles' boxes. The cover counts, slots and
    /// mask are all 0 here (`reduce` clears them); with the redo and skip the covered cells are
    /// listed by `cover` (status[4], status[8]) and dispatched indirectly (status[5..8],
    /// status[9..12]).
    fn encode_cover(
        &self,
        mut encoder: wgpu::CommandEncoder,
        cover: &wgpu::ComputePipeline,
        n: u32,
        split: Split,
    ) -> wgpu::CommandEncoder {
        encoder.clear_buffer(&self.status, 16, Some(32));
        self.dispatch_groups(&mut encoder, cover, self.time % 2, n);
        split("cover", encoder)
    }

    /// The redo and skip: the covered cells collide with the solid term first, from their
    /// pre-collision populations, and keep the result (shaders/imb.wgsl).
    fn encode_covered_collision(
        &self,
        mut encoder: wgpu::CommandEncoder,
        covered: &CoveredPasses,
        split: Split,
    ) -> wgpu::CommandEncoder {
        let parity = self.time % 2;
        self.dispatch_groups(&mut encoder, &covered.groups, parity, 1);
        let indirect = &self.imb.as_ref().expect("coupling").indirect;
        encoder.copy_buffer_to_buffer(&self.status, 20, indirect, 0, 28);
        encoder = split("covered_groups", encoder);
        for (offset, pipeline) in [0, 16].into_iter().zip(&covered.collide) {
            self.dispatch_indirect(&mut encoder, pipeline, parity, offset);
        }
        split("collide_covered", encoder)
    }

    /// Force and torque per particle (eq. 10-11): each particle's slices of its box summed, then
    /// the slices into the particle's load; the covers cleared for the next step.
    fn encode_reduce(
        &self,
        mut encoder: wgpu::CommandEncoder,
        passes: &StepPasses,
        n: u32,
        split: Split,
    ) -> wgpu::CommandEncoder {
        let parity = self.time % 2;
        self.dispatch_groups(
            &mut encoder,
            &passes.reduce,
            parity,
            (n * REDUCE_SLICES).div_ceil(64),
        );
        self.dispatch_groups(&mut encoder, &passes.sum_loads, parity, n.div_ceil(64));
        split("reduce", encoder)
    }

    /// With the redo and skip the fluid kernels, which update every cell as without particles
    /// (skip: all but the listed ones), and the store (or uncover) over the covered cells go in a
    /// submission of their own: it runs while the host reads the loads back and the DEM takes its
    /// step (docs/imb.md, "The redo").
    fn submit_fluid_after_loads(&mut self, covered: &CoveredPasses, split: Split) {
        let parity = self.time % 2;
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        self.encode_step(&mut encoder);
        encoder = split("fluid", encoder);
        for (offset, pipeline) in [0, 16].into_iter().zip(&covered.after_pipelines) {
            self.dispatch_indirect(&mut encoder, pipeline, parity, offset);
        }
        encoder = split(covered.after, encoder);
        self.gpu.queue.submit([encoder.finish()]);
    }

    /// The `bytes` of loads, once the submission `with_loads` is done, handed to `read`.
    fn read_loads(
        &self,
        bytes: u64,
        with_loads: wgpu::SubmissionIndex,
        read: &mut dyn FnMut(&[GpuLoad]) -> Result<(), String>,
    ) -> Result<(), String> {
        if bytes == 0 {
            return read(&[]);
        }
        let coupling = self.imb.as_ref().expect("coupling");
        let slice = coupling.readback.slice(..bytes);
        slice.map_async(wgpu::MapMode::Read, |_| {});
        self.gpu.wait_for(with_loads);
        let read_out = {
            let data = slice
                .get_mapped_range()
                .map_err(|e| format!("particle readback: {e:?}"))?;
            let loads: &[GpuLoad] =
                bytemuck::try_cast_slice(&data).map_err(|e| format!("particle readback: {e}"))?;
            read(loads)
        };
        coupling.readback.unmap();
        read_out
    }

    /// The host's part before the device's: the particles sized, checked and written into staging
    /// memory (the buffers grown to hold them); their pairs.
    fn stage_particles<P: Particles + ?Sized>(&mut self, particles: &P) -> Result<u64, String> {
        let chunks = chunk_sizes(particles);
        self.refuse_unfit(particles, &chunks)?;
        let pairs: u64 = chunks.iter().map(|c| c.pairs).sum();
        self.reserve(particles.count() as u64, pairs)?;
        self.upload_particles(particles, &chunks)?;
        Ok(pairs)
    }

    /// Writes the particles' GPU records (centres wrapped into the lattice, pair ranges from
    /// `chunks`) straight into the upload's staging memory, chunk by chunk in parallel.
    fn upload_particles<P: Particles + ?Sized>(
        &self,
        particles: &P,
        chunks: &[ChunkSize],
    ) -> Result<(), String> {
        let Some(bytes) = std::num::NonZeroU64::new(particles.count() as u64 * PARTICLE_BYTES) else {
            return Ok(());
        };
        let coupling = self.imb.as_ref().expect("coupling");
        let mut view = self
            .gpu
            .queue
            .write_buffer_with(&coupling.particles, 0, bytes)
            .ok_or("particle upload: no staging memory")?;
        // Records as bytes: the staging memory may only be written (wgpu's `WriteOnly`), and each
        // chunk's thread writes its own records.
        let (mut records, _) = view.slice(..).into_chunks::<{ PARTICLE_BYTES as usize }>();
        let staging = Staging(records.as_raw_element_ptr(), records.len());
        let periods = Periods::of(&self.setup);
        for_each_chunk(chunks.iter().collect(), |c, chunk: &ChunkSize| {
            let mut first = chunk.first;
            for j in c * CHUNK..(c * CHUNK + CHUNK).min(particles.count()) {
                let p = periods.wrap(&particles.particle(j));
                let edge = box_edge(p.radius);
                staging.write(
                    j,
                    GpuParticle {
                        pos_r: vec4(p.position, p.radius),
                        vel: p.velocity.map(|v| v as f32),
                        first,
                        omega: p.angular_velocity.map(|w| w as f32),
                        edge,
                    },
                );
                first += edge * edge * edge;
            }
        });
        Ok(())
    }

    /// Refuses particles the coupling cannot take, naming the first: more than its indices hold,
    /// a radius beyond its box index, a box longer than a periodic axis. `chunks` holds the
    /// largest box edge of each chunk: the particles are looked at one by one only when one is
    /// refused.
    fn refuse_unfit<P: Particles + ?Sized>(&self, particles: &P, chunks: &[ChunkSize]) -> Result<(), String> {
        let n = particles.count();
        if n > MAX_PARTICLES {
            return Err(format!(
                "{n} particles exceed the coupling's {MAX_PARTICLES} (imb.wgsl's slot keys hold 24-bit indices)"
            ));
        }
        let largest = chunks.iter().map(|c| c.largest_edge).max().unwrap_or(0);
        let shortest_periodic = (0..3)
            .filter(|&a| self.setup.periodic(a))
            .map(|a| self.setup.n[a])
            .min()
            .unwrap_or(usize::MAX);
        if largest <= MAX_BOX_EDGE && largest as usize <= shortest_periodic {
            return Ok(());
        }
        let radius = |j: usize| particles.radius(j);
        if let Some(j) = (0..n).find(|&j| box_edge(radius(j)) > MAX_BOX_EDGE) {
            return Err(format!(
                "particle {j}: radius {} cells exceeds the coupling's {} cells",
                radius(j),
                (MAX_BOX_EDGE - 1) / 2
            ));
        }
        if let Some((j, axis)) = (0..n).find_map(|j| {
            (0..3)
                .find(|&a| self.setup.periodic(a) && box_edge(radius(j)) as usize > self.setup.n[a])
                .map(|a| (j, a))
        }) {
            return Err(format!(
                "particle {j}: radius {} cells spans more than the periodic {} axis of {} cells \
                 (its box of {} cells would meet itself)",
                radius(j),
                ["x", "y", "z"][axis],
                self.setup.n[axis],
                box_edge(radius(j))
            ));
        }
        Ok(())
    }

    /// Dispatches as many workgroups as `covered_groups` wrote to status[5..8] (offset 0) or
    /// status[9..12] (offset 16).
    fn dispatch_indirect(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        pipeline: &wgpu::ComputePipeline,
        parity: u64,
        offset: u64,
    ) {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &self.way().bind_groups[parity as usize], &[]);
        pass.dispatch_workgroups_indirect(&self.imb.as_ref().expect("coupling").indirect, offset);
    }

    /// Where the covered cells take their solid term now (definite; the redo without coupling).
    pub fn covered_cells(&self) -> CoveredCells {
        self.way().mode
    }

    /// Particles one cell can hold.
    pub fn slots(&self) -> u32 {
        self.imb.as_ref().map_or(0, |c| c.slots_per_cell)
    }

    /// Since the start (one readback): the particle-cell covers that did not fit a cell's slots,
    /// and the covered cells that did not fit the list of covered cells (their solid term was
    /// missing); (0, 0) when none.
    pub fn lost_covers(&self) -> LostCovers {
        let status: Vec<u32> = bytemuck::cast_slice(&self.gpu.read_buffer(&self.status, 16)).to_vec();
        LostCovers {
            dropped: status[1],
            unlisted: status[2],
        }
    }

    /// Room in the list of covered cells.
    pub fn covered_cell_capacity(&self) -> u32 {
        self.imb.as_ref().map_or(0, |c| c.saved_capacity)
    }

    /// Test aid: the words of the cover counts, the cover mask and the slots that are not zero
    /// (`reduce` clears them all for the next step).
    #[cfg(test)]
    pub fn cover_words_left(&self) -> usize {
        let c = self.imb.as_ref().expect("coupling");
        [&c.covered, &c.slots]
            .iter()
            .map(|b| {
                let words: Vec<u32> = bytemuck::cast_slice(&self.gpu.read_buffer(b, b.size())).to_vec();
                words.iter().filter(|&&w| w != 0).count()
            })
            .sum()
    }

    /// Test aid: caps the list of covered cells at `cells`.
    #[cfg(test)]
    pub fn cap_covered_cells(&mut self, cells: u64) {
        if let Some(c) = self.imb.as_mut() {
            c.saved_cap = cells;
        }
    }

    /// Grows the particle and pair buffers to hold `particles` and `pairs`.
    fn reserve(&mut self, particles: u64, pairs: u64) -> Result<(), String> {
        let limit = self.gpu.limits.max_storage_buffer_binding_size;
        if pairs * PAIR_BYTES > limit {
            return Err(format!(
                "{pairs} particle-cell pairs exceed this device's binding limit of {limit} bytes"
            ));
        }
        let d = self.gpu.device.clone();
        let fused = self.covered_cells() == CoveredCells::Fused;
        let coupling = self.imb.as_mut().expect("coupling");
        let mut grew = false;
        if particles > coupling.particle_capacity {
            coupling.particle_capacity = particles.next_power_of_two();
            coupling.particles = storage_buffer(&d, "particles", coupling.particle_capacity * PARTICLE_BYTES);
            coupling.loads = storage_buffer(&d, "loads", coupling.particle_capacity * LOADS_BUFFER_BYTES);
            coupling.readback = readback_buffer(&d, coupling.particle_capacity * LOAD_BYTES);
            grew = true;
        }
        if pairs > coupling.pair_capacity {
            coupling.pair_capacity = pairs.next_power_of_two();
            coupling.pairs = storage_buffer(&d, "pairs", coupling.pair_capacity * PAIR_BYTES);
            grew = true;
        }
        // The redo's covered cells, at most min(cells, pairs), over the `fields` buffer (fused: none).
        let cells = self.setup.cells() as u64;
        let most = (limit.min(self.gpu.limits.max_buffer_size) / SAVED_BYTES)
            .min(cells)
            .min(coupling.saved_cap);
        let want = pairs.min(cells).next_power_of_two().min(most);
        if !fused && want > coupling.saved_capacity as u64 {
            let bytes = (want * SAVED_BYTES).max(cells * 16);
            self.fields = storage_buffer(&d, "fields", bytes);
            coupling.saved_capacity = (bytes / SAVED_BYTES).min(most) as u32;
            grew = true;
        }
        if grew {
            self.rebind();
        }
        Ok(())
    }
}

/// The particle with its centre wrapped into the lattice along the periodic axes (a DEM with a
/// periodic domain may send centres beyond it): its box then lies less than one period outside.
#[cfg(test)]
pub(super) fn into_lattice(setup: &Setup, p: &SolidParticle) -> SolidParticle {
    Periods::of(setup).wrap(p)
}

/// The lengths of the lattice's periodic axes, 0 along the others: what wraps the centres, looked
/// up once per step rather than per particle.
#[derive(Debug, Clone, Copy)]
struct Periods([f64; 3]);

impl Periods {
    fn of(setup: &Setup) -> Periods {
        Periods(std::array::from_fn(|a| {
            if setup.periodic(a) {
                setup.n[a] as f64
            } else {
                0.0
            }
        }))
    }

    /// `p` with its centre wrapped (`rem_euclid`, a libm `fmod`, only for a centre outside).
    fn wrap(&self, p: &SolidParticle) -> SolidParticle {
        let position = std::array::from_fn(|a| {
            let (x, period) = (p.position[a], self.0[a]);
            if period > 0.0 && !(0.0..period).contains(&x) {
                x.rem_euclid(period)
            } else {
                x
            }
        });
        SolidParticle { position, ..*p }
    }
}

/// Particles per chunk of the host's passes over a step's particles: the chunks run in parallel
/// (rayon); a step with fewer particles stays on the calling thread.
pub(super) const CHUNK: usize = 2048;

/// A chunk of [`CHUNK`] particles: the pair index of its first particle, its pairs (the cells of
/// its particles' bounding boxes) and its largest box edge.
#[derive(Debug, Clone, Copy, Default)]
struct ChunkSize {
    first: u32,
    pairs: u64,
    largest_edge: u32,
}

/// The chunks of a step's particles, sized from the radii (in parallel), with their first pairs.
fn chunk_sizes<P: Particles + ?Sized>(particles: &P) -> Vec<ChunkSize> {
    let n = particles.count();
    let mut chunks = vec![ChunkSize::default(); n.div_ceil(CHUNK)];
    for_each_chunk(chunks.iter_mut().collect(), |c, chunk: &mut ChunkSize| {
        for j in c * CHUNK..(c * CHUNK + CHUNK).min(n) {
            let edge = box_edge(particles.radius(j));
            chunk.pairs += (edge as u64).pow(3);
            chunk.largest_edge = chunk.largest_edge.max(edge);
        }
    });
    let mut first = 0u64;
    for chunk in &mut chunks {
        // Past u32 only when the pairs exceed any binding (`reserve` refuses them).
        chunk.first = first.min(u32::MAX as u64) as u32;
        first += chunk.pairs;
    }
    chunks
}

/// The particle records of an upload's staging memory (`len` of them), written record by record
/// from the threads of the chunks, never read.
struct Staging(std::ptr::NonNull<[u8; PARTICLE_BYTES as usize]>, usize);

// SAFETY: the threads write disjoint records (each its chunk's), while the view they point into
// outlives them (`upload_particles`).
unsafe impl Send for Staging {}
unsafe impl Sync for Staging {}

impl Staging {
    fn write(&self, j: usize, record: GpuParticle) {
        assert!(j < self.1, "particle record {j} beyond the upload's {}", self.1);
        // SAFETY: j is within the staging memory (asserted), which the caller's view keeps alive;
        // each record is written by one thread only; the pointee is bytes (alignment 1).
        unsafe { self.0.add(j).write(bytemuck::cast(record)) }
    }
}

/// `fill(c, chunk c)` for each chunk: in parallel when there is more than one, else on this
/// thread.
fn for_each_chunk<S: Send>(chunks: Vec<S>, fill: impl Fn(usize, S) + Sync) {
    use rayon::prelude::*;
    if chunks.len() <= 1 {
        chunks.into_iter().enumerate().for_each(|(c, s)| fill(c, s));
    } else {
        chunks.into_par_iter().enumerate().for_each(|(c, s)| fill(c, s));
    }
}

/// `out` (replaced) holds `load(j, load of j)` for every particle j of the GPU's loads.
fn convert_loads<T: Send>(
    loads: &[GpuLoad],
    out: &mut Vec<T>,
    load: &(impl Fn(usize, Load) -> T + Sync),
) -> Result<(), String> {
    out.clear();
    out.reserve(loads.len());
    let slots = out.spare_capacity_mut()[..loads.len()]
        .chunks_mut(CHUNK)
        .collect();
    for_each_chunk(slots, |c, chunk| {
        for (j, slot) in (c * CHUNK..).zip(chunk) {
            let l = loads[j].map(f64::from);
            slot.write(load(
                j,
                Load {
                    force: [l[0], l[1], l[2]],
                    torque: [l[3], l[4], l[5]],
                },
            ));
        }
    });
    // SAFETY: `for_each_chunk` wrote every one of the first loads.len() slots.
    unsafe { out.set_len(loads.len()) };
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Cells whose centre lies where the solid fraction of a sphere at `c` (radius r) is above 0.
    fn cells_covered(c: [f64; 3], r: f64) -> usize {
        let reach = solid_reach(r);
        let m = reach.ceil() as i64 + 1;
        let base = c.map(|x| x.floor() as i64);
        let mut count = 0;
        for dz in -m..=m {
            for dy in -m..=m {
                for dx in -m..=m {
                    let q = [base[0] + dx, base[1] + dy, base[2] + dz];
                    let d2: f64 = (0..3).map(|a| (q[a] as f64 + 0.5 - c[a]).powi(2)).sum();
                    count += usize::from(d2.sqrt() < reach);
                }
            }
        }
        count
    }

    #[test]
    fn covered_fraction_counts_the_cells_with_a_solid_fraction() {
        for (r, tolerance) in [(2.0, 0.08), (4.0, 0.03), (8.0, 0.01)] {
            let centres = [
                [10.0, 10.0, 10.0],
                [10.3, 10.7, 10.1],
                [10.5, 10.5, 10.5],
                [10.9, 10.2, 10.6],
            ];
            let counted: usize = centres.iter().map(|&c| cells_covered(c, r)).sum();
            let estimate = covered_fraction(std::iter::repeat_n(r, centres.len()), 1000) * 1000.0;
            let error = (estimate - counted as f64).abs() / counted as f64;
            assert!(
                error < tolerance,
                "r {r}: {estimate:.1} against {counted} cells counted"
            );
        }
    }

    #[test]
    fn auto_fuses_only_for_dense_beds() {
        let auto = CoveredCells::Auto;
        assert_eq!(auto.for_scene(0.0), CoveredCells::Redo);
        assert_eq!(auto.for_scene(0.05), CoveredCells::Redo);
        assert_eq!(auto.for_scene(0.3), CoveredCells::Fused);
        assert!(!auto.fused());
        assert_eq!(CoveredCells::Redo.for_scene(0.9), CoveredCells::Redo);
        assert_eq!(CoveredCells::Fused.for_scene(0.0), CoveredCells::Fused);
    }
}
