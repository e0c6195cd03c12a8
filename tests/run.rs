//! The library's run, with no command line: checkpoints, cancellation through the
//! caller's flag, resumption, and the guarantee that an interrupted and resumed
//! run equals an uninterrupted one bit for bit.

mod common;

use fsot::core::kernel::KernelSpec;
use fsot::core::mask::Mask;
use fsot::core::tile::Tile;
use fsot::error::Error;
use fsot::optimize::backend::BackendChoice;
#[cfg(feature = "vulkan")]
use fsot::optimize::backend::BackendKind;
use fsot::optimize::run::{CancelFlag, Checkpointing, Event, Outcome, Run, RunOptions};
use fsot::optimize::settings::Settings;
#[cfg(feature = "vulkan")]
use fsot::optimize::vulkan::VulkanOptions;

/// The test of the run's pacing times its iterations: it runs alone (write),
/// the others of this file together (read), so that their work on the same
/// cores (llvmpipe compiling a pass for seconds, say) does not slow its first
/// iteration and so change its steps.
static PACING: std::sync::RwLock<()> = std::sync::RwLock::new(());

fn others() -> std::sync::RwLockReadGuard<'static, ()> {
    PACING.read().unwrap_or_else(|e| e.into_inner())
}

fn settings(iterations: u32) -> Settings {
    let mut s = Settings::new(KernelSpec::from_name("taa", 2.1, None, 0.1, 60.0).unwrap(), 11);
    s.iterations = iterations;
    s
}

fn bits(mask: &Mask) -> Vec<u32> {
    mask.samples.iter().map(|v| v.to_bits()).collect()
}

/// Runs `options` to the end, uninterrupted.
fn straight(tile: Tile, s: Settings, options: RunOptions) -> Mask {
    let mut run = Run::start(tile, s, None, options).unwrap();
    assert_eq!(run.run(&CancelFlag::new(), &mut |_| {}).unwrap(), Outcome::Reached);
    run.finish().unwrap()
}

/// Cancels at the first progress at or past `stop`, then resumes in a new run.
fn interrupted_then_resumed(tile: Tile, s: Settings, options: RunOptions, stop: u32) -> (u32, Mask) {
    let path = options.checkpoint.as_ref().unwrap().path.clone();
    let cancel = CancelFlag::new();
    let mut run = Run::start(tile, s, None, options.clone()).unwrap();
    let mut checkpoints = Vec::new();
    let outcome = run
        .run(&cancel, &mut |event| match event {
            Event::Progress { iteration, .. } if iteration >= stop => cancel.cancel(),
            Event::Checkpoint { iteration, .. } => checkpoints.push(iteration),
            _ => {}
        })
        .unwrap();
    let Outcome::Cancelled { iteration, saved } = outcome else { panic!("not cancelled: {outcome:?}") };
    assert!(iteration >= stop && iteration < s.iterations, "stopped at {iteration}");
    assert_eq!(saved.as_deref(), Some(path.as_path()), "the state is saved when cancelled");
    assert!(!checkpoints.is_empty() && checkpoints.iter().all(|&c| c % 7 == 0), "every 7: {checkpoints:?}");
    drop(run);

    // The same run again without resuming refuses to overwrite the checkpoint.
    let mut fresh = options.clone();
    fresh.checkpoint.as_mut().unwrap().resume = false;
    assert!(matches!(Run::start(tile, s, None, fresh), Err(Error::CheckpointExists(_))));
    let mut resumed = options;
    resumed.checkpoint.as_mut().unwrap().resume = true;
    // Another run (another seed) cannot resume it.
    let mut other = s;
    other.seed += 1;
    let err = Run::start(tile, other, None, resumed.clone()).err().expect("another run's checkpoint");
    assert!(err.to_string().contains("different run"), "{err}");
    let mut run = Run::start(tile, s, None, resumed).unwrap();
    assert_eq!(run.resumed_from(), Some(iteration));
    assert_eq!(run.run(&CancelFlag::new(), &mut |_| {}).unwrap(), Outcome::Reached);
    let mask = run.finish().unwrap();
    assert!(!path.exists(), "a completed run removes its checkpoint");
    (iteration, mask)
}

fn checkpointed(options: RunOptions, dir: &tempfile::TempDir) -> RunOptions {
    let checkpoint = Checkpointing { path: dir.path().join("run.ckpt"), every: 7, resume: false };
    options.checkpoint(Some(checkpoint))
}

