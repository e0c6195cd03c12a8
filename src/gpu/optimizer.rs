//! The fsot optimizer on Vulkan: the same slices, transport rule, scatter and step
//! as the CPU path (`cpu.rs`), as compute passes. Every buffer is allocated once
//! per run; many iterations are recorded into one command buffer, with no host
//! round trip between them.
//!
//! Per iteration: transport (one workgroup per slice: draw, gather, project,
//! bitonic sort in shared memory, exact targets, scatter) -> for classes larger
//! than shared memory holds, two passes of the global radix sort (by projection,
//! then stably by class) and a finishing transport pass -> update.

use ash::vk;

use super::buffer::{Buffer, Location};
use super::context::Context;
use super::layout::{Pod, TransportPush, UpdatePush};
use super::pipeline::{barrier, submit_and_wait, ComputePipeline};
use super::shaders;
use super::sort::{as_bytes, copy_range, from_bytes, RadixSort, ARG_GATHER, ARG_SEGMENTS};
use super::timer::Timer;
use crate::error::{Error, Result};
use crate::kernel::Kernel;
use crate::mask::Mask;
use crate::optimize::{run_mask, slices_and_hits, RunState, Settings};
use crate::optimizer::{schedule, StepRule};
use crate::problem::Tile;
use crate::rng::seed_key;
use crate::slice::{level_thresholds, slice_key};

/// Classes up to this many samples are sorted in shared memory
/// (`FSOT_LOCAL_MAX` in transport_body.glsl).
pub const LOCAL_MAX: u32 = 2048;
/// Classes up to this many samples are sorted by one invocation in the per-lane
/// transport (`FSOT_LANE_MAX` in transport_lane_body.glsl, a specialization
/// constant; its private arrays take 16 bytes per sample per invocation, which
/// lavapipe takes and an NVIDIA driver refuses: the per-lane transport is for CPU
/// implementations only).
pub const LANE_MAX: u32 = 2048;
/// Largest dimension the GPU path handles (its exact targets are the closed form
/// for d <= 2).
pub const GPU_MAX_DIMS: usize = 2;
/// Iterations recorded per submission.
pub const BATCH: u32 = 32;

/// How the GPU path accumulates displacements.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GpuOptions {
    /// Fixed-point int64 atomics: bit-identical run to run. Otherwise float
    /// atomic add where the device has it (faster on some devices, not
    /// reproducible bit for bit).
    pub deterministic: bool,
    /// Time each pass with timestamp queries.
    pub profile: bool,
    /// Which transport pass to use: None picks by device (per lane on CPU
    /// implementations, workgroups on GPUs); tests force each.
    pub transport: Option<TransportKind>,
}

/// The two transport passes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransportKind {
    /// One workgroup per slice, bitonic sort in shared memory (GPUs).
    Workgroup,
    /// One invocation per slice, bucket sort in private memory (CPU implementations).
    PerLane,
}

/// Time spent per pass, from timestamp queries (nanoseconds, summed).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Profile {
    pub transport_ns: f64,
    pub large_ns: f64,
    pub update_ns: f64,
    pub iterations: u32,
}

pub struct GpuRun {
    pub tile: Tile,
    pub settings: Settings,
    pub kernel: Kernel,
    pub options: GpuOptions,
    slices: u32,
    hits_per_value: f64,
    iteration: u32,
    float_acc: bool,
    workgroup: u32,
    shape: TransportShape,
    large_capacity: u32,
    seg_bits: u32,
    /// Bits of a point index (the first large-class sort's key).
    point_bits: u32,
    pub profile: Profile,
    overflowed: u64,
    // Pipelines before buffers: dropped first.
    transport: ComputePipeline,
    update: ComputePipeline,
    gather: Option<ComputePipeline>,
    transport_large: Option<ComputePipeline>,
    sort: Option<RadixSort>,
    timer: Option<Timer>,
    samples: Buffer,
    first: Buffer,
    second: Buffer,
    _acc: Buffer,
    _taps: Buffer,
    costs: Buffer,
    large_meta: Buffer,
    _large_points: Buffer,
    _large_proj: Buffer,
    _large_seg: Buffer,
    _large_pkey: Buffer,
    _placeholders: Option<[Buffer; 2]>,
    readback: Buffer,
    ctx: Context,
}

