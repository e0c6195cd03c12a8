#version 450
// Fills a buffer with the counter-based random stream for one key: out[i] =
// hash2(key, i). Proves the toolchain and that CPU and GPU draw the same numbers.
#include "common.glsl"

layout(local_size_x_id = 0) in;

layout(std430, set = 0, binding = 0) writeonly buffer Out { uint values[]; };

layout(push_constant) uniform Push {
    uint key;
    uint count;
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i < pc.count) {
        values[i] = fsot_hash2(pc.key, i);
    }
}