#[test]
fn a_run_refuses_settings_and_masks_built_by_hand_out_of_range_before_any_work() {
    use fsot::{Spatial, StepRule, Temporal, Until};
    let _others = others();
    let tile = Tile::new(8, 8, 4, 1, 2).unwrap();
    let cpu = || RunOptions::default().backend(BackendChoice::Cpu);
    let refused = |tile: Tile, s: Settings, init: Option<&Mask>, why: &str| {
        let err = Run::start(tile, s, init, cpu()).err().unwrap_or_else(|| panic!("{why}: started"));
        assert!(matches!(err, Error::Invalid(_)), "{why}: {err}");
    };
    let with = |f: &dyn Fn(&mut Settings)| {
        let mut s = settings(3);
        f(&mut s);
        s
    };
    refused(Tile { width: 0, ..tile }, settings(3), None, "a tile without width");
    refused(Tile { dims: 9, ..tile }, settings(3), None, "nine dimensions");
    refused(tile, with(&|s| s.kernel.tolerance = 0.0), None, "a tolerance of 0 (an endless kernel)");
    refused(tile, with(&|s| s.kernel.tolerance = f64::NAN), None, "a NaN tolerance");
    refused(tile, with(&|s| s.kernel.spatial = Spatial::Gaussian { sigma: 1e6 }), None, "a huge sigma");
    refused(tile, with(&|s| s.kernel.spatial = Spatial::Display { ppd: f64::NAN }), None, "a NaN ppd");
    refused(tile, with(&|s| s.kernel.temporal = Temporal::Taa { alpha: 0.0 }), None, "alpha 0");
    refused(tile, with(&|s| s.kernel.temporal = Temporal::Perceptual { fps: 1e12 }), None, "fps 1e12");
    refused(tile, with(&|s| s.rule = StepRule::Momentum { step: f32::NAN, beta: 0.8 }), None, "a NaN step");
    refused(
        tile,
        with(&|s| s.rule = StepRule::Adam { lr: 0.01, beta1: 1.0, beta2: 1.0, eps: 0.0 }),
        None,
        "Adam's decays at 1",
    );
    refused(tile, with(&|s| s.until = Until::Objective(f64::NAN)), None, "a NaN objective to stop at");
    use fsot::Plateau;
    let plateau = |p: Plateau| move |s: &mut Settings| s.until = Until::Plateau(p);
    let endless = Plateau { window: u32::MAX, ..Plateau::DEFAULT };
    refused(tile, with(&plateau(endless)), None, "a plateau window of 2^32 - 1");
    let empty = Plateau { window: 0, ..Plateau::DEFAULT };
    refused(tile, with(&plateau(empty)), None, "a plateau window of 0");
    let infinite =
        Plateau { window: 1, decay_below: f64::INFINITY, factor: f32::INFINITY, ..Plateau::DEFAULT };
    refused(tile, with(&plateau(infinite)), None, "an infinite plateau factor");
    let nan_gain = Plateau { stop_below: f64::NAN, ..Plateau::DEFAULT };
    refused(tile, with(&plateau(nan_gain)), None, "a NaN gain");
    let mut short = Mask::white(tile, 1);
    short.samples.truncate(10);
    refused(tile, settings(3), Some(&short), "an initial mask of too few values");
    let mut nan = Mask::white(tile, 1);
    nan.samples[3] = f32::NAN;
    refused(tile, settings(3), Some(&nan), "an initial mask holding NaN");
    // Each field at its constructors' value starts.
    assert!(Run::start(tile, settings(3), Some(&Mask::white(tile, 1)), cpu()).is_ok());
}

#[test]
fn a_cancelled_and_resumed_cpu_run_equals_an_uninterrupted_one() {
    let _others = others();
    let tile = Tile::new(16, 16, 4, 1, 2).unwrap();
    let s = settings(60);
    let cpu = RunOptions::default().backend(BackendChoice::Cpu);
    let reference = straight(tile, s, cpu.clone());
    let dir = tempfile::tempdir().unwrap();
    let (stopped, resumed) = interrupted_then_resumed(tile, s, checkpointed(cpu, &dir), 25);
    assert_eq!(stopped, 25, "the CPU path stops after the iteration that saw the flag");
    assert_eq!(bits(&resumed), bits(&reference), "resumed and uninterrupted runs differ");
}

