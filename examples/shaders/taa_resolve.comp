#version 450
// The example renderer's TAA pass (examples/taa_renderer.rs): per pixel, the
// exponential history h = alpha * current + (1 - alpha) * h over the frames in
// order, starting at the first frame (a static camera: no reprojection).

layout(local_size_x = 64) in;

layout(set = 0, binding = 0, std430) readonly buffer Current { float current[]; };
layout(set = 0, binding = 1, std430) writeonly buffer Resolved { float resolved[]; };

layout(push_constant) uniform Push {
    uint pixels;
    uint frames;
    float alpha;
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.pixels) return;
    float history = current[i];
    resolved[i] = history;
    for (uint f = 1u; f < pc.frames; ++f) {
        history = pc.alpha * current[f * pc.pixels + i] + (1.0 - pc.alpha) * history;
        resolved[f * pc.pixels + i] = history;
    }
}
