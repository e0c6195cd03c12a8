//! Masks straight into a renderer's memory (`fsot::render::device`): the test plays
//! the renderer. It makes its own Vulkan instance (validation layer on, its own
//! messenger), device, queue, image and buffers with `ash`, hands them to fsot
//! through `Context::wrap` with its queue lock, and reads the image back with
//! its own commands on its own queue. What it finds must be the mask the CPU
//! path makes for the same settings, quantised; the include, run on the GPU
//! over the image fsot wrote, must give what `SamplerPlan::value` says; images
//! that cannot hold the mask are refused before any GPU work; validation stays
//! silent throughout.
#![cfg(feature = "vulkan")]

mod common;
#[path = "common/wgsl.rs"]
mod wgsl;

use ash::vk;
use common::host::Host;
use fsot::core::mask::Mask;
use fsot::core::tile::Tile;
use fsot::io::ktx2::{quantize, texels, Format};
use fsot::optimize::run::{optimize, CancelFlag};
use fsot::optimize::settings::Settings;
use fsot::render::device::{
    layers_for, make_into_image, vk_format, write_mask, write_mask_to_buffer, write_plan, write_plan_block,
    write_plan_block_for,
};
use fsot::render::sampler::{SamplerPart, SamplerPlan};
use fsot::vk::{BufferTarget, ComputeDesc, ComputePipeline};

fn u16s(bytes: &[u8]) -> Vec<u16> {
    bytes.chunks_exact(2).map(|c| u16::from_le_bytes([c[0], c[1]])).collect()
}

const SAMPLED: vk::ImageUsageFlags = vk::ImageUsageFlags::from_raw(
    vk::ImageUsageFlags::SAMPLED.as_raw()
        | vk::ImageUsageFlags::TRANSFER_DST.as_raw()
        | vk::ImageUsageFlags::TRANSFER_SRC.as_raw(),
);

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn a_mask_made_on_the_renderers_device_lands_in_its_image_as_the_cpu_path_makes_it() {
    let host = Host::new(true);
    let tile = Tile::new(16, 16, 4, 1, 2).unwrap();
    let mut settings =
        Settings::new(fsot::core::kernel::KernelSpec::from_name("taa", 2.1, None, 0.1, 60.0).unwrap(), 7);
    settings.iterations = 3;
    let image = host.image(vk::Format::R16G16_UNORM, 16, 16, layers_for(&tile, 1), SAMPLED);
    let made = {
        let ctx = host.fsot();
        // SAFETY: the host's resources, made as their targets state, used by nothing else.
        unsafe { make_into_image(&ctx, tile, settings, &image.target, &CancelFlag::new(), &mut |_| {}) }
            .unwrap()
            .expect("not cancelled")
    }; // fsot's context is gone: the renderer's device, queue and image live on
    let got = u16s(&host.read_image(&image, 4));
    // Exactly the returned mask, quantised to round(v 65535), frame by frame, row by row.
    let want = u16s(&texels(&made, Format::R16G16Unorm).unwrap());
    assert_eq!(got, want);
    // And the mask the CPU path makes for the same settings, quantised: the two
    // backends agree to float rounding (1e-5), so a level apart at most.
    let cpu = optimize(tile, settings, None).unwrap();
    let mut equal = 0;
    for (i, &g) in got.iter().enumerate() {
        let (x, y, f, k) = ((i / 2) % 16, (i / 32) % 16, i / 512, i % 2);
        let level = quantize(cpu.sample(x, y, f, 0)[k], 16) as i64;
        assert!((g as i64 - level).abs() <= 1, "texel {i}: image {g}, CPU path {level}");
        equal += (g as i64 == level) as usize;
    }
    assert!(equal * 100 >= got.len() * 95, "{equal} of {} levels equal", got.len());
    // Cancelled before it starts (an animated start to make, which the flag
    // also cuts short): no mask and no event.
    let cancel = CancelFlag::new();
    cancel.cancel();
    let mut animated = settings;
    animated.start = fsot::Start::Animated;
    let ctx = host.fsot();
    let mut events = 0;
    // SAFETY: as above.
    let none = unsafe { make_into_image(&ctx, tile, animated, &image.target, &cancel, &mut |_| events += 1) }
        .unwrap();
    drop(ctx);
    assert!(none.is_none() && events == 0, "{events} events");
    host.free_image(image);
    host.assert_silent();
}