#[cfg(feature = "vulkan")]
#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn a_cancelled_and_resumed_deterministic_vulkan_run_equals_an_uninterrupted_one() {
    let _others = others();
    let ctx = common::gpu_context();
    let tile = Tile::new(16, 16, 4, 1, 2).unwrap();
    let s = settings(60);
    let vulkan = RunOptions::default()
        .backend(BackendChoice::Vulkan)
        .context(Some(ctx.clone()))
        .vulkan(VulkanOptions::default().deterministic(true));
    let reference = straight(tile, s, vulkan.clone());
    let dir = tempfile::tempdir().unwrap();
    let (stopped, resumed) = interrupted_then_resumed(tile, s, checkpointed(vulkan, &dir), 25);
    // Batches end at checkpoints (every 7): the flag is seen at 28.
    assert_eq!(stopped, 28);
    assert_eq!(bits(&resumed), bits(&reference), "resumed and uninterrupted runs differ");
    common::assert_no_validation_messages(&ctx);
}

/// A Vulkan run paces its steps (one submission each) to last about half a second
/// at the last step's pace, so that the flag and the progress report answer
/// within that much even on a slow device: the first step is one iteration; on a
/// device that is fast for the tile, the steps after it are whole batches.
#[cfg(feature = "vulkan")]
#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn a_vulkan_run_steps_one_iteration_first_then_whole_batches_where_iterations_are_fast() {
    let _alone = PACING.write().unwrap_or_else(|e| e.into_inner());
    let ctx = common::gpu_context();
    let tile = Tile::new(8, 8, 2, 1, 2).unwrap();
    let options = RunOptions::default().backend(BackendChoice::Vulkan).context(Some(ctx.clone()));
    let mut run = Run::start(tile, settings(80), None, options).unwrap();
    let mut seen = Vec::new();
    let outcome = run
        .run(&CancelFlag::new(), &mut |event| {
            if let Event::Progress { iteration, .. } = event {
                seen.push(iteration)
            }
        })
        .unwrap();
    assert_eq!(outcome, Outcome::Reached);
    // 8x8x2 takes well under a millisecond per iteration even on lavapipe in CI
    // (a batch of 32 well under the half second).
    assert_eq!(seen, [1, 33, 65, 80], "steps: {seen:?}");
    common::assert_no_validation_messages(&ctx);
}

#[cfg(feature = "vulkan")]
#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn auto_takes_a_context_it_is_handed_and_says_which_backend_it_chose() {
    let _others = others();
    let ctx = common::gpu_context();
    let tile = Tile::new(8, 8, 2, 1, 3).unwrap();
    // Unhanded, auto looks for a GPU: a CPU implementation is not one.
    let run = Run::start(tile, settings(5), None, RunOptions::default()).unwrap();
    let kind = if ctx.info().is_cpu() { BackendKind::Cpu } else { BackendKind::Vulkan };
    assert_eq!(run.backend().kind(), kind, "{}", run.note());
    if kind == BackendKind::Cpu {
        assert!(run.note().starts_with("cpu"), "{}", run.note());
    }
    drop(run);
    let handed = RunOptions::default().context(Some(ctx.clone()));
    for dims in [2, 3, 8] {
        let on_gpu =
            Run::start(Tile::new(8, 8, 2, 1, dims).unwrap(), settings(5), None, handed.clone()).unwrap();
        assert_eq!(on_gpu.backend_kind(), BackendKind::Vulkan, "d = {dims}: a handed context is taken");
    }
    // A device without shaderFloat64 takes d >= 3 too (the float32-pair targets).
    // SAFETY: ctx's live device, with fewer features claimed than it has; guest is dropped first.
    let guest =
        unsafe { fsot::vk::Context::wrap(fsot::vk::ExternalDevice { float64: false, ..ctx.external() }) }
            .unwrap();
    let handed = RunOptions::default().context(Some(guest.clone()));
    let taken = Run::start(tile, settings(5), None, handed).unwrap();
    assert_eq!(taken.backend_kind(), BackendKind::Vulkan, "{}", taken.note());
    drop((taken, guest));
    common::assert_no_validation_messages(&ctx);
}

