//! Swap search over a mask's values under a pairwise energy: the engine of the
//! peers' vector STBN (simulated annealing, Wolfe et al. 2022 after Georgiev and
//! Fajardo 2016) and of FAST (greedy swaps, Donnelly et al. 2024).
//!
//! The energy sums, over ordered pairs of pixels (p, r) at a folded offset o of
//! the wrapping tile, a weight w(o) times a term of the two values:
//!
//!   E = sum_p sum_o w(o) phi(x_p, x_{p+o}).
//!
//! The offsets are symmetric (w(o) = w(-o)), so swapping the values of p and q
//! changes E by twice the change of the pairs that touch p or q, and costs
//! O(offsets). Each pass proposes as many swaps as there are pixels, in batches
//! whose deltas are computed in parallel from the state at the batch's start and
//! then applied in order; a proposal that reads a value an earlier accepted swap
//! of the batch changed is evaluated again at its turn. So the search is exact
//! (every delta is the true one) and gives what a sequential search gives, a
//! pure function of the seed, whatever the thread count.
//!
//! This module holds the energy, the schedule and the report both searches
//! share; `cpu` is the search on the CPU cores, `vulkan` the same search in
//! compute passes.

use rayon::prelude::*;

use crate::core::rng::{derive, Stream};
use crate::core::tile::Tile;
use crate::error::{Error, Result};
use crate::optimize::backend::BackendChoice;
#[cfg(feature = "vulkan")]
use crate::optimize::run::has_context;
use crate::optimize::run::RunOptions;

pub(crate) mod cpu;
#[cfg(feature = "vulkan")]
pub mod vulkan;

pub use cpu::swap_search;

/// The term of two values in the energy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ValueTerm {
    /// exp(-|a - b|^(d/2) / sigma^2), Georgiev and Fajardo's sample term (STBN
    /// uses it with sigma 1): pairs of close pixels with close values cost most.
    Gaussian { sigma: f64 },
    /// -|a - b| (Euclidean): FAST's term; weighted by the filter's
    /// autocorrelation, minimising it spreads close pixels' values apart.
    NegDistance,
}

/// A weight at an offset of the wrapping tile, each component in [0, size).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Offset {
    pub dx: usize,
    pub dy: usize,
    pub dt: usize,
    pub weight: f64,
}

/// A pairwise energy on a tile of scalar or vector values (1 spp).
pub struct PairEnergy {
    tile: Tile,
    offsets: Vec<Offset>,
    term: ValueTerm,
    /// For each offset of the tile (as a pixel index): whether it is one of
    /// `offsets` or zero, i.e. whether a pixel's energy reads the pixel there.
    reach: Vec<bool>,
}

impl PairEnergy {
    /// Folds the offsets onto the tile (any integers), merges those that land
    /// on the same offset, and drops the zero offset (a pixel with itself).
    /// The weights must be symmetric: w(o) = w(-o) after folding.
    pub fn new(tile: Tile, offsets: &[(i64, i64, i64, f64)], term: ValueTerm) -> Result<Self> {
        if tile.spp != 1 {
            return Err(Error::invalid(format!("swap methods make 1 spp masks; got {}", tile.describe())));
        }
        let (w, h, t) = (tile.width as i64, tile.height as i64, tile.frames as i64);
        let mut folded = std::collections::BTreeMap::<(usize, usize, usize), f64>::new();
        for &(dx, dy, dt, weight) in offsets {
            if !weight.is_finite() {
                return Err(Error::invalid("an energy weight is not finite"));
            }
            let key = (dx.rem_euclid(w) as usize, dy.rem_euclid(h) as usize, dt.rem_euclid(t) as usize);
            if key != (0, 0, 0) && weight != 0.0 {
                *folded.entry(key).or_insert(0.0) += weight;
            }
        }
        let fold = |v: usize, n: usize| (n - v) % n;
        for (&(dx, dy, dt), &weight) in &folded {
            let mirror = folded.get(&(fold(dx, tile.width), fold(dy, tile.height), fold(dt, tile.frames)));
            if mirror.is_none_or(|m| (m - weight).abs() > 1e-9 * weight.abs().max(1e-300)) {
                return Err(Error::invalid("the energy's weights are not symmetric"));
            }
        }
        let mut offsets: Vec<Offset> =
            folded.into_iter().map(|((dx, dy, dt), weight)| Offset { dx, dy, dt, weight }).collect();
        // In memory order, so a delta walks each row of neighbours in one sweep.
        offsets.sort_by_key(|o| (o.dt, o.dy, o.dx));
        let mut reach = vec![false; tile.pixels()];
        reach[0] = true;
        for o in &offsets {
            reach[(o.dt * tile.height + o.dy) * tile.width + o.dx] = true;
        }
        Ok(Self { tile, offsets, term, reach })
    }

