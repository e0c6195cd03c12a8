//! How the transport pass is launched on a device, within lavapipe's loop cap.

use crate::error::{Error, Result};
use crate::optimize::vulkan::layout::{order_bin, LANE_TABLE_WORDS, LANE_TIERS, ORDER_BINS};
use crate::vk::DeviceInfo;

/// Classes up to this many samples are sorted in shared memory (the
/// specialization constant `FSOT_LOCAL_MAX` of transport.comp).
pub const LOCAL_MAX: u32 = 2048;
/// Classes up to this many samples are sorted by one invocation in the per-lane
/// transport (`FSOT_LANE_MAX` of transport_lane.comp; its private arrays take 18
/// bytes per sample per invocation, which lavapipe takes and an NVIDIA driver
/// refuses at 20: the per-lane transport is for CPU implementations only),
/// unless the kernel's classes pass it and fit the loop budget
/// (`lane_limit_for`).
pub const LANE_MAX: u32 = 2048;
/// The per-lane transport's limit past LANE_MAX is the kernel's largest class
/// rounded up to a multiple of this (few pipelines to compile).
pub const LANE_STEP: u32 = 256;
/// Loop iterations one transport invocation may spend over its slices: under half
/// of lavapipe's cap of 65535 per invocation.
pub const LOOP_BUDGET: u32 = 30_000;
/// Loop iterations one per-lane invocation may spend on its slice: its sort's
/// worst case (the heap-sort fallback, about 47k at LANE_MAX) fits, as do the
/// f64 targets of small classes.
pub const LANE_BUDGET: u32 = 60_000;
/// Pairs of members sharing a bucket that one invocation of the workgroup
/// transport may sort by insertion, per bucket of its run plus sixteen
/// (`FSOT_INSERTION_BUDGET` of transport.comp); past it, the class takes the
/// bitonic network.
pub const GROUP_INSERTION_BUDGET: u32 = 4;
/// Invocations of the workgroup transport's second pass, which sorts the classes
/// past LOCAL_MAX in shared memory (`defer_max`).
pub const DEFER_WORKGROUP: u32 = 256;
/// Largest class the second pass may sort in shared memory.
pub const DEFER_LIMIT: u32 = 8192;
/// Workgroups of the second pass at most (`FSOT_DEFER_GROUPS`): the least
/// maxComputeWorkGroupCount a device gives. Past it, each takes several listed
/// slices.
pub const DEFER_GROUPS: u32 = 65535;
/// Chunks of the per-lane transport aimed at for each of the driver's threads,
/// where the slices' costs allow (`lane_table`; each tier adds at most one,
/// its last, partial): few, since each workgroup's start costs llvmpipe a few
/// microseconds (its lanes' private arrays among it), yet more than one, so
/// that the threads end together (fewer chunks leave threads idle at the end,
/// many more cost their start-up; BENCHMARKS.md, lavapipe).
pub const LANE_CHUNKS_PER_THREAD: u32 = 4;
/// Loop iterations of one round of the per-lane transport besides the slice's
/// sort and targets (`lane_cost`): the rounds' loop and the slice's draw (over
/// the dimensions: about 32 at d = 8 with a Gaussian direction's first try).
/// The class comes from the ordering, with no search.
pub const LANE_ROUND_LOOPS: u32 = 64;
/// Workgroup size of the large-class transport (transport_large.comp).
pub const LARGE_WORKGROUP: u32 = 128;

/// The f64 targets (d >= 3) walk the lower half's ranks, each quantile a
/// bracketed Newton solve from the last, each step one evaluation of 2^d terms.
/// Measured (the same solver in f64, random directions, d = 3 to 8, classes of
/// 16 to 2048): 2.4 to 4.2 steps per rank on average, plus one evaluation of the
/// moment; at most 21 steps from a cold start. Budgeted: twice the mean per rank,
/// and 24 for the start.
const WALK_EVALS: u32 = 10;
const COLD_EVALS: u32 = 24;
/// Newton steps one quantile may take at most (`FSOT_NEWTON_MAX` of
/// glsl/fsot/targets.glsl): the per-lane pass budgets every quantile at this, so
/// no class, however hard, takes an invocation past the loop cap (budgeting the
/// mean there would let a hard class, such as one of 39 samples at d = 8, run
/// past it and leave its targets as garbage).
const NEWTON_MAX: u32 = 60;

