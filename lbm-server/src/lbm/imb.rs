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
    /// Where the covered cells get their solid term.
    pub covered_cells: CoveredCells,
}

impl Default for ImbOptions {
    fn default() -> Self {
        Self {
            slots: 2,
            seed_weighting: false,
            covered_cells: CoveredCells::Auto,
        }
    }
}

/// Where the covered cells get their solid term (docs/imb.md, "Speed"). Both give the same
/// populations and loads (tested bit for bit); they differ in cost.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CoveredCells {
    /// Fused on a GPU, redo on a CPU driver.
    #[default]
    Auto,
    /// In the fluid kernels: every cell tests one bit of a cover mask, and a covered cell takes
    /// its solid term where it collides (no four-cell quads). Moves no population twice; costs a
    /// branch in the fluid kernels, which a GPU pays per warp that holds a covered cell and a CPU
    /// driver such as lavapipe (which runs both sides of a branch) for every cell.
    Fused,
    /// Saved before the fluid kernels and redone after them with the solid term: the fluid
    /// kernels stay branch-free, each covered cell's populations move three times.
    Redo,
}

impl CoveredCells {
    /// The scene's `coupling.covered_cells` ("auto", "fused", "redo").
    pub fn from_name(name: &str) -> Option<CoveredCells> {
        match name {
            "auto" => Some(CoveredCells::Auto),
            "fused" => Some(CoveredCells::Fused),
            "redo" => Some(CoveredCells::Redo),
            _ => None,
        }
    }

    /// Whether the solid term goes in the fluid kernels on this kind of device (`Auto` taken as
    /// sparse particles; see [`CoveredCells::for_scene`]).
    pub fn fused_on(self, device: wgpu::DeviceType) -> bool {
        match self {
            CoveredCells::Auto => device != wgpu::DeviceType::Cpu,
            CoveredCells::Fused => true,
            CoveredCells::Redo => false,
        }
    }

    /// `Auto` made definite for particles that cover `covered_fraction` of the cells: fused on a
    /// GPU; on a CPU driver redo for sparse particles and fused from [`FUSED_ON_CPU_FROM`] on.
    pub fn for_scene(self, device: wgpu::DeviceType, covered_fraction: f64) -> CoveredCells {
        let dense = covered_fraction >= FUSED_ON_CPU_FROM;
        match self {
            CoveredCells::Auto if self.fused_on(device) || dense => CoveredCells::Fused,
            CoveredCells::Auto => CoveredCells::Redo,
            mode => mode,
        }
    }
}

/// The covered fraction of the cells from which a CPU driver runs the coupled step faster with the
/// solid term fused: lavapipe, 64 x 64 x 128, TRT, spheres of 4 cells (BENCHMARKS.md): the redo
/// runs at 94 / 64 / 44 / 30 / 26% of LBM-only at 1 / 512 / 1728 / 2744 / 4096 spheres (0.01 /
/// 6 / 21 / 33 / 49% of the cells covered by [`covered_fraction`]), fused at 57 / 53 / 43 / 39 / 37%.
pub const FUSED_ON_CPU_FROM: f64 = 0.2;

/// The fraction of the cells that spheres of these radii (cells) cover: those whose centre lies
/// within r + 1/2 - 1/(12 r) of a sphere's centre (where the solid fraction is above 0), counted
/// per sphere (overlaps twice).
pub fn covered_fraction(radii: impl Iterator<Item = f64>, cells: usize) -> f64 {
    let covered: f64 = radii
        .map(|r| {
            let reach = r - 1.0 / (12.0 * r) + 0.5;
            4.0 / 3.0 * std::f64::consts::PI * reach.powi(3)
        })
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

/// The shader's `Particle`: what goes to the GPU each step.
#[repr(C)]
#[derive(Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuParticle {
    pos_r: [f32; 4],
    vel: [f32; 4],
    omega: [f32; 4],
    box_: [u32; 4],
}

/// The shader's `Load`: what comes back each step.
#[repr(C)]
#[derive(Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuLoad {
    force: [f32; 4],
    torque: [f32; 4],
}

const PARTICLE_BYTES: u64 = std::mem::size_of::<GpuParticle>() as u64;
const LOAD_BYTES: u64 = std::mem::size_of::<GpuLoad>() as u64;
/// The shader's pair: one vec4 per cell of a particle's bounding box.
const PAIR_BYTES: u64 = 16;
/// The shader's `Saved`: a covered cell and its 19 populations (over the `fields` buffer).
const SAVED_BYTES: u64 = 80;