    pub fn offsets(&self) -> &[Offset] {
        &self.offsets
    }
    pub fn tile(&self) -> &Tile {
        &self.tile
    }
    pub fn term(&self) -> ValueTerm {
        self.term
    }

    /// Proposals per batch at acceptance rate `acceptance`: about one in twenty
    /// taken swaps then reads a value an earlier one of its batch moved (a
    /// taken swap makes (2 x offsets + 2) / pixels of the tile stale).
    pub(crate) fn batch_for(&self, acceptance: f64) -> usize {
        let footprint = ((2 * self.offsets.len() + 2) as f64 / self.tile.pixels() as f64).min(1.0);
        (0.05 / (acceptance * footprint)) as usize
    }

    /// (x, y, frame) of pixel p.
    #[inline]
    fn coords(&self, p: usize) -> (usize, usize, usize) {
        let (w, h) = (self.tile.width, self.tile.height);
        (p % w, (p / w) % h, p / (w * h))
    }

    /// The pixel at offset o from the pixel at (x, y, f).
    #[inline]
    fn neighbour(&self, (x, y, f): (usize, usize, usize), o: &Offset) -> usize {
        let (w, h, t) = (self.tile.width, self.tile.height, self.tile.frames);
        let wrap = |v: usize, n: usize| if v >= n { v - n } else { v };
        (wrap(f + o.dt, t) * h + wrap(y + o.dy, h)) * w + wrap(x + o.dx, w)
    }

    /// Whether the energy terms of pixel a read the value of pixel b.
    #[inline]
    fn reaches(&self, a: (usize, usize, usize), b: (usize, usize, usize)) -> bool {
        let (w, h, t) = (self.tile.width, self.tile.height, self.tile.frames);
        let back = |u: usize, v: usize, n: usize| if v >= u { v - u } else { v + n - u };
        self.reach[(back(a.2, b.2, t) * h + back(a.1, b.1, h)) * w + back(a.0, b.0, w)]
    }

    #[inline]
    fn phi(&self, a: &[f32], b: &[f32]) -> f64 {
        if let ([u], [v]) = (a, b) {
            // Scalar values: |a - b| without a square root.
            let r = (*u as f64 - *v as f64).abs();
            return match self.term {
                ValueTerm::Gaussian { sigma } => (-r.sqrt() / (sigma * sigma)).exp(),
                ValueTerm::NegDistance => -r,
            };
        }
        let d2: f64 = a.iter().zip(b).map(|(&u, &v)| (u as f64 - v as f64).powi(2)).sum();
        match self.term {
            // |a - b|^(d/2) = (|a - b|^2)^(d/4)
            ValueTerm::Gaussian { sigma } => {
                let r = match a.len() {
                    2 => d2.sqrt(),
                    4 => d2,
                    d => d2.powf(d as f64 / 4.0),
                };
                (-r / (sigma * sigma)).exp()
            }
            ValueTerm::NegDistance => -d2.sqrt(),
        }
    }

    /// The energy summed pair by pair (what the searches track incrementally),
    /// in chunks of pixels of a fixed size added in order: the same sum whatever
    /// the thread count.
    pub fn total(&self, values: &[f32]) -> f64 {
        const CHUNK: usize = 4096;
        let d = self.tile.dims;
        let pixel = |p: usize| {
            let a = &values[p * d..p * d + d];
            let at = self.coords(p);
            self.offsets
                .iter()
                .map(|o| {
                    let r = self.neighbour(at, o);
                    o.weight * self.phi(a, &values[r * d..r * d + d])
                })
                .sum::<f64>()
        };
        let n = self.tile.pixels();
        let chunks: Vec<f64> = (0..n.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| (c * CHUNK..((c + 1) * CHUNK).min(n)).map(pixel).sum::<f64>())
            .collect();
        chunks.iter().sum()
    }