/// The two transport passes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransportKind {
    /// One workgroup per slice, bucket sort in shared memory (GPUs).
    Workgroup,
    /// One invocation per slice, bucket sort in private memory (CPU implementations).
    PerLane,
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
    /// Largest class the pass sorts itself (`FSOT_LANE_MAX` or
    /// `FSOT_LOCAL_MAX`); larger classes go to the large-class stage's global
    /// sort. Per lane: LANE_MAX, less for d >= 3, more where every class fits
    /// the budget (`lane_limit_for`).
    pub local_max: u32,
    /// The workgroup transport sorts a class that fits one subgroup by the
    /// first subgroup alone, each member ranked by counting (no workgroup
    /// barrier); the others by buckets. Only where the targets are in closed
    /// form (d <= 2); the per-lane transport ignores it.
    pub subgroup_classes: bool,
    /// Classes past `local_max` and at most this are sorted by a second pass of
    /// the workgroup transport (`FSOT_DEFER_MAX`: one workgroup of
    /// `defer_workgroup` invocations per listed slice) instead of the
    /// large-class stage's global sorts; 0: none (CPU implementations, the
    /// per-lane transport, kernels whose classes fit `local_max`).
    pub defer_max: u32,
    /// Invocations of that second pass.
    pub defer_workgroup: u32,
    /// Workgroups of that second pass at most (DEFER_GROUPS; less in tests).
    pub defer_groups: u32,
    /// Per lane: the chunks of slices aimed at an iteration (`lane_table`).
    pub lane_chunks: u32,
}

impl TransportShape {
    /// GPUs: 128 invocations, one slice each. CPU implementations (lavapipe):
    /// one subgroup per workgroup (its barriers are nearly free there, while a
    /// workgroup barrier costs a coroutine switch per subgroup) and 16 slices per
    /// workgroup (launches are dear), fewer when the kernel's largest class would
    /// take an invocation past LOOP_BUDGET loop iterations (lavapipe silently
    /// drops iterations past 65535 per invocation). On CPU implementations, the
    /// per-lane transport when the kernel allows: for samples of `dims` >= 3
    /// dimensions only where every class's f64 targets stay within LANE_BUDGET
    /// at their worst (`lane_limit`; forced per lane, larger classes go to the
    /// large-class stage), otherwise workgroups large enough that each
    /// invocation's share of the targets stays within LOOP_BUDGET
    /// (`fits_loop_budget` says whether a shape does). The per-lane transport
    /// reads the samples and the taps through texel views: not chosen where one
    /// would hold more than the device's maxTexelBufferElements (`texels`: the
    /// larger view's texels), nor where the device lacks subgroup votes (its
    /// lanes choose their sort together). `kind` forces a transport (None: by device);
    /// `forced` (invocations, slices per workgroup): the workgroup transport
    /// with that shape.
    pub fn choose(
        info: &DeviceInfo,
        max_class: u32,
        dims: usize,
        texels: u64,
        kind: Option<TransportKind>,
        forced: Option<(u32, u32)>,
    ) -> Self {
        let per_lane = match kind {
            Some(TransportKind::PerLane) => true,
            Some(TransportKind::Workgroup) => false,
            // Per lane when one invocation can also write out the largest class
            // for the large-class path within the loop budget, and that path's
            // invocations can take the classes past the lane's limit. For d >= 3
            // only when every class fits the lane: there the limit is small (the
            // targets budgeted at their worst), and on lavapipe the large-class
            // stage costs more than the workgroup transport saves, also with
            // the sort's lanes path (BENCHMARKS.md, lavapipe).
            None => {
                let limit = Self::lane_limit(dims);
                info.is_cpu()
                    && info.subgroup_vote
                    && texels <= info.max_texel_buffer_elements
                    && max_class <= LOOP_BUDGET / 2
                    && (dims <= 2 || max_class <= limit)
                    && Self::large_fits(max_class, limit, dims)
            }
        };
        let local_max = if per_lane { Self::lane_limit_for(max_class, dims) } else { LOCAL_MAX };
        let (workgroup, slices_per_group, one_subgroup) = if info.is_cpu() {
            (info.subgroup_size.clamp(1, 128), 16, true)
        } else {
            (128.min(info.max_workgroup_invocations), 1, false)
        };
        let mut shape = Self {
            workgroup,
            slices_per_group,
            one_subgroup,
            per_lane,
            local_max,
            subgroup_classes: dims <= crate::optimize::vulkan::CLOSED_FORM_DIMS,
            defer_max: 0,
            defer_workgroup: 0,
            defer_groups: DEFER_GROUPS,
            lane_chunks: 1,
        };
        let local = max_class.min(LOCAL_MAX);
        if info.is_cpu() && !per_lane {
            while shape.workgroup < info.max_workgroup_invocations.min(1024)
                && Self::group_iterations(local, shape.workgroup, dims) > LOOP_BUDGET
                && Self::shared_bytes(shape.workgroup * 2, LOCAL_MAX) <= info.max_shared_memory
            {
                shape.workgroup *= 2;
            }
            shape.one_subgroup = shape.workgroup <= info.subgroup_size;
        }
        let worst = Self::group_iterations(local, shape.workgroup, dims);
        shape.slices_per_group = shape.slices_per_group.min((LOOP_BUDGET / worst).max(1));
        if let Some((wg, spg)) = forced.filter(|&(wg, spg)| wg > 0 && spg > 0) {
            shape.workgroup = wg.min(info.max_workgroup_invocations);
            shape.slices_per_group = spg;
            shape.per_lane = false;
            shape.local_max = LOCAL_MAX;
            shape.one_subgroup = shape.workgroup <= info.subgroup_size;
        }
        shape
    }

