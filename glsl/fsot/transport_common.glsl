// Helpers of the transport passes (transport.comp for GPUs, transport_lane.comp
// for CPU implementations): same buffers, same rules. Include after bindings.glsl
// and the pass's push-constant block `pc` (TransportPush). Nothing here depends
// on a specialization constant that changes with the tile: llvmpipe compiles a
// pipeline at its first dispatch (seconds for these passes), and a pipeline
// that differs from run to run is compiled again for each run.
#include "accumulate.glsl"
#include "rank_targets.glsl"
#include "loop_cap.glsl"

// Class size of a slice in taps: those whose threshold exceeds its level
// (thresholds decrease).
uint fsot_class_taps(FsotSlice s) {
    uint lo = 0u, hi = pc.taps;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (fsot_tap(mid).w > s.level) { lo = mid + 1u; } else { hi = mid; }
    }
    return lo;
}

// Class size of a slice in samples: its taps times spp.
uint fsot_class_size(FsotSlice s) {
    return fsot_class_taps(s) * pc.spp;
}

// Bits of a coordinate in [0, size) (0 for a size of 1): src/optimize/vulkan/layout.rs
// axis_bits.
uint fsot_axis_bits(uint size) {
    return size > 1u ? uint(findMSB(size - 1u)) + 1u : 0u;
}

// A tap's offsets (dx, dy, dt) from its packed word (src/optimize/vulkan/layout.rs pack_tap):
// one word per member read where three would be (on a SIMD driver each read is
// a loop over the lanes).
uvec3 fsot_tap_offsets(uint packed) {
    uint bx = fsot_axis_bits(pc.width);
    uint by = fsot_axis_bits(pc.height);
    return uvec3(packed & ((1u << bx) - 1u), (packed >> bx) & ((1u << by) - 1u), packed >> (bx + by));
}

// Point index of class member i.
uint fsot_class_point(FsotSlice s, uint i) {
    // No integer division by a run-time value: on SIMD drivers (llvmpipe) each
    // one is a scalar divide per lane, both sides of a select included. i / spp
    // is the high word of i * m, m = floor((2^32 - 1) / spp) + 1 (the same for
    // every member, so computed once), exact while i * spp < 2^32
    // (src/optimize/vulkan/layout.rs: spp_reciprocal; a class holds at most taps x spp
    // members). Taps and centres both lie in [0, size), so one conditional
    // subtraction wraps.
    uint high, low;
    umulExtended(i, 0xffffffffu / pc.spp + 1u, high, low);
    uint tap_index = pc.spp == 1u ? i : high;
    uint member = i - tap_index * pc.spp;
    uvec3 tap = fsot_tap_offsets(fsot_tap(tap_index).x);
    uint x = s.cx + tap.x;
    uint y = s.cy + tap.y;
    uint f = s.ct + tap.z;
    x = x >= pc.width ? x - pc.width : x;
    y = y >= pc.height ? y - pc.height : y;
    f = f >= pc.frames ? f - pc.frames : f;
    return ((f * pc.height + y) * pc.width + x) * pc.spp + member;
}

// Projection of a point on the slice's direction after its toroidal shift.
// For d <= 2 written out: a loop over a run-time count with indexed private
// arrays costs gathers on SIMD drivers.
float fsot_project(FsotSlice s, uint point) {
    uint base = point * pc.dims;
    float y = fsot_sample(base) - s.shift[0];
    float p = 0.0 + s.theta[0] * (y - floor(y));
    if (pc.dims > 1u) {
        y = fsot_sample(base + 1u) - s.shift[1];
        p += s.theta[1] * (y - floor(y));
    }
#ifdef FSOT_ANY_DIMS
    for (uint k = 2u; k < pc.dims; ++k) {
        y = fsot_sample(base + k) - s.shift[k];
        p += s.theta[k] * (y - floor(y));
    }
#endif
    return p;
}

// Reserves room for a large class in the radix sort's input; -1 if full. The
// count never passes the capacity: the sort and the gather read it as theirs.
int fsot_reserve_large(uint slice, uint n) {
    uint off = atomicAdd(large_count, 0u);
    for (;;) {
        if (n > pc.large_capacity - min(off, pc.large_capacity)) {
            atomicAdd(large_overflow, 1u);
            return -1;
        }
        uint seen = atomicCompSwap(large_count, off, off + n);
        if (seen == off) {
            break;
        }
        off = seen;
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

// Bucket of a projection for the transports' bucket sorts: n equal buckets over
// the projections' range [offset, offset + a1 + a2] (`scale` = n / width),
// clamped. Monotone in the key, so equal keys share a bucket and the buckets
// come in key order.
uint fsot_bucket(float key_value, float offset, float scale, uint n) {
    return min(uint(max(key_value - offset, 0.0) * scale), n - 1u);
}

bool fsot_before(float ka, uint va, float kb, uint vb) {
    return ka < kb || (ka == kb && va < vb);
}
