//! The buffer plan of a Vulkan run: every buffer allocated once per run, sized
//! from the tile, the kernel and the device, with the large-class stage's
//! capacity.

use super::layout::{binding, pack_tap, CostSlot, LargeMetaHead, LargeSegment, RuleState};
use super::BATCH;
use crate::core::kernel::Kernel;
use crate::core::tile::Tile;
use crate::error::{Error, Result};
use crate::vk::buffer::upload_batch;
use crate::vk::commands::{barrier, zero};
use crate::vk::{Buffer, Context, Location, RadixSort, SortCount};

/// The large-class stage: classes larger than the transport pass sorts itself go
/// through the global radix sort.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LargePlan {
    /// Elements the large-class buffers hold (0: the kernel makes no large class).
    pub capacity: u32,
    /// Elements of large classes expected per iteration.
    pub expected: f64,
    /// Bits of a segment start (the last sort's key).
    pub seg_bits: u32,
    /// Bits of a point index (the first sort's key).
    pub point_bits: u32,
}

impl LargePlan {
    /// Capacity: three times the expected elements of large classes per iteration
    /// plus four largest classes (overflows are counted and reported), only when
    /// the kernel can make a class larger than `local_max`.
    pub fn new(
        ctx: &Context,
        tile: &Tile,
        thresholds: &[u32],
        taps: usize,
        slices: u32,
        local_max: u32,
    ) -> Self {
        let max_class = taps as u64 * tile.spp as u64;
        let mut expected = 0.0;
        let capacity = if max_class > local_max as u64 {
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
        Self {
            capacity,
            expected: expected * slices as f64,
            seg_bits: 32 - capacity.leading_zeros(),
            point_bits: (32 - (tile.points() as u32).saturating_sub(1).leading_zeros()).max(1),
        }
    }

    /// The same stage with at most `capacity` elements.
    pub fn at_most(self, capacity: u32) -> Self {
        let capacity = self.capacity.min(capacity);
        Self { capacity, seg_bits: 32 - capacity.leading_zeros(), ..self }
    }
}

/// Every buffer of a run.
pub struct RunBuffers {
    pub samples: Buffer,
    pub first: Buffer,
    pub second: Buffer,
    pub acc: Buffer,
    pub taps: Buffer,
    pub costs: Buffer,
    pub large_meta: Buffer,
    pub large_points: Buffer,
    pub large_proj: Buffer,
    pub large_seg: Buffer,
    pub large_pkey: Buffer,
    pub large_args: Buffer,
    /// The stopping rule's state, when the device evaluates it (`RuleState`).
    pub schedule: Buffer,
    /// The per-lane transport's slice order (`SliceOrder`, its lane table
    /// uploaded; a placeholder for the other transport).
    pub slice_order: Buffer,
    /// The workgroup transport's deferred slices (`Deferred`): the second
    /// pass's indirect dispatch, then the list (a placeholder without one).
    pub deferred: Buffer,
    /// Bound as the large keys and payloads when there is no sort (never written).
    pub placeholders: Option<[Buffer; 2]>,
    /// Host-visible: iteration costs, counters and state come back through it.
    pub readback: Buffer,
}

impl RunBuffers {
    /// Allocates and fills the buffers: `samples` and the kernel's tap table
    /// (dx, dy, dt, level threshold per tap) uploaded, everything else zero.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        ctx: &Context,
        tile: &Tile,
        kernel: &Kernel,
        thresholds: &[u32],
        samples: &[f32],
        adam: bool,
        float_acc: bool,
        large: &LargePlan,
        local_max: u32,
        order_words: u64,
        lane_table: &[u32],
        deferred_capacity: u32,
    ) -> Result<Self> {
        let info = ctx.info();
        let values = tile.values() as u64;
        let fits = |name: &str, bytes: u64| -> Result<u64> {
            if bytes > info.max_storage_buffer_range {
                Err(Error::invalid(format!(
                    "tile {} needs {bytes} bytes of {name}; {} binds at most {} (maxStorageBufferRange): a smaller tile fits",
                    tile.describe(),
                    info.name,
                    info.max_storage_buffer_range
                )))
            } else {
                Ok(bytes)
            }
        };
        let device = |bytes: u64, name: &str| Buffer::new(ctx, bytes, Location::Device, name);
        let samples_buf = device(fits("samples", values * 4)?, "samples")?;
        let acc = device(fits("accumulators", values * if float_acc { 4 } else { 8 })?, "accumulators")?;
        let first = device(values * 4, "state-first")?;
        let second = device(if adam { values * 4 } else { 4 }, "state-second")?;
        let mut table: Vec<u32> = Vec::with_capacity(kernel.taps.len() * 4);
        for (t, &q) in kernel.taps.iter().zip(thresholds) {
            let packed = pack_tap(tile, t.dx, t.dy, t.dt).ok_or_else(|| {
                Error::invalid(format!("tile {}: a kernel tap's offsets do not fit 32 bits", tile.describe()))
            })?;
            table.extend([packed, 0, 0, q]);
        }
        let taps = device(table.len() as u64 * 4, "kernel-taps")?;
        let costs = device(BATCH as u64 * std::mem::size_of::<CostSlot>() as u64, "costs")?;
        let segment = std::mem::size_of::<LargeSegment>() as u64;
        let head = std::mem::size_of::<LargeMetaHead>() as u64;
        let meta_len = head + segment * (large.capacity as u64 / (local_max as u64 + 1) + 1);
        let large_meta = device(meta_len, "large-meta")?;
        let large_len = (large.capacity.max(1) as u64) * 4;
        let placeholders = match large.capacity {
            0 => Some([device(16, "no-large-keys")?, device(16, "no-large-vals")?]),
            _ => None,
        };
        // Room for two state vectors (each rounded up to 16 bytes) or a batch's
        // costs, counters and the stopping rule's state.
        let batch_len = BATCH as u64 * std::mem::size_of::<CostSlot>() as u64
            + head
            + std::mem::size_of::<RuleState>() as u64;
        let readback_len = (values * 8 + 32).max(batch_len);
        let me = Self {
            samples: samples_buf,
            first,
            second,
            acc,
            costs,
            large_meta,
            large_points: device(large_len, "large-points")?,
            large_proj: device(large_len, "large-proj")?,
            large_seg: device(large_len, "large-seg")?,
            large_pkey: device(large_len, "large-projection-keys")?,
            large_args: device(32, "large-indirect-args")?,
            schedule: device(std::mem::size_of::<RuleState>() as u64, "stopping-rule")?,
            slice_order: device(fits("the slice order", order_words.max(4) * 4)?, "slice-order")?,
            deferred: device(
                fits("the deferred slices", 16 + 4 * deferred_capacity.max(1) as u64)?,
                "deferred-slices",
            )?,
            placeholders,
            readback: Buffer::new(ctx, readback_len, Location::Readback, "readback")?,
            taps,
        };
        // The second pass's dispatch: no workgroups yet, y and z 1.
        let dispatch = [0u32, 1, 1, 0];
        let uploads = [
            (&me.samples, bytemuck::cast_slice(samples)),
            (&me.taps, bytemuck::cast_slice(&table)),
            (&me.deferred, bytemuck::cast_slice(&dispatch)),
            (&me.slice_order, bytemuck::cast_slice(lane_table)),
        ];
        upload_batch(ctx, &uploads, |cmd| {
            for b in [&me.first, &me.second, &me.acc, &me.costs, &me.large_meta, &me.schedule] {
                zero(cmd, b, 0, ash::vk::WHOLE_SIZE);
            }
            barrier(cmd);
        })?;
        Ok(me)
    }

