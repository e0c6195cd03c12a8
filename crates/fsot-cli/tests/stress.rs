//! The numerical stress suite (crates/fsot-cli/src/stress.rs): at CI size here, at full size
//! (100k-iteration runs) with `cargo test --release -- --ignored` or `fsot stress`.
//! Every check must hold, on the CPU path and on the Vulkan device (lavapipe in CI,
//! validation layer on).

#[path = "../../../tests/common/mod.rs"]
mod common;

use fsot_cli::stress::{run_stress, StressSize};

fn run(size: StressSize, ctx: Option<fsot::vk::Context>) {
    let checks =
        run_stress(size, ctx.as_ref(), &mut |c| eprintln!("{}: {}: {}", c.group, c.name, c.figure)).unwrap();
    let failed: Vec<_> = checks.iter().filter(|c| c.passed == Some(false)).collect();
    assert!(failed.is_empty(), "failed: {failed:#?}");
    // A check the device cannot take is said, not counted as held.
    for c in checks.iter().filter(|c| c.passed.is_none()) {
        eprintln!("SKIPPED (not tried on this device): {}: {}: {}", c.group, c.name, c.figure);
    }
    // Every group ran: long runs, accumulation, extremes, determinism (and the
    // GPU comparison where there is a device).
    for group in ["long run, cpu", "accumulation", "extremes", "determinism"] {
        assert!(checks.iter().any(|c| c.group == group), "no {group} check");
    }
    if let Some(ctx) = ctx {
        assert!(checks.iter().any(|c| c.group == "float32 GPU vs float64 CPU"));
        assert!(checks.iter().any(|c| c.group == "long run, vulkan"));
        // A tile past one binding is tried where a binding holds at most 512 MiB.
        let past_a_binding = checks.iter().any(|c| c.name.contains("more than one binding"));
        let range = ctx.info().max_storage_buffer_range;
        if range <= 512 << 20 {
            assert!(past_a_binding, "no check of a tile past one binding of {} MiB", range >> 20);
        } else {
            let _ = common::skip(&format!("a tile past one binding of {} MiB is not tried", range >> 20));
        }
        common::assert_no_validation_messages(&ctx);
    }
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn the_stress_suite_holds_at_ci_size() {
    run(StressSize::quick(), Some(common::gpu_context()));
}

#[cfg_attr(not(fsot_skip_gpu), ignore = "run within the test above, with the GPU checks")]
#[test]
fn the_stress_suite_holds_at_ci_size_on_the_cpu_path() {
    run(StressSize::quick(), None);
}

#[test]
#[ignore = "minutes: 100k-iteration runs"]
fn the_stress_suite_holds_at_full_size() {
    run(StressSize::full(), Some(common::gpu_context()));
}