#[test]
fn a_run_without_checkpoints_stops_on_the_flag_and_writes_nothing() {
    let _others = others();
    let tile = Tile::new(8, 8, 2, 1, 2).unwrap();
    let mut run =
        Run::start(tile, settings(40), None, RunOptions::default().backend(BackendChoice::Cpu)).unwrap();
    let cancel = CancelFlag::new();
    cancel.cancel();
    let outcome = run.run(&cancel, &mut |_| panic!("no iteration after the flag")).unwrap();
    assert_eq!(outcome, Outcome::Cancelled { iteration: 0, saved: None });
}

#[test]
fn a_run_that_stops_by_the_plateau_rule_resumes_exactly_and_stops_where_it_would_have() {
    let _others = others();
    use fsot::core::step_rule::Plateau;
    use fsot::optimize::settings::Until;
    let tile = Tile::new(8, 8, 4, 1, 2).unwrap();
    // A quick rule: 8-iteration windows.
    let rule = Plateau { window: 8, ..Plateau::DEFAULT };
    let s = settings(5000).until(Until::Plateau(rule)).iterations(5000);
    let cpu = RunOptions::default().backend(BackendChoice::Cpu);
    let mut run = Run::start(tile, s, None, cpu.clone()).unwrap();
    assert_eq!(run.run(&CancelFlag::new(), &mut |_| {}).unwrap(), Outcome::Reached);
    let stopped_at = run.iteration();
    assert!(run.finished() && stopped_at < 5000, "the rule stopped it: {stopped_at}");
    assert_eq!(stopped_at % 8, 0, "at a window's end");
    let reference = run.finish().unwrap();
    assert_eq!(reference.meta("iterations"), Some(stopped_at.to_string().as_str()));

    // Cancelled mid-window (checkpoints every 5, windows of 8), then resumed.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.ckpt");
    let mut options = cpu.checkpoint(Some(Checkpointing { path, every: 5, resume: false }));
    let cancel = CancelFlag::new();
    let mut first = Run::start(tile, s, None, options.clone()).unwrap();
    let stop = stopped_at / 2 + 3;
    let outcome = first
        .run(&cancel, &mut |e| {
            if matches!(e, Event::Progress { iteration, .. } if iteration >= stop) {
                cancel.cancel()
            }
        })
        .unwrap();
    assert!(matches!(outcome, Outcome::Cancelled { iteration, .. } if iteration % 8 != 0), "{outcome:?}");
    drop(first);
    options.checkpoint.as_mut().unwrap().resume = true;
    let mut resumed = Run::start(tile, s, None, options).unwrap();
    resumed.run(&CancelFlag::new(), &mut |_| {}).unwrap();
    assert_eq!(resumed.iteration(), stopped_at, "the resumed run stops where the straight one did");
    assert_eq!(bits(&resumed.finish().unwrap()), bits(&reference));
}

#[test]
fn a_complete_run_keeps_its_checkpoint_until_its_mask_is_kept() {
    let tile = Tile::new(8, 8, 4, 1, 2).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let options = checkpointed(RunOptions::default().backend(BackendChoice::Cpu), &dir);
    let path = dir.path().join("run.ckpt");
    let mut run = Run::start(tile, settings(20), None, options.clone()).unwrap();
    run.run(&CancelFlag::new(), &mut |_| {}).unwrap();
    assert!(run.finished() && path.exists(), "a checkpoint every 7 iterations of 20");
    let e = run.finish_with(|_| Err(fsot::Error::invalid("the disk is full"))).unwrap_err();
    assert!(e.to_string().contains("the disk is full"), "{e}");
    assert!(path.exists(), "a mask not kept leaves the checkpoint to resume from");
    // Resumed, the run is complete: kept this time, its checkpoint goes.
    let resume = Checkpointing { resume: true, ..options.checkpoint.clone().unwrap() };
    let mut run = Run::start(tile, settings(20), None, options.checkpoint(Some(resume))).unwrap();
    assert_eq!(run.resumed_from(), Some(14));
    run.run(&CancelFlag::new(), &mut |_| {}).unwrap();
    let mut kept = Vec::new();
    let mask = run
        .finish_with(|m| {
            kept = bits(m);
            Ok(())
        })
        .unwrap();
    assert_eq!(kept, bits(&mask));
    assert!(!path.exists(), "a kept mask's checkpoint goes");
}

