#version 450
// Fills a buffer with the counter-based random stream for one key:
// hash_values[i] = hash2(key, i). Proves the toolchain and that CPU and GPU draw
// the same numbers.
#include "bindings.glsl"

layout(local_size_x_id = 0) in;
layout(push_constant) uniform Push { HashPush pc; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i < pc.count) {
        hash_values[i] = fsot_hash2(pc.key, i);
    }
}
