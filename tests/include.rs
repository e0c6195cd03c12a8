//! The public GLSL include (`glsl/include/fsot.glsl`): a renderer's shader fsot
//! never saw compiles against it with shaderc, at the renderer's own set
//! and binding and at the defaults, and its plan block's std140 layout (read from
//! the SPIR-V with rspirv) is what `fsot::render::sampler` fills. The WGSL include
//! (`wgsl/fsot.wgsl`) validates in a renderer's module with its own group and
//! binding (naga), with the same block layout. The sampler's CPU formula is
//! checked against the include's documented rule by hand.

mod common;
#[path = "common/wgsl.rs"]
mod wgsl;

use std::collections::HashMap;

use fsot::core::mask::Mask;
use fsot::core::tile::Tile;
use fsot::io::ktx2::Format;
use fsot::render::sampler::{PartBlock, PlanHead, SamplerPart, SamplerPlan, MAX_PARTS, R4};
use rspirv::dr::{load_bytes, Operand};
use rspirv::spirv::{Decoration, Op};

const RENDERER: &str = r#"#version 450
#extension GL_GOOGLE_include_directive : require
// A renderer's own bindings around fsot's.
layout(set = 0, binding = 0, rgba32f) uniform writeonly image2D frame_out;
layout(set = 0, binding = 1) uniform Camera { mat4 view; uint frame; } camera;
DEFINES
#include "fsot.glsl"
layout(local_size_x = 8, local_size_y = 8) in;
void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    FsotSampler s = fsot_start(pixel, camera.frame, 0u);
    float pick = fsot_get_1d(s);
    vec2 lens = fsot_get_2d(s);
    vec4 deep = fsot_get_4d(s);
    imageStore(frame_out, ivec2(pixel), vec4(pick, lens, deep.x));
}
"#;

/// Compiles the renderer's shader with `defines`.
fn compile(defines: &str) -> Vec<u8> {
    common::compile_glsl(&RENDERER.replace("DEFINES", defines))
}

/// (set, binding) of every named variable, the std140 offsets of every named
/// struct's members, and array strides by element struct name.
#[allow(clippy::type_complexity)]
fn reflect(spv: &[u8]) -> (HashMap<String, (u32, u32)>, HashMap<String, Vec<u32>>, HashMap<String, u32>) {
    let m = load_bytes(spv).unwrap();
    let word = |o: &Operand| match o {
        Operand::LiteralBit32(v) | Operand::IdRef(v) => *v,
        other => panic!("{other:?}"),
    };
    let mut names = HashMap::new();
    for i in &m.debug_names {
        if let (Op::Name, [id, Operand::LiteralString(s)]) = (i.class.opcode, &i.operands[..]) {
            names.insert(word(id), s.clone());
        }
    }
    let (mut sets, mut bindings, mut offsets, mut strides) =
        (HashMap::new(), HashMap::new(), HashMap::<u32, Vec<(u32, u32)>>::new(), HashMap::new());
    for i in &m.annotations {
        match (i.class.opcode, &i.operands[..]) {
            (Op::Decorate, [t, Operand::Decoration(Decoration::DescriptorSet), v]) => {
                sets.insert(word(t), word(v));
            }
            (Op::Decorate, [t, Operand::Decoration(Decoration::Binding), v]) => {
                bindings.insert(word(t), word(v));
            }
            (Op::Decorate, [t, Operand::Decoration(Decoration::ArrayStride), v]) => {
                strides.insert(word(t), word(v));
            }
            (Op::MemberDecorate, [t, member, Operand::Decoration(Decoration::Offset), v]) => {
                offsets.entry(word(t)).or_default().push((word(member), word(v)));
            }
            _ => {}
        }
    }
    let mut element_of = HashMap::new();
    for i in &m.types_global_values {
        if i.class.opcode == Op::TypeArray {
            element_of.insert(i.result_id.unwrap(), word(&i.operands[0]));
        }
    }
    let mut places = HashMap::new();
    for (id, set) in &sets {
        places.insert(names.get(id).cloned().unwrap_or_default(), (*set, bindings[id]));
    }
    let mut layouts = HashMap::new();
    for (id, mut members) in offsets {
        members.sort();
        layouts
            .insert(names.get(&id).cloned().unwrap_or_default(), members.into_iter().map(|m| m.1).collect());
    }
    let mut by_element = HashMap::new();
    for (array, stride) in strides {
        if let Some(e) = element_of.get(&array) {
            by_element.insert(names.get(e).cloned().unwrap_or_default(), stride);
        }
    }
    (places, layouts, by_element)
}