#[test]
fn a_start_cut_short_by_its_flag_ends_the_start_as_interrupted_and_saves_nothing() {
    let tile = Tile::new(32, 32, 8, 1, 2).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let cancel = CancelFlag::new();
    cancel.cancel();
    let options =
        checkpointed(RunOptions::default().backend(BackendChoice::Cpu), &dir).cancel_start(cancel.clone());
    let s = settings(100).start(fsot::Start::Animated);
    let e = Run::start(tile, s, None, options.clone()).err().expect("interrupted");
    assert!(matches!(e, Error::Interrupted), "{e}");
    assert!(!dir.path().join("run.ckpt").exists(), "nothing saved");
    // A start of white noise has no work to cut short: the flag is left to `run`.
    let mut run = Run::start(tile, settings(100).start(fsot::Start::White), None, options).unwrap();
    assert!(matches!(run.run(&cancel, &mut |_| {}).unwrap(), Outcome::Cancelled { iteration: 0, .. }));
}

#[test]
fn a_run_until_an_objective_stops_once_a_window_reaches_it() {
    let _others = others();
    use fsot::optimize::settings::Until;
    let tile = Tile::new(8, 8, 4, 1, 2).unwrap();
    let cpu = RunOptions::default().backend(BackendChoice::Cpu);
    // Where a plateau run's objective estimate goes, then a target short of it.
    let mut probe = Run::start(tile, settings(64), None, cpu.clone()).unwrap();
    let mut costs = Vec::new();
    probe
        .run(&CancelFlag::new(), &mut |e| {
            if let Event::Progress { objective: Some(c), .. } = e {
                costs.push(c)
            }
        })
        .unwrap();
    let target = costs[..32].iter().sum::<f64>() / 32.0 * 0.8;
    let s = settings(5000).until(Until::Objective(target)).iterations(5000);
    let mut run = Run::start(tile, s, None, cpu).unwrap();
    let mut windows = Vec::new();
    let mut window = Vec::new();
    run.run(&CancelFlag::new(), &mut |e| {
        if let Event::Progress { objective: Some(c), .. } = e {
            window.push(c);
            if window.len() == 32 {
                windows.push(window.iter().sum::<f64>() / 32.0);
                window.clear();
            }
        }
    })
    .unwrap();
    assert!(run.finished() && run.iteration() < 5000);
    let last = *windows.last().unwrap();
    assert!(last <= target, "stopped at a window of mean {last:e}, target {target:e}");
    assert!(
        windows[..windows.len() - 1].iter().all(|&w| w > target),
        "it went on past the target: {windows:?}"
    );
}

/// A run under a time budget on `backend`: (seconds from before `Run::start`
/// to the mask, iterations done, the slowest iteration's seconds as paced).
fn budget_run(backend: BackendChoice, budget: f64) -> (f64, u32, f64, Mask) {
    let tile = Tile::new(32, 32, 8, 1, 2).unwrap();
    let s = settings(100_000).until(fsot::Until::Seconds(budget));
    let begun = std::time::Instant::now();
    let mut run = Run::start(tile, s, None, RunOptions::default().backend(backend)).unwrap();
    // The set-up's parts, timed inside, against the whole of `Run::start` timed here.
    let whole = begun.elapsed().as_secs_f64();
    let set_up = run.set_up();
    assert!(set_up.start > 0.0, "an animated start takes time: {set_up:?}");
    assert!(set_up.backend > 0.0, "{set_up:?}");
    let parts = set_up.start + set_up.backend;
    // Nothing of note untimed (a margin for a busy machine's scheduling).
    assert!(parts <= whole && parts >= whole - 0.25, "{set_up:?} of {whole} s in Run::start");
    let mut slowest = 0.0f64;
    let mut last = (begun, 0u32);
    run.run(&CancelFlag::new(), &mut |e| {
        if let Event::Progress { iteration, .. } = e {
            let now = std::time::Instant::now();
            let per = now.duration_since(last.0).as_secs_f64() / (iteration - last.1).max(1) as f64;
            slowest = slowest.max(per);
            last = (now, iteration);
        }
    })
    .unwrap();
    let iterations = run.iteration();
    let mask = run.finish().unwrap();
    (begun.elapsed().as_secs_f64(), iterations, slowest, mask)
}

