// fsot.glsl: read fsot's masks in a renderer's shader, pbrt-style.
//
//     #define FSOT_SET 0          // optional, before the include: the descriptor set
//     #define FSOT_BINDING 0      // optional: the masks' binding; the plan's is FSOT_BINDING + 1
//     #include "fsot.glsl"
//     FsotSampler s = fsot_start(pixel, frame, sample_index);
//     float a = fsot_get_1d(s);   // the plan's next part, in the order the renderer consumes them
//     vec2  b = fsot_get_2d(s);
//
// Bindings (set FSOT_SET):
//   FSOT_BINDING      sampler2DArray: every mask of the plan stacked in one 2-D array
//                     image, mask m at layers [base_m, base_m + T * spp), layer
//                     base_m + t * spp + s holding sample s of frame t; a UNORM or
//                     SFLOAT format with channels for the largest part (fsot's
//                     `sampler` module writes it). Read with texelFetch: no filtering,
//                     any sampler will do.
//   FSOT_BINDING + 1  uniform FsotPlan (std140): the tile, the parts (per part: the
//                     pixel and frame offset, the base layer, the toroidal shift),
//                     filled by fsot from plan.json (`SamplerPlan::plan_block`).
//
// Each get reads the next part: component j of the part is
//     fract(texel[j] + shift[j] + fract(loop * R4[j]))
// at pixel ((x + ox) % W, (y + oy) % H) and layer base + ((f + of) % T) * spp + (i % spp),
// where loop = (f + of) / T counts the tile's repetitions in time: every loop of the
// tile adds the next point of the R4 sequence to the shift, so the period does not
// show. A get past the plan's last part returns white noise from a hash of the
// pixel, frame, sample and call count (defined, decorrelated, not optimized).
// Needs nothing beyond core Vulkan 1.2 GLSL (#version 450).
#ifndef FSOT_GLSL
#define FSOT_GLSL

#ifndef FSOT_SET
#define FSOT_SET 0
#endif
#ifndef FSOT_BINDING
#define FSOT_BINDING 0
#endif
// Parts the plan block holds (the block is 32 + 32 * FSOT_MAX_PARTS bytes).
#ifndef FSOT_MAX_PARTS
#define FSOT_MAX_PARTS 16
#endif

struct FsotPart {
    uvec4 offset_base; // x, y, frame offset; base layer
    vec4 shift;        // toroidal shift per component
};

layout(set = FSOT_SET, binding = FSOT_BINDING) uniform sampler2DArray fsot_masks;
layout(set = FSOT_SET, binding = FSOT_BINDING + 1, std140) uniform FsotPlan {
    uvec4 fsot_tile;  // W, H, T, spp
    uvec4 fsot_count; // parts, 0, 0, 0
    FsotPart fsot_parts[FSOT_MAX_PARTS];
};

struct FsotSampler {
    uvec2 pixel;
    uint frame;
    uint sample_index;
    uint next; // the next part to read
};

FsotSampler fsot_start(uvec2 pixel, uint frame, uint sample_index) {
    return FsotSampler(pixel, frame, sample_index, 0u);
}

// Roberts' R4 sequence, 1 / phi^k with phi the positive root of x^5 = x + 1, in
// 0.32 fixed point (rounded): loop * FSOT_R4 wraps to fract(loop / phi^k)
// within loop * 2^-33.
const uvec4 FSOT_R4 = uvec4(3679390609u, 3152041523u, 2700274806u, 2313257605u);

// A 32-bit integer hash (PCG output permutation) for the white-noise fallback.
uint fsot_hash(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

vec4 fsot_get(inout FsotSampler s) {
    uint part = s.next;
    s.next += 1u;
    if (part >= min(fsot_count.x, uint(FSOT_MAX_PARTS))) {
        uint h = fsot_hash(s.pixel.x ^ fsot_hash(s.pixel.y ^ fsot_hash(s.frame ^ fsot_hash(s.sample_index ^ fsot_hash(part)))));
        uvec4 bits = uvec4(h, fsot_hash(h), fsot_hash(h + 1u), fsot_hash(h + 2u));
        return vec4(bits >> 8u) * (1.0 / 16777216.0);
    }
    FsotPart p = fsot_parts[part];
    uint w = fsot_tile.x, h = fsot_tile.y, t = fsot_tile.z, spp = fsot_tile.w;
    uint f = s.frame + p.offset_base.z;
    uint loop = f / t;
    ivec3 at = ivec3(
        int((s.pixel.x + p.offset_base.x) % w),
        int((s.pixel.y + p.offset_base.y) % h),
        int(p.offset_base.w + (f % t) * spp + s.sample_index % spp));
    vec4 v = texelFetch(fsot_masks, at, 0);
    vec4 turn = vec4((uvec4(loop) * FSOT_R4) >> 8u) * (1.0 / 16777216.0);
    return fract(v + p.shift + turn);
}

float fsot_get_1d(inout FsotSampler s) { return fsot_get(s).x; }
vec2 fsot_get_2d(inout FsotSampler s) { return fsot_get(s).xy; }
vec3 fsot_get_3d(inout FsotSampler s) { return fsot_get(s).xyz; }
vec4 fsot_get_4d(inout FsotSampler s) { return fsot_get(s).xyzw; }

#endif