/// The frame the probes start at: eight frames before the frame count wraps.
const FIRST_FRAME: u32 = 0xFFFF_FFF8;

/// The renderer's shader: for every pixel, frame (three loops of the tile, from
/// `FIRST_FRAME` on, so the count wraps), sample of the pixel and part (one past
/// the last), the include's value.
const PROBE: &str = r#"#version 450
#extension GL_GOOGLE_include_directive : require
#define FSOT_SET 0
#define FSOT_BINDING 1
#include "fsot.glsl"
layout(set = 0, binding = 0, std430) buffer Out { vec4 values[]; };
layout(local_size_x = 64) in;
void main() {
    uint w = fsot_tile.x, h = fsot_tile.y, frames = 3u * fsot_tile.z, spp = fsot_tile.w;
    uint reads = fsot_count.x + 1u;
    uint i = gl_GlobalInvocationID.x;
    if (i >= w * h * frames * spp) return;
    uint at = i / spp;
    FsotSampler s = fsot_start(uvec2(at % w, (at / w) % h), 0xFFFFFFF8u + at / (w * h), i % spp);
    for (uint k = 0u; k < reads; ++k) values[i * reads + k] = fsot_get(s);
}
"#;

/// The same shader in WGSL, with fsot's WGSL include: the masks at binding 1 (a
/// texture read with textureLoad; the descriptor is the same combined image
/// sampler, whose image a WGSL texture reads), the plan block at 2.
const PROBE_WGSL: &str = r#"
@group(0) @binding(0) var<storage, read_write> values: array<vec4<f32>>;
@group(0) @binding(1) var fsot_masks: texture_2d_array<f32>;
@group(0) @binding(2) var<uniform> fsot_plan: FsotPlan;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = fsot_plan.tile.x;
    let h = fsot_plan.tile.y;
    let frames = 3u * fsot_plan.tile.z;
    let spp = fsot_plan.tile.w;
    let reads = fsot_plan.count.x + 1u;
    let i = id.x;
    if i >= w * h * frames * spp {
        return;
    }
    let at = i / spp;
    var s = fsot_start(vec2<u32>(at % w, (at / w) % h), 0xFFFFFFF8u + at / (w * h), i % spp);
    for (var k = 0u; k < reads; k++) {
        values[i * reads + k] = fsot_get(&s);
    }
}
"#;

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn the_include_reads_a_plan_written_into_the_renderers_image_as_the_cpu_mirror_says() {
    include_reads_the_plan(&common::compile_glsl(PROBE));
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn the_wgsl_include_reads_the_plan_as_the_glsl_one_does() {
    let wgsl = include_reads_the_plan(&wgsl::compile_wgsl(PROBE_WGSL));
    let glsl = include_reads_the_plan(&common::compile_glsl(PROBE));
    // Every value the same bit for bit, the white-noise fallback's too.
    let bits = |v: &[[f32; 4]]| v.iter().flat_map(|t| t.map(f32::to_bits)).collect::<Vec<u32>>();
    assert!(bits(&wgsl) == bits(&glsl), "the WGSL include reads other values than the GLSL one");
}

/// Writes a plan of two masks (2 samples a pixel) and three parts into the
/// renderer's image and uniform buffer, runs the probe `spirv` on them, checks
/// every value it read against the CPU mirror, and returns them.
fn include_reads_the_plan(spirv: &[u8]) -> Vec<[f32; 4]> {
    let host = Host::new(true);
    let tile = |d| Tile::new(8, 4, 3, 2, d).unwrap();
    let plan = SamplerPlan::new(
        vec![Mask::white(tile(2), 1), Mask::white(tile(1), 2)],
        vec![
            SamplerPart { mask: 0, dims: 2, offset: [0; 3], shift: vec![0.0, 0.0] },
            SamplerPart { mask: 1, dims: 1, offset: [5, 3, 2], shift: vec![0.75] },
            SamplerPart { mask: 0, dims: 2, offset: [3, 1, 1], shift: vec![0.25, 0.5] },
        ],
    )
    .unwrap();
    let format = Format::R16G16Unorm;
    let image = host.image(vk_format(format), 8, 4, layers_for(&tile(2), 2), SAMPLED);
    let block_bytes = plan.plan_block().unwrap().len() as u64;
    let (block, block_memory) =
        host.buffer(block_bytes, vk::BufferUsageFlags::UNIFORM_BUFFER | vk::BufferUsageFlags::TRANSFER_DST);
    let ctx = host.fsot();
    // SAFETY: the host's resources, made as their targets state, used by nothing else.
    unsafe { write_plan(&ctx, &plan, &image.target) }.unwrap();
    let block_target = BufferTarget {
        buffer: block,
        size: block_bytes,
        usage: vk::BufferUsageFlags::UNIFORM_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
        offset: 0,
    };
    // SAFETY: the host's resources, made as their targets state, used by nothing else.
    unsafe { write_plan_block(&ctx, &plan, &block_target) }.unwrap();
    assert_eq!(host.read_memory(block_memory, block_bytes as usize), plan.plan_block().unwrap());
    // A shader that defines FSOT_MAX_PARTS 32 takes a plan of 20 parts.
    let wide = SamplerPlan::new(
        plan.masks().to_vec(),
        (0..20).map(|k| SamplerPart { mask: 1, dims: 1, offset: [k, 0, 0], shift: vec![0.5] }).collect(),
    )
    .unwrap();
    // SAFETY: the host's resources, made as their targets state, used by nothing else.
    let err = unsafe { write_plan_block(&ctx, &wide, &block_target) }.unwrap_err().to_string();
    assert!(err.contains("FSOT_MAX_PARTS") && err.contains("plan_block_for"), "{err}");
    let wide_bytes = wide.plan_block_for(32).unwrap();
    let usage = vk::BufferUsageFlags::UNIFORM_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
    let (wide_block, wide_memory) = host.buffer(wide_bytes.len() as u64, usage);
    let wide_target = BufferTarget { buffer: wide_block, size: wide_bytes.len() as u64, usage, offset: 0 };
    // SAFETY: the host's resources, made as their targets state, used by nothing else.
    unsafe { write_plan_block_for(&ctx, &wide, 32, &wide_target) }.unwrap();
    assert_eq!(host.read_memory(wide_memory, wide_bytes.len()), wide_bytes);
    assert_eq!(wide_bytes.len(), 32 + 32 * 32, "a head and 32 parts, each two 16-byte vectors");

    // Run the probe through fsot's pipeline helper on the renderer's device, with
    // the renderer's own view and sampler.
    let d = &host.device;
    let view_info = vk::ImageViewCreateInfo::default()
        .image(image.target.image)
        .view_type(vk::ImageViewType::TYPE_2D_ARRAY)
        .format(image.target.format)
        .subresource_range(
            vk::ImageSubresourceRange::default()
                .aspect_mask(vk::ImageAspectFlags::COLOR)
                .level_count(1)
                .layer_count(image.target.layers),
        );
    // SAFETY: the image is alive and bound.
    let view = unsafe { d.create_image_view(&view_info, None) }.unwrap();
    // SAFETY: a default sampler.
    let sampler = unsafe { d.create_sampler(&vk::SamplerCreateInfo::default(), None) }.unwrap();
    let reads = plan.parts().len() + 1;
    let count = 8 * 4 * 9 * 2;
    let out = fsot::vk::Buffer::new(&ctx, (count * reads * 16) as u64, fsot::vk::Location::Device, "probe")
        .unwrap();
    let desc = ComputeDesc {
        spirv,
        bindings: 3,
        push_bytes: 0,
        spec: &[],
        sets: 1,
        images: &[1],
        uniforms: &[2],
        texels: &[],
        full_subgroups: false,
    };
    let pipeline = ComputePipeline::new(&ctx, &desc).unwrap();
    // SAFETY: the view, the sampler, `out` and the renderer's own uniform buffer
    // `block` outlive the one dispatch below; the image is sampled in its layout.
    unsafe {
        pipeline.bind_image(0, 1, view, sampler, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL).unwrap();
        pipeline.bind(0, &[(0, &out)]).unwrap();
        pipeline.bind_raw(0, &[(2, block)]).unwrap();
    }
    ctx.submit(|cmd| {
        pipeline.dispatch(cmd, 0, [(count as u32).div_ceil(64), 1, 1], &[]);
        fsot::vk::commands::barrier(cmd);
    })
    .unwrap();
    let got: Vec<[f32; 4]> = out.download(count * reads).unwrap();
    let mut fallback = Vec::new();
    for i in 0..count {
        let (at, sample) = (i / 2, (i % 2) as u32);
        let (x, y, f) = ((at % 8) as u32, ((at / 8) % 4) as u32, FIRST_FRAME.wrapping_add((at / 32) as u32));
        for k in 0..reads {
            let v = got[i * reads + k];
            match plan.value(k, x, y, f, sample, format) {
                Some(want) => {
                    // Every component, those past the mask's too (a channel
                    // the format lacks reads 0, alpha 1).
                    for j in 0..4 {
                        assert!(
                            (v[j] - want[j]).abs() < 1e-6,
                            "pixel ({x}, {y}) frame {f} sample {sample} part {k}: {v:?} vs {want:?}"
                        );
                    }
                }
                None => fallback.push(v[0]),
            }
        }
    }
    // Past the last part: defined white noise in [0, 1), not the masks.
    assert_eq!(fallback.len(), count);
    assert!(fallback.iter().all(|v| (0.0..1.0).contains(v)));
    let mean = fallback.iter().sum::<f32>() / count as f32;
    assert!((mean - 0.5).abs() < 0.1, "fallback mean {mean}");
    drop((pipeline, out, ctx));
    // SAFETY: nothing pending uses them.
    unsafe {
        d.destroy_sampler(sampler, None);
        d.destroy_image_view(view, None);
    }
    host.free_buffer(block, block_memory);
    host.free_image(image);
    host.assert_silent();
    got
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn images_and_buffers_that_cannot_hold_the_mask_are_refused_before_any_gpu_work() {
    let host = Host::new(true);
    // A queue the device does not have: refused before it is asked for.
    for (family, index, says) in
        [(99, 0, "queue family 99 of a device with"), (0, 99, "queue 99 of a family of")]
    {
        let external =
            fsot::vk::ExternalDevice { queue_family: family, queue_index: index, ..host.external() };
        // SAFETY: the host's live device; the queue it lacks is refused before it is asked for.
        let err =
            unsafe { fsot::vk::Context::wrap(external) }.err().expect("a queue the device lacks was taken");
        assert!(err.to_string().contains(says), "{err}");
    }
    let ctx = host.fsot();
    let tile = Tile::new(8, 8, 4, 1, 2).unwrap();
    let mask = Mask::white(tile, 3);
    let layers = layers_for(&tile, 1);
    let cases: [(vk::Format, u32, u32, vk::ImageUsageFlags, &str); 5] = [
        (vk::Format::R16G16_UNORM, 8, 4, SAMPLED, "the image is 8x4, the mask's tile 8x8"),
        (vk::Format::R16G16_UNORM, 8, 8, SAMPLED, "layers"),
        (vk::Format::B8G8R8A8_UNORM, 8, 8, SAMPLED, "fsot cannot write B8G8R8A8_UNORM"),
        (vk::Format::R8_UNORM, 8, 8, SAMPLED, "r8_unorm has 1 channel, the mask has d = 2"),
        (vk::Format::R16G16_UNORM, 8, 8, vk::ImageUsageFlags::SAMPLED, "lacks TRANSFER_DST"),
    ];
    for (k, (format, w, h, usage, says)) in cases.into_iter().enumerate() {
        let image = host.image(format, w, h, if k == 1 { layers * 2 } else { layers }, usage);
        // SAFETY: the host's resources, made as their targets state, used by nothing else.
        let err = unsafe { write_plan(&ctx, &SamplerPlan::single(mask.clone()).unwrap(), &image.target) }
            .unwrap_err();
        assert!(err.to_string().contains(says), "case {k}: {err}");
        // Refused before the optimizer starts: no iteration is run.
        let mut events = 0;
        let settings =
            Settings::new(fsot::core::kernel::KernelSpec::from_name("taa", 2.1, None, 0.1, 60.0).unwrap(), 1);
        let err =
            // SAFETY: the host's resources, made as their targets state, used by nothing else.
            unsafe { make_into_image(&ctx, tile, settings, &image.target, &CancelFlag::new(), &mut |_| events += 1) }
                .unwrap_err();
        assert!(err.to_string().contains(says), "case {k}: {err}");
        assert_eq!(events, 0);
        host.free_image(image);
    }
    // A buffer: too small, or without TRANSFER_DST.
    let bytes = (8 * 8 * 4 * 4) as u64;
    let (buffer, memory) =
        host.buffer(bytes, vk::BufferUsageFlags::TRANSFER_DST | vk::BufferUsageFlags::STORAGE_BUFFER);
    let target = BufferTarget { buffer, size: bytes, usage: vk::BufferUsageFlags::TRANSFER_DST, offset: 4 };
    // SAFETY: the host's resources, made as their targets state, used by nothing else.
    let err = unsafe { write_mask_to_buffer(&ctx, &mask, Format::R16G16Unorm, &target) }.unwrap_err();
    assert!(err.to_string().contains("do not fit"), "{err}");
    let target = BufferTarget { offset: 0, usage: vk::BufferUsageFlags::STORAGE_BUFFER, ..target };
    // SAFETY: the host's resources, made as their targets state, used by nothing else.
    let err = unsafe { write_mask_to_buffer(&ctx, &mask, Format::R16G16Unorm, &target) }.unwrap_err();
    assert!(err.to_string().contains("lacks TRANSFER_DST"), "{err}");
    // A mask whose values were set out of range by hand: refused, image or buffer.
    let target = BufferTarget { usage: vk::BufferUsageFlags::TRANSFER_DST, ..target };
    let mut nan = mask.clone();
    nan.samples[9] = f32::NAN;
    // SAFETY: the host's resources, made as their targets state, used by nothing else.
    let err = unsafe { write_mask_to_buffer(&ctx, &nan, Format::R16G16Unorm, &target) }.unwrap_err();
    assert!(err.to_string().contains("outside [0, 1)"), "{err}");
    let image = host.image(vk::Format::R16G16_UNORM, 8, 8, layers, SAMPLED);
    // SAFETY: the host's resources, made as their targets state, used by nothing else.
    let err = unsafe { write_mask(&ctx, &nan, &image.target) }.unwrap_err();
    assert!(err.to_string().contains("outside [0, 1)"), "{err}");
    host.free_image(image);
    // And one that fits: the texels land as the KTX2 file lays them out.
    // SAFETY: the host's resources, made as their targets state, used by nothing else.
    unsafe { write_mask_to_buffer(&ctx, &mask, Format::R16G16Unorm, &target) }.unwrap();
    assert_eq!(host.read_memory(memory, bytes as usize), texels(&mask, Format::R16G16Unorm).unwrap());
    drop(ctx);
    host.free_buffer(buffer, memory);
    host.assert_silent();
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn a_scene_plans_masks_are_made_on_the_renderers_device_and_stacked_in_its_image() {
    let host = Host::new(true);
    let text = "[display]\ntaa_alpha = 0.1\n[tile]\nsize = \"8x8x4\"\n\
                [[group]]\nname = \"pick\"\ndims = 1\n[[group]]\nname = \"lens\"\ndims = 2\n\
                [[group]]\nname = \"deep\"\ndims = 2\nvisible = false\n";
    let scene = fsot::scene::file::Scene::parse(text, "small").unwrap();
    let plan = fsot::scene::plan::Plan::new(&scene, &fsot::scene::plan::CostModel::unmeasured()).unwrap();
    assert_eq!(plan.masks.len(), 3);
    let tile = Tile::new(8, 8, 4, 1, 2).unwrap();
    // One layer short: refused before the first run.
    let short = host.image(vk::Format::R16G16_UNORM, 8, 8, layers_for(&tile, 3) - 1, SAMPLED);
    let ctx = host.fsot();
    let mut events = 0;
    // SAFETY: the host's resources, made as their targets state, used by nothing else.
    let err = unsafe {
        fsot::render::device::make_plan_into_image(
            &ctx,
            &plan,
            &short.target,
            &CancelFlag::new(),
            &mut |_| events += 1,
        )
    }
    .unwrap_err();
    assert!(err.to_string().contains("need 12"), "{err}");
    assert_eq!(events, 0);
    host.free_image(short);

    let image = host.image(vk::Format::R16G16_UNORM, 8, 8, layers_for(&tile, 3), SAMPLED);
    let mut done = Vec::new();
    // SAFETY: the host's resources, made as their targets state, used by nothing else.
    let sampler = unsafe {
        fsot::render::device::make_plan_into_image(&ctx, &plan, &image.target, &CancelFlag::new(), &mut |e| {
            if let fsot::scene::plan::PlanEvent::Done { file, iterations, .. } = e {
                done.push((file.to_string(), iterations))
            }
        })
    }
    .unwrap()
    .expect("not cancelled");
    drop(ctx);
    // The optimized masks ran until the plateau rule stopped them; the invisible
    // group reads white noise, made from its seed.
    assert_eq!(done.iter().map(|d| d.0.as_str()).collect::<Vec<_>>(), ["pick.exr", "lens.exr"]);
    assert!(done.iter().all(|d| d.1 > 0 && d.1 < 10_000), "{done:?}");
    assert_eq!(sampler.masks()[2].samples, Mask::white(tile, plan.masks[2].seed).samples);
    for k in 0..2 {
        // Each mask under the kernel it is made for (a scalar mask's eye is wider).
        let ratio = fsot::core::objective::score(&sampler.masks()[k], plan.masks[k].spec, 4096).ratio();
        assert!(ratio < 0.8, "mask {k}: {ratio} x white");
    }
    // Parts as the plan says, in the order the groups consume them.
    let parts: Vec<_> = plan.groups.iter().flat_map(|g| &g.parts).collect();
    assert_eq!(sampler.parts().len(), parts.len());
    for (s, p) in sampler.parts().iter().zip(&parts) {
        assert_eq!((s.dims, s.offset, &s.shift), (p.dims, p.offset, &p.shift));
        assert_eq!(plan.masks[s.mask].file, p.mask);
    }
    // The image holds the three masks, stacked, as the include reads them.
    let got = host.read_image(&image, 4);
    assert_eq!(got, sampler.texels(Format::R16G16Unorm).unwrap());

    // Under the plan's budget: each mask in its share of it, one after another.
    let budgeted = fsot::scene::plan::Plan { budget: Some(0.6), ..plan.clone() };
    let ctx = host.fsot();
    let began = std::time::Instant::now();
    let mut slowest = 0.0f64;
    let mut last = std::time::Instant::now();
    let mut order = Vec::new();
    // SAFETY: the host's resources, made as their targets state, used by nothing else.
    let sampler = unsafe {
        fsot::render::device::make_plan_into_image(
            &ctx,
            &budgeted,
            &image.target,
            &CancelFlag::new(),
            &mut |e| match e {
                fsot::scene::plan::PlanEvent::Start { file, .. } => order.push(format!("start {file}")),
                fsot::scene::plan::PlanEvent::Done { file, .. } => order.push(format!("done {file}")),
                fsot::scene::plan::PlanEvent::Run { .. } => {
                    slowest = slowest.max(last.elapsed().as_secs_f64());
                    last = std::time::Instant::now();
                }
                _ => {}
            },
        )
    }
    .unwrap()
    .expect("not cancelled");
    let seconds = began.elapsed().as_secs_f64();
    drop(ctx);
    for k in 0..2 {
        let budget = sampler.masks()[k].meta("budget_seconds");
        // Each run ends at the end of its share: the last at the budget's end (a
        // sum of shares, so within rounding).
        assert!(budget.is_some_and(|b| b.parse::<f64>().unwrap() <= 0.6 + 1e-9), "mask {k}: {budget:?}");
    }
    assert_eq!(order, ["start pick.exr", "done pick.exr", "start lens.exr", "done lens.exr"]);
    // The image's upload and the plan's set-up come on top of the runs' steps.
    assert!(seconds <= 0.6 + slowest + 0.5, "{seconds} s for a budget of 0.6 s ({slowest} s a step)");
    assert!(seconds >= 0.3, "{seconds} s: the budget was not used");
    host.free_image(image);
    host.assert_silent();
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn a_host_records_the_sort_into_its_own_command_buffer() {
    // The renderer's own command buffer, begun, submitted and waited for by
    // the renderer; fsot's radix sort recorded into it through `Recording`.
    // The pairs come out as a stable sort by key on the CPU orders them.
    let host = Host::new(true);
    let ctx = host.fsot();
    let n = 5000u32;
    let keys: Vec<u32> = (0..n).map(|i| i.wrapping_mul(2_654_435_761) >> 9).collect();
    let vals: Vec<u32> = (0..n).collect();
    let mut sort = fsot::vk::RadixSort::new(&ctx, n, fsot::vk::SortCount::Host).unwrap();
    sort.set_count(n).unwrap();
    sort.upload_pairs(&keys, &vals).unwrap();
    host.run(|cmd| {
        // SAFETY: `cmd` is the host's, begun on the device `ctx` wraps and its
        // compute queue, recorded only here; `run` waits for the device before
        // `sort` can go.
        let recording = unsafe { fsot::vk::Recording::new(&ctx, cmd) };
        // SAFETY: as above: the sort outlives the commands.
        unsafe { sort.record(recording, 32, Some(n)) };
    });
    let got: Vec<(u32, u32)> = sort
        .keys()
        .download::<u32>(n as usize)
        .unwrap()
        .into_iter()
        .zip(sort.vals().download::<u32>(n as usize).unwrap())
        .collect();
    let mut expected: Vec<(u32, u32)> = keys.into_iter().zip(vals).collect();
    expected.sort_by_key(|&(k, _)| k);
    assert!(got == expected, "the sort recorded into the host's buffer is not the stable sort");
    drop(sort);
    drop(ctx);
    host.assert_silent();
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn the_sort_sorts_a_hosts_own_buffers_in_place_and_refuses_ones_it_cannot_use() {
    // The renderer's buffers, filled through fsot's host-buffer fill, sorted
    // in place by a sort recorded into the renderer's command buffer, read back
    // by the renderer: by 32 bits (four passes) and by 24 (three: the odd pass
    // copied back into the host's buffers), each the CPU's stable sort.
    let host = Host::new(true);
    let ctx = host.fsot();
    let n = 3000u32;
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER
        | vk::BufferUsageFlags::TRANSFER_SRC
        | vk::BufferUsageFlags::TRANSFER_DST;
    let (kb, km) = host.buffer(4 * n as u64, usage);
    let (vb, vm) = host.buffer(4 * n as u64, usage);
    let target = |buffer| BufferTarget { buffer, size: 4 * n as u64, usage, offset: 0 };
    let mut sort = fsot::vk::RadixSort::with_storage_reads(&ctx, n, fsot::vk::SortCount::Host).unwrap();
    sort.set_count(n).unwrap();
    // SAFETY: both buffers outlive the sort (freed after it below), on its
    // device; nothing is pending.
    unsafe { sort.bind_pairs(&target(kb), &target(vb)) }.unwrap();
    for bits in [32u32, 24] {
        let keys: Vec<u32> = (0..n).map(|i| i.wrapping_mul(2_654_435_761) >> (32 - bits)).collect();
        let vals: Vec<u32> = (0..n).map(|i| i ^ 0x55).collect();
        // SAFETY: the host's buffers, alive, on the device `ctx` wraps, as
        // `target` states them; nothing else uses them now.
        unsafe { fsot::vk::buffer::fill_buffer(&ctx, &target(kb), bytemuck::cast_slice(&keys)) }.unwrap();
        // SAFETY: as above.
        unsafe { fsot::vk::buffer::fill_buffer(&ctx, &target(vb), bytemuck::cast_slice(&vals)) }.unwrap();
        host.run(|cmd| {
            // SAFETY: the host's command buffer, begun on the device `ctx`
            // wraps, recorded only here; `run` waits before anything goes.
            unsafe { sort.record(fsot::vk::Recording::new(&ctx, cmd), bits, Some(n)) };
        });
        let read =
            |memory| -> Vec<u32> { bytemuck::cast_slice(&host.read_memory(memory, 4 * n as usize)).to_vec() };
        let got: Vec<(u32, u32)> = read(km).into_iter().zip(read(vm)).collect();
        let mut expected: Vec<(u32, u32)> = keys.into_iter().zip(vals).collect();
        expected.sort_by_key(|&(k, _)| k);
        assert!(got == expected, "{bits} bits: the host's buffers are not the stable sort");
    }
    assert!(sort.sort_pairs(&[1], &[2]).unwrap_err().to_string().contains("host's buffers"));
    // A sort that reads through texel views, and buffers it cannot use, are
    // refused before anything is bound.
    let mut viewed = fsot::vk::RadixSort::new(&ctx, n, fsot::vk::SortCount::Host).unwrap();
    // SAFETY: refused before binding anything.
    let err = unsafe { viewed.bind_pairs(&target(kb), &target(vb)) }.unwrap_err().to_string();
    assert!(err.contains("with_storage_reads"), "{err}");
    let mut other = fsot::vk::RadixSort::with_storage_reads(&ctx, n, fsot::vk::SortCount::Host).unwrap();
    let small = BufferTarget { size: 4, ..target(kb) };
    let no_copy = BufferTarget { usage: vk::BufferUsageFlags::STORAGE_BUFFER, ..target(kb) };
    for (bad, says) in [(small, "must hold"), (no_copy, "usage")] {
        // SAFETY: refused before binding anything.
        let err = unsafe { other.bind_pairs(&bad, &target(vb)) }.unwrap_err().to_string();
        assert!(err.contains(says), "{err}");
    }
    drop((sort, viewed, other));
    drop(ctx);
    host.free_buffer(kb, km);
    host.free_buffer(vb, vm);
    host.assert_silent();
}