/// How the transport pass is launched on a device.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TransportShape {
    /// Invocations per workgroup.
    pub workgroup: u32,
    /// Slices per workgroup, one after another.
    pub slices_per_group: u32,
    /// The workgroup is one subgroup: subgroup barriers suffice.
    pub one_subgroup: bool,
    /// One invocation per slice (`transport_lane.comp`): for CPU implementations,
    /// which run invocations as SIMD lanes and pay dearly for barriers and
    /// shared-memory traffic between lanes.
    pub per_lane: bool,
}

impl TransportShape {
    /// GPUs: 128 invocations, one slice each. CPU implementations (lavapipe):
    /// one subgroup per workgroup (its barriers are nearly free there, while a
    /// workgroup barrier costs a coroutine switch per subgroup) and 16 slices per
    /// workgroup (launches are dear), fewer when the kernel's largest class would
    /// take an invocation past LOOP_BUDGET loop iterations (lavapipe silently
    /// drops iterations past 65535 per invocation). On CPU implementations, the
    /// per-lane transport when the kernel allows. `FSOT_TRANSPORT=WG,SPG` forces
    /// the workgroup transport with that shape.
    pub fn for_device(info: &super::context::DeviceInfo, max_class: u32) -> Self {
        let cpu = info.device_type == vk::PhysicalDeviceType::CPU;
        let mut shape = if cpu {
            let wg = info.subgroup_size.clamp(1, 128);
            // Per lane when one invocation can also write out the largest class
            // for the large-class path within the loop budget.
            let per_lane = max_class <= LOOP_BUDGET / 2;
            Self { workgroup: wg, slices_per_group: 16, one_subgroup: true, per_lane }
        } else {
            Self {
                workgroup: 128.min(info.max_workgroup_invocations),
                slices_per_group: 1,
                one_subgroup: false,
                per_lane: false,
            }
        };
        let worst = Self::slice_iterations(max_class.min(LOCAL_MAX), shape.workgroup);
        shape.slices_per_group = shape.slices_per_group.min((LOOP_BUDGET / worst).max(1));
        if let Ok(v) = std::env::var("FSOT_TRANSPORT") {
            let f: Vec<u32> = v.split(',').filter_map(|x| x.trim().parse().ok()).collect();
            if f.len() == 2 && f[0] > 0 && f[1] > 0 {
                shape.workgroup = f[0].min(info.max_workgroup_invocations);
                shape.slices_per_group = f[1];
                shape.per_lane = false;
                shape.one_subgroup = shape.workgroup <= info.subgroup_size;
            }
        }
        shape
    }
}

impl TransportShape {
    /// Upper bound on the loop iterations one invocation spends on a class of
    /// `n` samples (n <= LOCAL_MAX) in a workgroup of `wg`: gather, bitonic
    /// stages, targets, reduction.
    pub fn slice_iterations(n: u32, wg: u32) -> u32 {
        let p = n.max(2).next_power_of_two();
        let log = p.trailing_zeros();
        let per_stage = p.div_ceil(wg);
        let stages = log * (log + 1) / 2;
        stages * (per_stage + 1) + 3 * per_stage + 2 * log + 64
    }
}

/// Loop iterations one transport invocation may spend over its slices: under half
/// of lavapipe's cap of 65535 per invocation.
pub const LOOP_BUDGET: u32 = 30_000;

fn two_d(groups: u32) -> [u32; 3] {
    let x = groups.clamp(1, 65535);
    [x, groups.div_ceil(x).max(1), 1]
}