    /// Whether the workgroup transport's first pass may sort classes up to
    /// `limit` in place of LOCAL_MAX (`VulkanOptions::local_max`): a power of
    /// two from 64 to LOCAL_MAX.
    pub fn local_max_allowed(limit: u32) -> bool {
        limit.is_power_of_two() && (64..=LOCAL_MAX).contains(&limit)
    }

    /// Shared memory the workgroup transport (transport.comp) takes with
    /// `workgroup` invocations and classes up to `local_max`: the class's keys
    /// and points (4 bytes each a member) and bucket counts (2 bytes), two
    /// words an invocation (the scan's and the cost's subgroup totals), the f64
    /// subset sums of d = 8 (256 x 8 bytes) and a few flags (256 bytes
    /// allowed).
    pub fn shared_bytes(workgroup: u32, local_max: u32) -> u32 {
        10 * local_max + 8 * workgroup + 2048 + 256
    }

    /// Whether the workgroup transport in this shape, and its second pass,
    /// fit the device's shared memory (the per-lane transport takes none); if
    /// not, why.
    pub fn fits_shared_memory(&self, info: &DeviceInfo) -> Result<()> {
        if self.per_lane {
            return Ok(());
        }
        let second = (self.defer_max > 0).then_some((self.defer_workgroup, self.defer_max));
        for (wg, max) in std::iter::once((self.workgroup, self.local_max)).chain(second) {
            let bytes = Self::shared_bytes(wg, max);
            if bytes > info.max_shared_memory {
                return Err(Error::invalid(format!(
                    "the workgroup transport with {wg} invocations and classes up to {max} takes {bytes} \
                     bytes of shared memory; {} has {} (maxComputeSharedMemorySize): use fewer \
                     invocations",
                    info.name, info.max_shared_memory
                )));
            }
        }
        Ok(())
    }

    /// The second pass for classes past `local_max`, on GPUs: up to the
    /// smallest power of two that holds `max_class` (at most DEFER_LIMIT), or
    /// the largest that fits the device's shared memory with DEFER_WORKGROUP
    /// invocations; none on CPU implementations (lavapipe: its classes past the
    /// limit stay with the large-class stage, which the per-lane transport
    /// shares), per lane, or where every class fits `local_max`.
    pub fn defer_auto(&mut self, info: &DeviceInfo, max_class: u32) {
        if info.is_cpu() || self.per_lane || max_class <= self.local_max {
            return;
        }
        let wg = DEFER_WORKGROUP.min(info.max_workgroup_invocations);
        let mut max = max_class.next_power_of_two().min(DEFER_LIMIT);
        while max > self.local_max && Self::shared_bytes(wg, max) > info.max_shared_memory {
            max /= 2;
        }
        if max > self.local_max {
            self.defer_max = max;
            self.defer_workgroup = wg;
        }
    }

    /// Slices the second pass's list holds per iteration of `slices` slices: all
    /// of them (its workgroups take several each past `defer_groups`); 0 without
    /// a second pass.
    pub fn deferred_capacity(&self, slices: u32) -> u32 {
        if self.defer_max > 0 {
            slices
        } else {
            0
        }
    }

    /// The pass, its shape and how it sorts a class, in words.
    pub fn describe(&self) -> String {
        if self.per_lane {
            return format!(
                "per lane ({} invocations a workgroup, taking chunks of slices as the loop budget allows, \
                 largest classes first), classes up to {} by a bucket sort",
                self.workgroup, self.local_max
            );
        }
        let sort = match self.subgroup_classes {
            true => "buckets, those that fit a subgroup by the subgroup alone",
            false => "buckets",
        };
        let deferred = match self.defer_max {
            0 => String::new(),
            m => format!(", those up to {m} in a second pass of {} invocations", self.defer_workgroup),
        };
        format!(
            "workgroups of {} invocations, {} slice{} each, classes up to {} sorted by {sort}{deferred}",
            self.workgroup,
            self.slices_per_group,
            if self.slices_per_group == 1 { "" } else { "s" },
            self.local_max
        )
    }