/// Most particles a coupled step takes: imb.wgsl's `slot_key` holds 24-bit particle indices.
const MAX_PARTICLES: usize = 1 << 24;

/// The largest bounding box edge: imb.wgsl's `divide` takes box indices below 2^24 = 256^3.
const MAX_BOX_EDGE: u32 = 255;

/// Edge of the bounding box of a sphere of radius r, in cells (matches `cover` in imb.wgsl): from
/// the cell holding x - r to the one holding x + r, the cells whose centre lies within r + 1/2 of
/// x along each axis (beyond, the solid fraction is 0; docs/imb.md).
pub fn box_edge(radius: f64) -> u32 {
    (2.0 * radius).ceil() as u32 + 1
}

/// Receives the encoder after each pass of a coupled step (named) and returns the one to go on
/// with: the identity, or a submit and wait for timing each pass.
type Split<'a> = &'a mut dyn FnMut(&'static str, wgpu::CommandEncoder) -> wgpu::CommandEncoder;

/// The coupling's kernels: `cover` and `reduce`, and with the redo the passes around the fluid step.
struct Passes {
    cover: wgpu::ComputePipeline,
    reduce: wgpu::ComputePipeline,
    redo: Option<Redo>,
}

/// The passes of [`CoveredCells::Redo`]: `covered_groups`, then `save` and
/// `stream_collide_covered` for each KIND (bit 0 the parity, bit 1 the covered cells with a link
/// that leaves the fluid).
struct Redo {
    groups: wgpu::ComputePipeline,
    save: [wgpu::ComputePipeline; 4],
    covered: [wgpu::ComputePipeline; 4],
}

/// Buffers and pipelines of the coupling (tiny placeholders when the scene has no particles).
pub struct Coupling {
    particles: wgpu::Buffer,
    /// Force and torque per particle, apart from the states so that only they are read back.
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
    /// The solid term in the fluid kernels ([`CoveredCells::Fused`]).
    fused: bool,
    pipelines: Option<Passes>,
    /// Covered cells the `fields` buffer can hold (`Saved` records).
    saved_capacity: u32,
    /// Most covered cells the list may hold (below the device's limit only in tests).
    saved_cap: u64,
}

impl Coupling {
    pub fn new(d: &wgpu::Device, options: Option<ImbOptions>, cells: usize, fused: bool) -> Coupling {
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
            loads: storage_buffer(d, "loads", LOAD_BYTES),
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
            fused,
            pipelines: None,
            saved_capacity: 0,
            saved_cap: u64::MAX,
        }
    }

    /// Adds the cover and reduce pipelines when the coupling is on, and with the redo the save and
    /// covered-cell pipelines.
    pub fn with_pipelines(mut self, on: bool, make: &dyn Fn(&str, u32) -> wgpu::ComputePipeline) -> Coupling {
        if on {
            let redo = (!self.fused).then(|| Redo {
                groups: make("covered_groups", 0),
                save: [0, 1, 2, 3].map(|kind| make("save", kind)),
                covered: [0, 1, 2, 3].map(|kind| make("stream_collide_covered", kind)),
            });
            self.pipelines = Some(Passes {
                cover: make("cover", 0),
                reduce: make("reduce", 0),
                redo,
            });
        }
        self
    }

    /// Every kernel of the coupling (none when it is off).
    pub fn kernels(&self) -> Vec<&wgpu::ComputePipeline> {
        let Some(p) = &self.pipelines else {
            return Vec::new();
        };
        let mut all = vec![&p.cover, &p.reduce];
        if let Some(r) = &p.redo {
            all.push(&r.groups);
            all.extend(r.save.iter().chain(&r.covered));
        }
        all
    }

    /// Whether the covered cells take their solid term in the fluid kernels.
    pub fn fused(&self) -> bool {
        self.fused
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
        self.coupled_step(particles, &mut |_, encoder| encoder)
    }

    /// A coupled step with each pass submitted and waited for on its own: what `clock` advanced
    /// by over each pass (the submit round trip included), in the order of the step
    /// (`lbm-server bench --passes`).
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
        self.coupled_step(particles, &mut split)?;
        times.push(("readback", elapsed(&mut mark)));
        Ok(times)
    }

    /// The coupled step; `split` receives the encoder after each pass (named) and returns the one
    /// to go on with.
    fn coupled_step(&mut self, particles: &[SolidParticle], split: Split) -> Result<Vec<Load>, String> {
        self.refuse_unfit(particles)?;
        let (gpu_particles, pairs) = layout(&self.setup, particles);
        self.reserve(gpu_particles.len() as u64, pairs as u64)?;
        let coupling = self.imb.as_ref().expect("coupling");
        let passes = coupling
            .pipelines
            .as_ref()
            .ok_or("this lattice was made without particle coupling")?;
        let (cover, reduce) = (passes.cover.clone(), passes.reduce.clone());
        let redo = passes.redo.as_ref().map(|r| {
            // KIND = parity + 2 * (list of the cells with a link that leaves the fluid).
            let kind = |list: usize| (self.time % 2) as usize + 2 * list;
            (
                r.groups.clone(),
                [0, 1].map(|list| r.save[kind(list)].clone()),
                [0, 1].map(|list| r.covered[kind(list)].clone()),
            )
        });
        let parity = self.time % 2;
        let gpu = self.gpu.clone();
        gpu.queue
            .write_buffer(&coupling.particles, 0, bytemuck::cast_slice(&gpu_particles));
        gpu.queue.write_buffer(
            &coupling.info,
            0,
            bytemuck::cast_slice(&[particles.len() as u32, pairs, 0, coupling.saved_capacity]),
        );
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let n = particles.len() as u32;
        // The cover counts, slots and mask are all 0 here: `reduce` clears them. With the redo the
        // covered cells are listed by `cover` (status[4], status[8]) and dispatched indirectly
        // (status[5..8], status[9..12]).
        encoder.clear_buffer(&self.status, 16, Some(32));
        self.dispatch_groups(&mut encoder, &cover, parity, n);
        encoder = split("cover", encoder);
        match redo {
            // The fluid kernels give the covered cells their solid term (shaders/lbm.wgsl).
            None => {
                self.encode_step(&mut encoder);
                encoder = split("fluid", encoder);
            }
            // The fluid kernels update every cell without the solid term; the covered cells are
            // then redone from their saved populations (shaders/imb.wgsl).
            Some((groups, save, covered)) => {
                self.dispatch_groups(&mut encoder, &groups, parity, 1);
                let indirect = &self.imb.as_ref().expect("coupling").indirect;
                encoder.copy_buffer_to_buffer(&self.status, 20, indirect, 0, 28);
                encoder = split("covered_groups", encoder);
                for (offset, pipeline) in [0, 16].into_iter().zip(&save) {
                    self.dispatch_indirect(&mut encoder, pipeline, parity, offset);
                }
                encoder = split("save", encoder);
                self.encode_step(&mut encoder);
                encoder = split("fluid", encoder);
                for (offset, pipeline) in [0, 16].into_iter().zip(&covered) {
                    self.dispatch_indirect(&mut encoder, pipeline, parity, offset);
                }
                encoder = split("stream_collide_covered", encoder);
            }
        }
        self.dispatch_groups(&mut encoder, &reduce, parity, n.div_ceil(64));
        encoder = split("reduce", encoder);
        let coupling = self.imb.as_ref().expect("coupling");
        let bytes = n as u64 * LOAD_BYTES;
        if bytes > 0 {
            encoder.copy_buffer_to_buffer(&coupling.loads, 0, &coupling.readback, 0, bytes);
        }
        gpu.queue.submit([encoder.finish()]);
        if bytes == 0 {
            return Ok(Vec::new());
        }
        let slice = coupling.readback.slice(..bytes);
        slice.map_async(wgpu::MapMode::Read, |_| {});
        gpu.wait();
        let loads = {
            let data = slice
                .get_mapped_range()
                .map_err(|e| format!("particle readback: {e:?}"))?;
            let out: &[GpuLoad] = bytemuck::cast_slice(&data);
            out.iter()
                .map(|p| Load {
                    force: [p.force[0], p.force[1], p.force[2]].map(f64::from),
                    torque: [p.torque[0], p.torque[1], p.torque[2]].map(f64::from),
                })
                .collect()
        };
        coupling.readback.unmap();
        Ok(loads)
    }

    /// Refuses particles the coupling cannot take, naming the first: more than its indices hold,
    /// a radius beyond its box index, a box longer than a periodic axis.
    fn refuse_unfit(&self, particles: &[SolidParticle]) -> Result<(), String> {
        if particles.len() > MAX_PARTICLES {
            return Err(format!(
                "{} particles exceed the coupling's {MAX_PARTICLES} (imb.wgsl's slot keys hold 24-bit indices)",
                particles.len()
            ));
        }
        if let Some((j, p)) = particles
            .iter()
            .enumerate()
            .find(|(_, p)| box_edge(p.radius) > MAX_BOX_EDGE)
        {
            return Err(format!(
                "particle {j}: radius {} cells exceeds the coupling's {} cells",
                p.radius,
                (MAX_BOX_EDGE - 1) / 2
            ));
        }
        if let Some((j, axis)) = particles.iter().enumerate().find_map(|(j, p)| {
            (0..3)
                .find(|&a| self.setup.periodic(a) && box_edge(p.radius) as usize > self.setup.n[a])
                .map(|a| (j, a))
        }) {
            return Err(format!(
                "particle {j}: radius {} cells spans more than the periodic {} axis of {} cells \
                 (its box of {} cells would meet itself)",
                particles[j].radius,
                ["x", "y", "z"][axis],
                self.setup.n[axis],
                box_edge(particles[j].radius)
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
        pass.set_bind_group(0, &self.bind_groups[parity as usize], &[]);
        pass.dispatch_workgroups_indirect(&self.imb.as_ref().expect("coupling").indirect, offset);
    }

    /// Whether the covered cells take their solid term in the fluid kernels
    /// ([`CoveredCells::Fused`]) rather than being redone after them.
    pub fn covered_cells_fused(&self) -> bool {
        self.imb.as_ref().is_some_and(|c| c.fused())
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
        let coupling = self.imb.as_mut().expect("coupling");
        let mut grew = false;
        let fused = coupling.fused;
        if particles > coupling.particle_capacity {
            coupling.particle_capacity = particles.next_power_of_two();
            coupling.particles = storage_buffer(&d, "particles", coupling.particle_capacity * PARTICLE_BYTES);
            coupling.loads = storage_buffer(&d, "loads", coupling.particle_capacity * LOAD_BYTES);
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
pub(super) fn into_lattice(setup: &Setup, p: &SolidParticle) -> SolidParticle {
    let position = std::array::from_fn(|a| {
        let x = p.position[a];
        if setup.periodic(a) {
            x.rem_euclid(setup.n[a] as f64)
        } else {
            x
        }
    });
    SolidParticle { position, ..*p }
}

/// The GPU records of the particles (centres wrapped into the lattice, with their pair ranges) and
/// the total number of pairs.
fn layout(setup: &Setup, particles: &[SolidParticle]) -> (Vec<GpuParticle>, u32) {
    let mut first = 0u32;
    let records = particles
        .iter()
        .map(|p| {
            let p = into_lattice(setup, p);
            let m = box_edge(p.radius);
            let record = GpuParticle {
                pos_r: vec4(p.position, p.radius),
                vel: vec4(p.velocity, 0.0),
                omega: vec4(p.angular_velocity, 0.0),
                box_: [first, m, 0, 0],
            };
            first += m * m * m;
            record
        })
        .collect();
    (records, first)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Cells whose centre lies where the solid fraction of a sphere at `c` (radius r) is above 0.
    fn cells_covered(c: [f64; 3], r: f64) -> usize {
        let reach = r - 1.0 / (12.0 * r) + 0.5;
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
    fn auto_fuses_on_a_gpu_and_for_dense_beds_on_a_cpu() {
        use wgpu::DeviceType::{Cpu, DiscreteGpu};
        let auto = CoveredCells::Auto;
        assert_eq!(auto.for_scene(DiscreteGpu, 0.0), CoveredCells::Fused);
        assert_eq!(auto.for_scene(Cpu, 0.05), CoveredCells::Redo);
        assert_eq!(auto.for_scene(Cpu, 0.3), CoveredCells::Fused);
        assert_eq!(CoveredCells::Redo.for_scene(DiscreteGpu, 0.9), CoveredCells::Redo);
        assert_eq!(CoveredCells::Fused.for_scene(Cpu, 0.0), CoveredCells::Fused);
    }
}
