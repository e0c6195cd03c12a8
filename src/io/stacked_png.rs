//! Reading scalar masks published as one 8-bit PNG of stacked frames (the STBN
//! and FAST releases): W x (W T) pixels, frame t in rows W t to W t + W - 1,
//! value v standing for the sample (v + 0.5) / 256. Grey, or grey stored in
//! RGB(A) (the first channel is read). For comparisons only.

use std::path::Path;

use crate::core::mask::Mask;
use crate::core::tile::Tile;
use crate::error::{Error, Result};

pub fn read(path: &Path) -> Result<Mask> {
    let bad = |what: String| Error::invalid(format!("{}: {what}", path.display()));
    let bytes = crate::io::read_regular(path).map_err(|e| bad(format!("cannot read: {e}")))?;
    let mut reader =
        png::Decoder::new(std::io::Cursor::new(bytes)).read_info().map_err(|e| bad(format!("not a readable PNG: {e}")))?;
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).map_err(|e| bad(format!("not a readable PNG: {e}")))?;
    if info.bit_depth != png::BitDepth::Eight {
        return Err(bad("expected 8 bits per channel".into()));
    }
    let stride = info.color_type.samples();
    let (w, h) = (info.width as usize, info.height as usize);
    if w == 0 || h % w != 0 {
        return Err(bad(format!("{w} x {h} is not square frames stacked vertically")));
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
}
