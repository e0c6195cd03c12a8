//! The Vulkan optimizer against the CPU path (lavapipe in CI, validation on).
#![cfg(feature = "vulkan")]

mod common;

use fsot::core::kernel::{Kernel, KernelSpec};
use fsot::core::mask::Mask;
use fsot::core::objective::score;
use fsot::core::rng::seed_key;
use fsot::core::slice::{SliceSampler, DEFAULT_AXIS_SHARE};
use fsot::core::step_rule::StepRule;
use fsot::core::tile::Tile;
use fsot::core::transport::{transport_slice, Scratch};
use fsot::optimize::backend::Backend;
use fsot::optimize::run::optimize;
use fsot::optimize::settings::Settings;
use fsot::optimize::vulkan::shape::{TransportShape, LANE_BUDGET, LANE_MAX};
use fsot::optimize::vulkan::{TransportKind, VulkanHooks, VulkanOptions, VulkanRun};

/// The per-lane transport is for CPU implementations (lavapipe); a GPU must refuse
/// it with a clear error. True when `transport` is refused here (checked; the
/// rest of the check is then a skip, `common::skip`).
fn refused_here(ctx: &fsot::vk::Context, transport: TransportKind) -> bool {
    if transport != TransportKind::PerLane || ctx.info().device_type == ash::vk::PhysicalDeviceType::CPU {
        return false;
    }
    let tile = Tile::new(8, 8, 4, 1, 2).unwrap();
    let options = VulkanOptions::default()
        .deterministic(true)
        .hooks(VulkanHooks { transport: Some(transport), ..VulkanHooks::default() });
    let err =
        VulkanRun::new(ctx, tile, settings("taa", 5, 1), None, options).err().expect("per-lane on a GPU");
    assert!(err.to_string().contains("CPU implementations"), "{err}");
    common::skip(
        "the per-lane transport is for CPU implementations: on this GPU only its refusal was checked",
    )
}

/// The largest difference between two vectors of one length (checked).
fn largest_difference(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len(), "vectors of different lengths");
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

/// The bits of each value, to compare runs bit for bit.
fn bits(v: &[f32]) -> Vec<u32> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// Settings that start from white noise: these tests give both backends the
/// same start (`VulkanRun` and `CpuRun` themselves start from it).
fn settings(kernel: &str, iterations: u32, seed: u64) -> Settings {
    let mut s = Settings::new(KernelSpec::from_name(kernel, 2.1, None, 0.1, 60.0).unwrap(), seed);
    s.iterations = iterations;
    s.start = fsot::Start::White;
    s
}

/// The CPU path's summed displacement per coordinate for one iteration's slices
/// (f64).
fn cpu_displacements(mask: &Mask, s: &Settings, slices: u32, iteration: u32) -> Vec<f64> {
    fsot::optimize::cpu::reference_displacements(mask, s, slices, iteration)
}

fn compare_one_iteration(tile: Tile, kernel: &str, deterministic: bool) {
    for transport in [TransportKind::Workgroup, TransportKind::PerLane] {
        compare_one_iteration_with(tile, kernel, deterministic, transport);
    }
}

fn compare_one_iteration_with(tile: Tile, kernel: &str, deterministic: bool, transport: TransportKind) {
    compare_on_mask(&Mask::white(tile, 21), kernel, deterministic, transport);
}

fn compare_on_mask(mask: &Mask, kernel: &str, deterministic: bool, transport: TransportKind) {
    let options = VulkanOptions::default()
        .deterministic(deterministic)
        .hooks(VulkanHooks { transport: Some(transport), ..VulkanHooks::default() });
    compare_with_options(mask, kernel, options);
}

fn compare_with_options(mask: &Mask, kernel: &str, options: VulkanOptions) {
    compare_with_share(mask, kernel, options, DEFAULT_AXIS_SHARE);
}

