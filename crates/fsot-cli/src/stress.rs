//! The numerical stress suite (`fsot stress`, and crates/fsot-cli/tests/stress.rs at CI size): long
//! runs, float32 GPU against the CPU path's float64 transport, accumulation of a
//! million contributions into one value, extreme settings and shapes, ties, and
//! determinism across thread counts and GPU runs. Every check returns a figure, the
//! bound it is held to, and whether it held.

use std::time::Instant;

use rayon::prelude::*;

use fsot::core::kernel::KernelSpec;
use fsot::core::mask::Mask;
use fsot::core::objective::score;
use fsot::core::rng::{derive, Stream};
use fsot::core::tile::Tile;
use fsot::error::{Error, Result};
use fsot::optimize::backend::BackendChoice;
use fsot::optimize::cpu::{reference_displacements, Accumulator, FIXED_SCALE};
use fsot::optimize::run::{CancelFlag, Run, RunOptions};
use fsot::optimize::settings::Settings;
use fsot::optimize::vulkan::VulkanOptions;
use fsot::vk::Context;

/// How big the suite runs.
#[derive(Clone, Copy, Debug)]
pub struct StressSize {
    /// Iterations of the long runs (CPU path, GPU path).
    pub long_cpu: u32,
    pub long_gpu: u32,
    /// Contributions summed into one accumulator.
    pub accumulate: u32,
    /// Iterations of each extreme-setting run.
    pub extreme: u32,
}

impl StressSize {
    /// The full sizes: 100k iterations, 10^6 contributions.
    pub fn full() -> Self {
        Self { long_cpu: 100_000, long_gpu: 100_000, accumulate: 1_000_000, extreme: 200 }
    }
    /// A CI-sized run: short runs, the same million contributions.
    pub fn quick() -> Self {
        Self { long_cpu: 3_000, long_gpu: 600, accumulate: 1_000_000, extreme: 30 }
    }
}

/// One check's outcome.
#[derive(Clone, Debug)]
pub struct Check {
    pub group: &'static str,
    pub name: String,
    /// The measured figure, in words and numbers.
    pub figure: String,
    /// What it is held to.
    pub bound: String,
    /// Whether it held; None where it was not tried (the device cannot take it).
    pub passed: Option<bool>,
    pub seconds: f64,
}

fn spec(name: &str, sigma: f64, alpha: f64) -> Result<KernelSpec> {
    KernelSpec::from_name(name, sigma, None, alpha, 60.0)
}

fn settings(kernel: KernelSpec, iterations: u32, seed: u64) -> Settings {
    let mut s = Settings::new(kernel, seed);
    s.iterations = iterations;
    s
}

/// A library run on the CPU path, or on `ctx` with `vulkan`.
fn start(
    tile: Tile,
    s: Settings,
    init: Option<&Mask>,
    ctx: Option<&Context>,
    vulkan: VulkanOptions,
) -> Result<Run> {
    let options = match ctx {
        Some(c) => {
            RunOptions::default().backend(BackendChoice::Vulkan).context(Some(c.clone())).vulkan(vulkan)
        }
        None => RunOptions::default().backend(BackendChoice::Cpu),
    };
    Run::start(tile, s, init, options)
}

/// Runs to iteration `to`; the samples then.
fn samples_at(run: &mut Run, to: u32) -> Result<Vec<f32>> {
    run.advance(to, &CancelFlag::new(), &mut |_| {})?;
    run.backend().samples()
}

/// Samples finite and in [0, 1): the count of those that are not.
fn out_of_range(samples: &[f32]) -> usize {
    samples.iter().filter(|v| !(v.is_finite() && (0.0..1.0).contains(*v))).count()
}

