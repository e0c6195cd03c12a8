//! Global LSD radix sort of 32-bit keys with 32-bit payloads on the GPU.
//!
//! 8 bits per pass; each pass is histogram -> two-dispatch exclusive scan ->
//! stable scatter (`glsl/radix_*.comp`, `glsl/scan_*.comp`): reduce-then-scan, so
//! no workgroup ever waits on another (correct on lavapipe, which does not
//! guarantee forward progress between workgroups). Equal keys keep their input
//! order (stable), so a sort by several keys is a sequence of sorts, least
//! significant first. The element count is read from a buffer at run time.

use ash::vk;

use super::buffer::{Buffer, Location};
use super::context::Context;
use super::layout::{Pod, RadixPush};
use super::pipeline::{barrier, copy, submit_and_wait, ComputePipeline};
use super::shaders;
use super::timer::Timer;
use crate::error::{Error, Result};

/// Offsets of the indirect dispatch commands that `sort_args.comp` writes: the
/// sort's blocks, its scan chunks, the large-class gather, one group per class.
pub const ARG_BLOCKS: u64 = 0;
pub const ARG_CHUNKS: u64 = 16;
pub const ARG_GATHER: u64 = 32;
pub const ARG_SEGMENTS: u64 = 48;

/// The pass that sizes dispatches from a count on the GPU, and its output.
pub struct SortArgs {
    pipeline: ComputePipeline,
    pub buffer: Buffer,
}

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
    /// The first of (256 x 16), (256 x 8), (128 x 16), (64 x 32) invocations x
    /// items (a multiple of the scatter's 8 keys per round)
    /// items whose scatter fits in shared memory (per-subgroup digit counters,
    /// four digit tables, the staged block); the subgroup size is the device's,
    /// never assumed. Larger blocks mean fewer blocks, a smaller histogram and
    /// scan, and less fixed work per pair, but only pay when there are enough
    /// pairs to fill the device (on an H100: 7.1 against 6.45 G pairs/s at 16M,
    /// 3.9 against 4.7 at 1M), so 4096-pair blocks are for capacities from 4M.
    pub fn for_device(ctx: &Context, capacity: u32) -> Result<Self> {
        let info = ctx.info();
        let sub = info.subgroup_size.max(1);
        let candidates: &[(u32, u32)] = if capacity >= 1 << 22 {
            &[(256, 16), (256, 8), (128, 16), (64, 32)]
        } else {
            &[(256, 8), (128, 16), (64, 32)]
        };
        for &(wg, items) in candidates {
            let subgroups = wg.div_ceil(sub);
            let block = wg * items;
            let shared = subgroups * 256 * 4 + 4 * 256 * 4 + block * 8;
            if wg <= info.max_workgroup_invocations && shared <= info.max_shared_memory {
                return Ok(Self { workgroup: wg, items, subgroups, block });
            }
        }
        Err(Error::VulkanUnavailable(format!(
            "the radix sort does not fit this device's limits (subgroup {sub}, shared memory {} bytes)",
            info.max_shared_memory
        )))
    }
}

pub struct RadixSort {
    pub capacity: u32,
    shape: SortShape,
    blocks: u32,
    /// Element count (first u32), host-writable, unless an external one is bound.
    pub info: Option<Buffer>,
    /// Ping-pong key and payload buffers; input and result are in index 0.
    pub keys: [Buffer; 2],
    pub vals: [Buffer; 2],
    // Owned here, used through the descriptor sets.
    _hist: Buffer,
    _partials: Buffer,
    histogram: ComputePipeline,
    scan_reduce: ComputePipeline,
    scan_apply: ComputePipeline,
    scatter: ComputePipeline,
    /// Present when the count comes from a GPU buffer: indirect dispatch sizes.
    pub args: Option<SortArgs>,
    ctx: Context,
}

impl RadixSort {
    /// Largest capacity: the scan's two levels cover 2048 x 2048 histogram entries.
    pub fn max_capacity(ctx: &Context) -> u32 {
        let block = SortShape::for_device(ctx, u32::MAX).map(|s| s.block).unwrap_or(2048) as u64;
        let by_scan = (block * block / 256) * block;
        let by_binding = ctx.info().max_storage_buffer_range / 4;
        by_scan.min(by_binding).min(u32::MAX as u64) as u32
    }