    /// The change of the energy if the values of p and q (p != q) were swapped.
    pub fn swap_delta(&self, values: &[f32], p: usize, q: usize) -> f64 {
        let d = self.tile.dims;
        let (a, b) = (&values[p * d..p * d + d], &values[q * d..q * d + d]);
        let (at_p, at_q) = (self.coords(p), self.coords(q));
        let mut delta = 0.0;
        for o in &self.offsets {
            let r = self.neighbour(at_p, o);
            if r != q {
                let c = &values[r * d..r * d + d];
                delta += o.weight * (self.phi(b, c) - self.phi(a, c));
            }
            let r = self.neighbour(at_q, o);
            if r != p {
                let c = &values[r * d..r * d + d];
                delta += o.weight * (self.phi(a, c) - self.phi(b, c));
            }
        }
        2.0 * delta
    }
}

/// How long to search and how to accept.
#[derive(Clone, Copy, Debug)]
pub struct Schedule {
    /// Passes of as many proposals as pixels.
    pub passes: u32,
    /// Starting temperature as a fraction of the mean |delta| of random
    /// proposals on the starting values; 0 is a greedy search (only improving
    /// swaps).
    pub start_temperature: f64,
    /// Share of the passes, at the end, run greedily (temperature 0).
    pub greedy_share: f64,
}

impl Schedule {
    pub fn greedy(passes: u32) -> Self {
        Self { passes, start_temperature: 0.0, greedy_share: 1.0 }
    }

    /// The temperature of pass `pass`, from the starting one.
    pub(crate) fn temperature(&self, t0: f64, pass: u32) -> f64 {
        let annealed = (self.passes as f64 * (1.0 - self.greedy_share)).floor();
        if annealed <= 0.0 || pass as f64 >= annealed {
            return 0.0;
        }
        t0 * (1.0 - pass as f64 / annealed).powi(2)
    }
}

/// What a search did.
#[derive(Clone, Debug, Default)]
pub struct SwapReport {
    /// Offsets (neighbours) per pixel in the energy.
    pub offsets: usize,
    pub start_energy: f64,
    /// The energy after each pass (start energy plus the accepted deltas).
    pub trace: Vec<f64>,
    pub proposed: u64,
    pub accepted: u64,
    /// Accepted swaps that raised the energy (annealing at temperature > 0).
    pub uphill: u64,
    /// Proposals whose delta was computed again because an earlier swap of
    /// their batch changed a value it read (the CPU path).
    pub recomputed: u64,
    /// Proposals taken on their batch's starting values but dropped because an
    /// earlier taken swap of the batch moved a value they read (Vulkan).
    pub dropped: u64,
}

impl SwapReport {
    /// What the search did on `device`, in a line.
    pub fn describe(&self, device: &SwapDevice) -> String {
        format!(
            "{} neighbours per pixel, on {}: loss {:.6e} -> {:.6e}, {} of {} proposed swaps taken ({} re-evaluated, {} dropped, {} uphill)",
            self.offsets,
            device.describe(),
            self.start_energy,
            self.trace.last().copied().unwrap_or(self.start_energy),
            self.accepted,
            self.proposed,
            self.recomputed,
            self.dropped,
            self.uphill
        )
    }
}

/// Where a swap search runs.
#[derive(Clone, Default)]
pub enum SwapDevice {
    /// Rayon on the CPU cores: the exact sequential search.
    #[default]
    Cpu,
    /// Compute passes on a Vulkan device (`vulkan`).
    #[cfg(feature = "vulkan")]
    Vulkan(crate::vk::Context),
}

impl SwapDevice {
    /// The device in words.
    pub fn describe(&self) -> String {
        match self {
            SwapDevice::Cpu => format!("cpu ({} threads)", rayon::current_num_threads()),
            #[cfg(feature = "vulkan")]
            SwapDevice::Vulkan(ctx) => format!("vulkan ({})", ctx.info().name),
        }
    }