/// A long run with 20 checkpoints: every sample stays in [0, 1) and the objective
/// (fixed scoring slices) does not drift up: the last checkpoint's is within 3% of
/// the best (early checkpoints may wobble by a few percent while the step is large;
/// the largest such rise is reported).
fn long_run(
    group: &'static str,
    iterations: u32,
    mut step: impl FnMut(u32) -> Result<Vec<f32>>,
    tile: Tile,
    kernel: KernelSpec,
) -> Result<Check> {
    let start = Instant::now();
    let mut bad = 0usize;
    let mut best = f64::INFINITY;
    let mut worst_rise = 0.0f64;
    let mut objectives = Vec::new();
    for k in 1..=20u32 {
        let samples = step(iterations * k / 20)?;
        bad += out_of_range(&samples);
        let o = score(&Mask { tile, samples, meta: vec![] }, kernel, 4096);
        let ratio = o.ratio();
        if !ratio.is_finite() {
            bad += 1;
        }
        worst_rise = worst_rise.max(ratio / best - 1.0);
        best = best.min(ratio);
        objectives.push(ratio);
    }
    let first = objectives[0];
    let last = objectives[objectives.len() - 1];
    Ok(Check {
        group,
        name: format!("{iterations} iterations, {}, taa", tile.describe()),
        figure: format!(
            "{bad} samples out of [0,1) or non-finite; objective {first:.4} -> {last:.4} x white; largest rise over the best so far {:.2}%",
            100.0 * worst_rise
        ),
        bound: "0 bad samples; final objective within 3% of the best checkpoint".into(),
        passed: Some(bad == 0 && last <= 1.03 * best),
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// Sums `n` contributions of about 1e-3 into one accumulator: the CPU path's
/// fixed-point accumulator against an exact sum (f64 pairs summed in order with
/// Neumaier compensation).
fn accumulate_cpu(n: u32) -> Check {
    let start = Instant::now();
    let mut rng = Stream::new(derive(0xacc, n));
    let values: Vec<f64> = (0..n).map(|_| (rng.next_f64() * 2.0 - 1.0) * 1e-3).collect();
    let acc = Accumulator::new(1);
    values.par_iter().for_each(|&v| acc.add(0, v));
    let got = acc.take(0);
    let exact = neumaier(&values);
    let naive_f32 = values.iter().fold(0.0f32, |s, &v| s + v as f32) as f64;
    let bound = n as f64 * 0.5 / FIXED_SCALE;
    let err = (got - exact).abs();
    Check {
        group: "accumulation",
        name: format!("{n} contributions into one value, CPU fixed point"),
        figure: format!("error {err:.2e} (a float32 running sum: {:.2e})", (naive_f32 - exact).abs()),
        bound: format!("n x 2^-41 = {bound:.2e}"),
        passed: Some(err <= bound),
        seconds: start.elapsed().as_secs_f64(),
    }
}

fn neumaier(values: &[f64]) -> f64 {
    let (mut sum, mut c) = (0.0f64, 0.0f64);
    for &v in values {
        let t = sum + v;
        c += if sum.abs() >= v.abs() { (sum - t) + v } else { (v - t) + sum };
        sum = t;
    }
    sum + c
}

/// The same on the GPU through the benchmarked scatter kernel, every contribution
/// aimed at accumulator 0. Float atomics are shown beside it: each add rounds to
/// the running sum's precision, which is why the optimizer clears its
/// accumulators every iteration (about 16 adds each) and `--deterministic` uses
/// fixed point.
fn accumulate_gpu(ctx: &Context, n: u32) -> Result<Check> {
    let start = Instant::now();
    let r = crate::bench::scatter::scatter_into_one(ctx, n)?;
    let bound = n as f64 * 0.5 / FIXED_SCALE;
    let float = match r.float_error {
        Some(e) => format!(" (float atomics, for comparison: {e:.2e})"),
        None => String::new(),
    };
    Ok(Check {
        group: "accumulation",
        name: format!("{n} contributions into one value, GPU fixed point (int64 atomics)"),
        figure: format!("error {:.2e}{float}", r.fixed_error),
        bound: format!("n x 2^-41 = {bound:.2e}"),
        passed: Some(r.fixed_error <= bound),
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// A few iterations under an extreme setting or shape, on the CPU path and the GPU
/// (every d): samples stay in [0, 1) and finite, and the
/// objective does not get worse.
fn extreme(
    name: &str,
    tile: Tile,
    kernel: KernelSpec,
    iterations: u32,
    ctx: Option<&Context>,
    init: Option<&Mask>,
) -> Result<Vec<Check>> {
    let s = settings(kernel, iterations, 9);
    let start_mask = init.cloned().unwrap_or_else(|| Mask::white(tile, 9));
    let before = score(&start_mask, kernel, 2048).objective;
    let mut out = Vec::new();
    let mut judge = |backend: &str, samples: Vec<f32>, seconds: f64| {
        let bad = out_of_range(&samples);
        let after = score(&Mask { tile, samples, meta: vec![] }, kernel, 2048).objective;
        let ok = bad == 0 && after.is_finite() && after <= before * 1.001 + 1e-12;
        out.push(Check {
            group: "extremes",
            name: format!("{name} ({}), {backend}", tile.describe()),
            figure: format!("{bad} bad samples; objective {before:.3e} -> {after:.3e}"),
            bound: "0 bad samples; objective not worse".into(),
            passed: Some(ok),
            seconds,
        });
    };
    for (backend, ctx) in [("cpu", None), ("vulkan", ctx)] {
        if backend == "vulkan" && ctx.is_none() {
            continue;
        }
        let t = Instant::now();
        let mut run = start(tile, s, Some(&start_mask), ctx, VulkanOptions::default())?;
        let samples = samples_at(&mut run, s.iterations)?;
        judge(backend, samples, t.elapsed().as_secs_f64());
    }
    Ok(out)
}

/// Runs the suite; `ctx`: the Vulkan device for the GPU checks (None: CPU only).
pub fn run_stress(
    size: StressSize,
    ctx: Option<&Context>,
    log: &mut dyn FnMut(&Check),
) -> Result<Vec<Check>> {
    let mut checks = Vec::new();
    let mut push = |c: Check| {
        log(&c);
        checks.push(c);
    };
    let taa = spec("taa", 2.1, 0.1)?;
    for c in long_runs(size, ctx, taa)? {
        push(c);
    }
    if let Some(ctx) = ctx {
        for c in float32_against_float64(ctx)? {
            push(c);
        }
    }
    push(accumulate_cpu(size.accumulate));
    if let Some(ctx) = ctx {
        push(accumulate_gpu(ctx, size.accumulate)?);
    }
    for c in extremes(size, ctx, taa)? {
        push(c);
    }
    if let Some(ctx) = ctx {
        push(larger_than_a_binding(ctx, taa)?);
    }
    for c in determinism(ctx, taa)? {
        push(c);
    }
    Ok(checks)
}

/// Long runs on each backend.
fn long_runs(size: StressSize, ctx: Option<&Context>, taa: KernelSpec) -> Result<Vec<Check>> {
    let tile = Tile::new(8, 8, 4, 1, 2)?;
    let mut out = Vec::new();
    let mut run = start(tile, settings(taa, size.long_cpu, 1), None, None, VulkanOptions::default())?;
    out.push(long_run("long run, cpu", size.long_cpu, |to| samples_at(&mut run, to), tile, taa)?);
    if let Some(ctx) = ctx {
        let mut g = start(tile, settings(taa, size.long_gpu, 1), None, Some(ctx), VulkanOptions::default())?;
        out.push(long_run("long run, vulkan", size.long_gpu, |to| samples_at(&mut g, to), tile, taa)?);
    }
    Ok(out)
}

/// Float32 GPU displacements against the f64 CPU transport on the same slices.
fn float32_against_float64(ctx: &Context) -> Result<Vec<Check>> {
    let mut out = Vec::new();
    for (kernel, tile) in [
        ("spatial", Tile::new(16, 16, 4, 1, 2)?),
        ("taa", Tile::new(16, 16, 8, 1, 2)?),
        ("perceptual-taa", Tile::new(16, 16, 8, 2, 2)?),
        ("taa", Tile::new(32, 32, 8, 1, 1)?),
    ] {
        let start_time = Instant::now();
        let mask = Mask::white(tile, 21);
        let mut s = settings(spec(kernel, 2.1, 0.1)?, 10, 21);
        s.slices = Some(400);
        let mut g = start(tile, s, Some(&mask), Some(ctx), VulkanOptions::default())?;
        let mut diffs = Vec::new();
        for iteration in [0u32, 7] {
            let gpu = g.backend_mut().displacements(iteration)?;
            let cpu = reference_displacements(&mask, &s, 400, iteration);
            diffs.extend(gpu.iter().zip(&cpu).map(|(a, b)| (a - b).abs()));
        }
        diffs.sort_by(|a, b| a.total_cmp(b));
        let beyond = diffs.iter().filter(|&&d| d > 1e-5).count();
        let p999 = diffs[(diffs.len() * 999 / 1000).min(diffs.len() - 1)];
        let worst = diffs[diffs.len() - 1];
        out.push(Check {
            group: "float32 GPU vs float64 CPU",
            name: format!("{kernel}, {}, 400 slices, 2 iterations", tile.describe()),
            figure: format!(
                "{beyond} of {} coordinates beyond 1e-5{}; largest {worst:.1e}; 99.9th percentile {p999:.1e}",
                diffs.len(),
                if beyond > 0 {
                    " (near-ties of two projections ranked the other way in float32)"
                } else {
                    ""
                }
            ),
            bound: "99.9% within 1e-5; rank swaps (<= 0.1%) within 1e-2".into(),
            passed: Some(p999 <= 1e-5 && worst <= 1e-2),
            seconds: start_time.elapsed().as_secs_f64(),
        });
    }
    Ok(out)
}

/// Extreme settings and shapes; ties: every sample at the same value (every sort
/// key ties), and the float extremes of [0, 1).
fn extremes(size: StressSize, ctx: Option<&Context>, taa: KernelSpec) -> Result<Vec<Check>> {
    let n = size.extreme;
    let cases: Vec<(&str, Tile, KernelSpec)> = vec![
        ("sigma 0.25", Tile::new(16, 16, 4, 1, 2)?, spec("taa", 0.25, 0.1)?),
        ("sigma 12", Tile::new(32, 32, 2, 1, 2)?, spec("gaussian", 12.0, 0.1)?),
        ("alpha 0.001", Tile::new(16, 16, 8, 1, 2)?, spec("taa", 2.1, 0.001)?),
        ("alpha 1", Tile::new(16, 16, 8, 1, 2)?, spec("taa", 2.1, 1.0)?),
        ("alpha 0.999, perceptual-taa", Tile::new(16, 16, 8, 1, 2)?, spec("perceptual-taa", 2.1, 0.999)?),
        ("d = 8", Tile::new(8, 8, 4, 1, 8)?, taa),
        ("T = 1", Tile::new(16, 16, 1, 1, 2)?, taa),
        ("W = H = 1", Tile::new(1, 1, 8, 1, 2)?, taa),
        ("W = H = 2", Tile::new(2, 2, 8, 1, 2)?, taa),
        ("W = 3, H = 1", Tile::new(3, 1, 8, 1, 2)?, taa),
        ("1 x 1 x 1", Tile::new(1, 1, 1, 1, 1)?, taa),
        ("spp 16", Tile::new(8, 8, 4, 16, 2)?, taa),
    ];
    let mut out = Vec::new();
    for (name, tile, kernel) in cases {
        out.extend(extreme(name, tile, kernel, n, ctx, None)?);
    }
    let tile = Tile::new(8, 8, 4, 1, 2)?;
    let below_one = f32::from_bits(1.0f32.to_bits() - 1);
    for (name, value) in
        [("every sample 0.5", 0.5f32), ("every sample 0", 0.0), ("every sample 1 - ulp", below_one)]
    {
        let mask = Mask { tile, samples: vec![value; tile.values()], meta: vec![] };
        out.extend(extreme(name, tile, taa, n, ctx, Some(&mask))?);
    }
    Ok(out)
}

/// A tile whose accumulators exceed one binding (maxStorageBufferRange: 128 MiB
/// on lavapipe): a clear error before any work, not a crash or a wrong result.
fn larger_than_a_binding(ctx: &Context, taa: KernelSpec) -> Result<Check> {
    let range = ctx.info().max_storage_buffer_range;
    let start_time = Instant::now();
    if range > 512 << 20 {
        return Ok(Check {
            group: "extremes",
            name: "a tile larger than one binding".into(),
            figure: format!(
                "not tried: {} binds {} MiB, past what a tile can hold",
                ctx.info().name,
                range >> 20
            ),
            bound: "a clear error before any work".into(),
            passed: None,
            seconds: start_time.elapsed().as_secs_f64(),
        });
    }
    // 8 bytes per value (fixed-point accumulators), one value more than fits.
    let values = range / 8 + 1;
    let width = 4096u64;
    let tile = Tile::new(width as usize, values.div_ceil(width) as usize, 1, 1, 1)?;
    let options = VulkanOptions::default().deterministic(true);
    let result = start(tile, settings(taa, 1, 1), None, Some(ctx), options);
    let message = result.err().map(|e| e.to_string()).unwrap_or_default();
    Ok(Check {
        group: "extremes",
        name: format!("{} (more than one binding of {} MiB), vulkan", tile.describe(), range >> 20),
        figure: if message.is_empty() { "accepted".into() } else { format!("refused: {message}") },
        bound: "refused, naming maxStorageBufferRange".into(),
        passed: Some(message.contains("maxStorageBufferRange")),
        seconds: start_time.elapsed().as_secs_f64(),
    })
}

/// The same run, bit for bit: the CPU path across thread counts, the GPU's
/// deterministic mode across runs.
fn determinism(ctx: Option<&Context>, taa: KernelSpec) -> Result<Vec<Check>> {
    let tile = Tile::new(16, 16, 8, 2, 2)?;
    let s = settings(taa, 60, 5);
    let start_time = Instant::now();
    let mut results = Vec::new();
    for threads in [1usize, 2, 3, 8] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| Error::invalid(format!("cannot start {threads} threads: {e}")))?;
        let samples = pool.install(|| -> Result<Vec<f32>> {
            samples_at(&mut start(tile, s, None, None, VulkanOptions::default())?, s.iterations)
        })?;
        results.push(samples.iter().map(|v| v.to_bits()).collect::<Vec<u32>>());
    }
    let mut out = vec![same_check(
        format!("CPU path, {}, 60 iterations, 1 / 2 / 3 / 8 threads", tile.describe()),
        &results,
        start_time,
    )];
    if let Some(ctx) = ctx {
        let start_time = Instant::now();
        let options = VulkanOptions::default().deterministic(true);
        let mut runs = Vec::new();
        for _ in 0..3 {
            let samples = samples_at(&mut start(tile, s, None, Some(ctx), options)?, s.iterations)?;
            runs.push(samples.iter().map(|v| v.to_bits()).collect::<Vec<u32>>());
        }
        out.push(same_check(
            format!("GPU deterministic mode, {}, 60 iterations, 3 runs", tile.describe()),
            &runs,
            start_time,
        ));
    }
    Ok(out)
}

fn same_check(name: String, results: &[Vec<u32>], start_time: Instant) -> Check {
    let same = results.windows(2).all(|w| w[0] == w[1]);
    Check {
        group: "determinism",
        name,
        figure: if same { "bit-identical".into() } else { "DIFFERENT".into() },
        bound: "bit-identical".into(),
        passed: Some(same),
        seconds: start_time.elapsed().as_secs_f64(),
    }
}

/// The checks as a Markdown table.
pub fn to_markdown(checks: &[Check], machine: &str) -> String {
    let mut s = format!(
        "Machine: {machine}\n\n| group | check | figure | bound | held | s |\n| --- | --- | --- | --- | --- | ---: |\n"
    );
    for c in checks {
        s += &format!(
            "| {} | {} | {} | {} | {} | {:.2} |\n",
            c.group,
            c.name,
            c.figure,
            c.bound,
            match c.passed {
                Some(true) => "yes",
                Some(false) => "**NO**",
                None => "not tried",
            },
            c.seconds
        );
    }
    s
}
