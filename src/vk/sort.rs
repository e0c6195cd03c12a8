//! A reusable global LSD radix sort of 32-bit keys with 32-bit payloads, for any
//! size up to its capacity, on any context (a host's wrapped device included).
//!
//! 8 bits per pass; each pass is histogram -> two-dispatch exclusive scan ->
//! stable scatter (`glsl/sort/`): reduce-then-scan, so no workgroup ever waits on
//! another (correct on lavapipe, which does not guarantee forward progress between
//! workgroups). Small sorts cut the fixed cost of the dispatches (`SortPath`):
//! up to `TAIL_MAX_BLOCKS` blocks the histogram's last workgroup to finish scans
//! the histogram itself (`radix_histogram.comp`'s `TAIL` variant: it waits on
//! no one, it only counts who is done), two dispatches per pass instead of four;
//! a count the host knows fits one block takes one dispatch per pass
//! (`radix_small.comp`: the whole pass in one workgroup). A decoupled look-back
//! path (`SortPath::LookBack`: one read of the keys for every pass's digit counts,
//! then one dispatch per pass, five in all for 32-bit keys, against sixteen) is
//! there for GPUs, where a started workgroup goes on running while another waits
//! on it; a caller sets it, or has it chosen at run time where it sorts faster
//! than the block passes on the device (`sort_choice`: timed there). Equal keys
//! keep their input order (stable), so a sort by several
//! keys is a sequence of sorts, least significant first. The element count is
//! set by the host (`SortCount::Host`) or read on the GPU from the first word of
//! a buffer a producer pass writes (`SortCount::device`): then the sort sizes its
//! own dispatches from it (indirect).

use ash::vk;
use bytemuck::{Pod, Zeroable};

use super::buffer::{Buffer, BufferTarget, Location};
use super::commands::{barrier, copy_raw, zero, Recording};
use super::context::Context;
use super::error::{Error, Result};
use super::pipeline::{ComputeDesc, ComputePipeline};
use super::shaders;
use super::texel_view::TexelView;
use super::timer::Timer;

/// Binding indices of `glsl/sort/bindings.glsl`.
pub mod binding {
    pub const COUNT: u32 = 0;
    pub const KEYS_IN: u32 = 1;
    pub const VALS_IN: u32 = 2;
    pub const KEYS_OUT: u32 = 3;
    pub const VALS_OUT: u32 = 4;
    pub const HIST: u32 = 5;
    pub const PARTIALS: u32 = 6;
    pub const ARGS: u32 = 7;
    pub const LOOK_BACK: u32 = 8;
    /// The input keys and payloads as uniform texel buffers (the lanes path).
    pub const KEYS_TEXELS: u32 = 9;
    pub const VALS_TEXELS: u32 = 10;
    /// Bindings in the layout.
    pub const BINDINGS: u32 = 11;
    /// The uniform texel buffer bindings.
    pub const TEXELS: [u32; 2] = [KEYS_TEXELS, VALS_TEXELS];
    /// The texel buffers with their variables' names in GLSL.
    pub const TEXEL_VARIABLES: [(&str, u32); 2] =
        [("keys_texels", KEYS_TEXELS), ("vals_texels", VALS_TEXELS)];

    /// Every storage binding with the name of its block in GLSL.
    pub const BLOCKS: [(&str, u32); 9] = [
        ("SortCount", COUNT),
        ("KeysIn", KEYS_IN),
        ("ValsIn", VALS_IN),
        ("KeysOut", KEYS_OUT),
        ("ValsOut", VALS_OUT),
        ("Hist", HIST),
        ("Partials", PARTIALS),
        ("SortArgs", ARGS),
        ("LookBack", LOOK_BACK),
    ];
}

/// `RadixPush` in `glsl/sort/bindings.glsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct RadixPush {
    pub shift: u32,
    pub blocks: u32,
    pub chunks: u32,
    pub passes: u32,
}

/// Offsets of the indirect dispatches `radix_args.comp` writes.
const ARG_BLOCKS: u64 = 0;
const ARG_CHUNKS: u64 = 16;

/// Most blocks whose histogram the last histogram workgroup scans itself
/// (256 x 32 entries, four scan chunks of 2048: 65536 pairs in 2048-pair blocks).
/// A small sort of 64k pairs is within it, and the one workgroup's scan
/// stays at four chunks. The limit is set where the tail scan stops paying on
/// the implementations measured (BENCHMARKS.md, the radix sort).
pub const TAIL_MAX_BLOCKS: u32 = 32;

/// Which passes a sort records.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SortPath {
    /// On GPUs, one workgroup per pass for a count the host knows fits one
    /// block; the histogram's tail scan up to `TAIL_MAX_BLOCKS` blocks; the
    /// four block passes beyond. On CPU implementations, `Lanes`.
    #[default]
    Auto,
    /// Histogram, two scan dispatches and scatter over blocks, whatever the count.
    Blocks,
    /// The histogram's tail scan and the scatter (up to `TAIL_MAX_BLOCKS`
    /// blocks; past it, `Blocks`).
    Tail,
    /// One workgroup per pass whenever the host knows the count (for tests and
    /// benchmarks: it takes any count, slowly past a few hundred thousand).
    Single,
    /// Decoupled look-back: one read of the keys counts every pass's digits
    /// (`radix_digits.comp`), then one dispatch per pass (`radix_onesweep.comp`),
    /// in which a workgroup waits on the blocks that started before it. Only for
    /// devices on which a started workgroup goes on running while another waits
    /// (GPUs). Not lavapipe with several threads: there a workgroup can wait
    /// past lavapipe's 65535 loop iterations per invocation, which ends its
    /// wait silently and leaves its block misplaced (on busy cores, now and
    /// then; every such sort had an invocation cut at the cap). `Auto`
    /// never takes it; `sort_choice::choose_sort_path` picks it on a GPU where it
    /// was timed faster there (the optimizer's large-class stage does so).
    /// Tested on lavapipe with one thread (`crates/fsot-cli/tests/gpu_sort_look_back.rs`,
    /// `tests/gpu_sort_choice.rs`).
    LookBack,
    /// A run of `LANE_RUN` pairs an invocation, counted and placed by that
    /// invocation alone in input order (`radix_lane_histogram.comp`,
    /// `radix_lane_scatter.comp`), between the same two scan dispatches: no
    /// barrier, ballot or shared memory. For CPU implementations, which run a
    /// workgroup as the lanes of a vector (`Auto` takes it there); correct on
    /// any device.
    Lanes,
}

