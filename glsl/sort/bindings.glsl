// Every buffer, push-constant struct and binding index of the radix sort's passes,
// declared once. Mirrored once in Rust (src/vk/sort.rs); tests/spirv_layout.rs
// checks the compiled SPIR-V against the mirror. Every pass uses the same
// descriptor set layout (SORT_BINDINGS storage buffers); the ping-pong passes
// bind two sets, in and out swapped.
//
// An LSD sort of 32-bit keys with 32-bit payloads, 8 bits per pass,
// reduce-then-scan (no cross-workgroup waiting, so it is correct on drivers
// without forward progress between workgroups, lavapipe included), or, asked
// for on GPUs, decoupled look-back (radix_digits.comp, radix_onesweep.comp). A block is
// WG x ITEMS consecutive elements; block b's count of digit d lives at
// hist[d * blocks + b], so one exclusive scan of hist gives every (digit, block)
// its first output position. The element count is the first word of a buffer, so
// a producer on the GPU can set it.
#ifndef SORT_BINDINGS_GLSL
#define SORT_BINDINGS_GLSL

#define SORT_BINDING_COUNT 0
#define SORT_BINDING_KEYS_IN 1
#define SORT_BINDING_VALS_IN 2
#define SORT_BINDING_KEYS_OUT 3
#define SORT_BINDING_VALS_OUT 4
#define SORT_BINDING_HIST 5
#define SORT_BINDING_PARTIALS 6
#define SORT_BINDING_ARGS 7
#define SORT_BINDING_LOOK_BACK 8
#define SORT_BINDING_KEYS_TEXELS 9
#define SORT_BINDING_VALS_TEXELS 10
#define SORT_BINDINGS 11

struct RadixPush {
    uint shift;   // bit offset of this pass's digit
    uint blocks;  // blocks in the dispatch (hist has 256 x blocks entries); 0: from count
    uint chunks;  // scan chunks (workgroups of scan_reduce / scan_apply); 0: from count
    uint passes;  // the look-back path's digit count pass: digits counted (1 to 4)
};

layout(std430, set = 0, binding = SORT_BINDING_COUNT) readonly buffer SortCount { uint count; };
layout(std430, set = 0, binding = SORT_BINDING_KEYS_IN) readonly buffer KeysIn { uint keys_in[]; };
layout(std430, set = 0, binding = SORT_BINDING_VALS_IN) readonly buffer ValsIn { uint vals_in[]; };
layout(std430, set = 0, binding = SORT_BINDING_KEYS_OUT) writeonly buffer KeysOut { uint keys_out[]; };
layout(std430, set = 0, binding = SORT_BINDING_VALS_OUT) writeonly buffer ValsOut { uint vals_out[]; };
// The histogram is read by the workgroup that scans it in the histogram pass's
// TAIL variant, after other workgroups wrote it: coherent there.
#ifdef SORT_SCAN_TAIL
#define SORT_HIST_COHERENT coherent
#else
#define SORT_HIST_COHERENT
#endif
layout(std430, set = 0, binding = SORT_BINDING_HIST) SORT_HIST_COHERENT buffer Hist { uint hist[]; };
layout(std430, set = 0, binding = SORT_BINDING_PARTIALS) buffer Partials { uint partials[]; };
// Indirect dispatches when the count is only on the GPU: blocks, then scan chunks.
// (partials[0] is the TAIL histogram's count of finished workgroups, zeroed by the
// host before a sort and by the scanning workgroup after each pass.)
layout(std430, set = 0, binding = SORT_BINDING_ARGS) writeonly buffer SortArgs { uvec4 sort_args[]; };
// The look-back path (radix_digits.comp, radix_onesweep.comp; for devices that
// let a workgroup wait on one that started before it): per pass, a ticket counter
// (workgroups take block indices in the order they start) and the count of each
// digit over all pairs; per block and digit, a status word: 0 (not yet), or a
// flag in the top two bits (LB_AGGREGATE: the block's own count; LB_PREFIX: the
// count in every block up to and including this one) over a 30-bit count.
// Zeroed by the host: the whole buffer before a sort, the status before each pass.
layout(std430, set = 0, binding = SORT_BINDING_LOOK_BACK) buffer LookBack {
    uint lb_ticket[4];
    uint lb_digits[4 * 256];
    uint lb_status[];
};
// The input keys and payloads as uniform texel buffers (R32_UINT views of the
// same buffers), for the lanes path's reads (SORT_TEXEL_READS): a CPU
// implementation reads a storage buffer at per-lane addresses one lane at a
// time, and a texel buffer in one gather.
#ifdef SORT_TEXEL_READS
layout(set = 0, binding = SORT_BINDING_KEYS_TEXELS) uniform usamplerBuffer keys_texels;
layout(set = 0, binding = SORT_BINDING_VALS_TEXELS) uniform usamplerBuffer vals_texels;
uint key_in(uint i) { return texelFetch(keys_texels, int(i)).x; }
uint val_in(uint i) { return texelFetch(vals_texels, int(i)).x; }
#else
uint key_in(uint i) { return keys_in[i]; }
uint val_in(uint i) { return vals_in[i]; }
#endif
#define LB_AGGREGATE 0x40000000u
#define LB_PREFIX 0x80000000u
#define LB_COUNT 0x3fffffffu

#endif