    /// The kind of device, as masks record it: `cpu` or `vulkan`.
    pub fn kind(&self) -> &'static str {
        match self {
            SwapDevice::Cpu => "cpu",
            #[cfg(feature = "vulkan")]
            SwapDevice::Vulkan(_) => "vulkan",
        }
    }

    /// `swap_search` on this device.
    pub fn search(
        &self,
        energy: &PairEnergy,
        values: &mut [f32],
        schedule: Schedule,
        key: u32,
        on_pass: impl FnMut(u32, f64),
    ) -> Result<SwapReport> {
        match self {
            SwapDevice::Cpu => cpu::swap_search(energy, values, schedule, key, on_pass),
            #[cfg(feature = "vulkan")]
            SwapDevice::Vulkan(ctx) => vulkan::swap_search(ctx, energy, values, schedule, key, on_pass),
        }
    }
}

/// Where the peers' swap searches run under `options`, by the rule of a run:
/// `cpu`, `vulkan` (an error without a device), or `auto` (a GPU, or a device
/// named or handed in, else the CPU). Returns the device and the choice in words.
#[cfg(not(feature = "vulkan"))]
pub fn swap_device(options: &RunOptions) -> Result<(SwapDevice, String)> {
    match options.backend {
        BackendChoice::Vulkan => Err(crate::optimize::run::without_vulkan()),
        _ => Ok((SwapDevice::Cpu, SwapDevice::Cpu.describe())),
    }
}

/// Where the peers' swap searches run (see above).
#[cfg(feature = "vulkan")]
pub fn swap_device(options: &RunOptions) -> Result<(SwapDevice, String)> {
    let device = match options.backend {
        BackendChoice::Cpu => SwapDevice::Cpu,
        BackendChoice::Vulkan => SwapDevice::Vulkan(crate::optimize::run::context_for(options, false)?),
        BackendChoice::Auto => {
            let usable =
                crate::optimize::run::context_for(options, options.device.is_none() && !has_context(options))
                    .and_then(|ctx| match ctx.info().int64_atomics {
                        true => Ok(ctx),
                        false => Err(Error::VulkanUnavailable(format!(
                            "{} lacks 64-bit buffer atomics",
                            ctx.info().name
                        ))),
                    });
            match usable {
                Ok(ctx) => SwapDevice::Vulkan(ctx),
                Err(e) => {
                    let cpu = SwapDevice::Cpu;
                    let note = format!("{} (no Vulkan GPU used: {e})", cpu.describe());
                    return Ok((cpu, note));
                }
            }
        }
    };
    let note = device.describe();
    Ok((device, note))
}

/// Checks a search's values and starts its report (the energy summed); true
/// when there is nothing to search (fewer than two pixels, or no neighbours),
/// the trace then filled with the start energy.
pub(crate) fn start(energy: &PairEnergy, values: &[f32], schedule: Schedule) -> Result<(SwapReport, bool)> {
    let tile = energy.tile;
    if values.len() != tile.values() {
        return Err(Error::invalid("swap search: values do not match the tile"));
    }
    if values.iter().any(|v| !v.is_finite()) {
        return Err(Error::invalid("swap search: a value is not finite"));
    }
    let mut report = SwapReport {
        offsets: energy.offsets.len(),
        start_energy: energy.total(values),
        ..SwapReport::default()
    };
    let trivial = tile.pixels() < 2 || energy.offsets.is_empty();
    if trivial {
        report.trace = vec![report.start_energy; schedule.passes as usize];
    }
    Ok((report, trivial))
}

/// One random proposal (p, q, u) of a pass: two distinct pixels and the
/// uniform number that decides an uphill move.
pub(super) fn propose(rng: &mut Stream, n: usize) -> (usize, usize, f64) {
    let p = rng.below(n as u32) as usize;
    let q = (p + 1 + rng.below(n as u32 - 1) as usize) % n;
    (p, q, rng.next_f64())
}