/// Pairs one invocation of the lanes path counts and places (`SortPath::Lanes`):
/// long enough that a run's fixed work is small beside its pairs, and in the
/// middle of the range (2048 to 8192) over which the run length hardly matters.
pub const LANE_RUN: u32 = 4096;

/// Bytes before the look-back status words in the `LookBack` buffer: four
/// tickets and four passes' 256 digit counts.
const LOOK_BACK_HEAD: u64 = 16 + 4 * 256 * 4;

/// Where the element count comes from.
#[derive(Clone, Copy)]
pub enum SortCount<'a> {
    /// Set by the host (`RadixSort::set_count`).
    Host,
    /// The first u32 of a buffer, written on the GPU before the sort runs
    /// (`SortCount::device`).
    Device(DeviceCount<'a>),
}

/// The buffer a sort reads its count from (`SortCount::device`).
#[derive(Clone, Copy)]
pub struct DeviceCount<'a>(&'a Buffer);

impl<'a> SortCount<'a> {
    /// The count as the first u32 of `buffer`, written on the GPU before each
    /// sort runs.
    ///
    /// # Safety
    /// The sort made with it binds the buffer: `buffer` is a buffer of the
    /// sort's device that outlives the sort, and its first word is at most the
    /// sort's capacity whenever the sort runs (the passes are sized by it).
    pub unsafe fn device(buffer: &'a Buffer) -> Self {
        SortCount::Device(DeviceCount(buffer))
    }
}

/// Workgroups of one dispatch in x that every device runs (the least
/// maxComputeWorkGroupCount Vulkan allows).
const MAX_GROUPS: u64 = 65_535;

/// Launch shape chosen from the device's limits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SortShape {
    pub workgroup: u32,
    pub items: u32,
    pub subgroups: u32,
    /// Pairs per block: workgroup x items.
    pub block: u32,
}

impl SortShape {
    /// The first of (256 x 16), (256 x 8), (128 x 16), (64 x 32), (32 x 64),
    /// (32 x 32) invocations x items whose scatter fits in shared memory
    /// (`fits`); the subgroup size is the device's, never assumed. Lavapipe's
    /// 32 KiB takes 64 x 32 with its 8 lanes (256-bit vectors) and 32 x 64 with
    /// 4 (128-bit vectors, as on ARM64): 2048-pair blocks either way. Larger
    /// blocks mean fewer blocks, a smaller histogram and scan, and less fixed
    /// work per pair, but only pay when there are enough pairs to fill the
    /// device, so 4096-pair blocks are for capacities from 4M (BENCHMARKS.md,
    /// the radix sort).
    pub fn for_device(ctx: &Context, capacity: u32) -> Result<Self> {
        let info = ctx.info();
        Self::for_limits(info.subgroup_size, info.max_workgroup_invocations, info.max_shared_memory, capacity)
    }

    /// `for_device` for a device of these limits.
    pub fn for_limits(subgroup: u32, max_workgroup: u32, max_shared: u32, capacity: u32) -> Result<Self> {
        let candidates: &[(u32, u32)] = if capacity >= 1 << 22 {
            &[(256, 16), (256, 8), (128, 16), (64, 32), (32, 64), (32, 32)]
        } else {
            &[(256, 8), (128, 16), (64, 32), (32, 64), (32, 32)]
        };
        candidates
            .iter()
            .find_map(|&(wg, items)| Self::fits(wg, items, subgroup, max_workgroup, max_shared))
            .ok_or_else(|| {
                Error::VulkanUnavailable(format!(
                    "the radix sort does not fit this device's limits (subgroup {}, shared memory {max_shared} bytes)",
                    subgroup.max(1)
                ))
            })
    }

    /// `workgroup` invocations of `items` pairs each, if a device of these limits
    /// runs it: whole subgroups (the ranking walks a block subgroup by
    /// subgroup), items a positive multiple of the scatter's 8 keys per round,
    /// the workgroup within the device's, and the shared memory of its largest
    /// pass, the small sort (digit counters per subgroup, five digit tables, the
    /// staged block), within its.
    pub fn fits(
        workgroup: u32,
        items: u32,
        subgroup: u32,
        max_workgroup: u32,
        max_shared: u32,
    ) -> Option<Self> {
        let subgroup = subgroup.max(1);
        let subgroups = workgroup / subgroup;
        let block = workgroup.checked_mul(items)?;
        let shared = subgroups as u64 * 256 * 4 + 5 * 256 * 4 + block as u64 * 8;
        let ok = workgroup > 0
            && workgroup % subgroup == 0
            && items > 0
            && items % 8 == 0
            && workgroup <= max_workgroup
            && shared <= max_shared as u64;
        ok.then_some(Self { workgroup, items, subgroups, block })
    }

    /// The most pairs one sort of this shape can take: the scan's two levels
    /// cover block x block / 256 blocks.
    pub fn scan_capacity(&self) -> u64 {
        let block = self.block as u64;
        (block * block / 256) * block
    }

