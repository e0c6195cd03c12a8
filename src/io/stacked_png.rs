//! Reading scalar masks published as one 8-bit PNG of stacked frames (the STBN
//! and FAST releases): W x (W T) pixels, frame t in rows W t to W t + W - 1,
//! value v standing for the sample (v + 0.5) / 256. Grey, or grey stored in
//! RGB(A) (the first channel is read). For comparisons only.

use std::path::Path;

use crate::core::mask::Mask;
use crate::core::tile::{Tile, MAX_POINTS};
use crate::error::{Error, Result};

/// How many times its own size a PNG's pixels may take: deflate's ceiling of about
/// 1032 to 1, with room to spare.
const MAX_EXPANSION: usize = 1100;

pub fn read(path: &Path) -> Result<Mask> {
    let bad = |what: String| Error::invalid(format!("{}: {what}", path.display()));
    let bytes = crate::io::read_regular(path).map_err(|e| bad(format!("cannot read: {e}")))?;
    let file_len = bytes.len();
    let mut reader =
        png::Decoder::new(std::io::Cursor::new(bytes)).read_info().map_err(|e| bad(format!("not a readable PNG: {e}")))?;
    // The header alone decides, before the pixels are given any memory.
    let info = reader.info();
    let (w, h) = (info.width as usize, info.height as usize);
    if info.bit_depth != png::BitDepth::Eight {
        return Err(bad("expected 8 bits per channel".into()));
    }
    if info.color_type == png::ColorType::Indexed {
        return Err(bad("a palette image; expected grey, or grey stored in RGB(A)".into()));
    }
    if w == 0 || h % w != 0 {
        return Err(bad(format!("{w} x {h} is not square frames stacked vertically")));
    }
    if w.checked_mul(h).is_none_or(|points| points > MAX_POINTS) {
        return Err(bad(format!("{w} x {h} pixels is more than the largest tile ({MAX_POINTS} points)")));
    }
    let stride = info.color_type.samples();
    // Deflate expands at most about 1032 to 1: a header promising more than that
    // from the file's bytes is not a whole image.
    if w * h * stride > file_len.saturating_mul(MAX_EXPANSION) {
        return Err(bad(format!("{w} x {h} pixels cannot come from a file of {file_len} bytes")));
    }
    let mut buf = vec![0; reader.output_buffer_size()];
    let frame = reader.next_frame(&mut buf).map_err(|e| bad(format!("not a readable PNG: {e}")))?;
    // An animated PNG's first frame may cover less than the image: the rest
    // would read as zeros.
    if (frame.width as usize, frame.height as usize) != (w, h) {
        return Err(bad(format!(
            "its first frame is {} x {} of a {w} x {h} image (an animated PNG): not a whole image",
            frame.width, frame.height
        )));
    }
    let tile = Tile::new(w, w, h / w, 1, 1)?;
    // Row-major stacked frames match fsot's layout (frame-major, then rows).
    let samples = buf[..w * h * stride].iter().step_by(stride).map(|&v| (v as f32 + 0.5) / 256.0).collect();
    Ok(Mask { tile, samples, meta: vec![("method".into(), format!("published: {}", path.display()))] })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::png::grey_png;

    #[test]
    fn stacked_frames_read_in_order_and_bad_shapes_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        // 4 x 8 grey: two 4 x 4 frames; value v is the sample (v + 0.5) / 256.
        let pixels: Vec<u8> = (0..32).map(|i| (i * 8) as u8).collect();
        let path = dir.path().join("m.png");
        std::fs::write(&path, grey_png(&pixels, 8, 4).unwrap()).unwrap();
        let m = read(&path).unwrap();
        assert_eq!((m.tile.width, m.tile.height, m.tile.frames, m.tile.dims), (4, 4, 2, 1));
        assert_eq!(m.sample(1, 2, 1, 0)[0], ((16 + 8 + 1) as f32 * 8.0 + 0.5) / 256.0);
        let odd = dir.path().join("odd.png");
        std::fs::write(&odd, grey_png(&pixels[..24], 6, 4).unwrap()).unwrap();
        assert!(read(&odd).unwrap_err().to_string().contains("stacked"));
        std::fs::write(&odd, b"garbage").unwrap();
        assert!(read(&odd).unwrap_err().to_string().contains("not a readable PNG"));
        assert!(read(&dir.path().join("missing.png")).unwrap_err().to_string().contains("cannot read"));
    }

    /// A PNG of a header for `w` x `h` grey pixels and a few bytes of data.
    fn header_only_png(w: u32, h: u32) -> Vec<u8> {
        fn crc32(bytes: &[u8]) -> u32 {
            let mut crc = !0u32;
            for &b in bytes {
                crc ^= b as u32;
                for _ in 0..8 {
                    crc = if crc & 1 != 0 { (crc >> 1) ^ 0xEDB8_8320 } else { crc >> 1 };
                }
            }
            !crc
        }
        let chunk = |kind: &[u8], data: &[u8]| {
            let mut c = (data.len() as u32).to_be_bytes().to_vec();
            let body = [kind, data].concat();
            c.extend_from_slice(&body);
            c.extend_from_slice(&crc32(&body).to_be_bytes());
            c
        };
        let ihdr = [&w.to_be_bytes()[..], &h.to_be_bytes(), &[8, 0, 0, 0, 0]].concat();
        // A stored (uncompressed) zlib stream of one zero byte.
        let idat = [0x78, 0x01, 0x01, 0x01, 0x00, 0xfe, 0xff, 0x00, 0x00, 0x01, 0x00, 0x01];
        [&b"\x89PNG\r\n\x1a\n"[..], &chunk(b"IHDR", &ihdr), &chunk(b"IDAT", &idat), &chunk(b"IEND", &[])].concat()
    }

    #[test]
    fn a_header_promising_more_pixels_than_the_file_could_hold_is_refused_before_they_are_given_memory() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.png");
        // 2^40 pixels: past the largest tile.
        std::fs::write(&path, header_only_png(1 << 20, 1 << 20)).unwrap();
        let reason = read(&path).unwrap_err().to_string();
        assert!(reason.contains("more than the largest tile"), "{reason}");
        // 2^28 pixels, a tile's worth, from about 70 bytes.
        std::fs::write(&path, header_only_png(1 << 14, 1 << 14)).unwrap();
        let reason = read(&path).unwrap_err().to_string();
        assert!(reason.contains("cannot come from a file of"), "{reason}");
        // The same header for 4 x 8 pixels is read past it, to the missing data.
        std::fs::write(&path, header_only_png(4, 8)).unwrap();
        let reason = read(&path).unwrap_err().to_string();
        assert!(reason.contains("not a readable PNG"), "{reason}");
    }

    #[test]
    fn a_palette_image_is_refused_rather_than_read_as_its_indices() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.png");
        let mut bytes = Vec::new();
        let mut encoder = png::Encoder::new(&mut bytes, 4, 8);
        encoder.set_color(png::ColorType::Indexed);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_palette((0..=255u8).flat_map(|i| [255 - i; 3]).collect::<Vec<u8>>());
        let mut writer = encoder.write_header().unwrap();
        writer.write_image_data(&(0..32).collect::<Vec<u8>>()).unwrap();
        writer.finish().unwrap();
        std::fs::write(&path, bytes).unwrap();
        let reason = read(&path).unwrap_err().to_string();
        assert!(reason.contains("palette"), "{reason}");
    }
}
