//! The per-lane transport's slice order (`glsl/fsot/slice_order.glsl`): on a CPU
//! implementation of Vulkan, each iteration's slices are taken largest class
//! first, so the lanes that run together have classes of about the same size.
//! Checked against the CPU's own slice draws (lavapipe in CI, validation on).
#![cfg(feature = "vulkan")]

mod common;

use fsot::core::kernel::{Kernel, KernelSpec};
use fsot::core::rng::seed_key;
use fsot::core::slice::SliceSampler;
use fsot::core::tile::Tile;
use fsot::optimize::backend::Backend;
use fsot::optimize::settings::Settings;
use fsot::optimize::vulkan::shape::LANE_BUDGET;
use fsot::optimize::vulkan::{LaneTier, TransportKind, VulkanHooks, VulkanOptions, VulkanRun};
use fsot::vk::Context;

fn settings(seed: u64) -> Settings {
    let mut s = Settings::new(KernelSpec::from_name("taa", 2.1, None, 0.1, 60.0).unwrap(), seed);
    s.iterations = 40;
    s
}

/// Lanes' work over the members' when `lanes` consecutive slices run together
/// and each group takes as long as its largest class.
fn lane_waste(lens: &[u32], lanes: usize) -> f64 {
    let busy: u64 = lens.chunks(lanes).map(|c| *c.iter().max().unwrap() as u64 * c.len() as u64).sum();
    busy as f64 / lens.iter().map(|&n| n as u64).sum::<u64>() as f64
}

/// Whether the device is a CPU implementation, which the per-lane transport is
/// for (elsewhere the test fails unless skips are allowed: `common::skip`).
fn takes_the_per_lane_transport(ctx: &Context) -> bool {
    ctx.info().is_cpu()
        || !common::skip("the per-lane transport is for CPU implementations; this device is a GPU")
}

/// A whole deterministic per-lane run of 16x16x8 `taa` (seed 5, 40 iterations)
/// with these options besides: its samples.
fn whole_per_lane_run(ctx: &Context, options: VulkanOptions) -> Vec<f32> {
    let tile = Tile::new(16, 16, 8, 1, 2).unwrap();
    let options = options
        .deterministic(true)
        .hooks(VulkanHooks { transport: Some(TransportKind::PerLane), ..options.hooks });
    let mut run = VulkanRun::new(ctx, tile, settings(5), None, options).unwrap();
    while !run.finished() {
        run.step_batch(u32::MAX).unwrap();
    }
    run.mask().unwrap().samples
}

