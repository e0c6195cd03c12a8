#version 450
// The gradient scatter on its own, for `fsot bench`: contribution i adds
// scatter_values[i] to accumulator scatter_targets[i], through the transport
// passes' helper.
// variant FLOAT: FSOT_FLOAT_ATOMICS
#include "bindings.glsl"
#include "accumulate.glsl"

layout(local_size_x_id = 0) in;
layout(push_constant) uniform Push { ScatterPush pc; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i < pc.count) {
        fsot_add_component(scatter_targets[i], scatter_values[i]);
    }
}