impl GpuRun {
    pub fn new(
        ctx: &Context,
        tile: Tile,
        settings: Settings,
        init: Option<&Mask>,
        options: GpuOptions,
    ) -> Result<Self> {
        let info = ctx.info().clone();
        if tile.dims > GPU_MAX_DIMS {
            return Err(Error::invalid(format!(
                "the Vulkan optimizer handles d <= {GPU_MAX_DIMS} (closed-form targets); d = {} runs on --backend cpu",
                tile.dims
            )));
        }
        if !info.int64_atomics {
            return Err(Error::VulkanUnavailable(format!("{} lacks 64-bit buffer atomics", info.name)));
        }
        if !info.subgroup_ballot {
            return Err(Error::VulkanUnavailable(format!("{} lacks subgroup ballot in compute", info.name)));
        }
        let kernel = Kernel::new(settings.kernel, &tile);
        let (slices, hits_per_value) = slices_and_hits(&tile, &kernel, &settings)?;
        let samples0 = match init {
            Some(m) if m.tile != tile => {
                return Err(Error::invalid(format!(
                    "--init mask is {} but the run asks for {}",
                    m.tile.describe(),
                    tile.describe()
                )))
            }
            Some(m) => m.samples.clone(),
            None => Mask::white(tile, settings.seed).samples,
        };
        let float_acc = !options.deterministic && info.float_atomic_add;
        let kernel_max_class = (Kernel::new(settings.kernel, &tile).taps.len() * tile.spp) as u32;
        let mut shape = TransportShape::for_device(&info, kernel_max_class);
        match options.transport {
            Some(TransportKind::PerLane) if kernel_max_class > LOOP_BUDGET / 2 => {
                return Err(Error::invalid("the per-lane transport cannot take classes this large"))
            }
            // Built for CPU implementations only: an H100's driver (580) refuses
            // its pipeline at 2048 samples per invocation (bench/results/h100-run.log).
            Some(TransportKind::PerLane) if info.device_type != vk::PhysicalDeviceType::CPU => {
                return Err(Error::invalid(format!(
                    "the per-lane transport is for CPU implementations of Vulkan, not {}",
                    info.name
                )))
            }
            Some(TransportKind::PerLane) => shape.per_lane = true,
            Some(TransportKind::Workgroup) => shape.per_lane = false,
            None => {}
        }
        let values = tile.values() as u64;
        let fits = |name: &str, bytes: u64| -> Result<u64> {
            if bytes > info.max_storage_buffer_range {
                Err(Error::invalid(format!(
                    "tile {} needs {bytes} bytes of {name}; {} binds at most {} (maxStorageBufferRange): use a smaller tile or --backend cpu",
                    tile.describe(),
                    info.name,
                    info.max_storage_buffer_range
                )))
            } else {
                Ok(bytes)
            }
        };
        let samples = Buffer::new(ctx, fits("samples", values * 4)?, Location::Device, "samples")?;
        let first = Buffer::new(ctx, values * 4, Location::Device, "state-first")?;
        let second_len = if matches!(settings.rule, StepRule::Adam { .. }) { values * 4 } else { 4 };
        let second = Buffer::new(ctx, second_len, Location::Device, "state-second")?;
        let acc = Buffer::new(
            ctx,
            fits("accumulators", values * if float_acc { 4 } else { 8 })?,
            Location::Device,
            "accumulators",
        )?;
        let thresholds = level_thresholds(&kernel);
        let table: Vec<u32> =
            kernel.taps.iter().zip(&thresholds).flat_map(|(t, &q)| [t.dx, t.dy, t.dt, q]).collect();
        let taps = Buffer::new(ctx, table.len() as u64 * 4, Location::Device, "kernel-taps")?;
        let costs = Buffer::new(ctx, BATCH as u64 * 16, Location::Device, "costs")?;

        // Large classes: only when the kernel can make a class bigger than shared
        // memory holds. Capacity: three times the expected elements per iteration
        // plus four largest classes; overflows are counted and reported.
        let workgroup = shape.workgroup;
        let tpush = std::mem::size_of::<TransportPush>() as u32;
        let transport_spv = match (shape.per_lane, float_acc) {
            (true, true) => shaders::TRANSPORT_LANE_FLOAT,
            (true, false) => shaders::TRANSPORT_LANE,
            (false, true) => shaders::TRANSPORT_FLOAT,
            (false, false) => shaders::TRANSPORT,
        };
        let (transport, local_max) = if shape.per_lane {
            let spec = [shape.workgroup, shape.slices_per_group, shape.one_subgroup as u32, LANE_MAX];
            (ComputePipeline::new(ctx, transport_spv, 11, tpush, &spec)?, LANE_MAX)
        } else {
            let spec = [shape.workgroup, shape.slices_per_group, shape.one_subgroup as u32];
            (ComputePipeline::new(ctx, transport_spv, 11, tpush, &spec)?, LOCAL_MAX)
        };
        let max_class = kernel.taps.len() as u64 * tile.spp as u64;
        let needs_large = max_class > local_max as u64;
        let large_capacity = if needs_large {
            let mut expected = 0.0;
            for (l, &q) in thresholds.iter().enumerate() {
                let next = thresholds.get(l + 1).copied().unwrap_or(0);
                let p = (q as f64 - next as f64) / 4_294_967_296.0; // P(len = l + 1)
                let n = (l as u64 + 1) * tile.spp as u64;
                if n > local_max as u64 {
                    expected += p * n as f64;
                }
            }
            let cap = (3.0 * expected * slices as f64) as u64 + 4 * max_class;
            cap.min(RadixSort::max_capacity(ctx) as u64) as u32
        } else {
            0
        };
        let seg_bits = 32 - large_capacity.leading_zeros();
        let point_bits = 32 - (tile.points() as u32).saturating_sub(1).leading_zeros();
        let meta_len = 16 + 16 * (large_capacity as u64 / (local_max as u64 + 1) + 1);
        let large_meta = Buffer::new(ctx, meta_len, Location::Device, "large-meta")?;
        let large_len = (large_capacity.max(1) as u64) * 4;
        let large_points = Buffer::new(ctx, large_len, Location::Device, "large-points")?;
        let large_proj = Buffer::new(ctx, large_len, Location::Device, "large-proj")?;
        let large_seg = Buffer::new(ctx, large_len, Location::Device, "large-seg")?;
        let large_pkey = Buffer::new(ctx, large_len, Location::Device, "large-projection-keys")?;
        let sort =
            if needs_large { Some(RadixSort::new(ctx, large_capacity, Some(&large_meta))?) } else { None };
        // Without large classes the bindings still need buffers (never written).
        let placeholders = match &sort {
            Some(_) => None,
            None => Some([
                Buffer::new(ctx, 16, Location::Device, "no-large-keys")?,
                Buffer::new(ctx, 16, Location::Device, "no-large-vals")?,
            ]),
        };
        let (keys_buf, vals_buf) = match (&sort, &placeholders) {
            (Some(s), _) => (&s.keys[0], &s.vals[0]),
            (None, Some([k, v])) => (k, v),
            (None, None) => unreachable!("placeholders exist when there is no sort"),
        };

        let transport_buffers = [
            &samples,
            &taps,
            &acc,
            &costs,
            &large_meta,
            keys_buf,
            vals_buf,
            &large_points,
            &large_proj,
            &large_seg,
            &large_pkey,
        ];
        transport.bind(&transport_buffers)?;
        let update_spv = if float_acc { shaders::UPDATE_FLOAT } else { shaders::UPDATE };
        let update =
            ComputePipeline::new(ctx, update_spv, 4, std::mem::size_of::<UpdatePush>() as u32, &[256])?;
        update.bind(&[&samples, &acc, &first, &second])?;
        let (gather, transport_large) = match &sort {
            Some(s) => {
                // Set 0 keys by segment, set 1 by projection.
                let g = ComputePipeline::with_sets(ctx, shaders::LARGE_GATHER, 4, 0, &[256], 2)?;
                g.bind_set(0, &[&large_meta, &s.keys[0], &s.vals[0], &large_seg])?;
                g.bind_set(1, &[&large_meta, &s.keys[0], &s.vals[0], &large_pkey])?;
                let spv = if float_acc { shaders::TRANSPORT_LARGE_FLOAT } else { shaders::TRANSPORT_LARGE };
                // 128 invocations whatever the device: a class may hold
                // taps x spp samples, and each invocation loops over n / WG.
                let t = ComputePipeline::new(ctx, spv, 6, tpush, &[128])?;
                t.bind(&[&acc, &costs, &large_meta, &s.vals[0], &large_points, &large_proj])?;
                (Some(g), Some(t))
            }
            None => (None, None),
        };
        let timer = if options.profile { Some(Timer::new(ctx, 4 * BATCH)?) } else { None };
        let readback =
            Buffer::new(ctx, (values * 8).max(BATCH as u64 * 16 + 16), Location::Readback, "readback")?;

        // Upload the samples and the kernel table; zero the state.
        let mut staging =
            Buffer::new(ctx, (values * 4).max(table.len() as u64 * 4), Location::Upload, "staging")?;
        staging.write(as_bytes(&samples0))?;
        submit_and_wait(ctx, |cmd| unsafe {
            copy_range(ctx, cmd, &staging, &samples, values * 4);
            for b in [&first, &second, &acc, &costs, &large_meta] {
                ctx.device().cmd_fill_buffer(cmd, b.raw, 0, vk::WHOLE_SIZE, 0);
            }
            barrier(ctx, cmd);
        })?;
        staging.write(as_bytes(&table))?;
        submit_and_wait(ctx, |cmd| {
            copy_range(ctx, cmd, &staging, &taps, table.len() as u64 * 4);
            barrier(ctx, cmd);
        })?;
        Ok(Self {
            tile,
            settings,
            kernel,
            options,
            slices,
            hits_per_value,
            iteration: 0,
            float_acc,
            workgroup,
            shape,
            large_capacity,
            seg_bits,
            point_bits: point_bits.max(1),
            profile: Profile::default(),
            overflowed: 0,
            transport,
            update,
            gather,
            transport_large,
            sort,
            timer,
            samples,
            first,
            second,
            _acc: acc,
            _taps: taps,
            costs,
            large_meta,
            _large_points: large_points,
            _large_proj: large_proj,
            _large_seg: large_seg,
            _large_pkey: large_pkey,
            _placeholders: placeholders,
            readback,
            ctx: ctx.clone(),
        })
    }