#[test]
fn a_renderers_shader_compiles_with_its_own_set_and_binding_and_the_plan_block_is_the_rust_mirror() {
    let spv = compile("#define FSOT_SET 3\n#define FSOT_BINDING 7");
    let (places, layouts, strides) = reflect(&spv);
    assert_eq!(places["fsot_masks"], (3, 7));
    assert_eq!(places[""], (3, 8), "the plan block (an anonymous instance) at FSOT_BINDING + 1: {places:?}");
    assert_eq!(places["frame_out"], (0, 0), "the renderer's own bindings untouched");
    assert_eq!(layouts["FsotPlan"], [0, 16, 32]);
    assert_eq!(std::mem::offset_of!(PlanHead, count), 16);
    assert_eq!(std::mem::size_of::<PlanHead>(), 32);
    assert_eq!(layouts["FsotPart"], [0, 16]);
    assert_eq!(std::mem::offset_of!(PartBlock, shift), 16);
    assert_eq!(strides["FsotPart"] as usize, std::mem::size_of::<PartBlock>());
    // Defaults: set 0, bindings 0 and 1 (here the renderer's own use them too, so
    // it would define its own; the include itself compiles).
    let spv = compile("");
    let (places, ..) = reflect(&spv);
    assert_eq!(places["fsot_masks"], (0, 0));
    // And with a larger block (`compile` fails the test with shaderc's message otherwise).
    let spv = compile("#define FSOT_MAX_PARTS 64");
    let (places, ..) = reflect(&spv);
    assert_eq!(places["fsot_masks"], (0, 0));
}

const WGSL_RENDERER: &str = r#"
// A renderer's own bindings around fsot's, at its own group and binding.
@group(0) @binding(0) var frame_out: texture_storage_2d<rgba32float, write>;
@group(2) @binding(5) var fsot_masks: texture_2d_array<f32>;
@group(2) @binding(6) var<uniform> fsot_plan: FsotPlan;
@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    var s = fsot_start(id.xy, 0u, 0u);
    let pick = fsot_get_1d(&s);
    let lens = fsot_get_2d(&s);
    let deep = fsot_get_4d(&s);
    let more = fsot_get_3d(&s);
    textureStore(frame_out, vec2<i32>(id.xy), vec4<f32>(pick, lens, deep.x + more.z));
}
"#;

