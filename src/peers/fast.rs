//! FAST, filter-adapted spatiotemporal masks (Donnelly et al. 2024): swaps that
//! minimise the sum over pairs of pixels of the filter's autocorrelation at their
//! offset times minus the distance between their values,
//!
//!   L = sum_{p != q} A(q - p) (-|x_p - x_q|),
//!
//! so pixels the filter mixes get values far apart. The filter is separable: a
//! spatial filter (Gaussian, box or binomial, the same along x and y) and a
//! temporal one (Gaussian, box, binomial, or an exponential moving average with
//! blend alpha and history reset beta), combined as a product (one 3-D filter)
//! or a weighted sum (a spatial loss within each frame plus a temporal loss at
//! each pixel). Autocorrelations are taken on the wrapping tile, so the mask
//! tiles seamlessly.

use crate::core::mask::Mask;
use crate::core::rng::{derive, seed_key, Stream};
use crate::core::tile::Tile;
use crate::error::{Error, Result};
use crate::peers::swap::{PairEnergy, Schedule, SwapDevice, SwapReport, ValueTerm};

/// A 1-D filter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Filter {
    /// The identity (no filtering along this axis).
    None,
    /// A Gaussian of standard deviation sigma integrated over each pixel,
    /// 0.5 (erf((k + 0.5) / (sigma sqrt 2)) - erf((k - 0.5) / (sigma sqrt 2))),
    /// out to the taps that hold 99.5% of it, as the published generator makes it.
    Gaussian { sigma: f64 },
    /// n equal taps.
    Box { n: u32 },
    /// Binomial coefficients C(n, k), k = 0..n.
    Binomial { n: u32 },
    /// Exponential moving average, causal, over a history of m frames: weight
    /// alpha (1 - alpha)^k for the frame k back, the oldest frame of the
    /// history (1 - alpha)^(m - 1) (the blend starts from it). The history's
    /// length is random: beta is the chance per frame that it is thrown away
    /// (m geometric, truncated to the tile's frames), and the loss takes the
    /// autocorrelation's mean over m, as the published generator does (its
    /// "exponential"); the TAA case.
    Ema { alpha: f64, beta: f64 },
}

/// As `parse` takes it (`gaussian:1.3435`, `ema:0.1:0.1`, `none`).
impl std::fmt::Display for Filter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Filter::None => write!(f, "none"),
            Filter::Gaussian { sigma } => write!(f, "gaussian:{sigma}"),
            Filter::Box { n } => write!(f, "box:{n}"),
            Filter::Binomial { n } => write!(f, "binomial:{n}"),
            Filter::Ema { alpha, beta } => write!(f, "ema:{alpha}:{beta}"),
        }
    }
}

impl Filter {
    /// Parses `none`, `gaussian:SIGMA`, `box:N`, `binomial:N`, `ema:ALPHA:BETA`.
    pub fn parse(text: &str, temporal: bool) -> Result<Self> {
        let parts: Vec<&str> = text.split(':').collect();
        let num = |i: usize| -> Result<f64> {
            parts
                .get(i)
                .and_then(|s| s.trim().parse::<f64>().ok())
                .filter(|v| v.is_finite())
                .ok_or_else(|| Error::invalid(format!("filter `{text}`: expected a number after `:`")))
        };
        let count = |i: usize| -> Result<u32> {
            let v = num(i)?;
            if v.fract() != 0.0 || !(0.0..=64.0).contains(&v) {
                return Err(Error::invalid(format!("filter `{text}`: expected a whole number 0..64")));
            }
            Ok(v as u32)
        };
        let arity = |n: usize| -> Result<()> {
            if parts.len() != n {
                return Err(Error::invalid(format!("filter `{text}`: expected {} parameter(s)", n - 1)));
            }
            Ok(())
        };
        let filter = match parts[0] {
            "none" => {
                arity(1)?;
                Filter::None
            }
            "gaussian" => {
                arity(2)?;
                Filter::Gaussian { sigma: num(1)? }
            }
            "box" => {
                arity(2)?;
                Filter::Box { n: count(1)? }
            }
            "binomial" => {
                arity(2)?;
                Filter::Binomial { n: count(1)? }
            }
            "ema" if temporal => {
                arity(3)?;
                Filter::Ema { alpha: num(1)?, beta: num(2)? }
            }
            _ => {
                let names = if temporal {
                    "none, gaussian, box, binomial, ema"
                } else {
                    "none, gaussian, box, binomial"
                };
                return Err(Error::invalid(format!("unknown filter `{text}` (one of {names})")));
            }
        };
        filter.validate()?;
        Ok(filter)
    }