#[test]
fn a_run_under_a_time_budget_ends_within_about_one_iteration_of_it_with_its_iterations_said() {
    let _alone = PACING.write().unwrap_or_else(|e| e.into_inner());
    let budget = 0.6;
    let (seconds, iterations, slowest, mask) = budget_run(BackendChoice::Cpu, budget);
    assert!(iterations > 0 && iterations < 100_000, "{iterations} iterations");
    // One iteration past it, and a margin for a busy machine's scheduling.
    assert!(
        seconds <= budget + slowest + 0.2,
        "{seconds} s for a budget of {budget} s ({slowest} s an iteration)"
    );
    assert!(seconds >= 0.5 * budget, "{seconds} s: the budget was not used");
    assert_eq!(mask.meta("budget_seconds"), Some("0.6"));
    assert_eq!(mask.meta("iterations"), Some(iterations.to_string().as_str()));
    assert!(mask.samples.iter().all(|v| (0.0..1.0).contains(v)));
}

#[test]
fn a_run_under_a_time_budget_that_its_iteration_cap_ends_first_ends_on_the_schedules_last_step() {
    // A budget of an hour that 40 iterations of a small tile cannot reach: the
    // cap ends the run, so its steps follow the iterations through the cosine
    // schedule, one iteration each, to its last step: the fixed run of 40 from
    // the same start, bit for bit. Following the clock, they would all be near
    // the full step.
    let _others = others();
    let tile = Tile::new(16, 16, 4, 1, 2).unwrap();
    let make = |s: Settings| {
        let mut run = Run::start(tile, s, None, RunOptions::default().backend(BackendChoice::Cpu)).unwrap();
        run.run(&CancelFlag::new(), &mut |_| {}).unwrap();
        assert_eq!(run.iteration(), 40);
        run.finish().unwrap()
    };
    let fixed = make(settings(40).start(fsot::Start::White));
    let budgeted = make(settings(40).start(fsot::Start::White).until(fsot::Until::Seconds(3600.0)));
    assert_eq!(bits(&budgeted), bits(&fixed));
}

#[cfg(feature = "vulkan")]
#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn a_vulkan_run_under_a_time_budget_ends_within_about_one_iteration_of_it() {
    let _alone = PACING.write().unwrap_or_else(|e| e.into_inner());
    let budget = 1.5;
    let (seconds, iterations, slowest, _) = budget_run(BackendChoice::Vulkan, budget);
    assert!(iterations > 0, "{iterations} iterations");
    assert!(
        seconds <= budget + slowest + 0.3,
        "{seconds} s for a budget of {budget} s ({slowest} s an iteration)"
    );
    assert!(seconds >= 0.5 * budget, "{seconds} s: the budget was not used");
}

#[test]
fn a_time_budget_that_is_not_a_positive_time_or_that_asks_for_checkpoints_is_refused() {
    let tile = Tile::new(8, 8, 4, 1, 2).unwrap();
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY, 1e9] {
        let s = settings(100).until(fsot::Until::Seconds(bad));
        let e = Run::start(tile, s, None, RunOptions::default().backend(BackendChoice::Cpu)).err().unwrap();
        assert!(matches!(e, Error::Invalid(_)) && e.to_string().contains("time budget"), "{bad}: {e}");
    }
    let dir = tempfile::tempdir().unwrap();
    let s = settings(100).until(fsot::Until::Seconds(1.0));
    let options = checkpointed(RunOptions::default().backend(BackendChoice::Cpu), &dir);
    let e = Run::start(tile, s, None, options).err().unwrap();
    assert!(e.to_string().contains("takes no checkpoints"), "{e}");
}

#[test]
fn an_axis_share_outside_zero_to_one_is_refused_before_any_work() {
    let tile = Tile::new(8, 8, 4, 1, 2).unwrap();
    for bad in [-0.1, 1.5, f64::NAN, f64::INFINITY] {
        // An animated start would run first: the share is refused before it.
        let s = settings(100).axis_share(bad).start(fsot::Start::Animated);
        let e = Run::start(tile, s, None, RunOptions::default().backend(BackendChoice::Cpu)).err().unwrap();
        assert!(matches!(e, Error::Invalid(_)) && e.to_string().contains("axis share"), "{bad}: {e}");
    }
    for good in [0.0, 1.0] {
        assert!(Run::start(
            tile,
            settings(3).axis_share(good),
            None,
            RunOptions::default().backend(BackendChoice::Cpu)
        )
        .is_ok());
    }
}