#[test]
fn a_renderers_wgsl_module_validates_with_its_own_bindings_and_the_plan_block_is_the_rust_mirror() {
    // Parsed, validated and written as SPIR-V (`compile_wgsl` fails the test
    // with naga's message otherwise).
    let spv = wgsl::compile_wgsl(WGSL_RENDERER);
    let (places, layouts, strides) = reflect(&spv);
    assert_eq!(places["fsot_masks"], (2, 5));
    assert_eq!(places["fsot_plan"], (2, 6));
    assert_eq!(places["frame_out"], (0, 0));
    // The layout as naga lays out WGSL's uniform address space, and as written.
    let module = wgsl::wgsl_module(WGSL_RENDERER);
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).unwrap();
    let strukt = |name: &str| {
        let (handle, ty) = module.types.iter().find(|(_, t)| t.name.as_deref() == Some(name)).unwrap();
        match &ty.inner {
            naga::TypeInner::Struct { members, span } => (
                members.iter().map(|m| m.offset).collect::<Vec<_>>(),
                *span,
                layouter[handle].size,
                members.clone(),
            ),
            other => panic!("{name} is {other:?}"),
        }
    };
    let (plan, plan_span, _, members) = strukt("FsotPlan");
    assert_eq!(plan, [0, 16, 32]);
    let parts = match module.types[members[2].ty].inner {
        naga::TypeInner::Array { stride, size: naga::ArraySize::Constant(n), .. } => (stride, n.get()),
        ref other => panic!("parts is {other:?}"),
    };
    assert_eq!(parts, (std::mem::size_of::<PartBlock>() as u32, MAX_PARTS as u32));
    assert_eq!(
        plan_span as usize,
        std::mem::size_of::<PlanHead>() + MAX_PARTS * std::mem::size_of::<PartBlock>()
    );
    let (part, part_span, ..) = strukt("FsotPart");
    assert_eq!(part, [0, std::mem::offset_of!(PartBlock, shift) as u32]);
    assert_eq!(part_span as usize, std::mem::size_of::<PartBlock>());
    // The constants: the parts the block holds and the R4 sequence, as the Rust
    // mirror's.
    let constant = |name: &str| {
        let c = module.constants.iter().find(|(_, c)| c.name.as_deref() == Some(name)).unwrap().1;
        let literal = |e: naga::Handle<naga::Expression>| match module.global_expressions[e] {
            naga::Expression::Literal(naga::Literal::U32(v)) => v,
            ref other => panic!("{name}: {other:?}"),
        };
        match &module.global_expressions[c.init] {
            naga::Expression::Compose { components, .. } => components.iter().map(|&e| literal(e)).collect(),
            _ => vec![literal(c.init)],
        }
    };
    assert_eq!(constant("FSOT_MAX_PARTS"), [MAX_PARTS as u32]);
    assert_eq!(constant("FSOT_R4"), R4);
    // The SPIR-V naga writes carries the same offsets and stride.
    assert_eq!(layouts["FsotPlan"], [0, 16, 32]);
    assert_eq!(layouts["FsotPart"], [0, 16]);
    assert_eq!(strides["FsotPart"] as usize, std::mem::size_of::<PartBlock>());
}

#[test]
fn the_vulkan_guides_wgsl_shader_validates_with_the_include() {
    let guide = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/vulkan.md")).unwrap();
    let blocks: Vec<&str> =
        guide.split("```wgsl\n").skip(1).map(|b| b.split("```").next().unwrap()).collect();
    assert_eq!(blocks.len(), 1, "the guide's WGSL blocks");
    let spv = wgsl::compile_wgsl(blocks[0]);
    let (places, ..) = reflect(&spv);
    assert_eq!((places["fsot_masks"], places["fsot_plan"]), ((1, 0), (1, 1)));
}

fn two_masks() -> SamplerPlan {
    let tile = |d| Tile::new(4, 3, 2, 1, d).unwrap();
    let masks = vec![Mask::white(tile(1), 1), Mask::white(tile(2), 2)];
    let parts = vec![
        SamplerPart { mask: 0, dims: 1, offset: [0; 3], shift: vec![0.0] },
        SamplerPart { mask: 1, dims: 2, offset: [0; 3], shift: vec![0.0, 0.0] },
        SamplerPart { mask: 1, dims: 2, offset: [3, 1, 1], shift: vec![0.25, 0.5] },
    ];
    SamplerPlan::new(masks, parts).unwrap()
}

#[test]
fn the_plan_block_holds_the_tile_the_parts_and_each_masks_base_layer() {
    let plan = two_masks();
    let bytes = plan.plan_block().unwrap();
    assert_eq!(bytes.len(), 32 + 32 * MAX_PARTS);
    let u = |i: usize| u32::from_le_bytes(bytes[4 * i..4 * i + 4].try_into().unwrap());
    let f = |i: usize| f32::from_le_bytes(bytes[4 * i..4 * i + 4].try_into().unwrap());
    assert_eq!([u(0), u(1), u(2), u(3), u(4)], [4, 3, 2, 1, 3]);
    // Part 2 (words 24..32): offset 3, 1, 1; mask 1 starts at layer T * spp = 2.
    assert_eq!([u(24), u(25), u(26), u(27)], [3, 1, 1, 2]);
    assert_eq!([f(28), f(29), f(30), f(31)], [0.25, 0.5, 0.0, 0.0]);
    assert!(bytes[32 * 4..].iter().all(|b| *b == 0), "unused parts zero");
    assert!(plan.plan_block_for(2).is_err(), "three parts do not fit two");
    // The stacked image: mask 0's two layers then mask 1's, in a format for d = 2.
    let texels = plan.texels(Format::R16G16Unorm).unwrap();
    assert_eq!(texels.len(), 2 * (4 * 3 * 2) * 4);
}