    /// The most pairs one sort of this shape can take on any device: its
    /// scan's, and 65535 blocks (one dispatch's workgroups in x on every device).
    pub fn capacity(&self) -> u64 {
        self.scan_capacity().min(MAX_GROUPS * self.block as u64)
    }
}

/// One path's pipelines for a radix pass: histogram, the two scan dispatches
/// (None where the histogram scans itself), scatter.
struct PassPipelines<'a> {
    histogram: &'a ComputePipeline,
    scan: Option<(&'a ComputePipeline, &'a ComputePipeline)>,
    scatter: &'a ComputePipeline,
}

/// A pass's dispatch sizes with the count on the host: workgroups of the
/// histogram and scatter, blocks (or runs) in the histogram, scan chunks.
#[derive(Clone, Copy)]
struct PassSize {
    groups: u32,
    blocks: u32,
    chunks: u32,
}

/// The passes of `SortPath::Lanes`: a workgroup of the device's subgroup size,
/// `LANE_RUN` pairs an invocation (the scan's chunks of `LANE_RUN` entries).
struct LanePasses {
    workgroup: u32,
    histogram: ComputePipeline,
    scan_reduce: ComputePipeline,
    scan_apply: ComputePipeline,
    scatter: ComputePipeline,
    /// With a device count: the dispatch sizes for runs, as `RadixSort::args`.
    args: Option<(ComputePipeline, Buffer)>,
}

/// A reusable, stable radix sort of 32-bit keys with 32-bit payloads, on the
/// device: `sort_pairs` from the host, or `record` into a command buffer
/// (yours through `Recording`), on the sort's own buffers (`keys[0]`,
/// `vals[0]`) or a host's (`bind_pairs`). Its passes follow the device and
/// the count (one workgroup, a tail scan, block passes, or a run a lane on CPU
/// implementations); the result is the same whichever.
pub struct RadixSort {
    pub(crate) capacity: u32,
    /// Which passes `record` uses (forced by tests and benchmarks).
    #[cfg(feature = "internals")]
    #[doc(hidden)]
    pub path: SortPath,
    #[cfg(not(feature = "internals"))]
    pub(crate) path: SortPath,
    shape: SortShape,
    blocks: u32,
    /// The host-written count (`SortCount::Host`).
    host_count: Option<Buffer>,
    /// Ping-pong key and payload buffers; input and result are in index 0.
    pub(crate) keys: [Buffer; 2],
    /// The payloads beside `keys`, likewise.
    pub(crate) vals: [Buffer; 2],
    histogram: ComputePipeline,
    scan_reduce: ComputePipeline,
    scan_apply: ComputePipeline,
    scatter: ComputePipeline,
    histogram_tail: ComputePipeline,
    single: ComputePipeline,
    digits: ComputePipeline,
    onesweep: ComputePipeline,
    lanes: LanePasses,
    /// With a device count: the pass that sizes the dispatches, and its output.
    args: Option<(ComputePipeline, Buffer)>,
    // Used through the descriptor sets; dropped after the pipelines.
    _hist: Buffer,
    partials: Buffer,
    look_back: Buffer,
    /// The texel views of `keys` and `vals` per descriptor set (the lanes
    /// path's reads), where the device holds them.
    views: Option<[[TexelView; 2]; 2]>,
    /// A host's key and payload buffers in place of `keys[0]` and `vals[0]`
    /// (`bind_pairs`).
    host_pairs: Option<[vk::Buffer; 2]>,
    ctx: Context,
}

impl RadixSort {
    /// The most pairs one sort takes.
    pub fn capacity(&self) -> u32 {
        self.capacity
    }

    /// The sort's own key buffer: the input of `sort_pairs` and `record`
    /// without `bind_pairs`, and where the sorted keys land.
    pub fn keys(&self) -> &Buffer {
        &self.keys[0]
    }

    /// The payloads beside `keys`, likewise.
    pub fn vals(&self) -> &Buffer {
        &self.vals[0]
    }

    /// Uploads pairs into the sort's own buffers (`keys`, `vals`) for a
    /// `record` without `bind_pairs`: at most `capacity` of them.
    pub fn upload_pairs(&mut self, keys: &[u32], vals: &[u32]) -> Result<()> {
        if keys.len() != vals.len() {
            return Err(Error::invalid(format!("{} keys but {} payloads", keys.len(), vals.len())));
        }
        if keys.len() > self.capacity as usize {
            return Err(Error::invalid(format!("{} pairs, the sort takes {}", keys.len(), self.capacity)));
        }
        self.keys[0].upload(keys)?;
        self.vals[0].upload(vals)
    }

    /// Largest capacity: the scan's two levels cover block x block / 256 blocks,
    /// a dispatch takes at most 65535 blocks (every device's
    /// maxComputeWorkGroupCount reaches that), and each key buffer must fit one
    /// binding.
    pub fn max_capacity(ctx: &Context) -> u32 {
        let by_shape = SortShape::for_device(ctx, u32::MAX).map(|s| s.capacity()).unwrap_or(1 << 24);
        Self::capacity_limit(ctx, by_shape)
    }

    fn capacity_limit(ctx: &Context, by_shape: u64) -> u32 {
        let by_binding = ctx.info().max_storage_buffer_range / 4;
        by_shape.min(by_binding).min(u32::MAX as u64) as u32
    }

    /// A sort for up to `capacity` pairs, in the device's shape (`SortShape::for_device`).
    pub fn new(ctx: &Context, capacity: u32, count: SortCount) -> Result<Self> {
        let shape = SortShape::for_device(ctx, capacity.max(1))?;
        Self::with_shape(ctx, capacity, count, shape)
    }

