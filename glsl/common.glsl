// Shared by every fsot compute pass: the counter-based random generator (mirrors
// src/rng.rs bit for bit) and small helpers. Binding layouts live beside it here
// so the Rust side (src/gpu/) has one place to mirror.
#ifndef FSOT_COMMON_GLSL
#define FSOT_COMMON_GLSL

// 32-bit integer finaliser (lowbias32 constants); identical to rng::mix32.
uint fsot_mix32(uint x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

// Counter-based draw: key and counter hashed together; identical to rng::hash2.
uint fsot_hash2(uint key, uint counter) {
    return fsot_mix32(key ^ fsot_mix32(counter + 0x9e3779b9u));
}

// Uniform float in [0, 1) from the top 24 bits; identical to rng::unit_f32.
float fsot_unit(uint bits) {
    return float(bits >> 8) * (1.0 / 16777216.0);
}

#endif
