//! Spatiotemporal blue noise (Wolfe et al. 2022). Scalar masks: void-and-cluster
//! with STBN's energy, a 2-D Gaussian within each frame plus a 1-D Gaussian over
//! time at the same pixel, exp(-r^2 / (2 sigma^2)) with sigma 1.9 for both, on the
//! wrapping tile.
//!
//! The classic three phases (Ulichney 1993): an initial binary pattern (a tenth of
//! the pixels, relaxed by moving its tightest cluster into its largest void until
//! that changes nothing), then ranks below it by removing tightest clusters, then
//! ranks above it by filling largest voids. Every step updates the energy of the
//! toggled pixel's neighbourhood only; tournament trees find the extremes. Ties
//! go to the lowest pixel index, so the result is a pure function of the seed.
//!
//! Vector masks (d >= 2), as the STBN paper does after Georgiev and Fajardo
//! (2016): simulated annealing of swaps between pixels (`swap.rs`), the same
//! pixel weights times the sample term exp(-|a - b|^(d/2)).

use crate::core::rng::{derive, seed_key, Stream};
use crate::core::tile::Tile;
use crate::error::{Error, Result};
use crate::peers::fast::stratified_values;
use crate::peers::swap::{PairEnergy, Schedule, SwapDevice, SwapReport, ValueTerm};

pub const DEFAULT_SIGMA: f64 = 1.9;

/// STBN's energy kernel on a tile: spatial offsets within the frame and
/// temporal offsets at the same pixel, folded onto the wrapping tile.
struct Energy {
    spatial: Vec<(usize, usize, f64)>,
    temporal: Vec<(usize, f64)>,
}

/// STBN's energy weights as unfolded offsets (dx, dy, dt, weight): the 2-D
/// Gaussian exp(-r^2 / (2 sigma^2)) within the frame (the pixel itself included,
/// weight 1) and the 1-D Gaussian over time at the same pixel, to 3 sigma.
pub fn stbn_offsets(sigma_xy: f64, sigma_t: f64) -> Vec<(i64, i64, i64, f64)> {
    let mut out = Vec::new();
    let r = (3.0 * sigma_xy).ceil() as i64;
    for dy in -r..=r {
        for dx in -r..=r {
            out.push((dx, dy, 0, (-((dx * dx + dy * dy) as f64) / (2.0 * sigma_xy * sigma_xy)).exp()));
        }
    }
    let rt = (3.0 * sigma_t).ceil() as i64;
    for dt in (-rt..=rt).filter(|&dt| dt != 0) {
        out.push((0, 0, dt, (-((dt * dt) as f64) / (2.0 * sigma_t * sigma_t)).exp()));
    }
    out
}

impl Energy {
    fn new(tile: &Tile, sigma_xy: f64, sigma_t: f64) -> Self {
        let (w, h, t) = (tile.width as i64, tile.height as i64, tile.frames as i64);
        let mut spatial = vec![0.0f64; tile.width * tile.height];
        let mut temporal = vec![0.0f64; tile.frames];
        for (dx, dy, dt, g) in stbn_offsets(sigma_xy, sigma_t) {
            if dt == 0 {
                spatial[(dy.rem_euclid(h) * w + dx.rem_euclid(w)) as usize] += g;
            } else {
                temporal[dt.rem_euclid(t) as usize] += g;
            }
        }
        let w = tile.width;
        Self {
            spatial: spatial
                .iter()
                .enumerate()
                .filter(|(_, &g)| g > 0.0)
                .map(|(i, &g)| (i % w, i / w, g))
                .collect(),
            temporal: temporal.iter().enumerate().filter(|(_, &g)| g > 0.0).map(|(i, &g)| (i, g)).collect(),
        }
    }

    /// Adds `sign` x the kernel centred on pixel `p` to `field`.
    fn splat(&self, tile: &Tile, field: &mut [f64], p: usize, sign: f64) {
        let (w, h, t) = (tile.width, tile.height, tile.frames);
        let (x, y, f) = (p % w, (p / w) % h, p / (w * h));
        for &(dx, dy, g) in &self.spatial {
            field[(f * h + (y + dy) % h) * w + (x + dx) % w] += sign * g;
        }
        for &(dt, g) in &self.temporal {
            field[(((f + dt) % t) * h + y) * w + x] += sign * g;
        }
    }
}

/// A tournament tree over the pixels: the leaf of a pixel in the tracked state
/// holds its key, others hold +inf; each node keeps its subtree's smallest (key,
/// index). The extreme is the root; changing a leaf costs log N.
struct Tournament {
    size: usize,
    nodes: Vec<(f64, u32)>,
}

impl Tournament {
    fn new(n: usize) -> Self {
        let size = n.next_power_of_two();
        Self { size, nodes: vec![(f64::INFINITY, u32::MAX); 2 * size] }
    }