    internal! {
        /// A sort of a chosen shape (experiments, tests): refused where the device
        /// cannot run it (`SortShape::fits`) or its scan cannot cover `capacity`.
        fn with_shape(ctx: &Context, capacity: u32, count: SortCount, shape: SortShape) -> Result<Self> {
            Self::build(ctx, capacity, count, shape, true)
        }
    }

    /// A sort in the device's shape whose lanes path reads its input as
    /// storage, as where a texel view could not hold the capacity: the sort
    /// `bind_pairs` takes, to sort a host's buffers.
    pub fn with_storage_reads(ctx: &Context, capacity: u32, count: SortCount) -> Result<Self> {
        let shape = SortShape::for_device(ctx, capacity.max(1))?;
        Self::build(ctx, capacity, count, shape, false)
    }

    fn build(ctx: &Context, capacity: u32, count: SortCount, shape: SortShape, texels: bool) -> Result<Self> {
        let info = ctx.info();
        if SortShape::fits(
            shape.workgroup,
            shape.items,
            info.subgroup_size,
            info.max_workgroup_invocations,
            info.max_shared_memory,
        ) != Some(shape)
        {
            return Err(Error::invalid(format!(
                "the sort shape {} x {} does not fit {} (subgroup {}, shared memory {} bytes)",
                shape.workgroup, shape.items, info.name, info.subgroup_size, info.max_shared_memory
            )));
        }
        if !info.subgroup_ballot || !info.subgroup_arithmetic {
            return Err(Error::VulkanUnavailable(format!(
                "{} lacks subgroup ballot or arithmetic in compute",
                info.name
            )));
        }
        let max = Self::capacity_limit(ctx, shape.capacity());
        if capacity > max {
            return Err(Error::invalid(format!(
                "cannot sort {capacity} pairs on {}: at most {max} (binding, scan or dispatch limit)",
                ctx.info().name
            )));
        }
        let capacity = capacity.max(1);
        let blocks = capacity.div_ceil(shape.block);
        let chunks = (256 * blocks).div_ceil(shape.block);
        let bytes = capacity as u64 * 4;
        let host_count = match count {
            SortCount::Device(_) => None,
            SortCount::Host => {
                // A count of 0 until `set_count`: never a count past the buffers.
                Some(Buffer::with_data(ctx, &[0u32; 4], Location::Upload, "sort-count")?)
            }
        };
        let pair = |name: &str| -> Result<[Buffer; 2]> {
            Ok([
                Buffer::new(ctx, bytes, Location::Device, &format!("{name}-0"))?,
                Buffer::new(ctx, bytes, Location::Device, &format!("{name}-1"))?,
            ])
        };
        let (keys, vals) = (pair("sort-keys")?, pair("sort-vals")?);
        // The histogram and the scan's partials hold the blocks' counts or the
        // lanes path's runs', whichever are more (a shape's block may pass LANE_RUN).
        let runs = capacity.div_ceil(LANE_RUN);
        let hist_entries = 256 * blocks.max(runs) as u64;
        let partial_entries = chunks.max((256 * runs).div_ceil(LANE_RUN)) as u64;
        let hist = Buffer::new(ctx, hist_entries * 4, Location::Device, "sort-hist")?;
        let partials = Buffer::new(ctx, partial_entries * 4, Location::Device, "sort-partials")?;
        let look_back_bytes = LOOK_BACK_HEAD + 256 * blocks as u64 * 4;
        let look_back = Buffer::new(ctx, look_back_bytes, Location::Device, "sort-look-back")?;
        let spec = [shape.workgroup, shape.items, shape.subgroups, shape.block];
        let lane_group = info.subgroup_size.clamp(1, LANE_RUN);
        let lane_spec = [lane_group, LANE_RUN / lane_group, 1, LANE_RUN];
        // `full_subgroups` for the passes that rank a block subgroup by subgroup.
        let pass_with = |spirv: &[u8], spec: &[u32], full_subgroups: bool| {
            ComputePipeline::new(
                ctx,
                &ComputeDesc {
                    spirv,
                    bindings: binding::BINDINGS,
                    push_bytes: std::mem::size_of::<RadixPush>() as u32,
                    spec,
                    sets: 2,
                    images: &[],
                    uniforms: &[],
                    texels: &binding::TEXELS,
                    full_subgroups,
                },
            )
        };
        let pass = |spirv: &[u8]| pass_with(spirv, &spec, false);
        let ranking = |spirv: &[u8]| pass_with(spirv, &spec, true);
        let (histogram, scan_reduce, scan_apply, scatter, histogram_tail, single) = (
            pass(shaders::RADIX_HISTOGRAM)?,
            pass(shaders::SCAN_REDUCE)?,
            pass(shaders::SCAN_APPLY)?,
            ranking(shaders::RADIX_SCATTER)?,
            pass(shaders::RADIX_HISTOGRAM_TAIL)?,
            ranking(shaders::RADIX_SMALL)?,
        );
        let (digits, onesweep) = (pass(shaders::RADIX_DIGITS)?, ranking(shaders::RADIX_ONESWEEP)?);
        let count_buffer: &Buffer = match (count, &host_count) {
            (SortCount::Device(DeviceCount(c)), _) => c,
            (SortCount::Host, Some(own)) => own,
            (SortCount::Host, None) => return Err(Error::invalid("the sort's count buffer is missing")),
        };
        // With the count only on the GPU: the pass that sizes the dispatches
        // from it, `per_group` blocks a histogram and scatter workgroup.
        let args_pass =
            |block: u32, per_group: u32, name: &str| -> Result<Option<(ComputePipeline, Buffer)>> {
                let SortCount::Device(_) = count else { return Ok(None) };
                let buffer = Buffer::new(ctx, 32, Location::Device, name)?;
                let spec = [block, per_group];
                let desc = ComputeDesc {
                    spirv: shaders::RADIX_ARGS,
                    bindings: binding::BINDINGS,
                    push_bytes: 0,
                    spec: &spec,
                    sets: 1,
                    images: &[],
                    uniforms: &[],
                    texels: &binding::TEXELS,
                    full_subgroups: false,
                };
                let pipeline = ComputePipeline::new(ctx, &desc)?;
                // SAFETY: the sort holds the argument buffer with the pipeline and
                // the count buffer as long as it, and dispatches only through itself.
                unsafe { pipeline.bind(0, &[(binding::COUNT, count_buffer), (binding::ARGS, &buffer)])? };
                Ok(Some((pipeline, buffer)))
            };
        let args = args_pass(shape.block, 1, "sort-indirect-args")?;
        // The lanes path reads its input through texel views where the device
        // holds that many texels in one, else as storage.
        let views = if texels && u64::from(capacity) <= info.max_texel_buffer_elements {
            let view = |b: &Buffer| TexelView::new(ctx, b, vk::Format::R32_UINT, 4);
            Some([[view(&keys[0])?, view(&vals[0])?], [view(&keys[1])?, view(&vals[1])?]])
        } else {
            None
        };
        let (lane_histogram, lane_scatter) = match views {
            Some(_) => (shaders::RADIX_LANE_HISTOGRAM, shaders::RADIX_LANE_SCATTER),
            None => (shaders::RADIX_LANE_HISTOGRAM_STORAGE, shaders::RADIX_LANE_SCATTER_STORAGE),
        };
        let lanes = LanePasses {
            workgroup: lane_group,
            histogram: pass_with(lane_histogram, &lane_spec, false)?,
            scan_reduce: pass_with(shaders::SCAN_REDUCE, &lane_spec, false)?,
            scan_apply: pass_with(shaders::SCAN_APPLY, &lane_spec, false)?,
            scatter: pass_with(lane_scatter, &lane_spec, false)?,
            args: args_pass(LANE_RUN, lane_group, "sort-lane-indirect-args")?,
        };
        for s in 0..2 {
            let set = [
                (binding::COUNT, count_buffer),
                (binding::KEYS_IN, &keys[s]),
                (binding::VALS_IN, &vals[s]),
                (binding::KEYS_OUT, &keys[1 - s]),
                (binding::VALS_OUT, &vals[1 - s]),
                (binding::HIST, &hist),
                (binding::PARTIALS, &partials),
                (binding::LOOK_BACK, &look_back),
            ];
            for p in [
                &histogram,
                &scan_reduce,
                &scan_apply,
                &scatter,
                &histogram_tail,
                &single,
                &digits,
                &onesweep,
                &lanes.histogram,
                &lanes.scan_reduce,
                &lanes.scan_apply,
                &lanes.scatter,
            ] {
                // SAFETY: the sort holds its buffers and views as long as its
                // pipelines, and dispatches them only through itself.
                unsafe {
                    p.bind(s, &set)?;
                    if let Some(views) = &views {
                        p.bind_texels(
                            s,
                            &[(binding::KEYS_TEXELS, &views[s][0]), (binding::VALS_TEXELS, &views[s][1])],
                        )?;
                    }
                }
            }
        }
        Ok(Self {
            capacity,
            path: SortPath::Auto,
            shape,
            blocks,
            host_count,
            keys,
            vals,
            histogram,
            scan_reduce,
            scan_apply,
            scatter,
            histogram_tail,
            single,
            digits,
            onesweep,
            lanes,
            args,
            _hist: hist,
            partials,
            look_back,
            views,
            host_pairs: None,
            ctx: ctx.clone(),
        })
    }