#[test]
fn a_get_reads_the_offset_texel_adds_the_shift_and_a_new_r4_turn_per_loop_of_the_tile() {
    let plan = two_masks();
    let m = &plan.masks()[1];
    let fmt = Format::R32G32Sfloat;
    // Part 2 at pixel (2, 2), frame 0: texel ((2 + 3) % 4, (2 + 1) % 3, (0 + 1) % 2).
    let v = plan.value(2, 2, 2, 0, 0, fmt).unwrap();
    let t = m.sample(1, 0, 1, 0);
    for j in 0..2 {
        let want = (t[j] as f64 + [0.25, 0.5][j]).fract();
        assert!((v[j] as f64 - want).abs() < 1e-6, "{} against {want}", v[j]);
    }
    // Frame 3 + offset 1 = 4: the second loop of the 2-frame tile (turn 2).
    let v = plan.value(2, 2, 2, 3, 0, fmt).unwrap();
    let t = m.sample(1, 0, 0, 0);
    for j in 0..2 {
        let turn = (2.0 * R4[j] as f64 / 4_294_967_296.0).fract();
        let want = (t[j] as f64 + [0.25, 0.5][j] + turn).fract();
        assert!((v[j] as f64 - want).abs() < 1e-6, "{} against {want}", v[j]);
    }
    // R4 in fixed point is 1 / phi^k, phi^5 = phi + 1.
    let phi = 1.0 / (R4[0] as f64 / 4_294_967_296.0);
    assert!((phi.powi(5) - phi - 1.0).abs() < 1e-8);
    // UNORM: the texel as q / 65535.
    let v = plan.value(0, 0, 0, 0, 0, Format::R16Unorm).unwrap();
    let q = (plan.masks()[0].sample(0, 0, 0, 0)[0] as f64 * 65535.0).round() / 65535.0;
    assert!((v[0] as f64 - q.fract()).abs() < 1e-6);
    // Past the last part: the include's hash fallback, not a mask.
    assert_eq!(plan.value(3, 0, 0, 0, 0, fmt), None);
    // A 2-D mask in a one-channel format: no value (`texels` refuses it too).
    assert_eq!(plan.value(1, 0, 0, 0, 0, Format::R16Unorm), None);
    assert!(plan.texels(Format::R16Unorm).is_err());
}

