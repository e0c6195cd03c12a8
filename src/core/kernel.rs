//! Spatio-temporal kernels: the filter the rendering error goes through.
//!
//! A kernel is spatial filter x temporal filter. The spatial filter is a Gaussian
//! given in pixels, or the eye at a display's pixels per degree (`csf.rs`: a
//! mixture of Gaussians fitted to the contrast sensitivity). On a wrapping tile it becomes a
//! finite table of offsets (dx, dy, dt) from a centre pixel, each with a weight; the
//! table is folded onto the tile (offsets that land on the same tile pixel add up),
//! normalised to sum 1 and sorted by decreasing weight, so that the class of a level
//! z is a prefix of the table (see `transport`).
//!
//! Temporal filters are causal (lag 0 = the current frame, lag k = k frames back),
//! except the symmetric Gaussian. Negative taps (the perceptual filter has small ones)
//! are dropped after folding: the level-set form of the objective covers the
//! positive part of a kernel only (the README states this choice and its cost).

use crate::core::tile::Tile;
use crate::error::{Error, Result};

/// The Gaussians' widths a kernel accepts, in pixels or frames: under 0.01 every
/// weight but the centre's is far below the tolerance (the kernel is a point
/// already at 0.3), and the square of a far smaller width underflows.
pub(crate) const SIGMA_RANGE: std::ops::RangeInclusive<f64> = 0.01..=64.0;
/// TAA's blend weights: below 1e-4 the history is longer than any tile (and at
/// a subnormal alpha every temporal weight rounds to 0).
pub(crate) const ALPHA_RANGE: std::ops::RangeInclusive<f64> = 1e-4..=1.0;
/// The frame rates the eye's temporal response is defined for.
pub(crate) const FPS_RANGE: std::ops::RangeInclusive<f64> = 8.0..=1000.0;

/// The temporal part of a kernel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Temporal {
    /// Frames independent: Salaün et al. 2022 applied per frame.
    Spatial,
    /// Symmetric Gaussian over time, exp(-dt^2 / sigma_t^2) (akin to STBN).
    Gaussian {
        /// Width in frames, in [0.01, 64].
        sigma_t: f64,
    },
    /// TAA: exponential moving average, weight alpha (1 - alpha)^k at lag k.
    Taa {
        /// Blend weight of the current frame, in [0.0001, 1].
        alpha: f64,
    },
    /// FovVideoVDP sustained + transient temporal response at `fps`.
    Perceptual {
        /// Frame rate in frames per second, in [8, 1000].
        fps: f64,
    },
    /// TAA then the eye: the two filters convolved (the paper's full model).
    PerceptualTaa {
        /// Frame rate in frames per second, in [8, 1000].
        fps: f64,
        /// TAA's blend weight of the current frame, in [0.0001, 1].
        alpha: f64,
    },
}

/// The spatial part of a kernel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Spatial {
    /// exp(-(dx^2 + dy^2) / sigma^2), pixels (no factor 2, as in the paper).
    Gaussian {
        /// Width in pixels, in [0.01, 64].
        sigma: f64,
    },
    /// The eye's contrast sensitivity on a display of `ppd` pixels per degree.
    Display {
        /// The display's pixels per degree of visual angle, in [5, 500].
        ppd: f64,
    },
}

impl Spatial {
    /// The weights of a centred offset (dx, dy), before normalisation, and the
    /// largest offset with a weight: a Gaussian's weights are exp(-r^2 / sigma^2)
    /// to the tolerance; a display's are its fitted mixture.
    fn weights(&self, tolerance: f64, widen: f64) -> (i64, Box<dyn Fn(i64, i64) -> f64>) {
        match *self {
            Spatial::Gaussian { sigma } => {
                let r = (sigma * (1.0 / tolerance).ln().sqrt()).floor() as i64;
                let s2 = sigma * sigma;
                // The centre is 1 whatever the width (0 / 0 where sigma^2 underflows).
                let w = move |dx: i64, dy: i64| match dx * dx + dy * dy {
                    0 => 1.0,
                    r2 => (-(r2 as f64) / s2).exp(),
                };
                (r, Box::new(w))
            }
            Spatial::Display { ppd } => {
                let parts: Vec<(f64, Vec<f64>)> = crate::core::csf::mixture(ppd)
                    .into_iter()
                    .map(|(w, s)| (w, crate::core::csf::profile(s * widen)))
                    .collect();
                let r = parts.iter().map(|p| p.1.len() / 2).max().unwrap_or(0) as i64;
                let at = move |dx: i64, dy: i64| {
                    parts
                        .iter()
                        .map(|(w, p)| {
                            let c = (p.len() / 2) as i64;
                            let get = |k: i64| {
                                p.get((k + c) as usize).copied().filter(|_| k.abs() <= c).unwrap_or(0.0)
                            };
                            w * get(dx) * get(dy)
                        })
                        .sum()
                };
                (r, Box::new(at))
            }
        }
    }
}