/// Mean |delta| over 256 random proposals: the scale of the temperature.
pub(crate) fn mean_abs_delta(energy: &PairEnergy, values: &[f32], key: u32) -> f64 {
    let mut rng = Stream::new(derive(key, 0x7e3b));
    let n = energy.tile.pixels();
    let proposals: Vec<_> = (0..256).map(|_| propose(&mut rng, n)).collect();
    let deltas: Vec<f64> = proposals.par_iter().map(|&(p, q, _)| energy.swap_delta(values, p, q).abs()).collect();
    // Summed in order: the temperature, and so every decision, whatever the thread count.
    deltas.iter().sum::<f64>() / 256.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gaussian_offsets(sigma: f64) -> Vec<(i64, i64, i64, f64)> {
        let mut v = Vec::new();
        for dy in -4i64..=4 {
            for dx in -4i64..=4 {
                v.push((dx, dy, 0, (-((dx * dx + dy * dy) as f64) / (2.0 * sigma * sigma)).exp()));
            }
        }
        for dt in [-2i64, -1, 1, 2] {
            v.push((0, 0, dt, (-((dt * dt) as f64) / (2.0 * sigma * sigma)).exp()));
        }
        v
    }

    #[test]
    fn the_total_is_the_pairwise_sum_written_out() {
        // Offsets past the tile (folded), a pair landing on one offset (merged)
        // and the zero offset (dropped), against the double sum written out:
        // every pixel, every offset as given, coordinates wrapped by hand.
        let raw: Vec<(i64, i64, i64, f64)> = vec![
            (1, 0, 0, 0.5),
            (-1, 0, 0, 0.5),
            (0, 2, 1, 0.25),
            (0, -2, -1, 0.25),
            (6, 0, 0, 0.125),
            (-6, 0, 0, 0.125),
            (0, 0, 3, 2.0),
            (2, -1, -2, 0.75),
            (-2, 1, 2, 0.75),
        ];
        for (term, dims) in [
            (ValueTerm::Gaussian { sigma: 1.3 }, 1),
            (ValueTerm::Gaussian { sigma: 1.0 }, 3),
            (ValueTerm::NegDistance, 1),
            (ValueTerm::NegDistance, 2),
        ] {
            let tile = Tile::new(5, 4, 3, 1, dims).unwrap();
            let e = PairEnergy::new(tile, &raw, term).unwrap();
            let mut rng = Stream::new(5);
            let values: Vec<f32> = (0..tile.values()).map(|_| rng.next_f32()).collect();
            let (w, h, t) = (5i64, 4i64, 3i64);
            let mut want = 0.0f64;
            for f in 0..t {
                for y in 0..h {
                    for x in 0..w {
                        for &(dx, dy, dt, weight) in &raw {
                            let (nx, ny, nf) = ((x + dx).rem_euclid(w), (y + dy).rem_euclid(h), (f + dt).rem_euclid(t));
                            if (nx, ny, nf) == (x, y, f) {
                                continue; // (0, 0, 3) on 3 frames: the pixel itself
                            }
                            let at = |x: i64, y: i64, f: i64| ((f * h + y) * w + x) as usize * dims;
                            let (a, b) = (at(x, y, f), at(nx, ny, nf));
                            let distance = (0..dims)
                                .map(|k| (values[a + k] as f64 - values[b + k] as f64).powi(2))
                                .sum::<f64>()
                                .sqrt();
                            want += weight
                                * match term {
                                    ValueTerm::Gaussian { sigma } => {
                                        (-distance.powf(dims as f64 / 2.0) / (sigma * sigma)).exp()
                                    }
                                    ValueTerm::NegDistance => -distance,
                                };
                        }
                    }
                }
            }
            let got = e.total(&values);
            assert!((got - want).abs() < 1e-9 * want.abs(), "{term:?} d = {dims}: {got} against {want}");
        }
    }

    #[test]
    fn swap_delta_equals_the_change_of_the_summed_energy() {
        for (term, dims) in [(ValueTerm::Gaussian { sigma: 1.0 }, 2), (ValueTerm::NegDistance, 1)] {
            // A 5x4x3 tile is smaller than the offsets: folding and neighbour pairs.
            let tile = Tile::new(5, 4, 3, 1, dims).unwrap();
            let e = PairEnergy::new(tile, &gaussian_offsets(1.3), term).unwrap();
            let mut rng = Stream::new(11);
            let mut values: Vec<f32> = (0..tile.values()).map(|_| rng.next_f32()).collect();
            for (p, q) in [(0, 1), (0, 5), (3, 40), (59, 2), (7, 27)] {
                let before = e.total(&values);
                let delta = e.swap_delta(&values, p, q);
                for k in 0..dims {
                    values.swap(p * dims + k, q * dims + k);
                }
                let after = e.total(&values);
                assert!((after - before - delta).abs() < 1e-9 * before.abs().max(1.0), "{p} {q}");
            }
        }
    }

    #[test]
    fn batched_search_gives_what_a_sequential_search_gives() {
        // The reference: one proposal at a time, each delta from the summed
        // energy before and after (no incremental formula, no batches).
        let tile = Tile::new(6, 5, 3, 1, 1).unwrap();
        let e = PairEnergy::new(tile, &gaussian_offsets(1.0), ValueTerm::NegDistance).unwrap();
        let mut rng = Stream::new(8);
        let start: Vec<f32> = (0..tile.values()).map(|_| rng.next_f32()).collect();
        let schedule = Schedule { passes: 3, start_temperature: 0.3, greedy_share: 0.34 };
        let key = 77;
        let mut batched = start.clone();
        swap_search(&e, &mut batched, schedule, key, |_, _| {}).unwrap();
        let mut reference = start.clone();
        let t0 = 0.3 * mean_abs_delta(&e, &reference, key);
        for pass in 0..3 {
            let mut rng = Stream::new(derive(key, pass));
            let temperature = schedule.temperature(t0, pass);
            for _ in 0..tile.pixels() {
                let (p, q, u) = propose(&mut rng, tile.pixels());
                let before = e.total(&reference);
                reference.swap(p, q);
                let delta = e.total(&reference) - before;
                let accept = delta < -1e-12 || (temperature > 0.0 && u < (-delta / temperature).exp());
                if !accept {
                    reference.swap(p, q);
                }
            }
        }
        assert_eq!(batched, reference);
    }

    #[test]
    fn asymmetric_weights_are_refused() {
        let tile = Tile::new(8, 8, 2, 1, 1).unwrap();
        assert!(PairEnergy::new(tile, &[(1, 0, 0, 1.0)], ValueTerm::NegDistance).is_err());
        assert!(PairEnergy::new(tile, &[(1, 0, 0, 1.0), (-1, 0, 0, 1.0)], ValueTerm::NegDistance).is_ok());
        assert!(PairEnergy::new(Tile::new(8, 8, 2, 2, 1).unwrap(), &[], ValueTerm::NegDistance).is_err());
    }

    #[test]
    fn the_temperature_scale_and_the_total_are_the_same_sums_whatever_the_thread_count() {
        let tile = Tile::new(96, 96, 4, 1, 2).unwrap();
        let e = PairEnergy::new(tile, &gaussian_offsets(1.9), ValueTerm::Gaussian { sigma: 1.0 }).unwrap();
        let mut rng = Stream::new(11);
        let values: Vec<f32> = (0..tile.values()).map(|_| rng.next_f32()).collect();
        let with = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| (mean_abs_delta(&e, &values, 9).to_bits(), e.total(&values).to_bits()))
        };
        let one = with(1);
        for threads in [2, 3, 7] {
            assert_eq!(with(threads), one, "{threads} threads");
        }
    }

    #[test]
    fn the_tracked_energy_is_the_true_energy_and_the_search_is_deterministic() {
        let tile = Tile::new(12, 10, 4, 1, 2).unwrap();
        let e = PairEnergy::new(tile, &gaussian_offsets(1.9), ValueTerm::Gaussian { sigma: 1.0 }).unwrap();
        let mut rng = Stream::new(3);
        let start: Vec<f32> = (0..tile.values()).map(|_| rng.next_f32()).collect();
        let schedule = Schedule { passes: 6, start_temperature: 0.5, greedy_share: 0.5 };
        let mut a = start.clone();
        let report = swap_search(&e, &mut a, schedule, 5, |_, _| {}).unwrap();
        let tracked = *report.trace.last().unwrap();
        assert!((tracked - e.total(&a)).abs() < 1e-9 * tracked.abs());
        assert!(report.accepted > 0);
        assert_eq!(report.proposed, 6 * 480);
        let mut b = start.clone();
        rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| swap_search(&e, &mut b, schedule, 5, |_, _| {}).unwrap());
        assert_eq!(a, b);
        // Swaps only: the multiset of values is kept.
        let mut sa: Vec<u32> = a.iter().map(|v| v.to_bits()).collect();
        let mut ss: Vec<u32> = start.iter().map(|v| v.to_bits()).collect();
        sa.sort();
        ss.sort();
        assert_eq!(sa, ss);
    }
}
