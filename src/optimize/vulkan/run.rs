//! The fsot optimizer on Vulkan: the same slices, transport rule, scatter and step
//! as the CPU backend, as compute passes. Every buffer is allocated once per run
//! (`buffers.rs`); many iterations are recorded into one submission, with no host
//! round trip between them.
//!
//! Per iteration: transport (one workgroup per slice: draw, gather, project,
//! bucket sort in shared memory, exact targets, scatter) -> on GPUs, a second
//! transport pass over the slices whose classes passed the first's limit but fit
//! a larger workgroup's shared memory -> for classes larger still, three passes
//! of the global radix sort (by point, by projection, then stably by class) and a
//! finishing transport pass -> update.

use ash::vk;

use super::buffers::{LargePlan, RunBuffers};
use super::layout::{
    lane_dispatch_offset, lane_plan_word, lane_table_cost_word, lane_tier_word, slice_order_slots,
    slice_order_words, CostSlot, LargeMetaHead, PlateauPush, RuleState, TransportPush, UpdatePush,
    ARG_GATHER, ARG_SEGMENTS, COST_SCALE, LANE_TABLE_WORDS, LANE_TIERS, ORDER_BATCH, ORDER_FIXED_WORDS,
    ORDER_HEAD_WORDS, ORDER_SLICES_PER_INVOCATION,
};
use super::pipelines::{RunPipelines, Targets, GATHER_BY_PROJECTION, GATHER_BY_SEGMENT};
use super::shape::{
    two_d, TransportKind, TransportShape, DEFER_GROUPS, DEFER_LIMIT, DEFER_WORKGROUP, LANE_CHUNKS_PER_THREAD,
    LANE_MAX, LOCAL_MAX, LOOP_BUDGET,
};
use super::{VulkanOptions, BATCH, CLOSED_FORM_DIMS};
use crate::core::kernel::Kernel;
use crate::core::mask::Mask;
use crate::core::rng::seed_key;
use crate::core::slice::{level_thresholds, share_bits, slice_key};
use crate::core::step_rule::{schedule, Plateau, PlateauState, StepRule};
use crate::core::tile::Tile;
use crate::error::{Error, Result};
use crate::optimize::backend::{Backend, BackendKind, Profile, Report};
use crate::optimize::cpu::FIXED_SCALE;
use crate::optimize::settings::{initial_samples, run_mask, slices_and_hits, RunState, Settings};
use crate::vk::buffer::{download_batch, upload_batch};
use crate::vk::commands::{barrier, copy, zero};
use crate::vk::Recording;
use crate::vk::{choose_sort_path, Buffer, Context, PathChoice, RadixSort, SortPath, Timer};

/// One iteration's slice order as the per-lane transport takes it
/// (`VulkanRun::slice_order`; `glsl/fsot/slice_order.glsl`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LaneOrder {
    /// Slice indices by rank: the largest classes first.
    pub ranks: Vec<u32>,
    /// The transport's dispatch (x, y, z): a workgroup for each chunk at least.
    pub dispatch: [u32; 3],
    /// Chunks of the plan: workgroups that take slices.
    pub chunks: u32,
    /// The plan's tiers that hold slices, in rank order.
    pub tiers: Vec<LaneTier>,
}

/// A tier of a per-lane chunk plan: `slices` ranks from `first_rank`, in
/// chunks of lanes x `rounds` from chunk `first_chunk`, each slice budgeted
/// at `cost` loop iterations (the lane table's).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LaneTier {
    pub first_chunk: u32,
    pub first_rank: u32,
    pub slices: u32,
    pub rounds: u32,
    pub cost: u32,
}

pub struct VulkanRun {
    pub tile: Tile,
    pub settings: Settings,
    pub kernel: Kernel,
    pub options: VulkanOptions,
    slices: u32,
    hits_per_value: f64,
    iteration: u32,
    float_acc: bool,
    shape: TransportShape,
    large: LargePlan,
    /// Iterations whose slice orders the per-lane transport's buffer holds (0:
    /// the other transport, which takes slices in index order).
    order_slots: u32,
    profile: Profile,
    overflowed: u64,
    /// A step scale set by the caller; None: the cosine schedule.
    scale: Option<f32>,
    /// The stopping rule the device evaluates (`adopt_plateau`), as of the
    /// last batch read back.
    rule: Option<RuleState>,
    // Pipelines and the sort before the buffers they are bound to: dropped first.
    pipelines: RunPipelines,
    sort: Option<RadixSort>,
    /// How the large-class sort's path was chosen (None without that stage).
    sort_choice: Option<PathChoice>,
    timer: Option<Timer>,
    buffers: RunBuffers,
    ctx: Context,
}

