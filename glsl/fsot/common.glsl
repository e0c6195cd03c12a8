// Shared by every fsot compute pass: the counter-based random generator and the
// slice drawing (mirrors src/core/rng.rs and src/core/slice.rs), exact 1-D targets for
// d <= 2 in closed form, and sortable float keys. Buffers and push constants are
// in bindings.glsl.
#ifndef FSOT_COMMON_GLSL
#define FSOT_COMMON_GLSL

#define FSOT_MAX_DIMS 8
#define FSOT_TAU 6.28318530717958647692

#include "rng.glsl"

// ---- slices (src/core/slice.rs) ----

// cos and sin of an angle given in turns (u in [0, 1)), to float32 rounding on
// every device (hardware sin/cos may be off by 1e-6): exact quadrant reduction,
// then Taylor polynomials on |z| <= pi/4. Mirrors slice::turn_cos_sin.
vec2 fsot_turn_cos_sin(float u) {
    float x = 4.0 * u;
    float q = floor(x);
    float z = (x - q - 0.5) * 1.57079632679489662; // angle minus pi/4, |z| <= pi/4
    float z2 = z * z;
    float s = z * (1.0 + z2 * (-1.0 / 6.0 + z2 * (1.0 / 120.0 + z2 * (-1.0 / 5040.0 + z2 * (1.0 / 362880.0 + z2 * (-1.0 / 39916800.0 + z2 * (1.0 / 6227020800.0)))))));
    float c = 1.0 + z2 * (-0.5 + z2 * (1.0 / 24.0 + z2 * (-1.0 / 720.0 + z2 * (1.0 / 40320.0 + z2 * (-1.0 / 3628800.0 + z2 * (1.0 / 479001600.0))))));
    float h = 0.70710678118654752;
    // angle within the quadrant is pi/4 + z
    float cq = h * (c - s);
    float sq = h * (c + s);
    uint qi = uint(q) & 3u;
    if (qi == 0u) return vec2(cq, sq);
    if (qi == 1u) return vec2(-sq, cq);
    if (qi == 2u) return vec2(-cq, -sq);
    return vec2(sq, -cq);
}

struct FsotSlice {
    float theta[FSOT_MAX_DIMS];
    float shift[FSOT_MAX_DIMS];
    uint cx, cy, ct;
    uint level;
};

// axis_bits and pair_bits: slice::share_bits of the run's axis share.
FsotSlice fsot_draw_slice(uint slice_key, uint axis_bits, uint pair_bits, uint iteration, uint index, uint dims, uint w, uint h, uint t) {
    FsotSlice s;
    FsotStream rng;
    rng.key = fsot_hash2(fsot_derive(slice_key, iteration), index);
    rng.counter = 0u;
    for (uint k = 0u; k < FSOT_MAX_DIMS; ++k) { s.theta[k] = 0.0; s.shift[k] = 0.0; }
    uint pick = fsot_next(rng);
    if (dims == 1u) {
        s.theta[0] = 1.0;
    } else if (pick < axis_bits) {
        s.theta[fsot_below(rng, dims)] = 1.0;
    } else if (dims >= 3u && pick < pair_bits) {
        uint p = 2u * fsot_below(rng, dims / 2u);
        vec2 cs = fsot_turn_cos_sin(fsot_unit(fsot_next(rng)));
        s.theta[p] = cs.x;
        s.theta[p + 1u] = cs.y;
    } else if (dims == 2u) {
        vec2 cs = fsot_turn_cos_sin(fsot_unit(fsot_next(rng)));
        s.theta[0] = cs.x;
        s.theta[1] = cs.y;
    } else {
        for (uint attempt = 0u; attempt < 4u; ++attempt) {
            float norm = 0.0;
            for (uint k = 0u; k < dims; ++k) {
                float u1 = 1.0 - fsot_unit(fsot_next(rng));
                float u2 = fsot_unit(fsot_next(rng));
                s.theta[k] = sqrt(-2.0 * log(u1)) * cos(float(FSOT_TAU) * u2);
                norm += s.theta[k] * s.theta[k];
            }
            if (norm > 1e-12) {
                float inv = inversesqrt(norm);
                for (uint k = 0u; k < dims; ++k) { s.theta[k] *= inv; }
                break;
            }
            for (uint k = 0u; k < FSOT_MAX_DIMS; ++k) { s.theta[k] = 0.0; }
            s.theta[0] = 1.0;
        }
    }
    for (uint k = 0u; k < dims; ++k) { s.shift[k] = fsot_unit(fsot_next(rng)); }
    s.cx = fsot_below(rng, w);
    s.cy = fsot_below(rng, h);
    s.ct = fsot_below(rng, t);
    s.level = fsot_next(rng);
    return s;
}