/// Everything that defines a kernel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KernelSpec {
    /// The filter over pixels of one frame.
    pub spatial: Spatial,
    /// The filter over frames.
    pub temporal: Temporal,
    /// Offsets whose weight is below `tolerance` x the largest weight are dropped.
    /// Such offsets belong only to classes of levels below that fraction of the
    /// level range, drawn with that probability.
    pub tolerance: f64,
}

pub const DEFAULT_SIGMA: f64 = 2.1;
pub const DEFAULT_ALPHA: f64 = 0.1;
pub const DEFAULT_FPS: f64 = 60.0;
pub const DEFAULT_TOLERANCE: f64 = 1e-3;

/// The least mean class (samples) of a display's kernel: where the eye's
/// filter at the display's pixels per degree would leave fewer (no TAA on a
/// display of under about 60 pixels per degree: 7 at standard_fhd), its widths
/// are widened until classes reach this. Sliced transport on classes of a
/// handful of samples measures little of their spread. Widened so, the eye
/// scores level with a Gaussian of sigma 2.1 pixels without TAA on
/// standard_fhd and standard_4k (RESULTS.md, the leads).
pub const MIN_MEAN_CLASS: f64 = 20.0;

/// Kernel names as the command line and files spell them.
pub const KERNEL_NAMES: [&str; 5] = ["spatial", "gaussian", "taa", "perceptual", "perceptual-taa"];

