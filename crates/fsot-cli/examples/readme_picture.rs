//! The README's picture: four frames of a mask's first dimension, its spatial
//! power spectrum (mean over the frames) and its spatio-temporal one (x against
//! t), above a strip of frames after TAA from the example renderer (reference |
//! white noise | fsot). 8-bit grey PNG.
//!
//! cargo run --release -p fsot-cli --example readme_picture -- MASK.exr STRIP.png OUT.png
use fsot::core::mask::Mask;
use fsot_cli::eval::spectrum::{grey_png, spectrum_pixels, spectrum_xt, spectrum_xy};

const GAP: usize = 8;

/// A grey picture, row-major.
struct Picture {
    width: usize,
    height: usize,
    pixels: Vec<u8>,
}

impl Picture {
    fn blank(width: usize, height: usize) -> Picture {
        Picture { width, height, pixels: vec![255; width * height] }
    }

    /// Copies `src` (w x h) in at (x0, y0), each pixel as a `scale` x `scale` block.
    fn put(&mut self, src: &[u8], w: usize, h: usize, scale: usize, x0: usize, y0: usize) {
        for y in 0..h * scale {
            for x in 0..w * scale {
                self.pixels[(y0 + y) * self.width + x0 + x] = src[(y / scale) * w + x / scale];
            }
        }
    }
}

fn frame_pixels(mask: &Mask, frame: usize) -> Vec<u8> {
    let t = mask.tile;
    (0..t.width * t.height)
        .map(|i| (mask.sample(i % t.width, i / t.width, frame, 0)[0] * 256.0).clamp(0.0, 255.0) as u8)
        .collect()
}

fn read_grey_png(path: &str) -> Result<(Vec<u8>, usize, usize), String> {
    let file = std::fs::File::open(path).map_err(|e| format!("{path}: {e}"))?;
    let mut reader = png::Decoder::new(file).read_info().map_err(|e| format!("{path}: {e}"))?;
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).map_err(|e| format!("{path}: {e}"))?;
    if info.color_type != png::ColorType::Grayscale || info.bit_depth != png::BitDepth::Eight {
        return Err(format!("{path}: an 8-bit grey PNG was expected"));
    }
    buf.truncate(info.width as usize * info.height as usize);
    Ok((buf, info.width as usize, info.height as usize))
}

fn run(args: &[String]) -> Result<(), String> {
    let [mask, strip, out] = args else {
        return Err("usage: readme_picture MASK.exr STRIP.png OUT.png".into());
    };
    let mask = fsot::io::exr::read(mask.as_ref()).map_err(|e| e.to_string())?;
    let (strip, sw, sh) = read_grey_png(strip)?;
    let t = mask.tile;
    let scale = (128 / t.width.max(t.height)).max(1);
    let (cell_w, cell_h) = (t.width * scale, t.height * scale);
    let frames = 4.min(t.frames);
    let xy = spectrum_pixels(&spectrum_xy(&mask, 0).map_err(|e| e.to_string())?, t.height, t.width);
    let xt = spectrum_pixels(&spectrum_xt(&mask, 0).map_err(|e| e.to_string())?, t.frames, t.width);
    let top_w = (frames + 2) * (cell_w + GAP) - GAP;
    let top_h = cell_h.max(t.frames * scale);
    let width = top_w.max(sw);
    let mut picture = Picture::blank(width, top_h + GAP + sh);
    for f in 0..frames {
        picture.put(&frame_pixels(&mask, f), t.width, t.height, scale, f * (cell_w + GAP), 0);
    }
    picture.put(&xy, t.width, t.height, scale, frames * (cell_w + GAP), 0);
    picture.put(&xt, t.width, t.frames, scale, (frames + 1) * (cell_w + GAP), 0);
    picture.put(&strip, sw, sh, 1, (width - sw) / 2, top_h + GAP);
    let bytes = grey_png(&picture.pixels, picture.height, picture.width).map_err(|e| e.to_string())?;
    std::fs::write(out, bytes).map_err(|e| format!("{out}: {e}"))?;
    println!("wrote {out}: {} x {}", picture.width, picture.height);
    Ok(())
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if let Err(e) = run(&args) {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
