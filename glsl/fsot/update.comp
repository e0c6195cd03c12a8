#version 450
// The update pass, one invocation per coordinate: read its accumulated
// displacement and reset it, apply the step rule (src/core/step_rule.rs: step_value),
// wrap into [0, 1). The step scale is the push constant's (the cosine schedule,
// or the host's stopping rule) or the device's stopping rule's (plateau.comp).
// The TEXELS variants (CPU implementations) read through the texel views and
// leave the reset to the host, which fills the accumulators with zeros after
// the pass: on llvmpipe each storage-buffer access at per-lane addresses is a
// loop over the lanes.
// variant FLOAT: FSOT_FLOAT_ATOMICS
// variant TEXELS: FSOT_TEXEL_READS
// variant TEXELS_FLOAT: FSOT_TEXEL_READS FSOT_FLOAT_ATOMICS
#include "bindings.glsl"

layout(local_size_x_id = 0) in;
layout(push_constant) uniform Push { UpdatePush pc; };

float wrap01(float x) {
    float y = x - floor(x);
    return y >= 1.0 ? 0.0 : y;
}

void main() {
    // The stopping rule's state read first, where every lane runs: llvmpipe
    // reads it once there, and lane by lane after a divergent branch.
    bool stopped = schedule.stopped != 0u;
    float device_scale = schedule.scale;
    float scale = pc.scheduled != 0u ? device_scale : pc.scale;
    uint i = gl_GlobalInvocationID.y * (gl_NumWorkGroups.x * gl_WorkGroupSize.x) + gl_GlobalInvocationID.x;
    if (stopped || i >= pc.values) {
        return; // the stopping rule ended the run, or past the values
    }
    float g = fsot_acc(i) * pc.inv_hits;
#ifndef FSOT_TEXEL_READS
#ifdef FSOT_FLOAT_ATOMICS
    acc[i] = 0.0;
#else
    acc[i] = int64_t(0);
#endif
#endif
    float x = fsot_sample(i);
    // The samples and the first moment stored once for both rules: a SIMD
    // driver runs both sides of a branch, stores included (each a loop over
    // the lanes).
    float m = pc.p1 * fsot_first(i) + (1.0 - pc.p1) * g;
    first[i] = m;
    // The step is p0 scale m (momentum) or p0 scale mh / (sqrt(vh) + p3) (Adam),
    // in src/core/step_rule.rs's order of operations (a division by 1 is exact).
    float moment = m;
    float divisor = 1.0;
    if (pc.rule != 0u) {
        float v = pc.p2 * fsot_second(i) + (1.0 - pc.p2) * g * g;
        second[i] = v;
        moment = m / pc.bias1;
        divisor = sqrt(v / pc.bias2) + pc.p3;
    }
    samples[i] = wrap01(x + pc.p0 * scale * moment / divisor);
}