fn compare_with_share(mask: &Mask, kernel: &str, options: VulkanOptions, axis_share: f64) {
    let ctx = common::gpu_context();
    let transport = options.hooks.transport.unwrap_or(TransportKind::Workgroup);
    if refused_here(&ctx, transport) {
        return;
    }
    let tile = mask.tile;
    let mut s = settings(kernel, 10, 21).axis_share(axis_share);
    s.slices = Some(300);
    let mut gpu = VulkanRun::new(&ctx, tile, s, Some(mask), options).unwrap();
    for iteration in [0u32, 5] {
        let g = gpu.displacements(iteration).unwrap();
        let c = cpu_displacements(mask, &s, 300, iteration);
        let worst = largest_difference(&g, &c);
        assert_eq!(c.len(), tile.values(), "a displacement per coordinate");
        let moved = c.iter().filter(|v| **v != 0.0).count();
        assert!(moved > tile.values() / 4, "too few coordinates moved: {moved}");
        eprintln!(
            "{kernel} d = {} {:?} float pairs {}: largest difference {worst:.2e}",
            tile.dims, options.hooks.transport, options.hooks.float_pair_targets
        );
        assert!(worst < 1e-5, "{kernel} {tile:?} {options:?}: largest difference {worst}");
    }
    assert_eq!(gpu.overflowed(), 0);
    drop(gpu);
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn one_iteration_gives_the_cpu_displacements_small_classes() {
    compare_one_iteration(Tile::new(16, 16, 8, 1, 2).unwrap(), "taa", true);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn one_iteration_gives_the_cpu_displacements_in_one_dimension() {
    compare_one_iteration(Tile::new(16, 16, 8, 1, 1).unwrap(), "perceptual-taa", true);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn an_axis_share_other_than_the_default_gives_the_cpu_displacements() {
    for transport in [TransportKind::Workgroup, TransportKind::PerLane] {
        let options = VulkanOptions::default()
            .deterministic(true)
            .hooks(VulkanHooks { transport: Some(transport), ..VulkanHooks::default() });
        for (dims, share) in [(2, 0.85), (3, 0.9), (2, 0.0)] {
            let tile = Tile::new(16, 16, 8, 1, dims).unwrap();
            compare_with_share(&Mask::white(tile, 21), "taa", options, share);
        }
    }
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn per_lane_classes_up_to_its_limit_give_the_cpu_displacements() {
    // 3 spp: classes of several hundred to about two thousand points, all
    // sorted by one invocation each (bucket sort, insertion within buckets).
    let tile = Tile::new(16, 16, 8, 3, 2).unwrap();
    let kernel = Kernel::new(KernelSpec::from_name("gaussian", 2.1, None, 0.1, 60.0).unwrap(), &tile);
    let largest = kernel.taps.len() * 3;
    assert!(largest > 1024 && largest <= LANE_MAX as usize, "{largest}");
    compare_on_mask(&Mask::white(tile, 8), "gaussian", true, TransportKind::PerLane);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn per_lane_classes_past_2048_that_fit_the_loop_budget_need_no_large_class_stage() {
    // 3 spp of taa at 16x16x8: classes up to 2232 samples, all within one
    // invocation's loop budget, so the per-lane transport sorts them all (limit
    // 2304) and no large-class stage is built. The CPU's displacements: classes
    // past 2048 of spread keys (float32 may rank two nearly tied projections
    // the other way), and one iteration where all keys tie (the heap sort at
    // its worst).
    let ctx = common::gpu_context();
    if refused_here(&ctx, TransportKind::PerLane) {
        return;
    }
    let tile = Tile::new(16, 16, 8, 3, 2).unwrap();
    let kernel = Kernel::new(KernelSpec::from_name("taa", 2.1, None, 0.1, 60.0).unwrap(), &tile);
    assert_eq!(kernel.taps.len() * 3, 2232);
    let options = VulkanOptions::default().deterministic(true);
    let run = VulkanRun::new(&ctx, tile, settings("taa", 10, 21), None, options).unwrap();
    let launch = run.report().transport.unwrap_or_default();
    assert!(launch.contains("per lane") && launch.contains("classes up to 2304"), "{launch}");
    assert_eq!(run.large_capacity(), 0, "a large-class stage was built");
    drop(run);
    classes_past(options, 2048, 2, 3, false, DEFAULT_AXIS_SHARE);
    let mut tied = Mask::white(tile, 3);
    tied.samples.iter_mut().for_each(|v| *v = 0.375);
    compare_with_options(
        &tied,
        "taa",
        options.hooks(VulkanHooks { transport: Some(TransportKind::PerLane), ..options.hooks }),
    );
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn per_lane_sort_stays_exact_when_every_key_ties() {
    // Every sample at the same place: every projection of a class is equal, so
    // all keys pile into one bucket and the per-lane pass takes its heap-sort
    // fallback; ties go by point index on both paths, so the displacements
    // agree exactly as for distinct keys.
    let tile = Tile::new(16, 16, 8, 1, 2).unwrap();
    let mut mask = Mask::white(tile, 3);
    mask.samples.iter_mut().for_each(|v| *v = 0.375);
    for transport in [TransportKind::PerLane, TransportKind::Workgroup] {
        compare_on_mask(&mask, "taa", true, transport);
    }
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn per_lane_invocations_that_take_many_slices_give_the_cpu_displacements() {
    // Each workgroup takes a chunk of slices, as many a lane as its loop
    // budget allows at the chunk's classes and the iteration's share (four
    // chunks for each of the driver's threads): every
    // slice is still transported once, for spread keys, and for keys that all
    // tie in classes of several hundred to about two thousand samples, whose
    // heap sorts take each slice near its worst case. (That a chunk's rounds
    // fit the loop budget at its classes is tests/gpu_slice_order.rs's.)
    let options = VulkanOptions::default()
        .deterministic(true)
        .hooks(VulkanHooks { transport: Some(TransportKind::PerLane), ..VulkanHooks::default() });
    compare_with_options(&Mask::white(Tile::new(16, 16, 8, 1, 2).unwrap(), 21), "taa", options);
    let mut tied = Mask::white(Tile::new(16, 16, 8, 3, 2).unwrap(), 3);
    tied.samples.iter_mut().for_each(|v| *v = 0.375);
    compare_with_options(&tied, "gaussian", options);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn the_workgroup_transport_sorts_exactly_in_a_gpus_shape() {
    // The workgroup transport as a GPU runs it (128 invocations: on lavapipe 16
    // subgroups, so the bucket sort's scan crosses subgroups), and in a shape
    // whose last subgroup is partial (100 invocations), two slices a workgroup;
    // on distinct keys (the bucket sort, insertion within buckets), on keys that
    // all tie (every member in one bucket: the bitonic fallback), and in three
    // dimensions (the walk's targets over the sorted class).
    let ctx = common::gpu_context();
    let tile = Tile::new(16, 16, 8, 1, 2).unwrap();
    let mut tied = Mask::white(tile, 3);
    tied.samples.iter_mut().for_each(|v| *v = 0.375);
    let masks = [Mask::white(tile, 21), tied, Mask::white(Tile::new(16, 16, 8, 1, 3).unwrap(), 21)];
    for shape in [(128, 1), (100, 2)] {
        for mask in &masks {
            let options = VulkanOptions::default().deterministic(true).hooks(VulkanHooks {
                transport: Some(TransportKind::Workgroup),
                workgroup_shape: Some(shape),
                ..VulkanHooks::default()
            });
            compare_with_options(mask, "taa", options);
        }
    }
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn each_iterations_objective_estimate_is_the_cpu_paths() {
    // The estimate the stopping rule reads (the classes' squared distances to
    // their targets over their members, summed on the device) against the CPU
    // path's, iteration by iteration from the same samples: in each transport,
    // in a GPU's shape (the cost summed over 16 subgroups on lavapipe) and in
    // one whose last subgroup is partial, in two and three dimensions.
    let ctx = common::gpu_context();
    let shapes = [
        (TransportKind::Workgroup, Some((128, 1))),
        (TransportKind::Workgroup, Some((100, 2))),
        (TransportKind::PerLane, None),
    ];
    for dims in [2, 3] {
        let mask = Mask::white(Tile::new(16, 16, 8, 1, dims).unwrap(), 21);
        let s = settings("taa", 4, 21);
        let mut cpu = fsot::optimize::cpu::CpuRun::new(mask.tile, s, Some(&mask)).unwrap();
        let expected: Vec<f64> = (0..3).map(|_| cpu.step()).collect();
        for (transport, shape) in shapes {
            if refused_here(&ctx, transport) {
                continue;
            }
            let options = VulkanOptions::default().deterministic(true).hooks(VulkanHooks {
                transport: Some(transport),
                workgroup_shape: shape,
                ..VulkanHooks::default()
            });
            let mut gpu = VulkanRun::new(&ctx, mask.tile, s, Some(&mask), options).unwrap();
            let mut got = Vec::new();
            while got.len() < expected.len() {
                got.extend(gpu.step_up_to((expected.len() - got.len()) as u32).unwrap());
            }
            for (i, (g, c)) in got.iter().zip(&expected).enumerate() {
                let relative = (g - c).abs() / c;
                eprintln!("d = {dims} {transport:?} {shape:?} iteration {i}: {g:.6e} against {c:.6e}");
                assert!(
                    relative < 1e-4,
                    "d = {dims} {transport:?} {shape:?} iteration {i}: {g} against the CPU path's {c}"
                );
            }
        }
    }
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn the_workgroup_transports_second_pass_sorts_the_classes_past_its_limit() {
    // GPUs take a second pass of the workgroup transport for the classes past
    // its limit that shared memory still holds (the paper's tile: 2049 to
    // 2326), a workgroup per listed slice. Lavapipe's 32 KiB holds it with a
    // first pass limited to 1024 and a second up to 2048: classes of 1025 to
    // 2048 then take the second pass; at 4 spp the larger ones still take the
    // large-class stage, beside it.
    let ctx = common::gpu_context();
    let cases =
        [(Tile::new(16, 16, 8, 3, 2).unwrap(), "gaussian"), (Tile::new(16, 16, 8, 4, 2).unwrap(), "taa")];
    for (tile, kernel) in cases {
        let spec = KernelSpec::from_name(kernel, 2.1, None, 0.1, 60.0).unwrap();
        let largest = Kernel::new(spec, &tile).taps.len() * tile.spp;
        assert!(largest > 1024, "{kernel} {tile:?}: no class for the second pass ({largest})");
        let options = VulkanOptions::default().deterministic(true).hooks(VulkanHooks {
            transport: Some(TransportKind::Workgroup),
            local_max: Some(1024),
            defer: Some(2048),
            ..VulkanHooks::default()
        });
        let run = VulkanRun::new(&ctx, tile, settings(kernel, 5, 1), None, options).unwrap();
        let said = run.report().transport.unwrap_or_default();
        assert!(said.contains("up to 1024") && said.contains("up to 2048 in a second pass"), "{said}");
        assert_eq!(run.large_capacity() > 0, largest > 2048, "{kernel} {tile:?}: {largest}");
        drop(run);
        compare_with_options(&Mask::white(tile, 21), kernel, options);
        // Past its workgroup limit (65535 on a device; 2 here) each workgroup of
        // the second pass takes several listed slices.
        compare_with_options(
            &Mask::white(tile, 21),
            kernel,
            options.hooks(VulkanHooks { defer_groups: Some(2), ..options.hooks }),
        );
    }
    // A first pass of one small subgroup with a small limit: most classes then
    // take the second pass.
    for dims in [2, 3] {
        let options = VulkanOptions::default().deterministic(true).hooks(VulkanHooks {
            transport: Some(TransportKind::Workgroup),
            workgroup_shape: Some((8, 1)),
            local_max: Some(64),
            defer: Some(1024),
            ..VulkanHooks::default()
        });
        compare_with_options(&Mask::white(Tile::new(16, 16, 8, 1, dims).unwrap(), 21), "taa", options);
    }
    // Class by class, near-ties allowed their neighbour's target, in two and
    // three dimensions.
    let options = VulkanOptions::default().deterministic(true).hooks(VulkanHooks {
        transport: Some(TransportKind::Workgroup),
        local_max: Some(1024),
        defer: Some(2048),
        ..VulkanHooks::default()
    });
    for dims in [2, 3] {
        classes_past(options, 1024, dims, 4, true, DEFAULT_AXIS_SHARE);
    }
    // Asked for what the device or the shape cannot give: a clear error.
    let tile = Tile::new(16, 16, 8, 3, 2).unwrap();
    for (local_max, defer) in [(Some(1000), Some(2048)), (Some(1024), Some(1024)), (None, Some(3000))] {
        let options = VulkanOptions::default().hooks(VulkanHooks {
            transport: Some(TransportKind::Workgroup),
            local_max,
            defer,
            ..VulkanHooks::default()
        });
        let err =
            VulkanRun::new(&ctx, tile, settings("gaussian", 5, 1), None, options).err().expect("refused");
        assert!(err.to_string().contains("power of two"), "{err}");
    }
    let too_large = VulkanOptions::default().hooks(VulkanHooks {
        transport: Some(TransportKind::Workgroup),
        defer: Some(4096),
        ..VulkanHooks::default()
    });
    if ctx.info().max_shared_memory < TransportShape::shared_bytes(256, 4096) {
        let err =
            VulkanRun::new(&ctx, tile, settings("gaussian", 5, 1), None, too_large).err().expect("refused");
        assert!(err.to_string().contains("maxComputeSharedMemorySize"), "{err}");
    } else {
        // A device with that much shared memory takes the shape.
        VulkanRun::new(&ctx, tile, settings("gaussian", 5, 1), None, too_large).expect("within the limit");
    }
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn large_classes_sorted_globally_give_the_cpu_displacements() {
    for transport in [TransportKind::Workgroup, TransportKind::PerLane] {
        large_classes_with(transport, 2, DEFAULT_AXIS_SHARE);
    }
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn large_classes_in_three_dimensions_give_the_cpu_displacements() {
    // Per lane, d = 3 leaves classes past its limit (207) to this stage; and at
    // an axis share other than the default, which this stage draws by too.
    for transport in [TransportKind::Workgroup, TransportKind::PerLane] {
        large_classes_with(transport, 3, DEFAULT_AXIS_SHARE);
        large_classes_with(transport, 3, 0.9);
    }
}

fn large_classes_with(transport: TransportKind, dims: usize, axis_share: f64) {
    // On a GPU the workgroup transport's second pass would take these classes:
    // off, so that they reach the large-class stage everywhere.
    let options = VulkanOptions::default().deterministic(true).hooks(VulkanHooks {
        transport: Some(transport),
        defer: Some(0),
        ..VulkanHooks::default()
    });
    let limit = if transport == TransportKind::PerLane { TransportShape::lane_limit(dims) } else { 2048 };
    classes_past(options, limit, dims, 4, true, axis_share);
}

/// The classes past `limit` of 16x16x8 `taa` at `spp` (which the transport with
/// `options` leaves to the large-class stage, or to its second pass, or sorts
/// itself) against the CPU's, one slice per iteration, so each read-back is one
/// class; whether the run has a large-class stage (`large_stage`). In classes
/// of thousands of points some projections lie within float32 rounding of each
/// other and may rank the other way round on the GPU; such a point must then
/// get exactly its neighbour's target. The run draws its slices at `axis_share`.
fn classes_past(
    options: VulkanOptions,
    limit: u32,
    dims: usize,
    spp: usize,
    large_stage: bool,
    axis_share: f64,
) {
    let ctx = common::gpu_context();
    let transport = options.hooks.transport.unwrap_or(TransportKind::Workgroup);
    if refused_here(&ctx, transport) {
        return;
    }
    let tile = Tile::new(16, 16, 8, spp, dims).unwrap();
    let mut s = settings("taa", 5000, 5).axis_share(axis_share);
    s.slices = Some(1);
    let kernel = Kernel::new(s.kernel, &tile);
    assert!(kernel.taps.len() * spp > 2048, "the test must reach classes past 2048");
    let mask = Mask::white(tile, 5);
    let sampler = SliceSampler::new(seed_key(s.seed), tile, &kernel, s.axis_share);
    let mut gpu = VulkanRun::new(&ctx, tile, s, Some(&mask), options).unwrap();
    assert_eq!(gpu.large_capacity() > 1024, large_stage, "large-class capacity {}", gpu.large_capacity());
    let (mut checked, mut ties) = (0, 0);
    for iteration in 0..5000 {
        let slice = sampler.draw(iteration, 0);
        if slice.len * spp as u32 <= limit {
            continue;
        }
        let g = gpu.displacements(iteration).unwrap();
        // CPU: projection, rank target and displacement of each class member.
        let mut members = Vec::new();
        transport_slice(&mask.samples, &tile, &kernel, &slice, &mut Scratch::default(), |p, delta| {
            members.push((p, delta))
        });
        let mut order: Vec<(f64, u32, f64)> = members
            .iter()
            .map(|&(p, delta)| {
                let i = p as usize * dims;
                (fsot::core::transport::project(&mask.samples[i..i + dims], &slice), p, delta)
            })
            .collect();
        order.sort_by(|a, b| a.0.total_cmp(&b.0));
        for (r, &(proj, p, delta)) in order.iter().enumerate() {
            let i = p as usize * dims;
            let along: f64 = (0..dims).map(|k| g[i + k] * slice.theta[k]).sum();
            if (along - delta).abs() < 1e-5 {
                continue;
            }
            // Must be a near-tie (within float32 rounding of the projections,
            // 2e-6) that took a neighbour's rank.
            let neighbour = [r.wrapping_sub(1), r + 1].into_iter().filter(|&q| q < order.len()).find(|&q| {
                let (pq, _, dq) = order[q];
                (pq - proj).abs() < 2e-6 && (along - (dq + pq - proj)).abs() < 1e-5
            });
            assert!(neighbour.is_some(), "iteration {iteration}, rank {r}: gpu {along}, cpu {delta}");
            ties += 1;
        }
        checked += 1;
        if checked == 6 {
            break;
        }
    }
    eprintln!("{options:?}, d = {dims}: checked {checked} classes past {limit}, {ties} near-tie rank swaps");
    assert!(checked >= 3, "too few large classes drawn");
    assert_eq!(gpu.overflowed(), 0);
    drop(gpu);
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn large_classes_past_the_buffers_room_are_skipped_and_counted_and_the_sort_stays_within_the_buffers() {
    let ctx = common::gpu_context();
    let tile = Tile::new(16, 16, 8, 4, 2).unwrap();
    let s = settings("taa", 8, 3);
    let largest = Kernel::new(s.kernel, &tile).taps.len() as u32 * 4;
    // Room for one largest class and a little: most iterations draw several.
    let options = VulkanOptions::default().deterministic(true).hooks(VulkanHooks {
        transport: Some(TransportKind::Workgroup),
        defer: Some(0),
        large_capacity: Some(largest + 64),
        ..VulkanHooks::default()
    });
    let mut gpu = VulkanRun::new(&ctx, tile, s, None, options).unwrap();
    assert_eq!(gpu.large_capacity(), largest + 64);
    let mut costs = Vec::new();
    while costs.len() < 8 {
        // A count past the buffers (the sort and the gather then run past them)
        // fails the batch.
        costs.extend(gpu.step_up_to(8 - costs.len() as u32).unwrap());
    }
    assert!(gpu.overflowed() > 0, "no class overflowed: the test must reach a full buffer");
    assert!(costs.iter().all(|c| c.is_finite() && *c > 0.0), "{costs:?}");
    eprintln!("{} large classes skipped in 8 iterations, costs {costs:?}", gpu.overflowed());
    drop(gpu);
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn float_atomics_agree_with_the_cpu_too() {
    let ctx = common::gpu_context();
    if !ctx.info().float_atomic_add && common::skip(&format!("no float atomics on {}", ctx.info().name)) {
        return;
    }
    let tile = Tile::new(16, 16, 8, 1, 2).unwrap();
    let mask = Mask::white(tile, 21);
    for transport in [TransportKind::Workgroup, TransportKind::PerLane] {
        // Not deterministic: float atomics wherever the device has them, a CPU
        // implementation included.
        let options = VulkanOptions::default()
            .hooks(VulkanHooks { transport: Some(transport), ..VulkanHooks::default() });
        if refused_here(&ctx, transport) {
            continue;
        }
        let run = VulkanRun::new(&ctx, tile, settings("taa", 1, 21), Some(&mask), options).unwrap();
        assert!(run.uses_float_atomics(), "{transport:?}: the default took fixed point");
        drop(run);
        compare_with_options(&mask, "perceptual-taa", options);
    }
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn deterministic_mode_is_bit_identical_run_to_run() {
    let ctx = common::gpu_context();
    let tile = Tile::new(16, 16, 8, 4, 2).unwrap();
    let run = |transport| {
        let options = VulkanOptions::default()
            .deterministic(true)
            .hooks(VulkanHooks { transport: Some(transport), ..VulkanHooks::default() });
        let mut g = VulkanRun::new(&ctx, tile, settings("taa", 40, 3), None, options).unwrap();
        while !g.finished() {
            g.step_batch(u32::MAX).unwrap();
        }
        g.samples().unwrap()
    };
    for transport in [TransportKind::Workgroup, TransportKind::PerLane] {
        if refused_here(&ctx, transport) {
            continue;
        }
        let a = run(transport);
        let b = run(transport);
        assert_eq!(bits(&a), bits(&b), "{transport:?}");
        assert!(a.iter().all(|v| (0.0..1.0).contains(v)));
    }
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn a_resumed_deterministic_run_equals_an_uninterrupted_one_bit_for_bit() {
    let ctx = common::gpu_context();
    let tile = Tile::new(16, 16, 8, 1, 2).unwrap();
    let s = settings("taa", 70, 4);
    let options = VulkanOptions::default()
        .deterministic(true)
        .hooks(VulkanHooks { transport: None, ..VulkanHooks::default() });
    let mut straight = VulkanRun::new(&ctx, tile, s, None, options).unwrap();
    while !straight.finished() {
        straight.step_batch(u32::MAX).unwrap();
    }
    // Stopped at 45 (not a multiple of the 32-iteration batch), saved, restored
    // into a fresh run through the checkpoint file format.
    let mut first = VulkanRun::new(&ctx, tile, s, None, options).unwrap();
    while first.iteration() < 45 {
        first.step_batch(45 - first.iteration()).unwrap();
    }
    let fp = fsot::optimize::checkpoint::fingerprint(&tile, &s);
    let bytes = fsot::optimize::checkpoint::encode(&fp, &first.state().unwrap());
    drop(first);
    let saved = fsot::optimize::checkpoint::decode(&bytes, &fp, &tile).unwrap();
    assert_eq!(saved.iteration, 45);
    let mut resumed = VulkanRun::new(&ctx, tile, s, None, options).unwrap();
    resumed.restore(&saved).unwrap();
    while !resumed.finished() {
        resumed.step_batch(u32::MAX).unwrap();
    }
    let a = straight.samples().unwrap();
    let b = resumed.samples().unwrap();
    assert_eq!(bits(&a), bits(&b), "resumed run differs");
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn a_full_run_reaches_the_cpu_objective_within_five_percent() {
    let ctx = common::gpu_context();
    let tile = Tile::new(32, 32, 16, 1, 2).unwrap();
    let s = settings("taa", 150, 7);
    let cpu = optimize(tile, s, None).unwrap();
    let mut gpu = VulkanRun::new(&ctx, tile, s, None, VulkanOptions::default()).unwrap();
    let mut last = Vec::new();
    while !gpu.finished() {
        last = gpu.step_batch(u32::MAX).unwrap();
    }
    assert!(last.iter().all(|c| c.is_finite() && *c > 0.0));
    let g = gpu.mask().unwrap();
    let (sc, sg) = (score(&cpu, s.kernel, 8192).objective, score(&g, s.kernel, 8192).objective);
    eprintln!("objective: cpu {sc:.4e}, vulkan {sg:.4e}");
    assert!((sg - sc).abs() / sc < 0.05, "cpu {sc} vulkan {sg}");
    drop(gpu);
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn a_few_steps_of_momentum_and_of_adam_move_the_samples_as_the_cpu_path_does() {
    // The update pass in both variants (storage reads with the workgroup
    // transport; texel reads and the host's reset on CPU implementations with
    // the per-lane one) against the CPU path's f64 steps from the same start.
    let ctx = common::gpu_context();
    let tile = Tile::new(16, 16, 8, 1, 2).unwrap();
    let torus = |a: f32, b: f32| {
        let d = (a - b).abs();
        d.min(1.0 - d)
    };
    for rule in [StepRule::DEFAULT, StepRule::DEFAULT_ADAM] {
        let mut s = settings("taa", 4, 5);
        s.rule = rule;
        let white = Mask::white(tile, 5);
        let cpu = optimize(tile, s, Some(&white)).unwrap();
        let moved = cpu.samples.iter().zip(&white.samples).map(|(a, b)| torus(*a, *b)).fold(0.0, f32::max);
        assert!(moved > 1e-3, "{rule:?}: the CPU run moved the samples by at most {moved}");
        for transport in [TransportKind::Workgroup, TransportKind::PerLane] {
            if refused_here(&ctx, transport) {
                continue;
            }
            let options = VulkanOptions::default()
                .deterministic(true)
                .hooks(VulkanHooks { transport: Some(transport), ..VulkanHooks::default() });
            let mut gpu = VulkanRun::new(&ctx, tile, s, Some(&white), options).unwrap();
            while !gpu.finished() {
                gpu.step_batch(u32::MAX).unwrap();
            }
            let g = gpu.samples().unwrap();
            assert_eq!(g.len(), cpu.samples.len());
            let worst = g.iter().zip(&cpu.samples).map(|(a, b)| torus(*a, *b)).fold(0.0, f32::max);
            eprintln!("{rule:?} {transport:?}: moved up to {moved:.2e}, largest difference {worst:.2e}");
            assert!(worst < 1e-5, "{rule:?} {transport:?}: largest difference {worst}");
        }
    }
    common::assert_no_validation_messages(&ctx);
}

/// A run of `kernel` on `tile` with the transport forced, or why it is refused.
fn forced(
    ctx: &fsot::vk::Context,
    tile: Tile,
    kernel: &str,
    transport: TransportKind,
) -> Result<VulkanRun, String> {
    let options = VulkanOptions::default()
        .deterministic(true)
        .hooks(VulkanHooks { transport: Some(transport), ..VulkanHooks::default() });
    VulkanRun::new(ctx, tile, settings(kernel, 5, 1), None, options).map_err(|e| e.to_string())
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn one_iteration_gives_the_cpu_displacements_in_three_four_and_eight_dimensions() {
    // The box-spline targets, in f64 and in float32 pairs, against the CPU
    // path's f64 reference, on both transports. Per lane, a CPU implementation's
    // loop budget takes the f64 targets of classes up to the lane's limit only:
    // the larger classes of this kernel go to the large-class stage. The workgroups are sized so each invocation's share fits.
    let ctx = common::gpu_context();
    for dims in [3, 4, 8] {
        let tile = Tile::new(16, 16, 8, 1, dims).unwrap();
        for transport in [TransportKind::Workgroup, TransportKind::PerLane] {
            if refused_here(&ctx, transport) {
                continue;
            }
            let kernel = Kernel::new(KernelSpec::from_name("taa", 2.1, None, 0.1, 60.0).unwrap(), &tile);
            let taps = kernel.taps.len() as u32;
            let limit = TransportShape::lane_limit(dims);
            assert!(TransportShape::lane_iterations(taps.min(limit), dims) <= LANE_BUDGET);
            if transport == TransportKind::PerLane {
                assert!(taps > limit, "d = {dims}: {taps} taps, lane limit {limit}: no split to test");
                let run =
                    forced(&ctx, tile, "taa", transport).expect("per lane, the large classes split off");
                assert!(run.large_capacity() > 0 || taps <= limit, "d = {dims}: no large-class stage");
            }
            for float_pair_targets in [false, true] {
                let options = VulkanOptions::default().deterministic(true).hooks(VulkanHooks {
                    transport: Some(transport),
                    float_pair_targets,
                    ..VulkanHooks::default()
                });
                compare_with_options(&Mask::white(tile, 21), "taa", options);
            }
        }
    }
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn full_runs_in_three_four_and_eight_dimensions_reach_the_cpu_objective_within_five_percent() {
    let ctx = common::gpu_context();
    // d = 8 on a smaller tile: lavapipe's cost per iteration grows with d.
    for (dims, side) in [(3, 16), (4, 16), (8, 8)] {
        let tile = Tile::new(side, side, 8, 1, dims).unwrap();
        let s = settings("perceptual-taa", 100, 7);
        let cpu = optimize(tile, s, None).unwrap();
        let mut gpu = VulkanRun::new(&ctx, tile, s, None, VulkanOptions::default()).unwrap();
        while !gpu.finished() {
            gpu.step_batch(u32::MAX).unwrap();
        }
        let g = gpu.mask().unwrap();
        let (sc, sg) = (score(&cpu, s.kernel, 2048).objective, score(&g, s.kernel, 2048).objective);
        let white = score(&Mask::white(tile, 7), s.kernel, 2048).objective;
        eprintln!("d = {dims}: objective cpu {sc:.4e}, vulkan {sg:.4e}, white {white:.4e}");
        assert!(sg < 0.8 * white, "d = {dims}: the run did not optimise ({sg} against white {white})");
        assert!((sg - sc).abs() / sc < 0.05, "d = {dims}: cpu {sc} vulkan {sg}");
    }
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn a_device_without_f64_takes_float_pairs_and_classes_past_the_loop_budget_get_a_clear_error() {
    let ctx = common::gpu_context();
    // A device without shaderFloat64 (here: the same device, wrapped as a host
    // that did not enable it) takes d >= 3 with the float32-pair targets, whose
    // one iteration agrees with the CPU path's f64 within 1e-5.
    // SAFETY: ctx's live device, with fewer features claimed than it has; guest is dropped first.
    let guest =
        unsafe { fsot::vk::Context::wrap(fsot::vk::ExternalDevice { float64: false, ..ctx.external() }) }
            .unwrap();
    let mask = Mask::white(Tile::new(8, 8, 4, 1, 3).unwrap(), 4);
    let s = settings("taa", 5, 1);
    let mut run = VulkanRun::new(&guest, mask.tile, s, Some(&mask), VulkanOptions::default()).unwrap();
    let g = run.displacements(0).unwrap();
    let slices = run.slices_per_iteration();
    let c = cpu_displacements(&mask, &s, slices, 0);
    let worst = largest_difference(&g, &c);
    assert!(worst < 1e-5, "float32 pairs on a device without shaderFloat64: largest difference {worst}");
    drop(run);
    drop(guest);
    // On a CPU implementation, classes whose f64 targets would pass its loop
    // budget are refused rather than silently cut short: d = 8 with classes of
    // thousands of samples (4 spp).
    if ctx.info().is_cpu() {
        let err = forced(&ctx, Tile::new(16, 16, 8, 4, 8).unwrap(), "taa", TransportKind::Workgroup).err();
        let err = err.expect("d = 8 with large classes on a CPU implementation");
        assert!(err.contains("loop budget") && err.contains("CPU backend"), "{err}");
    } else {
        // Reported as a skip of that check (a failure unless skips are allowed).
        let _skipped = common::skip("the loop budget's refusal is a CPU implementation's");
    }
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn runs_on_a_device_that_a_host_renderer_made_and_leaves_it_alive() {
    // The "host" here is an fsot context whose handles we hand over as if a
    // renderer had made them; fsot must use them and not destroy them.
    let host = common::gpu_context();
    let tile = Tile::new(16, 16, 4, 1, 2).unwrap();
    {
        // SAFETY: the host context's live device, which outlives this block.
        let guest = unsafe { fsot::vk::Context::wrap(host.external()) }.unwrap();
        let mut run =
            VulkanRun::new(&guest, tile, settings("taa", 20, 2), None, VulkanOptions::default()).unwrap();
        while !run.finished() {
            run.step_batch(u32::MAX).unwrap();
        }
        assert!(run.samples().unwrap().iter().all(|v| (0.0..1.0).contains(v)));
    } // guest dropped: the host's device must still work
    let mut again =
        VulkanRun::new(&host, tile, settings("taa", 5, 2), None, VulkanOptions::default()).unwrap();
    again.step_batch(u32::MAX).unwrap();
    drop(again);
    common::assert_no_validation_messages(&host);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn large_classes_with_tied_keys_give_the_cpu_displacements() {
    // Every sample at one place: every class of thousands of members ties on
    // every key; the global sort path must break ties by point index, as the CPU.
    let tile = Tile::new(16, 16, 8, 4, 2).unwrap();
    let kernel = Kernel::new(KernelSpec::from_name("taa", 2.1, None, 0.1, 60.0).unwrap(), &tile);
    assert!(kernel.taps.len() * 4 > 2048, "the test must reach the large-class path");
    let mut mask = Mask::white(tile, 3);
    mask.samples.iter_mut().for_each(|v| *v = 0.625);
    // The large-class stage itself, not a GPU's second pass.
    let options = VulkanOptions::default().deterministic(true).hooks(VulkanHooks {
        transport: Some(TransportKind::Workgroup),
        defer: Some(0),
        ..VulkanHooks::default()
    });
    compare_with_options(&mask, "taa", options);
}
