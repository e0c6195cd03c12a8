// Helpers of the transport passes (transport.comp for GPUs, transport_lane.comp
// for CPU implementations): same buffers, same rules. Include after bindings.glsl
// and the pass's push-constant block `pc` (TransportPush). A pass may define
// FSOT_PASS_SPP, FSOT_PASS_DIMS, FSOT_PASS_X_BITS and FSOT_PASS_Y_BITS first as
// specialization constants (equal to what the defaults in rank_targets.glsl
// compute from `pc`), so that the compiler folds what depends on them.
#include "accumulate.glsl"
#include "rank_targets.glsl"
#include "loop_cap.glsl"

// Class size of a slice in taps: those whose threshold exceeds its level
// (thresholds decrease).
uint fsot_class_taps(FsotSlice s) {
    uint lo = 0u, hi = pc.taps;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (taps[mid].w > s.level) { lo = mid + 1u; } else { hi = mid; }
    }
    return lo;
}

// Class size of a slice in samples: its taps times spp.
uint fsot_class_size(FsotSlice s) {
    return fsot_class_taps(s) * FSOT_PASS_SPP;
}

// A tap's offsets (dx, dy, dt) from its packed word (src/gpu/layout.rs pack_tap):
// one word per member read where three would be (on a SIMD driver each read is
// a loop over the lanes).
uvec3 fsot_tap_offsets(uint packed) {
    uint bx = FSOT_PASS_X_BITS;
    uint by = FSOT_PASS_Y_BITS;
    return uvec3(packed & ((1u << bx) - 1u), (packed >> bx) & ((1u << by) - 1u), packed >> (bx + by));
}

// Point index of class member i.
uint fsot_class_point(FsotSlice s, uint i) {
    // No integer division or remainder by a run-time value where spp is a
    // specialization constant: on SIMD drivers (llvmpipe) each one is a scalar
    // divide per lane, both sides of a select included. Taps and centres both
    // lie in [0, size), so one conditional subtraction wraps.
    uint tap_index = FSOT_PASS_SPP == 1u ? i : i / FSOT_PASS_SPP;
    uint member = i - tap_index * FSOT_PASS_SPP;
    uvec3 tap = fsot_tap_offsets(taps[tap_index].x);
    uint x = s.cx + tap.x;
    uint y = s.cy + tap.y;
    uint f = s.ct + tap.z;
    x = x >= pc.width ? x - pc.width : x;
    y = y >= pc.height ? y - pc.height : y;
    f = f >= pc.frames ? f - pc.frames : f;
    return ((f * pc.height + y) * pc.width + x) * FSOT_PASS_SPP + member;
}

// Projection of a point on the slice's direction after its toroidal shift.
// For d <= 2 written out: a loop over a run-time count with indexed private
// arrays costs gathers on SIMD drivers.
float fsot_project(FsotSlice s, uint point) {
    uint base = point * FSOT_PASS_DIMS;
    float y = samples[base] - s.shift[0];
    float p = 0.0 + s.theta[0] * (y - floor(y));
    if (FSOT_PASS_DIMS > 1u) {
        y = samples[base + 1u] - s.shift[1];
        p += s.theta[1] * (y - floor(y));
    }
#ifdef FSOT_ANY_DIMS
    for (uint k = 2u; k < FSOT_PASS_DIMS; ++k) {
        y = samples[base + k] - s.shift[k];
        p += s.theta[k] * (y - floor(y));
    }
#endif
    return p;
}

// Reserves room for a large class in the radix sort's input; -1 if full.
int fsot_reserve_large(uint slice, uint n) {
    uint off = atomicAdd(large_count, n);
    if (off + n > pc.large_capacity) {
        atomicAdd(large_overflow, 1u);
        return -1;
    }
    uint seg = atomicAdd(large_segments, 1u);
    segments[seg] = LargeSegment(slice, off, n, 0u);
    return int(off);
}

// Writes large-class member i (element off + i) for the radix sort.
void fsot_write_large(FsotSlice s, uint off, uint i) {
    uint point = fsot_class_point(s, i);
    uint e = off + i;
    float proj = fsot_project(s, point);
    large_keys[e] = point;
    large_vals[e] = e;
    large_points[e] = point;
    large_proj[e] = proj;
    large_seg[e] = off;
    large_pkey[e] = fsot_float_key(proj);
}

bool fsot_before(float ka, uint va, float kb, uint vb) {
    return ka < kb || (ka == kb && va < vb);
}