    internal! {
        /// The launch shape chosen for the device.
        fn shape(&self) -> SortShape {
            self.shape
        }
    }

    /// Sets the element count (`SortCount::Host` sorts).
    pub fn set_count(&mut self, n: u32) -> Result<()> {
        if n > self.capacity {
            return Err(Error::invalid(format!("{n} pairs exceed the sort's capacity {}", self.capacity)));
        }
        let own =
            self.host_count.as_mut().ok_or_else(|| Error::invalid("this sort reads its count on the GPU"))?;
        own.upload(&[n])
    }

    /// Records a sort of `keys[0]`/`vals[0]` by their low `bits` bits (1 to 32;
    /// whole 8-bit digits, so by the low 8 x ceil(bits / 8) bits: bits above
    /// `bits` should be zero);
    /// the result is in `keys[0]`/`vals[0]`. Barriers included before and after.
    /// `known`: the element count when the host knows it (smaller dispatches;
    /// at most the capacity); None: the count is only on the GPU.
    ///
    /// # Safety
    /// `cmd` records on this sort's device, and the sort (with every buffer
    /// bound to it) outlives the execution of the recorded commands: a sort
    /// dropped before its recording is submitted and waited for leaves the
    /// commands reading freed objects.
    pub unsafe fn record(&self, cmd: Recording<'_>, bits: u32, known: Option<u32>) {
        self.record_stamped(cmd, bits, known, None)
    }

    /// Does a sort of `known` pairs take the single-workgroup pass?
    pub fn single_pass(&self, known: Option<u32>) -> bool {
        match (self.path, known) {
            (SortPath::Single, Some(_)) => true,
            (SortPath::Auto, Some(n)) => n <= self.shape.block && !self.ctx.info().is_cpu(),
            _ => false,
        }
    }

    /// Does a sort of `known` pairs (None: up to the capacity) scan its
    /// histogram in the histogram's last workgroup?
    pub fn tail_scan(&self, known: Option<u32>) -> bool {
        let blocks = known.unwrap_or(self.capacity).div_ceil(self.shape.block).max(1);
        let wanted = matches!(self.path, SortPath::Auto | SortPath::Tail) && !self.lanes_path();
        wanted && blocks <= TAIL_MAX_BLOCKS
    }

