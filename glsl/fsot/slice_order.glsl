// The per-lane transport's slice order (slice_order_count.comp,
// slice_order_place.comp, read by transport_lane.comp). A CPU implementation runs
// invocations as SIMD lanes, and a lane's loops run as long as the longest class
// among its neighbours'; class sizes spread widely (a level's class holds the
// taps above it), so neighbouring slices are given classes of about the same
// size: the lanes take the slices in decreasing class size from a queue, so
// that those of one workgroup take neighbouring ranks together and the
// driver's threads share large classes and small (transport_lane.comp).
// The slices themselves, and so the sums of their displacements, are unchanged.
// Include after transport_common.glsl (`pc`: TransportPush).
//
// `slice_order` holds the orders of up to B iterations of S slices, in slots k
// (src/gpu/layout.rs: slice_order_words; fewer slots where a binding cannot hold
// B, and the host then orders that many iterations at a time):
//   [k * BINS, (k + 1) * BINS)      slices of slot k in each bin;
//   B * BINS + k                    slot k's queue: the next rank to take;
//   [B * (BINS + 1) + 2 k S, ... + S)     each slice's bin;
//   [B * (BINS + 1) + (2 k + 1) S, ... + S) the slices in order.
// B is the batch (FSOT_ORDER_BATCH, the same as src/gpu/run.rs's BATCH). The
// bins and queues are zero before the ordering passes, which fill slots 0, 1,
// ... (workgroup row k) for iterations pc.iteration + k; the transport reads
// slot pc.order_slot and takes its ranks from that slot's queue.
#define FSOT_ORDER_BATCH 32u

uint fsot_order_bin_at(uint k, uint bin) {
    return k * FSOT_ORDER_BINS + bin;
}
uint fsot_order_next_at(uint k) {
    return FSOT_ORDER_BATCH * FSOT_ORDER_BINS + k;
}
uint fsot_order_key_at(uint k, uint slice) {
    return FSOT_ORDER_BATCH * (FSOT_ORDER_BINS + 1u) + 2u * k * pc.slices + slice;
}
uint fsot_order_rank_at(uint k, uint rank) {
    return FSOT_ORDER_BATCH * (FSOT_ORDER_BINS + 1u) + (2u * k + 1u) * pc.slices + rank;
}

// A slice's bin: bin 0 holds the largest classes (every tap), the last bin the
// smallest.
uint fsot_order_bin(FsotSlice s) {
    uint smaller = pc.taps - fsot_class_taps(s);
    return (smaller * FSOT_ORDER_BINS) / (pc.taps + 1u);
}
