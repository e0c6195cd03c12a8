//! Masks as PNG slices, one file per frame like the published STBN masks.
//!
//! With b bits (16 or 8), value v in [0, 1) is stored as floor(v * 2^b) (at most
//! 2^b - 1); a reader takes (stored + 0.5) / 2^b. With spp = 1 and d <= 4, `frameTTTT.png` holds
//! dimensions 0..d as grey (d = 1), RGB (d = 2, blue 0; d = 3) or RGBA (d = 4).
//! Otherwise each frame has one file per sample and group of up to four
//! dimensions: `frameTTTT_sSS_dA-B.png` (RGBA, unused channels 0).

use std::path::Path;

use crate::core::mask::Mask;
use crate::core::tile::Tile;
use crate::error::{Error, Result};
use crate::io::atomic::AtomicFile;

/// Quantises one value to 16 bits.
pub fn quantize(v: f32) -> u16 {
    quantize_bits(v, 16) as u16
}

/// Quantises one value to `bits` bits (1 to 16): floor(v 2^bits), clamped.
pub fn quantize_bits(v: f32, bits: u32) -> u32 {
    let levels = (1u64 << bits) as f64;
    ((v as f64 * levels).floor() as i64).clamp(0, levels as i64 - 1) as u32
}

/// One PNG slice: its file name, frame, sample and the dimensions it holds.
struct Slice {
    name: String,
    t: usize,
    s: usize,
    dims: Vec<usize>,
}

/// The slices of a tile, in order: one per frame for spp = 1 and d <= 4 (grey,
/// RGB or RGBA), else one per frame, sample and group of four dimensions.
fn slices(tile: &Tile) -> Vec<Slice> {
    let simple = tile.spp == 1 && tile.dims <= 4;
    let mut out = Vec::new();
    for t in 0..tile.frames {
        for s in 0..tile.spp {
            for group in (0..tile.dims).step_by(4) {
                let dims: Vec<usize> = (group..(group + 4).min(tile.dims)).collect();
                let name = if simple {
                    format!("frame{t:04}.png")
                } else {
                    format!("frame{t:04}_s{s:02}_d{}-{}.png", dims[0], dims[dims.len() - 1])
                };
                out.push(Slice { name, t, s, dims });
            }
        }
    }
    out
}

/// The file names `write` gives a tile's slices, in order.
pub fn names(tile: &Tile) -> Vec<String> {
    slices(tile).into_iter().map(|s| s.name).collect()
}

/// Every slice's file name and PNG bytes.
pub fn encode(mask: &Mask, bits: u32) -> Result<Vec<(String, Vec<u8>)>> {
    mask.check()?;
    let depth = match bits {
        8 => png::BitDepth::Eight,
        16 => png::BitDepth::Sixteen,
        _ => return Err(Error::invalid(format!("PNG slices hold 8 or 16 bits per channel, not {bits}"))),
    };
    let tile = mask.tile;
    let simple = tile.spp == 1 && tile.dims <= 4;
    let (color, channels) = match tile.dims {
        1 if simple => (png::ColorType::Grayscale, 1),
        2 | 3 if simple => (png::ColorType::Rgb, 3),
        _ => (png::ColorType::Rgba, 4),
    };
    let mut files = Vec::new();
    for Slice { name, t, s, dims } in slices(&tile) {
        let mut data = Vec::with_capacity(tile.width * tile.height * channels * bits as usize / 8);
        for y in 0..tile.height {
            for x in 0..tile.width {
                let sample = mask.sample(x, y, t, s);
                for c in 0..channels {
                    let v = dims.get(c).map(|&k| quantize_bits(sample[k], bits)).unwrap_or(0);
                    if bits == 8 {
                        data.push(v as u8);
                    } else {
                        data.extend_from_slice(&(v as u16).to_be_bytes());
                    }
                }
            }
        }
        let mut bytes = Vec::new();
        {
            let mut encoder = png::Encoder::new(&mut bytes, tile.width as u32, tile.height as u32);
            encoder.set_color(color);
            encoder.set_depth(depth);
            let mut writer =
                encoder.write_header().map_err(|e| Error::invalid(format!("PNG encoding failed: {e}")))?;
            writer.write_image_data(&data).map_err(|e| Error::invalid(format!("PNG encoding failed: {e}")))?;
        }
        files.push((name, bytes));
    }
    Ok(files)
}

/// The slices as outputs into `dir` (made if missing), each reserved and
/// encoded, for `atomic::commit_all` beside a run's other outputs.
pub fn outputs(mask: &Mask, dir: &Path, bits: u32) -> Result<Vec<(AtomicFile, Vec<u8>)>> {
    let files = encode(mask, bits)?;
    crate::io::atomic::make_folder(dir)?;
    files.into_iter().map(|(name, bytes)| Ok((AtomicFile::create(&dir.join(name))?, bytes))).collect()
}

/// Writes the slices into `dir` (made if missing) with `bits` bits per channel,
/// 8 or 16, every one in full before any file there is replaced; the names
/// written, in order.
pub fn write(mask: &Mask, dir: &Path, bits: u32) -> Result<Vec<String>> {
    let names = names(&mask.tile);
    crate::io::atomic::commit_all(outputs(mask, dir, bits)?)?;
    Ok(names)
}

/// 8-bit grey pixels (row-major) as PNG bytes.
pub fn grey_png(pixels: &[u8], rows: usize, cols: usize) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, cols as u32, rows as u32);
        encoder.set_color(png::ColorType::Grayscale);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(|e| Error::invalid(format!("PNG: {e}")))?;
        writer.write_image_data(pixels).map_err(|e| Error::invalid(format!("PNG: {e}")))?;
    }
    Ok(bytes)
}