impl KernelSpec {
    /// Kernel names as the command line and files spell them.
    pub const NAMES: [&'static str; 5] = KERNEL_NAMES;

    /// The kernel of that name (one of [`KernelSpec::NAMES`]) as `fsot optimize
    /// --kernel NAME` makes it by default: the eye on the default display
    /// (`standard_fhd`, 37.84 pixels per degree), TAA alpha 0.1 at 60 fps, and
    /// for `gaussian` a temporal sigma of 2.1 frames. `from_name` takes a
    /// Gaussian eye of a sigma in pixels instead, `on_display_named` another
    /// display.
    ///
    /// ```
    /// let taa = fsot::KernelSpec::named("perceptual-taa")?;
    /// assert_eq!(taa.name(), "perceptual-taa");
    /// assert_eq!(taa.spatial, fsot::Spatial::Display { ppd: 37.84 });
    /// assert!(fsot::KernelSpec::named("no such kernel").is_err());
    /// # Ok::<(), fsot::Error>(())
    /// ```
    pub fn named(name: &str) -> Result<Self> {
        Self::from_name(name, DEFAULT_SIGMA, None, DEFAULT_ALPHA, DEFAULT_FPS)?
            .on_display_named(crate::core::display::DEFAULT_DISPLAY)
    }

    /// Builds a spec from a kernel name and its parameters, validating each.
    pub fn from_name(name: &str, sigma: f64, sigma_t: Option<f64>, alpha: f64, fps: f64) -> Result<Self> {
        if !SIGMA_RANGE.contains(&sigma) {
            return Err(Error::invalid(format!("sigma must be in [0.01, 64] pixels, got {sigma:?}")));
        }
        let check_alpha = || -> Result<()> {
            if !ALPHA_RANGE.contains(&alpha) {
                return Err(Error::invalid(format!(
                    "alpha (TAA blend weight) must be in [0.0001, 1], got {alpha:?}"
                )));
            }
            Ok(())
        };
        let check_fps = || -> Result<()> {
            if !FPS_RANGE.contains(&fps) {
                return Err(Error::invalid(format!("fps must be in [8, 1000], got {fps:?}")));
            }
            Ok(())
        };
        if let Some(sigma_t) = sigma_t.filter(|s| !SIGMA_RANGE.contains(s)) {
            return Err(Error::invalid(format!("temporal sigma must be in [0.01, 64] frames, got {sigma_t:?}")));
        }
        let temporal = match name {
            "spatial" => Temporal::Spatial,
            // Both widths are checked above.
            "gaussian" => Temporal::Gaussian { sigma_t: sigma_t.unwrap_or(sigma) },
            "taa" => {
                check_alpha()?;
                Temporal::Taa { alpha }
            }
            "perceptual" => {
                check_fps()?;
                Temporal::Perceptual { fps }
            }
            "perceptual-taa" => {
                check_alpha()?;
                check_fps()?;
                Temporal::PerceptualTaa { fps, alpha }
            }
            other => {
                return Err(Error::invalid(format!(
                    "unknown kernel {other:?}; expected one of {}",
                    KERNEL_NAMES.join(", ")
                )))
            }
        };
        Ok(Self { spatial: Spatial::Gaussian { sigma }, temporal, tolerance: DEFAULT_TOLERANCE })
    }

    /// An error unless every parameter is one the constructors accept: for a
    /// spec whose public fields were set by hand. `Run::start` checks its kernel.
    pub fn check(&self) -> Result<()> {
        match self.spatial {
            Spatial::Gaussian { sigma } if !SIGMA_RANGE.contains(&sigma) => {
                return Err(Error::invalid(format!("sigma must be in [0.01, 64] pixels, got {sigma:?}")))
            }
            Spatial::Gaussian { .. } => {}
            Spatial::Display { ppd } => {
                crate::core::display::check_ppd(ppd)?;
            }
        }
        let alpha_ok = |a: f64| ALPHA_RANGE.contains(&a);
        let fps_ok = |f: f64| FPS_RANGE.contains(&f);
        let ok = match self.temporal {
            Temporal::Spatial => true,
            Temporal::Gaussian { sigma_t } => SIGMA_RANGE.contains(&sigma_t),
            Temporal::Taa { alpha } => alpha_ok(alpha),
            Temporal::Perceptual { fps } => fps_ok(fps),
            Temporal::PerceptualTaa { fps, alpha } => fps_ok(fps) && alpha_ok(alpha),
        };
        if !ok {
            return Err(Error::invalid(format!(
                "temporal filter {:?} out of range (sigma_t in [0.01, 64], alpha in [0.0001, 1], fps in [8, 1000])",
                self.temporal
            )));
        }
        if !(1e-12..=0.5).contains(&self.tolerance) {
            return Err(Error::invalid(format!("tolerance must be in [1e-12, 0.5], got {:?}", self.tolerance)));
        }
        Ok(())
    }

    /// The same kernel with the eye of a display of `ppd` pixels per degree as
    /// its spatial filter.
    pub fn on_display(self, ppd: f64) -> Result<Self> {
        let ppd = crate::core::display::check_ppd(ppd)?;
        Ok(Self { spatial: Spatial::Display { ppd }, ..self })
    }

    /// The same kernel with the eye of a display given as the command line's
    /// `--display` takes it: a display model's name (`standard_fhd`,
    /// `standard_4k`, ... as ColorVideoVDP names them), pixels per degree, or
    /// `WxH:DIAGONALin:DISTANCEm`.
    ///
    /// ```
    /// let k = fsot::KernelSpec::named("perceptual-taa")?.on_display_named("standard_fhd")?;
    /// assert_eq!(k.spatial, fsot::Spatial::Display { ppd: 37.84 });
    /// # Ok::<(), fsot::Error>(())
    /// ```
    pub fn on_display_named(self, display: &str) -> Result<Self> {
        self.on_display(crate::core::display::parse(display)?)
    }

    /// The kernel's name (one of [`KernelSpec::NAMES`]), set by its temporal filter.
    pub fn name(&self) -> &'static str {
        match self.temporal {
            Temporal::Spatial => "spatial",
            Temporal::Gaussian { .. } => "gaussian",
            Temporal::Taa { .. } => "taa",
            Temporal::Perceptual { .. } => "perceptual",
            Temporal::PerceptualTaa { .. } => "perceptual-taa",
        }
    }

    /// The spec `describe` wrote (a mask's `kernel` attribute), e.g.
    /// "perceptual-taa (sigma = 2.1, fps = 60, alpha = 0.1)"; None for any
    /// other text (a peer's description).
    pub fn from_description(text: &str) -> Option<Self> {
        let (name, rest) = text.trim().split_once(" (")?;
        let params = rest.strip_suffix(')')?;
        let mut values = std::collections::HashMap::new();
        for pair in params.split(", ") {
            let (key, value) = pair.split_once(" = ")?;
            values.insert(key, value.parse::<f64>().ok()?);
        }
        let spatial = match (values.contains_key("sigma"), values.contains_key("ppd")) {
            (true, false) => "sigma",
            (false, true) => "ppd",
            _ => return None,
        };
        let expected: &[&str] = match name {
            "spatial" => &[],
            "gaussian" => &["sigma_t"],
            "taa" => &["alpha"],
            "perceptual" => &["fps"],
            "perceptual-taa" => &["fps", "alpha"],
            _ => return None,
        };
        if values.len() != expected.len() + 1 || expected.iter().any(|k| !values.contains_key(k)) {
            return None;
        }
        let get = |k: &str, default: f64| values.get(k).copied().unwrap_or(default);
        let sigma_t = values.get("sigma_t").copied();
        let spec = Self::from_name(
            name,
            get("sigma", DEFAULT_SIGMA),
            sigma_t,
            get("alpha", DEFAULT_ALPHA),
            get("fps", DEFAULT_FPS),
        )
        .ok()?;
        match spatial {
            "ppd" => spec.on_display(get("ppd", 0.0)).ok(),
            _ => Some(spec),
        }
    }

