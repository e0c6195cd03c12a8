#version 450
#extension GL_GOOGLE_include_directive : require
// The example renderer's scene pass (examples/taa_renderer.rs): the soft-shadow
// scene of `fsot eval` (a square area light over the ground, a sphere circling
// between them), one frame per z of the dispatch. At 1 sample per pixel the
// light sample's two numbers come from fsot's masks through the public include;
// with `samples` > 1 it renders the reference instead (a jittered k x k grid).

#define FSOT_SET 0
#define FSOT_BINDING 1 // the masks at binding 1, the plan block at 2
#include "fsot.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0, std430) writeonly buffer Frames { float radiance[]; };

layout(push_constant) uniform Push {
    uint width;
    uint height;
    uint samples; // 1: fsot's numbers; k * k: the reference
    uint seed;
} pc;

const float TAU = 6.28318530718;
const float CYCLE = 256.0; // frames per cycle of the motion

// Whether the ray o + t d, |d| = 1, hits the sphere (c, r) for t in (0, t_max).
bool hits_sphere(vec3 o, vec3 d, vec3 c, float r, float t_max) {
    vec3 oc = o - c;
    float b = dot(oc, d);
    float disc = b * b - (dot(oc, oc) - r * r);
    if (disc < 0.0) return false;
    float s = sqrt(disc);
    float t = (-b - s > 1e-6) ? -b - s : -b + s;
    return t > 1e-6 && t < t_max;
}

// One light sample u of the ground point p at frame f.
float shade(vec2 p, float f, vec2 u) {
    float phase = f / CYCLE;
    vec3 ground = vec3(p, 0.0);
    float size = 0.35;
    vec3 light = vec3(0.5 + 0.1 * cos(TAU * phase), 0.5, 1.0) + vec3((u - 0.5) * size, 0.0);
    vec3 to = light - ground;
    float dist2 = dot(to, to);
    vec3 d = to * inversesqrt(dist2);
    vec3 sphere = vec3(0.5 + 0.22 * sin(TAU * phase), 0.5 + 0.22 * cos(TAU * phase), 0.3);
    if (hits_sphere(ground, d, sphere, 0.12, sqrt(dist2))) return 0.0;
    return d.z * d.z / dist2 * size * size * 8.0; // cos x cos / r^2 x area, about 1
}

uint hash(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

void main() {
    uvec3 id = gl_GlobalInvocationID;
    if (id.x >= pc.width || id.y >= pc.height) return;
    uint frame = id.z;
    // The unit square across the longer side, centred: (x + 0.5) / n when square.
    vec2 size = vec2(pc.width, pc.height);
    vec2 p = 0.5 + (vec2(id.xy) + 0.5 - 0.5 * size) / max(size.x, size.y);
    float value = 0.0;
    if (pc.samples <= 1u) {
        FsotSampler s = fsot_start(id.xy, frame, 0u);
        value = shade(p, float(frame), fsot_get_2d(s));
    } else {
        uint k = uint(sqrt(float(pc.samples)) + 0.5);
        uint key = hash(pc.seed ^ hash(id.x ^ hash(id.y ^ hash(frame))));
        for (uint i = 0u; i < k * k; ++i) {
            uint a = hash(key + 2u * i), b = hash(key + 2u * i + 1u);
            vec2 jitter = vec2(uvec2(a, b) >> 8u) * (1.0 / 16777216.0);
            value += shade(p, float(frame), (vec2(i % k, i / k) + jitter) / float(k));
        }
        value /= float(k * k);
    }
    radiance[(frame * pc.height + id.y) * pc.width + id.x] = value;
}
