//! The stopping rule evaluated on the device (`glsl/fsot/plateau.comp`): a run
//! whose rule the GPU decides ends where the host's rule (`step_rule::PlateauState`,
//! the CPU path's, forced with `VulkanOptions::host_stopping_rule`) ends the same
//! run, with the same step scales on the way: bit for bit, in deterministic mode
//! (lavapipe in CI, validation on).
#![cfg(feature = "vulkan")]

mod common;

use fsot::core::kernel::KernelSpec;
use fsot::core::step_rule::{Plateau, PlateauState, FINAL_FRACTION};
use fsot::core::tile::Tile;
use fsot::optimize::backend::BackendChoice;
use fsot::optimize::run::{CancelFlag, Checkpointing, Outcome, Run, RunOptions};
use fsot::optimize::settings::{Settings, Until};
use fsot::optimize::vulkan::layout::{CostSlot, RuleState, COST_SCALE};
use fsot::optimize::vulkan::{rule, VulkanHooks, VulkanOptions};
use fsot::vk::Context;

/// A rule that halves the step often and stops early, with windows (7) that do
/// not divide the Vulkan batch (32): the device's decisions fall inside batches.
const QUICK: Plateau = Plateau { window: 7, decay_below: 0.05, stop_below: 0.01, factor: 0.5 };
const CAP: u32 = 3000;

fn settings(until: Until) -> Settings {
    let mut s = Settings::new(KernelSpec::from_name("taa", 2.1, None, 0.1, 60.0).unwrap(), 5);
    s.iterations = CAP;
    s.until = until;
    s
}

fn options(ctx: &Context, host_rule: bool) -> RunOptions {
    RunOptions::default().backend(BackendChoice::Vulkan).context(Some(ctx.clone())).vulkan(
        VulkanOptions::default()
            .deterministic(true)
            .hooks(VulkanHooks { host_stopping_rule: host_rule, ..VulkanHooks::default() }),
    )
}

fn tile() -> Tile {
    Tile::new(8, 8, 4, 1, 2).unwrap()
}