    /// The sort of the large-class stage (its count: the first word of LargeMeta).
    ///
    /// # Safety
    /// The sort binds `large_meta`: these buffers outlive it.
    pub unsafe fn large_sort(&self, ctx: &Context, large: &LargePlan) -> Result<Option<RadixSort>> {
        match large.capacity {
            0 => Ok(None),
            // SAFETY: the caller's promise.
            c => Ok(Some(RadixSort::new(ctx, c, unsafe { SortCount::device(&self.large_meta) })?)),
        }
    }

    /// Every binding of the fsot layout but the gather's table, for `sort`'s
    /// buffers (or the placeholders).
    pub fn bindings<'a>(&'a self, sort: Option<&'a RadixSort>) -> Result<Vec<(u32, &'a Buffer)>> {
        let (keys, vals) = match (sort, &self.placeholders) {
            (Some(s), _) => (&s.keys[0], &s.vals[0]),
            (None, Some([k, v])) => (k, v),
            (None, None) => return Err(Error::invalid("large-class buffers without a sort")),
        };
        Ok(vec![
            (binding::SAMPLES, &self.samples),
            (binding::TAPS, &self.taps),
            (binding::ACC, &self.acc),
            (binding::COSTS, &self.costs),
            (binding::LARGE_META, &self.large_meta),
            (binding::LARGE_KEYS, keys),
            (binding::LARGE_VALS, vals),
            (binding::LARGE_POINTS, &self.large_points),
            (binding::LARGE_PROJ, &self.large_proj),
            (binding::LARGE_SEG, &self.large_seg),
            (binding::LARGE_PKEY, &self.large_pkey),
            (binding::FIRST, &self.first),
            (binding::SECOND, &self.second),
            (binding::LARGE_ARGS, &self.large_args),
            (binding::SCHEDULE, &self.schedule),
            (binding::SLICE_ORDER, &self.slice_order),
            (binding::DEFERRED, &self.deferred),
        ])
    }
}