impl VulkanRun {
    /// A run on `ctx`, from `init` or from white noise drawn from the seed.
    pub fn new(
        ctx: &Context,
        tile: Tile,
        settings: Settings,
        init: Option<&Mask>,
        options: VulkanOptions,
    ) -> Result<Self> {
        let info = ctx.info().clone();
        let targets = match (tile.dims > CLOSED_FORM_DIMS, info.float64 && !options.hooks.float_pair_targets)
        {
            (false, _) => Targets::ClosedForm,
            (true, true) => Targets::F64,
            (true, false) => Targets::FloatPairs,
        };
        if let Some(r) = crate::vk::missing(&info) {
            return Err(Error::VulkanUnavailable(format!("{} lacks {} ({})", info.name, r.name, r.used_for)));
        }
        let kernel = Kernel::new(settings.kernel, &tile);
        let (slices, hits_per_value) = slices_and_hits(&tile, &kernel, &settings)?;
        let samples = initial_samples(&tile, &settings, init)?;
        let float_acc = !options.deterministic && info.float_atomic_add;
        let max_class = (kernel.taps.len() * tile.spp) as u32;
        // The per-lane transport's texel views: the samples, and the taps.
        let texels = (tile.values() as u64).max(kernel.taps.len() as u64);
        let mut shape = transport_shape(ctx, max_class, tile.dims, texels, &options)?;
        // The driver's threads, for a CPU implementation: as many as the host's.
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get() as u32);
        shape.set_lane_chunks(LANE_CHUNKS_PER_THREAD * threads);
        // Classes past both passes' limits go to the large-class stage.
        let local_max = shape.local_max.max(shape.defer_max);
        let thresholds = level_thresholds(&kernel);
        let mut large = LargePlan::new(ctx, &tile, &thresholds, kernel.taps.len(), slices, local_max);
        if let Some(capacity) = options.hooks.large_capacity {
            large = large.at_most(capacity);
        }
        let adam = matches!(settings.rule, StepRule::Adam { .. });
        // The per-lane transport's slice orders: a batch's worth at a time where
        // one binding holds them, fewer otherwise (at least one).
        let order_slots = match shape.per_lane {
            true => options
                .hooks
                .slice_order_slots
                .map(|s| s.clamp(1, ORDER_BATCH))
                .unwrap_or_else(|| slice_order_slots(slices, info.max_storage_buffer_range)),
            false => 0,
        };
        let order_words = if order_slots > 0 { slice_order_words(slices, order_slots) } else { 0 };
        let lane_table = match order_slots {
            0 => Vec::new(),
            _ => shape.lane_table(kernel.taps.len() as u32, tile.spp as u32, tile.dims),
        };
        let buffers = RunBuffers::new(
            ctx,
            &tile,
            &kernel,
            &thresholds,
            &samples,
            adam,
            float_acc,
            &large,
            local_max,
            order_words,
            &lane_table,
            shape.deferred_capacity(slices),
        )?;
        // SAFETY: the run holds the sort before its buffers (dropped first).
        let mut sort = unsafe { buffers.large_sort(ctx, &large)? };
        let sort_choice = match sort.as_mut() {
            Some(sort) => {
                let choice = large_sort_path(ctx, &large, options.hooks.large_sort)?;
                sort.path = choice.path;
                Some(choice)
            }
            None => None,
        };
        let pipelines = RunPipelines::new(ctx, &shape, targets, float_acc, &buffers, sort.as_ref())?;
        let timer = if options.profile { Some(Timer::new(ctx, 4 * BATCH)?) } else { None };
        Ok(Self {
            tile,
            settings,
            kernel,
            options,
            slices,
            hits_per_value,
            iteration: 0,
            float_acc,
            shape,
            large,
            order_slots,
            profile: Profile::default(),
            overflowed: 0,
            scale: None,
            rule: None,
            pipelines,
            sort,
            sort_choice,
            timer,
            buffers,
            ctx: ctx.clone(),
        })
    }

    /// How the transport pass is launched.
    pub fn shape(&self) -> &TransportShape {
        &self.shape
    }

    /// The large-class stage's sort path and how it was chosen; None without
    /// that stage.
    pub fn sort_choice(&self) -> Option<PathChoice> {
        self.sort_choice
    }

    pub fn finished(&self) -> bool {
        self.iteration >= self.settings.iterations
    }
    pub fn uses_float_atomics(&self) -> bool {
        self.float_acc
    }
    pub fn large_capacity(&self) -> u32 {
        self.large.capacity
    }
    /// Large classes dropped because their buffer was full (should stay 0).
    pub fn overflowed(&self) -> u64 {
        self.overflowed
    }
    /// Where the run's time went (with `VulkanOptions::profile`).
    pub fn profile(&self) -> &Profile {
        &self.profile
    }

    /// The least bytes each pass must move per iteration, a model (transport,
    /// large-class stage, update): the transport reads every coordinate each
    /// class member projects and adds its displacement into an accumulator (4
    /// bytes read, one 8-byte fixed-point or 4-byte float atomic add, per hit);
    /// the large-class stage's three sorts read and write each expected element's
    /// key and payload once per pass, and its two gathers once each; the update
    /// reads and clears each accumulator and reads and writes each coordinate and
    /// its optimizer state.
    pub fn pass_bytes(&self) -> (f64, f64, f64) {
        let values = self.tile.values() as f64;
        let acc = if self.float_acc { 4.0 } else { 8.0 };
        let transport = self.hits_per_value * values * (4.0 + acc);
        let passes = (self.large.point_bits.div_ceil(8) + 4 + self.large.seg_bits.div_ceil(8)) as f64;
        let large = self.large.expected * 16.0 * (passes + 2.0);
        let state = if matches!(self.settings.rule, StepRule::Adam { .. }) { 16.0 } else { 8.0 };
        let update = values * (2.0 * acc + 8.0 + state);
        (transport, large, update)
    }

    /// Records the transport pass of one iteration (and the reset of the
    /// large-class counters), with the barriers around it.
    fn record_transport(&self, cmd: Recording<'_>, push: &TransportPush) {
        self.record_reset_large(cmd);
        barrier(cmd);
        self.record_transport_pass(cmd, push);
        barrier(cmd);
    }

    /// Records the slice orders of iterations `first..first + count` (count at
    /// most `order_slots`) into slots 0.. for the per-lane transport, barriers
    /// included; nothing for the other transport.
    fn record_slice_order(&self, cmd: Recording<'_>, first: u32, count: u32) {
        let Some([count_pass, place_pass]) = &self.pipelines.order else { return };
        let push = self.transport_push(first, 0);
        let table = LANE_TABLE_WORDS as u64 * 4;
        zero(cmd, &self.buffers.slice_order, table, ORDER_HEAD_WORDS as u64 * 4);
        barrier(cmd);
        let groups = self.slices.div_ceil(64 * ORDER_SLICES_PER_INVOCATION).clamp(1, 65535);
        count_pass.dispatch(cmd, 0, [groups, count, 1], bytemuck::bytes_of(&push));
        barrier(cmd);
        place_pass.dispatch(cmd, 0, [1, count, 1], bytemuck::bytes_of(&push));
        barrier(cmd);
    }

    /// The order the per-lane transport takes iteration `iteration`'s slices in,
    /// and its chunk plan, computed on the device as a batch would; None for
    /// the other transport, which takes them in index order.
    pub fn slice_order(&self, iteration: u32) -> Result<Option<LaneOrder>> {
        if self.pipelines.order.is_none() {
            return Ok(None);
        }
        self.ctx.submit(|cmd| self.record_slice_order(cmd, iteration, 1))?;
        // Slot 0: its ranks follow the lane table, every slot's bins and
        // plan, and its own slices' classes.
        let first = (ORDER_FIXED_WORDS + self.slices) as usize;
        let bytes = ((first + self.slices as usize) * 4) as u64;
        let parts = download_batch(&self.ctx, &[(&self.buffers.slice_order, bytes)], None)?;
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&parts[0]);
        let plan = lane_plan_word(0) as usize;
        let tier = |t: u32| {
            let at = lane_tier_word(0, t) as usize;
            LaneTier {
                first_chunk: words[at],
                first_rank: words[at + 1],
                slices: words[at + 2],
                rounds: words[at + 3],
                cost: words[lane_table_cost_word(t) as usize],
            }
        };
        Ok(Some(LaneOrder {
            ranks: words[first..].to_vec(),
            dispatch: [words[plan + 1], words[plan + 2], words[plan + 3]],
            chunks: words[plan + 4],
            tiers: (0..LANE_TIERS).map(tier).filter(|t| t.slices > 0).collect(),
        }))
    }

    /// Zeroes the large-class counters of one iteration, the elements and
    /// classes (a barrier must follow); the batch's counts stay.
    fn record_reset_large(&self, cmd: Recording<'_>) {
        zero(cmd, &self.buffers.large_meta, 0, 8);
        if self.pipelines.deferred.is_some() {
            // The dispatch's x and the count of slices listed (Deferred).
            zero(cmd, &self.buffers.deferred, 0, 4);
            zero(cmd, &self.buffers.deferred, 12, 4);
        }
    }

    /// The transport dispatch alone (barriers are the caller's).
    /// Per lane, as many workgroups as the slot's chunk plan holds chunks (the
    /// ordering's second pass wrote the dispatch).
    fn record_transport_pass(&self, cmd: Recording<'_>, push: &TransportPush) {
        let pass = &self.pipelines.transport;
        if self.shape.per_lane {
            let offset = lane_dispatch_offset(push.order_slot);
            pass.dispatch_indirect(cmd, 0, &self.buffers.slice_order, offset, bytemuck::bytes_of(push));
        } else {
            pass.dispatch(cmd, 0, two_d(self.shape.groups(self.slices)), bytemuck::bytes_of(push));
        }
    }

    /// The update pass reads through texel views (CPU implementations) and leaves
    /// the accumulators' reset to the fill the batch records after it.
    fn update_leaves_reset(&self) -> bool {
        self.pipelines.texels.is_some()
    }

    /// The update dispatch of iteration `iteration` alone (barriers are the
    /// caller's; so is the accumulators' reset where `update_leaves_reset`).
    fn record_update_pass(&self, cmd: Recording<'_>, iteration: u32) {
        let update = self.update_push(iteration);
        let groups = two_d((self.tile.values() as u32).div_ceil(256));
        self.pipelines.update.dispatch(cmd, 0, groups, bytemuck::bytes_of(&update));
    }

    /// Records what follows the transport pass for the classes too large for it:
    /// its second pass over the slices it listed, where the shape has one; then
    /// the large-class stage, when the kernel can make classes larger still: the
    /// dispatch sizes from the counts the transport left on the GPU, then three
    /// stable sorts (by point, by projection, by class; so each class ends in
    /// projection order with ties in point order, the CPU's), the gathers between
    /// them, and the finishing pass.
    fn record_large(&self, cmd: Recording<'_>, push: &TransportPush) {
        // The workgroup transport's second pass, over the slices it listed
        // (as many workgroups as listed: the indirect dispatch's count).
        if let Some(deferred) = &self.pipelines.deferred {
            deferred.dispatch_indirect(cmd, 0, &self.buffers.deferred, 0, bytemuck::bytes_of(push));
            barrier(cmd);
        }
        let (Some(sort), Some(large)) = (&self.sort, &self.pipelines.large) else { return };
        let args = &self.buffers.large_args;
        large.args.dispatch(cmd, 0, [1, 1, 1], &[]);
        barrier(cmd);
        // SAFETY: the run holds the sort and waits for every submission it records.
        unsafe { sort.record(cmd, self.large.point_bits, None) };
        large.gather.dispatch_indirect(cmd, GATHER_BY_PROJECTION, args, ARG_GATHER, &[]);
        barrier(cmd);
        // SAFETY: as above.
        unsafe { sort.record(cmd, 32, None) };
        large.gather.dispatch_indirect(cmd, GATHER_BY_SEGMENT, args, ARG_GATHER, &[]);
        barrier(cmd);
        // SAFETY: as above.
        unsafe { sort.record(cmd, self.large.seg_bits, None) };
        large.transport.dispatch_indirect(cmd, 0, args, ARG_SEGMENTS, bytemuck::bytes_of(push));
        barrier(cmd);
    }

    /// The stopping rule's pass after the iteration in cost slot `slot` of the
    /// batch, when the device evaluates the rule (a barrier must precede it,
    /// after that iteration's update, and follow it).
    fn record_rule(&self, cmd: Recording<'_>, slot: u32) {
        if let (Some(pass), Some(_)) = (&self.pipelines.plateau, &self.rule) {
            let push = PlateauPush { slot, iteration: self.iteration + slot };
            pass.dispatch(cmd, 0, [1, 1, 1], bytemuck::bytes_of(&push));
        }
    }

    fn transport_push(&self, iteration: u32, slot: u32) -> TransportPush {
        let (axis_bits, pair_bits) = share_bits(self.settings.axis_share);
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
            large_capacity: self.large.capacity,
            order_slot: slot % self.order_slots.max(1),
            deferred_capacity: self.shape.deferred_capacity(self.slices),
            axis_bits,
            pair_bits,
        }
    }

    fn update_push(&self, iteration: u32) -> UpdatePush {
        let t = iteration + 1;
        let mut p = UpdatePush {
            values: self.tile.values() as u32,
            step_t: t,
            scale: self.scale.unwrap_or_else(|| schedule(iteration, self.settings.iterations)),
            inv_hits: (1.0 / self.hits_per_value) as f32,
            scheduled: self.rule.is_some() as u32,
            ..Default::default()
        };
        match self.settings.rule {
            StepRule::Momentum { step, beta } => {
                (p.rule, p.p0, p.p1) = (0, step, beta);
            }
            StepRule::Adam { lr, beta1, beta2, eps } => {
                (p.rule, p.p0, p.p1, p.p2, p.p3) = (1, lr, beta1, beta2, eps);
                p.bias1 = 1.0 - beta1.powi(t as i32);
                p.bias2 = 1.0 - beta2.powi(t as i32);
            }
        }
        p
    }

    /// Runs up to `max` iterations (at most BATCH) in one submission; returns each
    /// iteration's objective estimate.
    pub fn step_batch(&mut self, max: u32) -> Result<Vec<f64>> {
        let mut costs = Self::step_together(&mut [self], &[max])?;
        Ok(costs.pop().unwrap_or_default())
    }

    /// Does `other` work on the same device (so the two can share a submission)?
    pub fn shares_device_with(&self, other: &VulkanRun) -> bool {
        self.ctx.device().handle() == other.ctx.device().handle()
    }

    /// Several runs on one device stepped in one submission: up to `max[r]`
    /// iterations of run r (at most BATCH), recorded pass by pass, so that the
    /// runs' transport passes run side by side with no barrier between them, as
    /// do their updates (several masks in flight: small masks fill a large GPU
    /// together). Returns each run's objective estimates. Timestamps (the
    /// profile) are taken for a run stepped alone.
    pub fn step_together(runs: &mut [&mut VulkanRun], max: &[u32]) -> Result<Vec<Vec<f64>>> {
        let Some(first) = runs.first() else { return Ok(Vec::new()) };
        if max.len() != runs.len() || runs.iter().any(|r| !r.shares_device_with(first)) {
            return Err(Error::invalid("runs stepped together must share one device, each with its count"));
        }
        let counts: Vec<u32> = runs
            .iter()
            .zip(max)
            .map(|(r, &m)| m.min(BATCH).min(r.settings.iterations - r.iteration))
            .collect();
        let most = counts.iter().copied().max().unwrap_or(0);
        if most == 0 {
            return Ok(vec![Vec::new(); runs.len()]);
        }
        let ctx = first.ctx.clone();
        let alone = runs.len() == 1;
        let cost_bytes = BATCH as u64 * std::mem::size_of::<CostSlot>() as u64;
        let head_bytes = std::mem::size_of::<LargeMetaHead>() as u64;
        let rule_bytes = std::mem::size_of::<RuleState>() as u64;
        {
            let runs: Vec<&VulkanRun> = runs.iter().map(|r| &**r).collect();
            let timer = runs[0].timer.as_ref().filter(|_| alone);
            let stamp = |cmd: Recording<'_>, i| {
                if let Some(t) = timer {
                    t.stamp(cmd, i);
                }
            };
            ctx.submit(|cmd| {
                for r in &runs {
                    zero(cmd, &r.buffers.costs, 0, vk::WHOLE_SIZE);
                    zero(cmd, &r.buffers.large_meta, 0, head_bytes);
                }
                if let Some(t) = timer {
                    t.reset(cmd);
                }
                barrier(cmd);
                // The runs still stepping at iteration k of the batch, with their pushes
                // (one list, reused).
                let mut active: Vec<(&VulkanRun, TransportPush)> = Vec::with_capacity(runs.len());
                for k in 0..most {
                    active.clear();
                    active.extend(
                        runs.iter()
                            .zip(&counts)
                            .filter(|(_, &c)| k < c)
                            .map(|(r, _)| (*r, r.transport_push(r.iteration + k, k))),
                    );
                    stamp(cmd, 4 * k);
                    // The per-lane transport's slice orders, for as many
                    // iterations as its slots hold (slices do not depend on
                    // the samples).
                    for (r, &c) in runs.iter().zip(&counts) {
                        if k < c && r.order_slots > 0 && k % r.order_slots == 0 {
                            r.record_slice_order(cmd, r.iteration + k, (c - k).min(r.order_slots));
                        }
                    }
                    for (r, _) in &active {
                        r.record_reset_large(cmd);
                    }
                    // The stopping rule of the iteration before (its costs are
                    // complete; the update that read the scale is done).
                    for (r, &c) in runs.iter().zip(&counts) {
                        if k >= 1 && k <= c {
                            r.record_rule(cmd, k - 1);
                        }
                    }
                    barrier(cmd);
                    for (r, push) in &active {
                        r.record_transport_pass(cmd, push);
                    }
                    barrier(cmd);
                    stamp(cmd, 4 * k + 1);
                    for (r, push) in &active {
                        r.record_large(cmd, push);
                    }
                    stamp(cmd, 4 * k + 2);
                    for (r, _) in &active {
                        r.record_update_pass(cmd, r.iteration + k);
                    }
                    barrier(cmd);
                    if active.iter().any(|(r, _)| r.update_leaves_reset()) {
                        for (r, _) in active.iter().filter(|(r, _)| r.update_leaves_reset()) {
                            zero(cmd, &r.buffers.acc, 0, vk::WHOLE_SIZE);
                        }
                        barrier(cmd);
                    }
                    stamp(cmd, 4 * k + 3);
                }
                for (r, &c) in runs.iter().zip(&counts) {
                    if c == most {
                        r.record_rule(cmd, most - 1);
                    }
                }
                barrier(cmd);
                for r in &runs {
                    let b = &r.buffers;
                    copy(cmd, &b.costs, &b.readback, cost_bytes, 0);
                    copy(cmd, &b.large_meta, &b.readback, head_bytes, cost_bytes);
                    copy(cmd, &b.schedule, &b.readback, rule_bytes, cost_bytes + head_bytes);
                }
                barrier(cmd);
            })?;
        }
        runs.iter_mut().zip(&counts).map(|(r, &count)| r.finish_batch(count, alone)).collect()
    }

    /// After a batch of `count` iterations: the objective estimates, overflowed
    /// large classes and timestamps read back.
    fn finish_batch(&mut self, count: u32, timed: bool) -> Result<Vec<f64>> {
        let cost_bytes = BATCH as usize * std::mem::size_of::<CostSlot>();
        let head_bytes = std::mem::size_of::<LargeMetaHead>();
        let raw: Vec<u8> =
            self.buffers.readback.read(cost_bytes + head_bytes + std::mem::size_of::<RuleState>())?;
        let slots: Vec<CostSlot> = bytemuck::pod_collect_to_vec(&raw[..cost_bytes]);
        let head: LargeMetaHead = bytemuck::pod_read_unaligned(&raw[cost_bytes..cost_bytes + head_bytes]);
        self.overflowed += head.large_overflow as u64;
        if head.large_count > self.large.capacity {
            // The sort and the gather took the count as theirs: past the
            // buffers, nothing they wrote can be trusted.
            return Err(Error::VulkanUnavailable(format!(
                "{} counted {} large-class elements in buffers of {} in iterations {} to {}: the batch is not kept",
                self.ctx.info().name,
                head.large_count,
                self.large.capacity,
                self.iteration + 1,
                self.iteration + count
            )));
        }
        if head.loop_cut > 0 {
            // Some class's work was cut short: its displacements are wrong, and
            // so is every iteration after. Nothing of the batch is kept.
            return Err(Error::VulkanUnavailable(format!(
                "{} cut {} transport invocations short at its loop limit (65535 iterations per \
                 invocation) in iterations {} to {}: their classes would move the wrong way; the CPU \
                 backend takes any class",
                self.ctx.info().name,
                head.loop_cut,
                self.iteration + 1,
                self.iteration + count
            )));
        }
        let mut count = count;
        if self.rule.is_some() {
            let rule: RuleState = bytemuck::pod_read_unaligned(&raw[cost_bytes + head_bytes..]);
            if rule.stopped() {
                // The iterations past the rule's end did nothing.
                count = count.min(rule.stop_iteration.saturating_sub(self.iteration));
            }
            self.rule = Some(rule);
        }
        let costs = slots[..count as usize]
            .iter()
            .map(|s| if s.count > 0 { s.squared as f64 / COST_SCALE / s.count as f64 } else { 0.0 })
            .collect();
        if let (Some(t), true) = (&self.timer, timed && count > 0) {
            let ns = t.read_ns(4 * count)?;
            // The slice order's passes count with the transport.
            for k in 0..count as usize {
                let at = 4 * k;
                self.profile.transport_ns += ns[at + 1] - ns[at];
                self.profile.large_ns += ns[at + 2] - ns[at + 1];
                self.profile.update_ns += ns[at + 3] - ns[at + 2];
            }
            self.profile.iterations += count;
        }
        self.iteration += count;
        Ok(costs)
    }

    /// Reads the first `count` values of a device buffer through the run's
    /// readback buffer (no allocation).
    fn fetch<T: bytemuck::Pod>(&self, buffer: &Buffer, count: usize) -> Result<Vec<T>> {
        let bytes = (count * std::mem::size_of::<T>()) as u64;
        let parts = download_batch(&self.ctx, &[(buffer, bytes)], Some(&self.buffers.readback))?;
        Ok(bytemuck::pod_collect_to_vec(&parts[0]))
    }
}