    /// A one-line description with every parameter, for files and logs.
    pub fn describe(&self) -> String {
        let t = match self.temporal {
            Temporal::Spatial => String::new(),
            Temporal::Gaussian { sigma_t } => format!(", sigma_t = {sigma_t}"),
            Temporal::Taa { alpha } => format!(", alpha = {alpha}"),
            Temporal::Perceptual { fps } => format!(", fps = {fps}"),
            Temporal::PerceptualTaa { fps, alpha } => format!(", fps = {fps}, alpha = {alpha}"),
        };
        let spatial = match self.spatial {
            Spatial::Gaussian { sigma } => format!("sigma = {sigma}"),
            Spatial::Display { ppd } => format!("ppd = {ppd}"),
        };
        format!("{} ({spatial}{t})", self.name())
    }
}

/// FovVideoVDP's temporal response (sustained + transient channels) sampled at
/// `fps`: ceil(0.25 fps) taps, tap 0 for the current frame, summing to 1.
pub fn perceptual_taps(fps: f64) -> Vec<f64> {
    let (sustained, transient, sum) = channel_taps(fps);
    sustained.iter().zip(&transient).map(|(s, t)| (s + t) / sum).collect()
}

/// The two channels `perceptual_taps` adds, each scaled as in that sum (so
/// their tap-wise sum is `perceptual_taps`, to rounding): (sustained, transient).
pub fn perceptual_channels(fps: f64) -> (Vec<f64>, Vec<f64>) {
    let (sustained, transient, sum) = channel_taps(fps);
    (sustained.iter().map(|s| s / sum).collect(), transient.iter().map(|t| t / sum).collect())
}

/// The sustained taps (summing to 1), the transient taps, and the sum of both.
fn channel_taps(fps: f64) -> (Vec<f64>, Vec<f64>, f64) {
    let n = (0.25 * fps).ceil() as usize;
    let n = n.max(2);
    let dt = (n as f64 / fps) / (n as f64 - 1.0);
    let sustained: Vec<f64> = (0..n)
        .map(|k| {
            let t = k as f64 * dt;
            let l = (t + 1e-4).ln() - 0.06f64.ln();
            (-(l * l) / (2.0 * 0.5 * 0.5)).exp()
        })
        .collect();
    let total: f64 = sustained.iter().sum();
    let sustained: Vec<f64> = sustained.iter().map(|v| v / total).collect();
    let transient: Vec<f64> = (0..n)
        .map(|k| if k + 1 < n { 0.062170507756932 * (sustained[k + 1] - sustained[k]) / dt } else { 0.0 })
        .collect();
    let sum: f64 = sustained.iter().zip(&transient).map(|(s, t)| s + t).sum();
    (sustained, transient, sum)
}

/// A temporal response as weights over lags `first_lag, first_lag + 1, ...`, and
/// past the last tap a geometric tail: w(last + m) = w(last) * ratio^m (for TAA).
#[derive(Clone, Debug, PartialEq)]
pub struct TemporalResponse {
    pub first_lag: i64,
    pub taps: Vec<f64>,
    pub tail_ratio: f64,
}

impl TemporalResponse {
    pub fn of(temporal: Temporal) -> Self {
        match temporal {
            Temporal::Spatial => Self { first_lag: 0, taps: vec![1.0], tail_ratio: 0.0 },
            Temporal::Gaussian { sigma_t } => {
                let r = (sigma_t * (1.0f64 / 1e-6).ln().sqrt()).ceil() as i64;
                let taps = (-r..=r).map(|k| (-((k * k) as f64) / (sigma_t * sigma_t)).exp()).collect();
                Self { first_lag: -r, taps, tail_ratio: 0.0 }
            }
            Temporal::Taa { alpha } => Self { first_lag: 0, taps: vec![alpha], tail_ratio: 1.0 - alpha },
            Temporal::Perceptual { fps } => {
                Self { first_lag: 0, taps: perceptual_taps(fps), tail_ratio: 0.0 }
            }
            Temporal::PerceptualTaa { fps, alpha } => {
                // (h * e)(k) = sum_m h(m) alpha (1 - alpha)^(k - m); past the last
                // perceptual tap it decays by (1 - alpha) per frame.
                let h = perceptual_taps(fps);
                let r = 1.0 - alpha;
                let taps = (0..h.len())
                    .map(|k| (0..=k).map(|m| h[m] * alpha * r.powi((k - m) as i32)).sum())
                    .collect();
                Self { first_lag: 0, taps, tail_ratio: r }
            }
        }
    }

