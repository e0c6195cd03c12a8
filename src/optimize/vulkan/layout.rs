//! The Rust mirror of `glsl/fsot/bindings.glsl`: binding indices, push-constant
//! structs and buffer records, each declared once here. `tests/spirv_layout.rs`
//! checks every offset, size and binding against the compiled SPIR-V.

use bytemuck::{Pod, Zeroable};

use crate::core::tile::Tile;

/// Binding indices (`FSOT_BINDING_*`); every fsot pass uses this one layout.
pub mod binding {
    pub const SAMPLES: u32 = 0;
    pub const TAPS: u32 = 1;
    pub const ACC: u32 = 2;
    pub const COSTS: u32 = 3;
    pub const LARGE_META: u32 = 4;
    pub const LARGE_KEYS: u32 = 5;
    pub const LARGE_VALS: u32 = 6;
    pub const LARGE_POINTS: u32 = 7;
    pub const LARGE_PROJ: u32 = 8;
    pub const LARGE_SEG: u32 = 9;
    pub const LARGE_PKEY: u32 = 10;
    pub const FIRST: u32 = 11;
    pub const SECOND: u32 = 12;
    pub const GATHER_TABLE: u32 = 13;
    pub const LARGE_ARGS: u32 = 14;
    pub const SCATTER_TARGETS: u32 = 15;
    pub const SCATTER_VALUES: u32 = 16;
    pub const HASH_VALUES: u32 = 17;
    pub const SCHEDULE: u32 = 18;
    pub const SLICE_ORDER: u32 = 19;
    pub const SAMPLE_TEXELS: u32 = 20;
    pub const TAP_TEXELS: u32 = 21;
    pub const ACC_TEXELS: u32 = 22;
    pub const FIRST_TEXELS: u32 = 23;
    pub const SECOND_TEXELS: u32 = 24;
    pub const DEFERRED: u32 = 25;
    /// Bindings in the layout (`FSOT_BINDINGS`).
    pub const BINDINGS: u32 = 26;
    /// Every uniform texel buffer with the name of its variable in GLSL.
    pub const TEXEL_VARIABLES: [(&str, u32); 5] = [
        ("sample_texels", SAMPLE_TEXELS),
        ("tap_texels", TAP_TEXELS),
        ("acc_texels", ACC_TEXELS),
        ("first_texels", FIRST_TEXELS),
        ("second_texels", SECOND_TEXELS),
    ];
    /// The bindings that are uniform texel buffers (TEXEL_VARIABLES's); every
    /// other is a storage buffer.
    pub const TEXELS: [u32; TEXEL_VARIABLES.len()] = {
        let mut out = [0; TEXEL_VARIABLES.len()];
        let mut i = 0;
        while i < out.len() {
            out[i] = TEXEL_VARIABLES[i].1;
            i += 1;
        }
        out
    };

    /// Every storage buffer with the name of its block in GLSL.
    pub const BLOCKS: [(&str, u32); 21] = [
        ("Samples", SAMPLES),
        ("Taps", TAPS),
        ("Acc", ACC),
        ("Costs", COSTS),
        ("LargeMeta", LARGE_META),
        ("LargeKeys", LARGE_KEYS),
        ("LargeVals", LARGE_VALS),
        ("LargePoints", LARGE_POINTS),
        ("LargeProj", LARGE_PROJ),
        ("LargeSeg", LARGE_SEG),
        ("LargePKey", LARGE_PKEY),
        ("First", FIRST),
        ("Second", SECOND),
        ("GatherTable", GATHER_TABLE),
        ("LargeArgs", LARGE_ARGS),
        ("ScatterTargets", SCATTER_TARGETS),
        ("ScatterValues", SCATTER_VALUES),
        ("HashValues", HASH_VALUES),
        ("Schedule", SCHEDULE),
        ("SliceOrder", SLICE_ORDER),
        ("Deferred", DEFERRED),
    ];
}

/// Fixed-point scale of the objective's squared distances (`FSOT_COST_SCALE`).
pub const COST_SCALE: f64 = 4_294_967_296.0;