    /// Upper bound on the loop iterations one invocation spends on a class of
    /// `n` samples (n <= LOCAL_MAX) in a workgroup of `wg`: the bucket sort
    /// (clearing, gathering and counting, its run of buckets' counts and first
    /// positions, the scan's subgroups, placing: an element or bucket per
    /// iteration), then either the insertion within its run (at most the run's
    /// members and twice GROUP_INSERTION_BUDGET moves) or the bitonic fallback
    /// (padding, then a pair per iteration per stage), then targets and
    /// reduction.
    pub fn slice_iterations(n: u32, wg: u32) -> u32 {
        let p = n.max(2).next_power_of_two();
        let log = p.trailing_zeros();
        let per = n.max(2).div_ceil(wg);
        let bucket = 5 * per + wg;
        let run = per + (per & 1); // buckets an invocation owns: whole words of two
        let insertion = run + 2 * GROUP_INSERTION_BUDGET * (run + 16);
        let pairs_per_stage = (p / 2).div_ceil(wg);
        let stages = log * (log + 1) / 2;
        let bitonic = p.div_ceil(wg) + stages * (pairs_per_stage + 1);
        bucket + insertion.max(bitonic) + per + 2 * log + 64
    }

    /// Loop iterations of the f64 targets (d >= 3) for a walk over `ranks`
    /// consecutive ranks: filling the subset sums, a cold start, the steps.
    pub fn walk_iterations(ranks: u32, dims: usize) -> u32 {
        if dims <= 2 {
            return 0;
        }
        let terms = 1u32 << dims;
        let eval = terms + 1;
        terms * dims as u32 + (COLD_EVALS + ranks * WALK_EVALS) * eval
    }

    /// Loop iterations of the f64 targets (d >= 3) for `ranks` ranks whatever
    /// the class: filling the subset sums, then each quantile at NEWTON_MAX
    /// evaluations and its moment.
    pub fn walk_worst(ranks: u32, dims: usize) -> u32 {
        if dims <= 2 {
            return 0;
        }
        let terms = 1u32 << dims;
        64 + terms * dims as u32 + ranks * (NEWTON_MAX * (terms + 1) + terms + 1)
    }

    /// Upper bound on one per-lane invocation's loop iterations for a class of
    /// `n` (n <= LANE_MAX): clear, count, prefix and place (n each), the sort's
    /// worst case (the insertion's listing pass, its list and its moves, at
    /// most n + n + 4n; or the heap-sort fallback), then the targets (n for
    /// d <= 2; for d >= 3 the walk over n / 2 ranks, each at its worst).
    pub fn lane_iterations(n: u32, dims: usize) -> u32 {
        let n = n.max(2);
        let heap = 3 * n / 2 + (3 * n / 2) * n.ilog2();
        let targets = if dims <= 2 { n } else { Self::walk_worst(n / 2, dims) };
        4 * n + (6 * n).max(heap) + targets
    }

    /// Upper bound on one workgroup invocation's loop iterations for a class of
    /// `n` (n <= LOCAL_MAX) with `wg` invocations in `dims` dimensions.
    pub fn group_iterations(n: u32, wg: u32, dims: usize) -> u32 {
        Self::slice_iterations(n, wg) + Self::walk_iterations((n / 2).div_ceil(wg), dims)
    }

    /// Whether every invocation of this shape, and of the large-class pass for
    /// classes up to `max_class`, stays within lavapipe's loop budget (only CPU
    /// implementations have one).
    pub fn fits_loop_budget(&self, info: &DeviceInfo, max_class: u32, dims: usize) -> bool {
        if !info.is_cpu() {
            return true;
        }
        let local = self.local_max;
        let fits_small = if self.per_lane {
            Self::lane_iterations(max_class.min(local), dims) <= LANE_BUDGET
        } else {
            self.slices_per_group * Self::group_iterations(max_class.min(local), self.workgroup, dims)
                <= LOOP_BUDGET
        };
        // The second pass: one slice a workgroup (and its slot's compare-and-swap
        // loop, at most 64, in the first pass: within the 64 of slack).
        let fits_deferred = self.defer_max == 0
            || Self::group_iterations(max_class.min(self.defer_max), self.defer_workgroup, dims)
                <= LOOP_BUDGET;
        fits_small && fits_deferred && Self::large_fits(max_class, local.max(self.defer_max), dims)
    }

    /// Whether the large-class stage's invocations stay within LOOP_BUDGET for
    /// classes of up to `max_class` when those up to `local` are sorted locally.
    fn large_fits(max_class: u32, local: u32, dims: usize) -> bool {
        max_class <= local
            || Self::walk_iterations((max_class / 2).div_ceil(LARGE_WORKGROUP), dims) <= LOOP_BUDGET
    }

