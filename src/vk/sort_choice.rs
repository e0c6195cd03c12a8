//! Choosing a radix sort's path at run time. The decoupled look-back path
//! (`SortPath::LookBack`) needs a device on which a started workgroup goes on
//! running while another waits on it, which Vulkan does not promise: NVIDIA's
//! and AMD's GPUs do (`DeviceInfo::keeps_workgroups_running`); Apple's and
//! mobile GPUs and CPU implementations with several threads (lavapipe) do not
//! promise it, and are never given it (on lavapipe a wait can also run past its
//! cap on loop iterations, which cuts it short silently). Where it may run,
//! whether it beats the block passes depends on the device and the size, so the
//! two are timed on the device itself, with timestamp queries, on pairs of the
//! size to be sorted, and the faster is kept. Both sort stably: the choice
//! changes how long a sort takes, never its result.

use super::buffer::{Buffer, Location};
use super::commands::{barrier, copy};
use super::context::Context;
use super::error::Result;
use super::sort::{RadixSort, SortCount, SortPath};
use super::timer::Timer;

/// Timed sorts per path, alternating, after one untimed sort of each; the
/// fastest of each path counts.
const ROUNDS: u32 = 3;

/// One sort of the same pairs by each path, GPU time from timestamps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathTimes {
    /// Pairs sorted, by their low `bits` bits.
    pub n: u32,
    /// The key bits sorted by.
    pub bits: u32,
    /// `SortPath::Auto` without the look-back path: one workgroup per pass, the
    /// histogram's tail scan or the block passes, by size.
    pub blocks_ms: f64,
    /// The decoupled look-back path.
    pub look_back_ms: f64,
}

impl PathTimes {
    /// The faster path (the block passes on a tie).
    pub fn faster(&self) -> SortPath {
        if self.look_back_ms < self.blocks_ms {
            SortPath::LookBack
        } else {
            SortPath::Auto
        }
    }
}

/// A sort path and how it was chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathChoice {
    /// The path.
    pub path: SortPath,
    /// The times it was chosen by; None where nothing was timed (a CPU
    /// implementation, a device without timestamps, or a path the caller set).
    pub times: Option<PathTimes>,
}

impl PathChoice {
    /// A path the caller set, untimed.
    pub fn forced(path: SortPath) -> Self {
        Self { path, times: None }
    }

    /// In words, for logs.
    pub fn describe(&self) -> String {
        let name = match self.path {
            SortPath::LookBack => "look-back",
            SortPath::Lanes => "lanes",
            _ => "block passes",
        };
        match self.times {
            Some(t) => format!(
                "{name} (timed here on {} pairs by {} bits: look-back {:.3} ms, block passes {:.3} ms)",
                t.n, t.bits, t.look_back_ms, t.blocks_ms
            ),
            None => format!("{name} (set, not timed)"),
        }
    }
}

/// The path for sorts of about `n` pairs by their low `bits` bits on `ctx`'s
/// device: the faster of the look-back path and the block passes, timed here
/// (`time_sort_paths`), on GPUs that keep started workgroups running and have
/// timestamps; `SortPath::Auto`, untimed, elsewhere (the lanes path on a CPU
/// implementation).
pub fn choose_sort_path(ctx: &Context, n: u32, bits: u32) -> Result<PathChoice> {
    let info = ctx.info();
    if !info.keeps_workgroups_running() || info.timestamp_period_ns <= 0.0 {
        return Ok(PathChoice { path: SortPath::Auto, times: None });
    }
    let times = time_sort_paths(ctx, n, bits)?;
    Ok(PathChoice { path: times.faster(), times: Some(times) })
}

/// Times a sort of the same `n` (at least 1) pseudo-random pairs by their low
/// `bits` bits by each path, in a sort of its own (the input restored before
/// each, outside the timed span). The caller makes sure the device may run the
/// look-back path (on lavapipe: one thread, `LP_NUM_THREADS=1`).
pub fn time_sort_paths(ctx: &Context, n: u32, bits: u32) -> Result<PathTimes> {
    let n = n.max(1);
    let bits = bits.clamp(1, 32);
    let mut sort = RadixSort::new(ctx, n, SortCount::Host)?;
    sort.set_count(n)?;
    // Hashed indices: keys spread over every digit, the same on every run.
    let keys: Vec<u32> = (0..n).map(spread).collect();
    let vals: Vec<u32> = (0..n).collect();
    let pristine_keys = Buffer::with_data(ctx, &keys, Location::Device, "sort-choice-keys")?;
    let pristine_vals = Buffer::with_data(ctx, &vals, Location::Device, "sort-choice-vals")?;
    let bytes = n as u64 * 4;
    let timer = Timer::new(ctx, 2)?;
    let mut best = [f64::INFINITY; 2];
    for round in 0..=ROUNDS {
        for (i, path) in [SortPath::Auto, SortPath::LookBack].into_iter().enumerate() {
            sort.path = path;
            ctx.submit(|cmd| {
                timer.reset(cmd);
                copy(cmd, &pristine_keys, &sort.keys[0], bytes, 0);
                copy(cmd, &pristine_vals, &sort.vals[0], bytes, 0);
                barrier(cmd);
                timer.stamp(cmd, 0);
                // SAFETY: the sort outlives this submission, which is waited for.
                unsafe { sort.record(cmd, bits, Some(n)) };
                timer.stamp(cmd, 1);
            })?;
            let ns = timer.read_ns(2)?;
            if round > 0 {
                best[i] = best[i].min((ns[1] - ns[0]) * 1e-6);
            }
        }
    }
    Ok(PathTimes { n, bits, blocks_ms: best[0], look_back_ms: best[1] })
}

/// Keys spread over all 32 bits, as a hash of the index spreads them (an odd
/// multiply, a xor-shift, another odd multiply).
fn spread(i: u32) -> u32 {
    let x = i.wrapping_mul(0x9e37_79b9);
    (x ^ (x >> 15)).wrapping_mul(0x2c1b_3c6d)
}