    fn validate(&self) -> Result<()> {
        let ok = match *self {
            Filter::None => true,
            Filter::Gaussian { sigma } => crate::core::kernel::SIGMA_RANGE.contains(&sigma),
            Filter::Box { n } => (1..=64).contains(&n),
            Filter::Binomial { n } => n <= 64,
            Filter::Ema { alpha, beta } => {
                crate::core::kernel::ALPHA_RANGE.contains(&alpha) && (0.0..1.0).contains(&beta)
            }
        };
        if ok {
            Ok(())
        } else {
            Err(Error::invalid(format!(
                "filter {self:?} out of range (sigma in [0.01, 64], box 1..64, binomial 0..64, alpha in [0.0001, 1], beta in [0, 1))"
            )))
        }
    }

    /// Taps (offset, weight).
    fn taps(&self) -> Vec<(i64, f64)> {
        match *self {
            Filter::None => vec![(0, 1.0)],
            Filter::Gaussian { sigma } => {
                let scale = std::f64::consts::FRAC_1_SQRT_2 / sigma;
                let tap = |k: i64| 0.5 * (erf(scale * (k as f64 + 0.5)) - erf(scale * (k as f64 - 0.5)));
                // Taps 0, +-1, ... until they hold 99.5% of the Gaussian.
                let mut r = 0i64;
                let mut total = tap(0);
                while total < GAUSSIAN_ENERGY {
                    r += 1;
                    total += 2.0 * tap(r);
                }
                (-r..=r).map(|k| (k, tap(k))).collect()
            }
            Filter::Box { n } => (0..n as i64).map(|k| (k - (n as i64 - 1) / 2, 1.0)).collect(),
            Filter::Binomial { n } => {
                let mut c = 1.0f64;
                (0..=n as i64)
                    .map(|k| {
                        let tap = (k - n as i64 / 2, c);
                        c = c * (n as i64 - k) as f64 / (k + 1) as f64;
                        tap
                    })
                    .collect()
            }
            // Its autocorrelation is a mean over histories (`autocorrelation`).
            Filter::Ema { .. } => unreachable!("an EMA's taps depend on its history"),
        }
    }



    /// Circular autocorrelation of the filter folded onto a wrapping axis of
    /// length n: `A[tau] = sum_j F[j] F[(j + tau) mod n]`, normalised to sum 1.
    pub fn autocorrelation(&self, n: usize) -> Vec<f64> {
        if let Filter::Ema { alpha, beta } = *self {
            // The mean over histories of m = 1..n frames, m geometric in beta
            // (uniform where beta is too small to tell from 0), of each
            // history's autocorrelation, wrapped. Over a history of m frames,
            // the pair of frames k and k + lag back (both newer than the
            // oldest) weighs alpha^2 r^(2k + lag), r = 1 - alpha, summed in
            // closed form; the oldest frame (weight r^(m - 1)) pairs with the
            // frame lag newer.
            let r = 1.0 - alpha;
            // 1 - (1 - beta)^n, without losing a tiny beta.
            let log_keep = (-beta).ln_1p();
            let reach = -(n as f64 * log_keep).exp_m1();
            let mut a = vec![0.0f64; n];
            for m in 1..=n {
                let weight = match reach > 0.0 {
                    true => beta * (log_keep * (m as f64 - 1.0)).exp() / reach,
                    false => 1.0 / n as f64,
                };
                let oldest = r.powi(m as i32 - 1);
                for lag in 0..m {
                    // Pairs (k, k + lag) with k + lag < m - 1: a geometric sum.
                    let pairs = (m - 1 - lag) as i32;
                    let geometric = match r * r < 1.0 {
                        true => (1.0 - (r * r).powi(pairs)) / (1.0 - r * r),
                        false => pairs as f64,
                    };
                    let before = alpha * alpha * r.powi(lag as i32) * geometric;
                    // The pair that ends at the oldest frame.
                    let last = match lag {
                        0 => oldest * oldest,
                        _ => alpha * r.powi(pairs) * oldest,
                    };
                    let c = weight * (before + last);
                    a[lag] += c;
                    if lag > 0 {
                        a[n - lag] += c;
                    }
                }
            }
            let total: f64 = a.iter().sum();
            return a.iter().map(|v| v / total).collect();
        }
        let mut folded = vec![0.0f64; n];
        for (k, w) in self.taps() {
            folded[k.rem_euclid(n as i64) as usize] += w;
        }
        // Over the folded filter's taps only (the rest add exact zeros, so the
        // sums are the same bits): n times the taps, not n^2.
        let taps: Vec<usize> = (0..n).filter(|&j| folded[j] != 0.0).collect();
        let mut a: Vec<f64> =
            (0..n).map(|tau| taps.iter().map(|&j| folded[j] * folded[(j + tau) % n]).sum::<f64>()).collect();
        // Exact symmetry (A[tau] = A[n - tau] up to the order of the sum).
        for tau in 1..n {
            let m = 0.5 * (a[tau] + a[n - tau]);
            a[tau] = m;
            a[n - tau] = m;
        }
        let total: f64 = a.iter().sum();
        a.iter().map(|v| v / total).collect()
    }
}

