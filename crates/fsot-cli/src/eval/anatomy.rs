//! What the judges see of a render's error, band by band: the radially averaged
//! spatial power spectrum of the error, its temporal power spectrum, and
//! ColorVideoVDP's pooled differences per visual channel and pyramid band.
//!
//! The error is the render minus the reference over the judged frames, both
//! divided by the reference's brightest judged pixel (the scale the judge's
//! tone mapping uses). Spectra are in the error's own units: the mean over
//! judged frames (spatial) or pixels (temporal) of |DFT|^2 / samples, so white
//! noise of variance v reads v in every bin.

use crate::eval::jod::Judge;
use fsot::error::Result;

/// Edges of the spatial frequency bins, cycles per pixel (radius in the 2-D
/// spectrum; the last bin reaches the corners, sqrt(2)/2).
pub const SPATIAL_EDGES: [f64; 7] = [0.0, 0.04, 0.08, 0.15, 0.25, 0.35, 0.71];
/// Edges of the temporal frequency bins, Hz (at the judge's frame rate).
pub const TEMPORAL_EDGES: [f64; 6] = [0.0, 1.5, 4.0, 8.0, 15.0, 30.01];

/// One render's error, dissected.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Anatomy {
    pub jod: f64,
    /// Mean error power per spatial bin (`SPATIAL_EDGES`).
    pub spatial: Vec<f64>,
    /// Mean error power per temporal bin (`TEMPORAL_EDGES`).
    pub temporal: Vec<f64>,
    /// ColorVideoVDP's pooled difference per channel (sustained achromatic,
    /// red-green, yellow-violet, transient achromatic) and band (finest
    /// first, the baseband last), with the channel and baseband weights it
    /// pools them with.
    pub bands: Vec<Vec<f64>>,
    /// The band frequencies, cycles per degree (the baseband last).
    pub band_frequencies: Vec<f64>,
}

impl Anatomy {
    /// The mean of several anatomies (of one method's renders).
    pub fn mean(all: &[Anatomy]) -> Anatomy {
        let n = all.len().max(1) as f64;
        let mut out = all.first().cloned().unwrap_or_default();
        let avg =
            |get: &dyn Fn(&Anatomy) -> &Vec<f64>, k: usize| all.iter().map(|a| get(a)[k]).sum::<f64>() / n;
        out.jod = all.iter().map(|a| a.jod).sum::<f64>() / n;
        out.spatial = (0..out.spatial.len()).map(|k| avg(&|a| &a.spatial, k)).collect();
        out.temporal = (0..out.temporal.len()).map(|k| avg(&|a| &a.temporal, k)).collect();
        for c in 0..out.bands.len() {
            for b in 0..out.bands[c].len() {
                out.bands[c][b] = all.iter().map(|a| a.bands[c][b]).sum::<f64>() / n;
            }
        }
        out
    }
}

/// |DFT|^2 of a real sequence of any length (direct sum; the lengths here are
/// under a hundred), index k for frequency k / len.
fn dft_power(x: &[f64]) -> Vec<f64> {
    let n = x.len();
    (0..n)
        .map(|k| {
            let (mut re, mut im) = (0.0, 0.0);
            for (j, v) in x.iter().enumerate() {
                let a = std::f64::consts::TAU * ((k * j) % n) as f64 / n as f64;
                re += v * a.cos();
                im -= v * a.sin();
            }
            re * re + im * im
        })
        .collect()
}

