//! Spatiotemporal blue noise (Wolfe et al. 2022), scalar masks: void-and-cluster
//! with STBN's energy, a 2-D Gaussian within each frame plus a 1-D Gaussian over
//! time at the same pixel, exp(-r^2 / (2 sigma^2)) with sigma 1.9 for both, on the
//! wrapping tile.
//!
//! The classic three phases (Ulichney 1993): an initial binary pattern (a tenth of
//! the pixels, relaxed by moving its tightest cluster into its largest void until
//! that changes nothing), then ranks below it by removing tightest clusters, then
//! ranks above it by filling largest voids. Every step updates the energy of the
//! toggled pixel's neighbourhood only; the extreme is found by a scan. Ties go to
//! the lowest pixel index, so the result is a pure function of the seed.

use crate::error::{Error, Result};
use crate::problem::Tile;
use crate::rng::{derive, seed_key, Stream};

pub const DEFAULT_SIGMA: f64 = 1.9;

/// STBN's energy kernel on a tile: spatial offsets within the frame and
/// temporal offsets at the same pixel, folded onto the wrapping tile.
struct Energy {
    spatial: Vec<(usize, usize, f64)>,
    temporal: Vec<(usize, f64)>,
}

impl Energy {
    fn new(tile: &Tile, sigma_xy: f64, sigma_t: f64) -> Self {
        let (w, h, t) = (tile.width, tile.height, tile.frames);
        let r = (3.0 * sigma_xy).ceil() as i64;
        let mut spatial = vec![0.0f64; w * h];
        for dy in -r..=r {
            for dx in -r..=r {
                let g = (-((dx * dx + dy * dy) as f64) / (2.0 * sigma_xy * sigma_xy)).exp();
                spatial[dy.rem_euclid(h as i64) as usize * w + dx.rem_euclid(w as i64) as usize] += g;
            }
        }
        let rt = (3.0 * sigma_t).ceil() as i64;
        let mut temporal = vec![0.0f64; t];
        for dt in -rt..=rt {
            if dt != 0 {
                temporal[dt.rem_euclid(t as i64) as usize] +=
                    (-((dt * dt) as f64) / (2.0 * sigma_t * sigma_t)).exp();
            }
        }
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

/// Index of the largest (`want_max`) or smallest energy among pixels whose state
/// is `state`; ties to the lowest index. Scanned on every core in fixed chunks,
/// so the answer does not depend on the thread count.
fn extreme(energy: &[f64], on: &[bool], state: bool, want_max: bool) -> Option<usize> {
    use rayon::prelude::*;
    const CHUNK: usize = 4096;
    let key = |e: f64| if want_max { -e } else { e };
    energy
        .par_chunks(CHUNK)
        .zip(on.par_chunks(CHUNK))
        .enumerate()
        .filter_map(|(c, (es, os))| {
            let mut best: Option<(f64, usize)> = None;
            for (i, (&e, &o)) in es.iter().zip(os).enumerate() {
                if o == state && best.map(|(b, _)| key(e) < b).unwrap_or(true) {
                    best = Some((key(e), c * CHUNK + i));
                }
            }
            best
        })
        .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
        .map(|(_, i)| i)
}

/// Ranks 0..N of every pixel of a scalar mask (a permutation), by void-and-cluster.
pub fn void_and_cluster(tile: &Tile, sigma_xy: f64, sigma_t: f64, seed: u64) -> Result<Vec<u32>> {
    if tile.dims != 1 || tile.spp != 1 {
        return Err(Error::invalid(format!(
            "void-and-cluster makes scalar masks (d = 1, 1 spp); got {}",
            tile.describe()
        )));
    }
    for (name, s) in [("sigma", sigma_xy), ("temporal sigma", sigma_t)] {
        if !(s.is_finite() && s > 0.0 && s <= 64.0) {
            return Err(Error::invalid(format!("STBN {name} must be in (0, 64], got {s}")));
        }
    }
    let n = tile.pixels();
    let kernel = Energy::new(tile, sigma_xy, sigma_t);
    // Initial pattern: a tenth of the pixels (at least one), chosen by the seed.
    let ones = (n / 10).max(1);
    let mut rng = Stream::new(derive(seed_key(seed), 0x57b1));
    let mut order: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        order.swap(i, rng.below(i as u32 + 1) as usize);
    }
    let mut on = vec![false; n];
    let mut energy = vec![0.0f64; n];
    for &p in &order[..ones] {
        on[p] = true;
        kernel.splat(tile, &mut energy, p, 1.0);
    }
    // Relax: move the tightest cluster into the largest void until it stays.
    for _ in 0..n {
        let cluster = extreme(&energy, &on, true, true).expect("pattern has ones"); // ok: ones >= 1
        on[cluster] = false;
        kernel.splat(tile, &mut energy, cluster, -1.0);
        let void = extreme(&energy, &on, false, false).expect("pattern has zeros"); // ok: a zero was just made
        on[void] = true;
        kernel.splat(tile, &mut energy, void, 1.0);
        if void == cluster {
            break;
        }
    }
    let mut rank = vec![u32::MAX; n];
    // Phase 1: ranks below the pattern, removing tightest clusters.
    {
        let mut on1 = on.clone();
        let mut e1 = energy.clone();
        for r in (0..ones).rev() {
            let c = extreme(&e1, &on1, true, true).expect("ones left"); // ok: r counts them
            on1[c] = false;
            kernel.splat(tile, &mut e1, c, -1.0);
            rank[c] = r as u32;
        }
    }
    // Phases 2 and 3: ranks above it, filling largest voids.
    for r in ones..n {
        let v = extreme(&energy, &on, false, false).expect("zeros left"); // ok: r < n
        on[v] = true;
        kernel.splat(tile, &mut energy, v, 1.0);
        rank[v] = r as u32;
    }
    Ok(rank)
}

/// A scalar STBN mask: rank r of N becomes the sample (r + 0.5) / N.
pub fn stbn_mask(tile: Tile, sigma_xy: f64, sigma_t: f64, seed: u64) -> Result<crate::mask::Mask> {
    let ranks = void_and_cluster(&tile, sigma_xy, sigma_t, seed)?;
    let n = ranks.len() as f64;
    let samples = ranks.iter().map(|&r| ((r as f64 + 0.5) / n) as f32).collect();
    let mut meta = vec![
        ("method".to_string(), "stbn".to_string()),
        ("kernel".to_string(), format!("stbn void-and-cluster (sigma = {sigma_xy}, sigma_t = {sigma_t})")),
        ("seed".to_string(), seed.to_string()),
        ("version".to_string(), env!("CARGO_PKG_VERSION").to_string()),
    ];
    meta.sort();
    Ok(crate::mask::Mask { tile, samples, meta })
}