/// The large-class sort's path: `set`, else chosen on the device
/// (`choose_sort_path`) for the stage's 32-bit sort (the projection keys: four
/// of its ten or so passes) at the expected count of an iteration.
fn large_sort_path(ctx: &Context, large: &LargePlan, set: Option<SortPath>) -> Result<PathChoice> {
    match set {
        Some(path) => Ok(PathChoice::forced(path)),
        None => {
            Ok(choose_sort_path(ctx, (large.expected.round() as u32).clamp(1, large.capacity.max(1)), 32)?)
        }
    }
}

/// The transport shape for this device and kernel, or why the asked one cannot be.
fn transport_shape(
    ctx: &Context,
    max_class: u32,
    dims: usize,
    texels: u64,
    options: &VulkanOptions,
) -> Result<TransportShape> {
    let info = ctx.info();
    match options.hooks.transport {
        Some(TransportKind::PerLane) if max_class > LOOP_BUDGET / 2 => {
            return Err(Error::invalid("the per-lane transport cannot take classes this large"))
        }
        Some(TransportKind::PerLane) if !info.subgroup_vote => {
            return Err(Error::VulkanUnavailable(format!(
                "the per-lane transport needs subgroup vote operations in compute shaders, which {} lacks",
                info.name
            )))
        }
        Some(TransportKind::PerLane) if texels > info.max_texel_buffer_elements => {
            return Err(Error::invalid(format!(
                "the per-lane transport reads the samples through a texel view of {texels} texels; {} \
                 holds at most {} (maxTexelBufferElements)",
                info.name, info.max_texel_buffer_elements
            )))
        }
        // Built for CPU implementations only: GPU drivers may refuse its
        // pipeline at 2048 samples per invocation.
        Some(TransportKind::PerLane) if !info.is_cpu() => {
            return Err(Error::invalid(format!(
                "the per-lane transport is for CPU implementations of Vulkan, not {}",
                info.name
            )))
        }
        _ => {}
    }
    let mut shape = TransportShape::choose(
        info,
        max_class,
        dims,
        texels,
        options.hooks.transport,
        options.hooks.workgroup_shape,
    );
    if let (Some(limit), true) = (options.hooks.unchecked_lane_limit, shape.per_lane) {
        shape.local_max = limit.clamp(2, LANE_MAX);
        return Ok(shape);
    }
    if let (Some(limit), false) = (options.hooks.local_max, shape.per_lane) {
        if !TransportShape::local_max_allowed(limit) {
            return Err(Error::invalid(format!(
                "the workgroup transport's class limit must be a power of two from 64 to {LOCAL_MAX}, not {limit}"
            )));
        }
        shape.local_max = limit;
    }
    match options.hooks.defer {
        None => shape.defer_auto(info, max_class),
        Some(0) => {}
        Some(max) if shape.per_lane || !max.is_power_of_two() || max <= shape.local_max || max > DEFER_LIMIT => {
            return Err(Error::invalid(format!(
                "the workgroup transport's second pass takes classes up to a power of two above {} and at most \
                 {DEFER_LIMIT}, not {max}{}",
                shape.local_max,
                if shape.per_lane { " (and the per-lane transport has none)" } else { "" }
            )))
        }
        Some(max) => {
            shape.defer_max = max;
            shape.defer_workgroup = DEFER_WORKGROUP.min(info.max_workgroup_invocations);
        }
    }
    if let Some(groups) = options.hooks.defer_groups {
        if !(1..=DEFER_GROUPS).contains(&groups) {
            return Err(Error::invalid(format!(
                "the second pass's workgroups must be from 1 to {DEFER_GROUPS}, not {groups}"
            )));
        }
        shape.defer_groups = groups;
    }
    shape.fits_shared_memory(info)?;
    if !shape.fits_loop_budget(info, max_class, dims) {
        return Err(Error::invalid(format!(
            "classes of up to {max_class} samples in d = {dims} would take {} past its loop budget \
             (a CPU implementation drops loop iterations past 65535 per invocation); use the CPU backend",
            info.name
        )));
    }
    Ok(shape)
}

