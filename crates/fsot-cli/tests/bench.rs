//! The benchmark suites (`fsot bench`): run time against error, CPU path against
//! Vulkan (lavapipe in CI), on the same problem and seed.

#[path = "../../../tests/common/mod.rs"]
mod common;

use fsot::core::kernel::KernelSpec;
use fsot::core::tile::Tile;
use fsot::optimize::backend::BackendChoice;
use fsot::optimize::run::RunOptions;
use fsot_cli::bench::convergence::{convergence, SceneJudge};

/// The convergence suite on each backend given; with both, they end at about
/// the same objective (same problem, same seed).
fn converge(backends: &[BackendChoice]) {
    let tile = Tile::new(16, 16, 8, 1, 2).unwrap();
    let spec = KernelSpec::from_name("taa", 2.1, None, 0.1, 60.0).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let judge = SceneJudge::new(tile, Some(dir.path())).unwrap();
    let mut last_objective = Vec::new();
    for &choice in backends {
        // With the validation layer on, any message makes `convergence` fail.
        let base = RunOptions::default().validation(true);
        let points = convergence(choice, &base, tile, spec, 3, &[5, 20, 40], &judge).unwrap();
        let iterations: Vec<u32> = points.iter().map(|p| p.iteration).collect();
        assert_eq!(iterations, vec![0, 5, 20, 40], "{choice:?}");
        assert!(points.windows(2).all(|w| w[1].seconds > w[0].seconds), "{choice:?}: time must grow");
        assert!(points.iter().all(|p| !p.machine.is_empty()));
        let (first, last) = (&points[0], &points[3]);
        // White noise at the start, far better at the end, on both measures.
        assert!((first.objective_ratio - 1.0).abs() < 0.1, "{first:?}");
        assert!(last.objective_ratio < 0.8 * first.objective_ratio, "{choice:?}: {last:?}");
        assert!(last.prelmse_ratio < first.prelmse_ratio, "{choice:?}: {last:?}");
        last_objective.push(last.objective_ratio);
    }
    if let [cpu, gpu] = last_objective[..] {
        assert!((cpu - gpu).abs() < 0.05 * cpu, "cpu {cpu} vulkan {gpu}");
    }
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn both_backends_converge_on_the_same_problem_and_their_checkpoints_are_in_order() {
    common::gpu_context();
    converge(&[BackendChoice::Cpu, BackendChoice::Vulkan]);
}

#[cfg_attr(not(fsot_skip_gpu), ignore = "run within the two-backend test above")]
#[test]
fn the_cpu_path_converges_and_its_checkpoints_are_in_order() {
    converge(&[BackendChoice::Cpu]);
}