// ---- exact targets for d <= 2 (src/core/targets.rs gives the general form) ----
//
// theta . U for U uniform on the square is a trapezoid on [0, a1 + a2]
// (a1 <= a2 the sorted |theta_k|), shifted by the sum of negative components.
// Its quantile function is sqrt(2 a1 a2 u) below u1 = a1 / (2 a2) and
// a2 u + a1 / 2 above it (up to 1/2; symmetric beyond). The mean over a rank's
// interval is computed piece by piece with cancellation-free differences, so
// float32 keeps its relative precision.

struct FsotTrapezoid { float a1; float a2; float offset; };

FsotTrapezoid fsot_trapezoid(float t0, float t1) {
    FsotTrapezoid z;
    float x = abs(t0), y = abs(t1);
    z.a1 = min(x, y);
    z.a2 = max(x, y);
    z.offset = min(t0, 0.0) + min(t1, 0.0);
    return z;
}

// Mean of the quantile over [y, x], 0 <= y < x <= 1/2, local coordinates, where
// x - y is one rank's width 1/n. No division by the (small) width: a bin wholly
// in one piece has a closed-form mean, and only the bin that straddles u1 mixes
// the two by its exact fraction; so float32 keeps its relative precision also
// where a device's division is approximate.
float fsot_piece_mean_low(FsotTrapezoid z, float y, float x) {
    // (2/3) sqrt(2 a1 a2) (x^1.5 - y^1.5) / (x - y)
    float sx = sqrt(x), sy = sqrt(y);
    return (2.0 / 3.0) * sqrt(2.0 * z.a1 * z.a2) * (x + sx * sy + y) / (sx + sy);
}

float fsot_piece_mean_mid(FsotTrapezoid z, float y, float x) {
    return 0.5 * z.a2 * (x + y) + 0.5 * z.a1;
}

// Written without branches: a SIMD driver (lavapipe) runs every branch for all
// its lanes, so each piece is evaluated once, on the part of the bin it covers,
// and weighted by that part (exactly 1 or 0 for a bin wholly in one piece,
// where the other piece's value is finite).
float fsot_quantile_mean(FsotTrapezoid z, uint q, uint n) {
    float nf = float(n);
    float y = float(q) / nf, x = float(q + 1u) / nf;
    float u1 = 0.5 * z.a1 / z.a2;
    float u1n = u1 * nf; // u1 in units of the width
    bool all_low = float(q + 1u) <= u1n;
    bool all_mid = float(q) >= u1n;
    float below = all_low ? 1.0 : (all_mid ? 0.0 : u1n - float(q)); // fraction of the bin below u1
    float low = fsot_piece_mean_low(z, y, all_low ? x : u1);
    float mid = fsot_piece_mean_mid(z, all_mid ? y : u1, x);
    return below * low + (1.0 - below) * mid;
}

// Target of rank r of n on the real line.
float fsot_rank_target(FsotTrapezoid z, uint r, uint n) {
    float total = z.a1 + z.a2;
    uint half_n = n / 2u;
    if ((n & 1u) == 1u && r == half_n) {
        return z.offset + 0.5 * total;
    }
    bool upper = r >= half_n + (n & 1u);
    uint q = upper ? n - 1u - r : r;
    float m;
    if (z.a1 <= 0.0) {
        m = z.a2 * (float(q) + 0.5) / float(n); // one axis: uniform on [0, a2]
    } else {
        m = fsot_quantile_mean(z, q, n);
    }
    return upper ? z.offset + total - m : z.offset + m;
}

// ---- sortable keys ----

// Maps a float to a uint that sorts in the same order (-0.0 before +0.0).
uint fsot_float_key(float f) {
    uint b = floatBitsToUint(f);
    return (b & 0x80000000u) != 0u ? ~b : (b | 0x80000000u);
}

float fsot_key_float(uint k) {
    return uintBitsToFloat((k & 0x80000000u) != 0u ? (k & 0x7fffffffu) : ~k);
}

#endif
