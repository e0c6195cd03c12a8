// The per-lane transport's slice order (slice_order_count.comp,
// slice_order_place.comp, read by transport_lane.comp). A CPU implementation runs
// invocations as SIMD lanes, and a lane's loops run as long as the longest class
// among its neighbours'; class sizes spread widely (a level's class holds the
// taps above it), so neighbouring slices are given classes of about the same
// size: the slices are ranked in decreasing class size, and shared out in
// chunks of neighbouring ranks, each as many as one workgroup's lanes can take
// within the loop cap at its classes' worst; the workgroups take the chunks
// from a queue, largest classes first, so that the driver's threads share
// large classes and small (transport_lane.comp).
// The slices themselves, and so the sums of their displacements, are unchanged.
// Include after transport_common.glsl (`pc`: TransportPush).
//
// `slice_order` holds a lane table, then the orders of up to B iterations of S
// slices, in slots k (src/optimize/vulkan/layout.rs: slice_order_words; fewer slots where a
// binding cannot hold B, and the host then orders that many iterations at a
// time). With L = FSOT_LANE_TABLE_WORDS, P = FSOT_LANE_PLAN_WORDS and
// H = L + B * (BINS + P):
//   [0, L)                          the lane table, written once by the host
//                                   (src/optimize/vulkan/shape.rs: lane_table): lanes a
//                                   chunk, chunks aimed at, each bin's tier,
//                                   each tier's cost and most rounds;
//   [L + k * BINS, ... + BINS)      slices of slot k in each bin;
//   [L + B * BINS + k * P, ... + P) slot k's chunk plan (fsot_lane_plan_at);
//   [H + 2 k S, ... + S)            each slice's class, in taps (the transport
//                                   reads it in place of searching the taps);
//   [H + (2 k + 1) S, ... + S)      the slices in order.
// B is the batch (FSOT_ORDER_BATCH, the same as src/optimize/vulkan/run.rs's BATCH). The
// bins and plans are zero before the ordering passes, which fill slots 0, 1,
// ... (workgroup row k) for iterations pc.iteration + k; the transport reads
// slot pc.order_slot and takes its chunks from that slot's queue.
#define FSOT_ORDER_BATCH 32u
#define FSOT_LANE_TIERS 64u
#define FSOT_LANE_PLAN_WORDS (8u + 4u * FSOT_LANE_TIERS)
#define FSOT_LANE_TABLE_WORDS (2u + FSOT_ORDER_BINS + 2u * FSOT_LANE_TIERS)
#define FSOT_ORDER_FIXED_WORDS (FSOT_LANE_TABLE_WORDS + FSOT_ORDER_BATCH * (FSOT_ORDER_BINS + FSOT_LANE_PLAN_WORDS))

// The lane table: lanes a chunk, the chunks aimed at, bin b's tier, tier t's
// cost (loop iterations one slice takes an invocation at worst) and most rounds.
#define FSOT_LANE_TABLE_LANES 0u
#define FSOT_LANE_TABLE_AIM 1u
uint fsot_lane_table_tier(uint bin) {
    return 2u + bin;
}
uint fsot_lane_table_cost(uint tier) {
    return 2u + FSOT_ORDER_BINS + 2u * tier;
}
uint fsot_lane_table_most(uint tier) {
    return 3u + FSOT_ORDER_BINS + 2u * tier;
}

// Slot k's chunk plan, from its first word p: p the queue of chunks, p + 1 ..
// p + 3 the transport's dispatch (x, y, z), p + 4 the chunks; tier t's first
// chunk, first rank, slices and rounds at p + 8 + 4 t + 0 .. 3.
uint fsot_lane_plan_at(uint k) {
    return FSOT_LANE_TABLE_WORDS + FSOT_ORDER_BATCH * FSOT_ORDER_BINS + k * FSOT_LANE_PLAN_WORDS;
}
uint fsot_lane_tier_at(uint k, uint tier) {
    return fsot_lane_plan_at(k) + 8u + 4u * tier;
}

uint fsot_order_bin_at(uint k, uint bin) {
    return FSOT_LANE_TABLE_WORDS + k * FSOT_ORDER_BINS + bin;
}
uint fsot_order_key_at(uint k, uint slice) {
    return FSOT_ORDER_FIXED_WORDS + 2u * k * pc.slices + slice;
}
uint fsot_order_rank_at(uint k, uint rank) {
    return FSOT_ORDER_FIXED_WORDS + (2u * k + 1u) * pc.slices + rank;
}

// The bin of a class of `class_taps` taps: bin 0 holds the largest classes
// (every tap), the last bin the smallest (src/optimize/vulkan/layout.rs: order_bin, which
// the lane table's tiers follow; in 64 bits, for kernels of past 2^24 taps).
uint fsot_order_bin(uint class_taps) {
    uint smaller = pc.taps - class_taps;
    return uint((uint64_t(smaller) * FSOT_ORDER_BINS) / uint64_t(pc.taps + 1u));
}