/// How the spatial and temporal filters make one loss.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Combine {
    /// One separable 3-D filter: A(dx, dy, dt) = A_s(dx, dy) A_t(dt).
    Product,
    /// weight x (spatial loss within each frame) + (1 - weight) x (temporal loss
    /// at each pixel).
    Sum { spatial_weight: f64 },
}

impl Combine {
    pub fn parse(text: &str) -> Result<Self> {
        if text == "product" {
            return Ok(Combine::Product);
        }
        if let Some(w) = text.strip_prefix("sum:") {
            if let Ok(w) = w.parse::<f64>() {
                if (0.0..=1.0).contains(&w) {
                    return Ok(Combine::Sum { spatial_weight: w });
                }
            }
        }
        Err(Error::invalid(format!("combination `{text}`: expected `product` or `sum:W` with W in [0, 1]")))
    }
}

/// A FAST filter setting.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FastSpec {
    pub spatial: Filter,
    pub temporal: Filter,
    pub combine: Combine,
}

impl Default for FastSpec {
    /// The published TAA mask's setting: Gaussian sigma 1.3435 times an EMA with
    /// alpha 0.1 and history reset 0.1.
    fn default() -> Self {
        Self {
            spatial: Filter::Gaussian { sigma: 1.3435 },
            temporal: Filter::Ema { alpha: 0.1, beta: 0.1 },
            combine: Combine::Product,
        }
    }
}

/// The share of a Gaussian its taps hold (the published generator's cut).
const GAUSSIAN_ENERGY: f64 = 0.995;

/// erf(x) to about 1e-15: its Taylor series below 3, the continued fraction
/// of erfc above.
fn erf(x: f64) -> f64 {
    let (sign, x) = if x < 0.0 { (-1.0, -x) } else { (1.0, x) };
    let value = if x < 3.0 {
        // 2/sqrt(pi) sum (-1)^k x^(2k+1) / (k! (2k+1)).
        let (mut term, mut sum, mut k) = (x, x, 0.0);
        while term.abs() > 1e-17 * sum.abs() {
            k += 1.0;
            term *= -x * x / k;
            sum += term / (2.0 * k + 1.0);
        }
        std::f64::consts::FRAC_2_SQRT_PI * sum
    } else {
        // erfc(x) = exp(-x^2) / sqrt(pi) / (x + (1/2) / (x + 1 / (x + (3/2) / (x + ...)))).
        let mut fraction = x;
        for k in (1..=60).rev() {
            fraction = x + (k as f64 / 2.0) / fraction;
        }
        1.0 - (-x * x).exp() / (std::f64::consts::PI.sqrt() * fraction)
    };
    sign * value
}

/// Autocorrelation weights below this share of the largest are dropped.
const CUTOFF: f64 = 1e-3;

impl FastSpec {
    /// An error unless both filters are in range and a sum's spatial weight is
    /// in [0, 1] (what `Filter::parse` and `Combine::parse` give).
    pub fn check(&self) -> Result<()> {
        self.spatial.validate()?;
        self.temporal.validate()?;
        match self.combine {
            Combine::Sum { spatial_weight } if !(0.0..=1.0).contains(&spatial_weight) => Err(Error::invalid(format!(
                "a sum's spatial weight must be in [0, 1], got {spatial_weight:?}"
            ))),
            _ => Ok(()),
        }
    }