    /// A sort for up to `capacity` pairs. `count`: a buffer whose first u32 the
    /// GPU sets to the element count; None: an own host-written one (`set_count`).
    pub fn new(ctx: &Context, capacity: u32, count: Option<&Buffer>) -> Result<Self> {
        let max = Self::max_capacity(ctx);
        if capacity > max {
            return Err(Error::invalid(format!(
                "cannot sort {capacity} pairs on {}: at most {max} (binding or scan limit)",
                ctx.info().name
            )));
        }
        let capacity = capacity.max(1);
        let shape = SortShape::for_device(ctx, capacity)?;
        let block = shape.block;
        let blocks = capacity.div_ceil(block);
        let chunks = (256 * blocks).div_ceil(block);
        let bytes = capacity as u64 * 4;
        let own_info = match count {
            Some(_) => None,
            None => Some(Buffer::new(ctx, 16, Location::Upload, "sort-count")?),
        };
        let keys = [
            Buffer::new(ctx, bytes, Location::Device, "sort-keys-0")?,
            Buffer::new(ctx, bytes, Location::Device, "sort-keys-1")?,
        ];
        let vals = [
            Buffer::new(ctx, bytes, Location::Device, "sort-vals-0")?,
            Buffer::new(ctx, bytes, Location::Device, "sort-vals-1")?,
        ];
        let hist = Buffer::new(ctx, 256 * blocks as u64 * 4, Location::Device, "sort-hist")?;
        let partials = Buffer::new(ctx, chunks as u64 * 4, Location::Device, "sort-partials")?;
        let spec = [shape.workgroup, shape.items, shape.subgroups, shape.block];
        let push = std::mem::size_of::<RadixPush>() as u32;
        let histogram = ComputePipeline::with_sets(ctx, shaders::RADIX_HISTOGRAM, 3, push, &spec, 2)?;
        let scan_reduce = ComputePipeline::new(ctx, shaders::SCAN_REDUCE, 3, push, &spec)?;
        let scan_apply = ComputePipeline::new(ctx, shaders::SCAN_APPLY, 3, push, &spec)?;
        let scatter = ComputePipeline::with_sets(ctx, shaders::RADIX_SCATTER, 6, push, &spec, 2)?;
        let info_buf: &Buffer = match (count, &own_info) {
            (Some(c), _) => c,
            (None, Some(o)) => o,
            (None, None) => unreachable!("own count buffer made above"),
        };
        for s in 0..2 {
            histogram.bind_set(s, &[info_buf, &keys[s], &hist])?;
            scatter.bind_set(s, &[info_buf, &keys[s], &vals[s], &keys[1 - s], &vals[1 - s], &hist])?;
        }
        scan_reduce.bind(&[info_buf, &hist, &partials])?;
        scan_apply.bind(&[info_buf, &hist, &partials])?;
        let args = match count {
            Some(c) => {
                let pipeline = ComputePipeline::new(ctx, shaders::SORT_ARGS, 2, 0, &[block])?;
                let buffer = Buffer::new(ctx, 64, Location::Device, "sort-indirect-args")?;
                pipeline.bind(&[c, &buffer])?;
                Some(SortArgs { pipeline, buffer })
            }
            None => None,
        };
        Ok(Self {
            capacity,
            shape,
            blocks,
            info: own_info,
            keys,
            vals,
            _hist: hist,
            _partials: partials,
            histogram,
            scan_reduce,
            scan_apply,
            scatter,
            args,
            ctx: ctx.clone(),
        })
    }

    pub fn shape(&self) -> SortShape {
        self.shape
    }

    /// Sets the element count in the sort's own count buffer.
    pub fn set_count(&mut self, n: u32) -> Result<()> {
        if n > self.capacity {
            return Err(Error::invalid(format!("{n} pairs exceed the sort's capacity {}", self.capacity)));
        }
        let info = self
            .info
            .as_mut()
            .ok_or_else(|| Error::invalid("this sort reads its count from another buffer"))?;
        info.write(&n.to_ne_bytes())
    }

    /// Records a sort of `keys[0]`/`vals[0]` by their low `bits` bits (1 to 32);
    /// the result is in `keys[0]`/`vals[0]`. Barriers included before and after.
    /// `known`: the element count when the host knows it (smaller dispatches);
    /// None: the count is only in the count buffer, the dispatch covers capacity.
    pub fn record(&self, cmd: vk::CommandBuffer, bits: u32, known: Option<u32>) {
        self.record_timed(cmd, bits, known, None)
    }