    /// Weight at lag `k` (0 outside the support).
    pub fn at(&self, k: i64) -> f64 {
        let i = k - self.first_lag;
        if i < 0 {
            return 0.0;
        }
        let i = i as usize;
        if i < self.taps.len() {
            self.taps[i]
        } else {
            let last = *self.taps.last().unwrap_or(&0.0);
            last * self.tail_ratio.powi((i + 1 - self.taps.len()) as i32)
        }
    }

    /// Folds the response onto a tile of `frames` frames: entry j is the total
    /// weight of the lags k with k = j (mod frames), j = frame offset backwards.
    /// The geometric tail is summed in closed form.
    pub fn folded(&self, frames: usize) -> Vec<f64> {
        let t = frames as i64;
        let mut out = vec![0.0; frames];
        for (i, w) in self.taps.iter().enumerate() {
            let k = self.first_lag + i as i64;
            out[k.rem_euclid(t) as usize] += w;
        }
        let last = *self.taps.last().unwrap_or(&0.0);
        if self.tail_ratio > 0.0 && last != 0.0 {
            let last_lag = self.first_lag + self.taps.len() as i64 - 1;
            let rt = self.tail_ratio.powi(frames as i32);
            let cycle = 1.0 - rt;
            for m in 1..=t {
                // lags last_lag + m + n*T, n >= 0: weight last * ratio^m * rt^n.
                let w = if cycle > 0.0 { last * self.tail_ratio.powi(m as i32) / cycle } else { 0.0 };
                out[(last_lag + m).rem_euclid(t) as usize] += w;
            }
        }
        out
    }
}

/// One entry of a kernel table: an offset from the centre pixel, already wrapped
/// onto the tile (add it to the centre and reduce mod W, H, T), and its weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tap {
    pub dx: u32,
    pub dy: u32,
    pub dt: u32,
    pub weight: f64,
}

/// A kernel on a given tile: taps sorted by decreasing weight, summing to 1.
#[derive(Clone, Debug)]
pub struct Kernel {
    pub spec: KernelSpec,
    pub taps: Vec<Tap>,
    /// Weight of the folded negative temporal taps that were dropped, relative to
    /// the positive total (0 for every kernel without negative lobes).
    pub dropped_negative: f64,
}

impl Kernel {
    pub fn new(spec: KernelSpec, tile: &Tile) -> Self {
        let kernel = Self::widened(spec, tile, 1.0);
        if !matches!(spec.spatial, Spatial::Display { .. }) || kernel.mean_class_len() >= MIN_MEAN_CLASS {
            return kernel;
        }
        // The display's eye leaves classes too small to measure: the least
        // widening (to 1/64) whose mean class reaches MIN_MEAN_CLASS, or the
        // widest tried.
        let (mut lo, mut hi) = (1.0f64, 4.0f64);
        if Self::widened(spec, tile, hi).mean_class_len() < MIN_MEAN_CLASS {
            return Self::widened(spec, tile, hi);
        }
        while hi - lo > 1.0 / 64.0 {
            let mid = 0.5 * (lo + hi);
            match Self::widened(spec, tile, mid).mean_class_len() >= MIN_MEAN_CLASS {
                true => hi = mid,
                false => lo = mid,
            }
        }
        Self::widened(spec, tile, hi)
    }