/// Class-size bins of the per-lane transport's slice order (`FSOT_ORDER_BINS`).
pub const ORDER_BINS: u32 = 256;
/// Slots of bins the slice order holds (`FSOT_ORDER_BATCH`): a batch.
pub const ORDER_BATCH: u32 = super::BATCH;
/// Slices each invocation of the slice order's first pass draws (at most; 64
/// invocations a workgroup): a few workgroups an iteration, each of whose
/// starts costs a CPU implementation a few microseconds (`examples/slice_order_time.rs`
/// times it), and well within lavapipe's
/// loop cap (a slice's draw and class search loop at most about 110 times).
pub const ORDER_SLICES_PER_INVOCATION: u32 = 16;

/// Tiers of the per-lane transport's chunk plan at most (`FSOT_LANE_TIERS`):
/// runs of bins whose worst slice costs an invocation within a factor of two.
pub const LANE_TIERS: u32 = 64;
/// Words of one slot's chunk plan (`fsot_lane_plan_at`): the chunk queue, the
/// transport's dispatch (x, y, z), the chunks, three spare, then per tier its
/// first chunk, first rank, slices and rounds.
pub const LANE_PLAN_WORDS: u32 = 8 + 4 * LANE_TIERS;
/// Words of the lane table at the start of `SliceOrder`, written once by the
/// host (`TransportShape::lane_table`): lanes a chunk, the chunks aimed at, each
/// bin's tier, then per tier its cost (loop iterations a slice at worst) and
/// most rounds.
pub const LANE_TABLE_WORDS: u32 = 2 + ORDER_BINS + 2 * LANE_TIERS;
/// Words of `SliceOrder` zeroed before each ordering, after the lane table:
/// every slot's bins and chunk plan.
pub const ORDER_HEAD_WORDS: u32 = ORDER_BATCH * (ORDER_BINS + LANE_PLAN_WORDS);
/// Words of `SliceOrder` before its per-slot regions.
pub const ORDER_FIXED_WORDS: u32 = LANE_TABLE_WORDS + ORDER_HEAD_WORDS;

/// The word of `SliceOrder` where slot `slot`'s chunk plan starts
/// (`fsot_lane_plan_at`): its queue, then its dispatch (x, y, z), then its
/// chunks.
pub fn lane_plan_word(slot: u32) -> u32 {
    LANE_TABLE_WORDS + ORDER_BATCH * ORDER_BINS + slot * LANE_PLAN_WORDS
}

/// The word of `SliceOrder` where tier `tier` of slot `slot`'s plan starts
/// (`fsot_lane_tier_at`): its first chunk, first rank, slices and rounds.
pub fn lane_tier_word(slot: u32, tier: u32) -> u32 {
    lane_plan_word(slot) + 8 + 4 * tier
}

/// The word of the lane table holding tier `tier`'s cost, its most rounds
/// next (`fsot_lane_table_cost`).
pub fn lane_table_cost_word(tier: u32) -> u32 {
    2 + ORDER_BINS + 2 * tier
}

/// Byte offset in `SliceOrder` of slot `slot`'s transport dispatch (x, y, z),
/// which the ordering's second pass writes.
pub fn lane_dispatch_offset(slot: u32) -> u64 {
    (lane_plan_word(slot) + 1) as u64 * 4
}

/// The slice order's bin of a class of `class_taps` of `taps` taps: bin 0 holds
/// the largest classes (`fsot_order_bin`).
pub fn order_bin(class_taps: u32, taps: u32) -> u32 {
    ((taps - class_taps.min(taps)) as u64 * ORDER_BINS as u64 / (taps as u64 + 1)) as u32
}

/// Words of `SliceOrder` for `slots` iterations' orders (at most ORDER_BATCH)
/// of `slices` slices each (the regions of `glsl/fsot/slice_order.glsl`): the
/// lane table, the bins and chunk plan of every slot, then per slot each
/// slice's bin and the slices in order.
pub fn slice_order_words(slices: u32, slots: u32) -> u64 {
    ORDER_FIXED_WORDS as u64 + slots as u64 * 2 * slices as u64
}