    pub fn describe(&self) -> String {
        let c = match self.combine {
            Combine::Product => "product".to_string(),
            Combine::Sum { spatial_weight } => format!("sum, spatial weight {spatial_weight}"),
        };
        format!("fast: spatial {}, temporal {}, {c}", self.spatial, self.temporal)
    }

    /// The pair weights of the loss on a tile.
    pub fn offsets(&self, tile: &Tile) -> Vec<(i64, i64, i64, f64)> {
        let ax = self.spatial.autocorrelation(tile.width);
        let ay = self.spatial.autocorrelation(tile.height);
        let at = self.temporal.autocorrelation(tile.frames);
        let mut out = Vec::new();
        match self.combine {
            Combine::Product => {
                let largest = ax[0] * ay[0] * at[0];
                for (dt, &t) in at.iter().enumerate() {
                    for (dy, &y) in ay.iter().enumerate() {
                        for (dx, &x) in ax.iter().enumerate() {
                            let w = x * y * t;
                            if w >= CUTOFF * largest {
                                out.push((dx as i64, dy as i64, dt as i64, w));
                            }
                        }
                    }
                }
            }
            Combine::Sum { spatial_weight } => {
                let largest = (spatial_weight * ax[0] * ay[0]).max((1.0 - spatial_weight) * at[0]);
                for (dy, &y) in ay.iter().enumerate() {
                    for (dx, &x) in ax.iter().enumerate() {
                        let w = spatial_weight * x * y;
                        if w >= CUTOFF * largest && w > 0.0 {
                            out.push((dx as i64, dy as i64, 0, w));
                        }
                    }
                }
                for (dt, &t) in at.iter().enumerate() {
                    let w = (1.0 - spatial_weight) * t;
                    if w >= CUTOFF * largest && w > 0.0 {
                        out.push((0, 0, dt as i64, w));
                    }
                }
            }
        }
        out
    }
}

/// Starting values of a swap method: each dimension holds the N stratified
/// values (r + 0.5) / N exactly once, shuffled independently per dimension, so
/// every one-dimensional marginal is as uniform as N values can be and swaps
/// (which move whole vectors) keep it so.
pub fn stratified_values(tile: &Tile, seed: u64, label: u32) -> Vec<f32> {
    let (n, d) = (tile.pixels(), tile.dims);
    let mut values = vec![0.0f32; n * d];
    for k in 0..d {
        let mut rng = Stream::new(derive(derive(seed_key(seed), label), k as u32));
        let mut order: Vec<usize> = (0..n).collect();
        for i in (1..n).rev() {
            order.swap(i, rng.below(i as u32 + 1) as usize);
        }
        for (p, &r) in order.iter().enumerate() {
            values[p * d + k] = crate::core::mask::stratum_centre(r, n);
        }
    }
    values
}

/// A FAST mask: greedy swaps from stratified values, searched on `device`.
pub fn fast_mask(
    tile: Tile,
    spec: &FastSpec,
    passes: u32,
    seed: u64,
    device: &SwapDevice,
    on_pass: impl FnMut(u32, f64),
) -> Result<(Mask, SwapReport)> {
    fast_mask_from(tile, spec, passes, seed, None, device, on_pass)
}