#[test]
fn a_coarse_start_makes_a_quarter_first_within_the_budget_and_says_so() {
    let _alone = PACING.write().unwrap_or_else(|e| e.into_inner());
    let tile = Tile::new(32, 32, 8, 1, 2).unwrap();
    let budget = 0.6;
    let s = settings(100_000).until(fsot::Until::Seconds(budget)).start(fsot::Start::Coarse);
    let begun = std::time::Instant::now();
    let mut run = Run::start(tile, s, None, RunOptions::default().backend(BackendChoice::Cpu)).unwrap();
    let note = run.start_note().expect("a coarse start says how it was made").to_string();
    assert!(note.contains("16x16x8") && note.contains("laid out 2x2"), "{note}");
    run.run(&CancelFlag::new(), &mut |_| {}).unwrap();
    let mask = run.finish().unwrap();
    let seconds = begun.elapsed().as_secs_f64();
    // The quarter's run and the whole tile's share one budget; a margin for the
    // last iteration and a busy machine.
    assert!(seconds <= budget + 0.3, "{seconds} s for a budget of {budget} s");
    assert_eq!(mask.meta("start"), Some("coarse"));
    assert!(mask.samples.iter().all(|v| (0.0..1.0).contains(v)));
    let score = mask.score(KernelSpec::from_name("taa", 2.1, None, 0.1, 60.0).unwrap()).unwrap();
    assert!(score.ratio() < 0.8, "{} x white noise", score.ratio());
}

#[test]
fn a_coarse_start_without_a_budget_or_without_an_even_quarter_of_sixteen_pixels_is_refused() {
    let s = settings(10).start(fsot::Start::Coarse);
    let e = Run::start(Tile::new(32, 32, 4, 1, 2).unwrap(), s, None, RunOptions::default()).err().unwrap();
    assert!(matches!(e, Error::Invalid(_)) && e.to_string().contains("--budget"), "{e}");
    for (w, h) in [(30, 32), (32, 33), (32, 24)] {
        let s = settings(10).until(fsot::Until::Seconds(1.0)).start(fsot::Start::Coarse);
        let e = Run::start(Tile::new(w, h, 4, 1, 2).unwrap(), s, None, RunOptions::default()).err().unwrap();
        assert!(
            matches!(e, Error::Invalid(_)) && e.to_string().contains("even and at least 32"),
            "{w}x{h}: {e}"
        );
    }
}

#[test]
fn a_run_from_a_given_mask_records_that_start_not_the_settings_one() {
    let tile = Tile::new(8, 8, 4, 1, 2).unwrap();
    let given = Mask::white(tile, 9);
    let s = settings(3).start(fsot::Start::Animated);
    let run = Run::start(tile, s, Some(&given), RunOptions::default()).unwrap();
    let mask = run.finish().unwrap();
    assert_eq!(mask.meta("start"), Some("a given mask"));
    let own = Run::start(tile, s, None, RunOptions::default()).unwrap().finish().unwrap();
    assert_eq!(own.meta("start"), Some("animated"));
}

#[test]
fn a_checkpoint_of_a_run_from_a_given_mask_resumes_only_with_that_start_given() {
    let dir = tempfile::tempdir().unwrap();
    let tile = Tile::new(8, 8, 4, 1, 2).unwrap();
    let given = Mask::white(tile, 9);
    let s = settings(40);
    let path = dir.path().join("run.ckpt");
    let options = |resume| {
        RunOptions::default().backend(BackendChoice::Cpu).checkpoint(Some(Checkpointing {
            path: path.clone(),
            every: 5,
            resume,
        }))
    };
    let mut run = Run::start(tile, s, Some(&given), options(false)).unwrap();
    run.advance(10, &CancelFlag::new(), &mut |_| {}).unwrap();
    let cancel = CancelFlag::new();
    cancel.cancel();
    assert!(matches!(run.run(&cancel, &mut |_| {}).unwrap(), Outcome::Cancelled { .. }));
    // Without the start it was made from: another run.
    let other = Run::start(tile, s, None, options(true)).map(|_| ()).unwrap_err().to_string();
    assert!(other.contains("different run"), "{other}");
    let resumed = Run::start(tile, s, Some(&given), options(true)).unwrap().finish();
    assert!(resumed.is_ok());
}