    /// As `record`; with a timer, stamps 0..=4 x passes: before the first
    /// dispatch, then after each of a pass's histogram, scan reduce, scan apply
    /// and scatter.
    pub fn record_timed(&self, cmd: vk::CommandBuffer, bits: u32, known: Option<u32>, timer: Option<&Timer>) {
        let stamp = |i: u32| {
            if let Some(t) = timer {
                t.stamp(cmd, i);
            }
        };
        let passes = bits.clamp(1, 32).div_ceil(8);
        barrier(&self.ctx, cmd);
        // With the count only on the GPU, size every dispatch from it (indirect).
        let indirect = match (known, &self.args) {
            (None, Some(args)) => {
                args.pipeline.dispatch(cmd, [1, 1, 1], &[]);
                barrier(&self.ctx, cmd);
                Some(&args.buffer)
            }
            _ => None,
        };
        let blocks = match known {
            Some(n) => n.div_ceil(self.shape.block).clamp(1, self.blocks),
            None => self.blocks,
        };
        let chunks = (256 * blocks).div_ceil(self.shape.block);
        stamp(0);
        for pass in 0..passes {
            let src = (pass % 2) as usize;
            let push = match indirect {
                // 0: the shaders derive both from the count, as sort_args did.
                Some(_) => RadixPush { shift: 8 * pass, blocks: 0, chunks: 0, pad: 0 },
                None => RadixPush { shift: 8 * pass, blocks, chunks, pad: 0 },
            };
            let p = push.bytes();
            let run = |pipeline: &ComputePipeline, set: usize, groups: u32, arg: u64| match indirect {
                Some(args) => pipeline.dispatch_indirect_set(cmd, set, args, arg, p),
                None => pipeline.dispatch_set(cmd, set, [groups, 1, 1], p),
            };
            run(&self.histogram, src, blocks, ARG_BLOCKS);
            barrier(&self.ctx, cmd);
            stamp(1 + 4 * pass);
            run(&self.scan_reduce, 0, chunks, ARG_CHUNKS);
            barrier(&self.ctx, cmd);
            stamp(2 + 4 * pass);
            run(&self.scan_apply, 0, chunks, ARG_CHUNKS);
            barrier(&self.ctx, cmd);
            stamp(3 + 4 * pass);
            run(&self.scatter, src, blocks, ARG_BLOCKS);
            barrier(&self.ctx, cmd);
            stamp(4 + 4 * pass);
        }
        if passes % 2 == 1 {
            copy(&self.ctx, cmd, &self.keys[1], &self.keys[0]);
            copy(&self.ctx, cmd, &self.vals[1], &self.vals[0]);
            barrier(&self.ctx, cmd);
        }
    }

    /// Uploads pairs, sorts them by all 32 bits, reads them back (tests, bench).
    pub fn sort_pairs(&mut self, keys: &[u32], vals: &[u32]) -> Result<(Vec<u32>, Vec<u32>)> {
        assert_eq!(keys.len(), vals.len());
        let n = keys.len() as u32;
        self.set_count(n)?;
        if n == 0 {
            return Ok((Vec::new(), Vec::new()));
        }
        let bytes = n as u64 * 4;
        let mut up_k = Buffer::new(&self.ctx, bytes, Location::Upload, "sort-upload-keys")?;
        let mut up_v = Buffer::new(&self.ctx, bytes, Location::Upload, "sort-upload-vals")?;
        up_k.write(as_bytes(keys))?;
        up_v.write(as_bytes(vals))?;
        let down_k = Buffer::new(&self.ctx, bytes, Location::Readback, "sort-readback-keys")?;
        let down_v = Buffer::new(&self.ctx, bytes, Location::Readback, "sort-readback-vals")?;
        submit_and_wait(&self.ctx, |cmd| {
            copy_range(&self.ctx, cmd, &up_k, &self.keys[0], bytes);
            copy_range(&self.ctx, cmd, &up_v, &self.vals[0], bytes);
            self.record(cmd, 32, Some(n));
            copy_range(&self.ctx, cmd, &self.keys[0], &down_k, bytes);
            copy_range(&self.ctx, cmd, &self.vals[0], &down_v, bytes);
            barrier(&self.ctx, cmd);
        })?;
        Ok((from_bytes(down_k.read()?), from_bytes(down_v.read()?)))
    }
}

/// Copies the first `bytes` bytes of `src` into `dst`.
pub fn copy_range(ctx: &Context, cmd: vk::CommandBuffer, src: &Buffer, dst: &Buffer, bytes: u64) {
    let region = [vk::BufferCopy::default().size(bytes)];
    unsafe { ctx.device().cmd_copy_buffer(cmd, src.raw, dst.raw, &region) };
}

pub fn as_bytes<T: Copy>(v: &[T]) -> &[u8] {
    unsafe { std::slice::from_raw_parts(v.as_ptr() as *const u8, std::mem::size_of_val(v)) }
}

pub fn from_bytes<T: Copy + Default>(b: &[u8]) -> Vec<T> {
    let n = b.len() / std::mem::size_of::<T>();
    let mut out = vec![T::default(); n];
    unsafe {
        std::ptr::copy_nonoverlapping(b.as_ptr(), out.as_mut_ptr() as *mut u8, n * std::mem::size_of::<T>())
    };
    out
}

/// The key order the GPU uses for floats (`fsot_float_key` in common.glsl):
/// -0.0 sorts just before +0.0; NaNs sort beyond the infinities by sign.
pub fn float_key(f: f32) -> u32 {
    let b = f.to_bits();
    if b & 0x8000_0000 != 0 {
        !b
    } else {
        b | 0x8000_0000
    }
}
