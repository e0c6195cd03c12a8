#version 450
// The update pass, one invocation per coordinate: read and reset its accumulated
// displacement, apply the step rule (src/step_rule.rs: step_value), wrap into
// [0, 1). The step scale is the push constant's (the cosine schedule, or the
// host's stopping rule) or the device's stopping rule's (plateau.comp).
// variant FLOAT: FSOT_FLOAT_ATOMICS
#include "bindings.glsl"

layout(local_size_x_id = 0) in;
layout(push_constant) uniform Push { UpdatePush pc; };

float wrap01(float x) {
    float y = x - floor(x);
    return y >= 1.0 ? 0.0 : y;
}

void main() {
    uint i = gl_GlobalInvocationID.y * (gl_NumWorkGroups.x * gl_WorkGroupSize.x) + gl_GlobalInvocationID.x;
    if (i >= pc.values || schedule.stopped != 0u) {
        return; // past the values, or the stopping rule ended the run
    }
    float scale = pc.scheduled != 0u ? schedule.scale : pc.scale;
#ifdef FSOT_FLOAT_ATOMICS
    float g = acc[i] * pc.inv_hits;
    acc[i] = 0.0;
#else
    float g = float(acc[i]) * (1.0 / FSOT_FIXED_SCALE) * pc.inv_hits;
    acc[i] = int64_t(0);
#endif
    float x = samples[i];
    if (pc.rule == 0u) {
        float m = pc.p1 * first[i] + (1.0 - pc.p1) * g;
        first[i] = m;
        samples[i] = wrap01(x + pc.p0 * scale * m);
    } else {
        float m = pc.p1 * first[i] + (1.0 - pc.p1) * g;
        float v = pc.p2 * second[i] + (1.0 - pc.p2) * g * g;
        first[i] = m;
        second[i] = v;
        float mh = m / pc.bias1;
        float vh = v / pc.bias2;
        samples[i] = wrap01(x + pc.p0 * scale * mh / (sqrt(vh) + pc.p3));
    }
}