impl Backend for VulkanRun {
    fn kind(&self) -> BackendKind {
        BackendKind::Vulkan
    }

    fn describe(&self) -> String {
        let scatter = if self.float_acc { "float atomics" } else { "fixed point, deterministic" };
        format!("vulkan on {} ({}; scatter: {scatter})", self.ctx.info().name, self.ctx.info().driver)
    }

    fn iteration(&self) -> u32 {
        self.iteration
    }

    fn slices_per_iteration(&self) -> u32 {
        self.slices
    }

    fn step_up_to(&mut self, max: u32) -> Result<Vec<f64>> {
        self.step_batch(max.max(1))
    }

    /// Samples and optimizer state read back in one submission.
    fn state(&self) -> Result<RunState> {
        let values = self.tile.values();
        let bytes = values as u64 * 4;
        let adam = matches!(self.settings.rule, StepRule::Adam { .. });
        let b = &self.buffers;
        let parts = download_batch(&self.ctx, &[(&b.samples, bytes), (&b.first, bytes)], Some(&b.readback))?;
        Ok(RunState {
            iteration: self.iteration,
            samples: bytemuck::pod_collect_to_vec(&parts[0]),
            first: bytemuck::pod_collect_to_vec(&parts[1]),
            second: if adam { self.fetch(&b.second, values)? } else { Vec::new() },
            plateau: None,
        })
    }