/// Slots of slice orders for `slices` slices per iteration that one binding of
/// `max_bytes` holds: a batch's worth (ORDER_BATCH) where it can, else fewer, at
/// least one (whose buffer is then refused with a clear error if too large).
pub fn slice_order_slots(slices: u32, max_bytes: u64) -> u32 {
    (1..=ORDER_BATCH).rev().find(|&s| slice_order_words(slices, s) * 4 <= max_bytes).unwrap_or(1)
}

/// The multiplier by which the transport passes divide a class member's index
/// by spp (`fsot_class_point`): i / spp is the high word of i * m, exact while
/// i * spp < 2^32. Unused for spp = 1 (the shader takes i itself).
pub fn spp_reciprocal(spp: u32) -> u32 {
    (u32::MAX / spp.max(1)).wrapping_add(1)
}

/// Bits of a coordinate in [0, size) in a packed tap (`fsot_axis_bits`): 0
/// for a size of 1.
pub fn axis_bits(size: u32) -> u32 {
    if size <= 1 {
        0
    } else {
        32 - (size - 1).leading_zeros()
    }
}

/// A kernel tap's offsets (each below its axis's size) packed in one word, as
/// the `Taps` table holds them (`fsot_tap_offsets` unpacks): dx in the low
/// `axis_bits(width)` bits, then dy in `axis_bits(height)` bits, then dt. None
/// where they do not fit 31 bits (the shader shifts by the sum of the first two
/// widths), which no tile of at most `MAX_POINTS` points reaches (each axis
/// takes under one bit more than its log2, and the sizes multiply to at most
/// 2^28).
pub fn pack_tap(tile: &Tile, dx: u32, dy: u32, dt: u32) -> Option<u32> {
    let (bx, by, bt) =
        (axis_bits(tile.width as u32), axis_bits(tile.height as u32), axis_bits(tile.frames as u32));
    let fits = dx < tile.width as u32 && dy < tile.height as u32 && dt < tile.frames as u32;
    (fits && bx + by + bt < 32).then(|| dx | dy << bx | dt << (bx + by))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_member_index_divides_by_spp_exactly_through_the_reciprocal() {
        // Every spp the tiles allow, every index of a class of up to 2^20 taps
        // (sampled past 2^16), against integer division.
        for spp in 2..=crate::core::tile::MAX_SPP as u32 {
            let m = spp_reciprocal(spp) as u64;
            let last = (1u64 << 20) * spp as u64;
            let indices = (0..1u64 << 16).chain((1u64 << 16..last).step_by(997)).chain([last - 1]);
            for i in indices {
                assert_eq!((i * m) >> 32, i / spp as u64, "spp {spp}, index {i}");
            }
        }
    }

    #[test]
    fn taps_pack_into_one_word_on_every_tile_and_unpack_as_the_shader_does() {
        // The shader's unpacking (fsot_tap_offsets), written out.
        let unpack = |tile: &Tile, p: u32| {
            let (bx, by) = (axis_bits(tile.width as u32), axis_bits(tile.height as u32));
            (p & ((1u64 << bx) - 1) as u32, (p >> bx) & ((1u64 << by) - 1) as u32, p >> (bx + by))
        };
        for (w, h, t) in
            [(1, 1, 1), (32, 32, 16), (5, 3, 7), (64, 1, 1), (256, 256, 64), (1 << 14, 1 << 14, 1)]
        {
            let tile = Tile::new(w, h, t, 1, 1).unwrap();
            for (dx, dy, dt) in [(0, 0, 0), (w - 1, h - 1, t - 1), (w / 2, h / 3, t / 2), (1 % w, 0, t - 1)] {
                let (dx, dy, dt) = (dx as u32, dy as u32, dt as u32);
                let p = pack_tap(&tile, dx, dy, dt).unwrap();
                assert_eq!(unpack(&tile, p), (dx, dy, dt), "{w}x{h}x{t}");
            }
        }
        // The worst tiles MAX_POINTS allows: every axis just past a power of two.
        for (w, h, t) in
            [(513, 511, 1023), (1025, 1025, 255), (2049, 2049, 63), ((1 << 28) - 1, 1, 1), (16385, 16383, 1)]
        {
            let tile = Tile::new(w, h, t, 1, 1).unwrap();
            assert!(pack_tap(&tile, w as u32 - 1, h as u32 - 1, t as u32 - 1).is_some(), "{w}x{h}x{t}");
        }
        assert_eq!(pack_tap(&Tile::new(4, 4, 4, 1, 1).unwrap(), 4, 0, 0), None, "an offset past its axis");
    }

    #[test]
    fn slice_orders_fill_a_binding_at_most() {
        let lavapipe = 128 << 20;
        assert_eq!(slice_order_slots(3000, lavapipe), ORDER_BATCH);
        // 256x256x64 at 16 hits per sample: about 594k slices per iteration.
        let slots = slice_order_slots(594_000, lavapipe);
        assert!((1..ORDER_BATCH).contains(&slots), "{slots}");
        assert!(slice_order_words(594_000, slots) * 4 <= lavapipe);
        assert!(slice_order_words(594_000, slots + 1) * 4 > lavapipe);
        assert_eq!(slice_order_slots(40_000_000, lavapipe), 1);
    }
}