    internal! {
        /// As `record`; with a timer, stamps 0..=4 x passes: before the first
        /// dispatch, then after each of a pass's histogram, scan reduce, scan apply
        /// and scatter (with the tail scan, the three after the histogram: the scan
        /// counts in it; on the single-workgroup path, the three before its one
        /// dispatch: all its time counts as scatter).
        fn record_timed(&self, cmd: Recording<'_>, bits: u32, known: Option<u32>, timer: Option<&Timer>) {
            self.record_stamped(cmd, bits, known, timer)
        }
    }

    fn record_stamped(&self, cmd: Recording<'_>, bits: u32, known: Option<u32>, timer: Option<&Timer>) {
        // The buffers hold the capacity: a larger count would size the passes past them.
        let known = known.map(|n| n.min(self.capacity));
        let stamp = |i: u32| {
            if let Some(t) = timer {
                t.stamp(cmd, i);
            }
        };
        let passes = bits.clamp(1, 32).div_ceil(8);
        barrier(cmd);
        if self.single_pass(known) {
            stamp(0);
            for pass in 0..passes {
                let push = RadixPush { shift: 8 * pass, blocks: 0, chunks: 0, passes: 0 };
                (1..4).for_each(|i| stamp(i + 4 * pass));
                self.single.dispatch(cmd, (pass % 2) as usize, [1, 1, 1], bytemuck::bytes_of(&push));
                barrier(cmd);
                stamp(4 + 4 * pass);
            }
            self.finish_odd(cmd, passes);
            return;
        }
        if self.lanes_path() {
            self.record_lanes(cmd, passes, known, &stamp);
            return;
        }
        let indirect = self.size_on_device(cmd, known, &self.args);
        let blocks = match known {
            Some(n) => n.div_ceil(self.shape.block).clamp(1, self.blocks),
            None => self.blocks,
        };
        let chunks = (256 * blocks).div_ceil(self.shape.block);
        if self.path == SortPath::LookBack {
            self.record_look_back(cmd, passes, blocks, indirect, &stamp);
            return;
        }
        let tail = self.tail_scan(known);
        if tail {
            // The finished-workgroup count starts at zero.
            zero(cmd, &self.partials, 0, 4);
            barrier(cmd);
        }
        let pipelines = PassPipelines {
            histogram: if tail { &self.histogram_tail } else { &self.histogram },
            scan: (!tail).then_some((&self.scan_reduce, &self.scan_apply)),
            scatter: &self.scatter,
        };
        let size = PassSize { groups: blocks, blocks, chunks };
        self.record_passes(cmd, passes, &pipelines, size, indirect, &stamp);
    }

