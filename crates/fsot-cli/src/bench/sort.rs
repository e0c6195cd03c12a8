//! The GPU radix sort against the CPU sort, pairs per second.

use std::time::Instant;

use rayon::prelude::*;

use super::timing::median;
use fsot::core::rng::{derive, Stream};
use fsot::error::{Error, Result};
use fsot::vk::commands::{barrier, copy};
use fsot::vk::{Buffer, Context, Location, RadixSort, SortCount, SortPath, Timer};

#[derive(Clone, Debug, PartialEq)]
pub struct SortBench {
    pub n: u32,
    pub device: String,
    /// Median GPU time of one sort (timestamp queries), seconds.
    pub gpu_seconds: f64,
    /// Median CPU time (rayon's parallel stable sort, all cores), seconds.
    pub cpu_seconds: f64,
    pub cpu_threads: usize,
    /// One profiled sort, milliseconds summed over the 4 passes: histogram, scan
    /// (2 dispatches), scatter.
    pub stages_ms: [f64; 3],
    /// Pairs per block on this device.
    pub block: u32,
    /// Whether the sort took the lanes path (`SortPath::Lanes`: runs of
    /// `LANE_RUN` pairs an invocation, in place of blocks).
    pub lanes: bool,
    /// The passes the sort took, in words, and its dispatches.
    pub passes: &'static str,
    pub dispatches: u32,
    /// Median GPU time of copying the keys and payloads once (read and write:
    /// 16 bytes per pair), in the same submissions: the device's copy bandwidth.
    pub copy_seconds: f64,
}

impl SortBench {
    pub fn gpu_pairs_per_second(&self) -> f64 {
        self.n as f64 / self.gpu_seconds
    }
    pub fn cpu_pairs_per_second(&self) -> f64 {
        self.n as f64 / self.cpu_seconds
    }
    /// Bytes a sort must move: 4 passes, each reading and writing the keys and
    /// payloads once (16 bytes per pair).
    pub fn bytes_moved(&self) -> f64 {
        4.0 * 16.0 * self.n as f64
    }
    /// The sort's effective bandwidth, bytes per second.
    pub fn sort_bandwidth(&self) -> f64 {
        self.bytes_moved() / self.gpu_seconds
    }
    /// The copy's bandwidth (16 bytes per pair moved), bytes per second.
    pub fn copy_bandwidth(&self) -> f64 {
        16.0 * self.n as f64 / self.copy_seconds
    }
}

/// Sorts `n` random 32-bit keys with 32-bit payloads `repeats` times on the GPU
/// (after a warm-up, the same input restored before each run, by the passes
/// `path` picks) and on the CPU; checks the GPU result against the CPU's. Times
/// a plain copy of the pairs in the same submission, for the copy bandwidth.
pub fn bench_sort(ctx: &Context, n: u32, repeats: u32, path: SortPath) -> Result<SortBench> {
    if n == 0 || repeats == 0 {
        return Err(Error::invalid("the sort benchmark needs at least one pair and one repeat"));
    }
    let mut rng = Stream::new(derive(0xbe7c, n));
    let keys: Vec<u32> = (0..n).map(|_| rng.next_u32()).collect();
    let vals: Vec<u32> = (0..n).collect();
    let mut sort = RadixSort::new(ctx, n, SortCount::Host)?;
    sort.path = path;
    sort.set_count(n)?;
    let bytes = n as u64 * 4;
    let pristine_k = Buffer::with_data(ctx, &keys, Location::Device, "bench-keys")?;
    let pristine_v = Buffer::with_data(ctx, &vals, Location::Device, "bench-vals")?;
    let runs = repeats + 2;
    let timer = Timer::new(ctx, 4 * runs)?;
    ctx.submit(|cmd| {
        timer.reset(cmd);
        for r in 0..runs {
            // The restore, timed: the copy bandwidth.
            barrier(cmd);
            timer.stamp(cmd, 4 * r);
            copy(cmd, &pristine_k, sort.keys(), bytes, 0);
            copy(cmd, &pristine_v, sort.vals(), bytes, 0);
            barrier(cmd);
            timer.stamp(cmd, 4 * r + 1);
            timer.stamp(cmd, 4 * r + 2);
            // SAFETY: the sort outlives this submission, which is waited for.
            unsafe { sort.record(cmd, 32, Some(n)) };
            timer.stamp(cmd, 4 * r + 3);
        }
    })?;
    let ns = timer.read_ns(4 * runs)?;
    let span =
        |a: usize| median((2..runs as usize).map(|r| (ns[4 * r + a + 1] - ns[4 * r + a]) * 1e-9).collect());
    let (copy_seconds, gpu_seconds) = (span(0), span(2));
    // One more run with a timestamp after every dispatch, for the breakdown.
    let stages = Timer::new(ctx, 17)?;
    ctx.submit(|cmd| {
        stages.reset(cmd);
        copy(cmd, &pristine_k, sort.keys(), bytes, 0);
        copy(cmd, &pristine_v, sort.vals(), bytes, 0);
        barrier(cmd);
        sort.record_timed(cmd, 32, Some(n), Some(&stages));
    })?;
    let t = stages.read_ns(17)?;
    let mut stages_ms = [0.0f64; 3];
    for pass in 0..4usize {
        let b = 4 * pass;
        stages_ms[0] += (t[b + 1] - t[b]) * 1e-6;
        stages_ms[1] += (t[b + 3] - t[b + 1]) * 1e-6;
        stages_ms[2] += (t[b + 4] - t[b + 3]) * 1e-6;
    }
    let (passes, dispatches) = sort.passes(Some(n));
    let (block, lanes) = (sort.shape().block, sort.lanes_path());
    // Check the last run against the CPU.
    let gpu_vals: Vec<u32> = sort.vals().download(n as usize)?;
    let input: Vec<(u32, u32)> = keys.iter().copied().zip(vals.iter().copied()).collect();
    let mut pairs = Vec::new();
    let mut cpu_times = Vec::new();
    for _ in 0..3 {
        pairs = input.clone();
        let start = Instant::now();
        pairs.par_sort_by_key(|x| x.0);
        cpu_times.push(start.elapsed().as_secs_f64());
    }
    if pairs.iter().zip(&gpu_vals).any(|(c, &g)| c.1 != g) {
        return Err(Error::invalid("the GPU sort disagreed with the CPU sort"));
    }
    Ok(SortBench {
        n,
        device: format!("{} ({})", ctx.info().name, ctx.info().driver),
        gpu_seconds,
        cpu_seconds: median(cpu_times),
        cpu_threads: rayon::current_num_threads(),
        stages_ms,
        block,
        lanes,
        passes,
        dispatches,
        copy_seconds,
    })
}
