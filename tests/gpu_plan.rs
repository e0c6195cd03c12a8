//! Several masks in flight on one Vulkan device (a scene plan's runs stepped
//! together, a batch of each in one submission) against each run stepped alone
//! (lavapipe in CI, validation on).
#![cfg(feature = "vulkan")]

mod common;

use fsot::core::kernel::KernelSpec;
use fsot::core::tile::Tile;
use fsot::optimize::backend::Backend;
use fsot::optimize::settings::Settings;
use fsot::optimize::vulkan::{VulkanOptions, VulkanRun};

fn run(ctx: &fsot::vk::Context, tile: Tile, kernel: &str, seed: u64) -> VulkanRun {
    let mut s = Settings::new(KernelSpec::from_name(kernel, 2.1, None, 0.1, 60.0).unwrap(), seed);
    s.iterations = 30;
    let options = VulkanOptions::default().deterministic(true);
    VulkanRun::new(ctx, tile, s, None, options).unwrap()
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn runs_stepped_together_make_bit_for_bit_the_masks_they_make_alone() {
    let ctx = common::gpu_context();
    // A 1-D and a 2-D mask, and one whose classes reach the large-class stage
    // (the global sort) at 64 spp.
    let cases = [
        (Tile::new(16, 16, 8, 1, 1).unwrap(), "perceptual-taa", 1),
        (Tile::new(8, 8, 4, 1, 2).unwrap(), "taa", 2),
        (Tile::new(8, 8, 4, 64, 2).unwrap(), "taa", 3),
    ];
    let make = || cases.map(|(tile, kernel, seed)| run(&ctx, tile, kernel, seed));
    let mut together = make();
    let mut alone = make();
    assert!(together[2].large_capacity() > 0, "the 64 spp case must reach the large-class stage");
    // Unequal steps, as a plan's stopping rules give: runs end at different times.
    let steps: [[u32; 3]; 3] = [[16, 10, 4], [14, 16, 16], [0, 4, 10]];
    for counts in steps {
        let mut members: Vec<&mut VulkanRun> = together.iter_mut().collect();
        let costs_together = VulkanRun::step_together(&mut members, &counts).unwrap();
        for ((r, &count), costs) in alone.iter_mut().zip(&counts).zip(&costs_together) {
            let costs_alone = if count > 0 { r.step_batch(count).unwrap() } else { Vec::new() };
            assert_eq!(&costs_alone, costs, "objective estimates");
        }
    }
    for (k, (a, b)) in together.iter().zip(&alone).enumerate() {
        assert_eq!(a.iteration(), b.iteration());
        assert_eq!(a.samples().unwrap(), b.samples().unwrap(), "case {k}: samples differ");
        assert_eq!(a.overflowed(), 0);
    }
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn runs_on_different_devices_are_not_stepped_together() {
    let a = common::gpu_context();
    let b = common::gpu_context();
    let tile = Tile::new(8, 8, 4, 1, 2).unwrap();
    let (mut x, mut y) = (run(&a, tile, "taa", 1), run(&b, tile, "taa", 1));
    assert!(!x.shares_device_with(&y));
    let err = VulkanRun::step_together(&mut [&mut x, &mut y], &[4, 4]).expect_err("two devices");
    assert!(err.to_string().contains("share one device"), "{err}");
    assert_eq!((x.iteration(), y.iteration()), (0, 0), "nothing ran");
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn a_plan_cancelled_while_its_masks_run_together_resumes_to_the_same_masks() {
    use fsot::optimize::backend::BackendChoice;
    use fsot::optimize::run::{CancelFlag, Outcome, RunOptions};
    use fsot::scene::file::Scene;
    use fsot::scene::plan::{CostModel, Plan, PlanEvent};
    let ctx = common::gpu_context();
    let text = "[display]\ntaa_alpha = 0.1\n[tile]\nsize = \"8x8x4\"\n\
                [[group]]\nname = \"a\"\ndims = 1\n[[group]]\nname = \"b\"\ndims = 2\n";
    let scene = Scene::parse(text, "together").unwrap();
    let plan = Plan::new(&scene, &CostModel { seconds_per_point: 1e-6, backend: "test".into() }).unwrap();
    let options = RunOptions::default()
        .backend(BackendChoice::Vulkan)
        .context(Some(ctx.clone()))
        .vulkan(VulkanOptions::default().deterministic(true));
    let straight = tempfile::tempdir().unwrap();
    plan.execute(straight.path(), &options, 10, false, &CancelFlag::new(), &mut |_| {}).unwrap();

    // Cancelled as mask b passes iteration 40: both were in flight together.
    let dir = tempfile::tempdir().unwrap();
    let cancel = CancelFlag::new();
    let mut seen = [0u32; 2];
    let outcome = plan
        .execute(dir.path(), &options, 10, false, &cancel, &mut |e| {
            if let PlanEvent::Run { index, event: fsot::optimize::run::Event::Progress { iteration, .. } } = e
            {
                seen[index] = iteration;
                if index == 1 && iteration >= 40 {
                    cancel.cancel();
                }
            }
        })
        .unwrap();
    assert!(matches!(outcome, Outcome::Cancelled { .. }), "{outcome:?}");
    assert!(seen[0] >= 40, "mask a advanced beside b: {seen:?}");
    assert!(!dir.path().join("plan.json").exists());
    plan.execute(dir.path(), &options, 10, true, &CancelFlag::new(), &mut |_| {}).unwrap();
    for name in ["a.exr", "b.exr"] {
        let x = fsot::io::exr::read(&dir.path().join(name)).unwrap();
        let y = fsot::io::exr::read(&straight.path().join(name)).unwrap();
        let bits = |m: &fsot::Mask| m.samples.iter().map(|v| v.to_bits()).collect::<Vec<u32>>();
        assert_eq!(bits(&x), bits(&y), "{name} differs");
    }
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn a_plan_under_a_budget_on_one_device_runs_its_masks_together_to_the_budgets_end() {
    use fsot::optimize::backend::BackendChoice;
    use fsot::optimize::run::{CancelFlag, RunOptions};
    use fsot::scene::file::Scene;
    use fsot::scene::plan::{CostModel, Plan, PlanEvent};
    let ctx = common::gpu_context();
    let text = "[display]\ntaa_alpha = 0.1\n[tile]\nsize = \"8x8x4\"\n[plan]\nbudget = 2\n\
                [[group]]\nname = \"a\"\ndims = 1\n[[group]]\nname = \"b\"\ndims = 2\n";
    let scene = Scene::parse(text, "budgeted").unwrap();
    let plan = Plan::new(&scene, &CostModel { seconds_per_point: 1e-6, backend: "test".into() }).unwrap();
    let began = std::time::Instant::now();
    let options =
        RunOptions::default().backend(BackendChoice::Vulkan).context(Some(ctx.clone())).budget_from(began);
    let dir = tempfile::tempdir().unwrap();
    let (mut events, mut slowest, mut last) = (Vec::new(), 0.0f64, std::time::Instant::now());
    plan.execute(dir.path(), &options, 10, false, &CancelFlag::new(), &mut |e| match e {
        PlanEvent::Start { file, .. } => events.push(format!("start {file}")),
        PlanEvent::Done { file, .. } => events.push(format!("done {file}")),
        PlanEvent::Run { .. } => {
            slowest = slowest.max(last.elapsed().as_secs_f64());
            last = std::time::Instant::now();
        }
        _ => {}
    })
    .unwrap();
    let seconds = began.elapsed().as_secs_f64();
    // Both start before either ends: they share the device and the whole budget.
    assert_eq!(&events[..2], ["start a.exr", "start b.exr"], "{events:?}");
    assert!(seconds >= 1.0 && seconds <= 2.0 + slowest + 0.5, "{seconds} s for 2 s ({slowest} s a step)");
    for name in ["a.exr", "b.exr"] {
        let mask = fsot::io::exr::read(&dir.path().join(name)).unwrap();
        assert_eq!(mask.meta("budget_seconds"), Some("2"), "{name}");
    }
    common::assert_no_validation_messages(&ctx);
}