    /// With the count only on the GPU (`known` None), records the path's
    /// `args` pass, which sizes every later dispatch from it, and returns its
    /// output for the indirect dispatches.
    fn size_on_device<'a>(
        &self,
        cmd: Recording<'_>,
        known: Option<u32>,
        args: &'a Option<(ComputePipeline, Buffer)>,
    ) -> Option<&'a Buffer> {
        let (None, Some((pipeline, buffer))) = (known, args) else { return None };
        pipeline.dispatch(cmd, 0, [1, 1, 1], &[]);
        barrier(cmd);
        Some(buffer)
    }

    /// Records `passes` radix passes of histogram, scan (unless the histogram
    /// scans itself) and scatter; stamps as `record_timed` (with the tail
    /// scan, the three after the histogram: the scan counts in it).
    fn record_passes(
        &self,
        cmd: Recording<'_>,
        passes: u32,
        p: &PassPipelines,
        size: PassSize,
        indirect: Option<&Buffer>,
        stamp: &dyn Fn(u32),
    ) {
        stamp(0);
        for pass in 0..passes {
            let src = (pass % 2) as usize;
            let push = RadixPush { shift: 8 * pass, blocks: size.blocks, chunks: size.chunks, passes: 0 };
            let run = |pipeline: &ComputePipeline, groups: u32, arg: u64| {
                launch(cmd, pipeline, src, indirect, arg, groups, push);
                barrier(cmd);
            };
            run(p.histogram, size.groups, ARG_BLOCKS);
            match p.scan {
                Some((reduce, apply)) => {
                    stamp(1 + 4 * pass);
                    run(reduce, size.chunks, ARG_CHUNKS);
                    stamp(2 + 4 * pass);
                    run(apply, size.chunks, ARG_CHUNKS);
                    stamp(3 + 4 * pass);
                }
                None => (1..4).for_each(|i| stamp(i + 4 * pass)),
            }
            run(p.scatter, size.groups, ARG_BLOCKS);
            stamp(4 + 4 * pass);
        }
        self.finish_odd(cmd, passes);
    }

    /// The passes a sort of `known` pairs takes, in words, with its dispatches
    /// for 32-bit keys.
    pub fn passes(&self, known: Option<u32>) -> (&'static str, u32) {
        if self.path == SortPath::LookBack {
            ("digit counts, then one look-back pass each", 5)
        } else if self.single_pass(known) {
            ("one workgroup per pass", 4)
        } else if self.lanes_path() {
            ("runs counted and placed an invocation each, two scan dispatches", 16)
        } else if self.tail_scan(known) {
            ("histogram with its tail scan, scatter", 8)
        } else {
            ("histogram, two scan dispatches, scatter", 16)
        }
    }

    /// Does a sort take the lanes path? Asked for, or by default on a CPU
    /// implementation, whatever the count: there one invocation sorting a run
    /// alone beats the block passes at every size (BENCHMARKS.md, the radix
    /// sort).
    pub fn lanes_path(&self) -> bool {
        match self.path {
            SortPath::Lanes => true,
            SortPath::Auto => self.ctx.info().is_cpu(),
            _ => false,
        }
    }

    /// The lanes path (`SortPath::Lanes`): per pass, the runs' histogram, the
    /// two scan dispatches and the runs' scatter; stamps as `record_timed`.
    fn record_lanes(&self, cmd: Recording<'_>, passes: u32, known: Option<u32>, stamp: &dyn Fn(u32)) {
        let lanes = &self.lanes;
        let indirect = self.size_on_device(cmd, known, &lanes.args);
        let runs = known.unwrap_or(self.capacity).div_ceil(LANE_RUN).max(1);
        let pipelines = PassPipelines {
            histogram: &lanes.histogram,
            scan: Some((&lanes.scan_reduce, &lanes.scan_apply)),
            scatter: &lanes.scatter,
        };
        let size = PassSize {
            groups: runs.div_ceil(lanes.workgroup),
            blocks: runs,
            chunks: (256 * runs).div_ceil(LANE_RUN),
        };
        self.record_passes(cmd, passes, &pipelines, size, indirect, stamp);
    }

    /// The look-back path (`SortPath::LookBack`): the digit counts of every pass
    /// in one dispatch, then one dispatch per pass; stamps as `record_timed`
    /// (a pass's time counts as scatter).
    fn record_look_back(
        &self,
        cmd: Recording<'_>,
        passes: u32,
        blocks: u32,
        indirect: Option<&Buffer>,
        stamp: &dyn Fn(u32),
    ) {
        let run = |pipeline: &ComputePipeline, set: usize, shift: u32| {
            let push = RadixPush { shift, blocks, chunks: 0, passes };
            launch(cmd, pipeline, set, indirect, ARG_BLOCKS, blocks, push)
        };
        zero(cmd, &self.look_back, 0, vk::WHOLE_SIZE);
        barrier(cmd);
        stamp(0);
        run(&self.digits, 0, 0);
        barrier(cmd);
        for pass in 0..passes {
            if pass > 0 {
                zero(cmd, &self.look_back, LOOK_BACK_HEAD, vk::WHOLE_SIZE);
                barrier(cmd);
            }
            (1..4).for_each(|i| stamp(i + 4 * pass));
            run(&self.onesweep, (pass % 2) as usize, 8 * pass);
            barrier(cmd);
            stamp(4 + 4 * pass);
        }
        self.finish_odd(cmd, passes);
    }

    /// After an odd number of passes the result is in the second buffers:
    /// copied back to the first.
    fn finish_odd(&self, cmd: Recording<'_>, passes: u32) {
        if passes % 2 == 1 {
            let [keys, vals] = self.host_pairs.unwrap_or([self.keys[0].raw, self.vals[0].raw]);
            copy_raw(cmd, self.keys[1].raw, keys, self.keys[1].size, 0);
            copy_raw(cmd, self.vals[1].raw, vals, self.vals[1].size, 0);
            barrier(cmd);
        }
    }

    /// Sorts the host's `keys` and `vals` in place from now on, instead of the
    /// sort's own `keys[0]` and `vals[0]` (which it then leaves alone): the
    /// count, bits and result as `record`. The sort must read its input as
    /// storage (`RadixSort::with_storage_reads`: a host's buffer need not allow
    /// texel views), and each buffer needs STORAGE_BUFFER, TRANSFER_SRC and
    /// TRANSFER_DST usage and room for the sort's capacity from offset 0.
    /// `sort_pairs` is refused from then on (the pairs are the host's).
    ///
    /// # Safety
    /// Each buffer was created on this sort's device with the size and usage its
    /// target states (the checks above trust them), has its memory bound, and
    /// can be used on the sort's queue family; the host keeps both alive for as
    /// long as the sort may record or its recorded commands may run, and no other
    /// work uses them while those commands run; and no submission that uses the
    /// sort is pending when this is called (it rewrites the sort's descriptor
    /// sets).
    pub unsafe fn bind_pairs(&mut self, keys: &BufferTarget, vals: &BufferTarget) -> Result<()> {
        if self.views.is_some() {
            return Err(Error::invalid(
                "a sort on a host's buffers reads them as storage: make it with RadixSort::with_storage_reads",
            ));
        }
        let need = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::TRANSFER_SRC
            | vk::BufferUsageFlags::TRANSFER_DST;
        let bytes = self.capacity as u64 * 4;
        for (what, t) in [("keys", keys), ("payloads", vals)] {
            if t.buffer == vk::Buffer::null() {
                return Err(Error::invalid(format!("the host's {what} buffer handle is null")));
            }
            if !t.usage.contains(need) {
                return Err(Error::invalid(format!(
                    "the host's {what} buffer lacks STORAGE_BUFFER, TRANSFER_SRC or TRANSFER_DST usage"
                )));
            }
            if t.offset != 0 || t.size < bytes {
                return Err(Error::invalid(format!(
                    "the host's {what} buffer must hold the sort's {} pairs ({bytes} bytes) from offset 0; it has {} from {}",
                    self.capacity, t.size, t.offset
                )));
            }
        }
        for p in [
            &self.histogram,
            &self.scan_reduce,
            &self.scan_apply,
            &self.scatter,
            &self.histogram_tail,
            &self.single,
            &self.digits,
            &self.onesweep,
            &self.lanes.histogram,
            &self.lanes.scan_reduce,
            &self.lanes.scan_apply,
            &self.lanes.scatter,
        ] {
            p.bind_raw(0, &[(binding::KEYS_IN, keys.buffer), (binding::VALS_IN, vals.buffer)])?;
            p.bind_raw(1, &[(binding::KEYS_OUT, keys.buffer), (binding::VALS_OUT, vals.buffer)])?;
        }
        self.host_pairs = Some([keys.buffer, vals.buffer]);
        Ok(())
    }

    /// Uploads pairs, sorts them by all 32 bits, reads them back.
    pub fn sort_pairs(&mut self, keys: &[u32], vals: &[u32]) -> Result<(Vec<u32>, Vec<u32>)> {
        self.sort_pairs_by(keys, vals, 32)
    }

    /// Uploads pairs, sorts them stably by the low `bits` bits of their keys
    /// (whole digits, as `record`), reads them back.
    pub fn sort_pairs_by(&mut self, keys: &[u32], vals: &[u32], bits: u32) -> Result<(Vec<u32>, Vec<u32>)> {
        if keys.len() != vals.len() {
            return Err(Error::invalid(format!("{} keys but {} payloads", keys.len(), vals.len())));
        }
        if self.host_pairs.is_some() {
            return Err(Error::invalid("this sort works on a host's buffers (bind_pairs): record it there"));
        }
        let n = u32::try_from(keys.len()).map_err(|_| Error::invalid("too many pairs"))?;
        self.set_count(n)?;
        if n == 0 {
            return Ok((Vec::new(), Vec::new()));
        }
        self.upload_pairs(keys, vals)?;
        // SAFETY: the sort outlives this submission, which is waited for.
        self.ctx.submit(|cmd| unsafe { self.record(cmd, bits, Some(n)) })?;
        Ok((self.keys[0].download(n as usize)?, self.vals[0].download(n as usize)?))
    }
}