#[test]
fn a_sampler_plan_is_refused_unless_every_part_reads_a_mask_it_holds() {
    let tile = |d| Tile::new(4, 3, 2, 1, d).unwrap();
    let part = |mask, dims, shift: &[f32]| SamplerPart { mask, dims, offset: [0; 3], shift: shift.to_vec() };
    let mut nan_mask = Mask::white(tile(1), 1);
    nan_mask.samples[0] = f32::NAN;
    let cases: Vec<(&str, Vec<Mask>, Vec<SamplerPart>)> = vec![
        ("no masks", vec![], vec![]),
        ("a mask index past the list", vec![Mask::white(tile(1), 1)], vec![part(1, 1, &[0.0])]),
        ("more dimensions than its mask", vec![Mask::white(tile(1), 1)], vec![part(0, 2, &[0.0, 0.0])]),
        ("no dimensions", vec![Mask::white(tile(1), 1)], vec![part(0, 0, &[])]),
        ("a shift per dimension missing", vec![Mask::white(tile(2), 1)], vec![part(0, 2, &[0.0])]),
        ("a NaN shift", vec![Mask::white(tile(1), 1)], vec![part(0, 1, &[f32::NAN])]),
        // In f32, fract(-1e-9) is 1.0: a get would leave [0, 1).
        ("a negative shift", vec![Mask::white(tile(1), 1)], vec![part(0, 1, &[-1e-9])]),
        ("a shift of 1", vec![Mask::white(tile(1), 1)], vec![part(0, 1, &[1.0])]),
        ("a mask of 5 dimensions", vec![Mask::white(tile(5), 1)], vec![part(0, 1, &[0.0])]),
        (
            "masks of two sizes",
            vec![Mask::white(tile(1), 1), Mask::white(Tile::new(4, 3, 4, 1, 1).unwrap(), 2)],
            vec![part(0, 1, &[0.0])],
        ),
        ("a NaN value", vec![nan_mask], vec![part(0, 1, &[0.0])]),
        ("more parts than a block holds", vec![Mask::white(tile(1), 1)], vec![part(0, 1, &[0.0]); 2048]),
    ];
    for (what, masks, parts) in cases {
        assert!(SamplerPlan::new(masks, parts).is_err(), "{what}");
    }
    // Past the default block, a larger FSOT_MAX_PARTS holds them, up to 64 KiB.
    let plan = SamplerPlan::new(vec![Mask::white(tile(1), 1)], vec![part(0, 1, &[0.0]); 20]).unwrap();
    assert!(plan.plan_block().unwrap_err().to_string().contains("FSOT_MAX_PARTS"));
    assert_eq!(plan.plan_block_for(64).unwrap().len(), 32 + 32 * 64);
    assert!(plan.plan_block_for(1 << 40).is_err(), "a block of 2^40 parts");
}

#[test]
fn a_get_at_an_offset_past_u32_wraps_as_the_includes_unsigned_arithmetic() {
    let tile = Tile::new(4, 3, 2, 1, 1).unwrap();
    let mask = Mask::white(tile, 1);
    let far = SamplerPart { mask: 0, dims: 1, offset: [u32::MAX, u32::MAX - 1, u32::MAX], shift: vec![0.0] };
    let plan = SamplerPlan::new(vec![mask.clone()], vec![far]).unwrap();
    // x = 5: (5 + 2^32 - 1) mod 2^32 = 4, 4 mod 4 = 0; y = 2: (2 + 2^32 - 2) mod 2^32 = 0.
    let v = plan.value(0, 5, 2, 0, 0, Format::R32Sfloat).unwrap();
    let turn = ((u32::MAX / 2).wrapping_mul(R4[0]) >> 8) as f64 / 16_777_216.0;
    let frame = (u32::MAX % 2) as usize;
    let want = (mask.sample(0, 0, frame, 0)[0] as f64 + turn).fract();
    assert!((v[0] as f64 - want).abs() < 1e-6, "{} against {want}", v[0]);
}

#[test]
fn a_plan_folder_reads_into_a_sampler_plan_and_a_bad_one_is_refused() {
    let text = "[display]\ntaa_alpha = 0.1\n[tile]\nsize = \"4x4x2\"\n\
                [[group]]\nname = \"light\"\ndims = 2\n[[group]]\nname = \"bsdf\"\ndims = 2\n";
    let scene = fsot::scene::file::Scene::parse(text, "s").unwrap();
    let options = fsot::RunOptions::default().backend(fsot::BackendChoice::Cpu);
    let plan = fsot::scene::plan::Plan::new(&scene, &fsot::scene::plan::CostModel::unmeasured()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    plan.execute(dir.path(), &options, 100, false, &fsot::optimize::run::CancelFlag::new(), &mut |_| {})
        .unwrap();
    let sp = SamplerPlan::read(dir.path()).unwrap();
    assert_eq!(sp.masks().len(), 1, "bsdf shares light's mask");
    assert_eq!(sp.parts().len(), 2);
    assert_eq!(sp.parts()[1].offset, fsot::scene::plan::share_offset(1, [4, 4, 2]));
    std::fs::write(dir.path().join("plan.json"), "{\"tile\": [4, 4, 2], \"groups\": 3}").unwrap();
    assert!(SamplerPlan::read(dir.path()).unwrap_err().to_string().contains("not a plan file"));
    assert!(SamplerPlan::read(&dir.path().join("missing")).is_err());
}
