// The update pass, one invocation per coordinate: read and reset its accumulated
// displacement, apply the step rule (src/optimizer.rs: step_value), wrap into
// [0, 1). Included by update.comp (fixed point) and update_float.comp.
#include "common.glsl"

layout(local_size_x_id = 0) in;

layout(std430, set = 0, binding = 0) buffer Samples { float samples[]; };
#ifdef FSOT_FLOAT_ATOMICS
layout(std430, set = 0, binding = 1) buffer Acc { float acc[]; };
#else
layout(std430, set = 0, binding = 1) buffer Acc { int64_t acc[]; };
#endif
layout(std430, set = 0, binding = 2) buffer First { float first[]; };
layout(std430, set = 0, binding = 3) buffer Second { float second[]; };

layout(push_constant) uniform Push { UpdatePush pc; };

float wrap01(float x) {
    float y = x - floor(x);
    return y >= 1.0 ? 0.0 : y;
}

void main() {
    uint i = gl_GlobalInvocationID.y * (gl_NumWorkGroups.x * gl_WorkGroupSize.x) + gl_GlobalInvocationID.x;
    if (i >= pc.values) {
        return;
    }
#ifdef FSOT_FLOAT_ATOMICS
    float g = acc[i] * pc.inv_hits;
    acc[i] = 0.0;
#else
    float g = float(acc[i]) * (1.0 / 1099511627776.0) * pc.inv_hits;
    acc[i] = int64_t(0);
#endif
    float x = samples[i];
    if (pc.rule == 0u) {
        float m = pc.p1 * first[i] + (1.0 - pc.p1) * g;
        first[i] = m;
        samples[i] = wrap01(x + pc.p0 * pc.scale * m);
    } else {
        float m = pc.p1 * first[i] + (1.0 - pc.p1) * g;
        float v = pc.p2 * second[i] + (1.0 - pc.p2) * g * g;
        first[i] = m;
        second[i] = v;
        float mh = m / pc.bias1;
        float vh = v / pc.bias2;
        samples[i] = wrap01(x + pc.p0 * pc.scale * mh / (sqrt(vh) + pc.p3));
    }
}
