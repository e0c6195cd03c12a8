// fsot.wgsl: read fsot's masks in a renderer's WGSL shader (wgpu, Bevy, a
// browser's WebGPU), as glsl/include/fsot.glsl does in GLSL.
//
// Join this file's text to the shader module's and declare the two bindings it
// reads, at the group and binding of your choice (WGSL finds module-scope
// declarations in any order):
//
//     @group(1) @binding(0) var fsot_masks: texture_2d_array<f32>;
//     @group(1) @binding(1) var<uniform> fsot_plan: FsotPlan;
//
//     var s = fsot_start(pixel, frame, sample_index);
//     let a = fsot_get_1d(&s);   // the plan's next part, in the order the renderer consumes them
//     let b = fsot_get_2d(&s);
//
// fsot_masks: every mask of the plan stacked in one 2-D array texture, mask m at
// layers [base_m, base_m + T * spp), layer base_m + t * spp + s holding sample s
// of frame t; a UNORM or float format with channels for the largest part (fsot's
// `sampler` module writes it into a renderer's image; for a plan of one mask,
// that mask's KTX2 file is this texture). Read with textureLoad: no sampler. On
// core WebGPU: an 8-bit UNORM or 32-bit float format (16-bit UNORM is optional
// there), at most 256 layers.
// fsot_plan: the tile, the parts (per part: the pixel and frame offset, the base
// layer, the toroidal shift), filled by fsot from plan.json
// (`SamplerPlan::plan_block`; its layout is the GLSL include's std140 block).
//
// Each get reads the next part: component j of the part is
//     fract(texel[j] + shift[j] + fract(loop * R4[j]))
// at pixel ((x + ox) % W, (y + oy) % H) and layer base + ((f + of) % T) * spp + (i % spp),
// where loop = (f + of) / T counts the tile's repetitions in time: every loop of the
// tile adds the next point of the R4 sequence to the shift, so the period does not
// show. A get past the plan's last part returns white noise from a hash of the
// pixel, frame, sample and call count (defined, decorrelated, not optimized).

// Parts the plan block holds (the block is 32 + 32 * FSOT_MAX_PARTS bytes); a plan
// of more parts needs this raised and `SamplerPlan::plan_block_for` to fill it.
const FSOT_MAX_PARTS: u32 = 16u;

struct FsotPart {
    offset_base: vec4<u32>, // x, y, frame offset; base layer
    shift: vec4<f32>,       // toroidal shift per component
}

struct FsotPlan {
    tile: vec4<u32>,  // W, H, T, spp
    count: vec4<u32>, // parts, 0, 0, 0
    parts: array<FsotPart, FSOT_MAX_PARTS>,
}

struct FsotSampler {
    pixel: vec2<u32>,
    frame: u32,
    sample_index: u32,
    next: u32, // the next part to read
}

fn fsot_start(pixel: vec2<u32>, frame: u32, sample_index: u32) -> FsotSampler {
    return FsotSampler(pixel, frame, sample_index, 0u);
}

// Roberts' R4 sequence, 1 / phi^k with phi the positive root of x^5 = x + 1, in
// 0.32 fixed point (rounded): loop * FSOT_R4 wraps to fract(loop / phi^k)
// within loop * 2^-33.
const FSOT_R4 = vec4<u32>(3679390609u, 3152041523u, 2700274806u, 2313257605u);

// A 32-bit integer hash (PCG output permutation) for the white-noise fallback.
fn fsot_hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

fn fsot_get(s: ptr<function, FsotSampler>) -> vec4<f32> {
    let part = (*s).next;
    (*s).next += 1u;
    if part >= min(fsot_plan.count.x, FSOT_MAX_PARTS) {
        let h = fsot_hash((*s).pixel.x ^ fsot_hash((*s).pixel.y ^ fsot_hash((*s).frame
            ^ fsot_hash((*s).sample_index ^ fsot_hash(part)))));
        let bits = vec4<u32>(h, fsot_hash(h), fsot_hash(h + 1u), fsot_hash(h + 2u));
        return vec4<f32>(bits >> vec4<u32>(8u)) * (1.0 / 16777216.0);
    }
    let p = fsot_plan.parts[part];
    let w = fsot_plan.tile.x;
    let h = fsot_plan.tile.y;
    let t = fsot_plan.tile.z;
    let spp = fsot_plan.tile.w;
    let f = (*s).frame + p.offset_base.z;
    let turns = f / t;
    let at = vec2<i32>(vec2<u32>(((*s).pixel.x + p.offset_base.x) % w, ((*s).pixel.y + p.offset_base.y) % h));
    let layer = i32(p.offset_base.w + (f % t) * spp + (*s).sample_index % spp);
    let v = textureLoad(fsot_masks, at, layer, 0);
    let turn = vec4<f32>((vec4<u32>(turns) * FSOT_R4) >> vec4<u32>(8u)) * (1.0 / 16777216.0);
    return fract(v + p.shift + turn);
}

fn fsot_get_1d(s: ptr<function, FsotSampler>) -> f32 { return fsot_get(s).x; }
fn fsot_get_2d(s: ptr<function, FsotSampler>) -> vec2<f32> { return fsot_get(s).xy; }
fn fsot_get_3d(s: ptr<function, FsotSampler>) -> vec3<f32> { return fsot_get(s).xyz; }
fn fsot_get_4d(s: ptr<function, FsotSampler>) -> vec4<f32> { return fsot_get(s).xyzw; }