    pub fn slices_per_iteration(&self) -> u32 {
        self.slices
    }
    pub fn iteration(&self) -> u32 {
        self.iteration
    }
    pub fn finished(&self) -> bool {
        self.iteration >= self.settings.iterations
    }
    pub fn uses_float_atomics(&self) -> bool {
        self.float_acc
    }
    pub fn large_capacity(&self) -> u32 {
        self.large_capacity
    }
    /// Large classes dropped because their buffer was full (should stay 0).
    pub fn overflowed(&self) -> u64 {
        self.overflowed
    }
    /// Messages of the validation layer, when the context has it on.
    pub fn validation_messages(&self) -> Vec<String> {
        self.ctx.validation_messages()
    }
    pub fn device_name(&self) -> &str {
        &self.ctx.info().name
    }

    /// Records the transport pass of one iteration (and the reset of the
    /// large-class counters).
    fn record_transport(&self, cmd: vk::CommandBuffer, push: &TransportPush) {
        let ctx = &self.ctx;
        unsafe {
            ctx.device().cmd_fill_buffer(cmd, self.large_meta.raw, 0, 16, 0);
        }
        barrier(ctx, cmd);
        self.transport.dispatch(cmd, two_d(self.transport_groups()), push.bytes());
        barrier(ctx, cmd);
    }