    /// The per-lane limit for a kernel whose largest class is `max_class`:
    /// `lane_limit`, unless the classes pass LANE_MAX at d <= 2 and all fit
    /// the loop budget (up to about 2600 samples): then the largest rounded up
    /// to a multiple of LANE_STEP, so that no class goes to the large-class
    /// stage, whose three global sorts cost lavapipe more than the whole
    /// transport at 128x128x30, where a few slices in a thousand pass 2048. The
    /// private arrays grow with it (46 KiB an invocation at 2560), and
    /// llvmpipe zero-fills them at each workgroup's start, so the limit stays
    /// at LANE_MAX where every class fits it.
    pub fn lane_limit_for(max_class: u32, dims: usize) -> u32 {
        let limit = Self::lane_limit(dims);
        let stretched = max_class.next_multiple_of(LANE_STEP);
        if max_class > limit && limit == LANE_MAX && Self::lane_iterations(stretched, dims) <= LANE_BUDGET {
            stretched
        } else {
            limit
        }
    }

    /// Largest class (at most LANE_MAX) that one per-lane invocation sorts and
    /// sends to its targets within LANE_BUDGET in `dims` dimensions: LANE_MAX
    /// for d <= 2; 207 for d = 3, 113 for d = 4, 7 for d = 8.
    pub fn lane_limit(dims: usize) -> u32 {
        let (mut lo, mut hi) = (2u32, LANE_MAX);
        while lo < hi {
            let mid = (lo + hi).div_ceil(2);
            if Self::lane_iterations(mid, dims) <= LANE_BUDGET {
                lo = mid;
            } else {
                hi = mid - 1;
            }
        }
        lo
    }

    /// Per lane, the chunks the plan aims at (`lane_table`):
    /// LANE_CHUNKS_PER_THREAD for each of the driver's threads, at least one.
    pub fn set_lane_chunks(&mut self, chunks: u32) {
        self.lane_chunks = chunks.max(1);
    }

    /// Loop iterations one per-lane invocation spends on a slice of a class of
    /// `class` at worst: its sort and targets (`lane_iterations`), or where the
    /// class passes `local_max`, its listing for the large-class stage, plus
    /// both, since a SIMD driver runs both sides of the branch when its lanes
    /// differ; and LANE_ROUND_LOOPS for drawing the slice.
    pub fn lane_cost(&self, class: u32, dims: usize) -> u32 {
        let listed = if class > self.local_max { class } else { 0 };
        Self::lane_iterations(class.min(self.local_max), dims).saturating_add(listed) + LANE_ROUND_LOOPS
    }

    /// The per-lane transport's lane table (the first LANE_TABLE_WORDS of
    /// `SliceOrder`, `glsl/fsot/slice_order.glsl`) for a kernel of `taps` taps
    /// at `spp` samples per pixel in `dims` dimensions: the lanes of a chunk
    /// (the workgroup, one subgroup), the chunks aimed at (`lane_chunks`),
    /// each bin's tier, and each tier's cost
    /// (`lane_cost` of its largest class) and most rounds (as many as
    /// LANE_BUDGET holds at that cost, at least one).
    /// A tier is a run of bins, in rank order, whose largest classes cost
    /// more than half its first's: a chunk of a tier, whatever its classes,
    /// stays within the loop cap, and spends at least half of what it budgets.
    pub fn lane_table(&self, taps: u32, spp: u32, dims: usize) -> Vec<u32> {
        let bins = ORDER_BINS as usize;
        let tiers = LANE_TIERS as usize;
        // The largest class of each bin, in taps (0: an empty bin).
        let mut top = vec![0u32; bins];
        for class_taps in 1..=taps {
            let bin = order_bin(class_taps, taps) as usize;
            top[bin] = top[bin].max(class_taps);
        }
        let mut tier_of = vec![0u32; bins];
        let mut cost = vec![1u32; tiers];
        let mut most = vec![1u32; tiers];
        let mut used = 0usize;
        for (bin, &t) in top.iter().enumerate() {
            if t > 0 {
                let c = self.lane_cost(t.saturating_mul(spp), dims);
                if used == 0 || (c <= cost[used - 1] / 2 && used < tiers) {
                    cost[used] = c;
                    most[used] = (LANE_BUDGET / c).max(1);
                    used += 1;
                }
            }
            tier_of[bin] = used.saturating_sub(1) as u32;
        }
        let mut table = vec![self.workgroup, self.lane_chunks];
        table.extend(tier_of);
        table.extend(cost.iter().zip(&most).flat_map(|(&c, &m)| [c, m]));
        debug_assert_eq!(table.len(), LANE_TABLE_WORDS as usize);
        table
    }