    fn set(&mut self, i: usize, key: f64) {
        let mut k = self.size + i;
        self.nodes[k] = (key, i as u32);
        while k > 1 {
            k /= 2;
            let (a, b) = (self.nodes[2 * k], self.nodes[2 * k + 1]);
            self.nodes[k] = if (b.0, b.1) < (a.0, a.1) { b } else { a };
        }
    }

    /// The smallest key's index (ties to the lowest index), if any leaf is live.
    fn best(&self) -> Option<usize> {
        let (key, i) = self.nodes[1];
        (key < f64::INFINITY).then_some(i as usize)
    }
}

/// The pattern, its energy, and the two extremes void-and-cluster needs: the
/// tightest cluster (largest energy among ones) and the largest void (smallest
/// energy among zeros).
struct Pattern<'a> {
    tile: &'a Tile,
    kernel: &'a Energy,
    on: Vec<bool>,
    energy: Vec<f64>,
    clusters: Tournament,
    voids: Tournament,
}

impl<'a> Pattern<'a> {
    fn new(tile: &'a Tile, kernel: &'a Energy, ones: &[usize]) -> Self {
        let n = tile.pixels();
        let mut on = vec![false; n];
        let mut energy = vec![0.0; n];
        for &p in ones {
            on[p] = true;
            kernel.splat(tile, &mut energy, p, 1.0);
        }
        let mut me =
            Self { tile, kernel, on, energy, clusters: Tournament::new(n), voids: Tournament::new(n) };
        for p in 0..n {
            me.refresh(p);
        }
        me
    }

    fn refresh(&mut self, p: usize) {
        let e = self.energy[p];
        if self.on[p] {
            self.clusters.set(p, -e);
            self.voids.set(p, f64::INFINITY);
        } else {
            self.clusters.set(p, f64::INFINITY);
            self.voids.set(p, e);
        }
    }

    fn toggle(&mut self, p: usize) {
        let sign = if self.on[p] { -1.0 } else { 1.0 };
        self.on[p] = !self.on[p];
        let (w, h, t) = (self.tile.width, self.tile.height, self.tile.frames);
        let (x, y, f) = (p % w, (p / w) % h, p / (w * h));
        for &(dx, dy, g) in &self.kernel.spatial {
            let q = (f * h + (y + dy) % h) * w + (x + dx) % w;
            self.energy[q] += sign * g;
            self.refresh(q);
        }
        for &(dt, g) in &self.kernel.temporal {
            let q = (((f + dt) % t) * h + y) * w + x;
            self.energy[q] += sign * g;
            self.refresh(q);
        }
        self.refresh(p);
    }
}

/// Ranks 0..N of every pixel of a scalar mask (a permutation), by void-and-cluster.
pub fn void_and_cluster(tile: &Tile, sigma_xy: f64, sigma_t: f64, seed: u64) -> Result<Vec<u32>> {
    if tile.dims != 1 || tile.spp != 1 {
        return Err(Error::invalid(format!(
            "void-and-cluster makes scalar masks (d = 1, 1 spp); got {}",
            tile.describe()
        )));
    }
    check_sigmas(sigma_xy, sigma_t)?;
    let n = tile.pixels();
    let kernel = Energy::new(tile, sigma_xy, sigma_t);
    let alone = kernel.spatial.iter().all(|&(x, y, _)| x == 0 && y == 0) && kernel.temporal.iter().all(|&(t, _)| t == 0);
    if alone && n > 1 {
        return Err(weighs_nothing(tile, sigma_xy, sigma_t));
    }
    // Initial pattern: a tenth of the pixels (at least one), chosen by the seed.
    let ones = (n / 10).max(1);
    let mut rng = Stream::new(derive(seed_key(seed), 0x57b1));
    let mut order: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        order.swap(i, rng.below(i as u32 + 1) as usize);
    }
    let mut pattern = Pattern::new(tile, &kernel, &order[..ones]);
    // Relax: move the tightest cluster into the largest void until it stays.
    for _ in 0..n {
        let Some(cluster) = pattern.clusters.best() else { break };
        pattern.toggle(cluster);
        let Some(void) = pattern.voids.best() else { break };
        pattern.toggle(void);
        if void == cluster {
            break;
        }
    }
    let mut rank = vec![u32::MAX; n];
    // Phase 1: ranks below the pattern, removing tightest clusters.
    let initial: Vec<usize> = (0..n).filter(|&p| pattern.on[p]).collect();
    {
        let mut below = Pattern::new(tile, &kernel, &initial);
        for r in (0..initial.len()).rev() {
            let Some(c) = below.clusters.best() else { break };
            below.toggle(c);
            rank[c] = r as u32;
        }
    }
    // Phases 2 and 3: ranks above it, filling largest voids.
    for r in initial.len()..n {
        let Some(v) = pattern.voids.best() else { break };
        pattern.toggle(v);
        rank[v] = r as u32;
    }
    if rank.contains(&u32::MAX) {
        return Err(Error::invalid("void-and-cluster left a pixel unranked (internal error)"));
    }
    Ok(rank)
}

