//! Pictures of an evaluation, one strip per scene and kind, the reference (where
//! there is one) then the methods in table order, left to right:
//! - `<scene>-frames.png`: the last frame after TAA, tone-mapped (gamma 2.2);
//! - `<scene>-errors.png`: that frame's error as the eye sees it (grey is zero,
//!   the same scale for every method: +-4 x white noise's RMS);
//! - `<scene>-spectra-xy.png`, `<scene>-spectra-xt.png`: power spectra of the raw
//!   1-spp error (no TAA), XY averaged over frames and XT over rows, log scale
//!   from 1/100 to 10 times white noise's mean level, DC in the centre.

use std::path::Path;

use crate::eval::spectrum::{grey_png, power_2d, spectrum_pixels};
use fsot::error::Result;
use fsot::io::atomic::AtomicFile;
use fsot::quality::eye::Eye;

/// Frames of one render: without TAA, and with.
pub type Frames = (Vec<Vec<f64>>, Vec<Vec<f64>>);

/// Gap between cells of a strip, pixels.
const GAP: usize = 2;

/// Cells side by side (each rows x cols, 8-bit) as one PNG.
fn strip(cells: &[Vec<u8>], rows: usize, cols: usize) -> Result<Vec<u8>> {
    let width = cells.len() * (cols + GAP) - GAP;
    let mut pixels = vec![255u8; width * rows];
    for (k, cell) in cells.iter().enumerate() {
        for r in 0..rows {
            let at = r * width + k * (cols + GAP);
            pixels[at..at + cols].copy_from_slice(&cell[r * cols..(r + 1) * cols]);
        }
    }
    grey_png(&pixels, rows, width)
}

/// The centre `side` x `side` crop of an n x n image.
fn crop(image: &[f64], n: usize, side: usize) -> Vec<f64> {
    let o = (n - side) / 2;
    (0..side * side).map(|i| image[(o + i / side) * n + o + i % side]).collect()
}

fn save(dir: &Path, name: &str, bytes: &[u8]) -> Result<()> {
    AtomicFile::create(&dir.join(name))?.commit(bytes)
}

/// Writes the four strips of one scene. `renders` holds, per method, its frames
/// without TAA and with TAA (the same render); `reference` likewise.
pub fn scene_pictures(
    dir: &Path,
    scene: &str,
    n: usize,
    eye: &Eye,
    reference: (&[Vec<f64>], &[Vec<f64>]),
    renders: &[Frames],
) -> Result<()> {
    let last = reference.0.len() - 1;
    // Crops of the largest power of two up to 64 pixels (spectra need one).
    let side = 1usize << 64.min(n).ilog2();
    // Frames after TAA, tone-mapped by the reference's brightest pixel.
    let peak = crop(&reference.1[last], n, side).iter().fold(1e-9f64, |a, &b| a.max(b));
    let tone = |img: &[f64]| -> Vec<u8> {
        crop(img, n, side)
            .iter()
            .map(|v| ((v / peak).clamp(0.0, 1.0).powf(1.0 / 2.2) * 255.0).round() as u8)
            .collect()
    };
    let mut cells = vec![tone(&reference.1[last])];
    cells.extend(renders.iter().map(|(_, taa)| tone(&taa[last])));
    save(dir, &format!("{scene}-frames.png"), &strip(&cells, side, side)?)?;
    // Errors as the eye sees them, on the interior.
    let inner = n - 2 * eye.margin;
    let seen: Vec<Vec<f64>> = renders
        .iter()
        .map(|(_, taa)| {
            let error: Vec<Vec<f64>> = taa
                .iter()
                .zip(reference.1)
                .map(|(a, b)| a.iter().zip(b).map(|(x, y)| x - y).collect())
                .collect();
            eye.filter(&error, last, n)
        })
        .collect();
    let rms = (seen[0].iter().map(|v| v * v).sum::<f64>() / seen[0].len() as f64).sqrt().max(1e-12);
    let eside = side.min(inner);
    let cells: Vec<Vec<u8>> = seen
        .iter()
        .map(|s| {
            crop(s, inner, eside)
                .iter()
                .map(|v| (128.0 + 127.0 * v / (4.0 * rms)).clamp(0.0, 255.0) as u8)
                .collect()
        })
        .collect();
    save(dir, &format!("{scene}-errors.png"), &strip(&cells, eside, eside)?)?;
    // Spectra of the raw error over the last `t` frames (a power of two).
    let t = (last + 1).min(32);
    let t = if t.is_power_of_two() { t } else { t.next_power_of_two() / 2 };
    let first = last + 1 - t;
    let spectra: Vec<(Vec<f64>, Vec<f64>)> = renders
        .iter()
        .map(|(raw, _)| {
            let errors: Vec<Vec<f64>> = (first..=last)
                .map(|f| {
                    crop(&raw[f].iter().zip(&reference.0[f]).map(|(x, y)| x - y).collect::<Vec<_>>(), n, side)
                })
                .collect();
            let mut xy = vec![0.0; side * side];
            for e in &errors {
                for (o, p) in xy.iter_mut().zip(power_2d(e, side, side)) {
                    *o += p;
                }
            }
            let mut xt = vec![0.0; t * side];
            for y in 0..side {
                let grid: Vec<f64> = (0..t * side).map(|i| errors[i / side][y * side + i % side]).collect();
                for (o, p) in xt.iter_mut().zip(power_2d(&grid, t, side)) {
                    *o += p;
                }
            }
            (xy, xt)
        })
        .collect();
    // Normalised by white noise's (the first method's) mean level.
    let level = |s: &[f64]| s[1..].iter().sum::<f64>() / (s.len() - 1) as f64;
    let (wxy, wxt) = (level(&spectra[0].0).max(1e-300), level(&spectra[0].1).max(1e-300));
    let cells: Vec<Vec<u8>> = spectra
        .iter()
        .map(|(xy, _)| spectrum_pixels(&xy.iter().map(|v| v / wxy).collect::<Vec<_>>(), side, side))
        .collect();
    save(dir, &format!("{scene}-spectra-xy.png"), &strip(&cells, side, side)?)?;
    let cells: Vec<Vec<u8>> = spectra
        .iter()
        .map(|(_, xt)| spectrum_pixels(&xt.iter().map(|v| v / wxt).collect::<Vec<_>>(), t, side))
        .collect();
    save(dir, &format!("{scene}-spectra-xt.png"), &strip(&cells, t, side)?)?;
    Ok(())
}
