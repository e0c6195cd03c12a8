//! Power spectra of masks: how a mask's noise is spread over spatial and temporal
//! frequencies (blue noise has little power near the centre, DC). XY spectra
//! average the 2-D spectrum of every frame; XT spectra average, over rows, the
//! 2-D spectrum of (x, t) slices. Sizes must be powers of two.

use fsot::core::mask::Mask;
use fsot::error::{Error, Result};

/// In-place radix-2 FFT (forward, no scaling). `re.len()` must be a power of two.
pub fn fft(re: &mut [f64], im: &mut [f64]) {
    let n = re.len();
    debug_assert!(n.is_power_of_two() && im.len() == n);
    let mut j = 0;
    for i in 1..n {
        let mut bit = n >> 1;
        while j & bit != 0 {
            j ^= bit;
            bit >>= 1;
        }
        j |= bit;
        if i < j {
            re.swap(i, j);
            im.swap(i, j);
        }
    }
    let mut len = 2;
    while len <= n {
        let angle = -std::f64::consts::TAU / len as f64;
        for start in (0..n).step_by(len) {
            for k in 0..len / 2 {
                let (s, c) = (angle * k as f64).sin_cos();
                let (a, b) = (start + k, start + k + len / 2);
                let (tr, ti) = (re[b] * c - im[b] * s, re[b] * s + im[b] * c);
                re[b] = re[a] - tr;
                im[b] = im[a] - ti;
                re[a] += tr;
                im[a] += ti;
            }
        }
        len <<= 1;
    }
}

/// |2-D DFT|^2 of a rows x cols grid (row-major) with its mean removed, added
/// into `out`.
fn add_power_2d(grid: &[f64], rows: usize, cols: usize, out: &mut [f64]) {
    let mean = grid.iter().sum::<f64>() / grid.len() as f64;
    let mut re: Vec<f64> = grid.iter().map(|v| v - mean).collect();
    let mut im = vec![0.0; rows * cols];
    for r in 0..rows {
        fft(&mut re[r * cols..(r + 1) * cols], &mut im[r * cols..(r + 1) * cols]);
    }
    let (mut cr, mut ci) = (vec![0.0; rows], vec![0.0; rows]);
    for c in 0..cols {
        for r in 0..rows {
            cr[r] = re[r * cols + c];
            ci[r] = im[r * cols + c];
        }
        fft(&mut cr, &mut ci);
        for r in 0..rows {
            out[r * cols + c] += cr[r] * cr[r] + ci[r] * ci[r];
        }
    }
}

fn check(mask: &Mask, dim: usize) -> Result<()> {
    let t = mask.tile;
    if dim >= t.dims {
        return Err(Error::invalid(format!("dimension {dim} of a d = {} mask", t.dims)));
    }
    for (name, v) in [("width", t.width), ("height", t.height), ("frames", t.frames)] {
        if !v.is_power_of_two() {
            return Err(Error::invalid(format!("spectra need power-of-two sizes; {name} is {v}")));
        }
    }
    Ok(())
}

/// Mean XY power spectrum (H rows x W columns, DC at index 0) of dimension `dim`
/// of sample 0, the mean removed, normalised so white noise averages 1.
pub fn spectrum_xy(mask: &Mask, dim: usize) -> Result<Vec<f64>> {
    check(mask, dim)?;
    let t = mask.tile;
    let mut out = vec![0.0; t.width * t.height];
    for f in 0..t.frames {
        let grid: Vec<f64> = (0..t.width * t.height)
            .map(|i| mask.sample(i % t.width, i / t.width, f, 0)[dim] as f64)
            .collect();
        add_power_2d(&grid, t.height, t.width, &mut out);
    }
    // White noise of variance 1/12 has expected power N / 12 per frequency.
    let scale = 12.0 / (t.frames * t.width * t.height) as f64;
    out.iter_mut().for_each(|v| *v *= scale);
    Ok(out)
}