/// Runs to the rule's end; the run, still open for inspection.
fn run_to_end(ctx: &Context, until: Until, host_rule: bool) -> Run {
    let mut run = Run::start(tile(), settings(until), None, options(ctx, host_rule)).unwrap();
    assert_eq!(run.rule_on_device(), !host_rule, "who evaluates the rule");
    run.run(&CancelFlag::new(), &mut |_| {}).unwrap();
    run
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn the_device_ends_a_plateau_run_where_the_host_rule_does_with_the_same_steps() {
    let ctx = common::gpu_context();
    let device = run_to_end(&ctx, Until::Plateau(QUICK), false);
    let host = run_to_end(&ctx, Until::Plateau(QUICK), true);
    let (d, h) = (device.state().unwrap(), host.state().unwrap());
    assert!(device.finished() && host.finished());
    assert!(d.iteration < CAP, "the rule must end the run before its cap ({})", d.iteration);
    assert_eq!(d.iteration, h.iteration, "where the run ended");
    assert_eq!(d.iteration % QUICK.window, 0, "a run ends at a window's end");
    assert_ne!(d.iteration % 32, 0, "this case ends inside a batch");
    let (dp, hp) = (d.plateau.unwrap(), h.plateau.unwrap());
    assert_eq!(dp.scale, FINAL_FRACTION, "the step was halved down to its floor before the end");
    assert_eq!((dp.scale, dp.count, dp.sum), (hp.scale, hp.count, hp.sum));
    assert_eq!(dp.previous.to_bits(), hp.previous.to_bits(), "the last window's mean");
    assert_eq!(d.samples, h.samples, "the same steps make the same samples");
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn the_device_ends_an_objective_run_where_the_host_rule_does() {
    let ctx = common::gpu_context();
    // A target the run reaches after a few windows, well before the plateau rule ends it.
    let until = Until::Objective(1.25e-3);
    let device = run_to_end(&ctx, until, false);
    let host = run_to_end(&ctx, until, true);
    let (d, h) = (device.state().unwrap(), host.state().unwrap());
    assert!(d.iteration > 32 && d.iteration < 1000, "the target ends the run ({})", d.iteration);
    assert_eq!(d.iteration, h.iteration, "where the run ended");
    let last = d.plateau.unwrap().previous;
    assert!(last <= 1.25e-3, "the last window's mean {last} reached the target");
    assert_eq!(d.samples, h.samples);
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn a_run_resumed_inside_a_window_hands_the_device_the_rule_where_it_stood() {
    let ctx = common::gpu_context();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.ckpt");
    let straight = run_to_end(&ctx, Until::Plateau(QUICK), false).state().unwrap();
    // Stopped at 45: inside a window (7) and a batch (32), after the first halvings.
    let with_checkpoint = |resume| {
        let checkpoint = Some(Checkpointing { path: path.clone(), every: 45, resume });
        let o = options(&ctx, false).checkpoint(checkpoint);
        Run::start(tile(), settings(Until::Plateau(QUICK)), None, o).unwrap()
    };
    let mut first = with_checkpoint(false);
    first.advance(45, &CancelFlag::new(), &mut |_| {}).unwrap();
    let cancel = CancelFlag::new();
    cancel.cancel();
    let outcome = first.run(&cancel, &mut |_| {}).unwrap();
    assert!(matches!(outcome, Outcome::Cancelled { iteration: 45, .. }), "{outcome:?}");
    let saved = first.state().unwrap().plateau.unwrap();
    assert!(saved.count > 0, "the checkpoint is inside a window");
    assert!(saved.scale < 1.0, "the step has been halved before the checkpoint");
    drop(first);
    let mut resumed = with_checkpoint(true);
    assert_eq!(resumed.resumed_from(), Some(45));
    assert!(resumed.rule_on_device());
    resumed.run(&CancelFlag::new(), &mut |_| {}).unwrap();
    let r = resumed.state().unwrap();
    assert_eq!(r.iteration, straight.iteration, "where the run ended");
    assert_eq!(r.samples, straight.samples, "resumed = straight, bit for bit");
    common::assert_no_validation_messages(&ctx);
}

/// The host's rule over the same cost slots, as `Run` applies it: the state,
/// and the iterations done when it ended the run, after each slot.
fn host_rule(
    rule: &Plateau,
    mut state: PlateauState,
    target: Option<f64>,
    slots: &[CostSlot],
) -> Vec<(PlateauState, Option<u32>)> {
    let mut stopped = None;
    let mut out = Vec::new();
    for (k, s) in slots.iter().enumerate() {
        if stopped.is_none() {
            let objective = if s.count > 0 { s.squared as f64 / COST_SCALE / s.count as f64 } else { 0.0 };
            let window_end = state.count + 1 == rule.window.max(1);
            let mut stop = state.observe(rule, objective);
            if let (true, Some(t)) = (window_end, target) {
                stop |= state.previous <= t;
            }
            if stop {
                stopped = Some(k as u32 + 1);
            }
        }
        out.push((state, stopped));
    }
    out
}

/// The device's pass over the same slots, held against `host_rule` slot by slot.
fn assert_device_follows_host(
    ctx: &Context,
    rule: &Plateau,
    start: PlateauState,
    target: Option<f64>,
    slots: &[CostSlot],
) -> Vec<(PlateauState, Option<u32>)> {
    let device = rule::replay(ctx, RuleState::new(rule, &start, target), slots).unwrap();
    let host = host_rule(rule, start, target, slots);
    assert_eq!((device.len(), host.len()), (slots.len(), slots.len()), "a state per slot");
    for (k, (d, (h, stopped))) in device.iter().zip(&host).enumerate() {
        let p = d.plateau_state();
        let got = (
            p.scale,
            p.count,
            p.sum.to_bits(),
            p.previous.to_bits(),
            d.stopped().then_some(d.stop_iteration),
        );
        let want = (h.scale, h.count, h.sum.to_bits(), h.previous.to_bits(), *stopped);
        assert_eq!(got, want, "slot {k}: device (scale, count, sum, previous, end) against the host's");
    }
    host
}

/// Cost slots whose objectives wander down by random relative steps.
fn wandering(seed: u64, n: usize, drift: f64) -> Vec<CostSlot> {
    let mut x = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
    let mut objective = 1.0e-3;
    (0..n)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let u = (x >> 11) as f64 / (1u64 << 53) as f64;
            objective *= 1.0 - drift * u + 0.4 * drift * (1.0 - u);
            let count = 500 + (x % 3000) as i64;
            CostSlot { squared: (objective * COST_SCALE * count as f64) as i64, count }
        })
        .collect()
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn the_device_pass_takes_the_host_rules_decisions_slot_by_slot() {
    let ctx = common::gpu_context();
    if !ctx.info().float64
        && common::skip(&format!("{} lacks shaderFloat64 (the host keeps the rule there)", ctx.info().name))
    {
        return;
    }
    let rule = Plateau { window: 4, decay_below: 0.01, stop_below: 0.003, factor: 0.5 };
    // Random descents whose window gains straddle both thresholds: every halving
    // down to the floor, then an end.
    let mut ends = 0;
    for seed in 1..=12 {
        let slots = wandering(seed, 400, 0.01);
        let host = assert_device_follows_host(&ctx, &rule, PlateauState::default(), None, &slots);
        ends += host.last().unwrap().1.is_some() as u32;
    }
    assert!(ends >= 6, "the descents must reach the rule's end ({ends} of 12 did)");
    // From a state mid-window (a resumed run), with a target met exactly by a
    // window's mean (<= ends it).
    let slots = wandering(99, 64, 0.02);
    let start = PlateauState { scale: 0.25, previous: 1.1e-3, sum: 2.0e-3, count: 2 };
    let free = host_rule(&rule, start, None, &slots);
    let mean = free[5].0.previous; // the second window's mean (slots 2..6)
    let host = assert_device_follows_host(&ctx, &rule, start, Some(mean), &slots);
    assert_eq!(host[5].1, Some(6), "the target equal to a window's mean ends the run there");
    // Empty slots (objective 0): 0 / 0 gains decide nothing, then a jump up.
    let mut slots = vec![CostSlot { squared: 0, count: 0 }; 12];
    slots.extend(wandering(7, 12, 0.01));
    assert_device_follows_host(&ctx, &rule, PlateauState::default(), None, &slots);
    // A window of one iteration, and the scale already at its floor.
    let one = Plateau { window: 1, ..rule };
    let floor = PlateauState { scale: FINAL_FRACTION, ..PlateauState::default() };
    assert_device_follows_host(&ctx, &one, floor, Some(1e-9), &wandering(3, 40, 0.004));
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn a_device_without_f64_leaves_the_rule_to_the_host_and_ends_at_the_same_iteration() {
    let ctx = common::gpu_context();
    // The same device wrapped as a host that did not enable shaderFloat64.
    // SAFETY: ctx's live device, with fewer features claimed than it has; guest is dropped first.
    let guest =
        unsafe { Context::wrap(fsot::vk::ExternalDevice { float64: false, ..ctx.external() }) }.unwrap();
    let mut run = Run::start(tile(), settings(Until::Plateau(QUICK)), None, options(&guest, false)).unwrap();
    assert!(!run.rule_on_device(), "without shaderFloat64 the host evaluates the rule");
    run.run(&CancelFlag::new(), &mut |_| {}).unwrap();
    let on_device = run_to_end(&ctx, Until::Plateau(QUICK), false).state().unwrap();
    let (g, d) = (run.state().unwrap(), on_device);
    assert_eq!(g.iteration, d.iteration, "where the run ended");
    assert_eq!(g.samples, d.samples);
    common::assert_no_validation_messages(&ctx);
}