    /// Records the large-class stage (two global sorts and the finishing pass),
    /// when the kernel can make classes too large for the transport pass.
    fn record_large(&self, cmd: vk::CommandBuffer, push: &TransportPush) {
        if let (Some(sort), Some(gather), Some(large)) = (&self.sort, &self.gather, &self.transport_large) {
            // The sort sizes its dispatches from the count the transport left on
            // the GPU (indirect), and writes the sizes of the two passes below.
            // Three stable sorts: by point, by projection, by class; so each
            // class ends in projection order with ties in point order (the CPU's).
            sort.record(cmd, self.point_bits, None);
            let Some(args) = &sort.args else { return };
            gather.dispatch_indirect_set(cmd, 1, &args.buffer, ARG_GATHER, &[]);
            barrier(&self.ctx, cmd);
            sort.record(cmd, 32, None);
            gather.dispatch_indirect_set(cmd, 0, &args.buffer, ARG_GATHER, &[]);
            barrier(&self.ctx, cmd);
            sort.record(cmd, self.seg_bits, None);
            large.dispatch_indirect_set(cmd, 0, &args.buffer, ARG_SEGMENTS, push.bytes());
            barrier(&self.ctx, cmd);
        }
    }

    /// Workgroups of the transport pass.
    fn transport_groups(&self) -> u32 {
        if self.shape.per_lane {
            self.slices.div_ceil(self.shape.workgroup)
        } else {
            self.slices.div_ceil(self.shape.slices_per_group)
        }
    }

