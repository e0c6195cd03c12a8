// The counter-based random generator of src/core/rng.rs (mix32, hash2, derive, the
// stream and its draws), shared by the fsot passes and, by `../fsot/rng.glsl`,
// the swap passes.
#ifndef FSOT_RNG_GLSL
#define FSOT_RNG_GLSL

uint fsot_mix32(uint x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

uint fsot_hash2(uint key, uint counter) {
    return fsot_mix32(key ^ fsot_mix32(counter + 0x9e3779b9u));
}

uint fsot_derive(uint key, uint label) {
    return fsot_mix32((key * 0x2c1b3c6du) ^ fsot_mix32(label ^ 0x85ebca6bu));
}

float fsot_unit(uint bits) {
    return float(bits >> 8) * (1.0 / 16777216.0);
}

struct FsotStream { uint key; uint counter; };

uint fsot_next(inout FsotStream s) {
    uint v = fsot_hash2(s.key, s.counter);
    s.counter += 1u;
    return v;
}

uint fsot_below(inout FsotStream s, uint n) {
    uint hi, lo;
    umulExtended(fsot_next(s), n, hi, lo);
    return hi;
}

#endif