/// Annealing schedule of vector STBN: from half the mean |delta| of the first
/// proposals down to zero over the first three quarters of the passes, then
/// greedy.
pub const ANNEALING: (f64, f64) = (0.1, 0.25);

/// Vector STBN (d >= 2): simulated annealing of swaps under STBN's pixel weights
/// times Georgiev and Fajardo's sample term exp(-|a - b|^(d/2)), from values
/// stratified per dimension.
pub fn stbn_vector(
    tile: Tile,
    sigma_xy: f64,
    sigma_t: f64,
    passes: u32,
    seed: u64,
    device: &SwapDevice,
    on_pass: impl FnMut(u32, f64),
) -> Result<(Vec<f32>, SwapReport)> {
    check_sigmas(sigma_xy, sigma_t)?;
    let energy = PairEnergy::new(tile, &stbn_offsets(sigma_xy, sigma_t), ValueTerm::Gaussian { sigma: 1.0 })?;
    if energy.offsets().is_empty() && tile.pixels() > 1 {
        return Err(weighs_nothing(&tile, sigma_xy, sigma_t));
    }
    let mut values = stratified_values(&tile, seed, 0x57b2);
    let schedule = Schedule { passes, start_temperature: ANNEALING.0, greedy_share: ANNEALING.1 };
    let report = device.search(&energy, &mut values, schedule, derive(seed_key(seed), 0x57b3), on_pass)?;
    Ok((values, report))
}

/// An STBN mask and, for vectors, what the search did: void-and-cluster for d = 1 (rank r of N becomes the sample
/// (r + 0.5) / N, on the CPU), annealing for d >= 2 (`passes` passes, searched
/// on `device`).
pub fn stbn_mask_with(
    tile: Tile,
    sigma_xy: f64,
    sigma_t: f64,
    passes: u32,
    seed: u64,
    device: &SwapDevice,
    on_pass: impl FnMut(u32, f64),
) -> Result<(crate::core::mask::Mask, Option<SwapReport>)> {
    let mut report = None;
    let (samples, how) = if tile.dims == 1 {
        let ranks = void_and_cluster(&tile, sigma_xy, sigma_t, seed)?;
        let n = ranks.len();
        let values = ranks.iter().map(|&r| crate::core::mask::stratum_centre(r as usize, n)).collect();
        (values, "void-and-cluster".to_string())
    } else {
        let (values, r) = stbn_vector(tile, sigma_xy, sigma_t, passes, seed, device, on_pass)?;
        report = Some(r);
        (values, format!("annealing, {passes} passes on {}", device.kind()))
    };
    let mut meta = vec![
        ("method".to_string(), "stbn".to_string()),
        ("kernel".to_string(), format!("stbn {how} (sigma = {sigma_xy}, sigma_t = {sigma_t})")),
        ("seed".to_string(), seed.to_string()),
        ("version".to_string(), env!("CARGO_PKG_VERSION").to_string()),
    ];
    meta.sort();
    Ok((crate::core::mask::Mask { tile, samples, meta }, report))
}

/// A scalar STBN mask (void-and-cluster).
pub fn stbn_mask(tile: Tile, sigma_xy: f64, sigma_t: f64, seed: u64) -> Result<crate::core::mask::Mask> {
    if tile.dims != 1 {
        return Err(Error::invalid("stbn_mask makes scalar masks; use stbn_mask_with for vectors"));
    }
    stbn_mask_with(tile, sigma_xy, sigma_t, 0, seed, &SwapDevice::Cpu, |_, _| {}).map(|(m, _)| m)
}

/// The error for an energy that weighs no pair of distinct pixels: no search
/// would move anything.
fn weighs_nothing(tile: &Tile, sigma_xy: f64, sigma_t: f64) -> Error {
    Error::invalid(format!(
        "STBN of sigma {sigma_xy} and temporal sigma {sigma_t} weighs no pair of pixels on a {} tile: \
         Gaussians narrower than a pixel",
        tile.describe()
    ))
}

fn check_sigmas(sigma_xy: f64, sigma_t: f64) -> Result<()> {
    for (name, s) in [("sigma", sigma_xy), ("temporal sigma", sigma_t)] {
        if !crate::core::kernel::SIGMA_RANGE.contains(&s) {
            return Err(Error::invalid(format!("STBN {name} must be in [0.01, 64], got {s:?}")));
        }
    }
    Ok(())
}