    /// The kernel with a display's eye widened `widen` times (1: as fitted).
    fn widened(spec: KernelSpec, tile: &Tile, widen: f64) -> Self {
        let (w, h, frames) = (tile.width as i64, tile.height as i64, tile.frames);
        // Spatial weights, folded onto W x H.
        let (r, weight) = spec.spatial.weights(spec.tolerance, widen);
        let peak = weight(0, 0);
        let mut spatial = vec![0.0f64; (w * h) as usize];
        for dy in -r..=r {
            for dx in -r..=r {
                let g = weight(dx, dy);
                if g >= spec.tolerance * peak {
                    spatial[(dy.rem_euclid(h) * w + dx.rem_euclid(w)) as usize] += g;
                }
            }
        }
        // Temporal weights, folded onto T, as forward frame offsets: lag k means
        // the frame k before the centre, i.e. offset (-k) mod T.
        let folded = TemporalResponse::of(spec.temporal).folded(frames);
        let mut temporal = vec![0.0f64; frames];
        let mut negative = 0.0;
        for (lag, &v) in folded.iter().enumerate() {
            let off = (frames - lag % frames) % frames;
            if v > 0.0 {
                temporal[off] = v;
            } else {
                negative -= v;
            }
        }
        let mut taps = Vec::new();
        for (dt, &wt) in temporal.iter().enumerate() {
            if wt <= 0.0 {
                continue;
            }
            for (i, &ws) in spatial.iter().enumerate() {
                if ws > 0.0 {
                    taps.push(Tap {
                        dx: (i as i64 % w) as u32,
                        dy: (i as i64 / w) as u32,
                        dt: dt as u32,
                        weight: ws * wt,
                    });
                }
            }
        }
        let max = taps.iter().map(|t| t.weight).fold(0.0, f64::max);
        taps.retain(|t| t.weight >= spec.tolerance * max);
        let total: f64 = taps.iter().map(|t| t.weight).sum();
        for t in &mut taps {
            t.weight /= total;
        }
        // Decreasing weight; ties broken by position so the order is reproducible.
        taps.sort_by(|a, b| b.weight.total_cmp(&a.weight).then((a.dt, a.dy, a.dx).cmp(&(b.dt, b.dy, b.dx))));
        let positive: f64 = temporal.iter().sum();
        Self { spec, taps, dropped_negative: negative / positive }
    }

    pub fn max_weight(&self) -> f64 {
        self.taps[0].weight
    }

    /// Number of taps whose weight is at least `z`: the class size (in pixels) of
    /// the level `z`.
    pub fn class_len(&self, z: f64) -> usize {
        self.taps.partition_point(|t| t.weight >= z)
    }