/// Records `pipeline` on descriptor set `set` over `groups` workgroups, or,
/// with `indirect`, over the size the GPU wrote at `arg` (the push's block and
/// chunk counts then 0: the shaders derive them from the count, as radix_args
/// does).
fn launch(
    cmd: Recording<'_>,
    pipeline: &ComputePipeline,
    set: usize,
    indirect: Option<&Buffer>,
    arg: u64,
    groups: u32,
    push: RadixPush,
) {
    match indirect {
        Some(args) => {
            let push = RadixPush { blocks: 0, chunks: 0, ..push };
            pipeline.dispatch_indirect(cmd, set, args, arg, bytemuck::bytes_of(&push))
        }
        None => pipeline.dispatch(cmd, set, [groups, 1, 1], bytemuck::bytes_of(&push)),
    }
}

/// The key order of floats on the GPU (`fsot_float_key` in glsl/fsot/common.glsl):
/// -0.0 sorts just before +0.0; NaNs sort beyond the infinities by sign.
pub fn float_key(f: f32) -> u32 {
    let b = f.to_bits();
    if b & 0x8000_0000 != 0 {
        !b
    } else {
        b | 0x8000_0000
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sort_takes_the_largest_block_whose_scatter_fits_the_devices_shared_memory() {
        let shape = |sub, shared, capacity| SortShape::for_limits(sub, 1024, shared, capacity).ok();
        let is =
            |wg, items, subgroups| Some(SortShape { workgroup: wg, items, subgroups, block: wg * items });
        // Lavapipe (32 KiB): 8 lanes on 256-bit vectors, 4 on 128-bit ones (ARM64).
        assert_eq!(shape(8, 32768, 1 << 20), is(64, 32, 8));
        assert_eq!(shape(4, 32768, 1 << 20), is(32, 64, 8));
        // 48 KiB and 32 lanes (NVIDIA); 4096-pair blocks for large sorts only.
        assert_eq!(shape(32, 49152, 1 << 20), is(256, 8, 8));
        assert_eq!(shape(32, 49152, 1 << 24), is(256, 16, 8));
        // Too little shared memory for any block: a clear refusal.
        let err = SortShape::for_limits(4, 1024, 16384, 1 << 20).unwrap_err().to_string();
        assert!(err.contains("subgroup 4") && err.contains("16384"), "{err}");
        // 32 x 32 where 32 x 64 no longer fits: 4 lanes, 24 KiB.
        assert_eq!(shape(4, 24576, 1 << 20), is(32, 32, 8));
    }

    #[test]
    fn a_chosen_sort_shape_fits_only_where_the_device_runs_it() {
        // 32 x 64 at 4 lanes: 8 subgroups' counters (8 KiB), five digit tables
        // (5 KiB), 2048 staged pairs (16 KiB): 29 KiB.
        assert!(SortShape::fits(32, 64, 4, 1024, 29 * 1024).is_some());
        assert!(SortShape::fits(32, 64, 4, 1024, 29 * 1024 - 1).is_none());
        assert!(SortShape::fits(32, 12, 8, 1024, 32768).is_none(), "not a multiple of 8 items");
        assert!(SortShape::fits(32, 0, 8, 1024, 32768).is_none());
        assert!(SortShape::fits(0, 8, 8, 1024, 32768).is_none());
        assert!(SortShape::fits(32, 32, 64, 1024, 49152).is_none(), "not whole subgroups");
        assert!(SortShape::fits(512, 8, 32, 256, 49152).is_none(), "past the device's workgroup");
        // A dispatch of 65535 blocks at most: 4096-pair blocks then cover a
        // block less than their scan's 2^28 pairs.
        let large = SortShape::fits(256, 16, 32, 1024, 49152).unwrap();
        assert_eq!((large.scan_capacity(), large.capacity()), (1 << 28, 65_535 * 4096));
        assert_eq!(SortShape::fits(64, 32, 8, 1024, 32768).unwrap().capacity(), 1 << 25);
        // The scan's two levels: 2048-pair blocks cover 32M pairs, 1024-pair 4M.
        assert_eq!(SortShape::fits(64, 32, 8, 1024, 32768).unwrap().scan_capacity(), 1 << 25);
        assert_eq!(SortShape::fits(32, 32, 4, 1024, 32768).unwrap().scan_capacity(), 1 << 22);
    }
}
