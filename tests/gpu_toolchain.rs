//! The GPU toolchain works: the embedded shaders run on a Vulkan device
//! (lavapipe in CI) with the validation layer on, and agree with the CPU.
#![cfg(feature = "vulkan")]

mod common;

use fsot::core::rng::hash2;
use fsot::optimize::vulkan::layout::{binding, HashPush};
use fsot::optimize::vulkan::shaders;
use fsot::vk::commands::barrier;
use fsot::vk::{Buffer, ComputeDesc, ComputePipeline, Location};

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn a_compute_shader_draws_the_same_random_stream_as_the_cpu() {
    let ctx = common::gpu_context();
    let info = ctx.info().clone();
    eprintln!("device: {} ({}), subgroup size {}", info.name, info.driver, info.subgroup_size);
    assert!(info.subgroup_size.is_power_of_two(), "{}", info.subgroup_size);

    let count: u32 = 1000; // not a multiple of the workgroup size: tests the bound check
    let key: u32 = 0xdead_beef;
    let workgroup = 64u32;
    let bytes = count as u64 * 4;
    let out = Buffer::new(&ctx, bytes, Location::Device, "hash-out").unwrap();
    let desc = ComputeDesc {
        spirv: shaders::HASH_FILL,
        bindings: binding::BINDINGS,
        push_bytes: std::mem::size_of::<HashPush>() as u32,
        spec: &[workgroup],
        sets: 1,
        images: &[],
        uniforms: &[],
        texels: &binding::TEXELS,
        full_subgroups: false,
    };
    let pipeline = ComputePipeline::new(&ctx, &desc).unwrap();
    // SAFETY: `out` is declared before the pipeline: it outlives every dispatch.
    unsafe { pipeline.bind(0, &[(binding::HASH_VALUES, &out)]) }.unwrap();
    let push = HashPush { key, count };
    ctx.submit(|cmd| {
        pipeline.dispatch(cmd, 0, [count.div_ceil(workgroup), 1, 1], bytemuck::bytes_of(&push));
        barrier(cmd);
    })
    .unwrap();
    let got: Vec<u32> = out.download(count as usize).unwrap();
    for (i, &v) in got.iter().enumerate() {
        assert_eq!(v, hash2(key, i as u32), "value {i}");
    }
    drop(pipeline);
    drop(out);
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn buffers_larger_than_a_binding_are_refused_with_a_clear_error() {
    let ctx = common::gpu_context();
    let limit = ctx.info().max_storage_buffer_range;
    let err = Buffer::new(&ctx, limit + 4, Location::Device, "too-big").err().expect("must fail");
    assert!(err.to_string().contains("maxStorageBufferRange"), "{err}");
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn the_validation_layer_is_live_and_its_messages_are_caught() {
    // A buffer with no usage bits breaks a valid-usage rule; the layer must report
    // it, or the other GPU tests' "no messages" would prove nothing.
    let ctx = common::gpu_context();
    let info = ash::vk::BufferCreateInfo::default().size(16).usage(ash::vk::BufferUsageFlags::empty());
    // Another context of the process, alive meanwhile: the message names the
    // first one's device, so it goes to that context alone.
    let other = common::gpu_context();
    // SAFETY: a deliberately invalid create info; the layer reports it, the driver may still make the buffer.
    let made = unsafe { ctx.device().create_buffer(&info, None) };
    if let Ok(buffer) = made {
        // SAFETY: the buffer was made above and is unused.
        unsafe { ctx.device().destroy_buffer(buffer, None) };
    }
    let messages = ctx.validation_messages();
    assert!(
        messages.iter().any(|m| m.contains("usage")),
        "expected a validation error about buffer usage, got {messages:?}"
    );
    common::assert_no_validation_messages(&other);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn contexts_made_one_after_another_share_one_instance_and_each_has_its_own_device() {
    // Drivers have failed after many instances made and destroyed in one
    // process: a context makes and destroys its device, on the process's one
    // instance (per validation setting).
    let first = common::gpu_context();
    let instance = first.external().instance.handle();
    drop(first);
    let second = common::gpu_context();
    assert_eq!(second.external().instance.handle(), instance, "a new instance for the second context");
    let third = common::gpu_context();
    assert_eq!(third.external().instance.handle(), instance);
    assert_ne!(second.device().handle(), third.device().handle(), "two live contexts share a device");
    // The first context's device is gone; the later ones work.
    let buffer = Buffer::new(&third, 64, Location::Device, "after-others").unwrap();
    drop(buffer);
    common::assert_no_validation_messages(&second);
    common::assert_no_validation_messages(&third);
}
