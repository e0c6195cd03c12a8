// Every buffer, push-constant struct and binding index of the fsot passes, declared
// once. Mirrored once in Rust (src/optimize/vulkan/layout.rs); tests/spirv_layout.rs checks
// the compiled SPIR-V against the mirror. Every pass uses the same descriptor set
// layout (FSOT_BINDINGS bindings: storage buffers, and two uniform texel
// buffers that view some of them again) and touches only the buffers it names.
// Include first, right after #version and any extension of the pass's own.
// FSOT_FLOAT_ATOMICS (set by scripts/spirv.sh for the `_FLOAT` variants): accumulators are
// floats added with VK_EXT_shader_atomic_float; otherwise int64 fixed point.
#ifndef FSOT_BINDINGS_GLSL
#define FSOT_BINDINGS_GLSL
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#ifdef FSOT_FLOAT_ATOMICS
#extension GL_EXT_shader_atomic_float : require
#endif
#include "common.glsl"

#define FSOT_BINDING_SAMPLES 0
#define FSOT_BINDING_TAPS 1
#define FSOT_BINDING_ACC 2
#define FSOT_BINDING_COSTS 3
#define FSOT_BINDING_LARGE_META 4
#define FSOT_BINDING_LARGE_KEYS 5
#define FSOT_BINDING_LARGE_VALS 6
#define FSOT_BINDING_LARGE_POINTS 7
#define FSOT_BINDING_LARGE_PROJ 8
#define FSOT_BINDING_LARGE_SEG 9
#define FSOT_BINDING_LARGE_PKEY 10
#define FSOT_BINDING_FIRST 11
#define FSOT_BINDING_SECOND 12
#define FSOT_BINDING_GATHER_TABLE 13
#define FSOT_BINDING_LARGE_ARGS 14
#define FSOT_BINDING_SCATTER_TARGETS 15
#define FSOT_BINDING_SCATTER_VALUES 16
#define FSOT_BINDING_HASH_VALUES 17
#define FSOT_BINDING_SCHEDULE 18
#define FSOT_BINDING_SLICE_ORDER 19
#define FSOT_BINDING_SAMPLE_TEXELS 20
#define FSOT_BINDING_TAP_TEXELS 21
#define FSOT_BINDING_ACC_TEXELS 22
#define FSOT_BINDING_FIRST_TEXELS 23
#define FSOT_BINDING_SECOND_TEXELS 24
#define FSOT_BINDING_DEFERRED 25
#define FSOT_BINDINGS 26

// Fixed-point scale of the int64 accumulators: 2^40, as src/optimize/cpu.rs.
#define FSOT_FIXED_SCALE 1099511627776.0
// Fixed-point scale of the objective's squared distances: 2^32.
#define FSOT_COST_SCALE 4294967296.0
// Bins of the per-lane transport's slice order (slice_order.glsl).
#define FSOT_ORDER_BINS 256u

// One iteration of the transport passes.
struct TransportPush {
    uint slice_key;      // rng::derive(seed key, 0x51ce)
    uint iteration;
    uint width;
    uint height;
    uint frames;
    uint spp;
    uint dims;
    uint taps;           // entries in the kernel table
    uint slices;         // slices this iteration
    uint cost_slot;      // where this iteration's objective goes: its index in the batch
    uint large_capacity; // elements the large-class buffers hold
    uint order_slot;     // where the per-lane transport finds this iteration's slice order
    uint deferred_capacity; // slices the deferred list holds (transport.comp's second pass)
    uint axis_bits;      // a slice's first draw below this: an axis (slice::share_bits)
    uint pair_bits;      // below this (d >= 3): a pair of coordinates
};

// The update pass.
struct UpdatePush {
    uint values;
    uint rule;        // 0 momentum, 1 Adam
    uint step_t;      // 1-based step number
    float scale;      // schedule factor
    float inv_hits;   // 1 / expected hits per value
    float p0;         // momentum: step;  Adam: lr
    float p1;         // momentum: beta;  Adam: beta1
    float p2;         // Adam: beta2
    float p3;         // Adam: eps
    float bias1;      // Adam: 1 - beta1^t
    float bias2;      // Adam: 1 - beta2^t
    uint scheduled;   // 1: the step scale is the stopping rule's (schedule.scale), not `scale`
};

