//! The gradient scatter benchmarked on its own (`fsot bench scatter`): the GPU's
//! sums against sums in f64, fixed point exact to its rounding, float atomics
//! within float rounding.

#[path = "../../../tests/common/mod.rs"]
mod common;

use fsot_cli::bench::scatter::{bench_scatter, contributions, reference_sums, FAN_IN};

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn the_benchmarked_scatter_sums_like_f64() {
    let ctx = common::gpu_context();
    for n in [1u32, 1000, 1 << 16] {
        let b = bench_scatter(&ctx, n, 1).unwrap();
        assert_eq!(b.targets, (n / FAN_IN).max(1));
        // Fixed point: one rounding to 2^-40 per contribution, at most a few dozen
        // per accumulator.
        assert!(b.fixed_error < 64.0 * 0.5 / (1u64 << 40) as f64, "{n}: {}", b.fixed_error);
        // Float atomics are measured exactly where the device has them.
        assert_eq!(b.float_error.is_some(), ctx.info().float_atomic_add, "{n}");
        if let Some(e) = b.float_error {
            // Float: sums of values below 2^-10 carry errors near 2^-33 each add.
            assert!(e < 1e-8, "{n}: {e}");
        }
    }
    common::assert_no_validation_messages(&ctx);
}

#[test]
fn the_reference_sums_are_each_targets_contributions_summed() {
    let n = 1 << 10;
    let (idx, val) = contributions(n);
    let targets = n / FAN_IN;
    let sums = reference_sums(&idx, &val, targets);
    assert_eq!(sums.len(), targets as usize);
    for (t, &sum) in sums.iter().enumerate() {
        // Brute force: the contributions whose index is this target, in f64.
        let mine: f64 = idx.iter().zip(&val).filter(|(&i, _)| i as usize == t).map(|(_, &v)| v as f64).sum();
        assert!((sum - mine).abs() < 1e-15, "target {t}: {sum} against {mine}");
    }
}