/// The 2-D |DFT|^2 of an n x n grid (row-major), by rows then columns.
fn dft_power_2d(grid: &[f64], n: usize) -> Vec<f64> {
    let tw: Vec<(f64, f64)> = (0..n)
        .map(|k| (std::f64::consts::TAU * k as f64 / n as f64).sin_cos())
        .map(|(s, c)| (c, -s))
        .collect();
    let dft = |re_in: &[f64], im_in: &[f64], re: &mut [f64], im: &mut [f64]| {
        for k in 0..n {
            let (mut a, mut b) = (0.0, 0.0);
            for j in 0..n {
                let (c, s) = tw[(k * j) % n];
                a += re_in[j] * c - im_in[j] * s;
                b += re_in[j] * s + im_in[j] * c;
            }
            re[k] = a;
            im[k] = b;
        }
    };
    let (mut re, mut im) = (vec![0.0; n * n], vec![0.0; n * n]);
    let zeros = vec![0.0; n];
    for r in 0..n {
        let (a, b) = (&mut re[r * n..(r + 1) * n], &mut im[r * n..(r + 1) * n]);
        dft(&grid[r * n..(r + 1) * n], &zeros, a, b);
    }
    let mut out = vec![0.0; n * n];
    let (mut cr, mut ci, mut or, mut oi) = (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    for c in 0..n {
        for r in 0..n {
            cr[r] = re[r * n + c];
            ci[r] = im[r * n + c];
        }
        dft(&cr, &ci, &mut or, &mut oi);
        for r in 0..n {
            out[r * n + c] = or[r] * or[r] + oi[r] * oi[r];
        }
    }
    out
}

/// Mean power per bin: `power[k]` at frequency `freq(k)`, binned by `edges`.
fn bin(power: impl Iterator<Item = (f64, f64)>, edges: &[f64]) -> Vec<f64> {
    let bins = edges.len() - 1;
    let (mut sum, mut count) = (vec![0.0; bins], vec![0usize; bins]);
    for (f, p) in power {
        if let Some(b) = (0..bins).find(|&b| f >= edges[b] && f < edges[b + 1]) {
            sum[b] += p;
            count[b] += 1;
        }
    }
    sum.iter().zip(&count).map(|(s, &c)| if c > 0 { s / c as f64 } else { 0.0 }).collect()
}

/// Signed frequency of DFT index k of n, in cycles per sample.
fn frequency(k: usize, n: usize) -> f64 {
    let k = if k > n / 2 { k as f64 - n as f64 } else { k as f64 };
    k / n as f64
}

/// The anatomy of `render` against `reference` (n x n frames, judged from
/// `start`), with the judge's verdict.
pub fn anatomy(
    render: &[Vec<f64>],
    reference: &[Vec<f64>],
    start: usize,
    n: usize,
    judge: &Judge,
) -> Result<Anatomy> {
    let verdict = judge.verdict(render, reference, start, n)?;
    let peak = reference[start..].iter().flatten().fold(1e-12f64, |a, &b| a.max(b));
    let error: Vec<Vec<f64>> = render[start..]
        .iter()
        .zip(&reference[start..])
        .map(|(r, q)| r.iter().zip(q).map(|(a, b)| (a - b) / peak).collect())
        .collect();
    let frames = error.len();
    let mut spatial = vec![0.0; n * n];
    for e in &error {
        for (s, p) in spatial.iter_mut().zip(dft_power_2d(e, n)) {
            *s += p / (n * n * frames) as f64;
        }
    }
    let radial =
        bin((0..n * n).map(|i| (frequency(i % n, n).hypot(frequency(i / n, n)), spatial[i])), &SPATIAL_EDGES);
    let mut temporal = vec![0.0; frames];
    for i in 0..n * n {
        let series: Vec<f64> = error.iter().map(|e| e[i]).collect();
        for (t, p) in temporal.iter_mut().zip(dft_power(&series)) {
            *t += p / (frames * n * n) as f64;
        }
    }
    let hz = judge.fps();
    let temporal = bin((0..frames).map(|k| (frequency(k, frames).abs() * hz, temporal[k])), &TEMPORAL_EDGES);
    Ok(Anatomy {
        jod: verdict.jod,
        spatial: radial,
        temporal,
        bands: verdict.bands,
        band_frequencies: verdict.band_frequencies,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn white_noise_reads_its_variance_in_every_bin_and_a_wave_only_in_its_own() {
        let n = 24;
        let mut rng = fsot::core::rng::Stream::new(5);
        let grid: Vec<f64> = (0..n * n).map(|_| rng.next_f64() - 0.5).collect();
        let p = dft_power_2d(&grid, n);
        // Parseval: the mean of |DFT|^2 / N is the mean square.
        let mean_square = grid.iter().map(|v| v * v).sum::<f64>() / (n * n) as f64;
        let parseval = p.iter().sum::<f64>() / (n * n * n * n) as f64;
        assert!((parseval - mean_square).abs() < 1e-12 * mean_square.max(1.0), "{parseval} {mean_square}");
        // Every bin of white noise (uniform, variance 1/12) reads 1/12: the
        // mean over 64 grids within 4 standard errors of those grids.
        let grids: Vec<Vec<f64>> = (0..64)
            .map(|_| {
                let grid: Vec<f64> = (0..n * n).map(|_| rng.next_f64() - 0.5).collect();
                let p = dft_power_2d(&grid, n);
                let radial = (0..n * n).map(|i| (frequency(i % n, n).hypot(frequency(i / n, n)), p[i]));
                bin(radial, &SPATIAL_EDGES).iter().map(|b| b / (n * n) as f64).collect()
            })
            .collect();
        for b in 0..SPATIAL_EDGES.len() - 1 {
            let values: Vec<f64> = grids.iter().map(|g| g[b]).collect();
            let mean = values.iter().sum::<f64>() / 64.0;
            let sd = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / 63.0).sqrt();
            assert!((mean - 1.0 / 12.0).abs() < 4.0 * sd / 8.0, "bin {b}: {mean} +- {}", sd / 8.0);
        }
        // A wave at 5 cycles along y (0.208 cycles per pixel): all its power in bin 3.
        let wave: Vec<f64> =
            (0..n * n).map(|i| (std::f64::consts::TAU * 5.0 * (i / n) as f64 / n as f64).cos()).collect();
        let p = dft_power_2d(&wave, n);
        let binned =
            bin((0..n * n).map(|i| (frequency(i % n, n).hypot(frequency(i / n, n)), p[i])), &SPATIAL_EDGES);
        let total: f64 = binned.iter().sum();
        assert!(binned[3] / total > 0.999, "{binned:?}");
        // The 1-D transform agrees with the 2-D one on a single row.
        let row: Vec<f64> = (0..n).map(|j| ((j * 7) % 5) as f64 - 2.0).collect();
        let mut grid = vec![0.0; n * n];
        grid[..n].copy_from_slice(&row);
        let p2 = dft_power_2d(&grid, n);
        for (k, p1) in dft_power(&row).iter().enumerate() {
            assert!((p1 - p2[k]).abs() < 1e-9, "bin {k}");
        }
    }
}