    /// How the transport pass is launched here.
    pub fn transport_shape(&self) -> TransportShape {
        self.shape
    }

    fn transport_push(&self, iteration: u32, slot: u32) -> TransportPush {
        TransportPush {
            slice_key: slice_key(seed_key(self.settings.seed)),
            iteration,
            width: self.tile.width as u32,
            height: self.tile.height as u32,
            frames: self.tile.frames as u32,
            spp: self.tile.spp as u32,
            dims: self.tile.dims as u32,
            taps: self.kernel.taps.len() as u32,
            slices: self.slices,
            cost_slot: slot,
            large_capacity: self.large_capacity,
            pad: 0,
        }
    }

    fn update_push(&self, iteration: u32) -> UpdatePush {
        let t = iteration + 1;
        let scale = schedule(iteration, self.settings.iterations);
        let mut p = UpdatePush {
            values: self.tile.values() as u32,
            step_t: t,
            scale,
            inv_hits: (1.0 / self.hits_per_value) as f32,
            ..Default::default()
        };
        match self.settings.rule {
            StepRule::Momentum { step, beta } => {
                p.rule = 0;
                p.p0 = step;
                p.p1 = beta;
            }
            StepRule::Adam { lr, beta1, beta2, eps } => {
                p.rule = 1;
                p.p0 = lr;
                p.p1 = beta1;
                p.p2 = beta2;
                p.p3 = eps;
                p.bias1 = 1.0 - beta1.powi(t as i32);
                p.bias2 = 1.0 - beta2.powi(t as i32);
            }
        }
        p
    }