    fn restore(&mut self, saved: &RunState) -> Result<()> {
        saved.check(&self.tile, &self.settings)?;
        let b = &self.buffers;
        let uploads = [
            (&b.samples, bytemuck::cast_slice(&saved.samples)),
            (&b.first, bytemuck::cast_slice(&saved.first)),
            (&b.second, bytemuck::cast_slice(&saved.second)),
        ];
        upload_batch(&self.ctx, &uploads, |_| {})?;
        self.iteration = saved.iteration;
        Ok(())
    }

    fn samples(&self) -> Result<Vec<f32>> {
        self.fetch(&self.buffers.samples, self.tile.values())
    }

    fn mask(&self) -> Result<Mask> {
        let mut mask = run_mask(&self.tile, &self.settings, self.iteration, self.slices, self.samples()?);
        mask.set_meta("backend", format!("vulkan ({})", self.ctx.info().name));
        if !self.float_acc {
            mask.set_meta("scatter", "fixed-point (deterministic)");
        }
        Ok(mask)
    }

    /// Runs only the transport passes of iteration `iteration` (no update) and
    /// returns the summed displacement of every coordinate; the accumulators are
    /// left at zero.
    fn displacements(&mut self, iteration: u32) -> Result<Vec<f64>> {
        let ctx = &self.ctx;
        let values = self.tile.values();
        let width = if self.float_acc { 4 } else { 8 };
        let push = self.transport_push(iteration, 0);
        let acc = &self.buffers.acc;
        ctx.submit(|cmd| {
            zero(cmd, acc, 0, vk::WHOLE_SIZE);
            barrier(cmd);
            self.record_slice_order(cmd, iteration, 1);
            self.record_transport(cmd, &push);
            self.record_large(cmd, &push);
            copy(cmd, acc, &self.buffers.readback, (values * width) as u64, 0);
            barrier(cmd);
            zero(cmd, acc, 0, vk::WHOLE_SIZE);
            barrier(cmd);
        })?;
        Ok(if self.float_acc {
            self.buffers.readback.read::<f32>(values)?.into_iter().map(f64::from).collect()
        } else {
            self.buffers.readback.read::<i64>(values)?.into_iter().map(|v| v as f64 / FIXED_SCALE).collect()
        })
    }