/// A per-lane run of `tile` (`taa`, seed 5), the CPU's draws of its slices,
/// and its kernel's taps.
fn per_lane_run_and_its_slices(ctx: &Context, tile: Tile) -> (VulkanRun, SliceSampler, u32) {
    let s = settings(5);
    let options = VulkanOptions::default()
        .hooks(VulkanHooks { transport: Some(TransportKind::PerLane), ..VulkanHooks::default() });
    let gpu = VulkanRun::new(ctx, tile, s, None, options).unwrap();
    let kernel = Kernel::new(s.kernel, &tile);
    (gpu, SliceSampler::new(seed_key(s.seed), tile, &kernel, s.axis_share), kernel.taps.len() as u32)
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn per_lane_slices_come_largest_class_first_and_each_exactly_once() {
    let ctx = common::gpu_context();
    if !takes_the_per_lane_transport(&ctx) {
        return;
    }
    let tile = Tile::new(16, 16, 8, 1, 2).unwrap();
    let (gpu, sampler, taps) = per_lane_run_and_its_slices(&ctx, tile);
    // Classes whose sizes fall in one of the order's 256 bins may come in any order.
    let bin_width = (taps + 1).div_ceil(256);
    for iteration in [0u32, 7, 31, 32, 39] {
        let order = gpu.slice_order(iteration).unwrap().expect("a per-lane run orders its slices").ranks;
        let slices = order.len() as u32;
        assert!(slices > 100, "{slices} slices");
        let mut seen = vec![false; slices as usize];
        for &slice in &order {
            assert!(slice < slices && !seen[slice as usize], "slice {slice} twice or out of range");
            seen[slice as usize] = true;
        }
        let by_index: Vec<u32> = (0..slices).map(|i| sampler.draw(iteration, i).len).collect();
        let by_rank: Vec<u32> = order.iter().map(|&i| by_index[i as usize]).collect();
        for (rank, pair) in by_rank.windows(2).enumerate() {
            assert!(
                pair[1] <= pair[0] + bin_width,
                "iteration {iteration}: rank {} has {} taps after {} (bins of {bin_width})",
                rank + 1,
                pair[1],
                pair[0]
            );
        }
        // As good as an exact sort (within what the bins' width allows), where
        // index order keeps lanes idle most of the time.
        let mut exact = by_index.clone();
        exact.sort_unstable_by(|a, b| b.cmp(a));
        let (before, after, best) =
            (lane_waste(&by_index, 8), lane_waste(&by_rank, 8), lane_waste(&exact, 8));
        eprintln!(
            "iteration {iteration}: lanes of 8 busy {before:.2}x the members in index order, {after:.3}x in \
             this order, {best:.3}x sorted exactly"
        );
        assert!(after <= best * 1.02, "iteration {iteration}: {after} against {best}");
        assert!(before > 1.5, "the index order was not wasteful to begin with: {before}");
    }
    drop(gpu);
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn the_chunk_plan_gives_every_rank_to_one_chunk_within_the_loop_budget() {
    // The ordering's second pass shares each iteration's ranks out in chunks,
    // tier by tier: every rank in exactly one chunk, every chunk's lanes within
    // the loop budget at the classes its ranks actually hold (the CPU's own
    // draws), a workgroup dispatched for every chunk, and no more chunks than
    // the rounds the share allows make. At 16x16x8 (1 and 3 spp: classes
    // past LANE_MAX in the second, and at d = 3, where the f64 targets make a
    // slice dear), and 32x32x16.
    let ctx = common::gpu_context();
    if !takes_the_per_lane_transport(&ctx) {
        return;
    }
    for tile in [
        Tile::new(16, 16, 8, 1, 2).unwrap(),
        Tile::new(16, 16, 8, 3, 2).unwrap(),
        Tile::new(16, 16, 8, 1, 3).unwrap(),
        Tile::new(32, 32, 16, 1, 2).unwrap(),
    ] {
        let s = settings(5);
        let options = VulkanOptions::default()
            .hooks(VulkanHooks { transport: Some(TransportKind::PerLane), ..VulkanHooks::default() });
        let gpu = VulkanRun::new(&ctx, tile, s, None, options).unwrap();
        let shape = *gpu.shape();
        let lanes = shape.workgroup;
        let kernel = Kernel::new(s.kernel, &tile);
        let sampler = SliceSampler::new(seed_key(s.seed), tile, &kernel, s.axis_share);
        for iteration in [0u32, 33] {
            let order = gpu.slice_order(iteration).unwrap().expect("a per-lane run orders its slices");
            let what = format!("{}, iteration {iteration}", tile.describe());
            let slices = order.ranks.len() as u32;
            let (mut rank, mut chunk) = (0u32, 0u32);
            for t in &order.tiers {
                assert_eq!(
                    (t.first_rank, t.first_chunk),
                    (rank, chunk),
                    "{what}: tiers not contiguous: {t:?}"
                );
                assert!(t.rounds >= 1, "{what}: {t:?}");
                assert!(t.rounds == 1 || t.rounds * t.cost <= LANE_BUDGET, "{what}: {t:?} past the budget");
                for r in t.first_rank..t.first_rank + t.slices {
                    let class = sampler.draw(iteration, order.ranks[r as usize]).len * tile.spp as u32;
                    let cost = shape.lane_cost(class, tile.dims);
                    assert!(cost <= t.cost, "{what}: rank {r}, a class of {class} costs {cost} in {t:?}");
                }
                rank += t.slices;
                chunk += t.slices.div_ceil(lanes * t.rounds);
            }
            assert_eq!(rank, slices, "{what}: the tiers miss ranks");
            assert_eq!(order.chunks, chunk, "{what}");
            let [x, y, z] = order.dispatch;
            assert!(x * y * z >= chunk && x <= 65535 && z == 1, "{what}: {:?} for {chunk}", order.dispatch);
            eprintln!("{what}: {slices} slices in {chunk} chunks, {} tiers", order.tiers.len());
            // Chunks hold as many rounds as the iteration's share allows: each
            // full chunk of a tier the budget or the cap does not hold back
            // carries more than half the share (total cost / chunks aimed at),
            // so at most twice the chunks aimed at are full ones, whatever
            // the lanes (8 on x86 lavapipe, 4 where its vectors are 128 bits).
            let held = |t: &LaneTier| (t.rounds + 1) * t.cost > LANE_BUDGET;
            let full: u32 =
                order.tiers.iter().filter(|t| !held(t)).map(|t| t.slices / (lanes * t.rounds)).sum();
            assert!(
                full <= 2 * shape.lane_chunks,
                "{what}: {full} full chunks, {} aimed at",
                shape.lane_chunks
            );
            assert!(chunk < slices.div_ceil(lanes), "{what}: {chunk} chunks for {slices} slices");
        }
        drop(gpu);
    }
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn ordering_fewer_iterations_at_a_time_gives_the_same_run() {
    // Where one binding cannot hold a batch's orders (large tiles), the slices
    // are ordered a few iterations at a time within the batch; the run is the
    // same bit for bit (deterministic mode), whatever the slots.
    let ctx = common::gpu_context();
    if !takes_the_per_lane_transport(&ctx) {
        return;
    }
    let samples = |slots| {
        whole_per_lane_run(
            &ctx,
            VulkanOptions::default()
                .hooks(VulkanHooks { slice_order_slots: slots, ..VulkanHooks::default() }),
        )
    };
    let whole = samples(None);
    for slots in [1, 3] {
        assert!(whole == samples(Some(slots)), "{slots} slots at a time changed the run");
    }
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn the_workgroup_transport_takes_slices_in_index_order() {
    let ctx = common::gpu_context();
    let tile = Tile::new(8, 8, 4, 1, 2).unwrap();
    let options = VulkanOptions::default()
        .hooks(VulkanHooks { transport: Some(TransportKind::Workgroup), ..VulkanHooks::default() });
    let gpu = VulkanRun::new(&ctx, tile, settings(5), None, options).unwrap();
    assert_eq!(gpu.slice_order(0).unwrap(), None);
    drop(gpu);
    common::assert_no_validation_messages(&ctx);
}