/// Mean XT power spectrum (T rows x W columns, DC at index 0) over the rows y.
pub fn spectrum_xt(mask: &Mask, dim: usize) -> Result<Vec<f64>> {
    check(mask, dim)?;
    let t = mask.tile;
    let mut out = vec![0.0; t.width * t.frames];
    for y in 0..t.height {
        let grid: Vec<f64> = (0..t.width * t.frames)
            .map(|i| mask.sample(i % t.width, y, i / t.width, 0)[dim] as f64)
            .collect();
        add_power_2d(&grid, t.frames, t.width, &mut out);
    }
    let scale = 12.0 / (t.height * t.width * t.frames) as f64;
    out.iter_mut().for_each(|v| *v *= scale);
    Ok(out)
}

/// Power spectrum of a rows x cols grid (both powers of two), mean removed,
/// DC at index 0, unnormalised.
pub fn power_2d(grid: &[f64], rows: usize, cols: usize) -> Vec<f64> {
    let mut out = vec![0.0; rows * cols];
    add_power_2d(grid, rows, cols, &mut out);
    out
}

/// A spectrum's pixels, DC in the centre, log scale from 1/100 to 10 times
/// white noise's level (8-bit grey).
pub fn spectrum_pixels(spectrum: &[f64], rows: usize, cols: usize) -> Vec<u8> {
    let mut pixels = vec![0u8; rows * cols];
    for r in 0..rows {
        for c in 0..cols {
            let v = spectrum[((r + rows / 2) % rows) * cols + (c + cols / 2) % cols];
            let level = ((v.max(1e-12).log10() + 2.0) / 3.0).clamp(0.0, 1.0);
            pixels[r * cols + c] = (level * 255.0).round() as u8;
        }
    }
    pixels
}

/// A spectrum as an 8-bit grey PNG (see `spectrum_pixels`).
pub fn spectrum_png(spectrum: &[f64], rows: usize, cols: usize) -> Result<Vec<u8>> {
    grey_png(&spectrum_pixels(spectrum, rows, cols), rows, cols)
}

pub use fsot::io::png::grey_png;

#[cfg(test)]
mod tests {
    use super::*;
    use fsot::core::tile::Tile;

    #[test]
    fn fft_matches_the_direct_dft() {
        let n = 16;
        let x: Vec<f64> = (0..n).map(|i| ((i * 7 + 3) % 11) as f64 - 5.0).collect();
        let (mut re, mut im) = (x.clone(), vec![0.0; n]);
        fft(&mut re, &mut im);
        for k in 0..n {
            let (mut dr, mut di) = (0.0, 0.0);
            for (j, v) in x.iter().enumerate() {
                let a = -std::f64::consts::TAU * (k * j) as f64 / n as f64;
                dr += v * a.cos();
                di += v * a.sin();
            }
            assert!((re[k] - dr).abs() < 1e-9 && (im[k] - di).abs() < 1e-9, "bin {k}");
        }
    }

    #[test]
    fn a_cosine_puts_its_power_at_its_frequency_and_white_noise_averages_one() {
        // A plane wave along x at frequency 3: power only at (0, +-3).
        let tile = Tile::new(16, 8, 2, 1, 1).unwrap();
        let samples = (0..tile.pixels())
            .map(|i| (0.5 + 0.4 * (std::f64::consts::TAU * 3.0 * (i % 16) as f64 / 16.0).cos()) as f32)
            .collect();
        let mask = Mask { tile, samples, meta: vec![] };
        let s = spectrum_xy(&mask, 0).unwrap();
        let total: f64 = s.iter().sum();
        assert!((s[3] + s[13]) / total > 0.999999);
        // White noise: mean level 1 (away from DC, which the mean removal zeroes).
        let white = Mask::white(Tile::new(32, 32, 16, 1, 1).unwrap(), 2);
        let s = spectrum_xy(&white, 0).unwrap();
        let mean = s[1..].iter().sum::<f64>() / (s.len() - 1) as f64;
        assert!((mean - 1.0).abs() < 0.05, "{mean}");
        assert!(spectrum_xt(&Mask::white(Tile::new(12, 8, 8, 1, 1).unwrap(), 1), 0).is_err());
    }
}