    /// Mean class size (pixels) over levels uniform in (0, max]: 1 / max weight.
    pub fn mean_class_len(&self) -> f64 {
        1.0 / self.max_weight()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tile(w: usize, h: usize, t: usize) -> Tile {
        Tile::new(w, h, t, 1, 2).unwrap()
    }

    #[test]
    fn perceptual_taps_at_60_fps_match_the_published_values() {
        let expected = [
            0.03956, 0.39841, 0.40469, 0.17788, 0.04191, -0.00678, -0.01701, -0.01501, -0.01069, -0.00698,
            -0.00435, -0.00265, -0.00159, -0.00094, 0.00354,
        ];
        let taps = perceptual_taps(60.0);
        assert_eq!(taps.len(), 15);
        for (a, b) in taps.iter().zip(expected) {
            assert!((a - b).abs() < 1e-4, "{a} vs {b}");
        }
        assert!((taps.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn taa_folds_to_the_closed_form_geometric_sum() {
        let alpha: f64 = 0.1;
        let frames = 16;
        let folded = TemporalResponse::of(Temporal::Taa { alpha }).folded(frames);
        let cycle = 1.0 - (1.0 - alpha).powi(frames as i32);
        for (k, v) in folded.iter().enumerate() {
            let exact = alpha * (1.0 - alpha).powi(k as i32) / cycle;
            assert!((v - exact).abs() < 1e-12, "lag {k}: {v} vs {exact}");
        }
        assert!((folded.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn perceptual_taa_is_the_convolution_of_its_parts() {
        let (fps, alpha) = (60.0, 0.1);
        let composed = TemporalResponse::of(Temporal::PerceptualTaa { fps, alpha });
        let h = perceptual_taps(fps);
        for k in 0..80i64 {
            let direct: f64 = (0..h.len() as i64)
                .filter(|&m| m <= k)
                .map(|m| h[m as usize] * alpha * (1.0f64 - alpha).powi((k - m) as i32))
                .sum();
            assert!((composed.at(k) - direct).abs() < 1e-12, "lag {k}");
        }
    }

    #[test]
    fn spatial_kernel_matches_the_gaussian_and_is_sorted() {
        let spec = KernelSpec::from_name("spatial", 2.1, None, 0.1, 60.0).unwrap();
        let k = Kernel::new(spec, &tile(64, 64, 4));
        assert!(k.taps.iter().all(|t| t.dt == 0));
        assert!(k.taps.windows(2).all(|p| p[0].weight >= p[1].weight));
        assert!((k.taps.iter().map(|t| t.weight).sum::<f64>() - 1.0).abs() < 1e-12);
        let centre = k.taps[0];
        assert_eq!((centre.dx, centre.dy), (0, 0));
        // Neighbour at distance 1 and at (2, 1), against exp(-r^2 / sigma^2).
        let find = |dx: u32, dy: u32| k.taps.iter().find(|t| t.dx == dx && t.dy == dy).unwrap().weight;
        assert!((find(1, 0) / centre.weight - (-1.0f64 / 4.41).exp()).abs() < 1e-12);
        assert!((find(2, 63) / centre.weight - (-5.0f64 / 4.41).exp()).abs() < 1e-12);
        // Mean class size is 1 / max weight: about pi sigma^2 pixels.
        assert!((k.mean_class_len() - std::f64::consts::PI * 4.41).abs() < 0.1);
    }

    /// The kernel's 2-D frequency response at (fx, fy) cycles per pixel, by the
    /// direct sum over its taps (a tile of one frame).
    fn response(k: &Kernel, w: u32, fx: f64, fy: f64) -> f64 {
        let signed = |d: u32| if d > w / 2 { d as f64 - w as f64 } else { d as f64 };
        k.taps
            .iter()
            .map(|t| t.weight * (std::f64::consts::TAU * (fx * signed(t.dx) + fy * signed(t.dy))).cos())
            .sum()
    }

    #[test]
    fn a_gaussian_kernel_responds_as_its_fourier_transform() {
        // exp(-r^2 / sigma^2) transforms to exp(-pi^2 sigma^2 f^2): on the pixel grid
        // to within aliasing, below 1e-3 for sigma 2.1.
        let spec = KernelSpec::from_name("spatial", 2.1, None, 0.1, 60.0).unwrap();
        let k = Kernel::new(spec, &tile(128, 128, 1));
        for (fx, fy) in [(0.0, 0.0), (0.05, 0.0), (0.1, 0.1), (0.2, 0.05), (0.3, 0.3), (0.5, 0.5)] {
            let exact = (-(std::f64::consts::PI * 2.1f64).powi(2) * (fx * fx + fy * fy)).exp();
            assert!((response(&k, 128, fx, fy) - exact).abs() < 1e-3, "({fx}, {fy})");
        }
    }

    #[test]
    fn a_display_kernel_follows_the_contrast_sensitivity_at_its_pixels_per_degree() {
        // Against Barten's formula in f64, over the whole pixel-frequency square:
        // flat up to the sensitivity's peak, then its fall. A positive mixture of
        // Gaussians rounds the shoulder at the peak (the worst point, about 0.12
        // below the target at 38 pixels per degree); it is far closer than the
        // Gaussian of sigma 2.1 pixels.
        for ppd in [38.0, 75.0] {
            let gaussian = Kernel::new(
                KernelSpec::from_name("spatial", 2.1, None, 0.1, 60.0).unwrap(),
                &tile(128, 128, 1),
            );
            let spec = gaussian.spec.on_display(ppd).unwrap();
            // The fit itself (a spatial kernel of one frame would be widened).
            let k = Kernel::widened(spec, &tile(128, 128, 1), 1.0);
            assert!(k.taps.iter().all(|t| t.weight > 0.0));
            let (mut worst, mut square, mut square_gaussian, mut n) = (0.0f64, 0.0, 0.0, 0.0);
            for i in 0..=20 {
                for j in 0..=20 {
                    let (fx, fy) = (0.025 * i as f64, 0.025 * j as f64);
                    let want = crate::core::csf::target(fx.hypot(fy), ppd);
                    let d = response(&k, 128, fx, fy) - want;
                    worst = worst.max(d.abs());
                    square += d * d;
                    square_gaussian += (response(&gaussian, 128, fx, fy) - want).powi(2);
                    n += 1.0;
                }
            }
            let (rms, rms_gaussian) = ((square / n).sqrt(), (square_gaussian / n).sqrt());
            assert!(worst < 0.13 && rms < 0.05, "ppd {ppd}: worst {worst}, rms {rms}");
            assert!(rms < 0.4 * rms_gaussian, "ppd {ppd}: rms {rms} against the Gaussian's {rms_gaussian}");
        }
        // A finer display sees less of a pixel-sized error: a wider kernel.
        let wide = |ppd| {
            let spec =
                KernelSpec::from_name("spatial", 2.1, None, 0.1, 60.0).unwrap().on_display(ppd).unwrap();
            Kernel::widened(spec, &tile(64, 64, 1), 1.0).mean_class_len()
        };
        assert!(wide(75.0) > 2.0 * wide(38.0), "{} against {}", wide(75.0), wide(38.0));
    }

    #[test]
    fn a_display_kernel_too_sharp_to_measure_is_widened_to_the_least_class() {
        let t = Tile::new(128, 128, 64, 1, 1).unwrap();
        let on = |name: &str, ppd: f64| {
            let spec = KernelSpec::from_name(name, 2.1, None, 0.1, 60.0).unwrap().on_display(ppd).unwrap();
            Kernel::new(spec, &t)
        };
        // Without TAA on a full-HD monitor the eye alone leaves about 7 samples a class.
        let sharp = Kernel::widened(on("perceptual", 37.84).spec, &t, 1.0);
        assert!(sharp.mean_class_len() < 10.0, "{}", sharp.mean_class_len());
        let widened = on("perceptual", 37.84);
        let m = widened.mean_class_len();
        assert!((MIN_MEAN_CLASS..MIN_MEAN_CLASS * 1.1).contains(&m), "{m}");
        // With TAA the classes are large enough: the eye as fitted.
        let taa = on("perceptual-taa", 37.84);
        assert!(taa.mean_class_len() >= MIN_MEAN_CLASS);
        assert_eq!(taa.taps, Kernel::widened(taa.spec, &t, 1.0).taps);
    }

    #[test]
    fn kernels_fold_onto_tiny_tiles() {
        let spec = KernelSpec::from_name("taa", 2.1, None, 0.1, 60.0).unwrap();
        let k = Kernel::new(spec, &tile(1, 2, 1));
        assert_eq!(k.taps.len(), 2);
        assert!((k.taps.iter().map(|t| t.weight).sum::<f64>() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn negative_perceptual_taps_are_dropped_and_reported() {
        let spec = KernelSpec::from_name("perceptual", 2.1, None, 0.1, 60.0).unwrap();
        let k = Kernel::new(spec, &tile(16, 16, 30));
        assert!(k.dropped_negative > 0.05 && k.dropped_negative < 0.1, "{}", k.dropped_negative);
        assert!(k.taps.iter().all(|t| t.weight > 0.0));
        let spec = KernelSpec::from_name("perceptual-taa", 2.1, None, 0.1, 60.0).unwrap();
        assert_eq!(Kernel::new(spec, &tile(16, 16, 30)).dropped_negative, 0.0);
    }

    #[test]
    fn bad_kernel_parameters_are_rejected() {
        assert!(KernelSpec::from_name("box", 2.1, None, 0.1, 60.0).is_err());
        assert!(KernelSpec::from_name("taa", 2.1, None, 1.5, 60.0).is_err());
        assert!(KernelSpec::from_name("taa", 2.1, None, 0.0, 60.0).is_err());
        assert!(KernelSpec::from_name("perceptual-taa", 2.1, None, 5e-324, 60.0).is_err(), "a subnormal alpha");
        // The smallest alpha makes a kernel of weights summing to 1.
        let smallest = KernelSpec::from_name("taa", 2.1, None, 1e-4, 60.0).unwrap();
        let sum: f64 = Kernel::new(smallest, &tile(8, 8, 64)).taps.iter().map(|t| t.weight).sum();
        assert!((sum - 1.0).abs() < 1e-12, "{sum}");
        assert!(KernelSpec::from_name("spatial", -1.0, None, 0.1, 60.0).is_err());
        assert!(KernelSpec::from_name("spatial", f64::NAN, None, 0.1, 60.0).is_err());
        assert!(KernelSpec::from_name("perceptual", 2.1, None, 0.1, 0.0).is_err());
    }

    #[test]
    fn a_description_reads_back_as_the_same_kernel_and_other_text_is_none() {
        for name in KERNEL_NAMES {
            for (sigma, alpha, fps, sigma_t) in [(2.1, 0.1, 60.0, None), (1.3435, 0.05, 30.0, Some(0.7))] {
                let spec = KernelSpec::from_name(name, sigma, sigma_t, alpha, fps).unwrap();
                assert_eq!(KernelSpec::from_description(&spec.describe()), Some(spec), "{}", spec.describe());
                let spec = spec.on_display(37.8).unwrap();
                assert_eq!(KernelSpec::from_description(&spec.describe()), Some(spec), "{}", spec.describe());
            }
        }
        for text in [
            "stbn vector (sigma = 1.9, sigma_t = 1.9)",
            "taa (sigma = 2.1)",
            "taa (sigma = 2.1, alpha = x)",
            "taa (sigma = 2.1, alpha = 0.1, fps = 60)",
            "taa (sigma = 2.1, alpha = 7)",
            "taa (sigma = 2.1, ppd = 40, alpha = 0.1)",
            "taa (ppd = 1, alpha = 0.1)",
            "",
        ] {
            assert_eq!(KernelSpec::from_description(text), None, "{text}");
        }
    }
}