/// `TransportPush`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TransportPush {
    pub slice_key: u32,
    pub iteration: u32,
    pub width: u32,
    pub height: u32,
    pub frames: u32,
    pub spp: u32,
    pub dims: u32,
    pub taps: u32,
    pub slices: u32,
    pub cost_slot: u32,
    pub large_capacity: u32,
    /// The per-lane transport's slice order slot (`slice_order.glsl`).
    pub order_slot: u32,
    /// Slices the workgroup transport's deferred list holds (its second pass).
    pub deferred_capacity: u32,
    /// A slice's first draw below this: an axis; below `pair_bits`: a pair
    /// (`slice::share_bits`).
    pub axis_bits: u32,
    pub pair_bits: u32,
}

/// `UpdatePush`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct UpdatePush {
    pub values: u32,
    pub rule: u32,
    pub step_t: u32,
    pub scale: f32,
    pub inv_hits: f32,
    pub p0: f32,
    pub p1: f32,
    pub p2: f32,
    pub p3: f32,
    pub bias1: f32,
    pub bias2: f32,
    /// 1: the step scale is the device's stopping rule's (`Schedule::scale`).
    pub scheduled: u32,
}

/// `PlateauPush`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct PlateauPush {
    pub slot: u32,
    pub iteration: u32,
}

/// `RuleState`: the stopping rule on the device (`step_rule::Plateau` and
/// `PlateauState`, and `Until::Objective`'s target). The f64 members are `uvec2`
/// bits in GLSL.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct RuleState {
    pub previous: f64,
    pub sum: f64,
    pub decay_below: f64,
    pub stop_below: f64,
    pub target: f64,
    pub scale: f32,
    pub factor: f32,
    pub floor_scale: f32,
    pub count: u32,
    pub window: u32,
    pub has_previous: u32,
    pub has_target: u32,
    pub stopped: u32,
    pub stop_iteration: u32,
    pub pad: u32,
}

/// `ScatterPush`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct ScatterPush {
    pub count: u32,
}

/// `HashPush`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct HashPush {
    pub key: u32,
    pub count: u32,
}

/// The head of `LargeMeta`, before its `LargeSegment`s.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct LargeMetaHead {
    pub large_count: u32,
    pub large_segments: u32,
    pub large_overflow: u32,
    pub loop_cut: u32,
}

/// `LargeSegment`: one large class in the large-class buffers.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct LargeSegment {
    pub slice: u32,
    pub first: u32,
    pub size: u32,
    pub pad: u32,
}

/// One cost slot of `Costs`: squared distances (COST_SCALE fixed point), count.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct CostSlot {
    pub squared: i64,
    pub count: i64,
}

/// `LargeArgs`: the large-class stage's indirect dispatches.
pub const ARG_GATHER: u64 = 0;
pub const ARG_SEGMENTS: u64 = 16;