// The stopping rule's pass (plateau.comp): the iteration just done and its cost slot.
struct PlateauPush {
    uint slot;
    uint iteration;
};

// The stopping rule on the device (src/core/step_rule.rs: Plateau and PlateauState,
// and Until::Objective), evaluated by plateau.comp. Its f64 values are kept as
// their bits (uvec2), so that passes compiled without shaderFloat64 can bind it.
struct RuleState {
    uvec2 previous;     // the last complete window's mean objective (when has_previous)
    uvec2 sum;          // the current window's objectives so far
    uvec2 decay_below;  // a window gaining less than this halves the step scale...
    uvec2 stop_below;   // ... or, with the scale at its floor, gaining less than this stops
    uvec2 target;       // stop at a window whose mean is at most this (when has_target)
    float scale;        // the step scale the update pass applies
    float factor;       // what the scale is multiplied by when a window does not pay
    float floor_scale;  // the scale's floor (FINAL_FRACTION)
    uint count;         // objectives in the current window
    uint window;        // iterations per window
    uint has_previous;
    uint has_target;
    uint stopped;       // 1 once the rule ended the run: every pass then does nothing
    uint stop_iteration; // iterations done when it did
    uint pad;
};

// The scatter benchmark.
struct ScatterPush {
    uint count;
};

// The toolchain probe (hash_fill.comp).
struct HashPush {
    uint key;
    uint count;
};

// A large class in the large-class buffers: its slice, first element, size.
struct LargeSegment {
    uint slice;
    uint first;
    uint size;
    uint pad;
};

layout(std430, set = 0, binding = FSOT_BINDING_SAMPLES) buffer Samples { float samples[]; };
// Kernel taps in decreasing weight: offsets packed in one word (fsot_tap_offsets),
// two unused words, level threshold.
layout(std430, set = 0, binding = FSOT_BINDING_TAPS) readonly buffer Taps { uvec4 taps[]; };
#ifdef FSOT_FLOAT_ATOMICS
layout(std430, set = 0, binding = FSOT_BINDING_ACC) buffer Acc { float acc[]; };
#else
layout(std430, set = 0, binding = FSOT_BINDING_ACC) buffer Acc { int64_t acc[]; };
#endif
// Per cost slot: squared distances (FSOT_COST_SCALE fixed point), count.
layout(std430, set = 0, binding = FSOT_BINDING_COSTS) buffer Costs { int64_t costs[]; };
// Large classes: elements used (the radix sort's count: the first word), classes
// (both reset each iteration), classes dropped for want of room and invocations
// that a CPU implementation's loop cap cut short (both counted over a batch), then
// one segment per class.
layout(std430, set = 0, binding = FSOT_BINDING_LARGE_META) buffer LargeMeta {
    uint large_count;
    uint large_segments;
    uint large_overflow;
    uint loop_cut;
    LargeSegment segments[];
};
// Large classes, element e: sort key and payload (the radix sort's input and
// output), point, projection, segment (its first element), and the projection's
// sortable key.
layout(std430, set = 0, binding = FSOT_BINDING_LARGE_KEYS) buffer LargeKeys { uint large_keys[]; };
layout(std430, set = 0, binding = FSOT_BINDING_LARGE_VALS) buffer LargeVals { uint large_vals[]; };
layout(std430, set = 0, binding = FSOT_BINDING_LARGE_POINTS) buffer LargePoints { uint large_points[]; };
layout(std430, set = 0, binding = FSOT_BINDING_LARGE_PROJ) buffer LargeProj { float large_proj[]; };
layout(std430, set = 0, binding = FSOT_BINDING_LARGE_SEG) buffer LargeSeg { uint large_seg[]; };
layout(std430, set = 0, binding = FSOT_BINDING_LARGE_PKEY) buffer LargePKey { uint large_pkey[]; };
// Optimizer state: momentum or Adam's first moment; Adam's second.
layout(std430, set = 0, binding = FSOT_BINDING_FIRST) buffer First { float first[]; };
layout(std430, set = 0, binding = FSOT_BINDING_SECOND) buffer Second { float second[]; };
// The gather's per-element table (projection keys, or segments).
layout(std430, set = 0, binding = FSOT_BINDING_GATHER_TABLE) readonly buffer GatherTable { uint gather_table[]; };
// Indirect dispatches of the large-class stage: gather, then one group per class.
layout(std430, set = 0, binding = FSOT_BINDING_LARGE_ARGS) writeonly buffer LargeArgs { uvec4 large_args[]; };
layout(std430, set = 0, binding = FSOT_BINDING_SCATTER_TARGETS) readonly buffer ScatterTargets { uint scatter_targets[]; };
layout(std430, set = 0, binding = FSOT_BINDING_SCATTER_VALUES) readonly buffer ScatterValues { float scatter_values[]; };
layout(std430, set = 0, binding = FSOT_BINDING_HASH_VALUES) writeonly buffer HashValues { uint hash_values[]; };
layout(std430, set = 0, binding = FSOT_BINDING_SCHEDULE) buffer Schedule { RuleState schedule; };
// The per-lane transport's slice orders, in slots of one iteration each
// (slice_order.glsl says where each part lies): per slot, the slices in each
// class-size bin, each slice's bin, and the slices in order of decreasing class size.
// Classes the workgroup transport defers to its second pass (transport.comp,
// FSOT_FROM_LIST): that pass's indirect dispatch (workgroups x, y, z: x the
// slices listed up to FSOT_DEFER_GROUPS; y and z 1), the slices listed, then
// the slices; x and the count are reset each iteration.
layout(std430, set = 0, binding = FSOT_BINDING_DEFERRED) buffer Deferred {
    uint deferred_groups[3];
    uint deferred_count;
    uint deferred_slices[];
};
layout(std430, set = 0, binding = FSOT_BINDING_SLICE_ORDER) buffer SliceOrder { uint slice_order[]; };

