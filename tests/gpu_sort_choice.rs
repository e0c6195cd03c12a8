//! The radix sort's path chosen at run time (`vk::choose_sort_path`): timed on
//! the device where the look-back path may run (NVIDIA's and AMD's GPUs), never
//! elsewhere; and whichever path the optimizer's large-class stage takes,
//! the masks are the same bits (deterministic mode). The look-back path's
//! workgroups wait on blocks that started before them, which lavapipe with
//! several threads does not promise to let run (and cuts a long wait short at
//! its cap on loop iterations, misplacing a block), so this binary runs lavapipe
//! with one thread (LP_NUM_THREADS=1, set before the device is made); on a GPU
//! the variable is ignored.
#![cfg(feature = "vulkan")]

mod common;

use fsot::core::kernel::KernelSpec;
use fsot::core::mask::Mask;
use fsot::core::tile::Tile;
use fsot::optimize::backend::Backend;
use fsot::optimize::settings::Settings;
use fsot::optimize::vulkan::{VulkanHooks, VulkanOptions, VulkanRun};
use fsot::vk::{choose_sort_path, time_sort_paths, PathChoice, SortPath};

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn the_sort_path_is_timed_on_gpus_only_and_either_path_makes_the_same_mask() {
    // One test in this binary: the variable is read when llvmpipe starts.
    std::env::set_var("LP_NUM_THREADS", "1");
    let ctx = common::gpu_context();

    // Both paths timed on the same pairs: each ran, and took time.
    let times = time_sort_paths(&ctx, 70_000, 32).unwrap();
    assert_eq!((times.n, times.bits), (70_000, 32));
    assert!(times.blocks_ms > 0.0 && times.look_back_ms > 0.0, "{times:?}");

    // The choice: on a CPU implementation, or a GPU not known to keep a
    // waiting workgroup's peers running, the block passes, untimed (the
    // look-back path could wait forever there); on NVIDIA's and AMD's GPUs the
    // faster, timed.
    let choice = choose_sort_path(&ctx, 70_000, 32).unwrap();
    let info = ctx.info();
    if !info.keeps_workgroups_running() || info.timestamp_period_ns <= 0.0 {
        assert_eq!(choice, PathChoice { path: SortPath::Auto, times: None });
    } else {
        let t = choice.times.expect("such a GPU times the two paths");
        assert!(t.blocks_ms > 0.0 && t.look_back_ms > 0.0, "{t:?}");
        let look_back_faster = t.look_back_ms < t.blocks_ms;
        assert_eq!(choice.path == SortPath::LookBack, look_back_faster, "{t:?}");
    }

    // The optimizer's large-class stage (4 spp: classes past the transport's
    // limit; on a GPU the second pass would take them, so it is turned off)
    // with each path set: the same samples bit for bit, and the report says
    // which path ran.
    let tile = Tile::new(16, 16, 8, 4, 2).unwrap();
    let mut settings = Settings::new(KernelSpec::from_name("taa", 2.1, None, 0.1, 60.0).unwrap(), 3);
    settings.iterations = 24;
    let mask = Mask::white(tile, 3);
    let run = |path: SortPath| {
        let options = VulkanOptions::default().deterministic(true).hooks(VulkanHooks {
            large_sort: Some(path),
            defer: Some(0),
            ..VulkanHooks::default()
        });
        let mut run = VulkanRun::new(&ctx, tile, settings, Some(&mask), options).unwrap();
        assert!(run.large_capacity() > 0, "the tile must reach the large-class stage");
        while !run.finished() {
            run.step_up_to(8).unwrap();
        }
        assert_eq!(run.overflowed(), 0);
        assert_eq!(run.sort_choice(), Some(PathChoice::forced(path)));
        run.state().unwrap().samples
    };
    let blocks = run(SortPath::Auto);
    let look_back = run(SortPath::LookBack);
    assert!(blocks != mask.samples, "the run must move the samples");
    assert!(blocks == look_back, "the look-back path changed the mask");
    common::assert_no_validation_messages(&ctx);
}
