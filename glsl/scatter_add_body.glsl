// The gradient scatter on its own, for `fsot bench`: contribution i adds
// values[i] to accumulator targets[i], through the transport passes' helper.
#include "common.glsl"

layout(local_size_x_id = 0) in;

layout(std430, set = 0, binding = 0) readonly buffer Targets { uint targets[]; };
layout(std430, set = 0, binding = 1) readonly buffer Values { float values[]; };
#ifdef FSOT_FLOAT_ATOMICS
layout(std430, set = 0, binding = 2) buffer Acc { float acc[]; };
#else
layout(std430, set = 0, binding = 2) buffer Acc { int64_t acc[]; };
#endif

layout(push_constant) uniform Push { uint count; } pc;

#include "accumulate.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i < pc.count) {
        fsot_add_component(targets[i], values[i]);
    }
}
