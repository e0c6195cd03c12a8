//! The gradient scatter on its own: `n` contributions added into `n / 16`
//! accumulators at random indices (the shape of the optimizer's scatter, where each
//! sample receives a contribution from many slices), on the GPU with the transport
//! passes' helper (`glsl/fsot/scatter_add.comp`) in fixed point and, where the
//! device has them, float atomics; on the CPU with the CPU path's accumulator.
//! Every result is checked against a sum in f64.

use std::time::Instant;

use rayon::prelude::*;

use super::timing::median;
use fsot::core::rng::{derive, Stream};
use fsot::error::{Error, Result};
use fsot::optimize::cpu::{Accumulator, FIXED_SCALE};
use fsot::optimize::vulkan::layout::{binding, ScatterPush};
use fsot::optimize::vulkan::shaders;
use fsot::vk::commands::{barrier, zero};
use fsot::vk::{Buffer, ComputeDesc, ComputePipeline, Context, Location, Timer};

/// Contributions per accumulator.
pub const FAN_IN: u32 = 16;
const WORKGROUP: u32 = 256;

#[derive(Clone, Debug, PartialEq)]
pub struct ScatterBench {
    pub n: u32,
    pub targets: u32,
    pub device: String,
    /// Median GPU seconds of one scatter: fixed point (int64 atomics).
    pub fixed_seconds: f64,
    /// The same with float atomics, where the device has them.
    pub float_seconds: Option<f64>,
    /// Median CPU seconds (the CPU path's fixed-point accumulator, all threads).
    pub cpu_seconds: f64,
    pub cpu_threads: usize,
    /// Largest |GPU - f64 sum| over the accumulators: fixed point, float.
    pub fixed_error: f64,
    pub float_error: Option<f64>,
}

impl ScatterBench {
    /// Bytes a scatter must move at least: each contribution's index and value read
    /// once, each accumulator read and written once (8 bytes, fixed point).
    pub fn bytes(&self) -> f64 {
        self.n as f64 * 8.0 + self.targets as f64 * 16.0
    }
}

/// The contributions: uniform random accumulators, values in (-2^-10, 2^-10) like
/// the optimizer's per-slice displacements.
pub fn contributions(n: u32) -> (Vec<u32>, Vec<f32>) {
    let targets = (n / FAN_IN).max(1);
    let mut rng = Stream::new(derive(0x5ca7, n));
    let idx = (0..n).map(|_| rng.below(targets)).collect();
    let val = (0..n).map(|_| (rng.next_f32() * 2.0 - 1.0) * (1.0 / 1024.0)).collect();
    (idx, val)
}

/// The sums in f64, one thread (the reference).
pub fn reference_sums(idx: &[u32], val: &[f32], targets: u32) -> Vec<f64> {
    let mut sums = vec![0.0f64; targets as usize];
    for (&i, &v) in idx.iter().zip(val) {
        sums[i as usize] += v as f64;
    }
    sums
}