    /// Workgroups of the workgroup transport for `slices` slices (the
    /// per-lane transport's come from its chunk plan, on the device).
    pub fn groups(&self, slices: u32) -> u32 {
        slices.div_ceil(self.slices_per_group)
    }
}

/// `groups` workgroups as a dispatch, spread over y past 65535.
pub fn two_d(groups: u32) -> [u32; 3] {
    let x = groups.clamp(1, 65535);
    [x, groups.div_ceil(x).max(1), 1]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What lavapipe (Mesa 22.3, AVX2) reports.
    fn lavapipe() -> DeviceInfo {
        DeviceInfo {
            name: "llvmpipe".into(),
            driver: String::new(),
            device_type: ash::vk::PhysicalDeviceType::CPU,
            vendor_id: 0x10005,
            subgroup_size: 8,
            max_storage_buffer_range: 1 << 27,
            max_texel_buffer_elements: 1 << 27,
            max_workgroup_invocations: 1024,
            max_shared_memory: 32768,
            timestamp_period_ns: 1.0,
            float_atomic_add: true,
            int64_atomics: true,
            subgroup_ballot: true,
            subgroup_vote: true,
            subgroup_arithmetic: true,
            float64: true,
            full_subgroups: true,
        }
    }

    /// A lane table's parts: lanes, chunks aimed at, each bin's tier, and
    /// each tier's cost and most rounds.
    fn table_parts(table: &[u32]) -> (u32, u32, &[u32], Vec<(u32, u32)>) {
        let bins = ORDER_BINS as usize;
        let tiers = table[2 + bins..].chunks(2).map(|p| (p[0], p[1])).collect();
        (table[0], table[1], &table[2..2 + bins], tiers)
    }

    #[test]
    fn the_lane_table_budgets_each_tier_at_its_largest_class() {
        let lavapipe = lavapipe();
        // The quick benchmark's problem (32x32x16 taa: 1360 taps, d = 2) on 2
        // threads: chunks of 8 lanes, 8 aimed at; the largest classes' tier
        // takes two rounds a chunk (the heap sort's worst case at 1360 fits
        // twice), and a tier of classes of at most a few taps takes hundreds.
        let mut shape = TransportShape::choose(&lavapipe, 1360, 2, 1 << 15, None, None);
        assert!(shape.per_lane);
        shape.set_lane_chunks(LANE_CHUNKS_PER_THREAD * 2);
        let table = shape.lane_table(1360, 1, 2);
        assert_eq!(table.len(), LANE_TABLE_WORDS as usize);
        let (lanes, aim, tier_of, tiers) = table_parts(&table);
        assert_eq!((lanes, aim), (8, 8));
        assert_eq!(tiers[0], (shape.lane_cost(1360, 2), 2));
        // Where the shaders (and `VulkanRun::slice_order`) read a tier's cost.
        assert_eq!(table[crate::optimize::vulkan::layout::lane_table_cost_word(1) as usize], tiers[1].0);
        let last = tier_of[ORDER_BINS as usize - 1] as usize;
        assert!(tiers[last].1 > 300, "{:?}", tiers[last]);
        // Whatever the kernel, dimension, spp and threads: tiers follow
        // the bins in rank order; a tier's cost is that of its first bin's
        // largest class, at least every class's of its bins, more than twice
        // the next tier's; and its rounds fit the loop budget at that cost (or
        // are one, which `choose` budgets).
        for dims in 1..=8 {
            for taps in [1u32, 2, 16, 100, 744, 1360, 2048, 5000] {
                for spp in [1u32, 3] {
                    let max_class = taps * spp;
                    let mut shape = TransportShape::choose(&lavapipe, max_class, dims, 1 << 15, None, None);
                    for threads in [1, 2, 64] {
                        shape.set_lane_chunks(LANE_CHUNKS_PER_THREAD * threads);
                        let table = shape.lane_table(taps, spp, dims);
                        let (lanes, aim, tier_of, tiers) = table_parts(&table);
                        let what = format!("d = {dims}, {taps} taps x {spp}, {threads} threads");
                        assert_eq!(
                            (lanes, aim),
                            (shape.workgroup, LANE_CHUNKS_PER_THREAD * threads),
                            "{what}"
                        );
                        assert!(tier_of.windows(2).all(|w| w[1] == w[0] || w[1] == w[0] + 1), "{what}");
                        for class_taps in 1..=taps {
                            let tier = tier_of[order_bin(class_taps, taps) as usize] as usize;
                            let cost = shape.lane_cost(class_taps * spp, dims);
                            assert!(
                                cost <= tiers[tier].0,
                                "{what}: {class_taps} taps cost {cost} > {:?}",
                                tiers[tier]
                            );
                        }
                        let used = *tier_of.last().unwrap() as usize + 1;
                        assert_eq!(tiers[0].0, shape.lane_cost(max_class, dims), "{what}");
                        for (t, &(cost, rounds)) in tiers[..used].iter().enumerate() {
                            assert!(rounds >= 1, "{what}: tier {t}");
                            assert!(
                                rounds == 1 || rounds * cost <= LANE_BUDGET,
                                "{what}: tier {t}: {rounds} x {cost}"
                            );
                            if let Some(&(next, _)) = tiers[..used].get(t + 1) {
                                assert!(2 * next <= cost, "{what}: tier {t} costs {cost}, the next {next}");
                            }
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn every_invocation_stays_under_the_loop_budget() {
        // The largest local class on one subgroup of 8 (lavapipe).
        assert!(TransportShape::slice_iterations(LOCAL_MAX, 8) < LOOP_BUDGET);
        // Per lane, one invocation sorts a whole class: clear, count, prefix and
        // place (one loop over n each), then either the insertion (a listing
        // pass of n, a list of at most n, and at most 4n moves,
        // FSOT_INSERTION_BUDGET) or the heap-sort fallback (3n/2 sift-downs of
        // at most log2 n steps each), then targets and scatter (n). At LANE_MAX
        // the fallback is the worst case, about 47k: under lavapipe's 65535 for
        // all loops of an invocation.
        let n = LANE_MAX;
        let log = n.ilog2();
        let insertion = n + n + 4 * n;
        let heap = 3 * n / 2 + (3 * n / 2) * log;
        let per_lane = 5 * n + insertion.max(heap);
        assert!(per_lane < 50_000, "{per_lane}");
        // The f64 targets: per lane, d = 3 fits at two hundred samples and d = 8
        // does not; workgroups grow until every invocation's share fits.
        assert!(TransportShape::lane_iterations(200, 3) <= LANE_BUDGET);
        assert!(TransportShape::lane_iterations(200, 8) > LANE_BUDGET);
        let lavapipe = lavapipe();
        for dims in 1..=8 {
            for max_class in [2u32, 16, 100, 744, 2048] {
                let shape = TransportShape::choose(&lavapipe, max_class, dims, 1 << 15, None, None);
                assert!(
                    shape.fits_loop_budget(&lavapipe, max_class, dims),
                    "d = {dims}, {max_class}: {shape:?}"
                );
                assert!(shape.per_lane || dims > 2 || max_class > LOOP_BUDGET / 2, "{dims} {max_class}");
            }
        }
        // Per lane, d <= 2: classes past LANE_MAX that all fit the budget get a
        // limit that holds them (the paper's tile, 2326: 2560), so no
        // large-class stage; 256x256x64's 3372 does not fit, and keeps 2048.
        assert_eq!(TransportShape::lane_limit_for(1408, 2), LANE_MAX);
        assert_eq!(TransportShape::lane_limit_for(2326, 2), 2560);
        assert_eq!(TransportShape::lane_limit_for(2326, 1), 2560);
        assert!(TransportShape::lane_iterations(2560, 2) <= LANE_BUDGET);
        assert_eq!(TransportShape::lane_limit_for(3372, 2), LANE_MAX);
        assert!(TransportShape::lane_iterations(3584, 2) > LANE_BUDGET);
        let paper = TransportShape::choose(&lavapipe, 2326, 2, 1 << 20, None, None);
        assert!(paper.per_lane && paper.local_max == 2560, "{paper:?}");
        assert!(paper.fits_loop_budget(&lavapipe, 2326, 2));
        // Per lane, d >= 3 sorts the classes up to its limit, the largest whose
        // loops fit, and leaves the rest to the large-class stage.
        assert_eq!(TransportShape::lane_limit(1), LANE_MAX);
        assert_eq!(TransportShape::lane_limit(2), LANE_MAX);
        for (dims, near) in [(3, 207), (4, 113), (8, 7)] {
            let limit = TransportShape::lane_limit(dims);
            assert_eq!(TransportShape::lane_limit_for(2326, dims), limit);
            assert!(TransportShape::lane_iterations(limit, dims) <= LANE_BUDGET, "d = {dims}: {limit}");
            assert!(TransportShape::lane_iterations(limit + 1, dims) > LANE_BUDGET, "d = {dims}: {limit}");
            assert!(limit.abs_diff(near) <= near / 20, "d = {dims}: limit {limit}, documented about {near}");
            let whole = TransportShape::choose(&lavapipe, limit, dims, 1 << 15, None, None);
            assert!(whole.per_lane && whole.local_max == limit, "d = {dims}: {whole:?}");
            let split = TransportShape::choose(&lavapipe, limit + 1, dims, 1 << 15, None, None);
            assert!(!split.per_lane && split.local_max == LOCAL_MAX, "d = {dims}: {split:?}");
            let forced =
                TransportShape::choose(&lavapipe, 1408, dims, 1 << 15, Some(TransportKind::PerLane), None);
            assert!(forced.per_lane && forced.local_max == limit, "d = {dims}: {forced:?}");
        }
        // Large classes of d = 8 pass the large-class pass's budget: refused.
        let shape = TransportShape::choose(&lavapipe, 20_000, 8, 1 << 15, None, None);
        assert!(!shape.fits_loop_budget(&lavapipe, 20_000, 8));
        // A device whose texel views hold fewer texels than the samples: the
        // workgroup transport, which reads them from the storage buffer.
        let small_views = DeviceInfo { max_texel_buffer_elements: 65536, ..lavapipe.clone() };
        assert!(TransportShape::choose(&small_views, 744, 2, 65536, None, None).per_lane);
        assert!(!TransportShape::choose(&small_views, 744, 2, 65537, None, None).per_lane);
        // Nor without subgroup votes.
        let no_vote = DeviceInfo { subgroup_vote: false, ..lavapipe.clone() };
        assert!(!TransportShape::choose(&no_vote, 744, 2, 1 << 15, None, None).per_lane);
        // Every shape lavapipe gets fits its 32 KiB of shared memory; 2048
        // invocations would not.
        for dims in 1..=8 {
            for max_class in [2u32, 744, 2048, 100_000] {
                let shape = TransportShape::choose(&lavapipe, max_class, dims, 1 << 15, None, None);
                let bytes = TransportShape::shared_bytes(shape.workgroup, LOCAL_MAX);
                assert!(bytes <= lavapipe.max_shared_memory, "d = {dims}, {max_class}: {shape:?}");
            }
        }
        assert!(TransportShape::shared_bytes(2048, LOCAL_MAX) > lavapipe.max_shared_memory);
        // A device with Vulkan's least shared memory (16 KiB) refuses the shape
        // by name; the per-lane transport, which takes none, passes.
        let small = DeviceInfo { max_shared_memory: 16384, ..lavapipe.clone() };
        let gpu_shape = TransportShape::choose(&small, 744, 2, 1 << 15, Some(TransportKind::Workgroup), None);
        let err = gpu_shape.fits_shared_memory(&small).unwrap_err().to_string();
        assert!(err.contains("maxComputeSharedMemorySize") && err.contains("16384"), "{err}");
        let lane = TransportShape::choose(&small, 744, 2, 1 << 15, Some(TransportKind::PerLane), None);
        assert!(lane.fits_shared_memory(&small).is_ok());
        // The second pass: on a GPU with 48 KiB of shared memory, classes past
        // 2048 up to 4096 (the paper's tile: 2326; 256x256x64: 3372); past
        // 4096 the rest go to the large-class stage; none where every class
        // fits, and none on lavapipe (a CPU implementation).
        let gpu = DeviceInfo {
            device_type: ash::vk::PhysicalDeviceType::DISCRETE_GPU,
            subgroup_size: 32,
            max_shared_memory: 49152,
            ..lavapipe.clone()
        };
        for (max_class, defer) in [(1408u32, 0u32), (2326, 4096), (3372, 4096), (5000, 4096)] {
            let mut shape = TransportShape::choose(&gpu, max_class, 2, 1 << 15, None, None);
            shape.defer_auto(&gpu, max_class);
            assert_eq!((shape.local_max, shape.defer_max), (LOCAL_MAX, defer), "{max_class}");
            assert!(shape.fits_shared_memory(&gpu).is_ok(), "{shape:?}");
            assert!(defer == 0 || shape.describe().contains("up to 4096 in a second pass of 256"));
            let mut cpu = TransportShape::choose(
                &lavapipe,
                max_class,
                2,
                1 << 15,
                Some(TransportKind::Workgroup),
                None,
            );
            cpu.defer_auto(&lavapipe, max_class);
            assert_eq!(cpu.defer_max, 0);
        }
        let mut small = TransportShape::choose(&gpu, 3000, 2, 1 << 15, None, None);
        small.defer_auto(&DeviceInfo { max_shared_memory: 32768, ..gpu.clone() }, 3000);
        assert_eq!(small.defer_max, 0, "4096 does not fit 32 KiB with 256 invocations");
        // A bitonic network of 2048 on 8 invocations: 66 stages of 1024 pairs,
        // 128 for each invocation.
        assert!(TransportShape::slice_iterations(2048, 8) >= 66 * 128);
    }
}