// Views of the samples, the taps, the accumulators and the optimizer's state as
// uniform texel buffers (src/vk/texel_view.rs; on CPU implementations only).
// Passes built with FSOT_TEXEL_READS read them through the texture path, which
// llvmpipe gathers with one vector instruction, where it reads a storage buffer
// at per-lane addresses one lane at a time; the accessors below pick the path.
layout(set = 0, binding = FSOT_BINDING_SAMPLE_TEXELS) uniform samplerBuffer sample_texels; // R32_SFLOAT
layout(set = 0, binding = FSOT_BINDING_TAP_TEXELS) uniform usamplerBuffer tap_texels; // R32G32B32A32_UINT
#ifdef FSOT_FLOAT_ATOMICS
layout(set = 0, binding = FSOT_BINDING_ACC_TEXELS) uniform samplerBuffer acc_texels; // R32_SFLOAT
#else
layout(set = 0, binding = FSOT_BINDING_ACC_TEXELS) uniform usamplerBuffer acc_texels; // R32G32_UINT: int64 halves
#endif
layout(set = 0, binding = FSOT_BINDING_FIRST_TEXELS) uniform samplerBuffer first_texels; // R32_SFLOAT
layout(set = 0, binding = FSOT_BINDING_SECOND_TEXELS) uniform samplerBuffer second_texels; // R32_SFLOAT

float fsot_sample(uint i) {
#ifdef FSOT_TEXEL_READS
    return texelFetch(sample_texels, int(i)).x;
#else
    return samples[i];
#endif
}
uvec4 fsot_tap(uint t) {
#ifdef FSOT_TEXEL_READS
    return texelFetch(tap_texels, int(t));
#else
    return taps[t];
#endif
}
float fsot_first(uint i) {
#ifdef FSOT_TEXEL_READS
    return texelFetch(first_texels, int(i)).x;
#else
    return first[i];
#endif
}
float fsot_second(uint i) {
#ifdef FSOT_TEXEL_READS
    return texelFetch(second_texels, int(i)).x;
#else
    return second[i];
#endif
}
// Accumulator i in units of the sample.
float fsot_acc(uint i) {
#if defined(FSOT_TEXEL_READS) && defined(FSOT_FLOAT_ATOMICS)
    return texelFetch(acc_texels, int(i)).x;
#elif defined(FSOT_TEXEL_READS)
    return float(int64_t(packUint2x32(texelFetch(acc_texels, int(i)).xy))) * (1.0 / FSOT_FIXED_SCALE);
#elif defined(FSOT_FLOAT_ATOMICS)
    return acc[i];
#else
    return float(acc[i]) * (1.0 / FSOT_FIXED_SCALE);
#endif
}

#endif
