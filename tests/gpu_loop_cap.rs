//! A CPU implementation of Vulkan (lavapipe) runs an invocation's loops for 65535
//! iterations in all and drops the rest silently. The transport passes are
//! budgeted to stay under that; should a class still run past it, the run fails
//! with a clear error (a device failure: `auto` goes on with the CPU path) rather
//! than moving samples by garbage targets (lavapipe, validation on).
#![cfg(feature = "vulkan")]

mod common;

use fsot::core::kernel::KernelSpec;
use fsot::core::tile::Tile;
use fsot::optimize::settings::Settings;
use fsot::optimize::vulkan::{TransportKind, VulkanHooks, VulkanOptions, VulkanRun};

fn settings(iterations: u32) -> Settings {
    let mut s = Settings::new(KernelSpec::from_name("perceptual-taa", 2.1, None, 0.1, 60.0).unwrap(), 1);
    s.iterations = iterations;
    s
}

fn run_with(ctx: &fsot::vk::Context, lane_limit: Option<u32>, iterations: u32) -> fsot::error::Result<()> {
    // d = 8: each quantile of the f64 targets takes a loop of 257 per Newton
    // step, so a class of 200 samples per lane is far past the cap.
    let tile = Tile::new(16, 16, 8, 1, 8).unwrap();
    let options = VulkanOptions::default().deterministic(true).hooks(VulkanHooks {
        transport: Some(TransportKind::PerLane),
        unchecked_lane_limit: lane_limit,
        ..VulkanHooks::default()
    });
    let mut run = VulkanRun::new(ctx, tile, settings(iterations), None, options)?;
    while !run.finished() {
        run.step_batch(u32::MAX)?;
    }
    Ok(())
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn a_class_cut_short_by_the_loop_cap_fails_the_run_clearly() {
    let ctx = common::gpu_context();
    if !ctx.info().is_cpu()
        && common::skip("only CPU implementations of Vulkan cap loops; this device is a GPU")
    {
        return;
    }
    let err = run_with(&ctx, Some(200), 4).expect_err("classes of 200 at d = 8 per lane pass the cap");
    let text = err.to_string();
    assert!(text.contains("loop limit") && text.contains("CPU backend"), "{text}");
    assert!(err.is_device_failure(), "auto must be able to go on with the CPU path: {err:?}");
    // The budgeted limit (7 samples per lane at d = 8, the rest in the large-class
    // stage) never trips it, over more iterations than the failing run took.
    run_with(&ctx, None, 10).expect("the budgeted transport stays under the cap");
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn a_start_half_tied_half_spread_takes_its_budgeted_rounds_with_no_class_cut_short() {
    // Half the tile at one point, half white noise: in a group of lanes some
    // classes are mostly tied (the heap sort) and some spread (insertion).
    // Each lane of the largest classes' chunks takes two slices of up to 1360
    // samples at 32x32x16 taa, which the budget allows for either sort at its
    // worst. The sorts' actual loops stay well below their worst cases here,
    // so this does not show that the lanes of a group sort alike (the budget's
    // reason to make them); it shows the rounds planned and a run of such
    // classes kept whole.
    let ctx = common::gpu_context();
    if !ctx.info().is_cpu()
        && common::skip("only CPU implementations of Vulkan cap loops; this device is a GPU")
    {
        return;
    }
    let tile = Tile::new(32, 32, 16, 1, 2).unwrap();
    let mut mask = fsot::core::mask::Mask::white(tile, 4);
    let half = mask.samples.len() / 2;
    mask.samples[..half].iter_mut().for_each(|v| *v = 0.25);
    let mut s = Settings::new(KernelSpec::from_name("taa", 2.1, None, 0.1, 60.0).unwrap(), 3);
    s.iterations = 64;
    // The top tier takes the two rounds the budget allows.
    let options = VulkanOptions::default()
        .hooks(VulkanHooks { transport: Some(TransportKind::PerLane), ..VulkanHooks::default() });
    let mut run = VulkanRun::new(&ctx, tile, s, Some(&mask), options).unwrap();
    let order = run.slice_order(0).unwrap().expect("a per-lane run orders its slices");
    assert_eq!(order.tiers[0].rounds, 2, "{:?}", order.tiers[0]);
    while !run.finished() {
        run.step_batch(u32::MAX).expect("no class cut short");
    }
    common::assert_no_validation_messages(&ctx);
}