/// A FAST mask from `start`'s values when given (swaps keep the values and
/// move them between pixels, so the mask's value histogram is `start`'s), else
/// from stratified values: greedy swaps searched on `device`. `start` must be
/// a mask of `tile`.
pub fn fast_mask_from(
    tile: Tile,
    spec: &FastSpec,
    passes: u32,
    seed: u64,
    start: Option<&Mask>,
    device: &SwapDevice,
    on_pass: impl FnMut(u32, f64),
) -> Result<(Mask, SwapReport)> {
    spec.check()?;
    let energy = PairEnergy::new(tile, &spec.offsets(&tile), ValueTerm::NegDistance)?;
    if energy.offsets().is_empty() {
        // No swap would change the loss: the result would be the start, unsearched.
        return Err(Error::invalid(format!(
            "{} weighs no pair of pixels on a {} tile: no filter (none and none), or one narrower than a pixel",
            spec.describe(),
            tile.describe()
        )));
    }
    let mut samples = match start {
        Some(m) if m.tile != tile => {
            return Err(Error::invalid(format!(
                "the initial mask is {} but FAST was asked for {}",
                m.tile.describe(),
                tile.describe()
            )))
        }
        Some(m) => m.samples.clone(),
        None => stratified_values(&tile, seed, 0xfa57),
    };
    let report = device.search(
        &energy,
        &mut samples,
        Schedule::greedy(passes),
        derive(seed_key(seed), 0xfa58),
        on_pass,
    )?;
    let mut meta = vec![
        ("method".to_string(), "fast".to_string()),
        ("kernel".to_string(), spec.describe()),
        ("seed".to_string(), seed.to_string()),
        ("passes".to_string(), passes.to_string()),
        ("start".to_string(), if start.is_some() { "the initial mask" } else { "stratified values" }.to_string()),
        ("backend".to_string(), device.kind().to_string()),
        ("version".to_string(), env!("CARGO_PKG_VERSION").to_string()),
    ];
    meta.sort();
    Ok((Mask { tile, samples, meta }, report))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_out_of_range_or_that_weigh_no_pair_are_refused_through_the_api_too() {
        let tile = Tile::new(8, 8, 4, 1, 1).unwrap();
        let spec = |spatial, temporal, combine| FastSpec { spatial, temporal, combine };
        let ema = Filter::Ema { alpha: 0.1, beta: 0.1 };
        for bad in [
            spec(Filter::Box { n: 0 }, ema, Combine::Product),
            spec(Filter::Gaussian { sigma: f64::NAN }, ema, Combine::Product),
            spec(Filter::Gaussian { sigma: 1e9 }, ema, Combine::Product),
            spec(Filter::Gaussian { sigma: 1.0 }, ema, Combine::Sum { spatial_weight: f64::NAN }),
            spec(Filter::None, Filter::None, Combine::Product),
        ] {
            let made = fast_mask(tile, &bad, 1, 0, &SwapDevice::Cpu, |_, _| {});
            assert!(made.is_err(), "{bad:?} made a mask");
        }
        let good = spec(Filter::Gaussian { sigma: 1.0 }, ema, Combine::Product);
        assert!(fast_mask(tile, &good, 1, 0, &SwapDevice::Cpu, |_, _| {}).is_ok());
    }

    #[test]
    fn autocorrelations_match_direct_sums() {
        // A box of 3 on a long axis: autocorrelation 3, 2, 1 at lags 0, 1, 2 (of 9).
        let a = Filter::Box { n: 3 }.autocorrelation(16);
        for (lag, want) in [(0, 3.0), (1, 2.0), (2, 1.0), (3, 0.0), (15, 2.0), (14, 1.0)] {
            assert!((a[lag] - want / 9.0).abs() < 1e-12, "lag {lag}: {}", a[lag]);
        }
        // Binomial 2 = (1, 2, 1): autocorrelation (1, 4, 6, 4, 1) / 16.
        let b = Filter::Binomial { n: 2 }.autocorrelation(8);
        for (lag, want) in [(0, 6.0), (1, 4.0), (2, 1.0), (7, 4.0), (6, 1.0), (4, 0.0)] {
            assert!((b[lag] - want / 16.0).abs() < 1e-12, "lag {lag}");
        }
        // EMA: each history's taps from the blend itself (h = x at the
        // history's first frame, then h = alpha x + (1 - alpha) h), the
        // response to a unit frame k back; the autocorrelation of every pair
        // of frames, wrapped, weighted by P(m) = beta (1 - beta)^(m - 1) over
        // m = 1..n, normalised.
        let (alpha, beta, n) = (0.3f64, 0.2f64, 5usize);
        let e = Filter::Ema { alpha, beta }.autocorrelation(n);
        let mut direct = vec![0.0; n];
        for m in 1..=n {
            let taps: Vec<f64> = (0..m)
                .map(|k| {
                    let mut h = if k + 1 == m { 1.0 } else { 0.0 };
                    for frame in (0..m - 1).rev() {
                        h = alpha * if frame == k { 1.0 } else { 0.0 } + (1.0 - alpha) * h;
                    }
                    h
                })
                .collect();
            let p = beta * (1.0 - beta).powi(m as i32 - 1);
            for i in 0..m {
                for j in 0..m {
                    direct[(j as i64 - i as i64).rem_euclid(n as i64) as usize] += p * taps[i] * taps[j];
                }
            }
        }
        let total: f64 = direct.iter().sum();
        for lag in 0..n {
            assert!((e[lag] - direct[lag] / total).abs() < 1e-12, "lag {lag}: {} vs {}", e[lag], direct[lag] / total);
        }
        // The published TAA setting (alpha = beta = 0.1) on 16 frames: lags 1,
        // 2, 4 and 8 at 0.124, 0.100, 0.067 and 0.044 of lag 0 (the published
        // generator's formula evaluated on its own).
        let a = Filter::Ema { alpha: 0.1, beta: 0.1 }.autocorrelation(16);
        for (lag, want) in [(1, 0.124), (2, 0.100), (4, 0.067), (8, 0.044)] {
            assert!((a[lag] / a[0] - want).abs() < 5e-4, "lag {lag}: {}", a[lag] / a[0]);
        }
        // A reset too rare for 1 - beta to tell from 1: every history length
        // alike, as at beta 0 (not a division by zero).
        let rare = Filter::Ema { alpha: 0.1, beta: 1e-17 }.autocorrelation(16);
        let never = Filter::Ema { alpha: 0.1, beta: 0.0 }.autocorrelation(16);
        for (x, y) in rare.iter().zip(&never) {
            assert!(x.is_finite() && (x - y).abs() < 1e-12, "{x} vs {y}");
        }
    }

    #[test]
    fn erf_matches_its_tables_and_a_gaussians_taps_hold_what_the_cut_keeps() {
        // Abramowitz and Stegun, table 7.1, and erf(3), erf(4) to 16 digits.
        for (x, want) in [
            (0.1, 0.112_462_916_018_284_9),
            (0.5, 0.520_499_877_813_046_5),
            (1.0, 0.842_700_792_949_714_9),
            (2.0, 0.995_322_265_018_952_7),
            (3.0, 0.999_977_909_503_001_4),
            (4.0, 0.999_999_984_582_742_1),
        ] {
            assert!((erf(x) - want).abs() < 2e-15, "erf({x}) = {}", erf(x));
            assert!((erf(-x) + want).abs() < 2e-15);
        }
        // Pixel-integrated taps hold at least 99.5% of the Gaussian, and would
        // not without their outermost pair.
        for sigma in [0.3, 1.3435, 2.0, 6.0] {
            let taps = Filter::Gaussian { sigma }.taps();
            let total: f64 = taps.iter().map(|t| t.1).sum();
            let outer = 2.0 * taps[0].1;
            assert!(total >= 0.995 && total - outer < 0.995, "sigma {sigma}: {total}, {outer}");
        }
    }

    #[test]
    fn filter_names_parse_and_bad_ones_are_refused() {
        assert_eq!(Filter::parse("gaussian:1.5", false).unwrap(), Filter::Gaussian { sigma: 1.5 });
        assert_eq!(Filter::parse("ema:0.1:0.1", true).unwrap(), Filter::Ema { alpha: 0.1, beta: 0.1 });
        assert_eq!(Filter::parse("box:3", true).unwrap(), Filter::Box { n: 3 });
        for bad in
            ["ema:0.1:0.1", "gaussian", "gaussian:-1", "box:0", "box:2.5", "binomial:x", "sinc:2", "none:1"]
        {
            assert!(Filter::parse(bad, false).is_err(), "{bad}");
        }
        for bad in ["ema:0:0.1", "ema:0.5:1", "ema:1.5:0", "ema:0.1"] {
            assert!(Filter::parse(bad, true).is_err(), "{bad}");
        }
        assert_eq!(Combine::parse("sum:0.25").unwrap(), Combine::Sum { spatial_weight: 0.25 });
        assert!(Combine::parse("sum:2").is_err() && Combine::parse("mix").is_err());
        // A filter is written as it is given.
        for text in ["none", "gaussian:1.3435", "box:3", "binomial:4", "ema:0.1:0.1"] {
            assert_eq!(Filter::parse(text, true).unwrap().to_string(), text);
        }
    }

    #[test]
    fn stratified_values_hold_each_stratum_once_per_dimension() {
        let tile = Tile::new(6, 5, 3, 1, 3).unwrap();
        let v = stratified_values(&tile, 4, 1);
        let n = tile.pixels();
        for k in 0..3 {
            let mut seen = vec![false; n];
            for p in 0..n {
                let r = (v[p * 3 + k] as f64 * n as f64 - 0.5).round() as usize;
                assert!(!seen[r]);
                seen[r] = true;
            }
        }
    }
}