    fn set_scale(&mut self, scale: Option<f32>) {
        self.scale = scale;
    }

    /// From the next batch a pass after each iteration evaluates the rule in
    /// f64 (`glsl/fsot/plateau.comp`), sets the update's step scale and ends the
    /// run, with no decision left to the host, so a batch need not end at a
    /// window's end. False (nothing changed) on a device without shaderFloat64,
    /// or with `VulkanOptions::host_stopping_rule`.
    fn adopt_plateau(&mut self, rule: &Plateau, state: &PlateauState, target: Option<f64>) -> Result<bool> {
        if self.pipelines.plateau.is_none() || self.options.hooks.host_stopping_rule {
            return Ok(false);
        }
        let device = RuleState::new(rule, state, target);
        upload_batch(&self.ctx, &[(&self.buffers.schedule, bytemuck::bytes_of(&device))], |_| {})?;
        self.rule = Some(device);
        Ok(true)
    }

    /// The device's rule as of the last batch read back.
    fn plateau(&self) -> Option<(PlateauState, bool)> {
        self.rule.map(|r| (r.plateau_state(), r.stopped()))
    }

    /// Runs on one device share a group (its device handle).
    fn group(&self) -> Option<usize> {
        Some(ash::vk::Handle::as_raw(self.ctx.device().handle()) as usize)
    }

    fn step_together(&mut self, others: &mut [&mut dyn Backend], max: &[u32]) -> Result<Vec<Vec<f64>>> {
        let mut runs: Vec<&mut VulkanRun> = vec![self];
        for other in others.iter_mut() {
            let run = other.as_any_mut().downcast_mut::<VulkanRun>();
            runs.push(run.ok_or_else(|| Error::invalid("only Vulkan runs step together with a Vulkan run"))?);
        }
        VulkanRun::step_together(&mut runs, max)
    }

    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }

    fn report(&self) -> Report {
        let (transport_bytes, large_bytes, update_bytes) = self.pass_bytes();
        Report {
            profile: self.options.profile.then(|| Profile {
                transport_bytes,
                large_bytes,
                update_bytes,
                ..self.profile.clone()
            }),
            skipped_large_classes: self.overflowed,
            validation_messages: self.ctx.validation_messages(),
            // Said where it was timed or set (on CPU implementations it is the
            // block passes, untimed, and goes unsaid).
            large_sort: self
                .sort_choice
                .filter(|c| c.times.is_some() || self.options.hooks.large_sort.is_some())
                .map(|c| c.describe()),
            transport: Some(self.shape.describe()),
        }
    }
}