    /// Runs up to `max` iterations (at most BATCH) in one submission; returns each
    /// iteration's objective estimate.
    pub fn step_batch(&mut self, max: u32) -> Result<Vec<f64>> {
        let count = max.min(BATCH).min(self.settings.iterations - self.iteration);
        if count == 0 {
            return Ok(Vec::new());
        }
        let ctx = self.ctx.clone();
        let device = ctx.device();
        let values = self.tile.values() as u32;
        submit_and_wait(&ctx, |cmd| unsafe {
            device.cmd_fill_buffer(cmd, self.costs.raw, 0, vk::WHOLE_SIZE, 0);
            if let Some(t) = &self.timer {
                t.reset(cmd);
            }
            barrier(&ctx, cmd);
            for k in 0..count {
                let it = self.iteration + k;
                let push = self.transport_push(it, k);
                if let Some(t) = &self.timer {
                    t.stamp(cmd, 4 * k);
                }
                self.record_transport(cmd, &push);
                if let Some(t) = &self.timer {
                    t.stamp(cmd, 4 * k + 1);
                }
                self.record_large(cmd, &push);
                if let Some(t) = &self.timer {
                    t.stamp(cmd, 4 * k + 2);
                }
                self.update.dispatch(cmd, two_d(values.div_ceil(256)), self.update_push(it).bytes());
                barrier(&ctx, cmd);
                if let Some(t) = &self.timer {
                    t.stamp(cmd, 4 * k + 3);
                }
            }
            copy_range(&ctx, cmd, &self.costs, &self.readback, BATCH as u64 * 16);
            let region = [vk::BufferCopy::default().src_offset(0).dst_offset(BATCH as u64 * 16).size(16)];
            device.cmd_copy_buffer(cmd, self.large_meta.raw, self.readback.raw, &region);
            barrier(&ctx, cmd);
        })?;
        let raw: Vec<i64> = from_bytes(&self.readback.read()?[..BATCH as usize * 16]);
        let meta: Vec<u32> =
            from_bytes(&self.readback.read()?[BATCH as usize * 16..BATCH as usize * 16 + 16]);
        self.overflowed += meta[2] as u64;
        let costs = (0..count as usize)
            .map(|k| {
                let (sq, n) = (raw[2 * k] as f64 / 4_294_967_296.0, raw[2 * k + 1]);
                if n > 0 {
                    sq / n as f64
                } else {
                    0.0
                }
            })
            .collect();
        if let Some(t) = &self.timer {
            let ns = t.read_ns(4 * count)?;
            for k in 0..count as usize {
                self.profile.transport_ns += ns[4 * k + 1] - ns[4 * k];
                self.profile.large_ns += ns[4 * k + 2] - ns[4 * k + 1];
                self.profile.update_ns += ns[4 * k + 3] - ns[4 * k + 2];
            }
            self.profile.iterations += count;
        }
        self.iteration += count;
        Ok(costs)
    }

    /// Diagnostics and tests: runs only the transport passes of iteration
    /// `iteration` (no update) and returns the summed displacement of every
    /// coordinate; the accumulators are left at zero.
    pub fn displacements(&mut self, iteration: u32) -> Result<Vec<f64>> {
        let ctx = self.ctx.clone();
        let device = ctx.device();
        let values = self.tile.values() as u64;
        let width = if self.float_acc { 4 } else { 8 };
        let push = self.transport_push(iteration, 0);
        submit_and_wait(&ctx, |cmd| {
            unsafe { device.cmd_fill_buffer(cmd, self._acc.raw, 0, vk::WHOLE_SIZE, 0) };
            barrier(&ctx, cmd);
            self.record_transport(cmd, &push);
            self.record_large(cmd, &push);
            copy_range(&ctx, cmd, &self._acc, &self.readback, values * width);
            barrier(&ctx, cmd);
            unsafe { device.cmd_fill_buffer(cmd, self._acc.raw, 0, vk::WHOLE_SIZE, 0) };
            barrier(&ctx, cmd);
        })?;
        let bytes = &self.readback.read()?[..(values * width) as usize];
        Ok(if self.float_acc {
            from_bytes::<f32>(bytes).into_iter().map(|v| v as f64).collect()
        } else {
            from_bytes::<i64>(bytes).into_iter().map(|v| v as f64 / crate::cpu::FIXED_SCALE).collect()
        })
    }

