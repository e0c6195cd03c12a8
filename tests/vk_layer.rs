//! The generic Vulkan layer on its own (no sampling): submissions from two
//! threads on one context, and the radix sort on a device that a host
//! application (this test) made itself and hands to fsot.
#![cfg(feature = "vulkan")]

mod common;

use ash::vk;
use fsot::core::rng::{derive, Stream};
use fsot::vk::{RadixSort, SortCount};

fn random_pairs(seed: u32, n: usize) -> (Vec<u32>, Vec<u32>) {
    let mut rng = Stream::new(derive(77, seed));
    let keys: Vec<u32> = (0..n).map(|_| rng.next_u32() % 1000).collect(); // many ties
    (keys, (0..n as u32).collect())
}

/// The CPU's stable sort: the reference.
fn cpu_sort(keys: &[u32], vals: &[u32]) -> (Vec<u32>, Vec<u32>) {
    let mut pairs: Vec<(u32, u32)> = keys.iter().copied().zip(vals.iter().copied()).collect();
    pairs.sort_by_key(|p| p.0);
    pairs.into_iter().unzip()
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn two_threads_sort_on_one_context_at_once() {
    let ctx = common::gpu_context();
    let threads: Vec<_> = (0..2u32)
        .map(|t| {
            let ctx = ctx.clone();
            std::thread::spawn(move || {
                let mut sort = RadixSort::new(&ctx, 100_000, SortCount::Host).unwrap();
                for round in 0..6u32 {
                    let (keys, vals) = random_pairs(10 * t + round, 30_000 + 7_000 * round as usize);
                    let got = sort.sort_pairs(&keys, &vals).unwrap();
                    assert_eq!(got, cpu_sort(&keys, &vals), "thread {t}, round {round}");
                }
            })
        })
        .collect();
    for t in threads {
        t.join().expect("a sorting thread failed");
    }
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn the_sort_runs_on_a_device_the_host_made() {
    // The host: its own instance (validation on, its own messenger), device and
    // queue, made with ash, without the 64-bit atomics the optimizer needs.
    let host = common::host::Host::new(false);
    {
        let ctx = host.fsot(); // fsot on the host's device, sharing the host's queue lock
        let mut sort = RadixSort::new(&ctx, 70_000, SortCount::Host).unwrap();
        for n in [1usize, 2047, 65_537] {
            let (keys, vals) = random_pairs(n as u32, n);
            assert_eq!(sort.sort_pairs(&keys, &vals).unwrap(), cpu_sort(&keys, &vals), "n = {n}");
        }
    } // fsot's sort and context dropped: the host's device must still be usable.
    let _host_submits = host.lock.lock().unwrap();
    // SAFETY: the host's own device, idle-waited under its queue lock.
    unsafe { host.device.device_wait_idle() }.expect("the host's device is alive");

    host.assert_silent();
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn an_owned_2d_array_image_takes_every_layer_and_gives_it_back_and_a_wrong_size_is_refused() {
    let ctx = common::gpu_context();
    let usage =
        vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::SAMPLED;
    let desc =
        fsot::vk::ImageDesc { format: vk::Format::R16G16_UNORM, width: 5, height: 3, layers: 4, usage };
    let mut image = fsot::vk::Image::new(&ctx, desc, "round-trip").unwrap();
    // Every texel distinct, so a swapped layer, row or channel would show.
    let bytes: Vec<u8> = (0..5 * 3 * 4 * 4).map(|i| (i * 7 % 251) as u8).collect();
    image.fill(&bytes, 4, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL).unwrap();
    assert_eq!(image.layout(), vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL);
    assert_eq!(image.read_back(4, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL).unwrap(), bytes);
    let err = image.fill(&bytes[4..], 4, vk::ImageLayout::GENERAL).unwrap_err();
    assert!(err.to_string().contains("holds 240 bytes, the data is 236"), "{err}");
    // A texel size other than the format's (1-byte texels of 4-byte R16G16: the
    // copy would read four times past the data), and an image left UNDEFINED.
    let err = image.fill(&bytes[..5 * 3 * 4], 1, vk::ImageLayout::GENERAL).unwrap_err();
    assert!(err.to_string().contains("4-byte texels, the copy was given 1"), "{err}");
    let err = image.read_back(16, vk::ImageLayout::GENERAL).unwrap_err();
    assert!(err.to_string().contains("4-byte texels, the copy was given 16"), "{err}");
    let err = image.fill(&bytes, 4, vk::ImageLayout::UNDEFINED).unwrap_err();
    assert!(err.to_string().contains("cannot be left in UNDEFINED"), "{err}");
    // Nor in a layout that is not a colour image's, nor in one its usage lacks.
    let err = image.fill(&bytes, 4, vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL).unwrap_err();
    assert!(err.to_string().contains("not DEPTH_STENCIL_ATTACHMENT_OPTIMAL"), "{err}");
    let err = image.fill(&bytes, 4, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL).unwrap_err();
    assert!(err.to_string().contains("needs the usage COLOR_ATTACHMENT"), "{err}");
    // Images the device cannot make, refused before vkCreateImage: no usage a
    // view allows, more layers than the device holds, a format it cannot store to.
    let copy_only = fsot::vk::ImageDesc { usage: vk::ImageUsageFlags::TRANSFER_DST, ..desc };
    let err = fsot::vk::Image::new(&ctx, copy_only, "copy-only").err().expect("a view of a copy-only image");
    assert!(err.to_string().contains("allows no view"), "{err}");
    let deep = fsot::vk::ImageDesc { layers: 1 << 24, ..desc };
    let err = fsot::vk::Image::new(&ctx, deep, "deep").err().expect("2^24 layers");
    assert!(err.to_string().contains("the device supports"), "{err}");
    let block_storage = fsot::vk::ImageDesc {
        format: vk::Format::BC1_RGB_UNORM_BLOCK,
        usage: vk::ImageUsageFlags::STORAGE,
        ..desc
    };
    let err = fsot::vk::Image::new(&ctx, block_storage, "bc1").err().expect("a compressed storage image");
    assert!(err.to_string().contains("not one of the plain colour formats"), "{err}");
    // Nor a packed format whose texels fsot cannot size (a copy would overrun its
    // staging buffer), nor a depth image's usage.
    let packed = fsot::vk::ImageDesc { format: vk::Format::B10G11R11_UFLOAT_PACK32, ..desc };
    let err = fsot::vk::Image::new(&ctx, packed, "packed").err().expect("a packed format");
    assert!(err.to_string().contains("not one of the plain colour formats"), "{err}");
    let depth_usage = fsot::vk::ImageDesc {
        usage: vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
        ..desc
    };
    let err = fsot::vk::Image::new(&ctx, depth_usage, "depth").err().expect("a depth usage");
    assert!(err.to_string().contains("not a colour image's"), "{err}");
    let _sampler = fsot::vk::Sampler::nearest(&ctx).unwrap();
    drop(image);
    common::assert_no_validation_messages(&ctx);
}

/// Reads texel j of a float view and of an RGBA32UI view (its texel j / 4,
/// component j % 4) into an output buffer: what a pass sees through a view.
const TEXEL_PROBE: &str = r#"#version 450
layout(local_size_x = 64) in;
layout(set = 0, binding = 0) uniform samplerBuffer floats;
layout(set = 0, binding = 1) uniform usamplerBuffer words;
layout(std430, set = 0, binding = 2) writeonly buffer Out { vec2 got[]; };
layout(push_constant) uniform Push { uint count; };
void main() {
    uint j = gl_GlobalInvocationID.x;
    if (j < count) {
        got[j] = vec2(texelFetch(floats, int(j)).x, float(texelFetch(words, int(j / 4u))[j % 4u]));
    }
}
"#;

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn a_texel_view_reads_a_buffer_as_its_storage_holds_it_and_a_binding_of_another_kind_is_refused() {
    let ctx = common::gpu_context();
    let spirv = common::compile_glsl(TEXEL_PROBE);
    use fsot::vk::{Buffer, ComputeDesc, ComputePipeline, Location, TexelView};
    let count = 1000usize;
    let floats: Vec<f32> = (0..count).map(|i| (i as f32 * 0.37).fract() - 0.5).collect();
    let words: Vec<u32> = (0..count as u32).map(|i| i * 7 % 1009).collect();
    let float_buf = Buffer::with_data(&ctx, &floats, Location::Device, "floats").unwrap();
    let word_buf = Buffer::with_data(&ctx, &words, Location::Device, "words").unwrap();
    let out = Buffer::new(&ctx, count as u64 * 8, Location::Device, "out").unwrap();
    let float_view = TexelView::new(&ctx, &float_buf, vk::Format::R32_SFLOAT, 4).unwrap();
    let word_view = TexelView::new(&ctx, &word_buf, vk::Format::R32G32B32A32_UINT, 16).unwrap();
    assert_eq!((float_view.texels, word_view.texels), (count as u64, count as u64 / 4));
    let desc = ComputeDesc {
        spirv: &spirv,
        bindings: 3,
        push_bytes: 4,
        spec: &[],
        sets: 1,
        images: &[],
        uniforms: &[],
        texels: &[0, 1],
        full_subgroups: false,
    };
    let pipeline = ComputePipeline::new(&ctx, &desc).unwrap();
    // SAFETY: the views and buffers are declared before the pipeline: they
    // outlive every dispatch.
    unsafe {
        pipeline.bind_texels(0, &[(0, &float_view), (1, &word_view)]).unwrap();
        pipeline.bind(0, &[(2, &out)]).unwrap();
        // A texel binding is no storage buffer, and a storage binding takes no view.
        assert!(pipeline.bind(0, &[(0, &float_buf)]).is_err());
        assert!(pipeline.bind_texels(0, &[(2, &float_view)]).is_err());
    }
    ctx.submit(|cmd| {
        pipeline.dispatch(cmd, 0, [(count as u32).div_ceil(64), 1, 1], &(count as u32).to_le_bytes());
        fsot::vk::commands::barrier(cmd);
    })
    .unwrap();
    let got: Vec<[f32; 2]> = out.download(count).unwrap();
    for (j, g) in got.iter().enumerate() {
        assert_eq!(*g, [floats[j], words[j] as f32], "texel {j}");
    }
    common::assert_no_validation_messages(&ctx);
}

/// Each invocation writes how many invocations of its subgroup are active, and
/// the subgroup size the shader sees.
const SUBGROUP_PROBE: &str = r#"#version 450
#extension GL_KHR_shader_subgroup_ballot : require
layout(local_size_x_id = 0) in;
layout(std430, set = 0, binding = 0) writeonly buffer Out { uvec2 got[]; };
void main() {
    got[gl_GlobalInvocationID.x] = uvec2(subgroupBallotBitCount(subgroupBallot(true)), gl_SubgroupSize);
}
"#;

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn a_pass_that_relies_on_full_subgroups_gets_them() {
    let ctx = common::gpu_context();
    let spirv = common::compile_glsl(SUBGROUP_PROBE);
    use fsot::vk::{Buffer, ComputeDesc, ComputePipeline, Location};
    let size = ctx.info().subgroup_size;
    // Whole subgroups: a workgroup of 64 invocations, or of one subgroup where
    // a subgroup is larger.
    let workgroup = size.max(64);
    let groups = 5u32;
    let count = (workgroup * groups) as usize;
    let out = Buffer::new(&ctx, count as u64 * 8, Location::Device, "out").unwrap();
    let desc = ComputeDesc {
        spirv: &spirv,
        bindings: 1,
        push_bytes: 0,
        spec: &[workgroup],
        sets: 1,
        images: &[],
        uniforms: &[],
        texels: &[],
        full_subgroups: true,
    };
    let pipeline = ComputePipeline::new(&ctx, &desc).unwrap();
    // Asked for where the device offers it (lavapipe does; the validation
    // layer checks the request), relied on where the device fills them unasked.
    assert_eq!(pipeline.full_subgroups(), ctx.info().full_subgroups);
    assert!(pipeline.full_subgroups() || ctx.info().fills_subgroups());
    // SAFETY: the buffer is declared before the pipeline: it outlives every dispatch.
    unsafe { pipeline.bind(0, &[(0, &out)]).unwrap() };
    ctx.submit(|cmd| {
        pipeline.dispatch(cmd, 0, [groups, 1, 1], &[]);
        fsot::vk::commands::barrier(cmd);
    })
    .unwrap();
    let got: Vec<[u32; 2]> = out.download(count).unwrap();
    for (i, g) in got.iter().enumerate() {
        assert_eq!(*g, [size, size], "invocation {i}: active lanes and gl_SubgroupSize");
    }
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn contexts_made_and_dropped_one_after_another_keep_working() {
    // A host may make a context for each job and drop it after: the 64th must
    // work as the first did (a sort checked against the CPU's), the process
    // keeping nothing of the ones before.
    const CONTEXTS: u32 = 64;
    for n in 1..=CONTEXTS {
        let ctx = fsot::vk::Context::new(&fsot::vk::ContextOptions { validation: true, device: None })
            .unwrap_or_else(|e| panic!("context {n} of {CONTEXTS} (the ones before made and dropped): {e}"));
        if n == 1 || n == CONTEXTS {
            let mut sort = RadixSort::new(&ctx, 4096, SortCount::Host).unwrap();
            let (keys, vals) = random_pairs(n, 4096);
            assert_eq!(sort.sort_pairs(&keys, &vals).unwrap(), cpu_sort(&keys, &vals), "context {n}");
            drop(sort);
        }
        common::assert_no_validation_messages(&ctx);
    }
}

#[test]
fn the_vulkan_layers_texel_sizes_agree_with_the_ktx2_formats_own() {
    for f in fsot::TexelFormat::ALL {
        let vk_format = vk::Format::from_raw(f.vk_format() as i32);
        assert_eq!(fsot::vk::texel_bytes_of(vk_format), Some(f.texel_bytes() as u32), "{}", f.name());
    }
    assert_eq!(fsot::vk::texel_bytes_of(vk::Format::B8G8R8A8_SRGB), Some(4));
    assert_eq!(fsot::vk::texel_bytes_of(vk::Format::R64G64B64A64_SFLOAT), Some(32));
    assert_eq!(fsot::vk::texel_bytes_of(vk::Format::BC1_RGB_UNORM_BLOCK), None, "a compressed block");
    assert_eq!(fsot::vk::texel_bytes_of(vk::Format::D32_SFLOAT), None, "depth");
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn a_submission_from_inside_the_recording_of_another_on_its_context_is_an_error_not_a_wait_for_ever() {
    use fsot::vk::{Buffer, Location};
    let ctx = common::gpu_context();
    let mut device_local = Buffer::new(&ctx, 64, Location::Device, "inner").unwrap();
    let mut inner = None;
    ctx.submit(|_| inner = Some(device_local.upload(&[7u32; 4]))).unwrap();
    let err = inner.unwrap().unwrap_err();
    assert!(err.to_string().contains("from inside the recording"), "{err}");
    // Outside a recording the same upload goes through, and the context works on.
    device_local.upload(&[7u32; 4]).unwrap();
    assert_eq!(device_local.download::<u32>(4).unwrap(), [7; 4]);
    common::assert_no_validation_messages(&ctx);
}