/// The largest difference; infinite when the lengths differ.
fn worst(a: &[f64], b: &[f64]) -> f64 {
    if a.len() != b.len() {
        return f64::INFINITY;
    }
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

/// The contributions on the device.
struct DeviceInput {
    idx: Buffer,
    val: Buffer,
    n: u32,
    targets: u32,
}

fn upload(ctx: &Context, idx: &[u32], val: &[f32], targets: u32) -> Result<DeviceInput> {
    let n = idx.len() as u32;
    let idx_buf = Buffer::with_data(ctx, idx, Location::Device, "scatter-targets")?;
    let val_buf = Buffer::with_data(ctx, val, Location::Device, "scatter-values")?;
    Ok(DeviceInput { idx: idx_buf, val: val_buf, n, targets })
}

/// Errors of `n` contributions (uniform in (-1e-3, 1e-3)) all added into one
/// accumulator, against their exact sum.
#[derive(Clone, Copy, Debug)]
pub struct OneTarget {
    pub fixed_error: f64,
    pub float_error: Option<f64>,
}

/// The stress suite's hot-spot case: every contribution into accumulator 0.
pub fn scatter_into_one(ctx: &Context, n: u32) -> Result<OneTarget> {
    if n == 0 || !ctx.info().int64_atomics {
        return Err(Error::invalid("the scatter needs contributions and 64-bit atomics"));
    }
    let mut rng = Stream::new(derive(0xacc, n));
    let val: Vec<f32> = (0..n).map(|_| (rng.next_f32() * 2.0 - 1.0) * 1e-3).collect();
    let idx = vec![0u32; n as usize];
    let exact: f64 = {
        // Summed in 2^-64 fixed point (i128): off by less than 2^-64 per value.
        let q: i128 = val.iter().map(|&v| (v as f64 * 2f64.powi(64)) as i128).sum();
        q as f64 / 2f64.powi(64)
    };
    let input = upload(ctx, &idx, &val, 1)?;
    let (_, fixed) = gpu_mode(ctx, &input, 1, false)?;
    let float = if ctx.info().float_atomic_add { Some(gpu_mode(ctx, &input, 1, true)?.1[0]) } else { None };
    Ok(OneTarget { fixed_error: (fixed[0] - exact).abs(), float_error: float.map(|f| (f - exact).abs()) })
}

/// One GPU mode: the median time of `repeats` scatters (after two warm-ups, the
/// accumulators cleared before each) and the sums of the last one.
fn gpu_mode(ctx: &Context, input: &DeviceInput, repeats: u32, float: bool) -> Result<(f64, Vec<f64>)> {
    let DeviceInput { idx, val, n, targets } = input;
    let (n, targets) = (*n, *targets);
    let spirv = if float { shaders::SCATTER_ADD_FLOAT } else { shaders::SCATTER_ADD };
    let width = if float { 4 } else { 8 };
    let acc_bytes = targets as u64 * width;
    let acc = Buffer::new(ctx, acc_bytes, Location::Device, "scatter-acc")?;
    let desc = ComputeDesc {
        spirv,
        bindings: binding::BINDINGS,
        push_bytes: std::mem::size_of::<ScatterPush>() as u32,
        spec: &[WORKGROUP],
        sets: 1,
        images: &[],
        uniforms: &[],
        texels: &binding::TEXELS,
        full_subgroups: false,
    };
    let pipeline = ComputePipeline::new(ctx, &desc)?;
    // SAFETY: the buffers outlive the pipeline, dropped at the end of this
    // function after its one submission is waited for.
    unsafe {
        pipeline.bind(
            0,
            &[(binding::SCATTER_TARGETS, idx), (binding::SCATTER_VALUES, val), (binding::ACC, &acc)],
        )?
    };
    let runs = repeats + 2;
    let timer = Timer::new(ctx, 2 * runs)?;
    let groups = n.div_ceil(WORKGROUP);
    let push = ScatterPush { count: n };
    ctx.submit(|cmd| {
        timer.reset(cmd);
        for r in 0..runs {
            zero(cmd, &acc, 0, acc_bytes);
            barrier(cmd);
            timer.stamp(cmd, 2 * r);
            pipeline.dispatch(cmd, 0, [groups, 1, 1], bytemuck::bytes_of(&push));
            barrier(cmd);
            timer.stamp(cmd, 2 * r + 1);
        }
    })?;
    let ns = timer.read_ns(2 * runs)?;
    let seconds = median((2..runs as usize).map(|r| (ns[2 * r + 1] - ns[2 * r]) * 1e-9).collect());
    let sums = if float {
        acc.download::<f32>(targets as usize)?.into_iter().map(f64::from).collect()
    } else {
        acc.download::<i64>(targets as usize)?.into_iter().map(|q| q as f64 / FIXED_SCALE).collect()
    };
    Ok((seconds, sums))
}

/// Scatters `n` contributions `repeats` times on the GPU (each mode) and on the
/// CPU; errors if a result strays from the f64 sums by more than the stated bounds
/// (fixed point: half a unit of 2^-40 per contribution, the only rounding; float:
/// 2^-20, far above the float rounding of sums of a few dozen values below 2^-10,
/// so it only catches lost or doubled contributions).
pub fn bench_scatter(ctx: &Context, n: u32, repeats: u32) -> Result<ScatterBench> {
    if n == 0 || repeats == 0 {
        return Err(Error::invalid("the scatter needs at least one contribution and one repeat"));
    }
    if !ctx.info().int64_atomics {
        return Err(Error::invalid(format!("{} has no 64-bit atomics", ctx.info().name)));
    }
    let targets = (n / FAN_IN).max(1);
    let (idx, val) = contributions(n);
    let reference = reference_sums(&idx, &val, targets);
    let input = upload(ctx, &idx, &val, targets)?;
    let (fixed_seconds, fixed_sums) = gpu_mode(ctx, &input, repeats, false)?;
    let fixed_error = worst(&fixed_sums, &reference);
    let float = if ctx.info().float_atomic_add {
        let (s, sums) = gpu_mode(ctx, &input, repeats, true)?;
        Some((s, worst(&sums, &reference)))
    } else {
        None
    };
    // Each contribution is rounded to a multiple of 2^-40 once; integer sums are exact.
    let max_fan_in = {
        let mut count = vec![0u32; targets as usize];
        idx.iter().for_each(|&i| count[i as usize] += 1);
        count.into_iter().max().unwrap_or(0) as f64
    };
    let fixed_bound = max_fan_in * 0.5 / FIXED_SCALE;
    if fixed_error > fixed_bound {
        return Err(Error::invalid(format!(
            "the GPU's fixed-point scatter is off by {fixed_error:e} (bound {fixed_bound:e})"
        )));
    }
    if let Some((_, e)) = float {
        if e > 1.0 / (1u64 << 20) as f64 {
            return Err(Error::invalid(format!("the GPU's float scatter is off by {e:e}")));
        }
    }
    // The CPU path's accumulator: contributions in parallel chunks, a lane per thread.
    let cpu_acc = Accumulator::new(targets as usize);
    let mut cpu_times = Vec::new();
    let mut cpu_sums = Vec::new();
    for _ in 0..3 {
        let start = Instant::now();
        idx.par_chunks(1 << 14).zip(val.par_chunks(1 << 14)).for_each(|(i, v)| {
            for (&i, &v) in i.iter().zip(v) {
                cpu_acc.add(i as usize, v as f64);
            }
        });
        cpu_times.push(start.elapsed().as_secs_f64());
        cpu_sums = (0..targets as usize).map(|t| cpu_acc.take(t)).collect();
    }
    let cpu_error = worst(&cpu_sums, &reference);
    if cpu_error > fixed_bound {
        return Err(Error::invalid(format!("the CPU scatter is off by {cpu_error:e}")));
    }
    Ok(ScatterBench {
        n,
        targets,
        device: format!("{} ({})", ctx.info().name, ctx.info().driver),
        fixed_seconds,
        float_seconds: float.map(|f| f.0),
        cpu_seconds: median(cpu_times),
        cpu_threads: rayon::current_num_threads(),
        fixed_error,
        float_error: float.map(|f| f.1),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn contributions_have_the_benchmarked_shape() {
        let (idx, val) = contributions(1 << 12);
        assert_eq!(idx.len(), 1 << 12);
        assert!(idx.iter().all(|&i| i < (1 << 12) / FAN_IN));
        assert!(val.iter().all(|v| v.abs() < 1.0 / 1024.0));
        // Every accumulator is hit, FAN_IN times on average, none far more often.
        let mut hits = vec![0u32; (1 << 12) / FAN_IN as usize];
        for &i in &idx {
            hits[i as usize] += 1;
        }
        assert!(hits.iter().all(|&h| h > 0 && h < 4 * FAN_IN), "{hits:?}");
    }
}
