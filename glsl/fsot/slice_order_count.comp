#version 450
// The slice order's first pass (slice_order.glsl): the invocations of each
// iteration of the batch (workgroup row k: iteration pc.iteration + k) draw its
// slices, a few each (src/optimize/vulkan/layout.rs: ORDER_SLICES_PER_INVOCATION), record
// each slice's class's size in taps (which the transport reads) and count it
// in its bin. The bins must be zero before. Run on CPU implementations only:
// the class size's binary search reads the taps through their texel view.
#define FSOT_TEXEL_READS
#include "bindings.glsl"
layout(push_constant) uniform Push { TransportPush pc; };
#include "transport_common.glsl"
#include "slice_order.glsl"

layout(local_size_x = 64) in;

void main() {
    uint k = gl_WorkGroupID.y;
    uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    for (uint slice = gl_GlobalInvocationID.x; slice < pc.slices; slice += stride) {
        FsotSlice s = fsot_draw_slice(pc.slice_key, pc.axis_bits, pc.pair_bits, pc.iteration + k, slice, pc.dims, pc.width, pc.height, pc.frames);
        uint class_taps = fsot_class_taps(s);
        slice_order[fsot_order_key_at(k, slice)] = class_taps;
        atomicAdd(slice_order[fsot_order_bin_at(k, fsot_order_bin(class_taps))], 1u);
    }
}