    /// The current samples, read back.
    pub fn samples(&self) -> Result<Vec<f32>> {
        let bytes = self.tile.values() as u64 * 4;
        submit_and_wait(&self.ctx, |cmd| {
            copy_range(&self.ctx, cmd, &self.samples, &self.readback, bytes);
            barrier(&self.ctx, cmd);
        })?;
        Ok(from_bytes(&self.readback.read()?[..bytes as usize]))
    }

    /// Where the run stands (samples and optimizer state read back).
    pub fn state(&self) -> Result<RunState> {
        let values = self.tile.values() as u64;
        let adam = matches!(self.settings.rule, StepRule::Adam { .. });
        let read = |buffer: &Buffer| -> Result<Vec<f32>> {
            submit_and_wait(&self.ctx, |cmd| {
                copy_range(&self.ctx, cmd, buffer, &self.readback, values * 4);
                barrier(&self.ctx, cmd);
            })?;
            Ok(from_bytes(&self.readback.read()?[..(values * 4) as usize]))
        };
        let samples = read(&self.samples)?;
        let first = read(&self.first)?;
        let second = if adam { read(&self.second)? } else { Vec::new() };
        Ok(RunState { iteration: self.iteration, samples, first, second })
    }

    /// Continues from a saved state (uploaded to the device).
    pub fn restore(&mut self, saved: &RunState) -> Result<()> {
        saved.check(&self.tile, &self.settings)?;
        let bytes = self.tile.values() as u64 * 4;
        let mut staging = Buffer::new(&self.ctx, bytes, Location::Upload, "restore-staging")?;
        let parts: [(&[f32], &Buffer); 3] =
            [(&saved.samples, &self.samples), (&saved.first, &self.first), (&saved.second, &self.second)];
        for (values, target) in parts {
            if values.is_empty() {
                continue;
            }
            staging.write(as_bytes(values))?;
            submit_and_wait(&self.ctx, |cmd| {
                copy_range(&self.ctx, cmd, &staging, target, bytes);
                barrier(&self.ctx, cmd);
            })?;
        }
        self.iteration = saved.iteration;
        Ok(())
    }

    pub fn mask(&self) -> Result<Mask> {
        let mut mask = run_mask(&self.tile, &self.settings, self.iteration, self.slices, self.samples()?);
        mask.set_meta("backend", format!("vulkan ({})", self.ctx.info().name));
        if !self.float_acc {
            mask.set_meta("scatter", "fixed-point (deterministic)");
        }
        let _ = self.workgroup;
        Ok(mask)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_invocation_stays_under_the_loop_budget() {
        // The largest local class on one subgroup of 8 (lavapipe), and many
        // slices per workgroup only when classes are small.
        assert!(TransportShape::slice_iterations(LOCAL_MAX, 8) < LOOP_BUDGET);
        for max_class in [2u32, 100, 500, 1360, 2048, 100_000] {
            let worst = TransportShape::slice_iterations(max_class.min(LOCAL_MAX), 8);
            let spg = 16u32.min((LOOP_BUDGET / worst).max(1));
            assert!(spg * worst <= LOOP_BUDGET, "{max_class}: {spg} x {worst}");
        }
        // Per lane, one invocation sorts a whole class: clear, count, prefix and
        // place (one loop over n each), then either insertion moves (n + at most
        // 4n, FSOT_INSERTION_BUDGET) or the heap-sort fallback (3n/2 sift-downs
        // of at most log2 n steps each), then targets and scatter (n). At
        // LANE_MAX the fallback is the worst case, about 47k: under lavapipe's
        // 65535 for all loops of an invocation.
        let n = LANE_MAX;
        let log = n.ilog2();
        let insertion = n + 4 * n;
        let heap = 3 * n / 2 + (3 * n / 2) * log;
        let per_lane = 5 * n + insertion.max(heap);
        assert!(per_lane < 50_000, "{per_lane}");
        // A bitonic network of 2048 on 8 invocations: 66 stages of 256 pairs.
        assert!(TransportShape::slice_iterations(2048, 8) >= 66 * 256);
    }
}
